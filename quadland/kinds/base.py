"""What a kind of loop is: the one object the engine, the CLI, margins, campaigns and plots ask.

quadland flies two kinds of loop today, the paper's 4-DOF loop and the 6-DOF
landing; each is one :class:`LoopKind` (:mod:`quadland.kinds`), owning what is
specific to it: its scenario schema, its symbolic loop, how a scenario
becomes that loop's vectors and a flight, its trajectory's columns, its
summary, metrics and limits, its figures, its operating point and linear
models, and its flight code's C defaults. Nothing outside a kind compares a
model's name: a third kind (another vehicle, a fixed-wing) is a new subclass
and one line in each registry (:data:`quadland.schema.SCHEMAS`,
:data:`quadland.kinds.KINDS`), the engine untouched. python-control's system
objects, which every analysis accepts, and RotorPy's split of vehicle,
controller and environment are the models of this design.
"""

from __future__ import annotations

import abc
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

from quadland.engine.envelope import Envelope
from quadland.engine.plan import SimulationPlan, check_plan
from quadland.engine.result import SimulationResult
from quadland.exceptions import MarginsError, ScenarioError
from quadland.metrics import Metric, violations
from quadland.scenario import Scenario
from quadland_symbolic.layout import Layout
from quadland_symbolic.loop import LoopModel

if TYPE_CHECKING:  # python-control (and matplotlib with it) loads on first analysis
    from quadland.linear import LinearModels, OperatingPoint

__all__ = ["LoopKind"]


class LoopKind(abc.ABC):
    """One kind of simulated loop (``scenario.model``).

    Attributes
    ----------
    name : str
        Its ``scenario.model`` value.
    summary_line : str
        What it flies, in one line (``quadland scenarios``).
    schema : mapping
        Its scenario schema (:data:`quadland.schema.SCHEMAS`).
    default_scenario : str
        The shipped scenario whose values its half of ``generated/`` carries.
    codegen_part : str
        Its half of the generated tree (``quadland_symbolic.codegen.generate_tree``).
    metrics : tuple of Metric
        What a campaign records of each run, in runs.csv's column order.
    trajectory : Layout
        The columns of its ``trajectory.csv``.
    loop_break : str
        Where its margin review breaks the loop, in one phrase.
    can_animate : bool
        Whether :meth:`animation` draws it.
    """

    name: ClassVar[str]
    summary_line: ClassVar[str]
    schema: ClassVar[Mapping]
    default_scenario: ClassVar[str]
    codegen_part: ClassVar[str]
    metrics: ClassVar[tuple[Metric, ...]]
    trajectory: ClassVar[Layout]
    loop_break: ClassVar[str]
    can_animate: ClassVar[bool] = False

    # ---------------------------------------------------------------- flying

    @abc.abstractmethod
    def loop_model(self, l: int) -> LoopModel:
        """Its symbolic loop for ``l`` RBF nodes."""

    def loop_sizes(self, l: int) -> tuple[int, int]:
        """``(states, held inputs)`` of :meth:`loop_model`'s loop (a kind may tell them
        from its layouts without building the loop's functions)."""
        loop = self.loop_model(l)
        return loop.state.size, loop.held.size

    @abc.abstractmethod
    def plan(self, scenario: Scenario) -> SimulationPlan:
        """A run's size, estimated from the scenario alone."""

    def check(self, scenario: Scenario) -> None:
        """Refuse, in one line naming the keys, a run over the budgets."""
        check_plan(self.plan(scenario))

    @abc.abstractmethod
    def envelope(self, scenario: Scenario) -> Envelope:
        """The bounds a flight must keep (a diverging one stops at them)."""

    @abc.abstractmethod
    def simulate(self, scenario: Scenario) -> SimulationResult:
        """Fly the scenario; a failed flight raises ``SimulationError`` with its rows."""

    # ---------------------------------------------------------------- judging

    @abc.abstractmethod
    def summary(self, result: SimulationResult) -> dict:
        """summary.json's figures of a run (JSON-ready)."""

    @abc.abstractmethod
    def run_metrics(self, result: SimulationResult) -> dict[str, float | None]:
        """The run's :attr:`metrics` by name (None where undefined)."""

    def io_values(self, scenario: Scenario) -> dict[str, Any]:
        """The numbers that close the loop model's functions for ``scenario``.

        ``{"x0", "p"}``: the continuous closed loop's initial state and
        parameters (None where the loop is sampled-data only); ``{"xp0",
        "pp"}``: the plant's initial state and parameters (``quadland.nlsys``);
        for a sampled-data loop, ``"sampled"``: ``{"xc0", "pc", "uh0", "dt",
        "delay", "substeps", "break_rates", "sensed"}``, the controller's
        memory, parameters and first held command, the period (s), the delay
        (periods), the RK4 steps per piece of the grid, the rates (Hz) of the
        other clocks that split a period, and whether the scenario flies on
        sensors (:class:`quadland.engine.period.SampledPeriod`).
        """
        raise NotImplementedError(f"{self.name}: no values for quadland.nlsys")

    def result_lines(self, summary: Mapping[str, Any]) -> list[str]:
        """What ``quadland simulate`` prints of a finished run: its verdict and figures,
        a few lines read from its ``summary.json`` object (none by default)."""
        return []

    def limits(self, scenario: Scenario,
               extra: Mapping[str, float] | None = None) -> dict[str, float]:
        """Each limited metric's upper limit: the scenario's own keys, then ``extra``'s."""
        out = {m.name: scenario[m.limit] for m in self.metrics if m.limit}
        out.update(extra or {})
        return out

    def judge(self, result: SimulationResult, metrics: Mapping[str, float | None],
              limits: Mapping[str, float]) -> list[str]:
        """Every reason a finished run is not a success, one phrase each (none: success)."""
        return violations(metrics, limits, {m.name: m.unit for m in self.metrics})

    @abc.abstractmethod
    def figures(self, result: SimulationResult) -> dict[str, Any]:
        """Its figures of a run, matplotlib ``Figure`` objects by file name."""

    def animation(self, result: SimulationResult, path: Path) -> Path:
        """An animation of the run written to ``path`` (kinds that draw one)."""
        raise ScenarioError(f"animate: draws a landing; this scenario's model is "
                            f"\"{self.name}\"")

    # ---------------------------------------------------------------- analysis

    @abc.abstractmethod
    def operating_point(self, scenario: Scenario, at: float | None = None) -> OperatingPoint:
        """Where its margin review linearizes: an equilibrium, or the simulated state at ``at``."""

    def computation_delay(self, scenario: Scenario) -> int:
        """Control periods from sampling to commanding that its flight code has (the
        margin review's default): one, unless the kind's scenarios set it (the
        paper's simulation applies its command at the sample; its review assumes
        the flight code's one period)."""
        return 1

    def sensor_channels(self, scenario: Scenario) -> dict[str, tuple[tuple[str, ...], float]]:
        """Its sensors for the margin review's sensor side: name -> (the linear models'
        measured outputs the sensor feeds, its flown latency in s); none by default."""
        return {}

    def check_operating_time(self, scenario: Scenario, at: float) -> None:
        """Refuse, before any work, a time :meth:`operating_point` cannot reach."""
        raise MarginsError(f"at: the {self.name} loop is analysed at its equilibrium only")

    @abc.abstractmethod
    def linear_models(self, scenario: Scenario, point: OperatingPoint) -> LinearModels:
        """Continuous-time plant, controller and loops at the point."""

    @abc.abstractmethod
    def sampled_models(self, scenario: Scenario, point: OperatingPoint, rate_hz: float,
                       delay_periods: int = 1) -> LinearModels:
        """Sampled-data models at ``rate_hz`` with ``delay_periods`` of computation delay."""

    @abc.abstractmethod
    def describe_point(self, scenario: Scenario, point: OperatingPoint
                       ) -> tuple[list[str], str]:
        """The margin table's opening lines for the point, and its continuous section's title."""

    # ---------------------------------------------------------------- code

    @abc.abstractmethod
    def codegen_defaults(self, scenario: Scenario):
        """The C defaults of its half of the generated tree, from a scenario's values."""

    def __repr__(self) -> str:
        return f"<loop kind {self.name!r}: {self.summary_line}>"

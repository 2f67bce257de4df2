"""The paper's 4-DOF loop as a loop kind."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from quadland.engine.envelope import Envelope
from quadland.engine.plan import SimulationPlan
from quadland.engine.result import SimulationResult
from quadland.kinds.base import LoopKind
from quadland.kinds.paper import PAPER_SCENARIO, report, simulate
from quadland.scenario import Scenario
from quadland.schema import PAPER_SCHEMA
from quadland_symbolic.codegen import Defaults
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.paper_loop import paper_loop

if TYPE_CHECKING:  # python-control (and matplotlib with it) loads on first analysis
    from quadland.linear import LinearModels, OperatingPoint

__all__ = ["PaperKind", "PAPER"]


class PaperKind(LoopKind):
    """The paper's relative altitude-attitude loop (``scenario.model = "paper"``).

    The closed loop of eq. (1)-(22) as one ODE (continuous) or its control step
    sampled at ``controller.rate_hz``; broken at the virtual input u of
    eq. (6) for its margins.
    """

    name = "paper"
    summary_line = "the paper's 4-DOF relative altitude-attitude loop (Section 4)"
    schema = PAPER_SCHEMA
    default_scenario = PAPER_SCENARIO
    codegen_part = "paper"
    metrics = report.PAPER_METRICS
    trajectory = simulate.TRAJECTORY
    loop_break = "plant input u (eq. 6), L = -K P, negative feedback"

    def loop_model(self, l: int) -> LoopModel:
        return paper_loop(l)

    def plan(self, scenario: Scenario) -> SimulationPlan:
        return simulate.paper_plan(scenario)

    def envelope(self, scenario: Scenario) -> Envelope:
        return simulate.paper_envelope(scenario)

    def simulate(self, scenario: Scenario) -> SimulationResult:
        return simulate.simulate_paper(scenario)

    def summary(self, result: SimulationResult) -> dict:
        return report.summarize(result)

    def io_values(self, scenario: Scenario) -> dict[str, Any]:
        from quadland.kinds.paper.values import model_values
        from quadland_symbolic.closed_loop import PAPER_PLANT_STATE, closed_loop_state
        from quadland_symbolic.paper_loop import PAPER_PLANT_PARAMS

        mv = model_values(scenario)
        x = closed_loop_state(mv.l).unpack(mv.x0)
        return {"x0": mv.x0, "p": mv.p,
                "xp0": PAPER_PLANT_STATE.pack({n: x[n] for n in PAPER_PLANT_STATE.names()}),
                "pp": PAPER_PLANT_PARAMS.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh))}

    def result_lines(self, summary: Mapping[str, Any]) -> list[str]:
        return report.paper_result_lines(summary)

    def run_metrics(self, result: SimulationResult) -> dict[str, float | None]:
        return report.paper_run_metrics(result)

    def figures(self, result: SimulationResult) -> dict[str, Any]:
        from quadland.plots.simulation import simulation_figures

        return simulation_figures(result)

    def operating_point(self, scenario: Scenario, at: float | None = None) -> OperatingPoint:
        from quadland.kinds.paper import linearize

        if at is None:
            return linearize.paper_equilibrium(scenario)
        return linearize.frozen_point(scenario, at)

    def check_operating_time(self, scenario: Scenario, at: float) -> None:
        from quadland.kinds.paper import linearize

        linearize.check_frozen_time(scenario, at)

    def linear_models(self, scenario: Scenario, point: OperatingPoint) -> LinearModels:
        from quadland.kinds.paper import linearize

        return linearize.paper_linear_models(scenario, point)

    def sampled_models(self, scenario: Scenario, point: OperatingPoint, rate_hz: float,
                       delay_periods: int = 1) -> LinearModels:
        from quadland.kinds.paper import linearize

        return linearize.paper_sampled_models(scenario, point, rate_hz, delay_periods)

    def describe_point(self, scenario: Scenario, point: OperatingPoint
                       ) -> tuple[list[str], str]:
        op = point.to_dict()
        s, v = op["state"], op["vehicle"]
        where = ("equilibrium (steady motion, constant disturbance)"
                 if point.kind == "equilibrium"
                 else f"frozen simulated state at t = {point.time:g} s")
        lines = [f"quadland margins: scenario {scenario.name}, {where}",
                 f"  z_e = {s['z1'] - v['z2']:.4g} m, phi = {s['phi1']:.3g} rad, "
                 f"theta = {s['theta1']:.3g} rad, psi_e = {s['psi_e']:.3g} rad, "
                 f"vehicle r2 = {v['r2']:.4g} rad/s, residual {op['residual']:.2g}",
                 "  loop broken at the plant input u (eq. 6), L = -K P; each loop with the "
                 "others closed", ""]
        return lines, "continuous-time controller"

    def codegen_defaults(self, scenario: Scenario) -> Defaults:
        from quadland.kinds.paper.flight import paper_defaults  # (its flight code: a build)

        return paper_defaults(scenario)


#: The paper's loop kind.
PAPER = PaperKind()

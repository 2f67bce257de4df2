"""Simulate a scenario: its loop kind flies it.

:func:`simulate` is the public entry point (``quadland.simulate``); the
scenario's kind (:func:`quadland.kinds.kind_of`) knows its loop, its clocks,
its envelope and its result's columns.
"""

from __future__ import annotations

import os

from quadland.engine.plan import SimulationPlan
from quadland.engine.result import SimulationResult, columns_sidecar
from quadland.kinds import kind_of
from quadland.scenario import Scenario, load_scenario

__all__ = ["simulate", "simulation_plan", "check_run", "SimulationResult", "columns_sidecar"]


def simulate(scenario: Scenario | str | os.PathLike) -> SimulationResult:
    """Simulate a scenario's closed loop.

    Parameters
    ----------
    scenario : Scenario, str or path
        From :func:`quadland.load_scenario`, or what it loads: a shipped
        scenario's name or a TOML file.

    Returns
    -------
    SimulationResult
        Every signal by name at the output times; ``layout`` names the
        columns of its ``trajectory.csv``.

    Raises
    ------
    ScenarioError
        A run over the memory or step budgets (one line naming the keys).
    SimulationError
        The flight failed (left its envelope, reached a singular attitude, a
        value stopped being finite); it carries the trajectory up to then.

    Examples
    --------
    >>> import quadland
    >>> sc = quadland.load_scenario("paper", ["simulation.duration=0.5"])
    >>> res = quadland.simulate(sc)
    >>> float(res["t"][-1]), len(res["t"])
    (0.5, 51)
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    return kind_of(scenario).simulate(scenario)


def simulation_plan(scenario: Scenario) -> SimulationPlan:
    """A run's size, estimated from its scenario alone (no allocation)."""
    return kind_of(scenario).plan(scenario)


def check_run(scenario: Scenario) -> None:
    """Refuse, in one line naming the keys, a run over the budgets; before any work."""
    kind_of(scenario).check(scenario)

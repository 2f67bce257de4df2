"""A run's size, estimated before it starts, and the budgets it must keep."""

from __future__ import annotations

import dataclasses

from quadland.exceptions import ScenarioError

__all__ = ["SimulationPlan", "plan_run", "check_plan", "MEMORY_BUDGET", "MAX_RK4_STEPS"]

#: Most memory a simulation may plan for its arrays, bytes.
MEMORY_BUDGET = 2 << 30
#: Most RK4 steps one simulation may take (about 7 min at l = 100).
MAX_RK4_STEPS = 2e8
#: The node count MAX_RK4_STEPS is for; the limit scales with 100 / l (a step's
#: cost grows with the node count).
REFERENCE_NODES = 100


@dataclasses.dataclass(frozen=True)
class SimulationPlan:
    """What a simulation will need, estimated from its scenario before it starts.

    Attributes
    ----------
    rows : int
        Output rows (trajectory.csv).
    intervals : int
        Hold intervals of the merged time grid (an upper bound).
    rk4_steps : int
        RK4 steps of the whole run (an upper bound).
    memory_bytes : int
        Memory for its arrays (states, outputs, columns, grid), bytes.
    nodes : int
        RBF nodes of its controller (a step's cost grows with them).
    """

    rows: int
    intervals: int
    rk4_steps: int
    memory_bytes: int
    nodes: int


def plan_run(scenario, state_size: int, disturbance_size: int, row_values: int,
             grid_state_values: int = 0) -> SimulationPlan:
    """Estimate a run's size from its scenario's clocks and the loop's vector sizes.

    Parameters
    ----------
    scenario : Scenario
        Its ``[simulation]``, ``[disturbance]`` and ``[controller]`` rates and
        ``rbf.nodes``.
    state_size, disturbance_size : int
        Entries of the loop's state and of its disturbance.
    row_values : int
        Values each output row holds (states, signals, columns), the state included.
    grid_state_values : int
        Values kept at every grid point (cvodes keeps the state at each).
    """
    d = scenario.data
    sim, ctrl, dist = d["simulation"], d["controller"], d["disturbance"]
    T = sim["duration"]
    rows = int(T * sim["output_rate_hz"]) + 2
    clocks = rows + int(T * dist["sample_rate_hz"]) + 2
    if ctrl["rate_hz"] > 0:
        clocks += int(T * ctrl["rate_hz"]) + 2
    memory = 8 * (rows * (row_values + disturbance_size + 12)
                  + clocks * (disturbance_size + 4 + grid_state_values))
    return SimulationPlan(rows - 1, clocks, clocks * sim["rk_steps_per_interval"], memory,
                          int(d["rbf"]["nodes"]))


def check_plan(plan: SimulationPlan) -> None:
    """Refuse, with one line naming the keys, a run over the memory or step budget."""
    if plan.memory_bytes > MEMORY_BUDGET:
        raise ScenarioError(
            f"simulation.duration x simulation.output_rate_hz: {plan.rows:,} output rows need "
            f"about {plan.memory_bytes / 2**30:.1f} GiB, over the {MEMORY_BUDGET / 2**30:g} GiB "
            "limit; lower either")
    l = plan.nodes
    limit = MAX_RK4_STEPS * REFERENCE_NODES / max(l, REFERENCE_NODES // 10)
    if plan.rk4_steps > limit:
        raise ScenarioError(
            f"simulation.duration: the run needs {plan.rk4_steps:.2g} RK4 steps (duration x "
            f"the fastest clock x simulation.rk_steps_per_interval), over the limit of "
            f"{limit:.2g} for {l} RBF nodes; lower one of them")

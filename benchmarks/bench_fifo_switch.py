"""The filter's FIFOs held where neither pushed nor popped (issue 20), paired in one process.

The runtime's simulator of a scenario's default landing (``held``: each FIFO's slots in
a ``Switch``, :func:`quadland_symbolic.landing.estimator_switch.fifo_switch`) against the
same model whose filter stage computes the slots by selection every period
(``selected``: ``conditional_step_function(..., held=False)``, before; the model renamed,
a build of its own). Each build's flight is checked the same bits first (every recorded
row, state and the end state), then both are flown alternately in one process (CPU ms,
median of ``--rounds``; the "baseline" of the lines printed is ``--baseline``).
``joined`` (``--baseline joined``) is the FIFOs held but the finish inside the filter's
stage, its outputs copied out of the stage's work vector (before the finish was a stage
of its own, :func:`~quadland_symbolic.landing.estimator_switch.conditional_step_stages`).
``--callgrind NAME`` flies one build once, for (``<model>``: ``landing_sensed_flat`` for
``highway``, ``landing_sensed`` for ``ship``, ``_selected`` or ``_joined`` appended for
that build)::

    valgrind --tool=callgrind --toggle-collect=qlsim_<model>_controller \\
        --toggle-collect=qlsim_<model>_plant --toggle-collect=qlsim_<model>_free_plant \\
        --toggle-collect=qlsim_<model>_event python benchmarks/bench_fifo_switch.py \\
        --flights highway --callgrind held

Run from the repository root: ``nice -n 10 python benchmarks/bench_fifo_switch.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

import casadi as ca

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import report_flights, timed_flights  # noqa: E402
from bench_delivery_ring import captured  # noqa: E402

from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland_symbolic.landing.estimator import (  # noqa: E402
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
)
from quadland_symbolic.landing.estimator_switch import conditional_step_function  # noqa: E402


def joined_stage(held: bool) -> ca.Function:
    """``sensed_filter`` as one stage (the finish inside it, its outputs copied out of its
    work vector): the FIFOs held, or by selection in its queues every period."""
    f = conditional_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING, held=held)
    ins = f.mx_in()
    return ca.Function("sensed_filter", ins, f.call(ins),
                       ["nav", "imu_now", "vision", "gnss", "range", "datalink", "p_est",
                        "dt", "t"], ["nav_next", "y", "diag"])


def builds(scenario: str):
    """``{"selected": ..., "joined": ..., "held": ...}`` simulators of ``scenario`` (``held``
    the runtime's: the FIFOs held, the finish its own stage), its flight's arguments."""
    held, args, kwargs = captured(scenario)
    model = built_model(held.model)
    loops = {"held": held}
    for name, fifo_held in (("selected", False), ("joined", True)):
        st = model.controller_stages
        stages = tuple(joined_stage(fifo_held) if s.name() == "sensed_filter" else s
                       for s in st.stages if s.name() != "sensed_finish")
        st = dataclasses.replace(st, stages=stages)
        loops[name] = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_{name}",
                                                       controller_stages=st,
                                                       controller=st.function()), "sampled")
    return loops, args, kwargs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--callgrind", choices=("selected", "joined", "held"))
    parser.add_argument("--baseline", choices=("selected", "joined"), default="selected")
    a = parser.parse_args()
    print(f"load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s)
        if a.callgrind:
            loops[a.callgrind].sampled(*args, **kwargs)
            continue
        out = timed_flights({"baseline, libm": loops[a.baseline], "held": loops["held"]},
                            args, kwargs, a.rounds)
        report_flights(s, out, a.rounds, f"of the {a.baseline} build's")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

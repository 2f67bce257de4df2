"""The plant's terms of time alone computed once an instant (issue 20), paired in one process.

The runtime's simulator of a scenario's default landing (``split``: the plant's, free
plant's and event's terms of the time and the parameters alone in functions of their
own, ``<function>_time``, which the driver calls once an instant,
:func:`quadland_symbolic.codegen.time_split.time_split`) against the same model built
without them (``whole``: ``quadland_symbolic.codegen.simulator.HOISTING`` empty, the
model renamed ``<model>_whole``, a build of its own). Each build's flight is checked the
same bits first (every recorded row, state and the end state), then both are flown
alternately in one process (CPU ms, median of ``--rounds``). ``--callgrind NAME`` flies
one build once, for (``<model>``: ``landing_sensed_flat`` for ``highway``,
``landing_sensed`` for ``ship``; ``_whole`` appended for that build; the ``_time``
functions exist only in ``split``)::

    valgrind --tool=callgrind --toggle-collect=qlsim_<model>_controller \\
        --toggle-collect=qlsim_<model>_plant --toggle-collect=qlsim_<model>_free_plant \\
        --toggle-collect=qlsim_<model>_event --toggle-collect=qlsim_<model>_plant_time \\
        --toggle-collect=qlsim_<model>_free_plant_time \\
        --toggle-collect=qlsim_<model>_event_time \\
        python benchmarks/bench_time_split.py --flights ship --callgrind split

The driver's check of the instant (a comparison of 8 bytes a call) is outside the
functions counted, as the driver's loop is.

Run from the repository root: ``nice -n 10 python benchmarks/bench_time_split.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import report_flights, timed_flights  # noqa: E402
from bench_delivery_ring import captured  # noqa: E402

from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland_symbolic.codegen import simulator  # noqa: E402


def builds(scenario: str):
    """``{"whole": ..., "split": ...}`` simulators of ``scenario`` (``split`` the
    runtime's), its flight's arguments."""
    split, args, kwargs = captured(scenario)
    model = built_model(split.model)
    real = simulator.HOISTING
    simulator.HOISTING = ()
    try:
        whole = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_whole"), "sampled")
    finally:
        simulator.HOISTING = real
    return {"whole": whole, "split": split}, args, kwargs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--callgrind", choices=("whole", "split"))
    a = parser.parse_args()
    print(f"load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s)
        if a.callgrind:
            loops[a.callgrind].sampled(*args, **kwargs)
            continue
        out = timed_flights({"baseline, libm": loops["whole"], "split": loops["split"]},
                            args, kwargs, a.rounds)
        report_flights(s, out, a.rounds, "of the whole build's")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

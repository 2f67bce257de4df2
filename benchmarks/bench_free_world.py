"""The compiled flight's world stage far from the deck (issue 20, nineteenth session).

The sensed loop's world stage (``sensed_world``) reads the IMU's truth, the specific force,
off the plant's derivative with the gear's contact (a foot's ``exp``, ``log1p`` and
``tanh``) at every control tick. Where the sampled driver flies its free plant (the gear
more than ``near`` above the deck, before the first contact), the contact's forces are
exactly zero and the stage's free function (``Staged.free``, the IMU's truth of the
plant without the contact) computes the same values; the driver says so with a flag.

Two builds of the runtime's simulator of each of ``--flights`` (the model renamed for
each): ``before`` (``staged_c.FREE_STAGES`` off: the world stage with the contact at every
tick) and ``now``; each flown on the runtime's own arguments of the default landing, the
``now`` flight checked the same bits as ``before``'s (every recorded row, signal, state
and the end state); then flown alternately in one process, CPU ms, median of
``--rounds``. ``--callgrind NAME`` flies one build of ``highway`` once, for::

    valgrind --tool=callgrind --toggle-collect=ffi_call --toggle-collect=closure_fcn \\
        python benchmarks/bench_free_world.py --callgrind now

Run from the repository root: ``nice -n 10 python benchmarks/bench_free_world.py``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import alternated_cpu, flag_builds  # noqa: E402
from bench_flight_params import _bits  # noqa: E402

from quadland_symbolic.codegen import staged_c  # noqa: E402

#: Each build: whether the stages' free functions are written and called.
WAYS = {"before": False, "now": True}


def builds(scenario: str, ways: dict):
    """The runtime's simulator of ``scenario`` built each of ``ways``, and its arguments."""
    return flag_builds(scenario, staged_c, "FREE_STAGES", ways, "fw")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--callgrind", choices=list(WAYS))
    a = parser.parse_args()
    if a.callgrind:
        loops, args, kwargs = builds("highway", {a.callgrind: WAYS[a.callgrind]})
        loops[a.callgrind].sampled(*args, **kwargs)
        return
    print(f"load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s, WAYS)
        runs = {k: loop.sampled(*args, **kwargs) for k, loop in loops.items()}
        same = _bits(runs["now"]) == _bits(runs["before"])
        cpu = alternated_cpu(loops, args, kwargs, a.rounds)
        base = statistics.median(cpu["before"])
        for k, v in cpu.items():
            m = statistics.median(v)
            print(f"- {s} flight alone ({float(runs[k].times[-1]):.1f} s flown), {k}: "
                  f"{1e3 * m:.2f} ms CPU (median of {a.rounds}, {1e3 * min(v):.2f} to "
                  f"{1e3 * max(v):.2f}), {m / base:.3f} of before; the same bits: "
                  f"{same if k == 'now' else '-'}")
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()

"""The compiled flight with its SX bodies' pointers taken once a call (issue 20, twentieth).

CasADi writes each read of an SX function's argument as ``a=arg[i]? arg[i][j] : 0;`` and
each write of a result as ``if (res[i]!=0) res[i][j]=a;``: a test and a branch on the
pointer at every element. ``quadland_symbolic.codegen.simulator.direct_access`` takes the
pointers once a call (zeros for a null argument, a sink for a null result), the same values.

Two builds of the runtime's simulator of each of ``--flights`` (the model renamed for each):
``before`` (``simulator.DIRECT_ACCESS`` off: CasADi's C as it writes it) and ``now``; each
flown on the runtime's own arguments of the default landing, the ``now`` flight checked the
same bits as ``before``'s (every recorded row, signal, state and the end state); then flown
alternately in one process, CPU ms, median of ``--rounds``, and the median of the rounds'
paired ratios (each round's two flights back to back). ``--callgrind NAME`` flies one build
of ``highway`` once, for::

    valgrind --tool=callgrind --toggle-collect=ffi_call --toggle-collect=closure_fcn \\
        python benchmarks/bench_direct_access.py --callgrind now

Run from the repository root: ``nice -n 10 python benchmarks/bench_direct_access.py``.
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

from quadland_symbolic.codegen import simulator  # noqa: E402

#: Each build: whether the SX bodies read and write through pointers taken once a call.
WAYS = {"before": False, "now": True}


def builds(scenario: str, ways: dict):
    """The runtime's simulator of ``scenario`` built each of ``ways``, and its arguments."""
    return flag_builds(scenario, simulator, "DIRECT_ACCESS", ways, "da")


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
        pairs = [n / b for n, b in zip(cpu["now"], cpu["before"], strict=True)]
        q = statistics.quantiles(pairs, n=4)
        print(f"- {s}, paired: the rounds' now / before {statistics.median(pairs):.3f} "
              f"(median; quartiles {q[0]:.3f} to {q[2]:.3f}), now the faster in "
              f"{sum(r < 1 for r in pairs)} of {a.rounds}")
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()

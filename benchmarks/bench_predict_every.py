"""The filter's horizon predicted every N-th control period (issue 20, twelfth session).

``estimator.predict_every = N`` (docs/estimator.md, E6b) is a parameter of the filter,
not of the build: the same compiled simulator flies every ``N``, its prediction in a
``Switch`` that runs it on one step in ``N``. For each of ``--every`` (default 1, 2, 3)
the runtime's simulator and arguments of ``--scenario``'s default landing with
``estimator.predict_every = N`` (captured as ``bench_delivery_ring.py`` does), then:

* the last recorded row (time, relative position and vertical speed) of each, so that a
  change of the flight shows;
* the flights alternately in one process, CPU ms, median of ``--rounds``, and the ratio
  to ``N = 1`` of the same round (the median of those);
* ``--callgrind N``: one flight of ``N`` only, for::

    valgrind --tool=callgrind --toggle-collect='qlsim_*' \\
        python benchmarks/bench_predict_every.py --callgrind 2

Run from the repository root: ``nice -n 10 python benchmarks/bench_predict_every.py``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import quadland
from quadland.engine.compiled import CompiledLoop


class _Captured(Exception):
    pass


def captured(scenario: str, every: int):
    """The runtime's simulator of the default flight with ``predict_every`` and its
    arguments."""
    seen, real = {}, CompiledLoop.sampled

    def capture(self, *args, **kwargs):
        seen.update(loop=self, args=args, kwargs=kwargs)
        raise _Captured

    CompiledLoop.sampled = capture
    try:
        quadland.simulate(quadland.load_scenario(
            scenario, {"estimator.predict_every": float(every)}))
    except _Captured:
        pass
    finally:
        CompiledLoop.sampled = real
    return seen["loop"], seen["args"], seen["kwargs"]


def touchdown(scenario: str, every: int) -> str:
    """The last recorded row's time and relative motion of the default landing."""
    r = quadland.simulate(quadland.load_scenario(
        scenario, {"estimator.predict_every": float(every)}))
    return ", ".join(f"{k} {np.asarray(r[k])[-1]:.5g}" for k in r.columns
                     if k in ("t", "x_e", "y_e", "z_e", "vz_e"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway")
    parser.add_argument("--every", default="1,2,3")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--callgrind", type=int)
    a = parser.parse_args()
    if a.callgrind is not None:
        loop, args, kwargs = captured(a.scenario, a.callgrind)
        loop.sampled(*args, **kwargs)
        return
    every = [int(n) for n in a.every.split(",")]
    flights = {n: captured(a.scenario, n) for n in every}
    assert len({id(f[0]) for f in flights.values()}) == 1, "one simulator for every N"
    for n in every:
        print(f"- N = {n}: {touchdown(a.scenario, n)}", flush=True)
    cpu = {n: [] for n in every}
    for _ in range(a.rounds):
        for n in every:
            loop, args, kwargs = flights[n]
            c0 = time.process_time()
            loop.sampled(*args, **kwargs)
            cpu[n].append(time.process_time() - c0)
    print(f"\n{a.scenario}, the compiled flight alone, CPU ms, median of {a.rounds} "
          "(ratio to N = 1, median of the rounds' ratios):")
    base = np.array(cpu[every[0]])
    for n in every:
        ratio = statistics.median(np.array(cpu[n]) / base)
        print(f"| N = {n} | {1e3 * statistics.median(cpu[n]):.1f} | {ratio:.3f} |")


if __name__ == "__main__":
    main()

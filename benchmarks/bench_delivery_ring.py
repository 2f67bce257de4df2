"""The sensors' delay lines as rings against the shift (issue 20): one flight, paired.

The runtime's compiled simulator of a landing on sensors keeps each sensor's delay
line in a ring (``Staged.rings``); the same model built with ``rings=()`` is the
simulator that shifts every line by a record each control tick (the previous
generated code, its world stage split in two). Both fly the runtime's own arguments
(captured from ``quadland.simulate`` of the scenario), checked the same bits first,
then timed alternately in this one process: CPU time (``time.process_time``) of the
compiled flight alone, median of ``--rounds``.

``--callgrind`` instead runs one flight of the chosen variant under the caller's
valgrind (``valgrind --tool=callgrind --toggle-collect='qlsim_*_sampled'``): the
instructions of the compiled flight, which the machine's load does not change::

    python benchmarks/bench_delivery_ring.py --scenario highway --rounds 15
    valgrind --tool=callgrind --callgrind-out-file=/tmp/ring.cg \\
        --toggle-collect='qlsim_*_sampled' \\
        python benchmarks/bench_delivery_ring.py --callgrind ring
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import time

import numpy as np

import quadland
from quadland.engine.compiled import CompiledLoop, built_model


class _Captured(Exception):
    pass


def captured(scenario: str):
    """The runtime's simulator of ``scenario``'s default flight and its arguments."""
    seen, real = {}, CompiledLoop.sampled

    def capture(self, *args, **kwargs):
        seen.update(loop=self, args=args, kwargs=kwargs)
        raise _Captured

    CompiledLoop.sampled = capture
    try:
        quadland.simulate(quadland.load_scenario(scenario))
    except _Captured:
        pass
    finally:
        CompiledLoop.sampled = real
    return seen["loop"], seen["args"], seen["kwargs"]


def twins(scenario: str):
    """``{"shift": ..., "ring": ...}`` simulators, and the flight's arguments."""
    ring, args, kwargs = captured(scenario)
    model = built_model(ring.model)
    stages = dataclasses.replace(model.controller_stages, rings=())
    shift = CompiledLoop(dataclasses.replace(model, name=model.name + "_shift",
                                             controller_stages=stages), "sampled")
    return {"shift": shift, "ring": ring}, args, kwargs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--callgrind", choices=("shift", "ring"))
    a = parser.parse_args()
    loops, args, kwargs = twins(a.scenario)
    if a.callgrind:
        loops[a.callgrind].sampled(*args, **kwargs)
        return
    runs = {k: loop.sampled(*args, **kwargs) for k, loop in loops.items()}
    x, y = runs["shift"], runs["ring"]
    same = all(np.array_equal(np.asarray(p).view(np.uint64), np.asarray(q).view(np.uint64))
               for p, q in ((x.X, y.X), (x.R, y.R), (x.times, y.times), (x.x_end, y.x_end)))
    assert same and x.status == y.status, "the ring's flight is not the shift's"
    ticks = int(np.floor(x.times[-1] * 250 + 1e-6)) + 1
    print(f"{a.scenario}: {x.times[-1]:.2f} s flown (about {ticks} control ticks), the same "
          f"bits; load average {os.getloadavg()}")
    cpu: dict = {k: [] for k in loops}
    for r in range(a.rounds):
        for k in (("shift", "ring") if r % 2 == 0 else ("ring", "shift")):
            t0 = time.process_time()
            loops[k].sampled(*args, **kwargs)
            cpu[k].append(time.process_time() - t0)
    med = {k: 1e3 * statistics.median(v) for k, v in cpu.items()}
    for k, v in cpu.items():
        print(f"- {k}: {med[k]:.1f} ms CPU a flight (median of {a.rounds}, "
              f"{1e3 * min(v):.1f} to {1e3 * max(v):.1f}), "
              f"{1e3 * med[k] / ticks:.1f} us a control tick")
    print(f"- ring / shift: {med['ring'] / med['shift']:.3f}; load average {os.getloadavg()}")


if __name__ == "__main__":
    main()

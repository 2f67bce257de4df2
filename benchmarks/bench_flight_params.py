"""The compiled flight's cost (issue 20, eighteenth session): the controller's values of its
parameters alone once a flight, and GCC's loop vectorizer's dynamic cost model, paired.

Two changes to the runtime's simulators, each measured against its absence in one run:

* ``cut``: the staged controller's SX stages cut on the parameters (``pc``, ``pp``), their
  values of the parameters alone computed once before the first tick
  (``quadland_symbolic.codegen.staged_c``); ``uncut``: ``CUT_PARAMS`` off, as before;
* ``vector``: ``-fvect-cost-model=dynamic`` (``quadland.engine.machine.VECTOR_FLAGS``);
  without it, the machine's flags as before.

Four builds of the runtime's simulator of each of ``--flights`` (the model renamed for
each, a build of its own; ``-O3`` with the shipped flags as a fifth, for reference), each
flown on the runtime's own arguments of the default landing; every build's flight checked
the same bits as the first's (every recorded row, signal, state and the end state); then
the builds flown alternately in one process, CPU ms, median of ``--rounds``.
``--compile`` also compiles each flag set's C of the ``highway`` simulator in an empty
cache (CPU of the compilers, ``RUSAGE_CHILDREN``). ``--callgrind NAME`` flies one build's
flight once, for::

    valgrind --tool=callgrind --toggle-collect=ffi_call --toggle-collect=closure_fcn \\
        python benchmarks/bench_flight_params.py --callgrind "cut, vector"

(the sensors' table's callback, ``closure_fcn``, toggled off inside the flight's call).
Run from the repository root: ``nice -n 10 python benchmarks/bench_flight_params.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import resource
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import alternated_cpu  # noqa: E402
from bench_delivery_ring import captured  # noqa: E402

from quadland.engine import build  # noqa: E402
from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland.engine.machine import VECTOR_FLAGS  # noqa: E402
from quadland_symbolic.codegen import simulator, staged_c  # noqa: E402

#: Each build: (cut the stages, the vectorizer's flag, optimization level).
WAYS = {"uncut, scalar (before)": (False, False, "-O2"), "cut, scalar": (True, False, "-O2"),
        "uncut, vector": (False, True, "-O2"), "cut, vector (now)": (True, True, "-O2"),
        "cut, -O3": (True, True, "-O3")}


def _flags(vector: bool):
    real = build.machine_flags
    return real if vector else (lambda cc: tuple(f for f in real(cc) if f not in VECTOR_FLAGS))


def builds(scenario: str, ways: dict):
    """The runtime's simulator of ``scenario`` built each of ``ways``, and its arguments."""
    loop, args, kwargs = captured(scenario)
    model = built_model(loop.model)
    real, loops = build.machine_flags, {}
    for name, (cut, vector, opt) in ways.items():
        i = list(WAYS).index(name)                   # each way's model name, whichever asked
        build.machine_flags, staged_c.CUT_PARAMS = _flags(vector), cut
        try:
            loops[name] = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_w{i}"),
                                       "sampled", opt=opt)
        finally:
            build.machine_flags, staged_c.CUT_PARAMS = real, True
    return loops, args, kwargs


def _bits(run) -> bytes:
    return b"".join(np.ascontiguousarray(getattr(run, a)).tobytes()
                    for a in ("X", "R", "times", "x_end")) + str(run.status).encode()


def timed(loops, args, kwargs, rounds: int) -> tuple[dict, dict, float]:
    """CPU seconds of each build's flight, alternately; whether each flew the first's bits."""
    runs = {k: loop.sampled(*args, **kwargs) for k, loop in loops.items()}
    ref = _bits(next(iter(runs.values())))
    same = {k: _bits(r) == ref for k, r in runs.items()}
    return (alternated_cpu(loops, args, kwargs, rounds), same,
            float(next(iter(runs.values())).times[-1]))


def compile_cpu(ways: dict) -> None:
    """Each flag set's compile CPU of the ``highway`` simulator, in an empty cache."""
    loop, _, _ = captured("highway")
    model = built_model(loop.model)
    files = simulator.simulator_sources(model, "sampled")
    sources = tuple(sorted(n for n in files if n.endswith(".c")))
    real = build.machine_flags
    for name, (_, vector, opt) in ways.items():
        if name.startswith("uncut"):
            continue
        with tempfile.TemporaryDirectory() as tmp:
            old = os.environ.get("XDG_CACHE_HOME")
            os.environ["XDG_CACHE_HOME"] = tmp
            build.machine_flags = _flags(vector)
            c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            try:
                build.build_library(files, sources, opt, "libbench", strict=False)
            finally:
                build.machine_flags = real
                if old is None:
                    del os.environ["XDG_CACHE_HOME"]
                else:
                    os.environ["XDG_CACHE_HOME"] = old
            c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        print(f"- compile, highway's simulator, {name}: "
              f"{c1.ru_utime + c1.ru_stime - c0.ru_utime - c0.ru_stime:.1f} s CPU")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--compile", action="store_true")
    parser.add_argument("--callgrind", choices=list(WAYS))
    a = parser.parse_args()
    if a.callgrind:
        loops, args, kwargs = builds("highway", {a.callgrind: WAYS[a.callgrind]})
        loops[a.callgrind].sampled(*args, **kwargs)
        return
    cc = build.find_compiler()
    print(f"compiler: {build.compiler_identity(cc).splitlines()[1]}; machine flags: "
          f"{' '.join(build.machine_flags(cc)) or '(none)'}; load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s, WAYS)
        cpu, same, flown = timed(loops, args, kwargs, a.rounds)
        base = statistics.median(next(iter(cpu.values())))
        for k, v in cpu.items():
            m = statistics.median(v)
            print(f"- {s} flight alone ({flown:.1f} s flown), {k}: {1e3 * m:.2f} ms CPU "
                  f"(median of {a.rounds}, {1e3 * min(v):.2f} to {1e3 * max(v):.2f}), "
                  f"{m / base:.3f} of before; "
                  f"{'the same bits' if same[k] else 'DIFFERENT BITS'}")
    if a.compile:
        compile_cpu(WAYS)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

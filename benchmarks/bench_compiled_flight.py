"""The compiled flight's cost (issue 20): the machine's AVX2 and the inline min/max, paired.

Two changes to how the runtime's simulators are built, each measured against its
absence in one run:

* ``machine``: ``-mavx2 -mno-fma -ffp-contract=off`` where the CPU has AVX2
  (``quadland.engine.machine``); ``baseline``: the build without them (``machine_flags``
  patched to give none);
* ``inline``: CasADi's ``casadi_fmax``/``casadi_fmin`` compared inline
  (``quadland_symbolic.codegen.simulator.inline_min_max``); ``libm``: libm's calls, as
  CasADi writes them (``INLINE_MIN_MAX`` off, the model renamed so that it is a build
  of its own).

Measured, side by side:

* the compiled flight alone (the runtime's own arguments of the default landing, as
  ``bench_delivery_ring.py`` captures them), the four builds alternately in one process,
  CPU ms, median of ``--rounds``, each build's flight checked the same bits first;
* with ``--before TREE`` (``git archive <commit> | tar -x -C TREE``): every column and
  state of ``quadland.simulate`` of each of ``--scenarios``, SHA-256, in a fresh process
  on the tree and on this code; and a one-worker ``highway`` campaign of ``--small`` and
  ``--large`` runs on each, in fresh child processes, interleaved: the CPU per landing is
  the slope between the two (the fixed costs cancel); their ``runs.csv`` byte for byte;
* the pure-C reference ``generated/example/land -q`` (7 runs).

``--extra NAME=FLAG,FLAG`` adds a build of other flags (with the inline min/max) to the
flights, e.g. ``native=-march=native,-ffp-contract=off``. Run from the repository root::

    git archive 42d6c22 | (mkdir -p /tmp/before && tar -x -C /tmp/before)
    nice -n 10 python benchmarks/bench_compiled_flight.py --before /tmp/before
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_delivery_ring import captured  # noqa: E402
from bench_landing_costs import child  # noqa: E402
from land_reference import land_q  # noqa: E402

from quadland.engine import build  # noqa: E402
from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland_symbolic.codegen import simulator  # noqa: E402

#: SHA-256 of every column and state of each scenario's default landing (argv[1:]).
DIGESTS = r"""
import hashlib, json, sys
import numpy as np
import quadland
out = {}
for s in sys.argv[1:]:
    r = quadland.simulate(quadland.load_scenario(s))
    d = hashlib.sha256()
    for name in r.columns:
        d.update(name.encode() + b"\0" + np.ascontiguousarray(r[name]).tobytes())
    d.update(np.ascontiguousarray(r.states).tobytes())
    out[s] = d.hexdigest()
print(json.dumps(out))
"""

#: A one-worker highway campaign of argv[1] runs: CPU, wall, runs.csv's SHA-256.
CAMPAIGN = r"""
import hashlib, json, sys, tempfile, time
from pathlib import Path
from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario

warm_up(load_scenario("highway"))
with tempfile.TemporaryDirectory() as tmp:
    c0, w0 = time.process_time(), time.perf_counter()
    r = run_campaign("highway", runs=int(sys.argv[1]), out=Path(tmp) / "c", plots=False,
                     workers=1)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    s = json.loads((r.folder / "summary.json").read_text())
    csv = hashlib.sha256((r.folder / "runs.csv").read_bytes()).hexdigest()
print(json.dumps({"cpu": cpu, "wall": wall, "csv": csv, "successes": s["successes"],
                  "runs": s["runs"]}))
"""


def builds(scenario: str, extra: dict):
    """The runtime's simulator of ``scenario`` built four ways (and ``extra``'s), and the
    flight's arguments."""
    loop, args, kwargs = captured(scenario)
    model = built_model(loop.model)
    real = build.machine_flags
    loops = {}
    ways = {"baseline, libm": (lambda cc: (), False), "baseline, inline": (lambda cc: (), True),
            "machine, libm": (real, False), "machine, inline": (real, True),
            **{k: ((lambda cc, f=f: f), True) for k, f in extra.items()}}
    for name, (flags, inline) in ways.items():
        build.machine_flags, simulator.INLINE_MIN_MAX = flags, inline
        try:
            suffix = "" if inline else "_libm"       # a build of its own (its key)
            loops[name] = CompiledLoop(dataclasses.replace(model, name=model.name + suffix),
                                       "sampled")
        finally:
            build.machine_flags, simulator.INLINE_MIN_MAX = real, True
    return loops, args, kwargs


def flag_builds(scenario: str, module, flag: str, ways: dict, tag: str):
    """The runtime's simulator of ``scenario`` built once for each of ``ways`` (name: the
    value of ``module.flag`` for that build, a name of its own per value: ``tag`` and the
    value), the flag set back to True after each; and the flight's arguments."""
    loop, args, kwargs = captured(scenario)
    model = built_model(loop.model)
    loops = {}
    for name, value in ways.items():
        setattr(module, flag, value)
        try:
            loops[name] = CompiledLoop(
                dataclasses.replace(model, name=f"{model.name}_{tag}{value:d}"), "sampled")
        finally:
            setattr(module, flag, True)
    return loops, args, kwargs


def timed_flights(loops, args, kwargs, rounds: int) -> dict:
    """CPU seconds of each build's flight, alternately; checked the same bits first."""
    runs = {k: loop.sampled(*args, **kwargs) for k, loop in loops.items()}
    ref = runs["baseline, libm"]
    same = {k: all(np.array_equal(np.asarray(getattr(r, a)).view(np.uint64),
                                  np.asarray(getattr(ref, a)).view(np.uint64))
                   for a in ("X", "R", "times", "x_end")) and r.status == ref.status
            for k, r in runs.items()}
    return {"cpu": alternated_cpu(loops, args, kwargs, rounds), "same": same,
            "flown": float(ref.times[-1])}


def alternated_cpu(loops, args, kwargs, rounds: int) -> dict:
    """CPU seconds of each build's flight, ``rounds`` times, the order reversed each round."""
    cpu: dict = {k: [] for k in loops}
    names = list(loops)
    for r in range(rounds):
        for k in names if r % 2 == 0 else names[::-1]:
            t0 = time.process_time()
            loops[k].sampled(*args, **kwargs)
            cpu[k].append(time.process_time() - t0)
    return cpu


def report_flights(scenario: str, out: dict, rounds: int, of: str) -> None:
    """Print :func:`timed_flights`' medians per build, each over the "baseline, libm"
    build's (``of`` names that ratio), and whether its bits are the baseline's."""
    base = statistics.median(out["cpu"]["baseline, libm"])
    for k, v in out["cpu"].items():
        m = statistics.median(v)
        print(f"- {scenario} flight alone ({out['flown']:.1f} s flown), {k}: {1e3 * m:.2f} ms "
              f"CPU (median of {rounds}, {1e3 * min(v):.2f} to {1e3 * max(v):.2f}), "
              f"{m / base:.3f} {of}; "
              f"{'the same bits' if out['same'][k] else 'DIFFERENT BITS'}")


def campaigns(before: Path, small: int, large: int, rounds: int) -> None:
    """The one-worker campaign's CPU per landing, before and now, interleaved."""
    trees = {"before": before, "now": None}
    for tree in trees.values():                      # build or load each tree's simulators
        child(CAMPAIGN, tree, "2")
    res: dict = {k: {"small": [], "large": []} for k in trees}
    for _ in range(rounds):
        for size, n in (("small", small), ("large", large)):
            for k, tree in trees.items():
                res[k][size].append(child(CAMPAIGN, tree, str(n)))
    span = large - small
    for k, v in res.items():
        cpu = [(b["cpu"] - s["cpu"]) / span for s, b in zip(v["small"], v["large"], strict=True)]
        wall = [(b["wall"] - s["wall"]) / span
                for s, b in zip(v["small"], v["large"], strict=True)]
        print(f"- campaign, one worker, per landing ({small} to {large} highway runs), {k}: "
              f"CPU {', '.join(f'{1e3 * c:.1f}' for c in cpu)} ms, wall "
              f"{', '.join(f'{1e3 * w:.1f}' for w in wall)} ms; the {large}-run campaign: "
              f"{v['large'][-1]['successes']} of {v['large'][-1]['runs']} landed")
    for size, n in (("small", small), ("large", large)):
        same = {r["csv"] for k in res for r in res[k][size]}
        print(f"- the {n}-run campaigns' runs.csv, before and now: "
              f"{'byte for byte the same' if len(same) == 1 else 'DIFFERENT'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path)
    parser.add_argument("--scenarios", default="highway,ship,turning,highway_100,ship_ss5")
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--small", type=int, default=60)
    parser.add_argument("--large", type=int, default=300)
    parser.add_argument("--campaign-rounds", type=int, default=1)
    parser.add_argument("--extra", action="append", default=[])
    a = parser.parse_args()
    extra = {k: tuple(v.split(",")) for k, v in (e.split("=", 1) for e in a.extra)}
    cc = build.find_compiler()
    print(f"compiler: {build.compiler_identity(cc).splitlines()[1]}; machine flags: "
          f"{' '.join(build.machine_flags(cc)) or '(none)'}; load average {os.getloadavg()}")
    if a.before is not None and a.scenarios:
        scenarios = a.scenarios.split(",")
        was, now = child(DIGESTS, a.before.resolve(), *scenarios), child(DIGESTS, None,
                                                                           *scenarios)
        for s in scenarios:
            print(f"- {s}: every column and state, before and now: "
                  f"{'the same bits' if was[s] == now[s] else 'DIFFERENT'}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s, extra)
        report_flights(s, timed_flights(loops, args, kwargs, a.rounds), a.rounds,
                       "of baseline, libm")
    ref = land_q(7)
    print(f"- `land -q`: {1e3 * statistics.median(ref):.1f} ms CPU (median of 7)")
    if a.before is not None and a.campaign_rounds:
        campaigns(a.before.resolve(), a.small, a.large, a.campaign_rounds)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

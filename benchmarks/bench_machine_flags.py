"""The simulators built for the machine's own instructions against the baseline (issue 20).

``quadland.engine.machine.machine_flags`` adds ``-mavx2`` (no FMA, no contraction) to
the runtime's simulators on an x86-64 CPU with AVX2. "baseline" is the same build
without them (``machine_flags`` patched to give none: the flags every x86-64 has),
"machine" the runtime's. In one run, side by side:

* the same bits: every column and state of ``quadland.simulate`` of each scenario
  (``--scenarios``), both builds;
* the compiled flight alone (the runtime's own arguments of the default landing, as
  ``bench_delivery_ring.py`` captures them), the two builds alternately in one process,
  CPU ms, median of ``--rounds``;
* a one-worker ``highway`` campaign of ``--small`` and ``--large`` runs in fresh
  child processes, the builds interleaved: the CPU per landing is the slope between
  the two (the fixed costs cancel); the campaigns' ``runs.csv`` compared byte for byte;
* the pure-C reference ``generated/example/land -q`` (7 runs).

Other flags can be measured beside them with ``--extra NAME=FLAG,FLAG`` (e.g.
``O3=-O3`` or ``native=-march=native,-ffp-contract=off``): the flight alone, and the
same-bits check of the first scenario. Run from the repository root::

    nice -n 10 python benchmarks/bench_machine_flags.py --rounds 15
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_delivery_ring import captured  # noqa: E402
from land_reference import land_q  # noqa: E402

import quadland  # noqa: E402
from quadland.engine import build  # noqa: E402
from quadland.engine.compiled import CompiledLoop, compiled_loop  # noqa: E402
from quadland.engine.machine import machine_flags  # noqa: E402

#: A one-worker campaign in a child, on the build named by argv[2]: CPU, wall, runs.csv.
CAMPAIGN = r"""
import hashlib, json, os, sys, tempfile, time
from pathlib import Path
from quadland.engine import build
if sys.argv[2] == "baseline":
    build.machine_flags = lambda cc: ()
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


def child(build_name: str, runs: int) -> dict:
    done = subprocess.run([sys.executable, "-c", CAMPAIGN, str(runs), build_name],
                          cwd=tempfile.gettempdir(), capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def flags_of(name: str, extra: dict):
    """``machine_flags`` of the build ``name``."""
    if name == "baseline":
        return lambda cc: ()
    if name == "machine":
        return machine_flags
    return lambda cc: extra[name]


def simulate_digest(scenario: str, flags) -> str:
    """SHA-256 of every column and state of ``scenario``'s landing on the build ``flags``."""
    real = build.machine_flags
    build.machine_flags = flags
    compiled_loop.cache_clear()
    try:
        result = quadland.simulate(quadland.load_scenario(scenario))
    finally:
        build.machine_flags = real
        compiled_loop.cache_clear()
    digest = hashlib.sha256()
    for name in result.columns:
        digest.update(name.encode() + np.ascontiguousarray(result[name]).tobytes())
    digest.update(np.ascontiguousarray(result.states).tobytes())
    return digest.hexdigest()


def flight_twins(scenario: str, names, extra):
    """The runtime's simulator of ``scenario`` built on each of ``names``, and its arguments."""
    loop, args, kwargs = captured(scenario)
    loops, real = {}, build.machine_flags
    for name in names:
        build.machine_flags = flags_of(name, extra)
        try:
            loops[name] = CompiledLoop(loop.model, "sampled")
        finally:
            build.machine_flags = real
    return loops, args, kwargs


def timed_flights(loops, args, kwargs, rounds: int) -> dict:
    """CPU seconds of each build's flight, alternately; checked the same bits first."""
    runs = {k: loop.sampled(*args, **kwargs) for k, loop in loops.items()}
    ref = runs["baseline"]
    same = {k: all(np.array_equal(np.asarray(getattr(r, a)).view(np.uint64),
                                  np.asarray(getattr(ref, a)).view(np.uint64))
                   for a in ("X", "R", "times", "x_end")) and r.status == ref.status
            for k, r in runs.items()}
    cpu: dict = {k: [] for k in loops}
    names = list(loops)
    for r in range(rounds):
        for k in names if r % 2 == 0 else names[::-1]:
            t0 = time.process_time()
            loops[k].sampled(*args, **kwargs)
            cpu[k].append(time.process_time() - t0)
    return {"cpu": cpu, "same": same, "flown": float(ref.times[-1])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", default="highway,ship,turning,highway_100,ship_ss5")
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--small", type=int, default=60)
    parser.add_argument("--large", type=int, default=300)
    parser.add_argument("--campaign-rounds", type=int, default=1)
    parser.add_argument("--extra", action="append", default=[])
    a = parser.parse_args()
    extra = {k: tuple(v.split(",")) for k, v in (e.split("=", 1) for e in a.extra)}
    cc = build.find_compiler()
    print(f"compiler: {build.compiler_identity(cc).splitlines()[1]}; machine flags: "
          f"{' '.join(build.machine_flags(cc)) or '(none)'}; load average {os.getloadavg()}")
    for i, s in enumerate(a.scenarios.split(",")):
        names = ("baseline", "machine", *(extra if i == 0 else ()))
        digests = {n: simulate_digest(s, flags_of(n, extra)) for n in names}
        verdict = ", ".join(f"{n} {'the same bits' if d == digests['baseline'] else 'DIFFERS'}"
                            for n, d in digests.items() if n != "baseline")
        print(f"- {s}: every column and state: {verdict}")
    for s in a.flights.split(","):
        loops, args, kwargs = flight_twins(s, ("baseline", "machine", *extra), extra)
        out = timed_flights(loops, args, kwargs, a.rounds)
        base = statistics.median(out["cpu"]["baseline"])
        for k, v in out["cpu"].items():
            m = statistics.median(v)
            print(f"- {s} flight alone ({out['flown']:.1f} s flown), {k}: {1e3 * m:.2f} ms CPU "
                  f"(median of {a.rounds}, {1e3 * min(v):.2f} to {1e3 * max(v):.2f}), "
                  f"{m / base:.3f} of the baseline, "
                  f"{'the same bits' if out['same'][k] else 'DIFFERENT BITS'}")
    ref = land_q(7)
    print(f"- `land -q`: {1e3 * statistics.median(ref):.1f} ms CPU (median of 7)")
    if not a.campaign_rounds:
        return
    res: dict = {k: {"small": [], "large": []} for k in ("baseline", "machine")}
    for _ in range(a.campaign_rounds):
        for size in ("small", "large"):
            for k in res:
                res[k][size].append(child(k, getattr(a, size)))
    span = a.large - a.small
    for k, v in res.items():
        cpu = [(b["cpu"] - s["cpu"]) / span for s, b in zip(v["small"], v["large"], strict=True)]
        print(f"- campaign, one worker, CPU per landing ({a.small} to {a.large} highway runs), "
              f"{k}: {', '.join(f'{1e3 * c:.1f}' for c in cpu)} ms; the {a.large}-run "
              f"campaign: {v['large'][-1]['successes']} of {v['large'][-1]['runs']} landed")
    for size in ("small", "large"):
        same = {r["csv"] for k in res for r in res[k][size]}
        print(f"- the {getattr(a, size)}-run campaigns' runs.csv: "
              f"{'byte for byte the same' if len(same) == 1 else 'DIFFERENT'}")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

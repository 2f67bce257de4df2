"""An envelope's runs without a touchdown against its landings, the workers' load, and a
profile-guided build of the simulator (issue 20).

Issue 20's map (``highway``, the car at 5 to 35 m/s against the crosswind 0 to 20 m/s,
20 x 20 cells of 30 runs). Three measurements:

* ``--split N`` flies ``N`` runs spread over the map (run ``(7309 i + 11) mod 12000``), in
  the order an envelope flies them (:func:`~quadland.campaign.grid.flight_order`, draws kept
  as a worker keeps them, one BLAS thread), in one child process, and times each part of a
  run (CPU, wrappers around the functions ``simulate_landing`` calls); the runs are grouped
  into those without a touchdown (flown to ``simulation.duration``) and the rest::

      nice -n 10 python benchmarks/bench_envelope_long_runs.py --split 200

* ``--phases N`` flies ``N`` landings of replicate 0 in slow cells twice each, whole and
  with ``simulation.duration`` 0.05 s before their touchdown (three rounds, medians): the
  compiled flight's CPU before the touchdown per simulated second, and what the last 2.05
  s (the first contact and the ride to ``landing.settle_time``) add::

      nice -n 10 python benchmarks/bench_envelope_long_runs.py --phases 40

* ``--schedule RUNS_CSV`` replays a whole map's runs on two workers as
  :func:`~quadland.campaign.local.pool_runs` feeds them (chunks of
  :func:`~quadland.campaign.local.chunk_size` runs, :data:`~quadland.campaign.local.AHEAD`
  chunks queued on each), each run costing what ``--split`` measured per simulated second
  (``--ms-per-s`` for the runs without a touchdown and the others, ``--ms-fixed`` a run),
  its flown time from ``RUNS_CSV`` (a map's runs.csv): the two workers' finishing times in
  the envelope's order and with the longest runs first::

      python benchmarks/bench_envelope_long_runs.py --schedule /tmp/env/runs.csv

* ``--pgo ROUNDS`` builds the sensed flat-deck loop's sampled simulator (the one the map
  flies) twice from its C, at the runtime's flags (``quadland.engine.build``) and with GCC's
  profile-guided optimization (``-fprofile-generate``, a training flight of ``--train``
  runs of each group on replicates 1 and 2, then ``-fprofile-use
  -fprofile-partial-training``), puts each in a copy of the build cache and flies replicate
  0's runs of each group in child processes alternating between the two caches: CPU ms a
  run, medians, and the SHA-256 of the runs' outcomes, which must be the same. With
  ``--command K`` the children are the whole command instead, ``quadland envelope`` over
  the map at ``K`` runs a cell, ``--no-plots``: the CPU of the command and all its
  processes and its runs.csv's SHA-256::

      nice -n 10 python benchmarks/bench_envelope_long_runs.py --pgo 3 --runs 30
      nice -n 10 python benchmarks/bench_envelope_long_runs.py --pgo 2 --command 3
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import heapq
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

AXES = ["initial.velocity2[0]=5:35:20", "wind.mean[1]=0:20:20"]

SPLIT = r'''
import functools, json, sys, time
from threadpoolctl import threadpool_limits
from quadland.engine.heap import keep_freed_memory
threadpool_limits(1)
keep_freed_memory()
from quadland.campaign.fly import fly, warm_up
from quadland.campaign.grid import KEEP_BYTES, cell_draws, flight_order, plan_envelope
from quadland.engine import compiled
from quadland.kinds.landing import report, simulate
runs, AXES = int(sys.argv[1]), json.loads(sys.argv[2])
env = plan_envelope("highway", None, AXES, 30)
warm_up(env.base)
picks = flight_order(env, sorted({(7309 * i + 11) % env.runs for i in range(runs)}))
draws = list(cell_draws(env, picks))
fly(env.base, draws[-1], env.spec.limits)          # the simulator loaded, SciPy imported
parts = {}
def timed(owner, name, label):
    f = getattr(owner, name)
    @functools.wraps(f)
    def wrapper(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            parts[label] = parts.get(label, 0.0) + time.process_time() - t
    setattr(owner, name, wrapper)
for owner, name, label in (
        (compiled.CompiledLoop, "sampled", "the compiled flight (`sampled`)"),
        (compiled.CompiledLoop, "outputs", "the outputs' C over the rows (`outputs`)"),
        (simulate, "_first_contact", "`_first_contact` (with the outputs)"),
        (simulate, "_result", "the result's columns (`_result`)"),
        (simulate, "landing_values", "the loop's vectors (`landing_values`)"),
        (simulate, "landing_disturbance", "the disturbance (`landing_disturbance`)"),
        (simulate, "sensed_vectors", "the filter's start (`sensed_vectors`)"),
        (report, "landing_run_metrics", "the metrics")):
    timed(owner, name, label)
groups = {}
for d in draws:
    parts.clear()
    t = time.process_time()
    o = fly(env.base, d, env.spec.limits, KEEP_BYTES)
    cpu = time.process_time() - t
    td = o.metrics.get("touchdown_time")
    key = "no touchdown" if o.status == "ok" and td is None else "touched down or failed"
    flown = env.base["simulation.duration"] if td is None else min(
        td + env.base["landing.settle_time"], env.base["simulation.duration"])
    g = groups.setdefault(key, {"runs": 0, "flown": 0.0, "cpu": 0.0, "parts": {}})
    g["runs"] += 1
    g["flown"] += flown
    g["cpu"] += cpu
    for k, v in parts.items():
        g["parts"][k] = g["parts"].get(k, 0.0) + v
print(json.dumps(groups))
'''

PHASES = r'''
import json, statistics, sys, time
from threadpoolctl import threadpool_limits
from quadland.engine.heap import keep_freed_memory
threadpool_limits(1)
keep_freed_memory()
from quadland.campaign.dispersed import dispersed
from quadland.campaign.fly import fly, warm_up
from quadland.campaign.grid import KEEP_BYTES, cell_draws, plan_envelope
from quadland.engine import compiled
from quadland.engine.kept import keeping
from quadland.kinds.landing.simulate import simulate_landing
n, AXES = int(sys.argv[1]), json.loads(sys.argv[2])
flight = [0.0]
sampled = compiled.CompiledLoop.sampled
def timed(*a, **k):
    t = time.process_time()
    try:
        return sampled(*a, **k)
    finally:
        flight[0] += time.process_time() - t
compiled.CompiledLoop.sampled = timed
env = plan_envelope("highway", None, AXES, 30)
warm_up(env.base)
draws = list(cell_draws(env, [c * 30 for c in range(0, 80, max(1, 80 // n))][:n]))
outs = [fly(env.base, d, env.spec.limits, KEEP_BYTES) for d in draws]
landed = [(d, o.metrics["touchdown_time"]) for d, o in zip(draws, outs)
          if o.metrics.get("touchdown_time") is not None]
cpu = {"whole": [[] for _ in landed], "cut": [[] for _ in landed]}
for _ in range(3):
    for i, (d, td) in enumerate(landed):
        for how in cpu:
            sc = dispersed(env.base, d.values)
            if how == "cut":
                sc = sc.replace(**{"simulation.duration": round(td - 0.05, 2)})
            flight[0] = 0.0
            with keeping(KEEP_BYTES):
                simulate_landing(sc)
            cpu[how][i].append(flight[0])
whole, cut = (statistics.mean(statistics.median(c) for c in cpu[h]) for h in ("whole", "cut"))
td = statistics.mean(t for _, t in landed)
print(json.dumps({"landings": len(landed), "touchdown": td, "whole": whole * 1e3,
                  "cut": cut * 1e3, "before per s": cut * 1e3 / (td - 0.05),
                  "last": (whole - cut) * 1e3}))
'''

FLY_SET = r'''
import hashlib, json, sys, time
from threadpoolctl import threadpool_limits
from quadland.engine.heap import keep_freed_memory
threadpool_limits(1)
keep_freed_memory()
from quadland.campaign.fly import fly, warm_up
from quadland.campaign.grid import KEEP_BYTES, cell_draws, plan_envelope
AXES, groups = json.loads(sys.argv[1]), json.loads(sys.argv[2])
env = plan_envelope("highway", None, AXES, 30)
warm_up(env.base)
out = {}
for label, picks in groups.items():
    draws = list(cell_draws(env, picks))
    fly(env.base, draws[0], env.spec.limits, KEEP_BYTES)
    t = time.process_time()
    outs = [fly(env.base, d, env.spec.limits, KEEP_BYTES) for d in draws]
    cpu = time.process_time() - t
    out[label] = (cpu / len(draws) * 1e3, hashlib.sha256(repr(
        [(o.index, o.status, o.success, sorted(o.metrics.items()), o.message)
         for o in outs]).encode()).hexdigest())
from quadland.kinds.landing.simulate import landing_loop_part
with open(landing_loop_part(10, "sampled", sensed=True, flat=True).library, "rb") as fh:
    out["library"] = hashlib.file_digest(fh, "sha256").hexdigest()
print(json.dumps(out))
'''


def python_env(cache: Path | None = None) -> dict:
    env = dict(os.environ, PYTHONHASHSEED="0", OPENBLAS_NUM_THREADS="1")
    if cache is not None:
        env["XDG_CACHE_HOME"] = str(cache)
    return env


def split(runs: int) -> None:
    """``--split``: the parts of a run, by group."""
    out = subprocess.run([sys.executable, "-c", SPLIT, str(runs), json.dumps(AXES)],
                         capture_output=True, text=True, check=True, env=python_env())
    groups = json.loads(out.stdout.splitlines()[-1])
    names = list(groups)
    print("| part, CPU ms a run | " + " | ".join(names) + " |")
    print("|---|" + "---:|" * len(names))
    g = groups
    print("| runs, mean time flown (s) | " + " | ".join(
        f"{g[n]['runs']}, {g[n]['flown'] / g[n]['runs']:.1f}" for n in names) + " |")
    print("| **the whole run** (`fly`) | " + " | ".join(
        f"**{g[n]['cpu'] / g[n]['runs'] * 1e3:.2f}**" for n in names) + " |")
    labels = sorted({k for n in names for k in g[n]["parts"]},
                    key=lambda k: -g[names[0]]["parts"].get(k, 0.0))
    for k in labels:
        print(f"| {k} | " + " | ".join(
            f"{g[n]['parts'].get(k, 0.0) / g[n]['runs'] * 1e3:.2f} "
            f"({g[n]['parts'].get(k, 0.0) / g[n]['cpu']:.1%})" for n in names) + " |")
    flight = "the compiled flight (`sampled`)"
    print("| the compiled flight per simulated second, ms | " + " | ".join(
        f"{g[n]['parts'].get(flight, 0.0) / g[n]['flown'] * 1e3:.3f}" for n in names) + " |")
    print("| the rest of the run, ms | " + " | ".join(
        f"{(g[n]['cpu'] - g[n]['parts'].get(flight, 0.0)) / g[n]['runs'] * 1e3:.2f}"
        for n in names) + " |")


def phases(n: int) -> None:
    """``--phases``: a landing's compiled flight before its touchdown and after."""
    out = subprocess.run([sys.executable, "-c", PHASES, str(n), json.dumps(AXES)],
                         capture_output=True, text=True, check=True, env=python_env())
    r = json.loads(out.stdout.splitlines()[-1])
    print(f"{r['landings']} landings, touchdown at {r['touchdown']:.2f} s on average; the "
          f"compiled flight {r['whole']:.2f} ms, to 0.05 s before the touchdown "
          f"{r['cut']:.2f} ms ({r['before per s']:.3f} ms per simulated second), the last "
          f"2.05 s {r['last']:.2f} ms ({r['last'] / 2.05:.3f} ms per simulated second)")


def finishing_times(costs: list[float], workers: int, chunk: int, ahead: int) -> list[float]:
    """When each worker finishes ``costs`` (s a run, in order), fed as ``pool_runs`` feeds
    them: ``ahead`` chunks of ``chunk`` runs queued on each, the next chunk to the worker
    whose chunk finished first."""
    chunks = [sum(costs[i:i + chunk]) for i in range(0, len(costs), chunk)]
    queues = [[] for _ in range(workers)]
    nxt = 0
    for q in queues:
        while nxt < len(chunks) and len(q) < ahead:
            q.append(chunks[nxt])
            nxt += 1
    events = [(q[0], w) for w, q in enumerate(queues) if q]
    heapq.heapify(events)
    end = [0.0] * workers
    while events:
        t, w = heapq.heappop(events)
        queues[w].pop(0)
        end[w] = t
        while nxt < len(chunks) and len(queues[w]) < ahead:
            queues[w].append(chunks[nxt])
            nxt += 1
        if queues[w]:
            heapq.heappush(events, (t + queues[w][0], w))
    return end


def schedule(path: Path, ms_per_s: tuple[float, float], ms_fixed: float) -> None:
    """``--schedule``: the two workers' ends in the envelope's order and longest first."""
    from quadland.campaign.grid import Envelope, flight_order
    from quadland.campaign.local import AHEAD, chunk_size

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    k = sum(r["cell"] == "0" for r in rows)
    costs, flown_nt, flown_td = {}, 0.0, 0.0
    for r in rows:
        if r["touchdown_time"]:
            flown = min(float(r["touchdown_time"]) + 2.0, 40.0)
            flown_td += flown
            costs[int(r["index"])] = (ms_fixed + ms_per_s[1] * flown) / 1e3
        else:
            flown_nt += 40.0
            costs[int(r["index"])] = (ms_fixed + ms_per_s[0] * 40.0) / 1e3
    n = len(rows)
    chunk = chunk_size(n, 2)
    total = sum(costs.values())
    print(f"{n} runs ({k} a cell), simulated s: without a touchdown {flown_nt:.0f}, "
          f"the others {flown_td:.0f} ({flown_nt / (flown_nt + flown_td):.1%} without)")
    print(f"modelled CPU {total:.1f} s, half of it {total / 2:.2f} s; chunks of {chunk}, "
          f"{AHEAD} ahead")
    orders = {"the envelope's (replicate by replicate)": flight_order(
                  Envelope(None, None, (), k), sorted(costs)),
              "longest first": sorted(costs, key=lambda g: -costs[g])}
    for name, order in orders.items():
        end = finishing_times([costs[g] for g in order], 2, chunk, AHEAD)
        print(f"{name}: workers end at {end[0]:.2f} and {end[1]:.2f} s, the map "
              f"{max(end):.2f} s ({max(end) - total / 2:+.2f} s over half the CPU)")


def _build(cc: str, flags: list[str], files: dict, out: Path) -> Path:
    work = out / "obj"
    work.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (work / name).write_text(text)
    objects = []
    for c in sorted(n for n in files if n.endswith(".c")):
        o = str(work / (c[:-2] + ".o"))
        subprocess.run([cc, *flags, "-c", c, "-o", o], cwd=work, check=True)
        objects.append(o)
    lib = out / "lib.so"
    subprocess.run([cc, "-shared", *[f for f in flags if f.startswith("-fprofile")],
                    "-o", str(lib), *objects, "-lm"], check=True)
    return lib


def _cache_with(xdg: Path, library: Path, lib: Path, dst: Path) -> Path:
    """A copy ``dst`` of the build cache ``xdg`` (an ``XDG_CACHE_HOME``) with ``library`` (a
    path in it) replaced by ``lib``: the ``XDG_CACHE_HOME`` of the children that fly it."""
    shutil.copytree(xdg / "quadland", dst / "quadland")
    target = dst / library.relative_to(xdg)
    shutil.copyfile(lib, target)
    with open(target, "rb") as fh:
        digest = hashlib.file_digest(fh, "sha256").hexdigest()
    target.with_name(target.name + ".sha256").write_text(digest + "\n")
    return dst


def _sha256(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def _picks(replicate: int, per_group: int) -> dict:
    """Runs of ``replicate`` in cells that land (the slowest fifth of the car's speeds)
    and in cells that mostly do not (the fastest row, 35 m/s)."""
    k = 30
    slow = [c * k + replicate for c in range(0, 80)]
    fast = [c * k + replicate for c in range(380, 400)]
    step = max(1, len(slow) // per_group)
    return {"slow cells": slow[::step][:per_group], "fastest row": fast[:per_group]}


def pgo_caches(tmp: Path, train: int) -> tuple[Path, Path]:
    """Two build caches: the runtime's build of the map's simulator, and the same C built
    with a profile of ``train`` runs a group on replicates 1 and 2."""
    from quadland.engine.build import SHARED_CFLAGS, language_flags, level_flags
    from quadland.engine.compiled import built_model, simulator_sources
    from quadland.engine.compiler import find_compiler
    from quadland.kinds.landing.simulate import landing_loop_part
    from quadland_symbolic.landing.loop_recipe import landing_loop_recipe

    part = landing_loop_part(10, "sampled", sensed=True, flat=True)
    library = Path(part.library)
    xdg = library.parents[2]                       # <XDG_CACHE_HOME>/quadland/<key>/<lib>
    files = simulator_sources(built_model(landing_loop_recipe(10, True, False, True)),
                              "sampled")
    cc = find_compiler()
    flags = [*language_flags(False, cc), *level_flags("-O2", cc), *SHARED_CFLAGS[:-1]]
    base = _build(cc, flags, files, tmp / "base")
    assert base.read_bytes() == library.read_bytes(), "the runtime's build differs"
    profile = tmp / "profile"
    gen = _build(cc, [*flags, f"-fprofile-generate={profile}", "-fprofile-update=single"],
                 files, tmp / "pgo")
    trained = _cache_with(xdg, library, gen, tmp / "cache-gen")
    for r in (1, 2):
        _fly_set(trained, _picks(r, train), _sha256(gen))
    assert any(profile.rglob("*.gcda")), "the training flight wrote no profile"
    use = _build(cc, [*flags, f"-fprofile-use={profile}", "-fprofile-partial-training"],
                 files, tmp / "pgo")                 # the same objects' names as the profile's
    assert use.read_bytes() != base.read_bytes(), "the profile changed nothing"
    return (_cache_with(xdg, library, base, tmp / "cache-base"),
            _cache_with(xdg, library, use, tmp / "cache-pgo"))


def _fly_set(cache: Path, picks: dict, library: str) -> dict:
    """``FLY_SET`` in a child on ``cache``, refused unless it flew the library of SHA-256
    ``library`` (a cache missing it would build the runtime's own)."""
    out = subprocess.run([sys.executable, "-c", FLY_SET, json.dumps(AXES), json.dumps(picks)],
                         check=True, capture_output=True, text=True, env=python_env(cache))
    got = json.loads(out.stdout.splitlines()[-1])
    flown = got.pop("library")
    assert flown == library, f"the child flew {flown[:12]}, not {library[:12]}"
    return got


def command_child(cache: Path, k: int, tmp: Path) -> dict:
    """The whole envelope command on ``cache``: the CPU of all its processes (the pool's
    forkserver and workers reaped, ``bench_envelope_run.reaped_run``), its runs.csv."""
    from bench_envelope_run import reaped_run

    out = tmp / "envelope"
    shutil.rmtree(out, ignore_errors=True)
    _, wall, cpu = reaped_run([sys.executable, "-m", "quadland", "envelope", "--scenario",
                               "highway", *(x for a in AXES for x in ("--axis", a)),
                               "--runs-per-cell", str(k), "--no-plots", "--out", str(out)],
                              None, python_env(cache))
    digest = hashlib.sha256((out / "runs.csv").read_bytes()).hexdigest()
    built = list(cache.rglob("qlsim_landing_sensed_flat_sampled.so"))
    assert len(built) == 1, "the command built its own simulator beside the one given"
    return {"the command, all processes, CPU s": (cpu, digest),
            "the command, wall s": (wall, digest)}


def pgo(rounds: int, runs: int, train: int, command: int) -> None:
    """``--pgo``: the two builds alternating in child processes, medians and ratios."""
    tmp = Path(tempfile.mkdtemp(prefix="bench-pgo-"))
    try:
        caches = dict(zip(("runtime's build", "profile-guided"), pgo_caches(tmp, train),
                          strict=True))
        libs = {name: _sha256(tmp / ("base" if name == "runtime's build" else "pgo") /
                              "lib.so") for name in caches}
        res: dict = {}
        for _ in range(rounds):
            for name, cache in caches.items():
                if command:
                    got = command_child(cache, command, tmp)
                else:
                    got = {f"{k}, CPU ms a run": v for k, v in
                           _fly_set(cache, _picks(0, runs), libs[name]).items()}
                for what, (value, digest) in got.items():
                    res.setdefault(what, {}).setdefault(name, []).append((value, digest))
        a, b = caches
        print(f"| median of {rounds} (min to max) | {a} | {b} | {b} / {a} | the same bytes |")
        print("|---|---:|---:|---:|---|")
        for what, by in res.items():
            va, vb = ([v for v, _ in by[n]] for n in (a, b))
            same = {d for n in (a, b) for _, d in by[n]}
            print(f"| {what} | {statistics.median(va):.2f} ({min(va):.2f} to {max(va):.2f}) | "
                  f"{statistics.median(vb):.2f} ({min(vb):.2f} to {max(vb):.2f}) | "
                  f"{statistics.median(vb) / statistics.median(va):.3f} | "
                  f"{'yes, ' + next(iter(same))[:8] if len(same) == 1 else 'NO'} |")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--split", type=int, default=0, metavar="N")
    parser.add_argument("--phases", type=int, default=0, metavar="N")
    parser.add_argument("--schedule", type=Path, default=None, metavar="RUNS_CSV")
    parser.add_argument("--ms-per-s", type=float, nargs=2, default=(1.18, 1.48),
                        help="the compiled flight's CPU ms per simulated second: runs "
                             "without a touchdown, the others")
    parser.add_argument("--ms-fixed", type=float, default=7.1,
                        help="CPU ms a run besides the compiled flight (the defaults: "
                             "docs/performance.md's --split 400 table)")
    parser.add_argument("--pgo", type=int, default=0, metavar="ROUNDS")
    parser.add_argument("--runs", type=int, default=30, help="--pgo: runs a group")
    parser.add_argument("--train", type=int, default=40,
                        help="--pgo: training runs a group and replicate")
    parser.add_argument("--command", type=int, default=0, metavar="K",
                        help="--pgo: the whole envelope command at K runs a cell")
    a = parser.parse_args()
    if a.split:
        split(a.split)
    if a.phases:
        phases(a.phases)
    if a.schedule is not None:
        schedule(a.schedule, tuple(a.ms_per_s), a.ms_fixed)
    if a.pgo:
        pgo(a.pgo, a.runs, a.train, a.command)


if __name__ == "__main__":
    main()

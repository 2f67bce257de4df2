"""An envelope worker's runs and the envelope's own process, paired with another tree (issue 20).

Issue 20's map (``highway``, the car at 5 to 35 m/s against the crosswind 0 to 20 m/s,
20 x 20 cells of 30 runs: 12,000 landings). Each round runs, in a fresh child process for
``--against TREE`` (an exported tree, ``git archive <commit> | tar -x -C /tmp/old``) and
for this checkout alternately:

* **a worker's runs**: ``--runs`` runs spread over the map (run ``g_i = (7309 i + 11) mod
  12000``: every prefix of them spreads over the cells), flown as a local worker flies
  them (:func:`quadland.campaign.fly.fly`, freed memory kept, one BLAS thread), in chunks
  of 8 draws pickled and unpickled as the pipe does, their outcomes pickled back; CPU ms a
  run (after one run outside the window), and the SHA-256 of the outcomes (index, seed,
  status, success, metrics, message, columns);
* **the envelope's process**: CPU s of ``plan_envelope`` (the axes, every cell's scenario
  checked), of every run's draw (``cell_draws`` of the 12,000) and of their runs.csv rows
  from the outcomes above, with the SHA-256 of the draws.

::

    nice -n 10 python benchmarks/bench_envelope_run.py --against /tmp/old --rounds 3 --runs 60

``--callgrind`` instead counts the instructions of a worker's run under ``valgrind
--tool=callgrind`` on each tree: the difference between processes flying ``--runs`` and
``--few`` runs, over the runs between (``PYTHONHASHSEED=0``, one BLAS thread).

``--replicates R`` flies, as the envelope now does, ``R`` replicates one after the other,
each in ``--runs / R`` cells spread over the map, with the draws kept between runs where
the tree keeps them (``quadland.campaign.grid.KEEP_BYTES``; the tree before flies the
same runs without)::

    nice -n 10 python benchmarks/bench_envelope_run.py --against /tmp/old --rounds 3 \
        --runs 60 --replicates 2

With ``--callgrind`` too, each process flies its runs replicate by replicate (``--few /
R`` and ``--runs / R`` of each): the first run of each replicate draws its table in both,
so the difference is over runs flown on kept draws where the tree keeps them.
``--wind`` times a run's disturbance alone (``landing_disturbance``: the wind, the force
and moment noise) over ``--runs`` runs of the map in ``--replicates`` replicates, kept where
the tree keeps (CPU ms a run, the SHA-256 of the disturbances; with ``--callgrind``, its
instructions a run)::

    nice -n 10 python benchmarks/bench_envelope_run.py --against /tmp/old --wind --rounds 5 \
        --runs 200 --replicates 2

``--set KEY=VALUE`` (repeatable) overrides the scenario in every child and command, e.g.
``highway`` without its crawl's gate (``--set landing.crawl_gate=0.0 ...``).

``--command K`` instead runs the whole command on each tree alternately, ``quadland
envelope --scenario highway`` over the map at ``K`` runs a cell, ``--no-plots``, its
local workers (``--workers``, default every core): the command's wall s, the wall s of
its flying (its last line's "flew N runs in X s"), the CPU s of the command and all its
processes (``RUSAGE_CHILDREN`` before and after: this process is the subreaper of the
command's descendants and waits for each, so the forkserver, which waits for its
workers, is counted with them), and the SHA-256 of its runs.csv (and of its envelope.json
less the session's wall time and rate and the scenario file's path)::

    nice -n 10 python benchmarks/bench_envelope_run.py --against /tmp/old --rounds 2 --command 4
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_tick_table import instructions, paired_table, tree_env

ROOT = Path(__file__).resolve().parent.parent
AXES = ["initial.velocity2[0]=5:35:20", "wind.mean[1]=0:20:20"]

CHILD = r'''
import hashlib, json, pickle, sys, time
from quadland.engine.heap import keep_freed_memory
from threadpoolctl import threadpool_limits
keep_freed_memory()
threadpool_limits(1)
runs, parent, warm = int(sys.argv[1]), sys.argv[2] == "1", sys.argv[3] == "1"
AXES, R = json.loads(sys.argv[4]), int(sys.argv[5])
SETS = json.loads(sys.argv[6]) if len(sys.argv) > 6 else []
out = {}
t0 = time.process_time()
from quadland.campaign.fly import fly, warm_up
from quadland.campaign.grid import cell_draws, plan_envelope, envelope_header
import quadland.campaign.grid as grid
t1 = time.process_time()
env = plan_envelope("highway", SETS or None, AXES, 30)
t2 = time.process_time()
warm_up(env.base)
picks = [(7309 * i + 11) % env.runs for i in range(runs + warm)]
kw = {}
if R:       # R replicates, each in runs / R cells spread over the map, flown replicate by
    K = env.runs_per_cell       # replicate; with the draws kept where the tree keeps them
    picks = [K - 1] * warm + [((7309 * i + 11) % len(env.cells)) * K + r
                              for r in range(R) for i in range(runs // R)]
    kw = {"keep": grid.KEEP_BYTES} if hasattr(grid, "KEEP_BYTES") else {}
draws = list(cell_draws(env, picks))
if warm:
    fly(env.base, draws[0], env.spec.limits)
    draws = draws[1:]
outs = []
t3 = time.process_time()
for k in range(0, len(draws), 8):
    chunk = pickle.loads(pickle.dumps(draws[k:k + 8]))
    done = [fly(env.base, d, env.spec.limits, **kw) for d in chunk]
    outs.extend(pickle.loads(pickle.dumps(done)))
t4 = time.process_time()
out["run, CPU ms"] = ((t4 - t3) / max(runs, 1) * 1e3, hashlib.sha256(repr(
    [(o.index, o.seed, o.status, o.success, sorted(o.metrics.items()), o.message,
      sorted(o.columns.items())) for o in outs]).encode()).hexdigest())
if parent:
    header = envelope_header(env)
    t5 = time.process_time()
    every = list(cell_draws(env, range(env.runs)))
    t6 = time.process_time()
    rows = [grid._row(o, header) for o in outs for _ in range(env.runs // max(len(outs), 1))]
    t7 = time.process_time()
    out["imports, CPU s"] = (t1 - t0, "")
    out["plan_envelope, CPU s"] = (t2 - t1, "")
    out["12,000 draws, CPU s"] = (t6 - t5, hashlib.sha256(repr(
        [(d.index, d.seed, sorted(d.values.items()), sorted(d.columns.items()))
         for d in every]).encode()).hexdigest())
    out["12,000 rows, CPU s"] = ((t7 - t6) * env.runs / max(len(rows), 1), hashlib.sha256(
        repr(rows).encode()).hexdigest())
print(json.dumps(out))
'''

WIND = r'''
import contextlib, hashlib, json, sys, time
from threadpoolctl import threadpool_limits
threadpool_limits(1)
calls, R, AXES, SETS = int(sys.argv[1]), int(sys.argv[2]), json.loads(sys.argv[3]), \
    json.loads(sys.argv[4])
import quadland.campaign.grid as grid
from quadland.campaign.dispersed import dispersed
from quadland.kinds.landing.values import landing_clocks, landing_disturbance
env = grid.plan_envelope("highway", SETS or None, AXES, 30)
K = env.runs_per_cell
picks = [((7309 * i + 11) % len(env.cells)) * K + r for r in range(R) for i in range(calls // R)]
runs = [dispersed(env.base, d.values) for d in grid.cell_draws(env, picks)]
times = landing_clocks(runs[0])[1].times()
try:
    from quadland.engine.kept import keeping
    keep = keeping(grid.KEEP_BYTES)
except ImportError:                              # a tree that keeps nothing
    keep = contextlib.nullcontext()
digest, cpu = hashlib.sha256(), 0.0
with keep:
    for sc in runs:
        t0 = time.process_time()
        w = landing_disturbance(sc, times)
        cpu += time.process_time() - t0
        digest.update(w.tobytes())
print(json.dumps({"a run's disturbance (the wind, the force and moment noise), CPU ms":
                  (cpu / len(runs) * 1e3, digest.hexdigest())}))
'''


def wind_child(tree: Path | None, tmp: Path, calls: int, replicates: int,
               sets: list[str] = ()) -> dict:
    """CPU ms of a run's ``landing_disturbance`` over ``calls`` runs of the map, replicate by
    replicate, kept where the tree keeps, with the SHA-256 of the disturbances."""
    env, cwd = tree_env(tree, tmp)
    out = subprocess.run([sys.executable, "-c", WIND, str(calls), str(max(replicates, 1)),
                          json.dumps(AXES), json.dumps(list(sets))], check=True, cwd=cwd,
                         env=env, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def child(tree: Path | None, tmp: Path, runs: int, parent: bool = True,
          replicates: int = 0, sets: list[str] = ()) -> dict:
    env, cwd = tree_env(tree, tmp)
    out = subprocess.run([sys.executable, "-c", CHILD, str(runs), "1" if parent else "0", "1",
                          json.dumps(AXES), str(replicates), json.dumps(list(sets))],
                         check=True, cwd=cwd, env=env, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def callgrind(tree: Path | None, tmp: Path, runs: int, replicates: int = 0,
              sets: list[str] = ()) -> int:
    """Callgrind's instruction count of a worker's process flying ``runs`` runs (no warm-up
    run: the first of both counts is the same run; with ``replicates``, the first run of
    each replicate)."""
    return instructions(tree, tmp, CHILD, str(runs), "0", "0", json.dumps(AXES),
                        str(replicates), json.dumps(list(sets)))


def _subreaper() -> None:
    """Make this process the reaper of its descendants orphaned (Linux ``prctl``)."""
    import ctypes

    PR_SET_CHILD_SUBREAPER = 36
    if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_CHILD_SUBREAPER)")


def reaped_run(args: list[str], cwd, env) -> tuple[str, float, float]:
    """Run ``args`` to its end, then wait every descendant it orphaned (the pool's
    forkserver and its workers): its stdout, wall s, and the CPU s of all those processes."""
    _subreaper()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    text = subprocess.run(args, check=True, cwd=cwd, env=env, capture_output=True,
                          text=True).stdout
    wall = time.perf_counter() - t0
    while True:
        try:
            os.waitpid(-1, 0)
        except ChildProcessError:
            break
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return text, wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def command(tree: Path | None, tmp: Path, k: int, workers: int | None,
            sets: list[str] = ()) -> dict:
    """The whole envelope command at ``k`` runs a cell on ``tree``: wall s, flying s, CPU s
    of all its processes, each with runs.csv's SHA-256."""
    env, cwd = tree_env(tree, tmp)
    out = tmp / f"envelope-{'before' if tree else 'now'}"
    subprocess.run(["rm", "-rf", str(out)], check=True)
    args = [sys.executable, "-m", "quadland", "envelope", "--scenario", "highway",
            *(x for a in AXES for x in ("--axis", a)), "--runs-per-cell", str(k),
            "--no-plots", "--out", str(out), *(["--workers", str(workers)] if workers else []),
            *(x for kv in sets for x in ("--set", kv))]
    text, wall, cpu = reaped_run(args, cwd, env)
    digest = hashlib.sha256((out / "runs.csv").read_bytes()).hexdigest()
    flying = float(re.search(r"flew \d+ runs in ([0-9.]+) s", text).group(1))
    return {"command, wall s": (wall, digest), "flying, wall s": (flying, digest),
            "all processes, CPU s": (cpu, digest),
            "envelope.json but its times and path, CPU s": (cpu, envelope_digest(out))}


def envelope_digest(out: Path) -> str:
    """SHA-256 of ``out``'s envelope.json less what differs between two flights of the same
    runs (the session's wall time and rate, the scenario file's path)."""
    data = json.loads((out / "envelope.json").read_text())
    for key in ("wall_s", "runs_per_s"):
        data["last_session"].pop(key, None)
    data["provenance"].pop("scenario_source", None)
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", type=Path, required=True, help="the tree before")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--runs", type=int, default=60)
    ap.add_argument("--few", type=int, default=4, help="--callgrind: the smaller process")
    ap.add_argument("--callgrind", action="store_true")
    ap.add_argument("--command", type=int, metavar="K", help="the whole command, K runs a cell")
    ap.add_argument("--replicates", type=int, default=0, metavar="R",
                    help="a worker's runs: R replicates in --runs / R cells each, flown "
                         "replicate by replicate, the draws kept where the tree keeps them")
    ap.add_argument("--workers", type=int, help="--command: local workers")
    ap.add_argument("--wind", action="store_true",
                    help="a run's disturbance alone (landing_disturbance), --runs calls in "
                         "--replicates replicates; with --callgrind, its instructions")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="a scenario override of every child and command (repeatable)")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if a.callgrind:
            for name, tree in (("before", a.against.resolve()), ("now", None)):
                few, many = ((instructions(tree, Path(tmp), WIND, str(n), str(max(
                    a.replicates, 1)), json.dumps(AXES), json.dumps(a.set)) if a.wind else
                    callgrind(tree, Path(tmp), n, a.replicates, a.set)) for n in (a.few, a.runs))
                print(f"{name}: {(many - few) / (a.runs - a.few) / 1e6:.2f} M instructions a "
                      f"run (processes of {a.few} and {a.runs} runs: {few:,} and {many:,})",
                      flush=True)
            return
        res: dict[str, dict[str, list]] = {"before": {}, "now": {}}
        for r in range(a.rounds):
            for name, tree in (("before", a.against.resolve()), ("now", None)):
                got = (command(tree, Path(tmp), a.command, a.workers, a.set) if a.command
                       else wind_child(tree, Path(tmp), a.runs, a.replicates, a.set)
                       if a.wind else child(tree, Path(tmp), a.runs,
                                            replicates=a.replicates, sets=a.set))
                for k, v in got.items():
                    res[name].setdefault(k, []).append(v)
            print(f"round {r + 1}: " + json.dumps({n: {k: round(v[-1][0], 3) for k, v in
                                                       d.items()} for n, d in res.items()}),
                  flush=True)
    paired_table(res, "what", 3)


if __name__ == "__main__":
    main()

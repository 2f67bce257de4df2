"""The sensors' per-tick table of an envelope's landings, paired with another tree (issue 20).

The table (:class:`quadland.kinds.landing.sensed.TickTable`, drawn as the compiled flight
asks for more through its callback) is a fifth of the CPU of issue 20's ``highway``
envelope: its runs that never touch down draw the sensors for the whole 40 s. Each round
runs, in a fresh child process for this checkout and for ``--against TREE`` (an exported
tree, e.g. ``git archive 0221e14 | tar -x -C /tmp/old``) alternately:

* the table drawn as a flight draws it, to 40 s (10,000 ticks: a run without a touchdown)
  and to 16.4 s (4,096 ticks: a landing at about 14 s), or to the ``--ticks`` given, CPU
  ms a table (median of ``--tables``), with the SHA-256 of its rows drawn;
* with ``--runs N`` (0: none), N runs spread over the cells of issue 20's map (the car
  at 5 to 35 m/s against the crosswind 0 to 20 m/s, 20 x 20 cells of 30 runs), flown as
  a campaign's worker flies them (``quadland.campaign.fly.fly``, freed memory kept):
  CPU ms a run, and the SHA-256 of their outcomes (status, success, metrics, message)::

    nice -n 10 python benchmarks/bench_tick_table.py --against /tmp/old --rounds 3 --runs 60

``--callgrind`` instead counts the instructions of a table (to 10,000 and to 4,096
ticks) under ``valgrind --tool=callgrind``, on each tree: half the difference between a
process that draws three tables and one that draws one (``PYTHONHASHSEED=0``, one BLAS
thread).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

CHILD = r'''
import hashlib, json, sys, time
from quadland.engine.heap import keep_freed_memory
from quadland.scenario import load_scenario
from quadland.kinds.landing.sensed import TickTable
keep_freed_memory()
tables, runs = int(sys.argv[1]), int(sys.argv[2])
sizes = [int(v) for v in sys.argv[3].split(",")]
sc = load_scenario("highway")

def table(ticks):
    t = TickTable(sc, 10001)
    tick = 0
    while tick < ticks:
        tick = t.more(tick)
    return t.rows

out = {}
for ticks in sizes:
    rows = table(ticks)
    digest = hashlib.sha256(rows[:ticks].tobytes()).hexdigest()   # (past them: unwritten)
    cpu = []
    for _ in range(tables):
        t0 = time.process_time()
        table(ticks)
        cpu.append(time.process_time() - t0)
    out[f"table {ticks}"] = (sorted(cpu)[len(cpu) // 2] * 1e3, digest)
if runs:
    from quadland.campaign.fly import fly, warm_up
    from quadland.campaign.grid import cell_draws, plan_envelope
    env = plan_envelope("highway", None, ["initial.velocity2[0]=5:35:20",
                                          "wind.mean[1]=0:20:20"], 30)
    warm_up(env.base)
    step = env.runs // runs
    draws = list(cell_draws(env, [i * step + (i * 7) % step for i in range(runs)]))
    t0 = time.process_time()
    outs = [fly(env.base, d) for d in draws]
    cpu = time.process_time() - t0
    digest = hashlib.sha256(repr([(o.index, o.status, o.success, sorted(o.metrics.items()),
                                   o.message) for o in outs]).encode()).hexdigest()
    out["envelope run"] = (cpu / runs * 1e3, digest)
print(json.dumps(out))
'''

_CALLGRIND = r'''
import sys
from quadland.engine.heap import keep_freed_memory
from quadland.scenario import load_scenario
from quadland.kinds.landing.sensed import TickTable
keep_freed_memory()
sc = load_scenario("highway")
for _ in range(int(sys.argv[1])):
    t = TickTable(sc, 10001)
    tick = 0
    while tick < int(sys.argv[2]):
        tick = t.more(tick)
'''


def tree_env(tree: Path | None, tmp: Path) -> tuple[dict, Path]:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    if tree is None:
        return env, ROOT
    path = tmp / "against"
    if not path.exists():
        path.mkdir()
        (path / "quadland").symlink_to(tree / "quadland")
        (path / "quadland_symbolic").symlink_to(tree / "symbolic")
    env["PYTHONPATH"] = str(path)
    return env, tmp


def instructions(tree: Path | None, tmp: Path, *args: str) -> int:
    """Callgrind's instruction count of ``python -c script *args`` (``args[0]`` the
    script) run on ``tree``'s code (this checkout's when None), with one hash seed and one
    BLAS thread."""
    env, cwd = tree_env(tree, tmp)
    env["PYTHONHASHSEED"] = "0"                # the same dictionaries' and sets' order
    env["OPENBLAS_NUM_THREADS"] = "1"          # no BLAS threads spinning
    out = tmp / "callgrind.out"
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                    sys.executable, "-c", *args], check=True, cwd=cwd, env=env,
                   capture_output=True)
    for line in out.read_text().splitlines():
        if line.startswith("summary:") or line.startswith("totals:"):
            return int(line.split()[1])
    raise RuntimeError("no totals in callgrind's output")


def callgrind(tree: Path | None, tmp: Path, tables: int, ticks: int) -> int:
    """Callgrind's instruction count of a process that draws ``tables`` tables to
    ``ticks``."""
    return instructions(tree, tmp, _CALLGRIND, str(tables), str(ticks))


def paired_table(res: dict, what: str, digits: int) -> None:
    """Print ``res["before"]`` against ``res["now"]`` (per key, rounds of (value, digest)):
    medians, ranges, their ratio and whether every round's digest is the same."""
    print(f"| {what}, median of the rounds (min to max) | before | now | now / before | "
          "same bits |")
    print("|---|---:|---:|---:|---|")
    for k in res["now"]:
        b, n = ([v[0] for v in res[w][k]] for w in ("before", "now"))
        same = {v[1] for v in res["before"][k]} == {v[1] for v in res["now"][k]}
        print(f"| {k} | {statistics.median(b):.{digits}f} ({min(b):.{digits}f} to "
              f"{max(b):.{digits}f}) | {statistics.median(n):.{digits}f} "
              f"({min(n):.{digits}f} to {max(n):.{digits}f}) | "
              f"{statistics.median(n) / statistics.median(b):.3f} | "
              f"{'yes, ' + res['now'][k][0][1][:8] if same else 'NO'} |")


def child(tree: Path | None, tmp: Path, tables: int, runs: int, ticks: str) -> dict:
    env, cwd = tree_env(tree, tmp)
    out = subprocess.run([sys.executable, "-c", CHILD, str(tables), str(runs), ticks], check=True,
                         cwd=cwd, env=env, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", type=Path, required=True, help="the tree before")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--tables", type=int, default=15)
    ap.add_argument("--runs", type=int, default=0)
    ap.add_argument("--ticks", default="10000,4096",
                    help="the tables' sizes, ticks (e.g. 10000,4096,6144: a run to 24.6 s)")
    ap.add_argument("--callgrind", action="store_true",
                    help="instructions a table: processes of 1 and 3 tables, each tree")
    a = ap.parse_args()
    if a.callgrind:
        with tempfile.TemporaryDirectory() as tmp:
            for ticks in (int(v) for v in a.ticks.split(",")):
                for name, tree in (("before", a.against.resolve()), ("now", None)):
                    one, three = (callgrind(tree, Path(tmp), n, ticks) for n in (1, 3))
                    print(f"{name}: {(three - one) / 2 / 1e6:.2f} M instructions a table to "
                          f"{ticks} ticks (processes of 1 and 3 tables: {one:,} and "
                          f"{three:,})", flush=True)
        return
    res: dict[str, dict[str, list]] = {"before": {}, "now": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds):
            for name, tree in (("before", a.against.resolve()), ("now", None)):
                for k, v in child(tree, Path(tmp), a.tables, a.runs, a.ticks).items():
                    res[name].setdefault(k, []).append(v)
            print(f"round {r + 1}: " + json.dumps({n: {k: round(v[-1][0], 2) for k, v in d.items()}
                                                  for n, d in res.items()}), flush=True)
    paired_table(res, "CPU ms", 2)

if __name__ == "__main__":
    main()

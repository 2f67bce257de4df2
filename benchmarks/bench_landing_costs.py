"""A campaign's landing in the runtime (issue 20): before and now, interleaved.

"Before" is a tree of the code before the change (``git archive <commit> | tar -x``),
run in child processes beside the installed tree ("now"), the two interleaved round
by round. Every figure is from a fresh child process, CPU time (user + system) unless
named wall:

* the pure-C reference ``generated/example/land -q`` (built with the example's
  Makefile), the child's CPU time, 7 runs;
* a one-worker ``highway`` campaign of ``--small`` and of ``--large`` runs, each in
  its own process: the CPU per landing is the slope between the two (the fixed
  costs cancel), and the same in wall time; the large campaign's outcome counts
  (``summary.json``) before and now;
* the sensors' per-tick table of the default ``highway`` landing: the whole
  ``simulation.duration`` drawn (before) against the table drawn as its flight
  goes (now), median of 15;
* the journal's ``fsync`` per run: the fsyncs of ``runs.csv`` in the large
  campaign, counted, and the wall time of one on this disk (median of 20).

Run from the repository root::

    git archive bf41d33 | (mkdir -p /tmp/before && tar -x -C /tmp/before)
    python benchmarks/bench_landing_costs.py --before /tmp/before
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from land_reference import land_q  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "generated" / "example"

#: A one-worker campaign in a child: its CPU and wall time, outcome and fsyncs.
CAMPAIGN = r"""
import json, os, sys, tempfile, time
from pathlib import Path
from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario

runs = int(sys.argv[1])
warm_up(load_scenario("highway"))
syncs = []
real = os.fsync
def fsync(fd):
    journal = os.readlink(f"/proc/self/fd/{fd}").endswith("runs.csv")
    t0 = time.perf_counter()
    real(fd)
    if journal:
        syncs.append(time.perf_counter() - t0)
os.fsync = fsync
with tempfile.TemporaryDirectory(dir=os.getcwd()) as tmp:
    c0, w0 = time.process_time(), time.perf_counter()
    r = run_campaign("highway", runs=runs, out=Path(tmp) / "c", plots=False, workers=1)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    s = json.loads((r.folder / "summary.json").read_text())
print(json.dumps({"cpu": cpu, "wall": wall, "fsyncs": len(syncs), "fsync_s": sum(syncs),
                  "counts": {k: s[k] for k in ("runs", "flown", "successes", "failures",
                                               "numerical_failures")},
                  "interval": s["confidence"]["interval"]}))
"""

#: The default highway landing's per-tick table, drawn as the code of the tree draws it.
TABLE = r"""
import json, statistics, time
import numpy as np
import quadland
from quadland.kinds.landing import sensed
from quadland.kinds.landing.values import landing_clocks

sc = quadland.load_scenario("highway")
n = len(landing_clocks(sc)[2].times())
last = int(np.floor(quadland.simulate(sc)["t"][-1] * sc["controller.rate_hz"] + 1e-6))
def draw():
    if hasattr(sensed, "TickTable"):            # now: as far as the flight goes
        table = sensed.TickTable(sc, n)
        for tick in range(0, last + 1, table.chunk):
            table.more(tick)
        return table.filled
    return sensed.tick_table(sc, n).shape[0]    # before: the whole duration
times = []
for _ in range(15):
    t0 = time.process_time()
    rows = draw()
    times.append(time.process_time() - t0)
print(json.dumps({"table_ms": 1e3 * statistics.median(times), "rows": rows, "ticks": n,
                  "flown_ticks": last + 1}))
"""


def child(code: str, tree: Path | None, *args: str) -> dict:
    """Run ``code`` in a fresh process on ``tree``'s code (None: the installed one)."""
    env = dict(os.environ)
    if tree is not None:
        path = Path(tempfile.mkdtemp(prefix="quadland-before-"))
        (path / "quadland").symlink_to(tree / "quadland")
        (path / "quadland_symbolic").symlink_to(tree / "symbolic")
        env["PYTHONPATH"] = str(path)
    done = subprocess.run([sys.executable, "-c", code, *args], env=env,
                          cwd=tempfile.gettempdir(), capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def fsync_wall(repeats: int = 20) -> float:
    """Median wall seconds of appending a line and ``fsync`` on the temporary folder's disk."""
    times = []
    with tempfile.NamedTemporaryFile(dir=tempfile.gettempdir()) as fh:
        for _ in range(repeats):
            os.write(fh.fileno(), b"x" * 300 + b"\n")
            t0 = time.perf_counter()
            os.fsync(fh.fileno())
            times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="a tree of the code before (quadland/ and symbolic/)")
    parser.add_argument("--small", type=int, default=60)
    parser.add_argument("--large", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=1)
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "now": None}
    for tree in trees.values():                 # build or load each tree's simulators
        child(CAMPAIGN, tree, "2")
    print(f"load average before: {os.getloadavg()}, {len(os.sched_getaffinity(0))} cores")
    ref = land_q(7)
    c_ms = 1e3 * statistics.median(ref)
    print(f"- `land -q`: {c_ms:.1f} ms CPU (median of 7, {1e3 * min(ref):.1f} to "
          f"{1e3 * max(ref):.1f})")
    out: dict = {key: {"small": [], "large": [], "table": []} for key in trees}
    for _ in range(args.rounds):
        for size in ("small", "large"):
            for key, tree in trees.items():
                out[key][size].append(child(CAMPAIGN, tree, str(getattr(args, size))))
        for key, tree in trees.items():
            out[key]["table"].append(child(TABLE, tree))
    span = args.large - args.small
    for key in trees:
        cpu = [(b["cpu"] - a["cpu"]) / span for a, b in zip(out[key]["small"],
                                                              out[key]["large"], strict=True)]
        wall = [(b["wall"] - a["wall"]) / span for a, b in zip(out[key]["small"],
                                                                out[key]["large"], strict=True)]
        large = out[key]["large"][-1]
        table = out[key]["table"][-1]
        print(f"- {key}: CPU per landing {', '.join(f'{1e3 * c:.1f}' for c in cpu)} ms "
              f"({', '.join(f'{1e3 * c / c_ms:.2f}' for c in cpu)}x `land -q`); wall "
              f"{', '.join(f'{1e3 * w:.1f}' for w in wall)} ms; the {args.large}-run "
              f"campaign's fsyncs of runs.csv: {large['fsyncs']} "
              f"({large['fsync_s']:.2f} s of wall); its outcome "
              f"{large['counts']}, 95 % interval {large['interval']}")
        print(f"  the default highway landing's tick table: "
              f"{statistics.median(t['table_ms'] for t in out[key]['table']):.2f} ms "
              f"({table['rows']} of {table['ticks']} rows drawn; the flight's ticks: "
              f"{table['flown_ticks']})")
    print(f"- one append and fsync on this disk: {1e3 * fsync_wall():.1f} ms wall (median of 20)")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

"""A campaign's costs per process and per landing (issue 20): before and now, interleaved.

"Before" is a tree of the code before the change (``git archive <commit> | tar -x``),
run in child processes beside the installed tree ("now"), the two interleaved round by
round, every figure from a fresh child process, CPU time (user + system) unless named
wall:

* **a process's start**: ``load_scenario("highway")`` and ``warm_up`` (the simulator
  found in the cache and loaded; before, the loop model built for its key), what the
  campaign's own process and each of its local workers pay once;
* **a landing**: a one-worker ``highway`` campaign of ``--small`` and of ``--large``
  runs, each in its own process; the CPU per landing is the slope between the two
  (issue 20's definition: the fixed costs cancel), over the pure-C reference
  ``generated/example/land -q``'s CPU (7 runs);
* **the command**: ``quadland campaign --scenario highway --runs 300 --no-plots`` on
  ``--workers`` local processes, its wall time (the target's figure, meaningful only on
  a quiet machine: the load average is printed) and the CPU of the command's own
  process, its workers' not included (they are the forkserver's children).

Run from the repository root::

    git archive efedd25 | (mkdir -p /tmp/before && tar -x -C /tmp/before)
    nice -n 10 python benchmarks/bench_campaign_process.py --before /tmp/before --rounds 3
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_landing_costs import CAMPAIGN, child  # noqa: E402
from land_reference import land_q  # noqa: E402

#: A fresh process's start: the scenario loaded, the simulator warmed up.
START = r"""
import json, time
c0 = time.process_time()
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario
base = load_scenario("highway")
c1 = time.process_time()
warm_up(base)
c2 = time.process_time()
print(json.dumps({"imports": c1 - c0, "warm_up": c2 - c1}))
"""

#: The command, timed from its start to its end, on the workers asked for.
COMMAND = r"""
import json, os, resource, sys, tempfile, time
from pathlib import Path
from quadland.cli import main
t0 = time.perf_counter()
with tempfile.TemporaryDirectory(dir=os.getcwd()) as tmp:
    code = main(["campaign", "--scenario", "highway", "--runs", sys.argv[1], "--workers",
                 sys.argv[2], "--out", str(Path(tmp) / "c"), "--no-plots"])
    assert not code, code
    wall = time.perf_counter() - t0
    s = json.loads((Path(tmp) / "c" / "summary.json").read_text())
me = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"wall": wall, "cpu": me.ru_utime + me.ru_stime,
                  "flying": s["last_session"]["wall_s"]}))
"""


def _median(values) -> float:
    return statistics.median(values)


def _cell(values, scale: float = 1e3, digits: int = 1) -> str:
    return (f"{scale * _median(values):.{digits}f} ({scale * min(values):.{digits}f} to "
            f"{scale * max(values):.{digits}f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="a tree of the code before (quadland/ and symbolic/)")
    parser.add_argument("--small", type=int, default=60)
    parser.add_argument("--large", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--runs", type=int, default=300, help="runs of the command")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "now": None}
    for tree in trees.values():                 # build or load each tree's simulators
        child(CAMPAIGN, tree, "2")
    print(f"load average before: {os.getloadavg()}, {len(os.sched_getaffinity(0))} cores")
    ref = land_q(7)
    c_ref = _median(ref)
    print(f"- `land -q`: {_cell(ref)} ms CPU (7 runs)")
    out = {key: {"start": [], "small": [], "large": [], "command": []} for key in trees}
    for r in range(args.rounds):
        for key, tree in trees.items():
            out[key]["start"].append(child(START, tree))
        for size in ("small", "large"):
            for key, tree in trees.items():
                out[key][size].append(child(CAMPAIGN, tree, str(getattr(args, size))))
        for key, tree in trees.items():
            out[key]["command"].append(child(COMMAND, tree, str(args.runs),
                                             str(args.workers)))
        print(f"  round {r + 1} of {args.rounds} done at {time.strftime('%H:%M:%S')}, load "
              f"{os.getloadavg()[0]:.1f}", flush=True)
    span = args.large - args.small
    print("| what | before | now | now / before |\n|---|---:|---:|---:|")
    rows = []
    for name, get, scale in (
            ("a process's start: imports and scenario, CPU ms",
             lambda o: [s["imports"] for s in o["start"]], 1e3),
            ("a process's start: `warm_up`, CPU ms", lambda o: [s["warm_up"] for s in o["start"]],
             1e3),
            (f"one-worker campaign, CPU per landing (slope {args.small} to {args.large}), ms",
             lambda o: [(b["cpu"] - a["cpu"]) / span
                        for a, b in zip(o["small"], o["large"], strict=True)], 1e3),
            (f"the command, {args.runs} runs on {args.workers} workers: its own process's CPU, s",
             lambda o: [c["cpu"] for c in o["command"]], 1),
            (f"the command, {args.runs} runs on {args.workers} workers: wall, s (loaded)",
             lambda o: [c["wall"] for c in o["command"]], 1),
            ("the same, flying (`last_session.wall_s`), s (loaded)",
             lambda o: [c["flying"] for c in o["command"]], 1)):
        before, now = get(out["before"]), get(out["now"])
        rows.append((name, before, now))
        digits = 2 if scale == 1 else 1
        print(f"| {name} | {_cell(before, scale, digits)} | {_cell(now, scale, digits)} | "
              f"{_median(now) / _median(before):.2f} |")
    slope = {key: [(b["cpu"] - a["cpu"]) / span for a, b in zip(out[key]["small"],
                                                                 out[key]["large"], strict=True)]
             for key in trees}
    for key in trees:
        print(f"- {key}: a landing {_median(slope[key]) / c_ref:.2f}x `land -q`'s CPU; the "
              f"{args.large}-run one-worker campaign's outcome {out[key]['large'][-1]['counts']}")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

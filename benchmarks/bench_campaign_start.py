"""A campaign's landing in a worker, part by part, and the campaign command's start (issue 20).

Two measurements, each in fresh child processes, "before" (an exported tree, ``git
archive <commit> | tar -x``, on ``PYTHONPATH``) alternating with "now" (this checkout)
round by round:

* ``--worker``: ``--runs`` runs of ``--scenario``'s campaign (``highway`` by default)
  flown as a local worker flies them (``quadland.campaign.fly.fly``, one BLAS thread,
  freed memory kept) after a warm-up of
  the simulator and five runs; the CPU per run, the CPU of each part of a run (timed
  around the functions, each part's own time, nested parts subtracted), each part's calls a
  run and the SHA-256 of the runs' outcomes;
* ``--command``: ``quadland campaign --scenario highway --runs R --no-plots`` on 2 local
  workers in a child process marked where its first worker is started: that process's
  CPU and wall until then (the fixed start-up), its CPU in all, the command's wall, the
  flying wall (its last line), the CPU of all its processes (``RUSAGE_CHILDREN``: this
  process reaps the orphaned forkserver and its workers) and runs.csv's SHA-256.

Run from the repository root::

    git -C /work/main archive HEAD | (mkdir -p /tmp/before && tar -x -C /tmp/before)
    python benchmarks/bench_campaign_start.py --before /tmp/before --rounds 3 --worker
    python benchmarks/bench_campaign_start.py --before /tmp/before --rounds 3 --command 300
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_envelope_run import reaped_run  # noqa: E402
from bench_tick_table import tree_env  # noqa: E402

#: The worker's runs, part by part: CPU ms per run of each part's own time.
WORKER = r'''
import functools, hashlib, json, sys, time, warnings
warnings.simplefilter("ignore")
from threadpoolctl import threadpool_limits
threadpool_limits(1)
from quadland.engine.heap import keep_freed_memory
keep_freed_memory()
from quadland.scenario import load_scenario
from quadland.campaign.spec import campaign_spec_of
from quadland.campaign.sampling import iter_draws
from quadland.campaign import fly as F
from quadland.kinds.landing import simulate as S, sensed, kind as K
from quadland.engine import compiled as C
acc, stack, calls = {}, [], {}
def wrap(owner, name, label):
    f = getattr(owner, name)
    @functools.wraps(f)
    def w(*a, **k):
        calls[label] = calls.get(label, 0) + 1
        t0 = time.process_time(); stack.append(0.0)
        try:
            return f(*a, **k)
        finally:
            dt = time.process_time() - t0; inner = stack.pop()
            acc[label] = acc.get(label, 0.0) + dt - inner
            if stack:
                stack[-1] += dt
    setattr(owner, name, w)
for owner, name, label in (
        (F, "dispersed", "the run's scenario (dispersed)"),
        (S, "landing_values", "the loop's vectors (landing_values)"),
        (S, "landing_envelope", "the envelope"),
        (S, "landing_disturbance", "the disturbance (wind, force and moment noise)"),
        (S, "sensed_vectors", "the filter's start (sensed_vectors)"),
        (S, "landing_loop_part", "the simulator's lookup"),
        (C.CompiledLoop, "sampled", "the compiled flight"),
        (sensed.TickTable, "more", "the sensors' table (more, called back)"),
        (S, "_first_contact", "the outputs and the first contact's row"),
        (S, "gear_columns", "the gear's columns (CasADi's VM)"),
        (S, "_result", "the result's other columns"),
        (K.LandingKind, "run_metrics", "the metrics"),
        (K.LandingKind, "judge", "the judgement"),
        (S, "simulate_landing", "simulate_landing's own (checks, clocks, table set-up)"),
        (F, "fly", "fly's own")):
    wrap(owner, name, label)
base = load_scenario(sys.argv[2])
spec = campaign_spec_of(base)
n = int(sys.argv[1])
draws = list(iter_draws(spec, range(n + 5), 300))
F.warm_up(base)
for d in draws[:5]:
    F.fly(base, d, spec.limits)
acc.clear(); calls.clear()
t0 = time.process_time()
outs = [F.fly(base, d, spec.limits) for d in draws[5:]]
total = time.process_time() - t0
digest = hashlib.sha256(repr([(o.index, o.status, o.success, sorted(o.metrics.items()),
                               o.message) for o in outs]).encode()).hexdigest()
print(json.dumps({"per run": total / n * 1e3, "sha": digest,
                  "parts": {k: v / n * 1e3 for k, v in acc.items()},
                  "calls a run": {k: v / n for k, v in calls.items()}}))
'''

#: The campaign command, marked where its first worker is started.
COMMAND = r'''
import json, sys, time
w0, c0 = time.perf_counter(), time.process_time()
marks = {}
from quadland import cli
from quadland.campaign import local
start = local._Worker.__init__
def init(self, *a, **k):
    start(self, *a, **k)
    marks.setdefault("first worker", (time.perf_counter() - w0, time.process_time() - c0))
local._Worker.__init__ = init
if __name__ == "__main__":
    cli.main(sys.argv[1:])
    marks["end"] = (time.perf_counter() - w0, time.process_time() - c0)
    print(json.dumps(marks))
'''


def worker(tree: Path | None, tmp: Path, runs: int, scenario: str = "highway") -> dict:
    env, cwd = tree_env(tree, tmp)
    out = subprocess.run([sys.executable, "-c", WORKER, str(runs), scenario], check=True, cwd=cwd,
                         env=env, capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def command(tree: Path | None, tmp: Path, runs: int) -> dict:
    env, cwd = tree_env(tree, tmp)
    script = tmp / "command.py"
    script.write_text(COMMAND)
    out = tmp / f"campaign-{'before' if tree else 'now'}"
    subprocess.run(["rm", "-rf", str(out)], check=True)
    text, wall, cpu = reaped_run([sys.executable, str(script), "campaign", "--scenario",
                                  "highway", "--runs", str(runs), "--workers", "2",
                                  "--no-plots", "--out", str(out)], cwd, env)
    marks = json.loads(text.strip().splitlines()[-1])
    flying = float(re.search(r"flew \d+ runs in ([0-9.]+) s", text).group(1))
    return {"until the first worker, the command's CPU s": marks["first worker"][1],
            "until the first worker, wall s": marks["first worker"][0],
            "the command's process, CPU s": marks["end"][1],
            "all processes, CPU s": cpu,
            "the command, wall s": wall, "flying, wall s": flying,
            "sha": hashlib.sha256((out / "runs.csv").read_bytes()).hexdigest()}


def _median(values: list) -> str:
    return f"{statistics.median(values):.3f} ({min(values):.3f} to {max(values):.3f})"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, help="the tree before")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--runs", type=int, default=40, help="--worker: runs per child")
    ap.add_argument("--worker", action="store_true")
    ap.add_argument("--command", type=int, metavar="R", help="the command's runs")
    ap.add_argument("--scenario", default="highway", help="--worker: the campaign's scenario")
    a = ap.parse_args()
    trees = (("before", a.before.resolve()), ("now", None))
    res: dict[str, list[dict]] = {"before": [], "now": []}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds):
            for name, tree in (trees if r % 2 == 0 else trees[::-1]):
                got = command(tree, Path(tmp), a.command) if a.command else \
                    worker(tree, Path(tmp), a.runs, a.scenario)
                res[name].append(got)
                print(f"round {r + 1} {name}: {json.dumps(got)}", flush=True)
    keys = [k for k in res["now"][0] if k not in ("sha", "parts", "calls a run")]
    if "parts" in res["now"][0]:
        keys += [f"parts/{k}" for k in res["now"][0]["parts"]]

    def values(name, key):
        if key.startswith("parts/"):
            return [g["parts"].get(key[6:], 0.0) for g in res[name]]
        return [g[key] for g in res[name]]

    print("| what | before | now | now / before (rounds) |\n|---|---:|---:|---:|")
    for key in keys:
        b, n = values("before", key), values("now", key)
        ratios = [y / x for x, y in zip(b, n, strict=True) if x]
        print(f"| {key} | {_median(b)} | {_median(n)} | "
              f"{statistics.median(ratios) if ratios else float('nan'):.3f} "
              f"({', '.join(f'{q:.3f}' for q in ratios)}) |")
    for name in res:
        print(name, "SHA-256:", sorted({g["sha"][:16] for g in res[name]}))
        if "calls a run" in res[name][0]:
            print(name, "calls a run:", json.dumps(res[name][0]["calls a run"]))


if __name__ == "__main__":
    main()

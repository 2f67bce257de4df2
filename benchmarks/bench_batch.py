"""Campaigns at the speed of C (issue 20, items 1 and 2): where a landing's time goes.

Measured in one run, medians of CPU time (user + system), each figure beside its
reference:

* the pure-C reference: ``generated/example/land -q`` (highway, no CSV, the
  report alone; built here with the example's Makefile), the child's CPU time;
* a warm ``quadland.simulate`` of ``highway`` and ``ship`` in this process, as
  before the session of 2026-11-26 that measured it (:func:`configure`: the deck's
  sinusoid sums evaluated on a flat deck too, the noise recursions over Python
  floats, the gear's columns from the full gear signals, the drive profile's planned
  speed evaluated in every run) and now, interleaved; and the same landings
  compared column by column, bit for bit (signs of zero included);
* the campaign's wall time per landing with one worker: the slope between a
  60-run and a 300-run ``highway`` campaign (fixed costs cancel), before and now,
  interleaved, against ``land -q``'s CPU (target: at most 1.5x); and per simulated
  second (the campaign's landings fly longer than ``land -q``'s);
* a 300-landing ``highway`` campaign on every core, each run alone per message
  (``chunk = 1``) and in chunks (``quadland.campaign.local.chunk_size``),
  its ``runs.csv`` compared (the same rows bit for bit), and ``quadland campaign``
  as a command from process start to exit (target: 2 s of wall);
* the 20 x 20 envelope of 30 runs per cell (12,000 landings, target 3 min),
  extrapolated from the measured throughput on every core.

The machine is shared: its load average is printed with the figures.

Run from the repository root::

    python benchmarks/bench_batch.py            # about eight minutes on 2 quiet cores
    python benchmarks/bench_batch.py --quick    # smaller campaigns (30 and 90 runs)
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import quadland
from quadland.campaign import execute, local
from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.engine import noise, recursion, wind
from quadland.kinds.landing import contact_report
from quadland.kinds.landing import simulate as landing_simulate
from quadland.scenario import load_scenario
from quadland_symbolic.landing import drive
from quadland_symbolic.landing.loop import landing_gear_signals_function

sys.path.insert(0, str(Path(__file__).resolve().parent))
from land_reference import land_q  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "generated" / "example"

_NOW = {"flat_deck": landing_simulate.flat_deck, "recursion": recursion.recursion,
        "gear": contact_report.flat_gear_signals, "planned": drive._planned_speed_change}


def configure(before: bool) -> None:
    """``before``: the full loop on a flat deck, the recursions over Python floats, the
    full gear signals and the planned speed evaluated each time (the code of bf429f3)."""
    landing_simulate.flat_deck = (lambda *a: False) if before else _NOW["flat_deck"]
    rec = (lambda *a: None) if before else _NOW["recursion"]
    noise.recursion = wind.recursion = rec
    contact_report.flat_gear_signals = landing_gear_signals_function if before else \
        _NOW["gear"]
    contact_report._mapped.cache_clear()
    drive._planned_speed_change = _NOW["planned"].__wrapped__ if before else _NOW["planned"]


def warm(name: str, repeats: int) -> dict:
    """CPU seconds of a warm simulate, before and now, interleaved; and whether the two
    results are equal bit for bit."""
    sc = load_scenario(name)
    results, times = {}, {True: [], False: []}
    for before in (True, False):
        configure(before)
        results[before] = quadland.simulate(sc)
    for _ in range(repeats):
        for before in (True, False):
            configure(before)
            start = time.process_time()
            quadland.simulate(sc)
            times[before].append(time.process_time() - start)
    configure(False)
    a, b = results[True], results[False]
    same = set(a.columns) == set(b.columns) and all(
        np.array_equal(np.asarray(a[k]).view(np.int64), np.asarray(b[k]).view(np.int64))
        for k in a.columns) and np.array_equal(a.states.view(np.int64),
                                               b.states.view(np.int64))
    return {"before": times[True], "now": times[False], "same": same,
            "span": float(b["t"][-1])}


def campaign(runs: int, workers: int, chunk: int | None = None, before: bool = False
             ) -> tuple[float, str, float]:
    """(wall s of flying, runs.csv's text, CPU s of this process) of a highway campaign
    into a new folder (with one worker, the CPU is the runs'); ``before``:
    :func:`configure`'s."""
    saved = execute.chunk_size
    if chunk is not None:
        execute.chunk_size = lambda n, w: chunk
    configure(before)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            cpu = time.process_time()
            result = run_campaign("highway", runs=runs, out=Path(tmp) / "c", plots=False,
                                  workers=workers)
            cpu = time.process_time() - cpu
            assert result.complete and result.flown == runs
            return result.elapsed, (result.folder / "runs.csv").read_text(), cpu
    finally:
        execute.chunk_size = saved
        configure(False)


def flown_seconds(runs_csv: str) -> float:
    """The mean simulated time of a campaign's landings: touchdown plus the settle time
    (``t_touchdown`` or the failure's time; the last row of a run is not in runs.csv)."""
    rows = list(csv.DictReader(io.StringIO(runs_csv)))
    key = next((k for k in ("touchdown_time", "t_touchdown", "time") if k in rows[0]), None)
    if key is None:
        return float("nan")
    settle = load_scenario("highway")["landing.settle_time"]
    return statistics.mean(float(r[key]) + settle for r in rows if r[key] not in ("", "nan"))


def command(runs: int) -> float:
    """Wall s of ``quadland campaign`` as a fresh process (figures included)."""
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "quadland", "campaign", "--scenario", "highway",
                        "--runs", str(runs), "--out", str(Path(tmp) / "c")], check=True,
                       capture_output=True)
        return time.perf_counter() - start


def _med(xs) -> str:
    return f"{1e3 * statistics.median(xs):,.1f} ({1e3 * min(xs):,.1f} to {1e3 * max(xs):,.1f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    small, large = (30, 90) if args.quick else (60, 300)
    cores = len(os.sched_getaffinity(0))
    for before in (True, False):
        configure(before)
        warm_up(load_scenario("highway"))
        warm_up(load_scenario("ship"))
    print(f"load average before: {os.getloadavg()}, {cores} cores")
    ref = land_q(7)
    c_ms = statistics.median(ref)
    done = subprocess.run([str(EXAMPLE / "build" / "land"), "-q"], check=True,
                          capture_output=True, text=True)
    report = json.loads((done.stdout + done.stderr).strip().splitlines()[-1])
    c_span = report["time"] + load_scenario("highway")["landing.settle_time"]
    print("\n| what | CPU (ms), median (min to max) | / land -q |\n|---|---:|---:|")
    print(f"| `generated/example/land -q` (highway, 7 runs; {c_span:.1f} s flown) | {_med(ref)} "
          f"| 1 |")
    for name in ("highway", "ship"):
        w = warm(name, 7)
        for key in ("before", "now"):
            print(f"| warm `simulate` {name} ({w['span']:.1f} s flown), {key} | {_med(w[key])} | "
                  f"{statistics.median(w[key]) / c_ms:.2f} |")
        gain = statistics.median(w["before"]) / statistics.median(w["now"])
        print(f"| {name}: before / now | | {gain:.2f}x faster; bit for bit: {w['same']} |")
    out = {}
    for runs in (small, large):                 # interleaved: before, now, before, now
        for before in (True, False):
            out[runs, before] = campaign(runs, 1, before=before)
    csv_same = out[large, True][1] == out[large, False][1]
    span = flown_seconds(out[large, False][1])
    for before in (True, False):
        (t_s, _, c_s), (t_l, _, c_l) = out[small, before], out[large, before]
        slope, cpu_slope = (t_l - t_s) / (large - small), (c_l - c_s) / (large - small)
        print(f"- one worker, {'before' if before else 'now'}: {small} runs {t_s:.2f} s, "
              f"{large} runs {t_l:.2f} s wall: **{1e3 * slope:.1f} ms per landing**, "
              f"{slope / c_ms:.2f}x `land -q`'s CPU (target <= 1.5x); in CPU time "
              f"{1e3 * cpu_slope:.1f} ms per landing, {cpu_slope / c_ms:.2f}x; per simulated "
              f"second {slope / span / (c_ms / c_span):.2f}x `land -q`'s in wall, "
              f"{cpu_slope / span / (c_ms / c_span):.2f}x in CPU")
    print(f"- the campaign's landings fly {span:.1f} s on average (touchdown plus the settle "
          f"time), `land -q`'s {c_span:.1f} s; runs.csv before and now identical: {csv_same}")
    per_run, runs_csv, _ = campaign(large, cores, chunk=1)
    chunked, chunk_csv, _ = campaign(large, cores)
    k = local.chunk_size(large, cores)
    print(f"- {large} runs on {cores} processes, one run per message: {per_run:.2f} s wall; "
          f"in chunks of {k}: {chunked:.2f} s ({per_run / chunked:.2f}x); runs.csv "
          f"identical: {runs_csv == chunk_csv}")
    wall = command(large)
    print(f"- `quadland campaign --scenario highway --runs {large}` as a command, start to "
          f"exit with the figures: {wall:.2f} s wall (target 2 s for 300)")
    envelope = 12000 * chunked / large
    print(f"- a 20 x 20 envelope of 30 runs per cell (12,000 landings) at this throughput: "
          f"{envelope / 60:.1f} min (target 3 min)")
    print(f"\nload average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

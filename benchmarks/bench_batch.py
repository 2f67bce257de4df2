"""Campaigns at the speed of C (issue 20, items 1 and 2): where a landing's time goes.

Measured in one run, medians of CPU time (user + system), each figure beside its
reference:

* the pure-C reference: ``generated/example/land -q`` (highway, no CSV, the
  report alone; built here with the example's Makefile), the child's CPU time;
* a warm ``quadland.simulate`` of ``highway`` and ``ship`` in this process, as
  before this work (the plant with the gear's contact throughout, ``near``
  infinite, and the sensors' Gauss-Markov noise row by row) and now (the plant
  without the contact until the lowest foot is within
  ``quadland.kinds.landing.gear.free_flight_gap``, the noise column by column),
  interleaved; and the same landings compared column by column (bit for bit);
* the campaign's wall time per landing with one worker: the slope between a
  60-run and a 300-run ``highway`` campaign (fixed costs cancel), against
  ``land -q``'s CPU (target: at most 1.5x);
* a 300-landing ``highway`` campaign on every core, each run alone per message
  (``chunk = 1``, as before) and in chunks (``quadland.campaign.local.chunk_size``),
  its ``runs.csv`` compared (the same rows bit for bit), and ``quadland campaign``
  as a command from process start to exit (target: 2 s of wall);
* the 20 x 20 envelope of 30 runs per cell (12,000 landings, target 3 min),
  extrapolated from the measured throughput on every core.

The machine is shared: its load average is printed with the figures.

Run from the repository root::

    python benchmarks/bench_batch.py            # about four minutes on 2 quiet cores
    python benchmarks/bench_batch.py --quick    # smaller campaigns (30 and 90 runs)
"""

from __future__ import annotations

import argparse
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
from quadland.engine import noise
from quadland.kinds.landing import sensing
from quadland.kinds.landing import simulate as landing_simulate
from quadland.kinds.landing.gear import free_flight_gap
from quadland.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "generated" / "example"


def _gauss_markov_by_rows(times, sigma, tau, normals):
    """The recursion as it was before issue 20: one NumPy row at a time."""
    normals = np.asarray(normals, dtype=float)
    n, m = normals.shape
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (m,))
    tau = np.broadcast_to(np.asarray(tau, dtype=float), (m,))
    x = np.empty((n, m))
    if n == 0:
        return x
    a = noise._decay(np.diff(np.asarray(times, dtype=float))[:, None], tau[None, :])
    b = sigma * np.sqrt(np.clip(1.0 - a * a, 0.0, None))
    x[0] = sigma * normals[0]
    for k in range(n - 1):
        x[k + 1] = a[k] * x[k] + b[k] * normals[k + 1]
    return x


def configure(before: bool) -> None:
    """``before``: the plant with the contact throughout and the row-by-row noise."""
    landing_simulate.free_flight_gap = (lambda sc: np.inf) if before else free_flight_gap
    sensing.gauss_markov = _gauss_markov_by_rows if before else noise.gauss_markov


def land_q(repeats: int) -> list[float]:
    """CPU seconds of each ``land -q`` (the child's rusage)."""
    subprocess.run(["make", "-s", "build/land"], cwd=EXAMPLE, check=True)
    out = []
    for _ in range(repeats):
        proc = subprocess.Popen([str(EXAMPLE / "build" / "land"), "-q"],
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _, status, usage = os.wait4(proc.pid, 0)
        proc.returncode = os.waitstatus_to_exitcode(status)
        assert proc.returncode == 0
        out.append(usage.ru_utime + usage.ru_stime)
    return out


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
        np.array_equal(a[k], b[k], equal_nan=True) for k in a.columns) and np.array_equal(
        a.states, b.states)
    return {"before": times[True], "now": times[False], "same": same}


def campaign(runs: int, workers: int, chunk: int | None = None) -> tuple[float, str, float]:
    """(wall s of flying, runs.csv's text, CPU s of this process) of a highway campaign
    into a new folder (with one worker, the CPU is the runs')."""
    saved = execute.chunk_size
    if chunk is not None:
        execute.chunk_size = lambda n, w: chunk
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
    warm_up(load_scenario("highway"))
    warm_up(load_scenario("ship"))
    print(f"load average before: {os.getloadavg()}, {cores} cores")
    ref = land_q(7)
    c_ms = statistics.median(ref)
    print("\n| what | CPU (ms), median (min to max) | / land -q |\n|---|---:|---:|")
    print(f"| `generated/example/land -q` (highway, 7 runs) | {_med(ref)} | 1 |")
    for name in ("highway", "ship"):
        w = warm(name, 5)
        for key, label in (("before", "the contact plant throughout, noise by rows"),
                           ("now", "free plant until 10 cm, noise by columns")):
            print(f"| warm `simulate` {name}, {label} | {_med(w[key])} | "
                  f"{statistics.median(w[key]) / c_ms:.2f} |")
        gain = statistics.median(w["before"]) / statistics.median(w["now"])
        print(f"| {name}: before / now | | {gain:.2f}x faster; bit for bit: {w['same']} |")
    t_small, _, c_small = campaign(small, 1)
    t_large, _, c_large = campaign(large, 1)
    slope = (t_large - t_small) / (large - small)
    cpu_slope = (c_large - c_small) / (large - small)
    print(f"\n- one worker: {small} runs {t_small:.2f} s, {large} runs {t_large:.2f} s wall: "
          f"**{1e3 * slope:.1f} ms per landing**, {slope / c_ms:.2f}x `land -q`'s CPU "
          f"(target <= 1.5x); in CPU time {1e3 * cpu_slope:.1f} ms per landing, "
          f"{cpu_slope / c_ms:.2f}x")
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

"""Campaign throughput: runs per second of ``quadland campaign`` on this machine.

Measured in one run, each campaign into a new folder with the compiled
simulators already built (the disk cache):

* the paper scenario's own 10 s runs (its ``[campaign]`` table: mass and
  inertia +-10 %, a new disturbance seed per run): in this process (one
  worker), on every core (local processes), and on a ``dask.distributed``
  ``LocalCluster`` of one single-threaded worker process per core on
  127.0.0.1;
* ``highway`` and ``ship``, on every core;
* ``quadland campaign`` as a command, from the start of the process to its
  end (imports, process pool, summary and figures included).

With ``--landing`` it also flies the shipped ``highway`` and ``ship``
campaigns whole (300 runs each) and renders their results for
``docs/landing.md``.

"runs/s" is the runs flown over the wall time of flying them
(``CampaignResult.elapsed``: from the first run submitted to the last
recorded, the start of the process pool included); the summary and the
figures come after. Requirement: 10 s paper runs at 40 runs/s or more on
this 2-core machine.

Run from the repository root::

    python benchmarks/bench_campaign.py            # about two minutes
    python benchmarks/bench_campaign.py --write    # and rewrite docs/performance.md's part
    python benchmarks/bench_campaign.py --landing --write    # and docs/landing.md's results

``--write`` replaces the text between ``<!-- bench_campaign: begin -->`` and
``<!-- bench_campaign: end -->`` of ``docs/performance.md`` (and, with
``--landing``, between ``<!-- campaign_results: begin -->`` and
``<!-- campaign_results: end -->`` of ``docs/landing.md``, with the figures
in ``docs/figures/campaign/``).
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "performance.md"
BEGIN, END = "<!-- bench_campaign: begin -->", "<!-- bench_campaign: end -->"
LANDING_DOC = ROOT / "docs" / "landing.md"
LANDING_BEGIN, LANDING_END = "<!-- campaign_results: begin -->", "<!-- campaign_results: end -->"
FIGURES = ROOT / "docs" / "figures" / "campaign"
TOUCHDOWN = ("sink_rate", "offset", "relative_speed", "tilt_deg")
TARGET = 40.0


def campaign(name: str, runs: int, **kw) -> tuple[float, float]:
    """(runs/s, wall s) of one campaign flown into a new folder."""
    with tempfile.TemporaryDirectory() as tmp:
        result = run_campaign(name, runs=runs, out=Path(tmp) / "c", plots=False, **kw)
        assert result.complete and result.flown == runs
        return runs / result.elapsed, result.elapsed


def dask_campaign(name: str, runs: int, workers: int) -> tuple[float, float]:
    import logging

    from distributed import LocalCluster

    logging.getLogger("distributed").setLevel(logging.ERROR)
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      host="127.0.0.1", dashboard_address=None, silence_logs=logging.ERROR
                      ) as cluster:
        return campaign(name, runs, scheduler=cluster.scheduler_address)


def command(name: str, runs: int) -> float:
    """Wall time of ``quadland campaign`` as a fresh process, figures included, s."""
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "quadland", "campaign", "--scenario", name,
                        "--runs", str(runs), "--out", str(Path(tmp) / "c")], check=True,
                       capture_output=True)
        return time.perf_counter() - start


def best(fn, repeats: int):
    """The fastest of ``repeats`` measurements (the machine is shared)."""
    return max((fn() for _ in range(repeats)), key=lambda r: r[0])


def measure(runs: int, repeats: int) -> dict:
    cores = len(os.sched_getaffinity(0))
    for name in ("paper", "highway", "ship"):
        warm_up(load_scenario(name))
    m = {"cores": cores, "runs": runs}
    m["paper_1"] = best(lambda: campaign("paper", runs // 4, workers=1), repeats)
    m["paper_all"] = best(lambda: campaign("paper", runs), repeats)
    m["paper_dask"] = best(lambda: dask_campaign("paper", runs, cores), repeats)
    m["highway"] = campaign("highway", 100)
    m["ship"] = campaign("ship", 100)
    m["command"] = min(command("paper", 300) for _ in range(repeats))
    return m


def render(m: dict) -> str:
    cores = m["cores"]
    rows = [("paper, 10 s runs, in this process (`--workers 1`)", m["paper_1"], m["runs"] // 4),
            (f"paper, 10 s runs, {cores} local processes (default)", m["paper_all"], m["runs"]),
            (f"paper, 10 s runs, Dask `LocalCluster`, {cores} worker processes on 127.0.0.1 "
             "(`--scheduler`)", m["paper_dask"], m["runs"]),
            (f"highway, {cores} local processes", m["highway"], 100),
            (f"ship, {cores} local processes", m["ship"], 100)]
    lines = [f"Measured by `python benchmarks/bench_campaign.py` ({platform.machine()}, "
             f"{cores} cores, Python {platform.python_version()}); best of the repeats (the "
             "machine is shared).", "",
             "| campaign | runs | wall (s) | runs/s | per run and core (ms) |",
             "| --- | ---: | ---: | ---: | ---: |"]
    for label, (rate, wall), n in rows:
        per = 1e3 * wall / n * (1 if "this process" in label else cores)
        lines.append(f"| {label} | {n} | {wall:.2f} | **{rate:.1f}** | {per:.1f} |")
    rate = m["paper_all"][0]
    lines += ["", f"- Requirement, 10 s paper runs at {TARGET:g} runs/s or more on this "
              f"{cores}-core machine: **{'met' if rate >= TARGET else 'not met'}** "
              f"({rate:.1f} runs/s).",
              f"- `quadland campaign` (300 paper runs) as a command, from process start to "
              f"exit with the summary and figures: {m['command']:.1f} s."]
    return "\n".join(lines) + "\n"


def landing_campaigns(write: bool) -> str:
    """Fly the shipped highway and ship campaigns whole; their results as Markdown."""
    import json
    import shutil

    rows, worst, notes = [], [], []
    for name in ("highway", "ship"):
        with tempfile.TemporaryDirectory() as tmp:
            result = run_campaign(name, out=Path(tmp) / name)
            s = json.loads((result.folder / "summary.json").read_text())
            if write:
                FIGURES.mkdir(parents=True, exist_ok=True)
                for fig in ("metrics_cdf.png", "failures.png"):
                    shutil.copyfile(result.folder / fig, FIGURES / f"{name}_{fig}")
        lo, hi = s["confidence"]["interval"]
        cells = [f"{s['metrics'][m]['p50']:.3g} / {s['metrics'][m]['p99']:.3g} / "
                 f"**{s['metrics'][m]['max']:.3g}** ({s['metrics'][m]['limit']:g})"
                 for m in TOUCHDOWN]
        rows.append(f"| `{name}` | {s['runs']} | {s['successes']} of {s['flown']} | "
                    f"{100 * lo:.1f} to {100 * hi:.1f} % | "
                    f"{100 * s['confidence']['lower_bound_one_sided']:.1f} % | "
                    + " | ".join(cells) + f" | {s['numerical_failures']} |")
        w = s["worst_runs"][0]
        worst.append(f"- `{name}`, run {w['index']} (largest metric / limit "
                     f"{w['severity']:.2f}: " + ", ".join(
                         f"{m} {w['metrics'][m]:.3g}" for m in TOUCHDOWN) + "); replay:\n\n"
                     f"  ```sh\n  {w['command']}\n  ```")
        sep = s.get("separation") or s.get("most_correlated")
        if s.get("separation"):
            notes.append(f"`{name}`: the failures are best separated by `{sep['parameter']}` "
                         f"(KS D = {sep['ks_statistic']:.2f}).")
        elif sep:
            notes.append(f"`{name}`: no failure; the largest metric / limit follows "
                         f"`{sep['parameter']}` most (Spearman rho = "
                         f"{sep['spearman_rho']:.2f}).")
    head = ("| campaign | runs | within limits | 95 % interval | 95 % lower bound (one-sided) | "
            "sink rate p50 / p99 / **max** (limit), m/s | offset, m | relative speed, m/s | "
            "tilt, deg | numerical failures |\n| --- | ---: | ---: | --- | ---: | --- | --- | "
            "--- | --- | ---: |")
    return "\n".join([
        f"Measured by `python benchmarks/bench_campaign.py --landing` ({platform.machine()}, "
        f"Python {platform.python_version()}): `quadland campaign --scenario NAME` with the "
        "shipped tables (300 runs each).", "", head, *rows, "",
        "The worst run of each (closest to a limit), with the command that flies it again:",
        "", *worst, "", *(f"- {n}" for n in notes), "",
        "| | `highway` | `ship` |", "| --- | --- | --- |",
        "| touchdown metrics against their limits | "
        "![](figures/campaign/highway_metrics_cdf.png) | "
        "![](figures/campaign/ship_metrics_cdf.png) |",
        "| the runs against the most telling parameter | "
        "![](figures/campaign/highway_failures.png) | "
        "![](figures/campaign/ship_failures.png) |"]) + "\n"


def _replace(path: Path, begin: str, end: str, text: str) -> None:
    doc = path.read_text()
    head, _, rest = doc.partition(begin)
    _, _, tail = rest.partition(end)
    if not rest:
        raise SystemExit(f"{path}: no {begin} marker")
    path.write_text(f"{head}{begin}\n\n{text}\n{end}{tail}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=600, help="paper runs per campaign")
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--landing", action="store_true",
                        help="also fly the highway and ship campaigns whole")
    parser.add_argument("--write", action="store_true", help="update the docs")
    args = parser.parse_args()
    text = render(measure(args.runs, args.repeats))
    print(text)
    if args.write:
        _replace(DOC, BEGIN, END, text)
    if args.landing:
        results = landing_campaigns(args.write)
        print(results)
        if args.write:
            _replace(LANDING_DOC, LANDING_BEGIN, LANDING_END, results)


if __name__ == "__main__":
    main()

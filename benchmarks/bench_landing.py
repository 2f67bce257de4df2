"""Landing scenarios: touchdown figures over seeds and speeds, and the 6-DOF loop's cost.

Measured in one run:

* each shipped landing scenario (``highway``, ``turning``, ``ship``) at its
  default seed: the touchdown figures of ``summary.json``'s ``landing``
  object and the time of each phase;
* each over ``simulation.seed`` 0-19: how many land within the limits, and
  the worst of each figure;
* ``highway`` at vehicle speeds from 50 to 100 km/h (``initial.velocity2``
  and ``vehicle.tau = [d11 u2, 0, 0]``), at its default seed and, at 80
  km/h, over seeds 0-19;
* the cost of a simulated second: ``quadland.simulate`` warm (the compiled
  simulator built beforehand), CPU time, medians, of the 6-DOF landing loop
  (a hover that never descends, ``landing.dwell_time`` longer than the
  run) against the paper's 4-DOF loop, continuous and sampled at the same
  250 Hz, at the node counts the scenarios ship with and at equal ones;
  and the landing loop on CasADi's virtual machine (no C compiler).

Run from the repository root::

    python benchmarks/bench_landing.py            # about a minute
    python benchmarks/bench_landing.py --write    # and rewrite docs/landing.md's measured part

``--write`` replaces the text between the markers ``<!-- bench_landing:
begin -->`` and ``<!-- bench_landing: end -->`` of ``docs/landing.md``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import quadland
from quadland.kinds.landing.report import landing_summary
from quadland.scenario import load_scenario

DOC = Path(__file__).resolve().parents[1] / "docs" / "landing.md"
BEGIN, END = "<!-- bench_landing: begin -->", "<!-- bench_landing: end -->"
SCENARIOS = ("highway", "turning", "ship")
SEEDS = range(20)
SPEEDS_KMH = (50, 60, 70, 80, 90, 100)
FIGURES = ("sink_rate", "offset", "relative_speed", "tilt_deg")


def land(name: str, overrides=()) -> dict:
    """summary.json's figures of one landing."""
    return landing_summary(quadland.simulate(load_scenario(name, list(overrides))))


def speed_overrides(kmh: float) -> list[str]:
    u2 = kmh / 3.6
    d11 = load_scenario("highway")["vehicle.d11"]
    return [f"initial.velocity2=[{u2!r}, 0.0]", f"vehicle.tau=[{d11 * u2!r}, 0.0, 0.0]"]


def sweep(name: str, extra=()) -> dict:
    """Seeds 0-19: successes, aborts and the worst of each figure."""
    runs = [land(name, [f"simulation.seed={s}", *extra])["landing"] for s in SEEDS]
    landed = [r for r in runs if r["touchdown"]]
    worst = {k: max(r[k] for r in landed) for k in FIGURES} if landed else {}
    return {"success": sum(r["success"] for r in runs), "runs": len(runs),
            "aborts": sum(r["aborts"] for r in runs),
            "time": max(r["time"] for r in landed) if landed else None, **worst}


def cpu_per_second(sc, runs: int = 5) -> float:
    """Median CPU seconds per simulated second of a warm ``simulate``."""
    quadland.simulate(sc)                                  # build / load once
    times = []
    for _ in range(runs):
        start = time.process_time()
        quadland.simulate(sc)
        times.append(time.process_time() - start)
    return statistics.median(times) / sc["simulation.duration"]


def hover(duration: float, *extra) -> quadland.Scenario:
    """``highway`` hovering for the whole run: it never descends, so never touches down."""
    return load_scenario("highway", [f"simulation.duration={duration}",
                                     "landing.dwell_time=1000.0", *extra])


def vm_per_second(duration: float = 5.0) -> float:
    """CPU seconds per simulated second of the landing loop on CasADi's VM.

    As without a C compiler: ``quadland.engine.compiled.have_compiler`` answers no.
    """
    import warnings

    from quadland.engine import compiled

    sc, found = hover(duration), compiled.have_compiler
    compiled.have_compiler = lambda: False
    compiled.compiled_loop.cache_clear()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", compiled.QuadlandWarning)
            start = time.process_time()
            quadland.simulate(sc)
            return (time.process_time() - start) / duration
    finally:
        compiled.have_compiler = found
        compiled.compiled_loop.cache_clear()


def costs() -> dict:
    T = 60.0
    paper = f"simulation.duration={T}"
    return {
        "landing, l = 10 (shipped), 250 Hz": cpu_per_second(hover(T)),
        "landing, l = 100, 250 Hz": cpu_per_second(hover(T, "rbf.nodes=100")),
        "paper, l = 100 (shipped), continuous": cpu_per_second(load_scenario("paper", [paper])),
        "paper, l = 100, sampled at 250 Hz": cpu_per_second(
            load_scenario("paper", [paper, "controller.rate_hz=250"])),
        "paper, l = 10, sampled at 250 Hz": cpu_per_second(
            load_scenario("paper", [paper, "controller.rate_hz=250", "rbf.nodes=10"])),
        "landing, l = 10, CasADi VM (no compiler), 250 Hz": vm_per_second(),
    }


def measure() -> dict:
    return {
        "default": {n: land(n) for n in SCENARIOS},
        "seeds": {n: sweep(n) for n in SCENARIOS},
        "speeds": {k: land("highway", speed_overrides(k))["landing"] for k in SPEEDS_KMH},
        "seeds_80": sweep("highway", speed_overrides(80)),
        "costs": costs(),
    }


def _f(v, digits=3):
    return "-" if v is None else f"{v:.{digits}f}"


def render(m: dict) -> str:
    out = [BEGIN, "",
           f"Measured by `python benchmarks/bench_landing.py` ({platform.machine()}, "
           f"Python {platform.python_version()}).", "",
           "**At the default seed** (limits: sink rate 0.5 m/s, offset 0.2 m, relative speed "
           "0.5 m/s, tilt 10 deg):", "",
           "| scenario | touchdown at (s) | sink rate (m/s) | offset (m) | relative speed (m/s) "
           "| tilt (deg) | aborts | success | align, descend from (s) |",
           "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name, s in m["default"].items():
        d, p = s["landing"], s["phases"]
        out.append(f"| `{name}` | {_f(d['time'], 2)} | {_f(d['sink_rate'])} | "
                   f"{_f(d['offset'])} | {_f(d['relative_speed'])} | {_f(d['tilt_deg'], 2)} | "
                   f"{d['aborts']} | {'yes' if d['success'] else 'no'} | "
                   f"{_f(p['align'], 2)}, {_f(p['descend'], 2)} |")
    out += ["", "**Over seeds 0-19** (the seed draws the disturbance's noise and the "
            "turbulence), the worst of each figure:", "",
            "| scenario | within limits | aborts | latest touchdown (s) | sink rate (m/s) | "
            "offset (m) | relative speed (m/s) | tilt (deg) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    rows = [(f"`{n}`", s) for n, s in m["seeds"].items()]
    rows.append(("`highway` at 80 km/h", m["seeds_80"]))
    for label, s in rows:
        out.append(f"| {label} | {s['success']} of {s['runs']} | {s['aborts']} | "
                   f"{_f(s['time'], 2)} | {_f(s.get('sink_rate'))} | {_f(s.get('offset'))} | "
                   f"{_f(s.get('relative_speed'))} | {_f(s.get('tilt_deg'), 2)} |")
    out += ["", "**`highway` at other speeds** (default seed; `initial.velocity2` and "
            "`vehicle.tau = [d11 u2, 0, 0]`):", "",
            "| km/h | sink rate (m/s) | offset (m) | relative speed (m/s) | tilt (deg) | "
            "success |", "| --- | --- | --- | --- | --- | --- |"]
    for kmh, d in m["speeds"].items():
        out.append(f"| {kmh} | {_f(d['sink_rate'])} | {_f(d['offset'])} | "
                   f"{_f(d['relative_speed'])} | {_f(d['tilt_deg'], 2)} | "
                   f"{'yes' if d['success'] else 'no'} |")
    out += ["", "**Cost of a simulated second** (`quadland.simulate` warm, CPU time, "
            "median of 5; 60 s runs, the landing loop hovering without descending):", "",
            "| loop | ms per simulated second |", "| --- | --- |"]
    for label, v in m["costs"].items():
        out.append(f"| {label} | {1e3 * v:.2f} |")
    out += ["", END]
    return "\n".join(out)


def write(text: str, path: Path = DOC) -> None:
    doc = path.read_text()
    head, sep, rest = doc.partition(BEGIN)
    _, sep2, tail = rest.partition(END)
    if not (sep and sep2):
        raise SystemExit(f"{path}: no {BEGIN} ... {END} markers")
    path.write_text(head + text + tail)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help="rewrite docs/landing.md's section")
    args = ap.parse_args(argv)
    text = render(measure())
    print(text)
    if args.write:
        write(text)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()

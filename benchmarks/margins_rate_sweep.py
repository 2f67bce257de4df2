"""Sampled-data margins against the control rate, with one period of computation delay.

For each loop the script sweeps ``controller.rate_hz`` and reports the
margins of the sampled loop that flight code flies: the plant held by a
zero-order hold, the step's exact discrete update, and the command sent one
period after the sample (``margin_report(..., delay_periods=1)``). Where the
verdict changes between two rates of the grid it bisects, to 1 Hz, for the
lowest rate at which every loop meets the requirement (6 dB / 45 deg), and the
lowest at which the multiloop disk margin meets it too.

* the landing loops (``highway``, ``turning``, ``ship``) at hover, with their
  shipped gains, and ``highway`` with the softer outer gains of the hover test
  in docs/landing.md (``k1p = k2p = 1``);
* the paper's loop (``l = 100``, printed law) with the plain hold and with the
  shipped hold compensation, with the delay and without it (the numbers
  docs/margins.md gave before the delay was modelled).

Run from the repository root::

    python benchmarks/margins_rate_sweep.py            # 5-10 minutes
    python benchmarks/margins_rate_sweep.py --write    # and rewrite docs/margins.md's part

``--write`` replaces the text between the markers ``<!-- margins_sweep:
begin -->`` and ``<!-- margins_sweep: end -->`` of ``docs/margins.md``.
"""

from __future__ import annotations

import argparse
import math
import platform
from pathlib import Path

from threadpoolctl import threadpool_limits

from quadland.margins import LoopReport, Requirement, margin_report
from quadland.scenario import load_scenario

DOC = Path(__file__).resolve().parents[1] / "docs" / "margins.md"
BEGIN, END = "<!-- margins_sweep: begin -->", "<!-- margins_sweep: end -->"
REQUIREMENT = Requirement(6.0, 45.0)
LANDING_RATES = (50, 100, 200, 250, 500, 1000, 2000, 5000, 10000)
PAPER_RATES = (10, 20, 30, 40, 50, 100, 500)
SOFT_OUTER = ["controller.k1p=[1.0, 1.0, 1.0]", "controller.k2p=[1.0, 1.0, 1.0]"]


def sampled(name: str, overrides, rate_hz: float, delay: int) -> LoopReport:
    """The sampled section of the margin review at ``rate_hz``."""
    sc = load_scenario(name, [*overrides, f"controller.rate_hz={rate_hz!r}"])
    return margin_report(sc, requirement=REQUIREMENT, delay_periods=delay).sampled


def continuous(name: str, overrides) -> LoopReport:
    return margin_report(load_scenario(name, list(overrides)),
                         requirement=REQUIREMENT).continuous


def lowest_rate(name, overrides, rates, reports, verdict) -> str:
    """The lowest rate (1 Hz) from which ``verdict`` holds on the rest of the grid."""
    ok = [verdict(r) for r in reports]
    if not ok[-1]:
        return f"none up to {rates[-1]:g} Hz"
    k = len(ok) - 1
    while k > 0 and ok[k - 1]:
        k -= 1
    if k == 0:
        return f"{rates[0]:g} Hz or less"
    lo, hi = rates[k - 1], rates[k]
    while hi - lo > 1:
        mid = math.floor((lo + hi) / 2)
        if verdict(sampled(name, overrides, mid, 1)):
            hi = mid
        else:
            lo = mid
    return f"{hi:g} Hz"


def _dbs(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.1f}"


def _row(label, r: LoopReport) -> str:
    if not r.stable:
        return f"| {label} | **unstable** | | | | | |"
    weakest = min(r.loops, key=lambda m: m.phase_margin_deg)
    gm = min(r.loops, key=lambda m: m.gain_margin_up_db)
    pms = " / ".join(f"{m.phase_margin_deg:.1f}" for m in r.loops)
    dms = " / ".join(f"{1e3 * m.delay_margin_s:.0f}" for m in r.loops)
    d = r.multiloop_disk.disk
    disk = f"a = {d.disk_margin:.3f}, +-{20 * math.log10(d.gain_margin[1]):.1f} dB, " \
           f"{d.phase_margin:.1f} deg" if d.disk_margin < 2 else f"a = {d.disk_margin:.3f}"
    verdict = "pass" if r.passed and r.multiloop_disk.passed else \
        "loops pass, disk fails" if r.passed else "fail"
    return (f"| {label} | {weakest.name} | {pms} | {gm.name} {_dbs(gm.gain_margin_up_db)} | "
            f"{dms} | {disk} | {verdict} |")


def landing_tables() -> list[str]:
    out = []
    cases = [("highway", [], "highway"), ("turning", [], "turning"), ("ship", [], "ship"),
             ("highway", SOFT_OUTER, "highway, outer gains k1p = k2p = 1")]
    for name, overrides, title in cases:
        cont = continuous(name, overrides)
        reports = [sampled(name, overrides, r, 1) for r in LANDING_RATES]
        loops = " / ".join(m.name for m in cont.loops)
        out += [f"**{title}** (phase and delay margins per loop: {loops})", "",
                "| rate | weakest loop | PM (deg) | smallest GM up (dB) | DM (ms) | "
                "multiloop disk | verdict |",
                "| --- | --- | --- | --- | --- | --- | --- |",
                _row("continuous limit", cont)]
        out += [_row(f"{r:g} Hz", rep) for r, rep in zip(LANDING_RATES, reports, strict=True)]
        loops_ok = lowest_rate(name, overrides, LANDING_RATES, reports, lambda r: r.passed)
        disk_ok = lowest_rate(name, overrides, LANDING_RATES, reports,
                              lambda r: r.passed and r.multiloop_disk.passed)
        out += ["", f"Lowest rate meeting 6 dB / 45 deg with one period of delay: every loop "
                    f"{loops_ok}; with the multiloop disk margin too {disk_ok}.", ""]
    return out


def paper_tables() -> list[str]:
    out = []
    for hold in (0.0, 0.5):
        overrides = [f"controller.hold_compensation={hold}"]
        out += [f"**paper, l = 100, hold compensation {hold:g}** (delay: commanded one period "
                "after the sample; none: at the sample, the numbers before the delay was "
                "modelled)", "",
                "| rate, delay | weakest loop | PM (deg) | smallest GM up (dB) | DM (ms) | "
                "multiloop disk | verdict |",
                "| --- | --- | --- | --- | --- | --- | --- |"]
        reports = {delay: [sampled("paper", overrides, rate, delay) for rate in PAPER_RATES]
                   for delay in (1, 0)}
        for k in reversed(range(len(PAPER_RATES))):
            for delay in (1, 0):
                out.append(_row(f"{PAPER_RATES[k]:g} Hz, {'1 period' if delay else 'none'}",
                                reports[delay][k]))
        loops_ok = lowest_rate("paper", overrides, PAPER_RATES, reports[1], lambda r: r.passed)
        disk_ok = lowest_rate("paper", overrides, PAPER_RATES, reports[1],
                              lambda r: r.passed and r.multiloop_disk.passed)
        out += ["", f"Lowest rate meeting 6 dB / 45 deg with one period of delay: every loop "
                    f"{loops_ok}; with the multiloop disk margin too {disk_ok}.", ""]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true",
                        help="rewrite the measured part of docs/margins.md")
    args = parser.parse_args()
    with threadpool_limits(1):
        lines = [f"Measured by `python benchmarks/margins_rate_sweep.py` ({platform.machine()}, "
                 f"Python {platform.python_version()}); requirement 6 dB / 45 deg.", ""]
        lines += landing_tables() + paper_tables()
    text = "\n".join(lines).rstrip() + "\n"
    print(text)
    if args.write:
        doc = DOC.read_text()
        head, sep, rest = doc.partition(BEGIN)
        _, sep2, tail = rest.partition(END)
        if not (sep and sep2):
            raise SystemExit(f"{DOC}: no {BEGIN} ... {END} markers")
        DOC.write_text(f"{head}{BEGIN}\n\n{text}\n{END}{tail}")


if __name__ == "__main__":
    main()

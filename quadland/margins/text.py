"""The text table ``quadland margins`` prints: one section per loop kind and rate."""

from __future__ import annotations

import math

from quadland.margins.report import LoopReport, MarginReport, Requirement, decibels
from quadland.margins.sensitivity import extras_lines

__all__ = ["format_report"]


def _fmt(x, spec=".3g", none="-"):
    if x is None:
        return none
    if isinstance(x, float) and math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return format(x, spec)


def _verdict(passed: bool) -> str:
    return "pass" if passed else "FAIL"


def _table(section: LoopReport, title: str, req: Requirement) -> list[str]:
    lines = [title,
             f"  {'loop':<9}{'GM up':>8}{'GM down':>9}{'PM':>8}{'w_c':>9}{'DM':>9}"
             f"{'w_180':>9}{'disk a':>8}{'disk GM':>9}{'disk PM':>9}  verdict",
             f"  {'':<9}{'dB':>8}{'dB':>9}{'deg':>8}{'rad/s':>9}{'s':>9}"
             f"{'rad/s':>9}{'':>8}{'+-dB':>9}{'deg':>9}"]
    for r in section.loops:
        d = r.disk
        tighter_up = r.gain_margin_up_db <= -r.gain_margin_down_db
        w180 = r.gain_margin_up_frequency if tighter_up else r.gain_margin_down_frequency
        lines.append(
            f"  {r.name:<9}{_fmt(r.gain_margin_up_db, '.1f'):>8}"
            f"{_fmt(r.gain_margin_down_db, '.1f'):>9}{_fmt(r.phase_margin_deg, '.1f'):>8}"
            f"{_fmt(r.crossover_frequency, '.3g'):>9}{_fmt(r.delay_margin_s, '.3g'):>9}"
            f"{_fmt(w180, '.3g'):>9}{d.disk_margin:>8.3f}"
            f"{_fmt(decibels(d.gain_margin[1]), '.1f'):>9}{d.phase_margin:>9.1f}"
            f"  {_verdict(r.passed)}")
    m = section.multiloop_disk.disk
    lines.append(f"  multiloop disk margin: alpha = {m.disk_margin:.3f}, gain "
                 f"[{m.gain_margin[0]:.3f}, {_fmt(m.gain_margin[1], '.3f')}] "
                 f"(+-{_fmt(decibels(m.gain_margin[1]), '.1f')} dB), phase +-"
                 f"{m.phase_margin:.1f} deg, at {m.frequency:.3g} rad/s: "
                 f"{_verdict(section.multiloop_disk.passed)}")
    lines += extras_lines(section.sensitivity, section.sensors, req)
    p = section.poles
    slow = ", ".join(f"{q.real:.4g}{q.imag:+.4g}j" for q in p.slowest)
    least = ", ".join(f"{q.real:.4g}{q.imag:+.4g}j (zeta {q.damping:.3f})"
                      for q in p.least_damped) or "none (all real)"
    lines.append(f"  closed loop ({p.count} states): "
                 f"{'stable' if section.stable else 'UNSTABLE'}")
    lines.append(f"  slowest poles (s-plane): {slow}")
    lines.append(f"  least damped poles:      {least}")
    lines.append(f"  requirement {req.gain_margin_db:g} dB / {req.phase_margin_deg:g} deg, each "
                 "loop with the others closed and the multiloop disk margin: "
                 f"{'PASS' if section.passed else 'FAIL'}")
    return lines


def _periods(k: int) -> str:
    return f"{k} period{'' if k == 1 else 's'}"


def format_report(report: MarginReport) -> str:
    """The margin review as a plain-text table.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    str
        The operating point, then per controller (continuous, sampled) one
        row per loop (gain margins up and down, phase margin, crossover,
        delay margin, phase crossover, loop-at-a-time disk margin, verdict),
        the multiloop disk margin, stability, the slowest and least damped
        poles and the section's verdict; then the one verdict of the review
        (:attr:`MarginReport.passed`, which sections it judges); ends with a
        newline.
    """
    from quadland.kinds import kind_of

    lines, title = kind_of(report.scenario).describe_point(report.scenario, report.point)
    lines += _table(report.continuous, title, report.requirement)
    if report.sampled is not None:
        sd = report.sampled
        delay = sd.computation_delay_periods
        lines += [""] + _table(sd, f"sampled-data controller, zero-order hold at "
                                   f"{sd.rate_hz:g} Hz, computation delay {_periods(delay)} "
                                   f"({1e3 * sd.computation_delay_s:.3g} ms)",
                               report.requirement)
    if report.filtered is not None:
        fd = report.filtered
        delay = fd.computation_delay_periods
        lines += [""] + _table(fd, f"sampled, filter in the loop: the navigation filter at its "
                                   f"steady state (rate-equivalent gain), its horizon and "
                                   f"output predictor, computation delay "
                                   f"{_periods(delay)}; the flown loop, "
                                   "the verdict's", report.requirement)
    judged = " and ".join(label for label, _ in report.judged)
    req = report.requirement
    lines += ["", f"verdict: {'PASS' if report.passed else 'FAIL'} against "
                  f"{req.gain_margin_db:g} dB / {req.phase_margin_deg:g} deg, judged on the "
                  f"{judged} section{'s' if len(report.judged) > 1 else ''}"]
    return "\n".join(lines) + "\n"

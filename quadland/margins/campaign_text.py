"""What ``quadland margins --campaign`` prints and the table of every draw it writes."""

from __future__ import annotations

import csv
import io
import math

from quadland.margins.campaign import CampaignMargins

__all__ = ["format_campaign", "draws_csv"]


def _num(x, spec=".4g") -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return format(x, spec)


def format_campaign(result: CampaignMargins) -> str:
    """The distribution of the draws' margins and the worst draws, as plain text.

    Parameters
    ----------
    result : CampaignMargins

    Returns
    -------
    str
        A header (scenario, draws, how many were reviewed and met the
        requirement), one row per figure (median, worst, the worst draw's
        index), then the worst draws with their commands; ends with a
        newline.
    """
    c, req = result.campaign, result.requirement
    n = len(result.draws)
    lines = [f"quadland margins --campaign: scenario {result.scenario}, {n} draws of its "
             f"[campaign] table (seed {c.get('seed')}, {c.get('sampling')} sampling), the "
             f"{result.section} loop",
             f"  reviewed {result.count('ok')}, invalid {result.count('invalid')}, without an "
             f"operating point {result.count('failed')}; meeting {req.gain_margin_db:g} dB / "
             f"{req.phase_margin_deg:g} deg: {result.passed} of {n}",
             "",
             f"  {'figure':<36}{'unit':>5}{'median':>10}{'worst':>10}{'draw':>6}"]
    for name, d in result.distribution.items():
        lines.append(f"  {name:<36}{result.units.get(name, ''):>5}{_num(d['median']):>10}"
                     f"{_num(d['worst']):>10}{d['worst_index']:>6}")
    if result.worst:
        lines += ["", "worst draws (by multiloop disk margin; without an operating point "
                      "first):"]
    for d in result.worst:
        f = d.figures
        what = (d.message if d.status != "ok" else
                f"alpha {_num(f['multiloop_disk.alpha'], '.3f')} "
                f"(+-{_num(f['multiloop_disk.gain_margin_db'], '.1f')} dB, "
                f"{_num(f['multiloop_disk.phase_margin_deg'], '.1f')} deg), "
                f"Ms {_num(f['multiloop.ms'], '.3f')}, Mt {_num(f['multiloop.mt'], '.3f')}"
                f"{'' if d.passed else ', FAIL ' + d.message}")
        lines += [f"  draw {d.index} (seed {d.seed}): {what}",
                  f"    replay:  {d.replay}", f"    margins: {d.review}"]
    return "\n".join(lines) + "\n"


def draws_csv(result: CampaignMargins) -> bytes:
    """``margins_draws.csv``: one row per draw, its dispersed values and its figures."""
    figures = list(result.units)
    columns = list(result.draws[0].columns) if result.draws else []
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["index", "seed", "status", "passed", *columns, *figures, "message"])
    for d in result.draws:
        w.writerow([d.index, d.seed, d.status, "true" if d.passed else "false",
                    *(d.columns.get(k, "") for k in columns),
                    *(repr(d.figures[k]) if k in d.figures else "" for k in figures),
                    d.message])
    return out.getvalue().encode("utf-8")

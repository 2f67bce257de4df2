"""The reach of a numeric dispersion's draws, and what a draw sets.

A dispersion's draw ``X`` lies within :func:`extremes` (a normal draw within
``-ndtri(U_EDGE)`` standard deviations of its mean, the unit cube being kept
within ``[U_EDGE, 1 - U_EDGE]``); :func:`apply_mode` turns it into a key's
value. :func:`check_finite` and :func:`check_reach` refuse, in one line
naming the entry, a dispersion whose draws overflow or leave a key's
physical range; :mod:`quadland.campaign.spec` calls them when it validates
the table, :mod:`quadland.campaign.sampling` draws. (``disp`` is a
:class:`quadland.campaign.spec.Dispersion`.)
"""

from __future__ import annotations

import math

from quadland.exceptions import ScenarioError
from quadland.schema import split_dotted

__all__ = ["U_EDGE", "NORMAL_REACH", "where", "apply_mode", "extremes", "check_finite",
           "check_reach"]

#: A point of the unit cube is kept within [U_EDGE, 1 - U_EDGE]: an inverse
#: CDF is infinite at 0 and 1. A normal draw reaches at most
#: ``-ndtri(U_EDGE) = 8.21`` standard deviations from its mean.
U_EDGE = 2.0 ** -53

#: ``-ndtri(U_EDGE)``, the most standard deviations a normal draw reaches, as SciPy's
#: ``scipy.special.ndtri`` computes it (``tests/test_campaign_start.py`` checks the bits):
#: a number here, so that checking a campaign's table does not import SciPy (about 0.2 s
#: of CPU before the workers start; the draws import it while they start).
NORMAL_REACH = 8.209536151601387


def where(key: str | None = None, param: str | None = None) -> str:
    text = "campaign" if key is None else f"campaign.dispersions.\"{key}\""
    return text + (f".{param}" if param else "")


def apply_mode(mode: str, nominal: float, x: float) -> float:
    """A key's value from its nominal and a draw ``x``, by ``mode``."""
    if mode == "offset":
        return nominal + x
    if mode == "relative":
        return nominal * (1.0 + x)
    return x


def extremes(disp) -> list[tuple[float, float]]:
    """Per dimension, the smallest and largest draw ``X`` of a numeric dispersion.

    A normal draw lies within ``ndtri(1 - U_EDGE)`` standard deviations of
    its mean (:data:`U_EDGE`); a truncated one within its bounds as well.
    """
    reach = NORMAL_REACH
    out = []
    for j in range(len(disp.low if disp.distribution == "uniform" else disp.std)):
        if disp.distribution == "uniform":
            out.append((disp.low[j], disp.high[j]))
            continue
        lo, hi = disp.mean[j] - reach * disp.std[j], disp.mean[j] + reach * disp.std[j]
        if disp.distribution == "truncnorm":
            lo, hi = max(lo, disp.low[j]), min(hi, disp.high[j])
            lo, hi = min(lo, disp.high[j]), max(hi, disp.low[j])
        out.append((lo, hi))
    return out


def check_finite(disp) -> None:
    """Refuse a dispersion some of whose draws, or the values they set, overflow."""
    reach = extremes(disp)
    for lo, hi in reach:
        width = hi - lo if disp.distribution == "uniform" else 0.0
        if not (math.isfinite(lo) and math.isfinite(hi) and math.isfinite(width)):
            param = "high" if disp.distribution == "uniform" else "std"
            raise ScenarioError(f"{where(disp.key, param)}: the draws overflow (they reach "
                                f"{lo:g} to {hi:g}); use a smaller spread")
    for target in disp.targets:
        for e, nominal in enumerate(target.nominal):
            lo, hi = reach[0 if len(reach) == 1 else e]
            for x in (lo, hi):
                value = apply_mode(disp.mode, nominal, x)
                if not math.isfinite(value):
                    at = target.key if target.scalar else f"{target.key}[{e}]"
                    raise ScenarioError(f"{where(disp.key)}: draws make {at} "
                                        f"non-finite ({disp.mode} {x:g} on {nominal:g}); "
                                        "use a smaller spread")


def check_reach(disp, schema) -> None:
    """Refuse a bounded distribution whose extreme draws leave a key's physical range."""
    for target in disp.targets:
        section, name = split_dotted(target.key)
        field = schema[section][name]
        for e, nominal in enumerate(target.nominal):
            j = 0 if len(disp.low) == 1 else e
            for x in (disp.low[j], disp.high[j]):
                if not math.isfinite(x):
                    continue
                value = apply_mode(disp.mode, nominal, x)
                complaint = field.complaint(value)
                if complaint:
                    at = target.key if target.scalar else f"{target.key}[{e}]"
                    raise ScenarioError(f"{where(disp.key)}: draws reach {at} = "
                                        f"{value:.6g}, outside its range "
                                        f"{field.range_text()}")

"""Figures of merit of a run and the limits they are held to, whatever the loop kind.

Each loop kind (:mod:`quadland.kinds`) names its metrics (:class:`Metric`,
"lower is better", an undefined one beyond any limit) and computes them from
a result; a campaign records them per run and judges them against their
limits (:func:`violations`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

__all__ = ["Metric", "violations", "settling_time"]


@dataclasses.dataclass(frozen=True)
class Metric:
    """One figure of a run.

    Attributes
    ----------
    name, unit, doc : str
    limit : str or None
        The scenario key that holds its upper limit, if any.
    counted : str or None
        For a 0/1 flag, what its 1 is called in a count ("false touchdowns"): a
        campaign's summary counts the runs where it is 1 and prints the count.
    """

    name: str
    unit: str
    doc: str
    limit: str | None = None
    counted: str | None = None


def violations(metrics: Mapping[str, float | None], limits: Mapping[str, float],
               units: Mapping[str, str] | None = None) -> list[str]:
    """Every limit a run misses, as ``"offset 0.23 > 0.2 m"`` (or ``"offset undefined"``)."""
    out = []
    for name, limit in limits.items():
        value = metrics.get(name)
        unit = "" if units is None or units.get(name, "-") == "-" else f" {units[name]}"
        if value is None:
            out.append(f"{name} undefined")
        elif not value <= limit:
            out.append(f"{name} {value:.4g} > {limit:.4g}{unit}")
    return out


def settling_time(t: np.ndarray, e: np.ndarray, band: float) -> float | None:
    """First time after which ``|e| <= band`` for the rest of the run.

    Returns 0.0 when the error starts and stays inside the band and None
    when it is outside the band at the last sample.
    """
    outside = np.flatnonzero(np.abs(e) > band)
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    if last == len(t) - 1:
        return None
    return float(t[last + 1])

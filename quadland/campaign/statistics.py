"""The statistics of a campaign: exact binomial bounds, order statistics, separation.

References
----------
C. J. Clopper and E. S. Pearson, "The use of confidence or fiducial limits
illustrated in the case of the binomial", Biometrika 26(4), 1934.

J. M. Hanson and B. B. Beard, "Applying Monte Carlo simulation to launch
vehicle design and requirements verification", J. Spacecraft and Rockets
49(1), 2012: with no failure in 299 runs, the success probability exceeds
0.99 at 95 % confidence.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["clopper_pearson", "lower_confidence_bound", "order_statistic", "separation",
           "Separation"]


def clopper_pearson(successes: int, n: int, level: float = 0.95) -> tuple[float, float]:
    """Exact two-sided confidence interval of a binomial proportion.

    Parameters
    ----------
    successes, n : int
        ``0 <= successes <= n``, ``n >= 1``.
    level : float
        Confidence level of the interval, e.g. 0.95.

    Returns
    -------
    (low, high) : tuple of float
        ``low = B(a/2; k, n - k + 1)``, ``high = B(1 - a/2; k + 1, n - k)``
        with ``B`` the beta quantile, ``a = 1 - level`` (0 and 1 at the edges).

    Examples
    --------
    >>> lo, hi = clopper_pearson(0, 10)
    >>> round(lo, 4), round(hi, 4)
    (0.0, 0.3085)
    """
    from scipy.stats import beta

    _check(successes, n, level)
    alpha = 1.0 - level
    k = successes
    low = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, n - k + 1))
    high = 1.0 if k == n else float(beta.ppf(1 - alpha / 2, k + 1, n - k))
    return low, high


def lower_confidence_bound(successes: int, n: int, level: float = 0.95) -> float:
    """Exact one-sided lower confidence bound of a binomial proportion.

    ``B(1 - level; k, n - k + 1)``: with ``k = n`` it is ``(1 - level)^(1/n)``,
    so 299 successes in 299 runs give 0.990 at 95 % (Hanson & Beard).

    Examples
    --------
    >>> round(lower_confidence_bound(299, 299), 5)
    0.99003
    """
    from scipy.stats import beta

    _check(successes, n, level)
    k = successes
    return 0.0 if k == 0 else float(beta.ppf(1.0 - level, k, n - k + 1))


def _check(k, n, level):
    if not (n >= 1 and 0 <= k <= n):
        raise ValueError(f"need 0 <= successes <= n and n >= 1, got {k} of {n}")
    if not 0 < level < 1:
        raise ValueError(f"level must be in (0, 1), got {level}")


def order_statistic(values: Sequence[float], q: float) -> float:
    """The ``q``-quantile as an order statistic: the ``ceil(q n)``-th smallest value.

    The value of a run (never an interpolation): at least a fraction ``q``
    of the runs are at or below it. ``q = 1`` gives the maximum. NumPy's
    ``percentile(..., method="inverted_cdf")`` is the same estimator.

    Examples
    --------
    >>> order_statistic([5.0, 1.0, 3.0, 2.0, 4.0], 0.5)
    3.0
    >>> order_statistic(range(1, 301), 0.99)
    297.0
    """
    x = np.sort(np.asarray(values, dtype=float))
    if x.size == 0:
        raise ValueError("no values")
    if not 0 < q <= 1:
        raise ValueError(f"q must be in (0, 1], got {q}")
    rank = max(1, math.ceil(q * x.size - 1e-9))
    return float(x[rank - 1])


class Separation(tuple):
    """``(parameter, statistic)``: the dispersed column that best separates two groups."""

    __slots__ = ()

    @property
    def parameter(self) -> str:
        """The column's name."""
        return self[0]

    @property
    def statistic(self) -> float:
        """Its two-sample Kolmogorov-Smirnov statistic, in [0, 1]."""
        return self[1]


def separation(columns: Mapping[str, np.ndarray], failed: np.ndarray) -> Separation | None:
    """The column whose values best separate the failed runs from the others.

    The two-sample Kolmogorov-Smirnov statistic ``D = max |F_failed -
    F_others|`` (the largest gap between the two empirical CDFs; 1 when a
    threshold splits them perfectly) is computed for every column that
    varies; the largest wins, the first in order on a tie.

    Returns
    -------
    Separation or None
        None without failures, without successes, or without a varying column.
    """
    failed = np.asarray(failed, dtype=bool)
    if failed.all() or not failed.any():
        return None
    best = None
    for name, values in columns.items():
        x = np.asarray(values, dtype=float)
        if np.ptp(x) == 0:
            continue
        a, b = np.sort(x[failed]), np.sort(x[~failed])
        grid = np.concatenate([a, b])
        gap = np.max(np.abs(np.searchsorted(a, grid, side="right") / a.size
                            - np.searchsorted(b, grid, side="right") / b.size))
        if best is None or gap > best[1] + 1e-12:
            best = (name, float(gap))
    return None if best is None else Separation(best)

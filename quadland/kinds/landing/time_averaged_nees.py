"""A consistency criterion that counts how correlated the normalized errors are.

The per-tick criterion (:meth:`~quadland.kinds.landing.consistency.ConsistencyResult.
nees_inside`) asks each tick's batch-average NEES to lie within the chi-square bounds of
``N`` runs at 95 % of the settled ticks. Each tick's bounds are exact, but consecutive
ticks are not independent draws: the hover's normalized errors are correlated over
seconds, so the settled window holds a few independent draws per run and the share of
ticks inside varies from batch to batch even for an exactly consistent filter
(``benchmarks/consistency_criterion_odds.py``: it meets 95 % in only 55 to 65 % of the
batches when the errors are correlated over 0.5 to 2 s).

This criterion tests the one number a consistent filter fixes: the **time-averaged
NEES** ``M = (1 / N K) sum_r sum_k eps_rk`` over ``N`` runs and ``K`` settled ticks, whose
expectation is the group's dimension ``n``. Its spread is that of ``N K_eff``
independent chi-square draws of ``n``, ``K_eff = K / tau`` the run's effective number of
independent ticks and ``tau = 1 + 2 sum_l (1 - l / K) rho(l)`` the integrated
autocorrelation time of the NEES series (in ticks), ``rho`` measured on the batch itself
(pooled over the runs, about the batch's grand mean; the sum truncated by Geyer's
initial positive sequence, 1992). Matching the mean and the variance (``Var M = 2 n /
(N K_eff)`` for a consistent filter), ``M`` is distributed as ``n chi2(nu) / nu``,
``nu = n N K_eff``: the two-sided bounds are ``n chi2.ppf((1 -+ level) / 2, nu) / nu``.

A run whose error is biased for the whole window (a run's offset, a nearly constant
state such as the pad's) shows as a correlation that never decays: ``K_eff`` falls
towards one per run and the bounds widen to those of ``N`` draws, as they should.
``benchmarks/consistency_criterion_odds.py`` validates it on a synthetic, exactly
consistent filter (and on one whose NEES is 1.5 or 0.67 times too large).
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["TimeAveragedNees", "integrated_autocorrelation", "time_averaged_nees"]


def integrated_autocorrelation(series: np.ndarray) -> float:
    """``tau = 1 + 2 sum_l (1 - l / K) rho(l)``, in samples, of ``(runs, K)`` series.

    The autocovariance is pooled over the runs about the grand mean, each lag's sum
    divided by ``runs K`` (the biased estimate, whose lag ``l`` carries the weight
    ``1 - l / K`` already); ``rho = c(l) / c(0)``. The sum runs over Geyer's initial
    positive sequence: pairs ``rho(2m) + rho(2m + 1)`` while they are positive. At least
    1 (no correlation), at most ``K`` (one draw per run).

    Examples
    --------
    >>> round(integrated_autocorrelation(np.array([[1.0, -1.0] * 50])), 6)
    1.0
    >>> integrated_autocorrelation(np.ones((3, 5)) + np.arange(3)[:, None])
    5.0
    """
    x = np.asarray(series, dtype=float)
    runs, K = x.shape
    d = x - x.mean()
    f = np.fft.rfft(d, n=2 * K, axis=1)
    acov = np.fft.irfft(np.abs(f) ** 2, n=2 * K, axis=1)[:, :K].sum(axis=0) / (runs * K)
    if not acov[0] > 0:
        return 1.0
    rho = acov / acov[0]
    pairs = np.append(rho, [0.0] * (K % 2)).reshape(-1, 2).sum(axis=1)  # rho(2m) + rho(2m+1)
    stop = np.flatnonzero(pairs <= 0)
    m = stop[0] if stop.size else len(pairs)
    tau = 2 * pairs[:m].sum() - 1                          # 1 + 2 sum_{l >= 1} rho(l)
    return float(min(max(tau, 1.0), K))


@dataclasses.dataclass(frozen=True)
class TimeAveragedNees:
    """The time-averaged NEES of a batch and its correlation-aware bounds.

    Attributes
    ----------
    mean : float
        ``M``: the NEES averaged over the runs and the settled ticks.
    dof : int
        ``n``, the group's dimension (``M``'s expectation for a consistent filter).
    runs, ticks : int
        ``N`` and ``K``.
    tau : float
        Ticks: the NEES series' integrated autocorrelation time.
    lo, hi : float
        The two-sided bounds of ``n chi2(nu) / nu``, ``nu = n N K / tau``.
    """

    mean: float
    dof: int
    runs: int
    ticks: int
    tau: float
    lo: float
    hi: float

    @property
    def effective_ticks(self) -> float:
        """``K_eff = K / tau``: independent draws per run."""
        return self.ticks / self.tau

    @property
    def inside(self) -> bool:
        """``lo <= mean <= hi``."""
        return self.lo <= self.mean <= self.hi


def time_averaged_nees(nees: np.ndarray, dof: int, level: float = 0.95) -> TimeAveragedNees:
    """The criterion on a ``(runs, ticks)`` array of one group's NEES (settled ticks).

    Raises
    ------
    ValueError
        ``nees`` is not a 2-D array of finite values with at least two ticks.
    """
    # scipy.stats takes a second to import: on first use only
    from scipy.stats import chi2

    x = np.asarray(nees, dtype=float)
    if x.ndim != 2 or x.shape[1] < 2 or not np.all(np.isfinite(x)):
        raise ValueError("time_averaged_nees: nees must be a (runs, ticks) array of "
                         "finite values, ticks >= 2")
    runs, ticks = x.shape
    tau = integrated_autocorrelation(x)
    nu = dof * runs * ticks / tau
    a = (1.0 - level) / 2
    return TimeAveragedNees(float(x.mean()), int(dof), runs, ticks, tau,
                            float(dof * chi2.ppf(a, nu) / nu),
                            float(dof * chi2.ppf(1.0 - a, nu) / nu))

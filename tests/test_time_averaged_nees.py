"""The correlation-aware NEES criterion (quadland.kinds.landing.time_averaged_nees).

Against closed forms: the integrated autocorrelation time of a first-order
autoregressive series, ``(1 + a) / (1 - a)``; the bounds of independent draws and of one
draw per run, which are the chi-square bounds of ``N K`` and ``N`` draws
(``chi2_bounds``). Then the criterion on a synthetic filter exactly as consistent as its
covariance says, its errors Gauss-Markov over 1 s as the hover's are
(benchmarks/consistency_criterion_odds.py, docs/estimator.md): accepted at the 95 % rate
within a binomial interval; rejected whenever its NEES is 1.5 or 0.67 times too large.
"""

import numpy as np
import pytest
from scipy.signal import lfilter
from scipy.stats import binom

from quadland.kinds.landing.consistency import chi2_bounds
from quadland.kinds.landing.time_averaged_nees import (
    integrated_autocorrelation,
    time_averaged_nees,
)


@pytest.mark.parametrize("a", [0.0, 0.5, 0.9, 0.98])
def test_integrated_autocorrelation_of_an_autoregressive_series(a):
    """``x_k = a x_(k-1) + w_k``: ``rho(l) = a^l``, ``tau = (1 + a) / (1 - a)`` (less
    ``2 a / ((1 - a)^2 K)`` of the window's weights, 0.2 % at most here), within four
    of the estimate's standard errors, ``tau sqrt(2 (2 M + 1) / (N K))`` summed to lag
    ``M ~ 5 tau`` (Priestley 1981, sec. 5.3; 3.2 % at ``a = 0.98``)."""
    rng = np.random.default_rng(int(100 * a))
    N, K = 200, 5000
    w = rng.standard_normal((N, K))
    w[:, 0] /= np.sqrt(1 - a ** 2)                          # stationary from the start
    x = lfilter([1.0], [1.0, -a], w, axis=1)
    want = (1 + a) / (1 - a) - 2 * a / ((1 - a) ** 2 * K)
    se = np.sqrt(2 * (2 * 5 * want + 1) / (N * K))
    assert integrated_autocorrelation(x) == pytest.approx(want, rel=4 * se)


def test_bounds_of_independent_draws_and_of_one_draw_per_run():
    """Independent ticks (tau 1): the bounds of ``N K`` chi-square draws of ``n``; a NEES
    constant over each run (tau ``K``): those of ``N`` draws."""
    rng = np.random.default_rng(3)
    N, K, n = 50, 400, 3
    white = rng.chisquare(n, (N, K))
    c = time_averaged_nees(white, n)
    assert c.tau == pytest.approx(1.0, abs=0.1)
    lo, hi = chi2_bounds(n, N * K / c.tau)
    assert (c.lo, c.hi) == pytest.approx((float(lo), float(hi)), rel=1e-12)
    assert c.mean == pytest.approx(white.mean(), rel=1e-15) and c.inside
    per_run = np.repeat(rng.chisquare(n, (N, 1)), K, axis=1)
    c = time_averaged_nees(per_run, n)
    assert c.tau == K and c.effective_ticks == 1.0
    lo, hi = chi2_bounds(n, N)
    assert (c.lo, c.hi) == pytest.approx((float(lo), float(hi)), rel=1e-12)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="time_averaged_nees"):
        time_averaged_nees(np.array([[1.0, np.nan]]), 1)
    with pytest.raises(ValueError, match="time_averaged_nees"):
        time_averaged_nees(np.ones(5), 1)


def test_a_consistent_filter_is_accepted_at_95_percent_and_a_scaled_one_never():
    """120 batches of 100 hovers, 6 errors each, Gauss-Markov of 1 s at 250 Hz over 5 s
    (each tick's NEES chi-square of 6): the share accepted lies within the binomial
    99.9 % interval of 0.95; the NEES scaled by 1.5 (overconfident) or 0.67
    (underconfident) is rejected in every batch. The per-tick criterion meets 95 % of
    the ticks in only about 60 % of such batches (docs/estimator.md)."""
    rng = np.random.default_rng(2026)
    batches, runs, dof, ticks, rho = 120, 100, 6, 1250, np.exp(-0.004 / 1.0)
    accepted = {1.0: 0, 1.5: 0, 0.67: 0}
    for _ in range(batches):
        w = rng.standard_normal((runs, dof, ticks)) * np.sqrt(1 - rho ** 2)
        w[:, :, 0] = rng.standard_normal((runs, dof))
        nees = np.sum(lfilter([1.0], [1.0, -rho], w, axis=2) ** 2, axis=1)
        for s in accepted:
            accepted[s] += time_averaged_nees(s * nees, dof).inside
    lo, hi = binom.ppf([0.0005, 0.9995], batches, 0.95)
    assert lo <= accepted[1.0] <= hi, accepted
    assert accepted[1.5] == accepted[0.67] == 0

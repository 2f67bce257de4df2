"""Campaign statistics against independent derivations.

The Clopper-Pearson bounds are checked against the binomial tail equations
that define them, solved here by root finding on ``scipy.stats.binom``
(not the beta quantiles the code uses), against closed forms at the edges
and against published figures; the order statistics against sorting and
NumPy's ``inverted_cdf`` percentile.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import binom

from quadland.campaign.statistics import (
    clopper_pearson,
    lower_confidence_bound,
    order_statistic,
    separation,
)


def _tail_bounds(k, n, alpha):
    """The interval's definition: P(X >= k | low) = alpha/2 and P(X <= k | high) = alpha/2."""
    low = 0.0 if k == 0 else brentq(lambda p: binom.sf(k - 1, n, p) - alpha / 2, 1e-15,
                                    1 - 1e-15, xtol=1e-15)
    high = 1.0 if k == n else brentq(lambda p: binom.cdf(k, n, p) - alpha / 2, 1e-15,
                                     1 - 1e-15, xtol=1e-15)
    return low, high


@pytest.mark.parametrize("k, n", [(0, 1), (1, 1), (0, 10), (3, 10), (10, 10), (5, 20),
                                  (150, 300), (297, 300), (299, 299), (1, 1000)])
def test_clopper_pearson_solves_the_binomial_tail_equations(k, n):
    lo, hi = clopper_pearson(k, n, 0.95)
    ref_lo, ref_hi = _tail_bounds(k, n, 0.05)
    assert lo == pytest.approx(ref_lo, abs=1e-10)
    assert hi == pytest.approx(ref_hi, abs=1e-10)
    assert lo <= k / n <= hi


def test_clopper_pearson_closed_forms_and_published_values():
    # Edges: k = 0 gives an upper bound 1 - (alpha/2)^(1/n); k = n a lower bound (alpha/2)^(1/n).
    for n in (1, 7, 50, 300):
        assert clopper_pearson(0, n)[1] == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-12)
        assert clopper_pearson(n, n)[0] == pytest.approx(0.025 ** (1 / n), rel=1e-12)
    # The textbook case 0 of 10: [0, 0.3085].
    assert clopper_pearson(0, 10) == (0.0, pytest.approx(0.3085, abs=5e-5))


def test_hanson_beard_299_runs_for_99_percent_at_95_percent():
    """No failure in 299 runs shows 99 % success at 95 % confidence; 298 runs do not."""
    assert lower_confidence_bound(299, 299, 0.95) == pytest.approx(0.05 ** (1 / 299), rel=1e-12)
    assert lower_confidence_bound(299, 299, 0.95) >= 0.99
    assert lower_confidence_bound(298, 298, 0.95) < 0.99
    # One failure needs 473 runs (Hanson & Beard's table): binomial tail, independently.
    n = 473
    assert binom.sf(n - 2, n, 0.99) <= 0.05 < binom.sf(n - 3, n - 1, 0.99)
    assert lower_confidence_bound(n - 1, n) >= 0.99 > lower_confidence_bound(n - 2, n - 1)


def test_one_sided_bound_is_the_tail_root():
    for k, n in ((0, 5), (12, 20), (290, 300)):
        ref = 0.0 if k == 0 else brentq(lambda p, k=k, n=n: binom.sf(k - 1, n, p) - 0.05,
                                        1e-15, 1 - 1e-15, xtol=1e-15)
        assert lower_confidence_bound(k, n) == pytest.approx(ref, abs=1e-10)


def test_bad_counts_are_refused():
    with pytest.raises(ValueError):
        clopper_pearson(3, 2)
    with pytest.raises(ValueError):
        lower_confidence_bound(0, 0)


@pytest.mark.parametrize("n", [1, 2, 7, 100, 299, 300, 1001])
def test_order_statistics_against_sorting_and_numpy(n, rng):
    x = rng.standard_normal(n)
    for q in (0.5, 0.9, 0.99, 1.0):
        got = order_statistic(x, q)
        assert got == np.sort(x)[max(1, math.ceil(q * n)) - 1]
        assert got == np.percentile(x, 100 * q, method="inverted_cdf")
        assert np.mean(x <= got) >= q - 1e-12          # at least a fraction q at or below
    assert order_statistic(x, 1.0) == x.max()


def test_separation_picks_the_threshold_parameter(rng):
    n = 400
    cause = rng.uniform(0, 1, n)
    noise = rng.uniform(0, 1, n)
    weak = cause + rng.normal(0, 0.5, n)
    failed = cause > 0.8
    sep = separation({"noise": noise, "weak": weak, "cause": cause, "constant": np.ones(n)},
                     failed)
    assert sep.parameter == "cause" and sep.statistic == pytest.approx(1.0)
    # The statistic is the two-sample KS statistic.
    from scipy.stats import ks_2samp

    got = separation({"weak": weak}, failed).statistic
    assert got == pytest.approx(ks_2samp(weak[failed], weak[~failed]).statistic)
    assert separation({"cause": cause}, np.zeros(n, bool)) is None
    assert separation({"cause": cause}, np.ones(n, bool)) is None

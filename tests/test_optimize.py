"""quadland.analysis.optimize: SciPy's three optimizers written out, checked against SciPy.

Each case runs SciPy's routine and ours on the same function and compares the points,
values and evaluation counts for equality (not within a tolerance: the port performs the
same floating-point operations in the same order). A margin review must not import
``scipy.optimize`` (0.15 s of CPU): checked in a fresh process.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import scipy.optimize

from quadland.analysis.optimize import bounded_minimum, brentq, nelder_mead

ROOT_CASES = [
    (lambda x: x ** 3 - 2 * x - 5, 2.0, 3.0),
    (lambda x: math.cos(x) - x, 0.0, 1.0),
    (lambda x: math.exp(x) - 10.0, -1.0, 5.0),
    (lambda x: math.atan(50 * (x - 0.3)), -1.0, 2.0),          # steep: bisections
    (lambda x: (x - 1.0) ** 3, 0.0, 3.0),                       # a triple root
    (lambda x: math.log(x) + 3.0, 1e-6, 1.0),
    (lambda x: x, -1.0, 0.0),                                   # f(b) = 0 exactly
    (lambda x: x - 1e-300, -1.0, 1.0),
    (lambda x: math.sin(1.0 / x), 0.2, 0.45),
]


def _counted(f):
    calls = []

    def g(x):
        calls.append(x)
        return f(x)
    return g, calls


@pytest.mark.parametrize("case", range(len(ROOT_CASES)))
@pytest.mark.parametrize("tols", [(2e-12, 4 * np.finfo(float).eps), (1e-14, 1e-12), (1e-3, 1e-6)])
def test_brentq_is_scipys(case, tols):
    f, a, b = ROOT_CASES[case]
    theirs, their_calls = _counted(f)
    ours, our_calls = _counted(f)
    try:
        expected = scipy.optimize.brentq(theirs, a, b, xtol=tols[0], rtol=tols[1])
    except RuntimeError:        # not converged in 100 iterations: ours neither
        with pytest.raises(RuntimeError, match="converge"):
            brentq(ours, a, b, xtol=tols[0], rtol=tols[1])
    else:
        assert brentq(ours, a, b, xtol=tols[0], rtol=tols[1]) == expected
    assert our_calls == their_calls


def test_brentq_refuses_what_scipy_refuses():
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1, -1.0, 1.0)
    with pytest.raises(ValueError, match="NaN"):
        brentq(lambda x: math.nan if x > 0.5 else x - 0.7, 0.0, 1.0)
    with pytest.raises(RuntimeError):
        brentq(lambda x: math.atan(x - 0.3), -1.0, 2.0, xtol=1e-14, rtol=1e-12, maxiter=3)
    with pytest.raises(RuntimeError):
        scipy.optimize.brentq(lambda x: math.atan(x - 0.3), -1.0, 2.0, xtol=1e-14,
                              rtol=1e-12, maxiter=3)


SCALAR_CASES = [
    (lambda x: (x - 0.3) ** 2, -1.0, 2.0),
    (lambda x: -math.exp(-(x - 0.7) ** 2 / 0.01), 0.0, 1.0),    # a narrow peak
    (lambda x: math.sin(3 * x) + 0.1 * x, -2.0, 2.0),
    (lambda x: abs(x - 0.123456789), -5.0, 5.0),                 # a kink
    (lambda x: x, 1.0, 2.0),                                     # at the bound
    (lambda x: -1.0 / (1.0 + 100 * (x - math.log(3.0)) ** 2), math.log(2.0), math.log(5.0)),
    (lambda x: 7.0, -1.0, 1.0),                                  # flat
]


@pytest.mark.parametrize("case", range(len(SCALAR_CASES)))
@pytest.mark.parametrize("xatol", [1e-5, 1e-8, 1e-10])
def test_bounded_minimum_is_scipys(case, xatol):
    f, lo, hi = SCALAR_CASES[case]
    theirs, their_calls = _counted(f)
    ours, our_calls = _counted(f)
    res = scipy.optimize.minimize_scalar(theirs, bounds=(lo, hi), method="bounded",
                                         options=dict(xatol=xatol))
    x, fun, nfev = bounded_minimum(ours, lo, hi, xatol=xatol)
    assert (x, fun, nfev) == (float(res.x), float(res.fun), res.nfev)
    assert our_calls == their_calls


def test_bounded_minimum_stops_at_maxiter_as_scipy():
    f = SCALAR_CASES[2][0]
    res = scipy.optimize.minimize_scalar(f, bounds=(-2.0, 2.0), method="bounded",
                                         options=dict(xatol=1e-12, maxiter=5))
    assert bounded_minimum(f, -2.0, 2.0, xatol=1e-12, maxiter=5) == (res.x, res.fun, 5)


def _rosen(x):
    return float(np.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1 - x[:-1]) ** 2))


def _largest_singular_scaled(M):
    # the objective of quadland.analysis.disk's mu bound, on a fixed matrix
    def f(x):
        d = np.exp(np.concatenate(([0.0], x)))
        S = d[:, None] * M / d[None, :]
        return math.sqrt(max(float(np.linalg.eigvalsh(S.conj().T @ S)[-1]), 0.0))
    return f


_rng = np.random.default_rng(3)
_M = _rng.normal(size=(4, 4)) + 1j * _rng.normal(size=(4, 4))

SIMPLEX_CASES = [
    (_rosen, [1.3, 0.7, 0.8, 1.9, 1.2], dict()),
    (_rosen, [-1.2, 1.0], dict(xatol=1e-8, fatol=1e-12, maxiter=4000)),
    (lambda x: float((x[0] - 2) ** 4 + (x[0] - 2 * x[1]) ** 2), [0.0, 3.0], dict()),
    (_largest_singular_scaled(_M), [0.0, 0.1, -0.2], dict(xatol=1e-8, fatol=1e-12,
                                                             maxiter=4000)),
    (lambda x: float(np.sum(np.abs(x - 0.5))), [0.0, 0.0, 0.0], dict(xatol=1e-8, fatol=1e-12,
                                                                     maxiter=4000)),
    (_rosen, [-1.2, 1.0, 0.5], dict(maxiter=30)),               # stopped by maxiter
]


@pytest.mark.parametrize("case", range(len(SIMPLEX_CASES)))
def test_nelder_mead_is_scipys(case):
    f, x0, options = SIMPLEX_CASES[case]
    theirs, their_calls = _counted(f)
    ours, our_calls = _counted(f)
    res = scipy.optimize.minimize(theirs, x0, method="Nelder-Mead", options=options)
    x, fun, nfev = nelder_mead(ours, x0, **options)
    np.testing.assert_array_equal(x, res.x)
    assert (fun, nfev) == (float(res.fun), res.nfev)
    assert len(our_calls) == len(their_calls)
    for mine, scipys in zip(our_calls, their_calls, strict=True):
        np.testing.assert_array_equal(mine, scipys)


def test_a_margin_review_does_not_import_scipy_optimize():
    code = ("import sys, quadland\n"
            "from quadland.margins import margin_report\n"
            "margin_report(quadland.load_scenario('paper'))\n"
            "print('scipy.optimize' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.split() == ["False"]

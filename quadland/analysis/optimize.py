"""The three optimizers the analysis uses, step for step as SciPy 1.17's.

``import scipy.optimize`` costs about 0.15 s of CPU (it imports ``scipy.sparse``,
``scipy.special``, ``scipy.fft``, ``scipy.spatial`` and parses 280 docstrings), a tenth
of a landing scenario's ``quadland margins``, for three small routines: Brent's root
finder (:func:`brentq`, SciPy's ``brentq``, written in C there), Brent's bounded
minimizer (:func:`bounded_minimum`, ``minimize_scalar(method="bounded")``) and the
Nelder-Mead simplex (:func:`nelder_mead`, ``minimize(method="Nelder-Mead")``). Each is
written here as SciPy computes it, the same floating-point operations in the same
order, so that they return bit for bit SciPy's points, values and evaluation counts
(``tests/test_optimize.py`` compares them on many functions); only the options the
analysis uses are kept.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["brentq", "bounded_minimum", "nelder_mead"]

#: SciPy's ``brentq`` refuses ``rtol`` below this (four machine epsilons).
_RTOL_MIN = 4 * np.finfo(float).eps

#: The golden section's step, SciPy's ``0.5 * (3.0 - sqrt(5.0))``.
_GOLDEN_MEAN = 0.5 * (3.0 - math.sqrt(5.0))


def _value(f, x: float) -> float:
    fx = float(f(x))
    if math.isnan(fx):
        raise ValueError(f"The function value at x={x:f} is NaN; solver cannot continue.")
    return fx


def brentq(f, a: float, b: float, xtol: float = 2e-12, rtol: float = 8.881784197001252e-16,
           maxiter: int = 100) -> float:
    """A root of ``f`` in ``[a, b]`` by Brent's method, as :func:`scipy.optimize.brentq`.

    Parameters
    ----------
    f : callable
        ``f(x) -> float``; ``f(a)`` and ``f(b)`` of opposite signs.
    a, b : float
        The bracket.
    xtol, rtol : float
        The root is found to within ``xtol + rtol * |x|``.
    maxiter : int
        Iterations before giving up.

    Returns
    -------
    float
        The root (SciPy's, bit for bit).

    Raises
    ------
    ValueError
        ``f(a)`` and ``f(b)`` of the same sign, a NaN value of ``f``, or a tolerance
        out of range.
    RuntimeError
        Not converged in ``maxiter`` iterations.
    """
    if xtol <= 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if rtol < _RTOL_MIN:
        raise ValueError(f"rtol too small ({rtol:g} < {_RTOL_MIN:g})")
    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre, fcur = _value(f, xpre), _value(f, xcur)
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:        # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:                   # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry     # a good short step
            else:
                spre = scur = sbis          # bisect
        else:
            spre = scur = sbis              # bisect
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _value(f, xcur)
    raise RuntimeError(f"Failed to converge after {maxiter} iterations, value is {xcur}.")


def _sign(v: float) -> float:
    """``np.sign`` of a float (NaN stays NaN)."""
    if v != v:
        return v
    return 1.0 if v > 0 else -1.0 if v < 0 else 0.0


def bounded_minimum(f, lo: float, hi: float, xatol: float = 1e-5, maxiter: int = 500
                    ) -> tuple[float, float, int]:
    """The minimum of ``f`` on ``[lo, hi]`` by Brent's bounded method, as
    ``scipy.optimize.minimize_scalar(f, bounds=(lo, hi), method="bounded")``.

    Parameters
    ----------
    f : callable
        ``f(x) -> float``.
    lo, hi : float
        Finite bounds, ``lo <= hi``.
    xatol : float
        Absolute tolerance in ``x``.
    maxiter : int
        Evaluations before stopping.

    Returns
    -------
    x, fun : float
        SciPy's ``res.x`` and ``res.fun``, bit for bit.
    nfev : int
        Evaluations of ``f``.
    """
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError("Optimization bounds must be finite scalars.")
    if lo > hi:
        raise ValueError("The lower bound exceeds the upper bound.")
    sqrt_eps = math.sqrt(2.2e-16)
    a, b = lo, hi
    fulc = a + _GOLDEN_MEAN * (b - a)
    nfc = xf = fulc
    rat = e = 0.0
    x = xf
    fx = f(x)
    num = 1
    ffulc = fnfc = fx
    xm = 0.5 * (a + b)
    tol1 = sqrt_eps * abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    while abs(xf - xm) > (tol2 - 0.5 * (b - a)):
        rat, e = _bounded_step((a, b), (xf, fx), (nfc, fnfc), (fulc, ffulc), (rat, e),
                               (xm, tol1, tol2))
        step = abs(rat)
        if not (step != step or tol1 != tol1):      # np.maximum keeps a NaN
            step = max(step, tol1)
        x = xf + (_sign(rat) + (rat == 0)) * step
        fu = f(x)
        num += 1
        if fu <= fx:
            if x >= xf:
                a = xf
            else:
                b = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                a = x
            else:
                b = x
            if fu <= fnfc or nfc == xf:
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif fu <= ffulc or fulc == xf or fulc == nfc:
                fulc, ffulc = x, fu
        xm = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        if num >= maxiter:
            break
    return float(xf), float(fx), num


def _bounded_step(bracket, best, second, third, steps, tolerances) -> tuple[float, float]:
    """The next step ``rat`` and the step before ``e`` of :func:`bounded_minimum`: a
    parabola through the three best points where it is acceptable, else a golden section
    (SciPy's loop body)."""
    (a, b), (xf, fx), (nfc, fnfc), (fulc, ffulc) = bracket, best, second, third
    (rat, e), (xm, tol1, tol2) = steps, tolerances
    golden = True
    if abs(e) > tol1:           # a parabolic fit?
        golden = False
        r = (xf - nfc) * (fx - ffulc)
        q = (xf - fulc) * (fx - fnfc)
        p = (xf - fulc) * q - (xf - nfc) * r
        q = 2.0 * (q - r)
        if q > 0.0:
            p = -p
        q = abs(q)
        r = e
        e = rat
        if abs(p) < abs(0.5 * q * r) and p > q * (a - xf) and p < q * (b - xf):
            rat = (p + 0.0) / q
            x = xf + rat
            if (x - a) < tol2 or (b - x) < tol2:
                rat = tol1 * (_sign(xm - xf) + ((xm - xf) == 0))
        else:
            golden = True
    if golden:                  # a golden-section step
        e = a - xf if xf >= xm else b - xf
        rat = _GOLDEN_MEAN * e
    return rat, e


def nelder_mead(f, x0, xatol: float = 1e-4, fatol: float = 1e-4, maxiter: int | None = None
                ) -> tuple[np.ndarray, float, int]:
    """A local minimum of ``f`` by the Nelder-Mead simplex, as
    ``scipy.optimize.minimize(f, x0, method="Nelder-Mead", options=dict(xatol=xatol,
    fatol=fatol, maxiter=maxiter))`` (no bounds, not adaptive).

    Parameters
    ----------
    f : callable
        ``f(x) -> float`` of a 1-D float array (a copy: ``f`` may keep it).
    x0 : array_like
        The start; its first simplex is SciPy's (each coordinate moved by 5 %, or
        to 0.00025 where it is 0).
    xatol, fatol : float
        Stop when the simplex is within ``xatol`` of its best vertex in every
        coordinate and its values within ``fatol`` of the best.
    maxiter : int, optional
        Iterations (``200 n`` if None; the evaluations are then limited to ``200 n``
        too, as SciPy's).

    Returns
    -------
    x : ndarray
    fun : float
        SciPy's ``res.x`` and ``res.fun``, bit for bit.
    nfev : int
        Evaluations of ``f``.
    """
    x0 = np.atleast_1d(np.asarray(x0)).flatten()
    x0 = np.asarray(x0, dtype=x0.dtype if np.issubdtype(x0.dtype, np.inexact) else np.float64)
    n = len(x0)
    rho, chi, psi, sigma = 1, 2, 0.5, 0.5
    sim = np.empty((n + 1, n), dtype=x0.dtype)
    sim[0] = x0
    for k in range(n):
        y = np.array(x0, copy=True)
        y[k] = (1 + 0.05) * y[k] if y[k] != 0 else 0.00025
        sim[k + 1] = y
    maxfun = n * 200 if maxiter is None else math.inf
    maxiter = n * 200 if maxiter is None else maxiter
    calls = [0]

    def func(x):
        if calls[0] >= maxfun:
            raise _TooManyCalls
        calls[0] += 1
        return f(np.copy(x))

    fsim = np.full((n + 1,), np.inf, dtype=float)
    try:
        for k in range(n + 1):
            fsim[k] = func(sim[k])
    except _TooManyCalls:
        pass
    finally:
        ind = np.argsort(fsim)
        sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    ind = np.argsort(fsim)
    fsim, sim = np.take(fsim, ind, 0), np.take(sim, ind, 0)
    iterations = 1
    while calls[0] < maxfun and iterations < maxiter:
        try:
            if (np.max(np.ravel(np.abs(sim[1:] - sim[0]))) <= xatol
                    and np.max(np.abs(fsim[0] - fsim[1:])) <= fatol):
                break
            _simplex_step(sim, fsim, func, n, (rho, chi, psi, sigma))
            iterations += 1
        except _TooManyCalls:
            pass
        ind = np.argsort(fsim)
        sim, fsim = np.take(sim, ind, 0), np.take(fsim, ind, 0)
    return sim[0], float(np.min(fsim)), calls[0]


class _TooManyCalls(Exception):
    pass


def _simplex_step(sim, fsim, func, n: int, coefficients) -> None:
    """One Nelder-Mead step on the sorted simplex, in place (SciPy's loop body)."""
    rho, chi, psi, sigma = coefficients
    xbar = np.add.reduce(sim[:-1], 0) / n
    xr = (1 + rho) * xbar - rho * sim[-1]
    fxr = func(xr)
    if fxr < fsim[0]:
        xe = (1 + rho * chi) * xbar - rho * chi * sim[-1]
        fxe = func(xe)
        if fxe < fxr:
            sim[-1], fsim[-1] = xe, fxe
        else:
            sim[-1], fsim[-1] = xr, fxr
        return
    if fxr < fsim[-2]:
        sim[-1], fsim[-1] = xr, fxr
        return
    if fxr < fsim[-1]:          # contraction
        xc = (1 + psi * rho) * xbar - psi * rho * sim[-1]
        fxc = func(xc)
        if fxc <= fxr:
            sim[-1], fsim[-1] = xc, fxc
            return
    else:                       # inside contraction
        xcc = (1 - psi) * xbar + psi * sim[-1]
        fxcc = func(xcc)
        if fxcc < fsim[-1]:
            sim[-1], fsim[-1] = xcc, fxcc
            return
    for j in range(1, n + 1):   # shrink
        sim[j] = sim[0] + sigma * (sim[j] - sim[0])
        fsim[j] = func(sim[j])

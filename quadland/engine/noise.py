"""Noise processes sampled exactly at given times.

Gauss-Markov (first-order, stationary start), its exact conditional fill
between known samples, random walk, and the sample clock. The sensors
(:mod:`quadland.kinds.landing.sensing`) draw their noise with these; each takes its
standard normal draws as an argument, so the caller owns the random stream.
"""

from __future__ import annotations

import numpy as np

from quadland.engine.loop import Clock
from quadland.engine.recursion import recursion

__all__ = ["sample_times", "gauss_markov", "gauss_markov_fill", "random_walk",
           "gauss_markov_after", "bridge"]


def sample_times(rate_hz: float, duration: float, phase: float = 0.0) -> np.ndarray:
    """A sensor's sample times, s: the loop's clock rule (:class:`quadland.engine.loop.Clock`).

    ``phase + k / rate_hz`` below ``duration``, as the control clock ticks (no
    sample at the final time itself), so that a sensor sampled with the
    control step reads the same instant, to the bit.

    Examples
    --------
    >>> sample_times(4.0, 1.0).tolist()
    [0.0, 0.25, 0.5, 0.75]
    >>> sample_times(4.0, 1.1, phase=0.1).tolist()
    [0.1, 0.35, 0.6, 0.85]
    """
    return Clock(rate_hz, phase, duration, closing=False).times()


def _columns(v, m: int) -> np.ndarray:
    """``v`` as ``m`` doubles (a view where it already is; broadcast otherwise)."""
    v = np.asarray(v, dtype=float)
    return v if v.shape == (m,) else np.broadcast_to(v, (m,))


def _decay(dt, tau):
    """``exp(-dt / tau)``: 1 for ``tau = inf``, 0 for ``tau = 0``."""
    tau, dt = np.asarray(tau, dtype=float), np.asarray(dt, dtype=float)
    positive = tau > 0
    if np.all(positive):                 # (NumPy's `where` broadcast is slow: only if needed)
        r = dt / tau
    else:
        r = np.where(positive, dt / np.where(positive, tau, 1.0), np.inf)
    return np.exp(-(r if np.all(dt > 0) else np.where(dt > 0, r, 0.0)))


def gauss_markov(times, sigma, tau, normals) -> np.ndarray:
    """A first-order Gauss-Markov process at ``times``, exactly.

    ``x_0 = sigma n_0`` (stationary), ``x_(k+1) = a_k x_k + sigma sqrt(1 -
    a_k^2) n_(k+1)``, ``a_k = exp(-(t_(k+1) - t_k) / tau)``: the exact
    discretization of ``dx = -x / tau dt + sigma sqrt(2 / tau) dW``.

    Parameters
    ----------
    times : array_like, shape (n,)
        Non-decreasing, s.
    sigma, tau : array_like, shape (m,)
        Stationary standard deviation and time constant of each column
        (``tau = inf``: a random constant; ``tau = 0``: white noise).
    normals : array_like, shape (n, m)
        Standard normal draws.

    Returns
    -------
    numpy.ndarray, shape (n, m)
    """
    normals = np.asarray(normals, dtype=float)
    n, m = normals.shape
    sigma, tau = _columns(sigma, m), _columns(tau, m)
    x = np.empty((n, m))
    if n == 0:
        return x
    a = _decay(np.diff(np.asarray(times, dtype=float))[:, None], tau[None, :])
    b = sigma * np.sqrt(np.maximum(1.0 - a * a, 0.0))     # (clip's values, one ufunc)
    x[0] = sigma * normals[0]
    compiled = recursion(x[0], a, b, normals)      # the same products and sums, in C
    if compiled is not None:
        return compiled
    # column by column over Python floats: the same two products and one sum per sample
    # as the rows of NumPy's arrays, bit for bit, four times faster (issue 20)
    for j, (aj, bj, nj) in enumerate(zip(a.T.tolist(), b.T.tolist(),
                                         normals[1:].T.tolist(), strict=True)):
        u, col = float(x[0, j]), [float(x[0, j])]
        for ak, bk, nk in zip(aj, bj, nj, strict=True):
            u = ak * u + bk * nk
            col.append(u)
        x[:, j] = col
    return x


def gauss_markov_after(times, sigma, tau, normals, t_prev=None, x_prev=None) -> np.ndarray:
    """:func:`gauss_markov` at ``times``, continued from its value ``x_prev`` at ``t_prev``.

    Without ``x_prev`` the process starts stationary at ``times[0]`` (as
    :func:`gauss_markov`); with it, ``normals[0]`` drives the step from ``t_prev``.
    The same products and sums per step: a process computed in pieces, each
    continued from the last, is the one computed at once, bit for bit.
    """
    if x_prev is None:
        return gauss_markov(times, sigma, tau, normals)
    normals = np.asarray(normals, dtype=float)
    n, m = normals.shape
    sigma, tau = _columns(sigma, m), _columns(tau, m)
    if n == 0:
        return np.empty((0, m))
    t = np.concatenate([[float(t_prev)], np.asarray(times, dtype=float)])
    a = _decay(np.diff(t)[:, None], tau[None, :])
    b = sigma * np.sqrt(np.maximum(1.0 - a * a, 0.0))     # (clip's values, one ufunc)
    rows = np.empty((n + 1, m))                          # (row 0 is never read)
    rows[1:] = normals
    x = recursion(np.asarray(x_prev, dtype=float), a, b, rows)
    if x is None:
        x = np.empty((n + 1, m))
        x[0] = x_prev
        for k in range(n):
            x[k + 1] = a[k] * x[k] + b[k] * rows[k + 1]
    return x[1:]


def bridge(t, left, right, sigma, tau, normal) -> np.ndarray:
    """A Gauss-Markov process's value at ``t`` drawn given its nearest known values.

    ``left`` is ``(t_a, x_a)`` before ``t`` (None: nothing before, the stationary law),
    ``right`` ``(t_b, x_b)`` after it (None: nothing after); the exact conditional
    distribution (the process is Markov), driven by the standard normal ``normal``.
    """
    sigma = np.asarray(sigma, dtype=float)
    var = sigma ** 2
    m = var.shape[0]
    if left is None:
        mean, P = np.zeros(m), var
    else:
        a1 = _decay(t - left[0], tau)
        mean, P = a1 * left[1], var * (1.0 - a1 * a1)
    cvar = P
    if right is not None:
        a2 = _decay(right[0] - t, tau)
        R = var * (1.0 - a2 * a2)
        den = a2 * a2 * P + R
        ok = den > 0
        K = np.where(ok, P * a2 / np.where(ok, den, 1.0), 0.0)
        mean = mean + K * (right[1] - a2 * mean)
        cvar = np.where(ok, P * R / np.where(ok, den, 1.0), 0.0)
    return mean + np.sqrt(np.clip(cvar, 0.0, None)) * normal


def gauss_markov_fill(known_t, known_x, new_t, sigma, tau, normals) -> np.ndarray:
    """A Gauss-Markov process at new times, given known values.

    The same process at ``new_t``, given its values at ``known_t``.

    Each new value is drawn from its exact conditional distribution given
    its nearest known neighbours (the process is Markov), the new points
    in time order, each joining the known ones: the result is one
    realization of the process on the union of the times.

    Parameters
    ----------
    known_t : array_like, shape (n,)
        Increasing, s.
    known_x : array_like, shape (n, m)
    new_t : array_like, shape (p,)
        Increasing, none equal to a ``known_t``, s.
    sigma, tau : array_like, shape (m,)
    normals : array_like, shape (p, m)
        Standard normal draws.
    """
    known_t = np.asarray(known_t, dtype=float)
    known_x = np.asarray(known_x, dtype=float)
    normals = np.asarray(normals, dtype=float)
    m = normals.shape[1]
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (m,))
    var = sigma ** 2
    out = np.empty((len(new_t), m))
    last_t, last_x = -np.inf, None
    for i, t in enumerate(np.asarray(new_t, dtype=float)):
        j = int(np.searchsorted(known_t, t))
        if j > 0 and known_t[j - 1] > last_t:
            ta, xa = known_t[j - 1], known_x[j - 1]
        else:
            ta, xa = last_t, last_x
        has_right = j < len(known_t)
        if xa is None:                       # nothing before: the stationary law
            ta, xa = -np.inf, np.zeros(m)
        a1 = _decay(t - ta, tau) if np.isfinite(ta) else np.zeros(m)
        P = var * (1.0 - a1 * a1)            # from the left neighbour
        mean, cvar = a1 * xa, P
        if has_right:
            a2 = _decay(known_t[j] - t, tau)
            R = var * (1.0 - a2 * a2)
            den = a2 * a2 * P + R
            ok = den > 0
            K = np.where(ok, P * a2 / np.where(ok, den, 1.0), 0.0)
            mean = mean + K * (known_x[j] - a2 * mean)
            cvar = np.where(ok, P * R / np.where(ok, den, 1.0), 0.0)
        out[i] = mean + np.sqrt(np.clip(cvar, 0.0, None)) * normals[i]
        last_t, last_x = t, out[i]
    return out


def random_walk(times, start, density, normals) -> np.ndarray:
    """A random walk at ``times`` from ``start``.

    ``b_0 = start``, ``b_(k+1) = b_k + density sqrt(t_(k+1) - t_k) n_(k+1)``.

    ``start`` and ``density`` per column; ``normals`` shape ``(n, m)`` (the
    first row is unused).
    """
    normals = np.asarray(normals, dtype=float)
    steps = np.zeros_like(normals)
    if len(normals) > 1:
        dt = np.diff(np.asarray(times, dtype=float))[:, None]
        steps[1:] = np.asarray(density, dtype=float) * np.sqrt(dt) * normals[1:]
    return np.asarray(start, dtype=float) + np.cumsum(steps, axis=0)

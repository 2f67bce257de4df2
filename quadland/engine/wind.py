"""Wind for landing scenarios: Dryden turbulence and discrete 1-cosine gusts.

The wind is a velocity in the Earth frame E, sampled on the disturbance's
hold grid; the landing plant turns it into a force through the rotor drag.
Two parts add up:

* **Dryden turbulence** (MIL-F-8785C, low altitude). Each axis is a
  first-order Gauss-Markov (Ornstein-Uhlenbeck) process with the Dryden
  longitudinal spectrum ``Phi(w) = sigma^2 (2 L / (pi V)) / (1 + (L w /
  V)^2)``, discretized exactly on the sample grid:
  ``u_{k+1} = a u_k + sigma sqrt(1 - a^2) n_k`` with ``a = exp(-V dt / L)``
  and ``n_k`` standard normal, started in its stationary distribution. The
  standard gives the lateral and vertical axes a second-order spectrum; the
  first-order one is kept for all three (the same variance and scale, a
  slower roll-off above ``V / L``), which is what a quadrotor near hover,
  with a bandwidth well below ``V / L``, sees alike.
* **1-cosine gusts** (MIL-F-8785C's discrete gust):
  ``v(t) = v_m / 2 (1 - cos(pi (t - t0) / d))`` for ``t0 <= t <= t0 + 2 d``,
  zero outside, along a given direction.

The draws come from the caller's seeded generator, so a run is repeated by
its seed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from quadland.engine.recursion import recursion

__all__ = ["FT", "DrydenTurbulence", "OneCosineGust", "dryden_low_altitude",
           "turbulence_samples", "gust_samples"]

#: One foot, m: MIL-F-8785C states its low-altitude scales in feet.
FT = 0.3048


@dataclasses.dataclass(frozen=True)
class DrydenTurbulence:
    """Intensities and scale lengths of the three axes (E: x, y horizontal, z up).

    Attributes
    ----------
    sigma : tuple of float
        Standard deviations, m/s.
    scale : tuple of float
        Scale lengths L, m.
    airspeed : float
        V, m/s: how fast the frozen turbulence field is crossed.
    """

    sigma: tuple[float, float, float]
    scale: tuple[float, float, float]
    airspeed: float


def dryden_low_altitude(w20: float, height: float, airspeed: float) -> DrydenTurbulence:
    """MIL-F-8785C's low-altitude intensities and scales (below 1000 ft).

    ``sigma_w = 0.1 W20``, ``sigma_u / sigma_w = 1 / (0.177 + 0.000823 h)^0.4``,
    ``L_w = h``, ``L_u = L_v = h / (0.177 + 0.000823 h)^1.2`` with ``h`` in
    feet (the standard's own units; converted here).

    Parameters
    ----------
    w20 : float
        Wind speed at 20 ft, m/s (light turbulence: 7.7 m/s = 15 kt).
    height : float
        Altitude above ground, m (at least 10 ft is used).
    airspeed : float
        m/s, at least 0.1.

    Examples
    --------
    >>> d = dryden_low_altitude(7.7, 10.0, 14.0)
    >>> round(d.sigma[2], 3), round(d.scale[2], 2)
    (0.77, 10.0)
    """
    h_ft = max(height / FT, 10.0)
    ratio = 1.0 / (0.177 + 0.000823 * h_ft) ** 0.4
    sigma_w = 0.1 * w20
    L_uv = h_ft / (0.177 + 0.000823 * h_ft) ** 1.2 * FT
    return DrydenTurbulence((sigma_w * ratio, sigma_w * ratio, sigma_w),
                            (L_uv, L_uv, h_ft * FT), max(airspeed, 0.1))


def turbulence_samples(turbulence: DrydenTurbulence, times: np.ndarray,
                       rng: np.random.Generator | None = None,
                       normals: np.ndarray | None = None) -> np.ndarray:
    """Turbulence velocity at ``times`` (evenly spaced), shape ``(3, len(times))``, m/s.

    The draws are ``rng.standard_normal((len(times), 3))``, or ``normals``, those
    draws made before (an envelope keeps a replicate's: they depend on its seed and the
    sample count alone, the filter on the airspeed and so on the cell). The three axes'
    recursions run in one call of the compiled recursion, column by column, the same
    products and sums as :func:`first_order_recursion` of each.
    """
    times = np.asarray(times, dtype=float)
    n = len(times)
    if normals is None:
        normals = rng.standard_normal((n, 3))
    elif np.shape(normals) != (n, 3):               # kept draws of another sample count
        raise ValueError(f"normals of shape {np.shape(normals)} for {n} times")
    if n == 0:
        return np.zeros((3, 0))
    draws = normals.T
    dt = times[1] - times[0] if n > 1 else 0.0
    a, b, u0 = np.zeros(3), np.zeros(3), np.zeros(3)
    for axis in range(3):
        sigma, L = turbulence.sigma[axis], turbulence.scale[axis]
        if sigma == 0:
            continue
        a_axis = math.exp(-turbulence.airspeed * dt / L)
        a[axis], b[axis] = a_axis, sigma * math.sqrt(1.0 - a_axis * a_axis)
        u0[axis] = sigma * draws[axis, 0]               # the stationary distribution
    still = [axis for axis in range(3) if turbulence.sigma[axis] == 0]
    compiled = recursion(u0, np.full((n - 1, 3), a), np.full((n - 1, 3), b), normals)
    if compiled is not None:                            # (n, 3): the axes as its columns
        compiled[:, still] = 0.0
        return compiled.T
    out = np.zeros((3, n))
    for axis in set(range(3)) - set(still):
        out[axis, 0] = u0[axis]
        out[axis, 1:] = first_order_recursion(float(a[axis]), float(b[axis]), draws[axis, 1:],
                                              float(u0[axis]))
    return out


def first_order_recursion(a: float, b: float, x: np.ndarray, u0: float) -> np.ndarray:
    """``u_k = b x_k + a u_(k-1)`` for ``k = 1..len(x)`` from ``u_0 = u0``.

    The same two products and one sum per sample, in the same order, as
    ``scipy.signal.lfilter([b], [1, -a], x, zi=[a u0])``: equal bit for bit
    (tests/test_wind.py), without importing ``scipy.signal`` (most of a second
    of every landing process's start, issue 20). In C
    (:func:`quadland.engine.recursion.recursion`: the same products, and the sum's
    operands in the other order: IEEE addition commutes); without a compiler a loop over
    Python floats, about 0.1 us a sample, 1.2 ms for the 40 s of three axes at 100 Hz.
    """
    x = np.asarray(x, dtype=float)
    n = len(x)
    compiled = recursion(np.array([u0]), np.full((n, 1), a), np.full((n, 1), b),
                         np.concatenate([[0.0], x])[:, None])
    if compiled is not None:
        return compiled[1:, 0]
    out = np.empty(n)
    u = u0
    for k, xk in enumerate(x.tolist()):
        u = b * xk + a * u
        out[k] = u
    return out


@dataclasses.dataclass(frozen=True)
class OneCosineGust:
    """A discrete 1-cosine gust.

    Attributes
    ----------
    start : float
        t0, s.
    half_length : float
        d, s: the gust builds up over ``d`` and dies down over the next ``d``.
    amplitude : float
        v_m, m/s, reached at ``t0 + d``.
    direction : tuple of float
        Unit vector in E (normalized here).
    """

    start: float
    half_length: float
    amplitude: float
    direction: tuple[float, float, float]


def gust_samples(gust: OneCosineGust, times: np.ndarray) -> np.ndarray:
    """The gust's velocity at ``times``, shape ``(3, len(times))``, m/s.

    Examples
    --------
    >>> g = OneCosineGust(1.0, 0.5, 4.0, (1.0, 0.0, 0.0))
    >>> gust_samples(g, np.array([0.0, 1.25, 1.5, 2.0]))[0].round(6).tolist()
    [0.0, 2.0, 4.0, 0.0]
    """
    times = np.asarray(times, dtype=float)
    e = np.asarray(gust.direction, dtype=float)
    e = e / np.linalg.norm(e) if np.linalg.norm(e) > 0 else e
    s = (times - gust.start) / gust.half_length
    inside = (s >= 0) & (s <= 2)
    v = np.where(inside, gust.amplitude / 2 * (1 - np.cos(np.pi * np.clip(s, 0, 2))), 0.0)
    return e[:, None] * v[None, :]

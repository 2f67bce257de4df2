"""Sensitivity peaks (Ms, Mt) and the delay margin of a group of channels.

Both work on the state space through :class:`~quadland.analysis.response.FrequencyResponse`,
like the rest of :mod:`quadland.analysis`. ``L`` is a square loop in the
negative-feedback convention (closed as ``u = -L u``), ``S = (I + L)^-1`` and
``T = I - S = L (I + L)^-1``.

* :func:`sensitivity_peaks`: per channel, with the other loops closed, the
  SISO loop ``l_i = 1 / S_ii - 1`` has sensitivity ``1 / (1 + l_i) = S_ii``
  and complementary sensitivity ``1 - S_ii``; their peaks over frequency are
  the loop's Ms and Mt. Multiloop: the peaks of ``sigma_max(S)`` and
  ``sigma_max(T)`` (the H-infinity norms of S and T).
* :func:`group_delay_margin`: the smallest delay ``tau``, common to a group
  of channels (a sensor's outputs), that destabilizes the loop, the other
  channels on time. With ``L`` partitioned into the group ``g`` and the rest
  ``r``, ``det(I + D L) = det(I + L_rr) det(I + e^(-j w tau) L_g)`` for ``D =
  diag(e^(-j w tau) I, I)``, where ``L_g = [(I + L)^-1]_gg^-1 - I`` is the loop
  seen at the group with the rest closed. A closed-loop pole reaches the
  imaginary axis first where an eigenvalue ``lambda`` of ``L_g(j w)`` has
  ``|lambda| = 1`` and the delay has turned it onto -1: ``tau = mod(180 + arg
  lambda, 360) / w``. For one channel that is the classical delay margin of
  :func:`quadland.analysis.allmargin`.

  ``(I + L)^-1`` is formed in double precision: where the return difference's
  condition number exceeds :data:`RESOLVABLE_CONDITION` (integral action makes
  it grow as ``1/w`` or faster toward zero frequency: 1e21 at 3e-5 rad/s on
  ``highway``), the eigenvalues' moduli carry errors of order one and their
  "crossings" are rounding noise, dozens of them at 1e-6 to 1e-4 rad/s with
  any phase at all. Such crossings are dropped (:attr:`GroupDelayMargin.unresolved`
  counts them).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.optimize

from quadland.analysis.response import (
    FrequencyResponse,
    closed_loop_poles,
    closed_loop_stable,
    frequency_grid,
    response_of,
    square_loop,
)

__all__ = ["Peak", "SensitivityPeaks", "GroupDelayMargin", "sensitivity_peaks",
           "group_delay_margin"]


@dataclasses.dataclass(frozen=True)
class Peak:
    """The largest value of a gain over frequency.

    Attributes
    ----------
    value : float
        The peak, a ratio (``inf`` for an unstable closed loop).
    frequency : float or None
        rad/s, where it is attained; ``inf`` for a supremum approached as the
        frequency grows (a continuous loop's ``|S| -> 1``); None for an
        unstable closed loop.
    """

    value: float
    frequency: float | None

    @property
    def db(self) -> float:
        """The peak in dB."""
        return 20.0 * math.log10(self.value) if self.value > 0 else -math.inf


@dataclasses.dataclass(frozen=True)
class SensitivityPeaks:
    """Peaks of the sensitivity and complementary sensitivity of a loop.

    Attributes
    ----------
    ms : Peak
        ``max_w |S(j w)|`` (SISO) or ``max_w sigma_max(S(j w))`` (multiloop).
    mt : Peak
        The same of ``T = I - S``.
    """

    ms: Peak
    mt: Peak


@dataclasses.dataclass(frozen=True)
class GroupDelayMargin:
    """Delay margin of a group of channels, the other channels on time.

    Attributes
    ----------
    channels : tuple of int
        The group's channels (indices of ``L``'s inputs and outputs).
    delay_margin : float
        s, the smallest destabilizing common delay; ``inf`` if no eigenvalue
        of the group's loop reaches unit magnitude (0 for an unstable loop).
    frequency : float or None
        rad/s, the crossing of that delay margin.
    phase_margin : float
        deg, ``180 + arg lambda`` at that crossing, in (-180, 180]
        (``inf`` without a crossing).
    crossings : tuple of tuple of float
        Every resolved unit-magnitude crossing of an eigenvalue: ``(frequency
        rad/s, phase margin deg, delay s)``.
    stable : bool
        Whether the loop, all channels closed and on time, is stable.
    unresolved : int
        Sign changes dropped because the return difference ``I + L`` was too
        ill-conditioned there to resolve ``|lambda| = 1`` (module notes).
    """

    channels: tuple[int, ...]
    delay_margin: float
    frequency: float | None
    phase_margin: float
    crossings: tuple[tuple[float, float, float], ...]
    stable: bool
    unresolved: int = 0

    def delay_to(self, phase_margin_deg: float) -> float:
        """s, the common delay that leaves ``phase_margin_deg`` at the tightest crossing.

        ``min_k (mod(PM_k, 360) - phase_margin_deg) / w_k`` (radians over
        rad/s); negative where a crossing already has less; ``inf`` without
        a crossing, 0 for an unstable loop.
        """
        if not self.stable:
            return 0.0
        if not self.crossings:
            return math.inf
        return min(math.radians(pm % 360.0 - phase_margin_deg) / w
                   for w, pm, _ in self.crossings)


#: The largest condition number of ``I + L(jw)`` at which :func:`group_delay_margin`
#: trusts a unit-modulus crossing: ``1e-3 / eps``, so that the inverse's relative
#: error bound ``cond * eps`` stays at or below 1e-3 (Golub and Van Loan, Matrix
#: Computations, 4th ed., sec. 2.6).
RESOLVABLE_CONDITION = 1e-3 / np.finfo(float).eps


def _refined_max(fun, grid, values) -> tuple[float, float]:
    """``(max, argmax)`` of ``fun`` near the largest of ``values`` (= fun(grid))."""
    k = int(np.argmax(values))
    best_w, best = float(grid[k]), float(values[k])
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    if b > a > 0:
        res = scipy.optimize.minimize_scalar(lambda lw: -fun(math.exp(lw)),
                                             bounds=(math.log(a), math.log(b)),
                                             method="bounded", options=dict(xatol=1e-10))
        if -res.fun > best:
            best_w, best = float(math.exp(res.x)), float(-res.fun)
    return best, best_w


def _peak(fun, grid, values, continuous: bool) -> Peak:
    """The refined peak of ``fun`` over the grid and zero frequency.

    A continuous loop's value still growing at the top of the grid (which
    reaches past its dynamics) is the supremum approached as ``w -> inf``:
    reported at frequency ``inf``, with the value there (``|S| -> 1`` for a
    strictly proper loop). One largest at the bottom of the grid is compared
    with the value at zero frequency, or with its limit (evaluated six decades
    lower) where the loop has a pole at zero.
    """
    best, w = _refined_max(fun, grid, values)
    if continuous and w == grid[-1]:
        best, w = max(best, float(fun(1e6 * grid[-1]))), math.inf
    with np.errstate(all="ignore"):
        try:
            # at a pole at zero (an integrator) G(0) is not defined: its limit instead
            at0 = float(fun(0.0 if w > grid[0] else 1e-6 * grid[0]))
        except (np.linalg.LinAlgError, ValueError, ZeroDivisionError):
            at0 = math.nan
    if math.isfinite(at0) and at0 > best:
        best, w = at0, 0.0
    return Peak(best, w)


def _grid(L, omega):
    resp = response_of(L)
    poles = closed_loop_poles(L)
    stable = closed_loop_stable(L, poles)
    grid = (frequency_grid(resp, extra_poles=poles) if omega is None
            else np.asarray(omega, dtype=float))
    return resp, grid, stable


def sensitivity_peaks(L, omega=None) -> tuple[list[SensitivityPeaks], SensitivityPeaks]:
    """Ms and Mt per channel (the others closed) and multiloop, with their frequencies.

    Parameters
    ----------
    L : control.StateSpace or control.TransferFunction
        Square loop transfer (negative feedback, ``u = -L u``), continuous
        or sampled.
    omega : array_like, optional
        Search grid, rad/s (default: :func:`frequency_grid`, to the Nyquist
        frequency of a sampled loop); the largest grid value is refined
        between its neighbours, and zero frequency is checked too.

    Returns
    -------
    per_loop : list of SensitivityPeaks
        Channel ``i``: ``max_w |S_ii|`` and ``max_w |1 - S_ii|``.
    multiloop : SensitivityPeaks
        ``max_w sigma_max(S)`` and ``max_w sigma_max(I - S)``.

    Notes
    -----
    An unstable closed loop has unbounded S and T (infinite H-infinity
    norms): every peak is ``inf`` with frequency None. ``1 / Ms`` is the
    smallest distance of the Nyquist curve of a SISO loop to -1, so the loop
    tolerates any gain in ``[Ms / (Ms + 1), Ms / (Ms - 1)]`` and a phase of
    ``2 asin(1 / (2 Ms))``.

    Examples
    --------
    >>> import control
    >>> (p,), _ = sensitivity_peaks(control.tf([3], [1, -2]))   # S = (s - 2)/(s + 1)
    >>> round(p.ms.value, 12), p.ms.frequency, round(p.mt.value, 12)
    (2.0, 0.0, 3.0)
    """
    L = square_loop(L, "sensitivity_peaks")
    m = L.ninputs
    resp, grid, stable = _grid(L, omega)
    if not stable:
        inf = Peak(math.inf, None)
        return [SensitivityPeaks(inf, inf)] * m, SensitivityPeaks(inf, inf)
    eye, continuous = np.eye(m), not resp.dt

    def S_at(w):
        return np.linalg.inv(eye + resp.at(resp.point(w)))

    S = np.linalg.inv(eye + resp(grid))
    per_loop = []
    for i in range(m):
        s_ii = S[:, i, i]
        per_loop.append(SensitivityPeaks(
            _peak(lambda w, i=i: abs(S_at(w)[i, i]), grid, np.abs(s_ii), continuous),
            _peak(lambda w, i=i: abs(1.0 - S_at(w)[i, i]), grid, np.abs(1.0 - s_ii),
                  continuous)))
    sv_S = np.linalg.norm(S, ord=2, axis=(-2, -1))
    sv_T = np.linalg.norm(eye - S, ord=2, axis=(-2, -1))
    multi = SensitivityPeaks(
        _peak(lambda w: np.linalg.norm(S_at(w), 2), grid, sv_S, continuous),
        _peak(lambda w: np.linalg.norm(eye - S_at(w), 2), grid, sv_T, continuous))
    return per_loop, multi


def _wrap180(deg: float) -> float:
    d = (deg + 180.0) % 360.0 - 180.0
    return 180.0 if d == -180.0 else d


def _unit_crossings(resp: FrequencyResponse, grid: np.ndarray, g: list[int], n: int
                    ) -> tuple[list[tuple[float, float, float]], int]:
    """Each resolved unit-modulus crossing of an eigenvalue of ``L_g`` on ``grid``, refined,
    as ``(w, phase margin deg, delay s)``, and how many sign changes were unresolved."""
    eye = np.eye(n)
    idx = np.ix_(g, g)

    def resolved(w):
        return np.linalg.cond(eye + resp.at(resp.point(w))) <= RESOLVABLE_CONDITION

    def eigs(G):
        S_g = np.linalg.inv(eye + G)[..., idx[0], idx[1]]
        return np.linalg.eigvals(np.linalg.inv(S_g) - np.eye(len(g)))

    def log_moduli(w):
        """Sorted ``log |lambda|`` at ``w``; NaN where ``L_g`` is not defined (a pole)."""
        try:
            lam = eigs(resp.at(resp.point(w)))
        except np.linalg.LinAlgError:
            return np.full(len(g), np.nan)
        return np.sort(np.log(np.maximum(np.abs(lam), 1e-300)))

    grid = grid[grid > 0]
    try:
        values = np.sort(np.log(np.maximum(np.abs(eigs(resp(grid))), 1e-300)), axis=-1)
    except np.linalg.LinAlgError:
        values = np.array([log_moduli(w) for w in grid])
    crossings, unresolved = [], 0
    for k in range(len(g)):
        v = values[:, k]
        for j in np.flatnonzero(np.sign(v[:-1]) * np.sign(v[1:]) < 0):
            if not (resolved(grid[j]) and resolved(grid[j + 1])):
                unresolved += 1
                continue
            try:
                w = scipy.optimize.brentq(lambda w, k=k: log_moduli(w)[k], grid[j], grid[j + 1],
                                          xtol=1e-14, rtol=1e-12)
                lam = eigs(resp.at(resp.point(w)))
            except (ValueError, RuntimeError, np.linalg.LinAlgError):
                continue
            lam = lam[np.argmin(np.abs(np.log(np.maximum(np.abs(lam), 1e-300))))]
            pm = _wrap180(math.degrees(np.angle(lam)) + 180.0)
            crossings.append((float(w), pm, math.radians(pm % 360.0) / w))
    return crossings, unresolved


def group_delay_margin(L, channels, omega=None) -> GroupDelayMargin:
    """The smallest delay common to ``channels`` that destabilizes the loop.

    Parameters
    ----------
    L : control.StateSpace or control.TransferFunction
        Square loop transfer (negative feedback), e.g. a loop broken at the
        plant output, whose channels are the measurements.
    channels : sequence of int
        The delayed channels (a sensor's outputs), the others on time.
    omega : array_like, optional
        Search grid, rad/s (default: :func:`frequency_grid`).

    Returns
    -------
    GroupDelayMargin

    Notes
    -----
    The moduli of the eigenvalues of ``L_g(j w)``, sorted, are continuous in
    ``w``: each crosses 1 at a sign change of its logarithm on the grid,
    refined by Brent's method; there the eigenvalue nearest the unit circle
    gives the phase margin. A sampled loop is evaluated up to its Nyquist
    frequency, the delay taken as ``e^(-j w tau)`` (a fraction of a period
    is a delay of the sampled signal's continuous-time reconstruction, as
    for :func:`quadland.analysis.allmargin`'s delay margins).

    Examples
    --------
    >>> import control
    >>> dm = group_delay_margin(control.tf([2], [1, 0]), [0])   # 2/s: pi/4 s
    >>> round(dm.delay_margin, 9), round(dm.frequency, 9)
    (0.785398163, 2.0)
    """
    L = square_loop(L, "group_delay_margin")
    g = sorted({int(c) for c in channels})
    if not g or g[0] < 0 or g[-1] >= L.ninputs:
        raise ValueError(f"group_delay_margin: channels must be indices below {L.ninputs}, "
                         f"got {list(channels)}")
    resp, grid, stable = _grid(L, omega)
    if not stable:
        return GroupDelayMargin(tuple(g), 0.0, None, math.inf, (), False)
    crossings, unresolved = _unit_crossings(resp, grid, g, L.ninputs)
    crossings.sort()
    if not crossings:
        return GroupDelayMargin(tuple(g), math.inf, None, math.inf, (), True, unresolved)
    w, pm, tau = min(crossings, key=lambda c: c[2])
    return GroupDelayMargin(tuple(g), tau, w, pm, tuple(crossings), True, unresolved)

"""Classical gain and phase margins of every crossing of a loop, channel by channel."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg
import scipy.optimize

from quadland.analysis.response import (
    FrequencyResponse,
    closed_loop_poles,
    closed_loop_stable,
    frequency_grid,
    loop_at_a_time,
    response_of,
    square_loop,
)

__all__ = ["Margins", "allmargin"]

#: A crossing is reported only where the first-order bound on the loop value's
#: relative error is below this: where the realization fixes the value at all.
#: Measured: genuine crossings 1e-13 to 0.11 (a badly scaled companion form),
#: crossings inside a roundoff-split repeated integrator 5.7e3 to 6.5e11.
_CROSSING_RELATIVE_ERROR = 1.0


@dataclasses.dataclass(frozen=True)
class Margins:
    """Classical margins of one loop (as MATLAB's ``allmargin``).

    Attributes
    ----------
    gain_margin : tuple of float
        ``-1 / L(j w)`` at every phase crossing (``L`` real and negative),
        as ratios: > 1 tolerates a gain increase, < 1 a gain reduction.
    gm_frequency : tuple of float
        Phase-crossover frequencies, rad/s.
    phase_margin : tuple of float
        ``180 + arg L(j w)`` at every gain crossing (``|L| = 1``), deg,
        wrapped to (-180, 180].
    pm_frequency : tuple of float
        Gain-crossover frequencies, rad/s.
    delay_margin : tuple of float
        Smallest added delay that puts ``L(j w)`` on -1 at each gain
        crossing, s: ``mod(phase margin, 360 deg) / w``.
    dm_frequency : tuple of float
        Their frequencies, rad/s (the gain crossovers).
    stable : bool
        Whether the nominal closed loop (all loops closed) is stable.
    """

    gain_margin: tuple[float, ...]
    gm_frequency: tuple[float, ...]
    phase_margin: tuple[float, ...]
    pm_frequency: tuple[float, ...]
    delay_margin: tuple[float, ...]
    dm_frequency: tuple[float, ...]
    stable: bool


def _channel(resp: FrequencyResponse, i: int):
    def l_of(omega: float) -> complex:
        return complex(loop_at_a_time(resp.at(resp.point(omega))[None])[0, i])
    return l_of


def _loop_error(resp: FrequencyResponse, i: int, omega: float) -> tuple[float, complex]:
    """A bound on ``|dl_i|`` for the realization's uncertainty, and ``l_i``, at ``omega``.

    With the other loops closed, ``l_i = 1 / S_ii - 1`` and ``S = (I + L)^-1``,
    so ``dl_i = -dS_ii / S_ii^2`` with ``dS_ii = -e_i^T S dL S e_i``. Returns
    ``(inf, nan)`` where ``l_i`` cannot be evaluated.
    """
    p = resp.point(omega)
    try:
        G = resp.at(p)
        S = np.linalg.inv(np.eye(G.shape[0]) + G)
    except (np.linalg.LinAlgError, ValueError):
        return math.inf, complex(math.nan)
    s_ii = S[i, i]
    if not (np.all(np.isfinite(S)) and abs(s_ii) > 0):
        return math.inf, complex(math.nan)
    l_i = complex(1.0 / s_ii - 1.0)
    return resp.uncertainty(p, S[i, :], S[:, i]) / abs(s_ii) ** 2, l_i


def _determined(resp: FrequencyResponse, i: int, omega: float) -> bool:
    """Whether the realization determines loop ``i``'s value at ``omega``.

    A crossing where ``|dl_i| / |l_i|`` may exceed 1 is an artefact of a
    repeated pole realized inexactly, not a property of the loop.
    """
    err, l_i = _loop_error(resp, i, omega)
    return bool(math.isfinite(abs(l_i)) and err <= _CROSSING_RELATIVE_ERROR * abs(l_i))


def _sign_determined(resp: FrequencyResponse, i: int, omega: float) -> bool:
    """Whether the sign of ``Im l_i`` at ``omega`` is fixed by the realization.

    A phase crossing is a change of that sign; where the phase lies within
    roundoff of -180 deg over a band (an integrator pair with a near-cancelled
    lead, ``k/s^2``), the computed sign flips at random and would give
    crossings that the loop does not have.
    """
    err, l_i = _loop_error(resp, i, omega)
    return bool(math.isfinite(err) and err < abs(l_i.imag))


def _roots(fun, grid, values, keep=None):
    """Refined sign changes of ``values`` (= fun(grid)) by Brent's method.

    ``keep(a, b)``, if given, must accept a bracketing pair of grid points.
    """
    out = []
    for k in np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0):
        if keep is not None and not keep(grid[k], grid[k + 1]):
            continue
        try:
            out.append(scipy.optimize.brentq(fun, grid[k], grid[k + 1], xtol=1e-14,
                                             rtol=1e-12))
        except (ValueError, RuntimeError):
            continue
    out += [grid[k] for k in np.flatnonzero(values == 0)
            if keep is None or keep(grid[k], grid[k])]
    return sorted(out)


def _siso_margins(i, lvals, grid, resp, stable) -> Margins:
    l_of = _channel(resp, i)
    finite = np.isfinite(lvals)
    g, lv = grid[finite], lvals[finite]
    # gain crossings: log|l| = 0
    wc = _roots(lambda w: math.log(abs(l_of(w))), g, np.log(np.abs(lv)))
    # phase crossings: Im l = 0 with Re l < 0
    wp = [w for w in _roots(lambda w: l_of(w).imag, g, lv.imag,
                            keep=lambda a, b: _sign_determined(resp, i, a)
                            and _sign_determined(resp, i, b))
          if l_of(w).real < 0]
    edges = [0.0] + ([math.pi / resp.dt] if resp.dt else [])
    for w in edges:
        try:
            lw = l_of(w)
        except (np.linalg.LinAlgError, ZeroDivisionError, ValueError):
            continue
        if np.isfinite(lw) and lw.real < 0 and abs(lw.imag) <= 1e-9 * abs(lw):
            wp = [w] + wp if w == 0.0 else wp + [w]
    wc = [w for w in wc if _determined(resp, i, w)]
    wp = [w for w in wp if _determined(resp, i, w)]
    gm = tuple(-1.0 / l_of(w).real for w in wp)
    pm = tuple(_wrap180(math.degrees(np.angle(l_of(w))) + 180.0) for w in wc)
    dm = tuple(math.radians(p % 360.0) / w for p, w in zip(pm, wc, strict=True))
    return Margins(gm, tuple(float(w) for w in wp), pm, tuple(float(w) for w in wc), dm,
                   tuple(float(w) for w in wc), stable)


def _wrap180(deg: float) -> float:
    d = (deg + 180.0) % 360.0 - 180.0
    return 180.0 if d == -180.0 else d


def allmargin(sys, omega=None) -> list[Margins]:
    """All classical crossings and margins of a SISO or square MIMO loop.

    Parameters
    ----------
    sys : control.StateSpace or control.TransferFunction
        Loop transfer ``L`` (negative feedback, ``u = -L u``).
    omega : array_like, optional
        Search grid, rad/s (default: :func:`frequency_grid`). Crossings are
        found as sign changes on the grid and refined by Brent's method.

    Returns
    -------
    list of Margins
        One per loop: for a MIMO ``L``, the SISO loop of channel ``i``
        broken with every other loop closed,
        ``l_i = 1 / [(I + L)^-1]_ii - 1``.

    Notes
    -----
    As MATLAB's ``allmargin``: every crossing is reported, not only the
    smallest; a loop without phase crossings has an empty ``gain_margin``
    (infinite gain margin). Crossings at ``omega = 0`` (and at the Nyquist
    frequency of a discrete loop) count when ``L`` is real and negative
    there. ``stable`` refers to the closed loop with all loops closed.

    A crossing is reported only where the realization determines the loop's
    value there (a first-order relative error bound below 1 for a
    perturbation of ``A`` of ``1e3 eps ||A||``, see
    :meth:`FrequencyResponse.uncertainty`). A repeated pole realized with
    roundoff (a triple integrator through slycot becomes three poles of
    about 1e-8) otherwise shows phase crossings inside the spurious cluster,
    with gain margins such as 1e-25.

    Examples
    --------
    >>> import control
    >>> m, = allmargin(control.tf([1], [1, 3, 2, 0]))
    >>> round(m.gain_margin[0], 6), round(m.gm_frequency[0] ** 2, 6)
    (6.0, 2.0)
    """
    sys = square_loop(sys, "allmargin")
    resp = response_of(sys)
    poles = closed_loop_poles(sys)
    grid = (frequency_grid(resp, extra_poles=poles) if omega is None
            else np.asarray(omega, dtype=float))
    stable = closed_loop_stable(sys, poles)
    lvals = loop_at_a_time(resp(grid))
    return [_siso_margins(i, lvals[:, i], grid, resp, stable) for i in range(sys.ninputs)]

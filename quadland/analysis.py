"""Classical and disk-based stability margins of linear feedback loops.

Every function here works on the state space, never on polynomials: the
frequency response comes from a complex Schur form ``A = Z T Z^H``
computed once, so that each frequency costs one triangular solve,
``G(s) = C Z (s I - T)^-1 Z^H B + D``. That is backward stable and fast
for loops of several hundred states, where polynomial forms (as in
``control.stability_margins``) lose every digit.

Conventions: ``L`` is a loop transfer in the negative-feedback convention,
closed as ``u = -L u`` (the closed loop is ``(I + L)^-1``); a MIMO ``L``
is square, one channel per loop.
"""

from __future__ import annotations

import dataclasses
import math

import control
import numpy as np
import scipy.linalg
import scipy.optimize

__all__ = ["Margins", "DiskMargin", "FrequencyResponse", "freqresp", "frequency_grid",
           "closed_loop_poles", "allmargin", "diskmargin", "sensitivity_sigma",
           "disk_gain_margin", "disk_phase_margin", "loop_at_a_time"]

_POINTS_PER_DECADE = 60
#: Roundoffs of ||A|| assumed in a realization's entries (see FrequencyResponse).
_REALIZATION_ROUNDOFFS = 1e3
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


@dataclasses.dataclass(frozen=True)
class DiskMargin:
    """Balanced (skew 0) disk margin and the gain and phase margins it implies.

    Attributes
    ----------
    disk_margin : float
        alpha: the loop stays stable for every multiplicative factor in the
        disk ``(1 + alpha/2 delta) / (1 - alpha/2 delta)``, ``|delta| < 1``.
    gain_margin : tuple of float
        ``(low, high)`` gain ratios that the disk contains.
    phase_margin : float
        ``2 atan(alpha / 2)``, deg.
    frequency : float
        Frequency of the critical perturbation, rad/s.
    """

    disk_margin: float
    gain_margin: tuple[float, float]
    phase_margin: float
    frequency: float


def disk_gain_margin(alpha: float) -> tuple[float, float]:
    """Gain interval ``[(1 - a/2)/(1 + a/2), (1 + a/2)/(1 - a/2)]`` of a balanced disk."""
    h = alpha / 2.0
    if h >= 1.0 - 1e-9:
        return (0.0, math.inf)
    return (float((1 - h) / (1 + h)), float((1 + h) / (1 - h)))


def disk_phase_margin(alpha: float) -> float:
    """Phase margin ``2 atan(alpha / 2)`` of a balanced disk, deg."""
    return math.degrees(2.0 * math.atan(alpha / 2.0))


def _disk(alpha: float, frequency: float) -> DiskMargin:
    return DiskMargin(float(alpha), disk_gain_margin(alpha), disk_phase_margin(alpha),
                      float(frequency))


def _is_discrete(sys) -> bool:
    return bool(sys.dt) and sys.dt is not True


class FrequencyResponse:
    """The response ``G(s)`` of a state-space system at any frequency.

    Built once from a complex Schur form of ``A``; calling it at ``omega``
    (rad/s) evaluates ``s = j omega`` (continuous) or ``z = exp(j omega
    dt)`` (discrete) with one triangular solve per frequency.

    Parameters
    ----------
    sys : control.StateSpace or control.TransferFunction
    """

    def __init__(self, sys):
        sys = sys if isinstance(sys, control.StateSpace) else control.ss(sys)
        if sys.dt is True:
            raise ValueError("freqresp: a discrete system needs a numeric sampling time")
        self.sys = sys
        self.dt = float(sys.dt) if _is_discrete(sys) else 0.0
        A, B, C = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C))
        self._D = np.asarray(sys.D, dtype=complex)
        # Size of the perturbation of A that the realization itself may carry:
        # conversions (tf -> ss through slycot, similarity transforms) leave
        # errors of a few hundred roundoffs of ||A|| in its entries.
        self.a_uncertainty = (_REALIZATION_ROUNDOFFS * np.finfo(float).eps
                              * (np.linalg.norm(A, 2) if A.size else 0.0))
        if A.shape[0]:
            T, Z = scipy.linalg.schur(A, output="complex")
            self._T, self._B, self._C = T, Z.conj().T @ B, C @ Z
            self.poles = np.diag(T).copy()
        else:
            self._T = None
            self.poles = np.zeros(0, dtype=complex)

    @property
    def shape(self) -> tuple[int, int]:
        """``(outputs, inputs)``."""
        return self._D.shape

    def at(self, point: complex) -> np.ndarray:
        """``G`` at one point of the complex plane (s or z)."""
        if self._T is None:
            return self._D.copy()
        n = self._T.shape[0]
        X = scipy.linalg.solve_triangular(point * np.eye(n) - self._T, self._B,
                                          check_finite=False)
        return self._C @ X + self._D

    def uncertainty(self, point: complex, left=None, right=None) -> float:
        """Bound on ``|left^T dG right|`` at ``point`` for ``||dA|| <= a_uncertainty``.

        To first order ``dG = C R dA R B`` with ``R = (point I - A)^-1``, so
        ``|left^T dG right| <= ||left^T C R|| a_uncertainty ||R B right||``
        (``left`` and ``right`` default to identities: a bound on ``||dG||``).
        Near a cluster of poles that a realization leaves where an exact
        model has a repeated pole (a multiple integrator turns into poles of
        size ``eps^(1/k)``), the resolvent is huge and ``G`` is not
        determined by the data.
        """
        if self._T is None:
            return 0.0
        n = self._T.shape[0]
        B = self._B if right is None else self._B @ np.reshape(right, (-1, 1))
        C = self._C if left is None else np.reshape(left, (1, -1)) @ self._C
        M = point * np.eye(n) - self._T
        RB = scipy.linalg.solve_triangular(M, B, check_finite=False)
        CR = scipy.linalg.solve_triangular(M, C.conj().T, trans="C",
                                           check_finite=False).conj().T
        return float(np.linalg.norm(CR, 2) * self.a_uncertainty * np.linalg.norm(RB, 2))

    def point(self, omega: float) -> complex:
        """``j omega`` or ``exp(j omega dt)``."""
        return np.exp(1j * omega * self.dt) if self.dt else 1j * omega

    def __call__(self, omega) -> np.ndarray:
        """Response at each of ``omega`` (rad/s), shape ``(len(omega), p, m)``."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        return np.stack([self.at(self.point(w)) for w in omega])


def freqresp(sys, omega) -> np.ndarray:
    """Frequency response from the state space, shape ``(len(omega), p, m)``.

    Parameters
    ----------
    sys : control.StateSpace or control.TransferFunction
    omega : array_like
        Frequencies, rad/s.

    Examples
    --------
    >>> import control
    >>> G = control.tf([1], [1, 1])
    >>> complex(freqresp(G, [1.0])[0, 0, 0])
    (0.5-0.5j)
    """
    return FrequencyResponse(sys)(omega)


def closed_loop_poles(L) -> np.ndarray:
    """Poles of the loop closed as ``u = -L u``: eig(A - B (I + D)^-1 C)."""
    L = L if isinstance(L, control.StateSpace) else control.ss(L)
    A, B, C, D = (np.asarray(m, dtype=float) for m in (L.A, L.B, L.C, L.D))
    if not A.shape[0]:
        return np.zeros(0, dtype=complex)
    return np.linalg.eigvals(A - B @ np.linalg.solve(np.eye(D.shape[0]) + D, C))


def _stable(L, p) -> bool:
    if _is_discrete(L):
        return bool(np.all(np.abs(p) < 1.0))
    return bool(np.all(p.real < 0.0))


def frequency_grid(resp: FrequencyResponse, points_per_decade: int = _POINTS_PER_DECADE,
                   extra_poles=()):
    """A log-spaced grid that spans the system's dynamics, rad/s.

    From two decades below to two decades above the nonzero magnitudes
    of the poles (and of ``extra_poles``, e.g. the closed loop's), widened
    upward until the loop gain has rolled off below 1/2; discrete systems
    stop at the Nyquist frequency ``pi / dt``.
    """
    poles = np.concatenate([resp.poles, np.asarray(extra_poles, dtype=complex)])
    if resp.dt:
        poles = np.log(poles[np.abs(poles) > 1e-300].astype(complex)) / resp.dt
    mags = np.abs(poles)
    mags = mags[mags > 1e-9]
    lo = 1e-2 * mags.min() if mags.size else 1e-2
    hi = 1e2 * mags.max() if mags.size else 1e2
    lo, hi = max(lo, 1e-6), max(hi, 10 * max(lo, 1e-6))
    if resp.dt:
        hi = math.pi / resp.dt
        lo = min(lo, 1e-3 * hi)
    else:
        while hi < 1e9 and np.max(np.abs(resp(hi))) >= 0.5:
            hi *= 10.0
    n = max(int(points_per_decade * math.log10(hi / lo)), 50)
    grid = np.logspace(math.log10(lo), math.log10(hi), n)
    if resp.dt:
        grid[-1] = hi * (1 - 1e-9)
    return grid


def loop_at_a_time(G: np.ndarray) -> np.ndarray:
    """SISO loops of each channel with all other loops closed.

    ``l_i = 1 / [(I + L)^-1]_ii - 1`` at each frequency, for ``G`` of shape
    ``(n_w, m, m)``; returns ``(n_w, m)``.
    """
    m = G.shape[-1]
    if m == 1:
        return G[:, :, 0]
    S = np.linalg.inv(np.eye(m) + G)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 1.0 / np.diagonal(S, axis1=1, axis2=2) - 1.0


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


def _square(sys, name):
    sys = sys if isinstance(sys, control.StateSpace) else control.ss(sys)
    if sys.ninputs != sys.noutputs:
        raise ValueError(f"{name}: the loop must be square, got {sys.noutputs} x {sys.ninputs}")
    return sys


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
    sys = _square(sys, "allmargin")
    resp = FrequencyResponse(sys)
    poles = closed_loop_poles(sys)
    grid = (frequency_grid(resp, extra_poles=poles) if omega is None
            else np.asarray(omega, dtype=float))
    stable = _stable(sys, poles)
    lvals = loop_at_a_time(resp(grid))
    return [_siso_margins(i, lvals[:, i], grid, resp, stable) for i in range(sys.ninputs)]


def _perron_scaling(M: np.ndarray, iterations: int = 30) -> np.ndarray:
    """Diagonal scalings d (batched) that balance the off-diagonal parts of |M|."""
    A = np.abs(M)
    m = A.shape[-1]
    A = A * (1 - np.eye(m)) + 1e-300
    d = np.ones(A.shape[:-1])
    for _ in range(iterations):
        S = d[..., :, None] * A / d[..., None, :]
        rows, cols = S.sum(axis=-1), S.sum(axis=-2)
        d = d * np.sqrt(cols / rows) ** 0.5
    return d


def _scaled_norm(M, d):
    return np.linalg.norm(d[..., :, None] * M / d[..., None, :], ord=2, axis=(-2, -1))


def _mu_upper(M: np.ndarray) -> float:
    """min over positive diagonal D of sigma_max(D M D^-1): an upper bound on mu.

    The objective is convex in log D, so a local search finds the global
    minimum of the bound.
    """
    m = M.shape[0]
    if m == 1:
        return float(abs(M[0, 0]))
    d0 = _perron_scaling(M)
    x0 = np.log(d0[1:] / d0[0])

    def f(x):
        return float(_scaled_norm(M, np.exp(np.r_[0.0, x])))

    res = scipy.optimize.minimize(f, x0, method="Nelder-Mead",
                                  options=dict(xatol=1e-8, fatol=1e-12, maxiter=4000))
    return min(float(res.fun), f(x0))


def _peak(fun, grid, values):
    """Maximum of ``fun`` near the largest of ``values`` (bounded refinement)."""
    k = int(np.argmax(values))
    best_w, best = grid[k], values[k]
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    if b > a:
        res = scipy.optimize.minimize_scalar(lambda lw: -fun(math.exp(lw)),
                                             bounds=(math.log(a), math.log(b)),
                                             method="bounded", options=dict(xatol=1e-10))
        if -res.fun > best:
            best_w, best = math.exp(res.x), -res.fun
    return float(best), float(best_w)


def diskmargin(L, omega=None) -> tuple[list[DiskMargin], DiskMargin]:
    """Balanced disk margins, loop at a time and multiloop.

    Parameters
    ----------
    L : control.StateSpace or control.TransferFunction
        Loop transfer (negative feedback, ``u = -L u``), SISO or square.
    omega : array_like, optional
        Frequency grid, rad/s (default: :func:`frequency_grid`).

    Returns
    -------
    per_loop : list of DiskMargin
        Channel ``i`` alone perturbed, the other loops closed:
        ``alpha_i = 1 / max_w |S_ii - 1/2|``.
    multiloop : DiskMargin
        Independent perturbations in every channel at once:
        ``alpha = 1 / max_w mu(S - I/2)`` for a diagonal complex
        perturbation, with mu replaced by its D-scaled upper bound, so
        the reported alpha is a guaranteed lower bound.

    Notes
    -----
    Skew ``sigma = 0`` (balanced), so ``S - I/2 = (S - T)/2`` with
    ``S = (I + L)^-1``, ``T = I - S`` [1]_. An unstable nominal loop has
    alpha = 0. The peak is searched on the grid and refined between the
    neighbouring grid points; for the multiloop bound every grid point
    whose cheap (Perron-scaled) bound exceeds the best optimized value is
    optimized too.

    References
    ----------
    .. [1] P. Seiler, A. Packard and P. Gahinet, "An introduction to disk
       margins", IEEE Control Systems Magazine 40(5), 78-95, 2020.
    """
    L = _square(L, "diskmargin")
    m = L.ninputs
    poles = closed_loop_poles(L)
    if not _stable(L, poles):
        zero = _disk(0.0, 0.0)
        return [zero] * m, zero
    resp = FrequencyResponse(L)
    grid = (frequency_grid(resp, extra_poles=poles) if omega is None
            else np.asarray(omega, dtype=float))
    half = 0.5 * np.eye(m)

    def M_at(w):
        return np.linalg.inv(np.eye(m) + resp.at(resp.point(w))) - half

    M = np.linalg.inv(np.eye(m) + resp(grid)) - half
    per_loop = []
    for i in range(m):
        peak, w = _peak(lambda w, i=i: abs(M_at(w)[i, i]), grid, np.abs(M[:, i, i]))
        with np.errstate(all="ignore"):
            try:
                dc = abs(M_at(0.0)[i, i])
            except (np.linalg.LinAlgError, ValueError):
                dc = -1.0
        if np.isfinite(dc) and dc > peak:
            peak, w = dc, 0.0
        per_loop.append(_disk(1.0 / peak, w))
    if m == 1:
        return per_loop, per_loop[0]
    cheap = _scaled_norm(M, _perron_scaling(M))
    best, best_k = -1.0, 0
    for k in np.argsort(cheap)[::-1]:
        if cheap[k] <= best:
            break
        mu = _mu_upper(M[k])
        if mu > best:
            best, best_k = mu, k
    a, b = grid[max(best_k - 1, 0)], grid[min(best_k + 1, len(grid) - 1)]
    w_best = grid[best_k]
    if b > a:
        res = scipy.optimize.minimize_scalar(lambda lw: -_mu_upper(M_at(math.exp(lw))),
                                             bounds=(math.log(a), math.log(b)),
                                             method="bounded", options=dict(xatol=1e-8))
        if -res.fun > best:
            best, w_best = -res.fun, math.exp(res.x)
    try:
        M0 = M_at(0.0)
    except (np.linalg.LinAlgError, ValueError):
        M0 = None
    if M0 is not None and np.all(np.isfinite(M0)):
        mu0 = _mu_upper(M0)
        if mu0 > best:
            best, w_best = mu0, 0.0
    return per_loop, _disk(1.0 / best, w_best)


def sensitivity_sigma(L, omega) -> tuple[np.ndarray, np.ndarray]:
    """Singular values of ``S = (I + L)^-1`` and ``T = I - S`` at ``omega``.

    Parameters
    ----------
    L : control.StateSpace or control.TransferFunction
        Square loop transfer (negative feedback, ``u = -L u``).
    omega : array_like
        Frequencies, rad/s.

    Returns
    -------
    sigma_S, sigma_T : ndarray, shape (len(omega), m)
        Largest first.
    """
    G = freqresp(L, omega)
    m = G.shape[-1]
    S = np.linalg.inv(np.eye(m) + G)
    return (np.linalg.svd(S, compute_uv=False), np.linalg.svd(np.eye(m) - S, compute_uv=False))

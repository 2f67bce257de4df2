"""Disk margins: loop at a time, and the multiloop bound through mu."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg
import scipy.optimize

from quadland.analysis.response import (
    closed_loop_poles,
    closed_loop_stable,
    freqresp,
    frequency_grid,
    response_of,
    square_loop,
)

__all__ = ["DiskMargin", "disk_gain_margin", "disk_phase_margin", "diskmargin",
           "sensitivity_sigma"]


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
    """``sigma_max(D M D^-1)`` (batched): the root of the largest eigenvalue of
    ``S^H S``, accurate to a relative eps and cheaper than an SVD for small ``m``."""
    S = d[..., :, None] * M / d[..., None, :]
    H = np.swapaxes(S, -1, -2).conj() @ S
    return np.sqrt(np.maximum(np.linalg.eigvalsh(H)[..., -1], 0.0))


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
        # _scaled_norm of one matrix, written out: the optimizer calls it a few hundred
        # times per frequency, where numpy's overheads were half its cost
        d = np.exp(np.concatenate(([0.0], x)))
        S = d[:, None] * M / d[None, :]
        return math.sqrt(max(float(np.linalg.eigvalsh(S.conj().T @ S)[-1]), 0.0))

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
    L = square_loop(L, "diskmargin")
    m = L.ninputs
    poles = closed_loop_poles(L)
    if not closed_loop_stable(L, poles):
        zero = _disk(0.0, 0.0)
        return [zero] * m, zero
    resp = response_of(L)
    grid = (frequency_grid(resp, extra_poles=poles) if omega is None
            else np.asarray(omega, dtype=float))
    half = 0.5 * np.eye(m)

    def M_at(w):
        return np.linalg.inv(np.eye(m) + resp.at(resp.point(w))) - half

    M = np.linalg.inv(np.eye(m) + resp(grid)) - half
    per_loop = [_loop_disk(M_at, grid, M, i) for i in range(m)]
    if m == 1:
        return per_loop, per_loop[0]
    return per_loop, _multiloop_disk(M_at, grid, M)


def _at_zero(M_at):
    """``M_at(0)``, or None where the loop has a pole at zero frequency."""
    with np.errstate(all="ignore"):
        try:
            M0 = M_at(0.0)
        except (np.linalg.LinAlgError, ValueError):
            return None
    return M0 if np.all(np.isfinite(M0)) else None


def _loop_disk(M_at, grid, M, i) -> DiskMargin:
    """Channel ``i`` alone: ``alpha_i = 1 / max_w |S_ii - 1/2|``, zero frequency included."""
    peak, w = _peak(lambda w: abs(M_at(w)[i, i]), grid, np.abs(M[:, i, i]))
    M0 = _at_zero(M_at)
    if M0 is not None and abs(M0[i, i]) > peak:
        peak, w = abs(M0[i, i]), 0.0
    return _disk(1.0 / peak, w)


def _multiloop_disk(M_at, grid, M) -> DiskMargin:
    """Every channel at once: ``alpha = 1 / max_w mu(S - I/2)`` with mu's D-scaled upper
    bound, optimized at every grid point whose cheap bound exceeds the best so far, then
    refined between the best point's neighbours and checked at zero frequency."""
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
    M0 = _at_zero(M_at)
    if M0 is not None:
        mu0 = _mu_upper(M0)
        if mu0 > best:
            best, w_best = mu0, 0.0
    return _disk(1.0 / best, w_best)


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

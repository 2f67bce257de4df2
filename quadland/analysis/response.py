"""The frequency response of a state-space loop, its grid, poles and loop-at-a-time form.

Every function works on the state space, never on polynomials (see the
package :mod:`quadland.analysis`).
"""

from __future__ import annotations

import collections
import hashlib
import math
import threading
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg
import scipy.optimize

from quadland.analysis.modal import MODAL_CHECK, Modal

if TYPE_CHECKING:
    import control

__all__ = ["FrequencyResponse", "state_space", "response_of", "freqresp", "frequency_grid",
           "closed_loop_poles", "closed_loop_stable", "loop_at_a_time", "square_loop",
           "is_discrete", "POINTS_PER_DECADE"]

POINTS_PER_DECADE = 60
#: Roundoffs of ||A|| assumed in a realization's entries (see FrequencyResponse).
_REALIZATION_ROUNDOFFS = 1e3
#: Systems whose response and closed-loop poles :func:`response_of` keeps.
_KEPT = 4
_RECENT: collections.OrderedDict = collections.OrderedDict()
#: Grids and single points whose response each FrequencyResponse keeps.
_KEPT_GRIDS, _KEPT_POINTS = 4, 64


def state_space(sys):
    """``sys`` if it is a state space (its ``A``, ``B``, ``C``, ``D`` and ``dt``: a
    ``control.StateSpace`` or a :class:`quadland.linear.Realization`), else
    ``control.ss(sys)`` (python-control is imported only then)."""
    if all(hasattr(sys, k) for k in ("A", "B", "C", "D", "dt")):
        return sys
    import control

    return control.ss(sys)


def is_discrete(sys) -> bool:
    """Whether a python-control system is sampled (``dt`` a period, not None or True)."""
    return bool(sys.dt) and sys.dt is not True


class FrequencyResponse:
    """The response ``G(s)`` of a state-space system at any frequency.

    Built once from a complex Schur form of ``A``; calling it at ``omega``
    (rad/s) evaluates ``s = j omega`` (continuous) or ``z = exp(j omega
    dt)`` (discrete): from the modal form (:mod:`quadland.analysis.modal`),
    one product for the whole grid, where the eigenvectors are well
    conditioned and the two forms agree; otherwise with one triangular
    solve per frequency. :func:`response_of` keeps the latest few, so that
    the analyses of one loop share one; each keeps its latest grids and
    points (a loop's margins, disk margins and sensitivity peaks read the
    same grid, and its crossings are read again where they are reported).

    Parameters
    ----------
    sys : control.StateSpace, Realization or control.TransferFunction
    """

    def __init__(self, sys):
        sys = state_space(sys)
        if sys.dt is True:
            raise ValueError("freqresp: a discrete system needs a numeric sampling time")
        self.sys = sys
        self.dt = float(sys.dt) if is_discrete(sys) else 0.0
        A, B, C = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C))
        self._D = np.asarray(sys.D, dtype=complex)
        # Size of the perturbation of A that the realization itself may carry:
        # conversions (tf -> ss through slycot, similarity transforms) leave
        # errors of a few hundred roundoffs of ||A|| in its entries.
        self.a_uncertainty = (_REALIZATION_ROUNDOFFS * np.finfo(float).eps
                              * (np.linalg.norm(A, 2) if A.size else 0.0))
        self._modal = None
        self._grids: collections.OrderedDict = collections.OrderedDict()
        self._points: collections.OrderedDict = collections.OrderedDict()
        if A.shape[0]:
            T, Z = scipy.linalg.schur(A, output="complex")
            self._T, self._B, self._C = T, Z.conj().T @ B, C @ Z
            self.poles = np.diag(T).copy()
            self._negated: dict = {}
            self._negated_diagonal = -self.poles
            self._modal = self._checked_modal()
        else:
            self._T = None
            self.poles = np.zeros(0, dtype=complex)

    def _checked_modal(self) -> Modal | None:
        """The modal form, if conditioned well enough and equal to the Schur form's solves
        (to :data:`~quadland.analysis.modal.MODAL_CHECK`) at three frequencies across the
        poles' magnitudes."""
        modal = Modal(self._T, self._B, self._C)
        if not modal.usable:
            return None
        mags = np.abs(np.log(self.poles[self.poles != 0]) / self.dt if self.dt else self.poles)
        mags = mags[np.isfinite(mags) & (mags > 0)]
        omega = np.geomspace(mags.min(), mags.max(), 3) if mags.size else np.ones(1)
        for w in omega:
            p = self.point(min(w, 0.9 * math.pi / self.dt) if self.dt else w)
            with np.errstate(all="ignore"):
                try:
                    direct = self._solve(p)
                except np.linalg.LinAlgError:                   # on a pole
                    continue
                diff = np.linalg.norm(modal.response([p])[0] + self._D - direct)
            if not diff <= MODAL_CHECK * np.linalg.norm(direct):
                return None
        return modal

    @property
    def modal(self) -> bool:
        """Whether the response comes from the modal form (else from triangular solves)."""
        return self._modal is not None

    def _solve(self, point: complex) -> np.ndarray:
        """``G`` at ``point`` by a triangular solve of the Schur form."""
        return self._C @ scipy.linalg.solve_triangular(self._shifted(point), self._B,
                                                       check_finite=False) + self._D

    def _shifted(self, point: complex) -> np.ndarray:
        """``point I - T``: the calling thread's copy of ``-T`` with its diagonal rewritten,
        each entry ``-T_ii + point`` (a new copy of ``-T`` per point, 1.6 MB for 323
        states, took as long as the solve)."""
        thread = threading.get_ident()
        M = self._negated.get(thread)
        if M is None:
            M = self._negated[thread] = -self._T
        M.flat[::M.shape[0] + 1] = self._negated_diagonal + point
        return M

    @property
    def shape(self) -> tuple[int, int]:
        """``(outputs, inputs)``."""
        return self._D.shape

    def at(self, point: complex) -> np.ndarray:
        """``G`` at one point of the complex plane (s or z), by a triangular solve.

        Backward stable, unlike the modal form (whose error grows with the
        eigenvectors' condition): the refinements of crossings and peaks, and
        the values reported, come from here; grids from :meth:`__call__`.
        """
        if self._T is None:
            return self._D.copy()
        key = complex(point)
        if key not in self._points:
            self._points[key] = self._solve(point)
            _trim(self._points, _KEPT_POINTS)
        return self._points[key].copy()

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
        key = omega.tobytes()
        if key not in self._grids:
            self._grids[key] = self._grid(omega)
            _trim(self._grids, _KEPT_GRIDS)
        return self._grids[key].copy()

    def _grid(self, omega: np.ndarray) -> np.ndarray:
        if self._modal is None or not omega.size:
            return np.stack([self._D.copy() if self._T is None else self._solve(self.point(w))
                             for w in omega])
        points = np.array([self.point(w) for w in omega], dtype=complex)
        with np.errstate(all="ignore"):
            G = self._modal.response(points) + self._D
        for k in np.flatnonzero(~np.all(np.isfinite(G), axis=(1, 2))):
            G[k] = self._solve(points[k])                 # on a pole: as the solve says
        return G


def _trim(kept: collections.OrderedDict, most: int) -> None:
    while len(kept) > most:
        kept.popitem(last=False)


def _digest(sys: control.StateSpace) -> str:
    digest = hashlib.sha256(repr(sys.dt).encode())
    for M in (sys.A, sys.B, sys.C, sys.D):
        a = np.ascontiguousarray(M, dtype=float)
        digest.update(repr(a.shape).encode() + a.tobytes())
    return digest.hexdigest()


def _kept(sys, what: str, make):
    sys = state_space(sys)
    key = (_digest(sys), what)
    if key not in _RECENT:
        _RECENT[key] = make(sys)
        while len(_RECENT) > 2 * _KEPT:
            _RECENT.popitem(last=False)
    _RECENT.move_to_end(key)
    return _RECENT[key]


def response_of(sys) -> FrequencyResponse:
    """The :class:`FrequencyResponse` of ``sys``, shared with the latest calls for equal
    systems (equal matrices and sampling time: the same loop's margins, disk margins and
    singular values factor it once)."""
    return _kept(sys, "response", FrequencyResponse)


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
    return response_of(sys)(omega)


def closed_loop_poles(L) -> np.ndarray:
    """Poles of the loop closed as ``u = -L u``: eig(A - B (I + D)^-1 C) (kept for the
    latest few loops, as :func:`response_of`; a copy)."""
    return _kept(L, "closed-loop poles", _closed_loop_poles).copy()


def _closed_loop_poles(L: control.StateSpace) -> np.ndarray:
    A, B, C, D = (np.asarray(m, dtype=float) for m in (L.A, L.B, L.C, L.D))
    if not A.shape[0]:
        return np.zeros(0, dtype=complex)
    return np.linalg.eigvals(A - B @ np.linalg.solve(np.eye(D.shape[0]) + D, C))


def closed_loop_stable(L, p) -> bool:
    """Whether the poles ``p`` of the loop closed around ``L`` are stable (inside the
    unit circle if ``L`` is sampled, in the left half-plane if not)."""
    if is_discrete(L):
        return bool(np.all(np.abs(p) < 1.0))
    return bool(np.all(p.real < 0.0))


def frequency_grid(resp: FrequencyResponse, points_per_decade: int = POINTS_PER_DECADE,
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


def square_loop(sys, name):
    """``sys`` as a state space, refused unless square (one channel per loop)."""
    sys = state_space(sys)
    if sys.ninputs != sys.noutputs:
        raise ValueError(f"{name}: the loop must be square, got {sys.noutputs} x {sys.ninputs}")
    return sys



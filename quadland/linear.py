"""Linear models of a loop at an operating point, whatever the loop kind.

A loop kind (:mod:`quadland.kinds`) finds its operating point and the
Jacobians of its plant and controller there; this module holds what is
common: the :class:`OperatingPoint` and :class:`LinearModels` types, Newton's
method for the equilibrium (:func:`newton`), the assembly of the broken and
closed loops from the Jacobians (:func:`assemble`), the zero-order hold
(:func:`zoh`) and the computation delay on the command (:func:`delayed`).

Sign convention: ``u = K y`` is what the controller computes, so with the
loop broken at the plant input the return is ``K P``; in the negative
feedback convention of :mod:`quadland.analysis` the loop transfer is
``L = -K P`` (and ``-P K`` broken at the plant output).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.linalg

from quadland.exceptions import MarginsError, OperatingPointError

if TYPE_CHECKING:
    import control

__all__ = ["OperatingPoint", "Realization", "MODEL_NAMES", "LinearModels", "newton", "assemble",
           "zoh", "delayed", "check_delay_periods"]


@dataclasses.dataclass(frozen=True)
class OperatingPoint:
    """Where a loop is linearized.

    Attributes
    ----------
    kind : str
        ``"equilibrium"`` (steady motion) or ``"frozen"`` (a simulated state).
    time : float or None
        s, the simulated time of a frozen point.
    xr : ndarray
        Plant state (the loop kind's linearization coordinates, named by
        ``state_names``).
    xc : ndarray
        Controller state.
    vehicle : ndarray, shape (3,)
        Vehicle surge, sway (m/s) and yaw rate r2 (rad/s).
    z2 : float
        m, deck altitude (the landing loop: the pad centre's).
    w : ndarray
        The constant disturbance at the point (the loop kind's layout).
    u : ndarray, shape (4,)
        Loop input at the point.
    residual : float
        ``|d/dt [xr, xc]|`` at the point: ~0 at an equilibrium, the drift
        of a frozen point.
    iterations : int
        Newton iterations (0 for a frozen point).
    model : str
        The loop kind (``scenario.model``) that made it.
    state_names : tuple of str
        The names of ``xr``'s entries.
    controller : mapping
        The controller state summarized for reports (JSON-ready).
    """

    kind: str
    time: float | None
    xr: np.ndarray
    xc: np.ndarray
    vehicle: np.ndarray
    z2: float
    w: np.ndarray
    u: np.ndarray
    residual: float
    iterations: int
    model: str
    state_names: tuple[str, ...]
    controller: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return dict(kind=self.kind, time_s=self.time, model=self.model,
                    state={n: float(v) for n, v in zip(self.state_names, self.xr, strict=True)},
                    **self.controller,
                    vehicle=dict(u2=float(self.vehicle[0]), v2=float(self.vehicle[1]),
                                 r2=float(self.vehicle[2]), z2=self.z2),
                    disturbance=self.w.tolist(), u=self.u.tolist(), residual=self.residual,
                    newton_iterations=self.iterations)


@dataclasses.dataclass(frozen=True, eq=False)
class Realization:
    """A state-space system's matrices, period and signal names, without python-control.

    What the margin review and its figures read: :mod:`quadland.analysis` takes
    it as it takes a ``control.StateSpace`` (the attributes below), and a
    review need not import python-control (about 0.7 s of CPU: it loads
    ``scipy.signal`` and ``matplotlib.pyplot``). :meth:`to_control` makes the
    python-control system.

    Attributes
    ----------
    A, B, C, D : ndarray
        ``x' = A x + B u``, ``y = C x + D u`` (or ``x[k+1] = ...``).
    dt : float
        0 for continuous time, else the sampling period (s).
    inputs, outputs, states : tuple of str
        The signals' names.
    name : str
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    dt: float
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    states: tuple[str, ...]
    name: str

    @property
    def ninputs(self) -> int:
        """Inputs, as python-control names it."""
        return self.B.shape[1]

    @property
    def noutputs(self) -> int:
        """Outputs."""
        return self.C.shape[0]

    @property
    def nstates(self) -> int:
        """States."""
        return self.A.shape[0]

    @property
    def input_labels(self) -> list[str]:
        """The inputs' names, as python-control gives them."""
        return list(self.inputs)

    @property
    def output_labels(self) -> list[str]:
        """The outputs' names."""
        return list(self.outputs)

    @property
    def state_labels(self) -> list[str]:
        """The states' names."""
        return list(self.states)

    def to_control(self) -> control.StateSpace:
        """The python-control system (``control.ss``, continuous when ``dt`` is 0)."""
        import control

        kw = dict(dt=self.dt) if self.dt else {}
        return control.ss(self.A, self.B, self.C, self.D, inputs=list(self.inputs),
                          outputs=list(self.outputs), states=list(self.states), name=self.name,
                          **kw)


#: The models of :class:`LinearModels`, in its attributes' order.
MODEL_NAMES = ("plant", "controller", "loop_input", "loop_output", "closed_loop")


@dataclasses.dataclass(frozen=True)
class LinearModels:
    """State-space models of the loop at one operating point.

    Each model is a ``control.StateSpace``, made from its :class:`Realization`
    when first read (python-control is imported then); ``realizations`` holds
    them without python-control, for the margin review.

    Attributes
    ----------
    point : OperatingPoint
    realizations : mapping of str to Realization
        Each of :data:`MODEL_NAMES`.
    plant : control.StateSpace
        P: u (4) -> y, states xr (the paper's loop: y = xr, 10; the landing
        loop: the quadrotor's measurements, 12).
    controller : control.StateSpace
        K: y -> u (4), states xc (the paper's: the adaptive states, and
        sampled with hold compensation the law's previous output
        ``u_prev``; the landing loop's: the step's memory); a sampled
        controller's last states are its computation delay.
    loop_input : control.StateSpace
        ``L_i = -K P`` (4 x 4), the loop broken at the plant input.
    loop_output : control.StateSpace
        ``L_o = -P K``, the loop broken at the plant output.
    closed_loop : control.StateSpace
        States ``[xr, xc]``; input an additive disturbance at u, output y.
    dt : float
        0 for continuous time, else the sampling period (s).
    delay_periods : int
        Control periods between sampling and commanding (0 in continuous
        time).
    loop_names : tuple of str
        One name per input of the loop.
    """

    point: OperatingPoint
    realizations: Mapping[str, Realization]
    dt: float = 0.0
    delay_periods: int = 0
    loop_names: tuple[str, ...] = ()

    @functools.cached_property
    def plant(self) -> control.StateSpace:
        return self.realizations["plant"].to_control()

    @functools.cached_property
    def controller(self) -> control.StateSpace:
        return self.realizations["controller"].to_control()

    @functools.cached_property
    def loop_input(self) -> control.StateSpace:
        return self.realizations["loop_input"].to_control()

    @functools.cached_property
    def loop_output(self) -> control.StateSpace:
        return self.realizations["loop_output"].to_control()

    @functools.cached_property
    def closed_loop(self) -> control.StateSpace:
        return self.realizations["closed_loop"].to_control()


def newton(residual, xi, tol: float, max_iter: int):
    """Newton's method with step halving on ``residual(x) -> (F, dF)``; ``(x, iterations)``."""
    r, J = residual(xi)
    norm = np.linalg.norm(r)
    for it in range(1, max_iter + 1):
        try:
            step = np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            raise OperatingPointError("no equilibrium: singular Jacobian in Newton's method "
                                      f"(residual {norm:.3g})") from None
        lam = 1.0
        while lam > 1e-6:
            trial = xi - lam * step
            r_t, J_t = residual(trial)
            if np.all(np.isfinite(r_t)) and np.linalg.norm(r_t) < norm * (1 - 1e-4 * lam):
                break
            lam /= 2
        else:
            raise OperatingPointError(f"no equilibrium: Newton's method stalled at residual "
                                      f"{norm:.3g} after {it} iterations")
        xi, r, J, norm = trial, r_t, J_t, np.linalg.norm(r_t)
        if norm < tol:
            return xi, it
    raise OperatingPointError(f"no equilibrium: Newton's method did not converge in "
                              f"{max_iter} iterations (residual {norm:.3g})")


def assemble(point, Ap, Bp, Cp, Ac, Bc, Cc, Dc, dt, names, delay_periods=0) -> LinearModels:
    n, nc = Ap.shape[0], Ac.shape[0]
    ny, m = Cp.shape[0], Bp.shape[1]
    dt = float(dt) if dt else 0.0
    x_names, y_names, u_names = names["x"], names["y"], names["u"]
    xc_names = names["c"] + [f"u_delay{j + 1}[{k}]" for j in range(delay_periods)
                             for k in range(m)]

    def model(name, A, B, C, D, inputs, outputs, states):
        return Realization(*(np.array(M, dtype=float, ndmin=2) for M in (A, B, C, D)), dt,
                           tuple(inputs), tuple(outputs), tuple(states), name)

    states = x_names + xc_names
    A_i = np.block([[Ap, np.zeros((n, nc))], [Bc @ Cp, Ac]])
    A_o = np.block([[Ac, np.zeros((nc, n))], [Bp @ Cc, Ap]])
    A_cl = np.block([[Ap + Bp @ Dc @ Cp, Bp @ Cc], [Bc @ Cp, Ac]])
    returns = [f"{k}_return" for k in u_names]
    realizations = dict(
        plant=model("plant", Ap, Bp, Cp, np.zeros((ny, m)), u_names, y_names, x_names),
        controller=model("controller", Ac, Bc, Cc, Dc, y_names, u_names, xc_names),
        loop_input=model("loop_input", A_i, np.vstack([Bp, np.zeros((nc, m))]),
                         -np.hstack([Dc @ Cp, Cc]), np.zeros((m, m)), u_names, returns, states),
        loop_output=model("loop_output", A_o, np.vstack([Bc, Bp @ Dc]),
                          np.hstack([np.zeros((ny, nc)), -Cp]), np.zeros((ny, ny)), y_names,
                          [f"{k}_return" for k in y_names], xc_names + x_names),
        closed_loop=model("closed_loop", A_cl, np.vstack([Bp, np.zeros((nc, m))]),
                          np.hstack([Cp, np.zeros((ny, nc))]), np.zeros((ny, m)), u_names,
                          y_names, states))
    return LinearModels(point, realizations, dt, delay_periods, tuple(names["loops"]))


def zoh(A, B, dt):
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def delayed(Phi, Gam, C, D, periods: int):
    """The controller ``(Phi, Gam, C, D)`` followed by ``periods`` unit delays on its output.

    ``d_1[k+1] = C x[k] + D y[k]``, ``d_j+1[k+1] = d_j[k]``, output ``d_periods[k]``.
    """
    if periods == 0:
        return Phi, Gam, C, D
    nc, m = Phi.shape[0], C.shape[0]
    nd = m * periods
    shift = np.eye(nd, k=-m)                     # d_j+1 <- d_j
    A = np.block([[Phi, np.zeros((nc, nd))],
                  [np.vstack([C, np.zeros((nd - m, nc))]), shift]])
    B = np.vstack([Gam, D, np.zeros((nd - m, Gam.shape[1]))])
    out = np.hstack([np.zeros((m, nc)), np.zeros((m, nd - m)), np.eye(m)])
    return A, B, out, np.zeros_like(D)




def check_delay_periods(delay_periods) -> int:
    """``delay_periods`` as an int, refused in one line unless an integer >= 0."""
    if isinstance(delay_periods, bool) or int(delay_periods) != delay_periods \
            or delay_periods < 0:
        raise MarginsError(f"delay_periods: must be an integer >= 0, got {delay_periods}")
    return int(delay_periods)

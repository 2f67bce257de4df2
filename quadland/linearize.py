"""Operating points and linear models of the closed loop.

The loop is broken at the virtual input u of eq. (6). The plant maps u to
the measured relative state ``y = xr = [z1, phi1, theta1, psi_e, u1, v1,
w1, p1, q1, r1]``; the controller maps y to u and carries the adaptive
states ``xc = [vec(W_hat), zeta_hat]``. The coordinates and what is left
out (planar positions, the vehicle's own dynamics) are explained in
``symbolic.linearization`` and ``docs/margins.md``.

Sign convention: ``u = K y`` is what the controller computes, so with the
loop broken at the plant input the return is ``K P``; in the negative
feedback convention of :mod:`quadland.analysis` the loop transfer is
``L = -K P`` (and ``-P K`` broken at the plant output).
"""

from __future__ import annotations

import dataclasses

import control
import numpy as np
import scipy.linalg

from quadland.constants import TILT_MIN
from quadland.exceptions import (
    MarginsError,
    OperatingPointError,
    ScenarioError,
    SingularAttitudeError,
)
from quadland.model import model_values
from quadland.scenario import Scenario
from symbolic.closed_loop import closed_loop_state
from symbolic.linearization import (
    RELATIVE_PLANT,
    VEHICLE_SPEEDS,
    controller_states,
    equilibrium_residual_function,
    linearization_function,
)
from symbolic.parameters import VEHICLE
from symbolic.quadrotor import DISTURBANCE
from symbolic.relative import VIRTUAL_INPUT
from symbolic.vehicle import STATE as VEHICLE_STATE

__all__ = ["LOOP_NAMES", "INPUT_NAMES", "OperatingPoint", "LinearModels", "equilibrium",
           "frozen_point", "linear_models", "sampled_models"]

#: The four loops, one per virtual input.
LOOP_NAMES = ("altitude", "roll", "pitch", "yaw")
#: Names of the virtual inputs u (eq. 6).
INPUT_NAMES = VIRTUAL_INPUT.element_names()


@dataclasses.dataclass(frozen=True)
class OperatingPoint:
    """Where the loop is linearized.

    Attributes
    ----------
    kind : str
        ``"equilibrium"`` (steady motion) or ``"frozen"`` (a simulated state).
    time : float or None
        s, the simulated time of a frozen point.
    xr : ndarray, shape (10,)
        Relative plant state (``symbolic.linearization.RELATIVE_PLANT``).
    xc : ndarray, shape (4 l + 4,)
        Adaptive states ``[vec(W_hat), zeta_hat]``.
    vehicle : ndarray, shape (3,)
        Vehicle surge, sway (m/s) and yaw rate r2 (rad/s).
    z2 : float
        m, deck altitude.
    w : ndarray, shape (6,)
        Disturbance ``[d_F (N), d_M (N m)]``.
    u : ndarray, shape (4,)
        Virtual input at the point.
    residual : float
        ``|d/dt [xr, xc]|`` at the point: ~0 at an equilibrium, the drift
        of a frozen point.
    iterations : int
        Newton iterations (0 for a frozen point).
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

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return dict(kind=self.kind, time_s=self.time,
                    state={n: float(v) for n, v in
                           zip(RELATIVE_PLANT.element_names(), self.xr, strict=True)},
                    zeta_hat=self.xc[-4:].tolist(),
                    norm_W_hat=float(np.linalg.norm(self.xc[:-4])),
                    vehicle=dict(u2=float(self.vehicle[0]), v2=float(self.vehicle[1]),
                                 r2=float(self.vehicle[2]), z2=self.z2),
                    disturbance=self.w.tolist(), u=self.u.tolist(), residual=self.residual,
                    newton_iterations=self.iterations)


@dataclasses.dataclass(frozen=True)
class LinearModels:
    """State-space models of the loop at one operating point.

    Attributes
    ----------
    point : OperatingPoint
    plant : control.StateSpace
        P: u (4) -> y (10), states xr.
    controller : control.StateSpace
        K: y (10) -> u (4), states xc (the adaptive states; sampled with hold
        compensation, also the law's previous output ``u_prev``).
    loop_input : control.StateSpace
        ``L_i = -K P`` (4 x 4), the loop broken at the plant input.
    loop_output : control.StateSpace
        ``L_o = -P K`` (10 x 10), the loop broken at the plant output.
    closed_loop : control.StateSpace
        States ``[xr, xc]``; input an additive disturbance at u, output y.
    dt : float
        0 for continuous time, else the sampling period (s).
    """

    point: OperatingPoint
    plant: control.StateSpace
    controller: control.StateSpace
    loop_input: control.StateSpace
    loop_output: control.StateSpace
    closed_loop: control.StateSpace
    dt: float = 0.0


def _constant_disturbance(scenario: Scenario) -> np.ndarray:
    d = scenario.data["disturbance"]
    return DISTURBANCE.pack(dict(d_F=d["force_bias"], d_M=d["moment_bias"]))


def equilibrium(scenario: Scenario, *, tol: float = 1e-9, max_iter: int = 50) -> OperatingPoint:
    """The closed loop's steady motion under the constant disturbance.

    Solves ``[xr_dot, xc_dot, vehicle speeds_dot] = 0`` by Newton's method
    with the exact symbolic Jacobian, from hover at the reference with
    zero adaptive states, halving steps that do not reduce the residual.

    Parameters
    ----------
    scenario : Scenario
    tol : float
        Convergence threshold on the residual's 2-norm.
    max_iter : int

    Raises
    ------
    OperatingPointError
        When Newton's method does not converge or the Jacobian is singular.
    """
    mv = model_values(scenario)
    l = mv.l
    F = equilibrium_residual_function(l)
    w = _constant_disturbance(scenario)
    xr0 = RELATIVE_PLANT.zeros()
    xr0[0:4] = mv.ref[0:4]                                   # hover at the reference e1d
    xr0[RELATIVE_PLANT.index("z1")] += VEHICLE.unpack(mv.p_veh)["z2"][0]
    nr, nc = RELATIVE_PLANT.size, controller_states(l).size
    xi = np.concatenate([xr0, np.zeros(nc), VEHICLE_SPEEDS.zeros()])

    def residual(x):
        r, J = F(x, w, mv.p_quad, mv.p_veh, mv.p_ctrl, mv.ref)
        return np.asarray(r, dtype=float).ravel(), np.asarray(J, dtype=float)

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
            break
    else:
        raise OperatingPointError(f"no equilibrium: Newton's method did not converge in "
                                  f"{max_iter} iterations (residual {norm:.3g})")
    return _point(scenario, "equilibrium", None, xi[:nr], xi[nr:nr + nc], xi[nr + nc:], w, it)


def frozen_point(scenario: Scenario, t: float) -> OperatingPoint:
    """The simulated closed-loop state at time ``t`` (s), frozen.

    Simulates the scenario up to ``t`` (nothing at ``t = 0``). The point
    is generally not an equilibrium: the linear models then describe the
    loop's local, frozen-time behaviour.
    """
    from quadland.scenario import MAX_DURATION_S, SCHEMA
    from quadland.simulate import (
        MAX_RK4_STEPS,
        MEMORY_BUDGET,
        check_plan,
        simulate,
        simulation_plan,
    )

    shortest = SCHEMA["simulation"]["duration"].lo
    if not (t == 0 or shortest <= t <= MAX_DURATION_S):
        raise MarginsError(f"at: must be 0 or in [{shortest:g}, {MAX_DURATION_S:g}] s, got {t:g}")
    mv = model_values(scenario)
    if t > 0:
        upto = scenario.replace(**{"simulation.duration": float(t)})
        try:
            check_plan(upto)
        except ScenarioError:
            plan = simulation_plan(upto)
            raise MarginsError(
                f"at: reaching {t:g} s takes {plan.rows:,} output rows "
                f"({plan.memory_bytes / 2**30:.1f} GiB) and {plan.rk4_steps:.2g} RK4 steps, "
                f"over the limits ({MEMORY_BUDGET / 2**30:g} GiB, {MAX_RK4_STEPS:.0e} steps)"
            ) from None
        res = simulate(upto)
        x = res.states[-1]
        w = np.array([res[k][-1] for k in DISTURBANCE.element_names()])
    else:
        from quadland.model import disturbance_samples
        x, w = mv.x0, disturbance_samples(scenario, np.zeros(1))[:, 0]
    xs = closed_loop_state(mv.l).unpack(x)
    xv = VEHICLE_STATE.unpack(xs["xv"])
    xr = xs["xq"].copy()
    xr[RELATIVE_PLANT.index("psi_e")] -= xv["psi2"][0]
    xc = np.concatenate([xs["W_hat"].ravel(order="F"), xs["zeta_hat"]])
    speeds = np.concatenate([xv[n] for n in VEHICLE_SPEEDS.names()])
    return _point(scenario, "frozen", float(t), xr, xc, speeds, w, 0)


def _point(scenario, kind, t, xr, xc, vehicle, w, iterations) -> OperatingPoint:
    mv = model_values(scenario)
    tilt = np.cos(xr[1]) * np.cos(xr[2])
    if abs(tilt) < TILT_MIN:
        raise SingularAttitudeError(f"operating point at cos(theta) cos(phi) = {tilt:.2e}: "
                                    "the thrust map is singular there")
    z2 = float(VEHICLE.unpack(mv.p_veh)["z2"][0])
    out = linearization_function(mv.l)(xr, xc, [z2, vehicle[2]], w, mv.p_quad, mv.p_ctrl,
                                       mv.ref)
    u, xr_dot, xc_dot = (np.asarray(v, dtype=float).ravel() for v in out[0:3])
    return OperatingPoint(kind, t, np.asarray(xr, float), np.asarray(xc, float),
                          np.asarray(vehicle, float), z2, np.asarray(w, float), u,
                          float(np.linalg.norm(np.r_[xr_dot, xc_dot])), iterations)


def _jacobians(scenario: Scenario, point: OperatingPoint):
    mv = model_values(scenario)
    out = linearization_function(mv.l)(point.xr, point.xc, [point.z2, point.vehicle[2]],
                                       point.w, mv.p_quad, mv.p_ctrl, mv.ref)
    return tuple(np.asarray(v, dtype=float) for v in out[3:9])


def _assemble(point, Ap, Bp, Ac, Bc, Cc, Dc, dt, n_hold=0) -> LinearModels:
    n, nc = Ap.shape[0], Ac.shape[0]
    m = Bp.shape[1]
    n_adapt = nc - n_hold
    xc_names = ([f"W_hat[{k}]" for k in range(n_adapt - 4)]
                + [f"zeta_hat[{k}]" for k in range(4)]
                + [f"u_prev[{k}]" for k in range(n_hold)])
    kw = dict(dt=dt) if dt else {}
    y_names = list(RELATIVE_PLANT.element_names())
    plant = control.ss(Ap, Bp, np.eye(n), np.zeros((n, m)), inputs=list(INPUT_NAMES),
                       outputs=y_names, states=y_names, name="plant", **kw)
    controller = control.ss(Ac, Bc, Cc, Dc, inputs=y_names, outputs=list(INPUT_NAMES),
                            states=xc_names, name="controller", **kw)
    states = y_names + xc_names
    A_i = np.block([[Ap, np.zeros((n, nc))], [Bc, Ac]])
    loop_input = control.ss(A_i, np.vstack([Bp, np.zeros((nc, m))]), -np.hstack([Dc, Cc]),
                            np.zeros((m, m)), inputs=list(INPUT_NAMES),
                            outputs=[f"{k}_return" for k in INPUT_NAMES], states=states,
                            name="loop_input", **kw)
    A_o = np.block([[Ac, np.zeros((nc, n))], [Bp @ Cc, Ap]])
    loop_output = control.ss(A_o, np.vstack([Bc, Bp @ Dc]),
                             np.hstack([np.zeros((n, nc)), -np.eye(n)]), np.zeros((n, n)),
                             inputs=y_names, outputs=[f"{k}_return" for k in y_names],
                             states=xc_names + y_names, name="loop_output", **kw)
    A_cl = np.block([[Ap + Bp @ Dc, Bp @ Cc], [Bc, Ac]])
    closed = control.ss(A_cl, np.vstack([Bp, np.zeros((nc, m))]),
                        np.hstack([np.eye(n), np.zeros((n, nc))]), np.zeros((n, m)),
                        inputs=list(INPUT_NAMES), outputs=y_names, states=states,
                        name="closed_loop", **kw)
    return LinearModels(point, plant, controller, loop_input, loop_output, closed, dt)


def linear_models(scenario: Scenario, point: OperatingPoint) -> LinearModels:
    """Continuous-time plant, controller, broken loops and closed loop at a point.

    Parameters
    ----------
    scenario : Scenario
    point : OperatingPoint
        From :func:`equilibrium` or :func:`frozen_point`.

    Returns
    -------
    LinearModels
        From the exact symbolic Jacobians of ``symbolic.linearization``.
    """
    return _assemble(point, *_jacobians(scenario, point), 0.0)


def _zoh(A, B, dt):
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def sampled_models(scenario: Scenario, point: OperatingPoint, rate_hz: float) -> LinearModels:
    """Sampled-data models: zero-order hold at ``rate_hz`` on both sides.

    The plant is discretized with its input u held (the held wrench of the
    sampled simulator, linearized); the controller's adaptive states with
    the measurement held over the period, which is exactly how
    ``symbolic.control_step`` integrates eq. (22). u is applied at the
    sample it is computed, with no computation delay. With
    ``controller.hold_compensation = kappa > 0`` the controller also holds
    the law's previous output ``u_prev`` (four more states) and commands
    ``(1 + kappa) u_law - kappa u_prev``, as the control step does.
    """
    if not rate_hz > 0:
        raise ValueError(f"sampled_models: rate_hz must be > 0, got {rate_hz}")
    Ap, Bp, Ac, Bc, Cc, Dc = _jacobians(scenario, point)
    dt = 1.0 / rate_hz
    Phi_p, Gam_p = _zoh(Ap, Bp, dt)
    Phi_c, Gam_c = _zoh(Ac, Bc, dt)
    kappa = float(scenario.data["controller"]["hold_compensation"])
    if kappa == 0:
        return _assemble(point, Phi_p, Gam_p, Phi_c, Gam_c, Cc, Dc, dt)
    m, nc = Cc.shape
    Phi_k = np.block([[Phi_c, np.zeros((nc, m))], [Cc, np.zeros((m, m))]])
    Gam_k = np.vstack([Gam_c, Dc])
    C_k = np.hstack([(1 + kappa) * Cc, -kappa * np.eye(m)])
    return _assemble(point, Phi_p, Gam_p, Phi_k, Gam_k, C_k, (1 + kappa) * Dc, dt, n_hold=m)

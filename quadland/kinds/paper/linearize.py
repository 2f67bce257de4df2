"""The paper's loop linearized: its equilibrium or a frozen state, and its linear models.

The loop is broken at the virtual input u of eq. (6). The plant maps u to
the measured relative state ``y = xr = [z1, phi1, theta1, psi_e, u1, v1, w1,
p1, q1, r1]``; the controller maps y to u and carries the adaptive states
``xc = [vec(W_hat), zeta_hat]``. The coordinates and what is left out
(planar positions, the vehicle's own dynamics) are explained in
``quadland_symbolic.linearization`` and ``docs/margins.md``. A sampled
controller sends its command one control period after it samples (flight
code computes during the period): :func:`paper_sampled_models` puts
``delay_periods`` unit delays on the command.
"""

from __future__ import annotations

import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.disturbance import disturbance_samples
from quadland.engine.plan import MAX_RK4_STEPS, MEMORY_BUDGET
from quadland.exceptions import MarginsError, ScenarioError, SingularAttitudeError
from quadland.kinds.paper.simulate import check_paper_plan, paper_plan, simulate_paper
from quadland.kinds.paper.values import model_values
from quadland.linear import (
    LinearModels,
    OperatingPoint,
    assemble,
    check_delay_periods,
    delayed,
    newton,
    zoh,
)
from quadland.scenario import Scenario
from quadland.schema import MAX_DURATION_S, PAPER_SCHEMA
from quadland_symbolic.backstepping import PAPER_REFERENCE
from quadland_symbolic.closed_loop import closed_loop_state
from quadland_symbolic.linearization import (
    FROZEN_VEHICLE,
    RELATIVE_PLANT,
    VEHICLE_SPEEDS,
    controller_states,
    equilibrium_residual_function,
    linearization_function,
)
from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE
from quadland_symbolic.relative import VIRTUAL_INPUT
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["LOOP_NAMES", "INPUT_NAMES", "paper_equilibrium", "check_frozen_time",
           "frozen_point", "paper_linear_models", "paper_sampled_models"]

#: The four loops of the paper's loop, one per virtual input.
LOOP_NAMES = ("altitude", "roll", "pitch", "yaw")
#: Names of the virtual inputs u (eq. 6).
INPUT_NAMES = VIRTUAL_INPUT.element_names()


def _constant_disturbance(scenario: Scenario) -> np.ndarray:
    d = scenario.data["disturbance"]
    return BODY_DISTURBANCE.pack(dict(d_F=d["force_bias"], d_M=d["moment_bias"]))


def paper_equilibrium(scenario: Scenario, *, tol: float = 1e-9,
                      max_iter: int = 50) -> OperatingPoint:
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
    e1d = PAPER_REFERENCE.unpack(mv.ref)["e1d"]              # hover at the reference e1d
    xr0[RELATIVE_PLANT.slice("z1")] = e1d[0]                 # e1 = [z_e, phi, theta, psi_e]
    xr0[RELATIVE_PLANT.slice("eta1")] = e1d[1:4]
    xr0[RELATIVE_PLANT.index("z1")] += VEHICLE.unpack(mv.p_veh)["z2"][0]
    nr, nc = RELATIVE_PLANT.size, controller_states(l).size
    xi = np.concatenate([xr0, np.zeros(nc), VEHICLE_SPEEDS.zeros()])

    def residual(x):
        r, J = F(x, w, mv.p_quad, mv.p_veh, mv.p_ctrl, mv.ref)
        return np.asarray(r, dtype=float).ravel(), np.asarray(J, dtype=float)

    xi, it = newton(residual, xi, tol, max_iter)
    return _point(scenario, "equilibrium", None, xi[:nr], xi[nr:nr + nc], xi[nr + nc:], w, it)


def check_frozen_time(scenario: Scenario, t: float) -> None:
    """Refuse, before any work, a time :func:`frozen_point` cannot reach.

    Raises
    ------
    MarginsError
        For a time out of range, or a run up to ``t`` over the simulator's
        limits; the message starts with ``"at: "``.
    """
    shortest = PAPER_SCHEMA["simulation"]["duration"].lo
    if not (t == 0 or shortest <= t <= MAX_DURATION_S):
        raise MarginsError(f"at: must be 0 or in [{shortest:g}, {MAX_DURATION_S:g}] s, got {t:g}")
    if t > 0:
        upto = scenario.replace(**{"simulation.duration": float(t)})
        try:
            check_paper_plan(upto)
        except ScenarioError:
            plan = paper_plan(upto)
            raise MarginsError(
                f"at: reaching {t:g} s takes {plan.rows:,} output rows "
                f"({plan.memory_bytes / 2**30:.1f} GiB) and {plan.rk4_steps:.2g} RK4 steps, "
                f"over the limits ({MEMORY_BUDGET / 2**30:g} GiB, {MAX_RK4_STEPS:.0e} steps)"
            ) from None


def frozen_point(scenario: Scenario, t: float) -> OperatingPoint:
    """The simulated closed-loop state at time ``t`` (s), frozen.

    Simulates the scenario up to ``t`` (nothing at ``t = 0``). The point
    is generally not an equilibrium: the linear models then describe the
    loop's local, frozen-time behaviour. The paper's loop only.
    """
    check_frozen_time(scenario, t)
    mv = model_values(scenario)
    if t > 0:
        res = simulate_paper(scenario.replace(**{"simulation.duration": float(t)}))
        x = res.states[-1]
        w = np.array([res[k][-1] for k in BODY_DISTURBANCE.element_names()])
    else:
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
    phi1, theta1, _ = RELATIVE_PLANT.unpack(np.asarray(xr, float))["eta1"]
    tilt = np.cos(phi1) * np.cos(theta1)
    if abs(tilt) < TILT_MIN:
        raise SingularAttitudeError(f"operating point at cos(theta) cos(phi) = {tilt:.2e}: "
                                    "the thrust map is singular there")
    z2 = float(VEHICLE.unpack(mv.p_veh)["z2"][0])
    frozen = FROZEN_VEHICLE.pack(dict(z2=z2, r2=VEHICLE_SPEEDS.unpack(vehicle)["r2"]))
    out = linearization_function(mv.l)(xr, xc, frozen, w, mv.p_quad, mv.p_ctrl, mv.ref)
    u, xr_dot, xc_dot = (np.asarray(v, dtype=float).ravel() for v in out[0:3])
    xc = np.asarray(xc, float)
    adaptive = controller_states(mv.l).unpack(xc)
    return OperatingPoint(kind, t, np.asarray(xr, float), xc, np.asarray(vehicle, float), z2,
                          np.asarray(w, float), u, float(np.linalg.norm(np.r_[xr_dot, xc_dot])),
                          iterations, "paper", RELATIVE_PLANT.element_names(),
                          dict(zeta_hat=adaptive["zeta_hat"].tolist(),
                               norm_W_hat=float(np.linalg.norm(adaptive["W_hat"]))))


def _jacobians(scenario: Scenario, point: OperatingPoint):
    mv = model_values(scenario)
    frozen = FROZEN_VEHICLE.pack(dict(z2=point.z2,
                                      r2=VEHICLE_SPEEDS.unpack(point.vehicle)["r2"]))
    out = linearization_function(mv.l)(point.xr, point.xc, frozen, point.w, mv.p_quad,
                                       mv.p_ctrl, mv.ref)
    return tuple(np.asarray(v, dtype=float) for v in out[3:9])


def _paper_names(n_adapt: int, n_hold: int = 0):
    y = list(RELATIVE_PLANT.element_names())
    return dict(x=y, y=y, u=list(INPUT_NAMES),
                c=([f"W_hat[{k}]" for k in range(n_adapt - 4)]
                   + [f"zeta_hat[{k}]" for k in range(4)]
                   + [f"u_prev[{k}]" for k in range(n_hold)]),
                loops=LOOP_NAMES)


def paper_linear_models(scenario: Scenario, point: OperatingPoint) -> LinearModels:
    """Continuous-time plant, controller, broken loops and closed loop at a point.

    From the exact symbolic Jacobians of ``quadland_symbolic.linearization``.
    """
    Ap, Bp, Ac, Bc, Cc, Dc = _jacobians(scenario, point)
    return assemble(point, Ap, Bp, np.eye(Ap.shape[0]), Ac, Bc, Cc, Dc, 0.0,
                    _paper_names(Ac.shape[0]))


def paper_sampled_models(scenario: Scenario, point: OperatingPoint, rate_hz: float,
                   delay_periods: int = 1) -> LinearModels:
    """Sampled-data models: zero-order hold at ``rate_hz``, with computation delay.

    The plant is discretized with its input u held (the held wrench of the
    sampled simulator, linearized). The paper's controller has its adaptive
    states integrated with the measurement held over the period, which is
    exactly how ``quadland_symbolic.control_step`` integrates eq. (22); with
    ``controller.hold_compensation = kappa > 0`` it also holds the law's
    previous output ``u_prev`` (four more states) and commands ``(1 + kappa)
    u_law - kappa u_prev``, as the control step does.

    Parameters
    ----------
    scenario : Scenario
    point : OperatingPoint
    rate_hz : float
        Control rate, Hz (> 0).
    delay_periods : int, optional
        Control periods from sampling to commanding (default 1): the
        command computed from the samples at ``t_k`` acts from
        ``t_(k + delay_periods)``, as flight code that computes during
        the period and sends at the next tick. Each period is a ``z^-1``
        on the command (four more controller states); 0 applies it at the
        sample, as the simulator does.
    """
    if not rate_hz > 0:
        raise ValueError(f"sampled_models: rate_hz must be > 0, got {rate_hz}")
    delay_periods = check_delay_periods(delay_periods)
    dt = 1.0 / rate_hz
    Ap, Bp, Ac, Bc, Cc, Dc = _jacobians(scenario, point)
    Phi_p, Gam_p = zoh(Ap, Bp, dt)
    Phi_c, Gam_c = zoh(Ac, Bc, dt)
    kappa = float(scenario.data["controller"]["hold_compensation"])
    Cp = np.eye(Ap.shape[0])
    if kappa == 0:
        K = delayed(Phi_c, Gam_c, Cc, Dc, delay_periods)
        return assemble(point, Phi_p, Gam_p, Cp, *K, dt, _paper_names(Ac.shape[0]),
                         delay_periods)
    m, nc = Cc.shape
    Phi_k = np.block([[Phi_c, np.zeros((nc, m))], [Cc, np.zeros((m, m))]])
    Gam_k = np.vstack([Gam_c, Dc])
    C_k = np.hstack([(1 + kappa) * Cc, -kappa * np.eye(m)])
    K = delayed(Phi_k, Gam_k, C_k, (1 + kappa) * Dc, delay_periods)
    return assemble(point, Phi_p, Gam_p, Cp, *K, dt, _paper_names(nc, n_hold=m),
                     delay_periods)

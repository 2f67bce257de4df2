"""Relative altitude-attitude model (eq. 5-7).

``e1 = [z1 - z2, phi1, theta1, psi1 - psi2]`` and
``e2 = [dz_e/dt, Omega_e]`` with ``Omega_e = Omega1 - Rr1^-1 [0, 0, r2]``
obey ``e1_dot = R e2`` (eq. 10) and ``e2_dot = f + u + d`` (eq. 7), where
``u = [cos(theta1) cos(phi1) F_total / m1, Mx/Ix, My/Iy, Mz/Iz]`` is the
virtual input. The vehicle measurement is ``yv = [z2, psi2, r2]``.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import euler_rate_matrix, euler_rate_matrix_inv, vertical_row
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE, WRENCH
from quadland_symbolic.vehicle import VEHICLE_MEASUREMENT, VEHICLE_STATE, yaw_acceleration

#: Units of the four channels: altitude, roll, pitch, yaw.
_CHANNEL_ACCEL = ("m/s^2", "rad/s^2", "rad/s^2", "rad/s^2")

#: Relative position e1 (eq. 5, 7).
E1 = Layout("e1", (Field("e1", 4, ("m", "rad", "rad", "rad"),
                         "relative altitude and attitude",
                         elements=("z_e", "phi_e", "theta_e", "psi_e")),))
#: Relative rates e2 (eq. 7).
E2 = Layout("e2", (Field("e2", 4, ("m/s", "rad/s", "rad/s", "rad/s"),
                         "relative vertical speed and body rates",
                         elements=("dz_e", "p_e", "q_e", "r_e")),))
#: Virtual input u (eq. 6).
VIRTUAL_INPUT = Layout("u", (Field("u", 4, _CHANNEL_ACCEL, "virtual inputs (eq. 6)",
                                   elements=("u_1", "u_2", "u_3", "u_4")),))

__all__ = [
    "E1",
    "E2",
    "VIRTUAL_INPUT",
    "relative_states",
    "tilt",
    "error_rate_matrix",
    "nominal_drift",
    "relative_drift",
    "virtual_input",
    "wrench_from_virtual",
    "disturbance_input",
    "relative_function",
]


def relative_states(xq, yv):
    """Relative states e1 and e2 (eq. 5, 7) from measured states.

    ``w2 = 0``: the vehicle does not heave.
    """
    q, v = QUAD_STATE.unpack(xq), VEHICLE_MEASUREMENT.unpack(yv)
    z1, eta1, V1, Omega1 = q["z1"], q["eta1"], q["V1"], q["Omega1"]
    z2, psi2, r2 = v["z2"], v["psi2"], v["r2"]
    e1 = ca.vertcat(z1 - z2, eta1[0], eta1[1], eta1[2] - psi2)
    Omega_e = Omega1 - euler_rate_matrix_inv(eta1) @ ca.vertcat(0, 0, r2)
    e2 = ca.vertcat(vertical_row(eta1) @ V1, Omega_e)
    return e1, e2


def tilt(eta1):
    """cos(theta1) cos(phi1): the thrust's share along E's z (eq. 6); the thrust map
    divides by it."""
    return ca.cos(eta1[0]) * ca.cos(eta1[1])


def error_rate_matrix(eta1):
    """R = diag(1, Rr1) of eq. (10), so that e1_dot = R e2."""
    return ca.diagcat(1, euler_rate_matrix(eta1))


def nominal_drift(xq, p_quad):
    """The quadrotor's own part of f (eq. 6): gravity, drag, gyroscopic terms."""
    p = QUADROTOR.unpack(p_quad)
    m1, I, Kt, Kr, g_s = p["m1"], p["I"], p["Kt"], p["Kr"], p["g"]
    q = QUAD_STATE.unpack(xq)
    eta1, V1, Omega1 = q["eta1"], q["V1"], q["Omega1"]
    Ix, Iy, Iz = I[0], I[1], I[2]
    p1, q1, r1 = Omega1[0], Omega1[1], Omega1[2]
    f1 = -(vertical_row(eta1) @ (Kt * V1)) / m1 - g_s
    gyro = ca.vertcat((Iz - Iy) * q1 * r1 / Ix, (Ix - Iz) * p1 * r1 / Iy, (Iy - Ix) * p1 * q1 / Iz)
    f2 = -Kr * Omega1 / I - gyro
    return ca.vertcat(f1, f2)


def relative_drift(xq, xv, p_quad, p_veh):
    """f of eq. (6), the drift of the relative model.

    The vehicle terms are ``-Rr12_dot [0, 0, r2] - Rr12 [0, 0, r2_dot]``
    with ``Rr12 = Rr1^-1``; ``Rr12_dot`` is differentiated symbolically
    along ``eta1_dot = Rr1 Omega1``.
    """
    q, v = QUAD_STATE.unpack(xq), VEHICLE_STATE.unpack(xv)
    eta1, Omega1 = q["eta1"], q["Omega1"]
    u2, v2, r2 = v["u2"], v["v2"], v["r2"]
    eta = ca.SX.sym("eta", 3)
    coupling = ca.Function("coupling", [eta], [euler_rate_matrix_inv(eta)[:, 2]])
    # d/dt (Rr12[:, 2]) r2 = (d Rr12[:, 2] / d eta1) eta1_dot r2
    col_dot = ca.jtimes(coupling(eta), eta, euler_rate_matrix(eta1) @ Omega1)
    col_dot = ca.substitute(col_dot, eta, eta1)
    r2_dot = yaw_acceleration(u2, v2, r2, p_veh)
    vehicle_terms = -col_dot * r2 - euler_rate_matrix_inv(eta1)[:, 2] * r2_dot
    return nominal_drift(xq, p_quad) + ca.vertcat(0, vehicle_terms)


def virtual_input(xq, wrench, p_quad):
    """Virtual input u of eq. (6) produced by a wrench."""
    p = QUADROTOR.unpack(p_quad)
    eta1, wr = QUAD_STATE.unpack(xq)["eta1"], WRENCH.unpack(wrench)
    u1 = tilt(eta1) * wr["F_total"] / p["m1"]
    return ca.vertcat(u1, wr["M"] / p["I"])


def wrench_from_virtual(xq, u, p_quad):
    """Wrench ``[F_total, Mx, My, Mz]`` that realises a virtual input u.

    Singular where ``cos(theta1) cos(phi1) = 0``; callers guard that.
    """
    p = QUADROTOR.unpack(p_quad)
    F_total = p["m1"] * u[0] / tilt(QUAD_STATE.unpack(xq)["eta1"])
    return ca.vertcat(F_total, p["I"] * u[1:4])


def disturbance_input(xq, d_F, d_M, p_quad):
    """d of eq. (6): ``[J d_F / m1, d_M / I]``."""
    p = QUADROTOR.unpack(p_quad)
    eta1 = QUAD_STATE.unpack(xq)["eta1"]
    return ca.vertcat(vertical_row(eta1) @ d_F / p["m1"], d_M / p["I"])


def relative_function() -> ca.Function:
    """``relative(xq, xv, yv, wrench, d_F, d_M, p_quad, p_veh) -> (e1, e2, R, f, u, d)``."""
    xq, xv, yv = QUAD_STATE.sym(), VEHICLE_STATE.sym(), VEHICLE_MEASUREMENT.sym()
    wrench, (d_F, d_M) = WRENCH.sym(), BODY_DISTURBANCE.syms()
    p_quad, p_veh = QUADROTOR.sym(), VEHICLE.sym()
    e1, e2 = relative_states(xq, yv)
    return ca.Function(
        "relative",
        [xq, xv, yv, wrench, d_F, d_M, p_quad, p_veh],
        [e1, e2, error_rate_matrix(QUAD_STATE.unpack(xq)["eta1"]),
         relative_drift(xq, xv, p_quad, p_veh),
         virtual_input(xq, wrench, p_quad), disturbance_input(xq, d_F, d_M, p_quad)],
        ["xq", "xv", "yv", "wrench", "d_F", "d_M", "p_quad", "p_veh"],
        ["e1", "e2", "R", "f", "u", "d"],
    )

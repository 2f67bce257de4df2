"""Relative altitude-attitude model (eq. 5-7).

``e1 = [z1 - z2, phi1, theta1, psi1 - psi2]`` and
``e2 = [dz_e/dt, Omega_e]`` with ``Omega_e = Omega1 - Rr1^-1 [0, 0, r2]``
obey ``e1_dot = R e2`` (eq. 10) and ``e2_dot = f + u + d`` (eq. 7), where
``u = [cos(theta1) cos(phi1) F_total / m1, Mx/Ix, My/Iy, Mz/Iz]`` is the
virtual input. The vehicle measurement is ``yv = [z2, psi2, r2]``.
"""

from __future__ import annotations

import casadi as ca

from symbolic.kinematics import euler_rate_matrix, euler_rate_matrix_inv, vertical_row
from symbolic.parameters import QUADROTOR, VEHICLE
from symbolic.vehicle import yaw_acceleration

__all__ = [
    "relative_states",
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
    z1, eta1, V1, Omega1 = xq[0], xq[1:4], xq[4:7], xq[7:10]
    z2, psi2, r2 = yv[0], yv[1], yv[2]
    e1 = ca.vertcat(z1 - z2, eta1[0], eta1[1], eta1[2] - psi2)
    Omega_e = Omega1 - euler_rate_matrix_inv(eta1) @ ca.vertcat(0, 0, r2)
    e2 = ca.vertcat(vertical_row(eta1) @ V1, Omega_e)
    return e1, e2


def error_rate_matrix(eta1):
    """R = diag(1, Rr1) of eq. (10), so that e1_dot = R e2."""
    return ca.diagcat(1, euler_rate_matrix(eta1))


def nominal_drift(xq, p_quad):
    """The quadrotor's own part of f (eq. 6): gravity, drag, gyroscopic terms."""
    p = QUADROTOR.unpack(p_quad)
    m1, I, Kt, Kr, g_s = p["m1"], p["I"], p["Kt"], p["Kr"], p["g"]
    eta1, V1, Omega1 = xq[1:4], xq[4:7], xq[7:10]
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
    eta1, Omega1 = xq[1:4], xq[7:10]
    u2, v2, r2 = xv[3], xv[4], xv[5]
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
    phi1, theta1 = xq[1], xq[2]
    u1 = ca.cos(theta1) * ca.cos(phi1) * wrench[0] / p["m1"]
    return ca.vertcat(u1, wrench[1:4] / p["I"])


def wrench_from_virtual(xq, u, p_quad):
    """Wrench ``[F_total, Mx, My, Mz]`` that realises a virtual input u.

    Singular where ``cos(theta1) cos(phi1) = 0``; callers guard that.
    """
    p = QUADROTOR.unpack(p_quad)
    phi1, theta1 = xq[1], xq[2]
    F_total = p["m1"] * u[0] / (ca.cos(theta1) * ca.cos(phi1))
    return ca.vertcat(F_total, p["I"] * u[1:4])


def disturbance_input(xq, d_F, d_M, p_quad):
    """d of eq. (6): ``[J d_F / m1, d_M / I]``."""
    p = QUADROTOR.unpack(p_quad)
    eta1 = xq[1:4]
    return ca.vertcat(vertical_row(eta1) @ d_F / p["m1"], d_M / p["I"])


def relative_function() -> ca.Function:
    """``relative(xq, xv, yv, wrench, d_F, d_M, p_quad, p_veh) -> (e1, e2, R, f, u, d)``."""
    xq, xv, yv = ca.SX.sym("xq", 10), ca.SX.sym("xv", 6), ca.SX.sym("yv", 3)
    wrench, d_F, d_M = ca.SX.sym("wrench", 4), ca.SX.sym("d_F", 3), ca.SX.sym("d_M", 3)
    p_quad, p_veh = QUADROTOR.sym(), VEHICLE.sym()
    e1, e2 = relative_states(xq, yv)
    return ca.Function(
        "relative",
        [xq, xv, yv, wrench, d_F, d_M, p_quad, p_veh],
        [e1, e2, error_rate_matrix(xq[1:4]), relative_drift(xq, xv, p_quad, p_veh),
         virtual_input(xq, wrench, p_quad), disturbance_input(xq, d_F, d_M, p_quad)],
        ["xq", "xv", "yv", "wrench", "d_F", "d_M", "p_quad", "p_veh"],
        ["e1", "e2", "R", "f", "u", "d"],
    )

"""Quadrotor rigid-body model (eq. 1-2) and its rotor mixer.

State ``xq = [z1, phi1, theta1, psi1, u1, v1, w1, p1, q1, r1]``: altitude
(m, E, z up), ZYX Euler angles (rad), body velocity V1 (m/s) and body rates
Omega1 (rad/s). The wrench is ``[F_total, Mx, My, Mz]`` (N, N m).
"""

from __future__ import annotations

import casadi as ca

from symbolic.kinematics import euler_rate_matrix, skew, vertical_row
from symbolic.parameters import QUADROTOR

__all__ = [
    "STATE_NAMES",
    "quadrotor_rhs",
    "mixer_matrix",
    "wrench_from_rotors",
    "rotors_from_wrench",
    "quadrotor_function",
    "mixer_function",
]

STATE_NAMES = ("z1", "phi1", "theta1", "psi1", "u1", "v1", "w1", "p1", "q1", "r1")


def quadrotor_rhs(xq, wrench, d_F, d_M, p_quad):
    """Time derivative of the quadrotor state (eq. 1-2).

    ``m1 V1_dot + S(Omega1) m1 V1 = F - Kt V1 - m1 R^T g + d_F`` and
    ``I1 Omega1_dot + S(Omega1) I1 Omega1 = T - Kr Omega1 + d_M``, with
    gravity ``g = [0, 0, g_s]`` pointing down in E (z up).
    """
    p = QUADROTOR.unpack(p_quad)
    m1, I, Kt, Kr, g_s = p["m1"], p["I"], p["Kt"], p["Kr"], p["g"]
    eta1, V1, Omega1 = xq[1:4], xq[4:7], xq[7:10]
    R_T_g = g_s * vertical_row(eta1).T                        # R^T [0, 0, g_s]
    F = ca.vertcat(0, 0, wrench[0])                           # N, body z
    T = wrench[1:4]                                           # N m
    z1_dot = vertical_row(eta1) @ V1                          # eq. 1
    eta1_dot = euler_rate_matrix(eta1) @ Omega1               # eq. 1
    V1_dot = -skew(Omega1) @ V1 + (F - Kt * V1 + d_F) / m1 - R_T_g              # eq. 2
    Omega1_dot = (T - Kr * Omega1 + d_M - skew(Omega1) @ (I * Omega1)) / I      # eq. 2
    return ca.vertcat(z1_dot, eta1_dot, V1_dot, Omega1_dot)


def mixer_matrix(p_quad):
    """The 4x4 map from rotor forces F1..F4 to the wrench (under eq. 2).

    ``F_total = sum F_i``, ``Mx = d (F2 - F4)``, ``My = d (F3 - F1)``,
    ``Mz = c (F1 - F2 + F3 - F4)``.
    """
    p = QUADROTOR.unpack(p_quad)
    d, c = p["arm"], p["c"]
    return ca.vertcat(
        ca.horzcat(1, 1, 1, 1),
        ca.horzcat(0, d, 0, -d),
        ca.horzcat(-d, 0, d, 0),
        ca.horzcat(c, -c, c, -c),
    )


def wrench_from_rotors(rotor, p_quad):
    """Wrench ``[F_total, Mx, My, Mz]`` produced by rotor forces."""
    return mixer_matrix(p_quad) @ rotor


def rotors_from_wrench(wrench, p_quad):
    """Rotor forces F1..F4 that produce a wrench (closed-form inverse).

    The mixer has the closed-form inverse
    ``F1 = T/4 - My/(2d) + Mz/(4c)``, ``F2 = T/4 + Mx/(2d) - Mz/(4c)``,
    ``F3 = T/4 + My/(2d) + Mz/(4c)``, ``F4 = T/4 - Mx/(2d) - Mz/(4c)``.
    """
    p = QUADROTOR.unpack(p_quad)
    d, c = p["arm"], p["c"]
    T, Mx, My, Mz = wrench[0], wrench[1], wrench[2], wrench[3]
    return ca.vertcat(
        T / 4 - My / (2 * d) + Mz / (4 * c),
        T / 4 + Mx / (2 * d) - Mz / (4 * c),
        T / 4 + My / (2 * d) + Mz / (4 * c),
        T / 4 - Mx / (2 * d) - Mz / (4 * c),
    )


def quadrotor_function() -> ca.Function:
    """``quadrotor(xq, wrench, d_F, d_M, p_quad) -> xq_dot`` (eq. 1-2)."""
    xq = ca.SX.sym("xq", 10)
    wrench = ca.SX.sym("wrench", 4)
    d_F, d_M = ca.SX.sym("d_F", 3), ca.SX.sym("d_M", 3)
    p_quad = QUADROTOR.sym()
    return ca.Function(
        "quadrotor", [xq, wrench, d_F, d_M, p_quad],
        [quadrotor_rhs(xq, wrench, d_F, d_M, p_quad)],
        ["xq", "wrench", "d_F", "d_M", "p_quad"], ["xq_dot"],
    )


def mixer_function() -> ca.Function:
    """``mixer(rotor, wrench, p_quad) -> (wrench_of_rotor, rotor_of_wrench)``."""
    rotor, wrench, p_quad = ca.SX.sym("rotor", 4), ca.SX.sym("wrench", 4), QUADROTOR.sym()
    return ca.Function(
        "mixer", [rotor, wrench, p_quad],
        [wrench_from_rotors(rotor, p_quad), rotors_from_wrench(wrench, p_quad)],
        ["rotor", "wrench", "p_quad"], ["wrench_of_rotor", "rotor_of_wrench"],
    )

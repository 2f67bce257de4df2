"""Quadrotor rigid-body model (eq. 1-2) and its rotor mixer.

State ``xq`` (layout :data:`QUAD_STATE`): altitude z1 (m, E, z up), ZYX Euler
angles eta1 (rad), body velocity V1 (m/s) and body rates Omega1 (rad/s).
The wrench is ``[F_total, M_x, M_y, M_z]`` (N, N m, layout :data:`WRENCH`),
the rotor forces ``F_1..F_4`` (N, :data:`ROTORS`) and the disturbance
``[d_F, d_M]`` (N, N m, :data:`BODY_DISTURBANCE`).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import euler_rate_matrix, skew, vertical_row
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR

__all__ = [
    "QUAD_STATE",
    "WRENCH",
    "ROTORS",
    "BODY_DISTURBANCE",
    "quadrotor_rhs",
    "mixer_matrix",
    "wrench_from_rotors",
    "rotors_from_wrench",
    "quadrotor_function",
    "mixer_function",
]

#: The quadrotor's state xq (eq. 1-2).
QUAD_STATE = Layout("xq", (
    Field("z1", 1, "m", "altitude in E (z up)"),
    Field("eta1", 3, "rad", "ZYX Euler angles roll, pitch, yaw",
          elements=("phi1", "theta1", "psi1")),
    Field("V1", 3, "m/s", "body velocity", elements=("u1", "v1", "w1")),
    Field("Omega1", 3, "rad/s", "body rates", elements=("p1", "q1", "r1")),
), "measured quadrotor state: Earth frame z up, ZYX Euler angles")

#: Thrust and moments in the body frame (eq. 2).
WRENCH = Layout("wrench", (
    Field("F_total", 1, "N", "total thrust along body z"),
    Field("M", 3, "N m", "body moments", elements=("M_x", "M_y", "M_z")),
), "thrust and body moments")

#: The four rotor forces (under eq. 2).
ROTORS = Layout("rotor", (
    Field("F", 4, "N", "rotor forces", elements=("F_1", "F_2", "F_3", "F_4")),
), "rotor forces")

#: External disturbance on the quadrotor, body frame (eq. 2).
BODY_DISTURBANCE = Layout("w", (
    Field("d_F", 3, "N", "disturbance force", elements=("d_Fx", "d_Fy", "d_Fz")),
    Field("d_M", 3, "N m", "disturbance moment", elements=("d_Mx", "d_My", "d_Mz")),
), "disturbance force and moment, body frame")


def quadrotor_rhs(xq, wrench, d_F, d_M, p_quad):
    """Time derivative of the quadrotor state (eq. 1-2).

    ``m1 V1_dot + S(Omega1) m1 V1 = F - Kt V1 - m1 R^T g + d_F`` and
    ``I1 Omega1_dot + S(Omega1) I1 Omega1 = T - Kr Omega1 + d_M``, with
    gravity ``g = [0, 0, g_s]`` pointing down in E (z up).
    """
    p = QUADROTOR.unpack(p_quad)
    m1, I, Kt, Kr, g_s = p["m1"], p["I"], p["Kt"], p["Kr"], p["g"]
    x = QUAD_STATE.unpack(xq)
    eta1, V1, Omega1 = x["eta1"], x["V1"], x["Omega1"]
    R_T_g = g_s * vertical_row(eta1).T                        # R^T [0, 0, g_s]
    wr = WRENCH.unpack(wrench)
    F = ca.vertcat(0, 0, wr["F_total"])                       # N, body z
    T = wr["M"]                                               # N m
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
    wr = WRENCH.unpack(wrench)
    T, Mx, My, Mz = wr["F_total"], wr["M"][0], wr["M"][1], wr["M"][2]
    return ca.vertcat(
        T / 4 - My / (2 * d) + Mz / (4 * c),
        T / 4 + Mx / (2 * d) - Mz / (4 * c),
        T / 4 + My / (2 * d) + Mz / (4 * c),
        T / 4 - Mx / (2 * d) - Mz / (4 * c),
    )


def quadrotor_function() -> ca.Function:
    """``quadrotor(xq, wrench, d_F, d_M, p_quad) -> xq_dot`` (eq. 1-2)."""
    xq, wrench = QUAD_STATE.sym(), WRENCH.sym()
    d_F, d_M = BODY_DISTURBANCE.syms()
    p_quad = QUADROTOR.sym()
    return ca.Function(
        "quadrotor", [xq, wrench, d_F, d_M, p_quad],
        [quadrotor_rhs(xq, wrench, d_F, d_M, p_quad)],
        ["xq", "wrench", "d_F", "d_M", "p_quad"], ["xq_dot"],
    )


def mixer_function() -> ca.Function:
    """``mixer(rotor, wrench, p_quad) -> (wrench_of_rotor, rotor_of_wrench)``."""
    rotor, wrench, p_quad = ROTORS.sym(), WRENCH.sym(), QUADROTOR.sym()
    return ca.Function(
        "mixer", [rotor, wrench, p_quad],
        [wrench_from_rotors(rotor, p_quad), rotors_from_wrench(wrench, p_quad)],
        ["rotor", "wrench", "p_quad"], ["wrench_of_rotor", "rotor_of_wrench"],
    )

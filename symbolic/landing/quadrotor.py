"""The 6-DOF quadrotor in E with first-order motors (eq. 1-2).

State ``x1q`` (:data:`QUAD6_STATE`): position p1 in E (m, z up), ZYX Euler angles
eta1 (rad), body velocity V1 (m/s), body rates Omega1 (rad/s) and the four
rotor forces F (N), which lag their commands. Eq. (2) is the paper's, reused
from :func:`quadland_symbolic.quadrotor.quadrotor_rhs`; eq. (1) gains the horizontal
rows, ``p1_dot = R(eta1) V1``.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, quadrotor_rhs, wrench_from_rotors

__all__ = [
    "QUAD6_STATE",
    "ACTUATOR",
    "COMMAND",
    "saturate",
    "quadrotor6_rhs",
    "quadrotor6_function",
]

_ROTOR_NAMES = ("F_1", "F_2", "F_3", "F_4")

#: The 6-DOF quadrotor's state x1q.
QUAD6_STATE = Layout("x1q", (
    Field("p1", 3, "m", "position in E (z up)", elements=("x1", "y1", "z1")),
    Field("eta1", 3, "rad", "ZYX Euler angles roll, pitch, yaw",
          elements=("phi1", "theta1", "psi1")),
    Field("V1", 3, "m/s", "body velocity", elements=("u1", "v1", "w1")),
    Field("Omega1", 3, "rad/s", "body rates", elements=("p1", "q1", "r1")),
    Field("F", 4, "N", "rotor forces (motor states)", elements=_ROTOR_NAMES),
), "6-DOF quadrotor: Earth frame z up, ZYX Euler angles, rotor forces")

#: Motors and landing gear.
ACTUATOR = Layout("p_act", (
    Field("motor_time_constant", 1, "s", "first-order lag tau_m of each rotor force"),
    Field("F_max", 1, "N", "largest force of one rotor"),
    Field("gear_height", 1, "m", "depth of the landing gear's lowest point below the centre"),
    Field("drag_quadratic", 3, "N s^2/m^2", "the body's quadratic (bluff-body) drag, body axes "
          "(quadland_symbolic.landing.aero)", elements=("Kq1", "Kq2", "Kq3")),
    Field("rotor_radius", 1, "m", "rotor radius R of the ground effect (0: none)"),
    Field("air_density", 1, "kg/m^3", "air density rho of the ground effect's induced velocity"),
    Field("rotor_efficiency", 4, "-", "force each rotor makes per newton commanded (1: as "
          "modelled; a damaged rotor less)", elements=tuple(f"eff_{n}" for n in _ROTOR_NAMES)),
    Field("cg_offset", 3, "m", "centre of gravity from the rotors' centre, body axes (0: "
          "centred)", elements=("cg_x", "cg_y", "cg_z")),
), "actuator, landing-gear and aerodynamic constants, and the airframe's departures from its model")

#: The rotor force commands, the plant's control input.
COMMAND = Layout("F_cmd", (
    Field("F_cmd", 4, "N", "rotor force commands",
          elements=tuple(f"{n}_cmd" for n in _ROTOR_NAMES)),
), "rotor force commands")


def saturate(F_cmd, p_act):
    """The command a motor can follow: clipped to ``[0, F_max]``.

    ``fmax``/``fmin`` return their non-NaN argument, so a NaN command reads
    as 0 (the motor winds down) and the plant stays finite for any command.
    """
    return ca.fmin(ca.fmax(F_cmd, 0), ACTUATOR.unpack(p_act)["F_max"])


def quadrotor6_rhs(x1q, F_cmd, d_F, d_M, p_quad, p_act):
    """Time derivative of the 6-DOF quadrotor state (eq. 1-2, motor lag).

    ``p1_dot = R(eta1) V1`` (eq. 1, all three rows: its last is J V1);
    ``eta1_dot``, ``V1_dot``, ``Omega1_dot`` are eq. (1)-(2) with the wrench
    of the actual rotor forces through the mixer;
    ``F_dot = (e sat(F_cmd) - F) / tau_m`` with each rotor's efficiency ``e``
    (1 as modelled). A centre of gravity ``r`` off the rotors' centre (body
    axes) adds the thrust's moment about it, ``-r x T e_z = T [-r_y, r_x, 0]``
    (the inertia and the drag's point of action are left as they are).
    ``d_F``, ``d_M``: body frame.
    """
    x, act = QUAD6_STATE.unpack(x1q), ACTUATOR.unpack(p_act)
    p1, eta1, V1, Omega1, F = x["p1"], x["eta1"], x["V1"], x["Omega1"], x["F"]
    tau_m = act["motor_time_constant"]                                    # s
    wrench = wrench_from_rotors(F, p_quad)                                # under eq. 2
    # thrust T e_z acts at the rotors' centre, r from the centre of gravity: + (-r) x T e_z
    r = act["cg_offset"]
    d_M_cg = wrench[0] * ca.vertcat(-r[1], r[0], 0)
    xq_dot = quadrotor_rhs(ca.vertcat(p1[2], eta1, V1, Omega1), wrench, d_F, d_M + d_M_cg,
                           p_quad)
    p1_dot = rotation(eta1) @ V1                                          # eq. 1
    F_dot = (act["rotor_efficiency"] * saturate(F_cmd, p_act) - F) / tau_m  # motor lag
    return ca.vertcat(p1_dot, xq_dot[1:], F_dot)


def quadrotor6_function() -> ca.Function:
    """``quadrotor6(x1q, F_cmd, d_F, d_M, p_quad, p_act) -> x1q_dot`` (eq. 1-2)."""
    x1q, F_cmd = QUAD6_STATE.sym(), COMMAND.sym()
    d_F, d_M = BODY_DISTURBANCE.syms()
    p_quad, p_act = QUADROTOR.sym(), ACTUATOR.sym()
    return ca.Function(
        "quadrotor6", [x1q, F_cmd, d_F, d_M, p_quad, p_act],
        [quadrotor6_rhs(x1q, F_cmd, d_F, d_M, p_quad, p_act)],
        ["x1q", "F_cmd", "d_F", "d_M", "p_quad", "p_act"], ["x1q_dot"],
    )

"""The quadrotor relative to the deck, in the deck frame (eq. 5-6 in 6-DOF).

``p_e = R_deck^T (p1 - p2)`` is the quadrotor's centre seen from the pad
centre, in deck axes (``x_e, y_e, z_e``); ``v_e`` and ``a_e`` are its first
and second time derivatives *in the deck frame* (what a deck-mounted observer
measures), taken symbolically along both bodies' motion, so the transport,
Coriolis, centripetal and deck-rotation terms are never written by hand. The
attitude follows eq. (5): ``eta_e = eta1 - eta2`` and
``Omega_e = Omega1 - Rr1^-1 eta2_dot`` (with ``eta2 = [0, 0, psi2]`` this is
eq. 5's ``Omega1 - Rr1^-1 [0, 0, r2]``), so that ``eta_e_dot = Rr1 Omega_e``.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import euler_rate_matrix_inv, rotation
from quadland_symbolic.landing.deck import DECK_PARAMS, deck_pose, time_derivative, vehicle_motion
from quadland_symbolic.landing.quadrotor import ACTUATOR, COMMAND, QUAD6_STATE, quadrotor6_rhs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["TOUCHDOWN_LIMITS",
    "RELATIVE6",
    "RELATIVE6_ACCELERATION",
    "relative6",
    "relative6_acceleration",
    "gear_gap",
    "deck_gear_gap",
    "TOUCHDOWN_FIGURES",
    "touchdown_figures",
    "touchdown_figures_function",
    "relative6_function",
    "relative6_acceleration_function",
]

#: Outputs of :func:`relative6_function`, in order.
RELATIVE6 = Layout("rel6", (
    Field("p_e", 3, "m", "quadrotor centre from the pad centre, deck frame",
          elements=("x_e", "y_e", "z_e")),
    Field("v_e", 3, "m/s", "d/dt p_e (rate seen in the deck frame)",
          elements=("dx_e", "dy_e", "dz_e")),
    Field("eta_e", 3, "rad", "relative attitude eta1 - eta2",
          elements=("phi_e", "theta_e", "psi_e")),
    Field("Omega_e", 3, "rad/s", "relative body rates Omega1 - Rr1^-1 eta2_dot",
          elements=("p_e", "q_e", "r_e")),
    Field("gear_gap", 1, "m", "landing gear above the deck plane, along its normal"),
), "relative state in the deck frame")

#: Outputs of :func:`relative6_acceleration_function`, in order.
RELATIVE6_ACCELERATION = Layout("acc6", (
    Field("a_e", 3, "m/s^2", "d^2/dt^2 p_e (in the deck frame)",
          elements=("ddx_e", "ddy_e", "ddz_e")),
    Field("Omega_e_dot", 3, "rad/s^2", "d/dt Omega_e",
          elements=("dp_e", "dq_e", "dr_e")),
), "relative accelerations")

#: How a touchdown went: the figures of summary.json's ``landing`` object.
TOUCHDOWN_FIGURES = Layout("touchdown", (
    Field("sink_rate", 1, "m/s", "-dz_e: the centre's speed towards the deck, along its normal"),
    Field("offset", 1, "m", "hypot(x_e, y_e): horizontal distance from the pad centre"),
    Field("relative_speed", 1, "m/s", "hypot(dx_e, dy_e): horizontal relative speed"),
    Field("tilt_deg", 1, "deg", "angle between the body z axis and the deck normal"),
), "touchdown figures, deck frame")

#: The limits a touchdown is held to (a landing scenario's ``[landing]`` keys), in
#: the report's order: each is ``max_`` and the name of a :data:`TOUCHDOWN_FIGURES`.
TOUCHDOWN_LIMITS = tuple(f"max_{n}" for n in ("sink_rate", "offset", "tilt_deg",
                                               "relative_speed"))
assert {n.removeprefix("max_") for n in TOUCHDOWN_LIMITS} == set(TOUCHDOWN_FIGURES.names())

_PARAM_NAMES = ["p_quad", "p_act", "p_veh", "p_deck"]


def deck_gear_gap(p_e, R_deck, R1, gear_height):
    """The gear's height above the deck plane from the relative position and both attitudes.

    ``n2 . (p1 - gear_height R1 e_z - p2) = z_e - gear_height n2 . (R1 e_z)``
    with ``n2 = R_deck e_z``, since ``z_e = n2 . (p1 - p2)``: what the
    simulator's touchdown event and the flight code's guidance both compute
    (the latter from the landing sensor, the IMU and the deck's attitude).
    """
    return p_e[2] - gear_height * (R_deck[:, 2].T @ R1[:, 2])


def touchdown_figures(p_e, v_e, eta1, eta2):
    """:data:`TOUCHDOWN_FIGURES` of a contact: sink rate, offset, relative speed, tilt.

    The tilt is ``acos(n1 . n2)`` with ``n1 = R(eta1) e_z`` and ``n2 =
    R(eta2) e_z`` (the argument clipped to [-1, 1]), in degrees.
    """
    cos_tilt = rotation(eta1)[:, 2].T @ rotation(eta2)[:, 2]
    return ca.vertcat(-v_e[2], ca.hypot(p_e[0], p_e[1]), ca.hypot(v_e[0], v_e[1]),
                      180 / ca.pi * ca.acos(ca.fmin(ca.fmax(cos_tilt, -1), 1)))


@functools.cache
def touchdown_figures_function() -> ca.Function:
    """``touchdown_figures(p_e, v_e, eta1, eta2) -> figures`` (:data:`TOUCHDOWN_FIGURES`)."""
    p_e, v_e, eta1, eta2 = (ca.SX.sym(n, 3) for n in ("p_e", "v_e", "eta1", "eta2"))
    return ca.Function("touchdown_figures", [p_e, v_e, eta1, eta2],
                       [touchdown_figures(p_e, v_e, eta1, eta2)],
                       ["p_e", "v_e", "eta1", "eta2"], ["figures"])


def _param_syms():
    return [QUADROTOR.sym(), ACTUATOR.sym(), VEHICLE.sym(), DECK_PARAMS.sym()]


def _relative_pose(x1q, xv, t, p_act, p_veh, p_deck):
    """p_e, eta_e and gear_gap: no derivatives."""
    q, deck = QUAD6_STATE.unpack(x1q), deck_pose(xv, t, p_veh, p_deck)
    p1, eta1 = q["p1"], q["eta1"]
    R_deck = deck.R_deck
    p_e = R_deck.T @ (p1 - deck.p2)
    gap = deck_gear_gap(p_e, R_deck, rotation(eta1), ACTUATOR.unpack(p_act)["gear_height"])
    return p_e, eta1 - deck.eta2, gap


def _build():
    """Symbols and the expressions of both Functions."""
    x1q, xv, t = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t")
    F_cmd, w = COMMAND.sym(), BODY_DISTURBANCE.sym()
    p_quad, p_act, p_veh, p_deck = params = _param_syms()
    ws = BODY_DISTURBANCE.unpack(w)
    x = ca.vertcat(x1q, xv)
    x_dot = ca.vertcat(quadrotor6_rhs(x1q, F_cmd, ws["d_F"], ws["d_M"], p_quad, p_act),
                       vehicle_motion(xv, t, p_veh, p_deck))

    def d_dt(e):
        return time_derivative(e, x, x_dot, t)

    q = QUAD6_STATE.unpack(x1q)
    p_e, eta_e, gap = _relative_pose(x1q, xv, t, p_act, p_veh, p_deck)
    v_e = d_dt(p_e)
    eta2_dot = d_dt(deck_pose(xv, t, p_veh, p_deck).eta2)
    Omega_e = q["Omega1"] - euler_rate_matrix_inv(q["eta1"]) @ eta2_dot     # eq. 5
    states = [p_e, v_e, eta_e, Omega_e, gap]
    accel = [d_dt(v_e), d_dt(Omega_e)]
    return (x1q, xv, t, F_cmd, w, params), states, accel


@functools.cache
def relative6_function() -> ca.Function:
    """``relative6(x1q, xv, t, p_quad, p_act, p_veh, p_deck) -> (p_e, v_e, eta_e,
    Omega_e, gear_gap)`` (eq. 5 in 6-DOF), outputs :data:`RELATIVE6`.

    ``v_e`` depends on the states only: ``p1_dot = R(eta1) V1``.
    """
    (x1q, xv, t, _, _, params), states, _ = _build()
    return ca.Function("relative6", [x1q, xv, t, *params], states,
                       ["x1q", "xv", "t", *_PARAM_NAMES], list(RELATIVE6.names()))


@functools.cache
def relative6_acceleration_function() -> ca.Function:
    """``relative6_acceleration(x1q, xv, t, F_cmd, w, p_quad, p_act, p_veh, p_deck)
    -> (a_e, Omega_e_dot)`` (eq. 6 in 6-DOF), outputs :data:`RELATIVE6_ACCELERATION`.

    The plant's inputs and signature: ``w = [d_F, d_M]`` (body frame). The
    accelerations depend on the rotor *states* F, not on ``F_cmd``, which the
    motors only follow with a lag; ``F_cmd`` is an argument for uniformity.
    """
    (x1q, xv, t, F_cmd, w, params), _, accel = _build()
    return ca.Function("relative6_acceleration", [x1q, xv, t, F_cmd, w, *params], accel,
                       ["x1q", "xv", "t", "F_cmd", "w", *_PARAM_NAMES],
                       list(RELATIVE6_ACCELERATION.names()))


def relative6(x1q, xv, t, p_quad, p_act, p_veh, p_deck):
    """``(p_e, v_e, eta_e, Omega_e, gear_gap)`` (:func:`relative6_function`)."""
    return tuple(relative6_function()(x1q, xv, t, p_quad, p_act, p_veh, p_deck))


def relative6_acceleration(x1q, xv, t, F_cmd, w, p_quad, p_act, p_veh, p_deck):
    """``(a_e, Omega_e_dot)`` (:func:`relative6_acceleration_function`)."""
    return tuple(relative6_acceleration_function()(x1q, xv, t, F_cmd, w,
                                                   p_quad, p_act, p_veh, p_deck))


def gear_gap(x1q, xv, t, p_act, p_veh, p_deck):
    """Signed distance from the deck plane to the landing gear's lowest point.

    ``n2 . (p1 - gear_height R(eta1) e_z - p2)`` with ``n2 = R_deck e_z``, the
    deck normal; the deck plane passes through the pad centre p2. Touchdown
    is its zero crossing (from above).
    """
    return _relative_pose(x1q, xv, t, p_act, p_veh, p_deck)[2]

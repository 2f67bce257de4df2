"""The quadrotor pinned to the pad after touchdown: its pose, and the wrench that holds it.

At touchdown the pose relative to the deck is frozen (:data:`ANCHOR`); from then
on the quadrotor rides the deck rigidly and every signal follows from the deck's
prescribed motion (:func:`landed_outputs_function`). The gear model of
:mod:`quadland_symbolic.landing.contact` is the dynamic alternative.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.deck import deck_pose, time_derivative, vee, vehicle_motion
from quadland_symbolic.landing.guidance import LANDED, TOUCHDOWN
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
from quadland_symbolic.landing.quadrotor import ACTUATOR
from quadland_symbolic.landing.signals import LANDING_SIGNALS, landing_signals
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.loop import RIDE_TOL
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import WRENCH, wrench_from_rotors
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["ANCHOR", "landed_outputs_function", "landed_row_function", "anchor_function"]


#: The pose at which the quadrotor is pinned to the deck after touchdown.
ANCHOR = Layout("anchor", (
    Field("p_e", 3, "m", "the quadrotor's centre in the deck frame at touchdown"),
    Field("R_rel", 9, "-", "R_deck^T R(eta1) at touchdown", shape=(3, 3)),
), "the quadrotor's pose on the deck")


@functools.cache
def landed_outputs_function() -> ca.Function:
    """``landed_outputs(xv, t, pp, anchor, F, phase, aborts) -> (y, x1q)``: the quadrotor on
    the deck.

    The quadrotor is pinned at the pose ``anchor`` (:data:`ANCHOR`):
    ``p1 = p2 + R_deck p_e``, ``R(eta1) = R_deck R_rel``, and its rotor
    forces are ``F`` (idle, winding down). Its velocity, rates and
    accelerations are symbolic time derivatives along the vehicle's motion
    (eq. 4) and the deck's prescribed motion. ``d_F`` and ``d_M`` are then
    what eq. (2) needs to hold: the deck's contact, wind and disturbance
    together, ``d_F = R^T m (p1'' + g e_z) - F_total e_z + Kt V1`` and
    ``d_M = I Omega' + Omega x I Omega - M + Kr Omega``. The ZYX yaw is
    ``atan2``'s, in ``(-pi, pi]``: the caller unwraps it. ``x1q`` is the
    quadrotor's state so pinned.
    """
    xv, t, pp = VEHICLE_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    anchor, F = ANCHOR.sym(), ca.SX.sym("F", 4)
    phase, aborts = ca.SX.sym("phase"), ca.SX.sym("aborts")
    p, a = LANDING_PLANT_PARAMS.unpack(pp), ANCHOR.unpack(anchor)
    q = QUADROTOR.unpack(p["p_quad"])
    xv_dot = vehicle_motion(xv, t, p["p_veh"], p["p_deck"])

    def d_dt(e):
        return time_derivative(e, xv, xv_dot, t)

    deck = deck_pose(xv, t, p["p_veh"], p["p_deck"])
    p1 = deck.p2 + deck.R_deck @ a["p_e"]
    R1 = deck.R_deck @ a["R_rel"]
    eta1 = ca.vertcat(ca.atan2(R1[2, 1], R1[2, 2]),
                      ca.atan2(-R1[2, 0], ca.sqrt(R1[2, 1] ** 2 + R1[2, 2] ** 2)),
                      ca.atan2(R1[1, 0], R1[0, 0]))
    p1_dot = d_dt(p1)
    V1 = R1.T @ p1_dot                                                 # eq. 1
    Omega1 = vee(R1.T @ d_dt(R1))
    wrench = WRENCH.unpack(wrench_from_rotors(F, p["p_quad"]))
    m1, I, g = q["m1"], q["I"], q["g"]
    d_F = (R1.T @ (m1 * (d_dt(p1_dot) + ca.vertcat(0, 0, g)))
           - ca.vertcat(0, 0, wrench["F_total"]) + q["Kt"] * V1)           # eq. 2, solved
    d_M = (I * d_dt(Omega1) + ca.cross(Omega1, I * Omega1) - wrench["M"]
           + q["Kr"] * Omega1)                                             # eq. 2, solved
    x1q = ca.vertcat(p1, eta1, V1, Omega1, F)
    y = landing_signals(x1q, xv, t, pp, d_F, d_M, phase, aborts)
    return ca.Function("landed_outputs", [xv, t, pp, anchor, F, phase, aborts], [y, x1q],
                       ["xv", "t", "pp", "anchor", "F", "phase", "aborts"], ["y", "x1q"])


@functools.cache
def anchor_function() -> ca.Function:
    """``landing_anchor(y) -> anchor``: the touchdown pose (:data:`ANCHOR`) from the signals
    ``y`` (:data:`LANDING_SIGNALS`) at the contact: ``p_e`` and ``R_rel = R_deck^T R(eta1)``."""
    y = LANDING_SIGNALS.sym()
    ys = LANDING_SIGNALS.unpack(y)
    R_rel = rotation(ys["eta2"]).T @ rotation(ys["eta1"])
    return ca.Function("landing_anchor", [y], [ca.vertcat(ys["p_e"], ca.vec(R_rel))], ["y"],
                       ["anchor"])


@functools.cache
def landed_row_function() -> ca.Function:
    """``landed_row(xv, t, pp, anchor, F_td, t_td, settle, aborts) -> (y, x1q)``: a row of
    the ride on the deck.

    The rotor forces wind down from their touchdown values as
    ``F_td exp(-(t - t_td) / tau_m)`` (commands zero, the motors' lag); the
    phase is TOUCHDOWN, then LANDED from ``t_td + settle`` (within
    :data:`~quadland_symbolic.loop.RIDE_TOL`); the signals and the pinned state
    are :func:`landed_outputs_function`'s. The one text of a ride's row: the
    simulators' ``ride_row`` is built on it, and the pure-C example calls its C.
    """
    xv, t, pp = VEHICLE_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    anchor, F_td = ANCHOR.sym(), ca.SX.sym("F_td", 4)
    t_td, settle, aborts = ca.SX.sym("t_td"), ca.SX.sym("settle"), ca.SX.sym("aborts")
    p_act = LANDING_PLANT_PARAMS.unpack(pp)["p_act"]
    tau_m = ACTUATOR.unpack(p_act)["motor_time_constant"]
    F = F_td * ca.exp(-(t - t_td) / tau_m)
    phase = ca.if_else(t >= t_td + settle - RIDE_TOL, LANDED, TOUCHDOWN)
    y, x1q = landed_outputs_function()(xv, t, pp, anchor, F, phase, aborts)
    return ca.Function("landed_row", [xv, t, pp, anchor, F_td, t_td, settle, aborts], [y, x1q],
                       ["xv", "t", "pp", "anchor", "F_td", "t_td", "settle", "aborts"],
                       ["y", "x1q"])

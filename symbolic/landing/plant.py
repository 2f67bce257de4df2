"""The landing plant as one ODE: 6-DOF quadrotor and vehicle (eq. 1-4).

State ``xp`` (:data:`LANDING_PLANT_STATE`) = ``[x1q (16), xv (6), x_gear (3)]``; inputs held over
a control period: the rotor commands ``F_cmd`` (:data:`~quadland_symbolic.landing.
quadrotor.COMMAND`) and the disturbance ``w = [d_F, d_M]``
(:data:`quadland_symbolic.quadrotor.BODY_DISTURBANCE`, body frame); the time ``t`` drives
the deck. The deck's heave, roll and pitch are prescribed, not integrated.

The landing gear's contact (:mod:`quadland_symbolic.landing.gear`, on
:mod:`quadland_symbolic.landing.contact`) adds its wrench to ``d_F``, ``d_M``
from the first touch on, and its memory ``x_gear`` (load impulse, contact
clock, peak load) to the state; the touchdown policy's rotor cut acts on
the commands. Far above the deck the contact's forces are exactly zero.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.aero import aero_force
from quadland_symbolic.landing.contact import GEAR, LOCK
from quadland_symbolic.landing.deck import DECK_PARAMS, DECK_POSE, deck_pose, vehicle_motion
from quadland_symbolic.landing.gear import GEAR_STATE, TOUCHDOWN_POLICY, gear_terms
from quadland_symbolic.landing.quadrotor import ACTUATOR, COMMAND, QUAD6_STATE, quadrotor6_rhs
from quadland_symbolic.landing.relative import RELATIVE6, relative6
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["LANDING_PLANT_STATE", "LANDING_PLANT_PARAMS", "LANDING_PLANT_OUTPUTS",
           "LANDING_DISTURBANCE", "landing_plant_rhs", "landing_plant_function",
           "landing_outputs_function", "wind_force", "body_disturbance", "loop_plant_function"]

#: State of the landing plant.
LANDING_PLANT_STATE = Layout("xp_land", (
    Field.nested("x1q", QUAD6_STATE, "6-DOF quadrotor"),
    Field.nested("xv", VEHICLE_STATE, "vehicle (planar, eq. 4)"),
    Field.nested("gear", GEAR_STATE, "landing gear's memory: load impulse, contact clock, peak"),
), "landing plant state: 6-DOF quadrotor, vehicle and the gear's memory")

#: Parameters of the landing plant.
LANDING_PLANT_PARAMS = Layout("pp_land", (
    Field.nested("p_quad", QUADROTOR, "quadrotor rigid body (Table 1)"),
    Field.nested("p_act", ACTUATOR, "motors and landing gear"),
    Field.nested("p_veh", VEHICLE, "vehicle constants and inputs (its z2 is unused)"),
    Field.nested("p_deck", DECK_PARAMS, "prescribed deck motion and pad"),
    Field.nested("p_gear", GEAR, "landing gear's feet, stiffness, damping and friction"),
    Field.nested("p_lock", LOCK, "lock-down device (F_hold = 0: none)"),
    Field.nested("p_td", TOUCHDOWN_POLICY, "touchdown policy: the rotor cut"),
), "landing plant parameters")

#: Signals of :func:`landing_outputs_function`: the landing trajectory's columns.
LANDING_PLANT_OUTPUTS = Layout("y6", (
    QUAD6_STATE["p1"],
    QUAD6_STATE["eta1"],
    DECK_POSE["p2"],
    DECK_POSE["eta2"],
    *RELATIVE6.fields,
    QUAD6_STATE["F"],
    COMMAND["F_cmd"],
    *BODY_DISTURBANCE.fields,
), "landing signals: both bodies in E, the relative state, rotors and disturbance")


def landing_plant_rhs(xp, F_cmd, w, t, pp, contact: bool = True):
    """``xp_dot``: eq. (1)-(2) with motor lag for x1q, eq. (3)-(4) for xv, the gear's memory.

    ``t`` drives the vehicle's profile (:func:`~quadland_symbolic.landing.deck.vehicle_motion`);
    the deck's prescribed heave, roll and pitch move no state. The gear's contact
    feels the deck's motion
    (:func:`quadland_symbolic.landing.gear.gear_terms`: its wrench joins ``w``'s
    ``d_F``, ``d_M``; the touchdown policy's cut acts on ``F_cmd``). ``contact =
    False``: the plant in free flight, the gear's forces and memory left out (the
    simulator's plant before the first contact, where they vanish).
    """
    x, ws = LANDING_PLANT_STATE.unpack(xp), BODY_DISTURBANCE.unpack(w)
    p = LANDING_PLANT_PARAMS.unpack(pp)
    d_F, d_M, gear_dot = ca.SX.zeros(3), ca.SX.zeros(3), ca.SX.zeros(GEAR_STATE.size)
    if contact:
        d_F, d_M, gear_dot, F_cmd = gear_terms(x["x1q"], x["xv"], x["gear"], F_cmd, t,
                                               p["p_quad"], p["p_veh"], p["p_deck"],
                                               p["p_gear"], p["p_lock"], p["p_td"])
    return ca.vertcat(
        quadrotor6_rhs(x["x1q"], F_cmd, ws["d_F"] + d_F, ws["d_M"] + d_M, p["p_quad"],
                       p["p_act"]),
        vehicle_motion(x["xv"], t, p["p_veh"], p["p_deck"]),
        gear_dot,
    )


def landing_plant_function() -> ca.Function:
    """``landing_plant(xp, F_cmd, w, t, pp) -> xp_dot`` (eq. 1-4, motor lag)."""
    xp, F_cmd, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), BODY_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    return ca.Function("landing_plant", [xp, F_cmd, w, t, pp],
                       [landing_plant_rhs(xp, F_cmd, w, t, pp)],
                       ["xp", "F_cmd", "w", "t", "pp"], ["xp_dot"])


def landing_outputs_function() -> ca.Function:
    """``landing_outputs(xp, F_cmd, w, t, pp) -> y`` with ``y`` laid out as
    :data:`LANDING_PLANT_OUTPUTS`.

    ``x1 y1 z1 phi1 theta1 psi1`` (quadrotor in E), ``x2 y2 z2 phi2 theta2
    psi2`` (pad centre and deck attitude in E), the relative state of
    :data:`quadland_symbolic.landing.relative.RELATIVE6` (``x_e y_e z_e`` ...), the rotor
    forces ``F_1..F_4``, their commands and the disturbance ``d_Fx ..``.
    """
    xp, F_cmd, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), BODY_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    x, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    q = QUAD6_STATE.unpack(x["x1q"])
    deck = deck_pose(x["xv"], t, p["p_veh"], p["p_deck"])
    rel = relative6(x["x1q"], x["xv"], t, p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])
    y = ca.vertcat(q["p1"], q["eta1"], deck.p2, deck.eta2, *rel, q["F"], F_cmd, w)
    return ca.Function("landing_outputs", [xp, F_cmd, w, t, pp], [y],
                       ["xp", "F_cmd", "w", "t", "pp"], ["y"])


#: The held disturbance of the landing loop: wind in E, then eq. (2)'s d_F, d_M.
LANDING_DISTURBANCE = Layout("w_land", (
    Field("v_wind", 3, "m/s", "wind velocity in E", elements=("vx_wind", "vy_wind", "vz_wind")),
    *BODY_DISTURBANCE.fields,
), "wind velocity (E) and the disturbance force and moment (body)")


def wind_force(eta1, v_wind, p_quad):
    """Body force of the wind through eq. (2)'s drag: ``Kt R(eta1)^T v_wind``, N."""
    return QUADROTOR.unpack(p_quad)["Kt"] * (rotation(eta1).T @ v_wind)


def body_disturbance(xp, w, pp, t):
    """``[d_F + wind_force + aero_force, d_M]``: the landing plant's disturbance input
    (:func:`~quadland_symbolic.landing.aero.aero_force`: quadratic drag, ground effect)."""
    ws, x = LANDING_DISTURBANCE.unpack(w), LANDING_PLANT_STATE.unpack(xp)
    p = LANDING_PLANT_PARAMS.unpack(pp)
    eta1 = QUAD6_STATE.unpack(x["x1q"])["eta1"]
    d_F = (ws["d_F"] + wind_force(eta1, ws["v_wind"], p["p_quad"])
           + aero_force(x["x1q"], x["xv"], ws["v_wind"], t, p["p_act"], p["p_veh"], p["p_deck"]))
    return ca.vertcat(d_F, ws["d_M"])


@functools.cache
def loop_plant_function(contact: bool = True) -> ca.Function:
    """``landing_loop_plant(xp, F_cmd, w, t, pp) -> xp_dot``: the landing plant under
    the loop's disturbance ``w`` (:data:`LANDING_DISTURBANCE`: wind in E, body ``d_F``, ``d_M``);
    ``contact = False``: ``landing_free_plant``, in free flight (:func:`landing_plant_rhs`).
    Common subexpressions are merged (the deck's pose serves the feet and the lock)."""
    xp, F_cmd, w, t, pp = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym(), \
        ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    return ca.Function("landing_loop_plant" if contact else "landing_free_plant",
                       [xp, F_cmd, w, t, pp],
                       [landing_plant_rhs(xp, F_cmd, body_disturbance(xp, w, pp, t), t, pp,
                                          contact)],
                       ["xp", "F_cmd", "w", "t", "pp"], ["xp_dot"], {"cse": True})

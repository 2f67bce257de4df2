"""The gear's contact in the landing plant: its states, the touchdown policy, its signals.

The contact of :mod:`quadland_symbolic.landing.contact` acts on the 6-DOF
quadrotor from the first touch on, through eq. (2)'s body-frame disturbance
``d_F``, ``d_M`` (as the wind does), so bounce, slide and tip-over happen in
the simulation. Three plant states (:data:`GEAR_STATE`) carry what the gear
remembers, each an ODE so that the fixed-step RK4 stays well posed:

* ``impulse``: the gear's load impulse over the weight,
  ``impulse' = sum_i F_n_i / (m1 g)`` (s): how long the gear has carried
  the weight, zero before the first touch;
* ``t_contact``: the time since the gear's contact switch closed,
  ``t_contact' = clip(impulse / s_switch - 1, 0, 1)``: the switch closes once
  the impulse reaches ``s_switch`` (the load a foot switch needs, a few
  milliseconds into the touch) and the clock then runs at full rate by
  ``2 s_switch``; it latches (a bounce does not reset it);
* ``F_peak``: the peak load on the legs, followed by ``F_peak' = PEAK_RATE
  max(sum_i max(F_n_i - P_i, 0) - F_peak, 0)`` (``P_i`` the pull of a device in foot
  ``i``, which closes through the foot's sole, not its leg; 0 for a device at the
  gear's centre, whose pull the legs carry): it never falls, and it reads a load pulse
  of angular frequency ``w`` low by about ``(w / PEAK_RATE)^2 / 2`` (0.13 %
  for the default gear's 100 rad/s); RK4 integrates it at every substep.

The **touchdown policy** (:data:`TOUCHDOWN_POLICY`) acts on that switch, in
hardware: with ``cut = 1`` the rotors' commands go to ``F_idle`` once the
switch has been closed ``cut_delay`` (a ramp of :data:`CUT_RAMP` keeps the
plant continuous); with ``cut = 0`` the flight code keeps commanding them
(hold-down thrust: the fixed-pitch rotors can only cut theirs). The
lock-down device (:data:`~quadland_symbolic.landing.contact.LOCK`, ``F_hold
= 0`` for none) takes the switch's closing as its ``t_signal``
(``t - t_contact``; a closed clock of 0 leaves it disengaged).

:func:`foot_gap_function` is the first contact's event (the lowest foot's
height above the deck plane); :func:`gear_signals_function` gives the
report its figures at each row.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.aero import aero_force
from quadland_symbolic.landing.contact import (
    FOOT,
    GEAR,
    HOLD,
    LOCK,
    contact_function,
    friction_margin,
    gear_defaults,
    lock_defaults,
    tip_over_angles,
)
from quadland_symbolic.landing.deck import DECK_PARAMS, deck_pose
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.quadrotor import WRENCH, wrench_from_rotors
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["GEAR_STATE", "TOUCHDOWN_POLICY", "GEAR_SIGNALS", "FAILURES", "CUT_THRUST",
           "PEAK_RATE", "CUT_RAMP",
           "contact_params", "contact_switch", "gear_terms", "foot_gap",
           "foot_gap_function", "gear_signals_function"]

#: Why a landing on the gear failed, in the order a verdict names them (the report's).
FAILURES = ("tilted", "bounced", "tipped", "gear load", "off the pad", "not secured")

#: The rotors count as cut, for the tip-over judge, below this share of the weight in
#: total thrust (a rotor cut passes it 60 ms after the cut with the shipped 20 ms
#: motors, ``exp(-3)``): then nothing but the gear holds the body up.
CUT_THRUST = 0.05

#: 1/s: the rate at which ``F_peak`` follows a rising gear load.
PEAK_RATE = 2000.0

#: s: the rotor cut's ramp from the flight code's commands to ``F_idle``.
CUT_RAMP = 1e-3

#: The gear's memory in the plant state.
GEAR_STATE = Layout("x_gear", (
    Field("impulse", 1, "s", "the gear's load impulse over the weight, int sum F_n dt / (m1 g)"),
    Field("t_contact", 1, "s", "time since the gear's contact switch closed (0 before)"),
    Field("F_peak", 1, "N", "peak total normal load of the gear so far"),
), "gear memory: load impulse, contact clock, peak load")

#: What happens once the gear touches.
TOUCHDOWN_POLICY = Layout("p_td", (
    Field("cut", 1, "0/1", "1: the contact switch cuts the rotors to F_idle (rotor idle)"),
    Field("cut_delay", 1, "s", "time from the switch closing to the cut"),
    Field("F_idle", 1, "N", "each rotor's command once cut"),
    Field("s_switch", 1, "s", "load impulse over the weight that closes the contact switch"),
), "touchdown policy: rotor cut on the contact switch")

#: The gear's signals at one instant (:func:`gear_signals_function`).
GEAR_SIGNALS = Layout("gear_sig", (
    Field("foot_gap", 1, "m", "the lowest foot's height above the deck plane (< 0: pressed in)"),
    Field("centre_gap", 1, "m", "the gear centre's height above the deck plane"),
    Field("F_gear", 1, "N", "total normal load of the feet"),
    Field("feet_down", 1, "-", "feet below the plane and pressing"),
    Field("engaged", 1, "-", "lock-down engagement, 0 to 1 (0 without a device)"),
    Field("F_lock", 1, "N", "lock-down pull"),
    Field("roll_rel", 1, "rad", "body roll relative to the deck (about the body x axis)"),
    Field("pitch_rel", 1, "rad", "body pitch relative to the deck (about the body y axis)"),
    Field("tilt_rel", 1, "rad", "angle between the body z axis and the deck normal"),
    Field("tip_margin", 1, "-", "the centre's projection along the deck normal onto the feet's "
          "plane over the support rectangle's half-side, the larger of x and y (> 1: outside)"),
    Field("friction_margin", 1, "-", "friction needed over available at rest (< 1 holds)"),
    Field("foot_sink_rate", 1, "m/s", "the lowest foot's speed into the deck plane"),
    Field("foot_offset", 1, "m", "the farthest foot's distance from the pad centre in the "
          "deck plane (deck frame x, y)"),
), "gear signals for the report")


def contact_params(surface: str = "ship_deck", device: str | None = None,
                   cut: bool = True) -> dict:
    """The plant's gear, lock and policy parameters (``p_gear``, ``p_lock``, ``p_td``) of
    :func:`~quadland_symbolic.landing.contact.gear_defaults`'s gear on ``surface``, the
    lock-down ``device`` (None: none) and the rotor cut on contact (``cut``, no delay, to
    zero, the switch at 2 ms of the weight): a dict to add to the plant's ``pack``."""
    lock = dict(lock_defaults(device or "magnet"))
    if device is None:
        lock["F_hold"] = 0.0
    return dict(p_gear=GEAR.pack(gear_defaults(surface)), p_lock=LOCK.pack(lock),
                p_td=TOUCHDOWN_POLICY.pack(dict(cut=float(cut), cut_delay=0.0, F_idle=0.0,
                                                s_switch=0.002)))


def contact_switch(xp_gear):
    """1 once the gear's contact switch has closed (``t_contact > 0``), else 0: the flight
    code reads it beside its own touchdown verdict (the guidance's ``touchdown`` cue)."""
    return GEAR_STATE.unpack(xp_gear)["t_contact"] > 0


def _contact(x1q, xv, t, t_contact, p_veh, p_deck, p_gear, p_lock):
    return contact_function()(x1q, xv, t, t - t_contact, p_veh, p_deck, p_gear, p_lock)


def gear_terms(x1q, xv, xg, F_cmd, t, p_quad, p_veh, p_deck, p_gear, p_lock, p_td):
    """The contact's part of the plant.

    Returns
    -------
    d_F, d_M : casadi.SX
        The feet's and the lock-down's body-frame wrench (add to eq. 2's).
    xg_dot : casadi.SX
        :data:`GEAR_STATE`'s derivative.
    F_cmd : casadi.SX
        The rotor commands after the policy's cut.
    """
    g, pol = GEAR_STATE.unpack(xg), TOUCHDOWN_POLICY.unpack(p_td)
    q = QUADROTOR.unpack(p_quad)
    d_F, d_M, foot, hold = _contact(x1q, xv, t, g["t_contact"], p_veh, p_deck, p_gear,
                                    p_lock)
    F_n = FOOT.unpack(foot)["F_n"]
    load = ca.sum1(F_n)                                                   # N
    legs = ca.sum1(ca.fmax(F_n - HOLD.unpack(hold)["foot_pull"], 0))      # N, on the legs
    clock = ca.fmin(ca.fmax(g["impulse"] / pol["s_switch"] - 1, 0), 1)
    xg_dot = ca.vertcat(load / (q["m1"] * q["g"]), clock,
                        PEAK_RATE * ca.fmax(legs - g["F_peak"], 0))
    gate = pol["cut"] * ca.fmin(ca.fmax((g["t_contact"] - pol["cut_delay"]) / CUT_RAMP, 0), 1)
    return d_F, d_M, xg_dot, F_cmd + gate * (pol["F_idle"] - F_cmd)


def foot_gap(x1q, xv, t, p_veh, p_deck, p_gear):
    """The lowest foot's height above the deck plane, ``-max_i delta_i`` (m)."""
    foot = contact_function()(x1q, xv, t, 0, p_veh, p_deck, p_gear, LOCK.zeros())[2]
    return -ca.mmax(FOOT.unpack(foot)["delta"])


def _relative_attitude(x1q, R_deck):
    """Roll, pitch and tilt of the body relative to the deck, and the deck normal in body
    axes (the last row of ``R_deck^T R1``)."""
    R_rel = R_deck.T @ rotation(QUAD6_STATE.unpack(x1q)["eta1"])
    roll = ca.atan2(R_rel[2, 1], R_rel[2, 2])
    pitch = ca.atan2(-R_rel[2, 0], ca.sqrt(R_rel[2, 1] ** 2 + R_rel[2, 2] ** 2))
    return roll, pitch, ca.acos(ca.fmin(ca.fmax(R_rel[2, 2], -1), 1)), R_rel[2, :].T


def tip_margin(n_body, tip):
    """Where the centre's projection along the deck normal falls on the feet's plane, over
    the support rectangle's half-sides: ``max(|n_x| / (n_z tan tip_y), |n_y| / (n_z tan
    tip_x))`` with ``n_body`` the deck normal in body axes and ``tip`` the
    :func:`~quadland_symbolic.landing.contact.tip_over_angles` (about x, about y);
    above 1 the centre is outside the rectangle. ``tan(tilt) / margin`` is the tangent
    of the tip-over angle in the tilt's direction (the projection scales with the
    tilt's tangent). A body on its side or upside down (``n_z <= 1e-9``) reads 1e9.
    """
    nz = ca.fmax(n_body[2], 1e-9)
    inside = ca.fmax(ca.fabs(n_body[0]) / (nz * ca.tan(tip[1])),
                     ca.fabs(n_body[1]) / (nz * ca.tan(tip[0])))
    return ca.if_else(n_body[2] > 1e-9, inside, 1e9)


@functools.cache
def foot_gap_function() -> ca.Function:
    """``foot_gap(x1q, xv, t, p_veh, p_deck, p_gear) -> g``: :func:`foot_gap`; the first
    contact is its zero crossing."""
    x1q, xv, t = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t")
    p_veh, p_deck, p_gear = VEHICLE.sym(), DECK_PARAMS.sym(), GEAR.sym()
    return ca.Function("foot_gap", [x1q, xv, t, p_veh, p_deck, p_gear],
                       [foot_gap(x1q, xv, t, p_veh, p_deck, p_gear)],
                       ["x1q", "xv", "t", "p_veh", "p_deck", "p_gear"], ["g"])


@functools.cache
def gear_signals_function() -> ca.Function:
    """``gear_signals(x1q, xv, xg, t, v_wind, p_quad, p_act, p_veh, p_deck, p_gear, p_lock) ->
    s`` (:data:`GEAR_SIGNALS`); ``v_wind``: the wind velocity in E at ``t`` (m/s).

    The friction margin is :func:`~quadland_symbolic.landing.contact.friction_margin`
    with the rotors' thrust (their forces now), the lock's pull and every
    aerodynamic force the plant applies (:func:`~quadland_symbolic.landing.plant.
    body_disturbance` without its ``d_F``) as the other forces: eq. (2)'s linear drag
    and the quadratic drag of the airspeed ``V1 - R1^T v_wind`` (the body's velocity,
    which on the deck is the deck's, against the wind's: on a car's roof at 100 km/h
    in still air, 17.8 N, more than friction alone holds; a 10 m/s wind on a still
    deck, 4.2 N) and the ground effect's lift. The sink rate is the lowest foot's
    ``-n2 . v_i`` relative to the deck's material point under it; ``foot_offset`` the
    farthest foot's ``hypot`` of its deck-frame ``x, y`` from the pad centre.
    """
    x1q, xv, xg, t = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), GEAR_STATE.sym(), ca.SX.sym("t")
    v_wind = ca.SX.sym("v_wind", 3)
    p_quad, p_veh, p_deck = QUADROTOR.sym(), VEHICLE.sym(), DECK_PARAMS.sym()
    p_gear, p_lock, p_act = GEAR.sym(), LOCK.sym(), ACTUATOR.sym()
    q = QUAD6_STATE.unpack(x1q)
    t_contact = GEAR_STATE.unpack(xg)["t_contact"]
    _, _, foot, hold = _contact(x1q, xv, t, t_contact, p_veh, p_deck, p_gear, p_lock)
    fs, hs = FOOT.unpack(foot), HOLD.unpack(hold)
    deck = deck_pose(xv, t, p_veh, p_deck)
    n2 = deck.R_deck[:, 2]
    R1 = rotation(q["eta1"])
    r_feet = GEAR.unpack(p_gear)["r_feet"]
    # the lowest foot's velocity relative to the deck along -n2
    low = fs["delta"]
    lowest = ca.mmax(low)
    weights = ca.if_else(low >= lowest, 1, 0)
    arm = R1 @ r_feet @ weights / ca.sum1(weights)
    v1E, w1E = R1 @ q["V1"], R1 @ q["Omega1"]
    d = q["p1"] + arm - deck.p2
    v_rel = v1E + ca.cross(w1E, arm) - deck.v2E - ca.cross(deck.w2E, d)
    roll, pitch, tilt, n_body = _relative_attitude(x1q, deck.R_deck)
    tip = tip_over_angles(p_gear)
    thrust = WRENCH.unpack(wrench_from_rotors(q["F"], p_quad))["F_total"]
    Kt = QUADROTOR.unpack(p_quad)["Kt"]
    aero = (-Kt * q["V1"] + Kt * (R1.T @ v_wind)           # eq. (2)'s drag of the airspeed
            + aero_force(x1q, xv, v_wind, t, p_act, p_veh, p_deck))
    F_other = R1 @ (ca.vertcat(0, 0, thrust) + aero) - hs["F_lock"] * n2
    margin = friction_margin(x1q, xv, t, F_other, p_quad, p_veh, p_deck, p_gear)
    # no device (F_hold = 0): nothing engages, whatever the lock's clock says
    engaged = ca.if_else(LOCK.unpack(p_lock)["F_hold"] > 0, hs["engaged"], 0)
    feet_deck = deck.R_deck.T @ (q["p1"] + R1 @ r_feet - deck.p2 @ ca.DM.ones(1, r_feet.shape[1]))
    foot_offset = ca.sqrt(ca.mmax(feet_deck[0, :] ** 2 + feet_deck[1, :] ** 2))
    s = ca.vertcat(-lowest, hs["lock_gap"], ca.sum1(fs["F_n"]), ca.sum1(fs["in_contact"]),
                   engaged, hs["F_lock"], roll, pitch, tilt,
                   tip_margin(n_body, tip), margin,
                   -(n2.T @ v_rel), foot_offset)
    names = ["x1q", "xv", "xg", "t", "v_wind", "p_quad", "p_act", "p_veh", "p_deck", "p_gear",
             "p_lock"]
    return ca.Function("gear_signals",
                       [x1q, xv, xg, t, v_wind, p_quad, p_act, p_veh, p_deck, p_gear, p_lock],
                       [s], names, ["s"])

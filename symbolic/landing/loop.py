"""The landing loop as the simulator sees it: plant with wind, sensors, guidance, landing step.

:func:`landing_loop` bundles, in the shape of :class:`quadland_symbolic.loop.LoopModel`:

* **plant** ``plant(xp, F_cmd, w, t, pp)``: the landing plant
  (:mod:`quadland_symbolic.landing.plant`) under the held disturbance ``w``
  (:data:`LANDING_DISTURBANCE`): the wind velocity in E and the body-frame
  ``[d_F, d_M]``. The rotor drag of eq. (2) acts on the velocity relative to
  the air, ``-Kt (V1 - R(eta1)^T v_wind)``, so the wind adds the body force
  ``Kt R(eta1)^T v_wind`` (:func:`wind_force`) to ``d_F``;
* **controller** ``controller(xp, xc, pc, first, t)``: perfect sensors
  (:func:`~quadland_symbolic.landing.sensors.measurement_function`), then one
  guidance step (:func:`~quadland_symbolic.landing.controller.landing_guidance`) whose
  reference feeds one landing step
  (:func:`~quadland_symbolic.landing.controller.landing_law`), both at the control
  rate; the memory ``xc`` (:func:`landing_loop_memory`) is the guidance's state
  (the phase among it) and the step's; the held input is the rotor commands,
  the guard the measured tilt; **step_args** gives both steps' arguments, for
  the flight code behind the same signature (``controller.backend = "c"``);
* **event** ``event(xp, t, pp)``: the lowest foot's height above the deck
  (:func:`quadland_symbolic.landing.gear.foot_gap`); the first contact is
  located at the instant it happens and the integration goes on through it
  (``event_continues``): the gear's contact, in the plant, carries the
  quadrotor from then on, a free body on the deck;
* **assemble** ``x = [xp, xc]`` and **outputs** ``y`` (:func:`loop_outputs`):
  the signals of the landing trajectory.

``landing_loop(l, welded=True)`` is the idealization the gear's contact
replaced, for a user who asks for it: the event is the gear gap (a point
``gear_height`` below the centre), touchdown ends the integration, and the
quadrotor rides on the deck, pinned at its touchdown pose with its rotors
idle (:mod:`quadland_symbolic.landing.ride`): the loop's *ride*
(:func:`landing_ride_start`, and the model's ``ride_rhs``, the vehicle alone,
and ``ride_row``, the loop's state, signals and recorded signals of a row, from
the vehicle's state, the deck's motion and that pose); its plant is
``landing_free_plant``, without the gear's contact.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import tilt_angle
from quadland_symbolic.landing.controller import (
    landing_controller_params,
    landing_guidance,
    landing_law,
    landing_memory,
    landing_step_outputs,
    measured_cues,
)
from quadland_symbolic.landing.deck import vehicle_motion
from quadland_symbolic.landing.gear import (
    GEAR_STATE,
    contact_switch,
    foot_gap_function,
    gear_signals_function,
)
from quadland_symbolic.landing.guidance import (
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
)
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from quadland_symbolic.landing.quadrotor import COMMAND, QUAD6_STATE
from quadland_symbolic.landing.relative import gear_gap
from quadland_symbolic.landing.ride import ANCHOR, anchor_function, landed_row_function
from quadland_symbolic.landing.sensors import measurement_function
from quadland_symbolic.landing.signals import LANDING_SIGNALS, landing_signals_function
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["LANDING_RECORDED", "LANDING_ENVELOPE", "landing_loop_memory", "landing_loop_params",
           "landing_loop_state", "loop_outputs", "gear_gap_function", "first_contact_function",
           "landing_gear_signals_function",
           "landing_ride_constants",
           "landing_ride_start", "landing_ride_functions", "landing_flight_step",
           "landing_envelope_function", "landing_loop"]

#: What the loop records of each control step (held until the next).
LANDING_RECORDED = Layout("rec_land", (
    COMMAND["F_cmd"],
    landing_step_outputs(1)["eta_d"],
    POSITION_REFERENCE["p_ref"],
    landing_step_outputs(1)["limits"],
), "the landing step's commands, attitude reference, position reference and limit flags")

#: The magnitudes a landing must keep within its envelope (:func:`landing_envelope_function`):
#: each is compared with a bound the runtime derives from the scenario.
LANDING_ENVELOPE = Layout("env_land", (
    Field("distance", 1, "m", "horizontal distance from the vehicle's reference point"),
    Field("height", 1, "m", "|z1|, the quadrotor's altitude in E"),
    Field("speed", 1, "m/s", "largest body velocity component |V1|"),
    Field("rate", 1, "rad/s", "largest body rate |Omega1|"),
    Field("rotor", 1, "N", "largest rotor force |F| (the motors' states)"),
    Field("weight", 1, "-", "largest network weight |W_hat| (eq. 22)"),
    Field("robust", 1, "-", "largest robust term estimate |zeta_hat| (eq. 22)"),
    Field("tilt", 1, "rad", "tilt of the thrust axis from the vertical, acos(cos phi cos theta)"),
), "magnitudes checked against the landing's flight envelope")


@functools.cache
def landing_loop_memory(l: int) -> Layout:
    """The landing loop's memory: the guidance's state and the landing step's."""
    return Layout("xc_land", (
        Field.nested("xg", GUIDANCE_STATE, "guidance: phase, dwell timer, z_ref, aborts"),
        Field.nested("mem", landing_memory(l), "landing step: network, filter, compensator"),
    ), "landing loop memory")


@functools.cache
def landing_loop_params(l: int) -> Layout:
    """The landing loop's controller parameters: sensors' model, law, guidance, period."""
    return Layout("pc_land", (
        Field.nested("pp", LANDING_PLANT_PARAMS,
                     "plant model of the (perfect) sensors and of the law"),
        Field.nested("p_ctrl", landing_controller_params(l), "landing step"),
        Field.nested("p_guid", GUIDANCE_PARAMS, "guidance"),
        Field("dt", 1, "s", "control period"),
    ), "landing loop controller parameters")


@functools.cache
def landing_loop_state(l: int) -> Layout:
    """The landing loop's whole state ``x = [xp, xc]``."""
    return Layout("x_land", (
        Field.nested("xp", LANDING_PLANT_STATE, "plant"),
        Field.nested("xc", landing_loop_memory(l), "controller memory"),
    ), "landing loop state")


def loop_outputs(l: int, x, w, t, pp):
    """The :data:`LANDING_SIGNALS` of the loop state ``x`` (:func:`landing_loop_state`) under
    ``w``."""
    xs = landing_loop_state(l).unpack(x)
    xg = landing_loop_memory(l).unpack(xs["xc"])["xg"]
    return landing_signals_function()(xs["xp"], xg, w, t, pp)


@functools.cache
def gear_gap_function() -> ca.Function:
    """``landing_gear_gap(xp, t, pp) -> g``: the gear's height above the deck plane, m;
    touchdown is its zero crossing (the simulator's event)."""
    xp, t, pp = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    s, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    return ca.Function("landing_gear_gap", [xp, t, pp],
                       [gear_gap(s["x1q"], s["xv"], t, p["p_act"], p["p_veh"], p["p_deck"])],
                       ["xp", "t", "pp"], ["g"])


@functools.cache
def first_contact_function() -> ca.Function:
    """``landing_first_contact(xp, t, pp) -> g``: the lowest foot's height above the deck
    plane, m (:func:`quadland_symbolic.landing.gear.foot_gap`); the first contact is its
    zero crossing (the simulator's event, which the integration goes on through)."""
    xp, t, pp = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    s, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    return ca.Function("landing_first_contact", [xp, t, pp],
                       [foot_gap_function()(s["x1q"], s["xv"], t, p["p_veh"], p["p_deck"],
                                            p["p_gear"])],
                       ["xp", "t", "pp"], ["g"])


@functools.cache
def landing_gear_signals_function() -> ca.Function:
    """``landing_gear_signals(xp, w, t, pp) -> s``: the gear's signals
    (:data:`quadland_symbolic.landing.gear.GEAR_SIGNALS`) of the plant's state under the
    held disturbance ``w`` (:data:`LANDING_DISTURBANCE`: its wind enters the friction
    margin as the plant's drag of the airspeed)."""
    xp, t, pp = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    w = LANDING_DISTURBANCE.sym()
    s, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    sig = gear_signals_function()(s["x1q"], s["xv"], s["gear"], t,
                                  LANDING_DISTURBANCE.unpack(w)["v_wind"], p["p_quad"],
                                  p["p_act"], p["p_veh"], p["p_deck"], p["p_gear"],
                                  p["p_lock"])
    return ca.Function("landing_gear_signals", [xp, w, t, pp], [sig],
                       ["xp", "w", "t", "pp"], ["s"])


@functools.cache
def landing_envelope_function(l: int) -> ca.Function:
    """``envelope(x, uh) -> s``: the :data:`LANDING_ENVELOPE` magnitudes of the loop state ``x``
    (:func:`landing_loop_state`); ``uh``, the held rotor commands, is not needed (they are
    clipped)."""
    x, uh = landing_loop_state(l).sym(), COMMAND.sym()
    xs = landing_loop_state(l).unpack(x)
    ps, cs = LANDING_PLANT_STATE.unpack(xs["xp"]), landing_loop_memory(l).unpack(xs["xc"])
    q, v = QUAD6_STATE.unpack(ps["x1q"]), VEHICLE_STATE.unpack(ps["xv"])
    mem = landing_memory(l).unpack(cs["mem"])
    s = ca.vertcat(ca.norm_2(q["p1"][0:2] - ca.vertcat(v["x2"], v["y2"])), ca.fabs(q["p1"][2]),
                   ca.mmax(ca.fabs(q["V1"])), ca.mmax(ca.fabs(q["Omega1"])),
                   ca.mmax(ca.fabs(q["F"])), ca.mmax(ca.fabs(mem["W_hat"])),
                   ca.mmax(ca.fabs(mem["zeta_hat"])), tilt_angle(q["eta1"]))
    return ca.Function("envelope", [x, uh], [s], ["x", "uh"], ["s"])


@functools.cache
def landing_ride_constants(l: int, recorded: Layout = LANDING_RECORDED) -> Layout:
    """``a``, what the ride after touchdown holds fixed, formed at the touchdown (the
    loop's ``recorded`` layout, :data:`LANDING_RECORDED` or a sensed loop's)."""
    return Layout("ride_land" if recorded is LANDING_RECORDED else f"ride_{recorded.name}", (
        Field.nested("anchor", ANCHOR, "the pose pinned to the deck"),
        Field.nested("gear", GEAR_STATE, "the gear's memory at touchdown, held"),
        Field("F_td", 4, "N", "rotor forces at touchdown (then winding down)"),
        Field("t_td", 1, "s", "touchdown time"),
        Field("settle", 1, "s", "landing.settle_time: the phase is LANDED from t_td + settle"),
        Field("aborts", 1, "-", "the guidance's abort count"),
        Field.nested("xc", landing_loop_memory(l), "the controller's memory, frozen"),
        Field.nested("rec", recorded, "the recorded signals, rotor commands zero"),
    ), "constants of the ride on the deck")


@functools.cache
def landing_ride_start(l: int, recorded: Layout = LANDING_RECORDED) -> ca.Function:
    """``ride_start(x, y, rec, t, settle) -> (z, a)``: the ride's state (the vehicle's
    ``xv``) and constants (:func:`landing_ride_constants`) from the loop's state,
    signals and recorded signals (``recorded``) at touchdown."""
    x, y, rec = landing_loop_state(l).sym(), LANDING_SIGNALS.sym(), recorded.sym()
    t, settle = ca.SX.sym("t"), ca.SX.sym("settle")
    xs = landing_loop_state(l).unpack(x)
    ps, rs = LANDING_PLANT_STATE.unpack(xs["xp"]), recorded.unpack(rec)
    idle = ca.vertcat(ca.SX.zeros(4), *(rs[f.name] for f in recorded.fields[1:]))
    a = ca.vertcat(anchor_function()(y), ps["gear"], QUAD6_STATE.unpack(ps["x1q"])["F"], t,
                   settle,
                   LANDING_SIGNALS.unpack(y)["aborts"], xs["xc"], idle)
    return ca.Function("ride_start", [x, y, rec, t, settle], [ps["xv"], a],
                       ["x", "y", "rec", "t", "settle"], ["z", "a"])


def landing_ride_functions(l: int, recorded: Layout = LANDING_RECORDED
                           ) -> tuple[ca.Function, ca.Function]:
    """``ride_rhs(z, t, pp) -> z_dot``: the vehicle (eq. 4, driven); ``ride_row(z, a, t, pp) ->
    (x, y, rec)``: the quadrotor pinned at ``a``'s anchor, its rotor forces
    ``F_td exp(-(t - t_td) / tau_m)`` (commands zero, the motors' lag), the phase
    TOUCHDOWN, then LANDED from ``t_td + settle``."""
    z, t, pp = VEHICLE_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    p = LANDING_PLANT_PARAMS.unpack(pp)
    ride_rhs = _named("ride_rhs", [z, t, pp], [vehicle_motion(z, t, p["p_veh"], p["p_deck"])],
                      ["z", "t", "pp"], ["z_dot"])
    a = landing_ride_constants(l, recorded).sym()
    c = landing_ride_constants(l, recorded).unpack(a)
    y, x1q = landed_row_function()(z, t, pp, ca.vertcat(c["anchor"]), c["F_td"], c["t_td"],
                                   c["settle"], c["aborts"])
    ride_row = _named("ride_row", [z, a, t, pp],
                      [ca.vertcat(x1q, z, c["gear"], c["xc"]), y, c["rec"]],
                      ["z", "a", "t", "pp"], ["x", "y", "rec"])
    return ride_rhs, ride_row


def landing_flight_step(l: int, y, cues, cs: dict, ps: dict):
    """One guidance step and one landing step on the measurements ``y`` and the
    guidance's ``cues`` (:data:`~quadland_symbolic.landing.guidance.GUIDANCE_CUES`).

    ``cs``, ``ps``: the unpacked loop memory and controller parameters (with the
    fields ``xg``, ``mem`` and ``pp``, ``p_ctrl``, ``p_guid``, ``dt``). Returns
    the flight code's arguments (by name), the memory ``[xg, mem]`` after the
    step, the :data:`LANDING_RECORDED` signals and the landing step's results.
    """
    plant_p = LANDING_PLANT_PARAMS.unpack(ps["pp"])
    args = dict(y=y, cues=cues, xg=cs["xg"], mem=cs["mem"], p_ctrl=ps["p_ctrl"],
                p_quad=plant_p["p_quad"], p_act=plant_p["p_act"], p_guid=ps["p_guid"],
                dt=ps["dt"])
    xg_next, ref = landing_guidance(cs["xg"], y, cues, ps["dt"], ps["p_guid"])
    res = landing_law(l, y, ref, cs["mem"], ps["p_ctrl"], plant_p["p_quad"], plant_p["p_act"],
                      ps["dt"])
    rec = ca.vertcat(res["F_cmd"], res["eta_d"], POSITION_REFERENCE.unpack(ref)["p_ref"],
                     res["limits"])
    return args, ca.vertcat(xg_next, res["mem_next"]), rec, res


def _named(name, ins, outs, in_names, out_names):
    return ca.Function(name, ins, outs, in_names, out_names)


@functools.cache
def landing_loop(l: int, welded: bool = False) -> LoopModel:
    """The landing loop for ``l`` RBF nodes (see the module docstring).

    Sampled-data only: the landing step runs at the control rate (``pc``'s
    ``dt``) and its rotor commands are held; there is no continuous loop
    (``rhs`` is None). ``p`` of ``outputs`` is the plant's ``pp``. ``welded``:
    the idealization of a touchdown that ends the flight, the quadrotor then
    pinned to the deck (the runtime zeroes the gear's forces for it).
    """
    xc_lay, pc_lay, x_lay = landing_loop_memory(l), landing_loop_params(l), landing_loop_state(l)
    xp, uh, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    plant = _named("plant", [xp, uh, w, t, pp],
                   [loop_plant_function(not welded)(xp, uh, w, t, pp)],
                   ["xp", "uh", "w", "t", "pp"], ["xp_dot"])
    free_plant = None if welded else _named(
        "free_plant", [xp, uh, w, t, pp], [loop_plant_function(False)(xp, uh, w, t, pp)],
        ["xp", "uh", "w", "t", "pp"], ["xp_dot"])

    xc, pc, first = xc_lay.sym(), pc_lay.sym(), ca.SX.sym("first")
    cs, ps = xc_lay.unpack(xc), pc_lay.unpack(pc)
    y = measurement_function()(xp, t, ps["pp"])
    cues = measured_cues(y, ps["p_guid"])
    switch = contact_switch(LANDING_PLANT_STATE.unpack(xp)["gear"])
    cues = ca.vertcat(cues[0], cues[1], switch)             # the gear's switch, too
    args, xc_next, rec, res = landing_flight_step(l, y, cues, cs, ps)
    step_args = _named("step_args", [xp, xc, pc, first, t], list(args.values()),
                       ["xp", "xc", "pc", "first", "t"], list(args))
    controller = _named("controller", [xp, xc, pc, first, t],
                        [xc_next, res["F_cmd"], rec, res["tilt"]],
                        ["xp", "xc", "pc", "first", "t"], ["xc_next", "uh", "rec", "guard"])

    assemble = _named("assemble", [xp, xc], [ca.vertcat(xp, xc)], ["xp", "xc"], ["x"])
    ride_rhs, ride_row = landing_ride_functions(l) if welded else (None, None)
    x = x_lay.sym()
    output_fn = _named("outputs", [x, w, t, pp], [loop_outputs(l, x, w, t, pp)],
                       ["x", "w", "t", "p"], ["y"])
    gap = gear_gap_function() if welded else first_contact_function()
    event = _named("event", [xp, t, pp], [gap(xp, t, pp)], ["xp", "t", "pp"], ["g"])
    return LoopModel("landing_welded" if welded else "landing", x_lay, LANDING_DISTURBANCE,
                     LANDING_PLANT_PARAMS, LANDING_SIGNALS,
                     None, output_fn,
                     LANDING_PLANT_STATE, COMMAND, xc_lay, LANDING_PLANT_PARAMS, pc_lay,
                     LANDING_RECORDED, plant,
                     controller, assemble, step_args=step_args, event=event,
                     envelope=_named("envelope", [x, uh], [landing_envelope_function(l)(x, uh)],
                                     ["x", "uh"], ["s"]),
                     envelope_layout=LANDING_ENVELOPE, flight="landing_flight_controller.c.jinja",
                     ride_rhs=ride_rhs, ride_row=ride_row, event_continues=not welded,
                     free_plant=free_plant)

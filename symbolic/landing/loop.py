"""The landing loop as the simulator sees it: plant with wind, sensors, guidance, landing step.

:func:`landing_loop` bundles, in the shape of :class:`symbolic.simulation.LoopModel`:

* **plant** ``plant(xp, F_cmd, w, t, pp)``: the landing plant
  (:mod:`symbolic.landing.plant`) under the held disturbance ``w``
  (:data:`LANDING_DISTURBANCE`): the wind velocity in E and the body-frame
  ``[d_F, d_M]``. The rotor drag of eq. (2) acts on the velocity relative to
  the air, ``-Kt (V1 - R(eta1)^T v_wind)``, so the wind adds the body force
  ``Kt R(eta1)^T v_wind`` (:func:`wind_force`) to ``d_F``;
* **controller** ``controller(xp, xc, pc, first, t)``: perfect sensors
  (:func:`~symbolic.landing.controller.measurement_function`), then one
  guidance step (:func:`~symbolic.landing.controller.landing_guidance`) whose
  reference feeds one landing step
  (:func:`~symbolic.landing.controller.landing_law`), both at the control
  rate; the memory ``xc`` (:func:`landing_loop_memory`) is the guidance's state
  (the phase among it) and the step's; the held input is the rotor commands,
  the guard the measured tilt; **step_args** gives both steps' arguments, for
  the flight code behind the same signature (``controller.backend = "c"``);
* **event** ``event(xp, t, pp)``: the gear gap; touchdown ends the
  integration at the instant it happens;
* **assemble** ``x = [xp, xc]`` and **outputs** ``y`` (:func:`loop_outputs`):
  the signals of the landing trajectory.

After touchdown the quadrotor rides on the deck, pinned at its touchdown
pose with its rotors idle; :func:`landed_outputs_function` gives the same
signals from the vehicle's state, the deck's motion and that pose.
"""

from __future__ import annotations

import functools

import casadi as ca

from symbolic.guidance import GUIDANCE_PARAMS, GUIDANCE_STATE, POSITION_REFERENCE
from symbolic.kinematics import rotation
from symbolic.landing.controller import (
    landing_controller_params,
    landing_guidance,
    landing_law,
    landing_memory,
    landing_step_outputs,
    measurement_function,
)
from symbolic.landing.deck import DECK_POSE, deck_pose, time_derivative, vee
from symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE, landing_plant_rhs
from symbolic.landing.quadrotor import COMMAND, QUAD6_STATE
from symbolic.landing.relative import RELATIVE6, gear_gap, relative6
from symbolic.layout import Field, Layout
from symbolic.parameters import QUADROTOR
from symbolic.quadrotor import BODY_DISTURBANCE, WRENCH, wrench_from_rotors
from symbolic.simulation import LoopModel
from symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

__all__ = ["LANDING_DISTURBANCE", "LANDING_RECORDED", "LANDING_SIGNALS", "ANCHOR", "wind_force",
           "landing_loop_memory",
           "landing_loop_params", "landing_loop_state", "loop_outputs", "loop_plant_function",
           "landing_signals_function", "gear_gap_function", "landed_outputs_function",
           "anchor_function", "LANDING_TRAJECTORY", "LANDING_ENVELOPE",
           "landing_envelope_function", "landing_loop"]

#: The held disturbance of the landing loop: wind in E, then eq. (2)'s d_F, d_M.
LANDING_DISTURBANCE = Layout("w_land", (
    Field("v_wind", 3, "m/s", "wind velocity in E", elements=("vx_wind", "vy_wind", "vz_wind")),
    *BODY_DISTURBANCE.fields,
), "wind velocity (E) and the disturbance force and moment (body)")

#: What the loop records of each control step (held until the next).
LANDING_RECORDED = Layout("rec_land", (
    COMMAND["F_cmd"],
    landing_step_outputs(1)["eta_d"],
    POSITION_REFERENCE["p_ref"],
    landing_step_outputs(1)["limits"],
), "the landing step's commands, attitude reference, position reference and limit flags")

#: The landing trajectory's signals (one vector, the simulator's ``y``).
LANDING_SIGNALS = Layout("y_land", (
    Field("phase", 1, "-", "guidance phase (symbolic.guidance.PHASES)"),
    QUAD6_STATE["p1"],
    QUAD6_STATE["eta1"],
    DECK_POSE["p2"],
    DECK_POSE["eta2"],
    *RELATIVE6.fields,
    Field("F_total", 1, "N", "thrust acting (the rotor states, after motor lag and limits)"),
    Field("M", 3, "N m", "body moments of the rotor states", elements=("M_x", "M_y", "M_z")),
    QUAD6_STATE["F"],
    Field("d_F", 3, "N", "every external force but thrust, gravity and eq. 2's drag "
          "(wind, disturbance, contact), body frame", elements=("d_Fx", "d_Fy", "d_Fz")),
    Field("d_M", 3, "N m", "every external moment but the rotors' and eq. 2's drag, body "
          "frame", elements=("d_Mx", "d_My", "d_Mz")),
    Field("aborts", 1, "-", "aborted descents so far"),
), "landing signals: both bodies in E, the relative state, rotors, external forces")

#: The columns of a landing's trajectory.csv (``quadland simulate`` and the
#: generated C example ``land``): the time, then these :data:`LANDING_SIGNALS`.
LANDING_TRAJECTORY = Layout("landing_trajectory", (
    Field("t", 1, "s", "time"),
    *(LANDING_SIGNALS[n] for n in ("phase", "p1", "eta1", "p2", "eta2", "p_e", "F_total", "M", "F",
                           "d_F")),
), "one row per output time of a landing, and one at touchdown")

#: The pose at which the quadrotor is pinned to the deck after touchdown.
ANCHOR = Layout("anchor", (
    Field("p_e", 3, "m", "the quadrotor's centre in the deck frame at touchdown"),
    Field("R_rel", 9, "-", "R_deck^T R(eta1) at touchdown", shape=(3, 3)),
), "the quadrotor's pose on the deck")


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
), "magnitudes checked against the landing's flight envelope")


def wind_force(eta1, v_wind, p_quad):
    """Body force of the wind through eq. (2)'s drag: ``Kt R(eta1)^T v_wind``, N."""
    return QUADROTOR.unpack(p_quad)["Kt"] * (rotation(eta1).T @ v_wind)


def _body_disturbance(xp, w, pp):
    """``[d_F + wind_force, d_M]``: the landing plant's disturbance input."""
    ws = LANDING_DISTURBANCE.unpack(w)
    eta1 = QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(xp)["x1q"])["eta1"]
    d_F = ws["d_F"] + wind_force(eta1, ws["v_wind"], LANDING_PLANT_PARAMS.unpack(pp)["p_quad"])
    return ca.vertcat(d_F, ws["d_M"])


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


def _signals(x1q, xv, t, pp, d_F, d_M, phase, aborts):
    """The :data:`LANDING_SIGNALS` vector of a quadrotor state with its external forces."""
    p = LANDING_PLANT_PARAMS.unpack(pp)
    q = QUAD6_STATE.unpack(x1q)
    deck = deck_pose(xv, t, p["p_veh"], p["p_deck"])
    rel = relative6(x1q, xv, t, p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])
    return ca.vertcat(phase, q["p1"], q["eta1"], deck.p2, deck.eta2, *rel,
                      wrench_from_rotors(q["F"], p["p_quad"]), q["F"], d_F, d_M, aborts)


def loop_outputs(l: int, x, w, t, pp):
    """The :data:`LANDING_SIGNALS` of the loop state ``x`` (:func:`landing_loop_state`) under
    ``w``."""
    xs = landing_loop_state(l).unpack(x)
    xg = landing_loop_memory(l).unpack(xs["xc"])["xg"]
    return landing_signals_function()(xs["xp"], xg, w, t, pp)


@functools.cache
def loop_plant_function() -> ca.Function:
    """``landing_loop_plant(xp, F_cmd, w, t, pp) -> xp_dot``: the landing plant under
    the loop's disturbance ``w`` (:data:`LANDING_DISTURBANCE`: wind in E, body ``d_F``, ``d_M``)."""
    xp, F_cmd, w, t, pp = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym(), \
        ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    return ca.Function("landing_loop_plant", [xp, F_cmd, w, t, pp],
                       [landing_plant_rhs(xp, F_cmd, _body_disturbance(xp, w, pp), t, pp)],
                       ["xp", "F_cmd", "w", "t", "pp"], ["xp_dot"])


@functools.cache
def landing_signals_function() -> ca.Function:
    """``landing_signals(xp, xg, w, t, pp) -> y``: :data:`LANDING_SIGNALS` in flight.

    The plant's state ``xp``, the guidance's state ``xg`` (its phase and
    abort count) and the disturbance ``w`` (:data:`LANDING_DISTURBANCE`).
    """
    xp, xg, w, t, pp = LANDING_PLANT_STATE.sym(), GUIDANCE_STATE.sym(), LANDING_DISTURBANCE.sym(), \
        ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    ps, gs = LANDING_PLANT_STATE.unpack(xp), GUIDANCE_STATE.unpack(xg)
    d = BODY_DISTURBANCE.unpack(_body_disturbance(xp, w, pp))
    y = _signals(ps["x1q"], ps["xv"], t, pp, d["d_F"], d["d_M"], gs["phase"], gs["aborts"])
    return ca.Function("landing_signals", [xp, xg, w, t, pp], [y],
                       ["xp", "xg", "w", "t", "pp"], ["y"])


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
    xv_dot = vehicle_rhs(xv, p["p_veh"])

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
    y = _signals(x1q, xv, t, pp, d_F, d_M, phase, aborts)
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
                   ca.mmax(ca.fabs(mem["zeta_hat"])))
    return ca.Function("envelope", [x, uh], [s], ["x", "uh"], ["s"])


def _named(name, ins, outs, in_names, out_names):
    return ca.Function(name, ins, outs, in_names, out_names)


@functools.cache
def landing_loop(l: int) -> LoopModel:
    """The landing loop for ``l`` RBF nodes (see the module docstring).

    Sampled-data only: the landing step runs at the control rate (``pc``'s
    ``dt``) and its rotor commands are held; there is no continuous loop
    (``rhs`` is None). ``p`` of ``outputs`` is the plant's ``pp``.
    """
    xc_lay, pc_lay, x_lay = landing_loop_memory(l), landing_loop_params(l), landing_loop_state(l)
    xp, uh, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    plant = _named("plant", [xp, uh, w, t, pp], [loop_plant_function()(xp, uh, w, t, pp)],
                   ["xp", "uh", "w", "t", "pp"], ["xp_dot"])

    xc, pc, first = xc_lay.sym(), pc_lay.sym(), ca.SX.sym("first")
    cs, ps = xc_lay.unpack(xc), pc_lay.unpack(pc)
    plant_p = LANDING_PLANT_PARAMS.unpack(ps["pp"])
    y = measurement_function()(xp, t, ps["pp"])
    args = dict(y=y, xg=cs["xg"], mem=cs["mem"], p_ctrl=ps["p_ctrl"], p_quad=plant_p["p_quad"],
                p_act=plant_p["p_act"], p_guid=ps["p_guid"], dt=ps["dt"])
    step_args = _named("step_args", [xp, xc, pc, first, t], list(args.values()),
                       ["xp", "xc", "pc", "first", "t"], list(args))
    xg_next, ref = landing_guidance(cs["xg"], y, ps["dt"], ps["p_guid"])
    res = landing_law(l, y, ref, cs["mem"], ps["p_ctrl"], plant_p["p_quad"], plant_p["p_act"],
                      ps["dt"])
    rec = ca.vertcat(res["F_cmd"], res["eta_d"], POSITION_REFERENCE.unpack(ref)["p_ref"],
                     res["limits"])
    controller = _named("controller", [xp, xc, pc, first, t],
                        [ca.vertcat(xg_next, res["mem_next"]), res["F_cmd"], rec, res["tilt"]],
                        ["xp", "xc", "pc", "first", "t"], ["xc_next", "uh", "rec", "guard"])

    assemble = _named("assemble", [xp, xc], [ca.vertcat(xp, xc)], ["xp", "xc"], ["x"])
    x = x_lay.sym()
    output_fn = _named("outputs", [x, w, t, pp], [loop_outputs(l, x, w, t, pp)],
                       ["x", "w", "t", "p"], ["y"])
    event = _named("event", [xp, t, pp], [gear_gap_function()(xp, t, pp)],
                   ["xp", "t", "pp"], ["g"])
    return LoopModel("landing", x_lay, LANDING_DISTURBANCE, LANDING_PLANT_PARAMS, LANDING_SIGNALS,
                     None, output_fn,
                     LANDING_PLANT_STATE, COMMAND, xc_lay, LANDING_PLANT_PARAMS, pc_lay,
                     LANDING_RECORDED, plant,
                     controller, assemble, step_args=step_args, event=event,
                     envelope=_named("envelope", [x, uh], [landing_envelope_function(l)(x, uh)],
                                     ["x", "uh"], ["s"]),
                     envelope_layout=LANDING_ENVELOPE, flight="landing_flight_controller.c.jinja")

"""The landing loop on what the aircraft can know: sensors, delivery, the navigation filter.

:func:`landing_sensed_loop` is :func:`quadland_symbolic.landing.loop.landing_loop` with
its perfect measurements replaced by the world's sensors and the flight code's
navigation filter. The plant, the event, the envelope, the loop state ``x = [xp, xg,
mem]`` and the ride after touchdown are the same; the controller, at each control
tick ``t_k`` (period ``T``), does, in this order:

1. **World: sampling.** Each sensor of
   :data:`~quadland_symbolic.landing.sensors.SENSOR_NAMES` reads the true plant
   (``sense_<name>(xp, uh, w, t, pp, p_sens, noise)``, the plant's own parameters
   ``pp``, not the controller's model) with this tick's noise row. A sensor samples
   on the control clock: its tick row's ``<name>_sampled`` is 1 on the ticks of its
   rate (drawn by :mod:`quadland.kinds.landing.sensing`), and ``<name>_kept`` is 0
   for a packet the link loses. The packet is ``fresh`` when sampled, kept and (for
   the camera and the range finder) valid, stamped with its capture time ``tau =
   t_k``.
2. **World: delivery.** The packet enters the sensor's delay line (``line_<name>``,
   :data:`DELIVERY_SLOTS` packets) and leaves it ``delay_<name>`` ticks later: a
   packet of latency ``L`` arrives at ``t_k + L`` and is read at the first control
   tick at or after it, ``delay = ceil(L / T)``. The latency is constant per sensor,
   so packets arrive in the order they were taken, at most one per tick.
3. **Flight code: the IMU.** The IMU's packet of this tick (or the last one
   delivered, held, when none arrives).
4. **Flight code: the filter.** One step of the navigation filter
   (:func:`~quadland_symbolic.landing.estimator.estimator_step_function` at its flight
   sizes :data:`~quadland_symbolic.landing.estimator.FLIGHT_DEPTH`,
   :data:`~quadland_symbolic.landing.estimator.FLIGHT_COUPLING`) on the delivered
   packets; its output is the controller's measurement.
5. **Flight code: the land detector** (:mod:`quadland_symbolic.landing.land_detector`)
   on its cues (:func:`detector_cues`): the delivered range, the estimated gear gap
   and vertical speed, the thrust acting now over the model's hover thrust, the
   IMU's specific force along body z and the guidance's phase. Its ground-contact
   stage is the guidance's ``touchdown`` cue, the gear's contact switch
   (:func:`~quadland_symbolic.landing.gear.contact_switch`, the touchdown
   policy's) its ``contact_switch`` cue; the time since the filter last fused
   a marker detection (the memory's ``marker_age``) is its ``marker_age``.
6. **Flight code: guidance and landing step** on the estimate and those cues, with
   the controller's own model ``pc.pp``
   (:func:`~quadland_symbolic.landing.loop.landing_flight_step`).

The recorded signals add the estimate and the filter's health to the unsensed
loop's (:data:`SENSED_RECORDED`).

The model's **step_args** (same signature as the controller) gives the flight code's
arguments: the world's next delay lines, the packets read now and the IMU of step 3,
the flight memory and parameters. With ``controller.backend = "c"`` the compiled
simulator flies steps 4 to 6 as the generated flight C behind the controller's
signature (``ql_estimator_step``, ``ql_land_detector_form_cues``,
``ql_land_detector_step``, ``ql_guidance_step``, ``ql_landing_step``;
``symbolic/templates/landing_sensed_flight_controller.c.jinja``), the world part and
the IMU's hold staying CasADi's.
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    landing_controller_params,
    landing_memory,
)
from quadland_symbolic.landing.delivery import (
    DELIVERY_SLOTS,
    NAV_PACKET_OF,
    deliver,
    delivery_delay,
    delivery_record,
    push_stage,
    read_stage,
    sensor_record,
)
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_diagnostics,
    estimator_memory,
)
from quadland_symbolic.landing.estimator_switch import conditional_step_stages
from quadland_symbolic.landing.gear import contact_switch
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
)
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_FLAGS,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    TIME_CAP,
    land_detector_function,
)
from quadland_symbolic.landing.loop import (
    LANDING_RECORDED,
    landing_flight_step,
    landing_loop,
    landing_ride_functions,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    IMU,
    NAV,
    covariance_pattern,
    estimator_params,
)
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.quadrotor import COMMAND
from quadland_symbolic.landing.relative import deck_gear_gap
from quadland_symbolic.landing.sensors import (
    NOISES,
    SENSOR_NAMES,
    SENSOR_PARAMS,
)
from quadland_symbolic.landing.signals import LANDING_SIGNALS, LANDING_TRAJECTORY
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.stages import Staged

__all__ = ["DELIVERY_SLOTS", "SENSED_TICK", "SENSED_RECORDED", "SENSED_TRAJECTORY", "NAV_PACKET_OF",
           "delivery_record", "delivery_delay", "sensed_loop_memory", "sensed_loop_params",
           "detector_cues", "detector_cues_function", "landing_sensed_loop"]

#: One control tick's row of the world's random draws (``n``).
SENSED_TICK = Layout("n_sensed", tuple(
    f for name in SENSOR_NAMES for f in (
        Field(f"{name}_sampled", 1, "0/1", f"1 when the {name} samples at this tick"),
        Field(f"{name}_kept", 1, "0/1", f"1 unless the {name}'s packet of this tick is lost"),
        Field.nested(f"{name}_noise", NOISES[name], f"the {name}'s noise at this tick"))),
    "per control tick: each sensor's sample flag, delivery flag and noise")

#: The filter's memory at its flight sizes.
_NAV_MEMORY = estimator_memory(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)

#: What the sensed loop records of each control step: the unsensed loop's, the
#: estimate, the filter's horizon standard deviations and each block's NIS; last, the
#: filter's horizon state, covariance and time (its consistency, docs/estimator.md).
SENSED_RECORDED = Layout("rec_sensed", (
    *LANDING_RECORDED.fields,
    Field("p_e_hat", 3, "m", "estimated relative position, deck frame (the step's input)",
          elements=("x_e_hat", "y_e_hat", "z_e_hat")),
    Field("v_e_hat", 3, "m/s", "estimated relative velocity, deck frame",
          elements=("vx_e_hat", "vy_e_hat", "vz_e_hat")),
    Field("sigma_p_r", 3, "m", "filter's standard deviation of p_r at its horizon, E",
          elements=("sigma_p_x", "sigma_p_y", "sigma_p_z")),
    Field("nis", len(BLOCKS), "-", "each block's NIS this step (0: not due, -1: not finite)",
          elements=tuple(f"nis_{b.name}" for b in BLOCKS)),
    Field("fused", len(BLOCKS), "0/1", "each block fused this step",
          elements=tuple(f"fused_{b.name}" for b in BLOCKS)),
    *(f for f in estimator_diagnostics().fields
      if f.name in ("n_fused", "n_rejected", "n_discarded", "n_dropped")),
    estimator_diagnostics()["n_held"],
    Field("marker_age", 1, "s", "time since the filter last fused a marker detection"),
    Field("detector", 3, "0/1", "the land detector's stages",
          elements=("ground_contact", "maybe_landed", "landed")),
    # the filter's memory after the step: the horizon's prior for the next (world-side
    # analysis reads it; the flight code's outputs do not change)
    Field("nav_x_h", NAV.size, NAV.element_units(), "filter state at its horizon t_h",
          elements=tuple(f"x_h_{e}" for e in NAV.element_names())),
    Field("nav_P_h", _NAV_MEMORY["P_h"].size, _NAV_MEMORY["P_h"].unit,
          "its covariance: the stored upper-triangle entries, row by row",
          elements=covariance_pattern(FLIGHT_COUPLING).element_names("P_h")),
    Field("nav_t_h", 1, "s", "the horizon's time t_h", elements=("t_h",)),
), "the landing step's signals, the navigation estimate and the filter's health")


#: The columns of a sensed landing's trajectory.csv: the unsensed one's, the true
#: relative velocity, and the filter's estimate and standard deviations beside them.
SENSED_TRAJECTORY = Layout("sensed_trajectory", (
    *LANDING_TRAJECTORY.fields, LANDING_SIGNALS["v_e"],
    *(SENSED_RECORDED[n] for n in ("p_e_hat", "v_e_hat", "sigma_p_r")),
), "one row per output time of a sensed landing, and one at touchdown")


@functools.cache
def sensed_loop_memory(l: int) -> Layout:
    """The sensed loop's memory: guidance, landing step, filter, held IMU, delay lines."""
    return Layout("xc_sensed", (
        Field.nested("xg", GUIDANCE_STATE, "guidance: phase, dwell timer, z_ref, aborts"),
        Field.nested("mem", landing_memory(l), "landing step: network, filter, compensator"),
        Field.nested("nav", estimator_memory(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING),
                     "navigation filter (flight code)"),
        Field.nested("imu_held", IMU, "the last IMU packet delivered (flight code)"),
        Field.nested("xld", LAND_DETECTOR_STATE, "land detector (flight code)"),
        Field("marker_age", 1, "s", "time since the filter last fused a marker detection "
              "(flight code)"),
        *(Field(f"line_{name}", DELIVERY_SLOTS * delivery_record(name).size, "-",
                f"{name} packets in delivery, newest first (world)")
          for name in SENSOR_NAMES),
    ), "sensed landing loop memory")


@functools.cache
def sensed_loop_params(l: int) -> Layout:
    """The sensed loop's controller parameters: the flight code's, then the world's sensors."""
    return Layout("pc_sensed", (
        Field.nested("pp", LANDING_PLANT_PARAMS, "the controller's own model of the plant"),
        Field.nested("p_ctrl", landing_controller_params(l), "landing step"),
        Field.nested("p_guid", GUIDANCE_PARAMS, "guidance"),
        Field("dt", 1, "s", "control period"),
        Field.nested("p_est", estimator_params(), "navigation filter"),
        Field.nested("p_ld", LAND_DETECTOR_PARAMS, "land detector"),
        Field.nested("p_sens", SENSOR_PARAMS, "the sensors' truth models (world)"),
        Field("delay", len(SENSOR_NAMES), "ticks", "each sensor's delivery delay (world)",
              elements=tuple(f"delay_{n}" for n in SENSOR_NAMES)),
    ), "sensed landing loop controller parameters")


def detector_cues(y, range_read, imu_now, uh_held, cs: dict, ps: dict):
    """The land detector's :data:`~quadland_symbolic.landing.land_detector.LAND_DETECTOR_CUES`.

    ``y``: the filter's :data:`LANDING_MEASUREMENT`; ``range_read``: the range
    finder's delivered record (:func:`delivery_record`); ``imu_now``: this tick's
    IMU packet; ``uh_held``: the rotor commands acting now. The ranged gap is
    ``(s - h) n2 . b3`` (the beam and the gear both along ``-b3``, ``h`` the gear's
    height below the centre, ``n2`` the deck normal from the broadcast attitude);
    the thrust ratio uses the controller's own model of mass and gravity.
    """
    return _cues(y, range_read, imu_now, uh_held, cs["xg"], ps["p_guid"],
                 LANDING_PLANT_PARAMS.unpack(ps["pp"])["p_quad"])


def _cues(y, range_read, imu_now, uh_held, xg, p_guid, p_quad):
    """:func:`detector_cues` on the guidance's state and parameters and the model's ``p_quad``."""
    m, r = LANDING_MEASUREMENT.unpack(y), delivery_record("rangefinder").unpack(range_read)
    h = GUIDANCE_PARAMS.unpack(p_guid)["touchdown_height"]
    R2 = rotation(m["eta2"])
    quad = QUADROTOR.unpack(p_quad)
    return ca.vertcat(
        (r["s"] - h) * (R2[:, 2].T @ r["b3_E"]), r["fresh"],
        deck_gear_gap(m["p_e"], R2, rotation(m["eta1"]), h), m["v_e"][2],
        ca.sum1(uh_held) / (quad["m1"] * quad["g"]),
        IMU.unpack(imu_now)["f_b"][2],
        GUIDANCE_STATE.unpack(xg)["phase"] == DESCEND)


@functools.cache
def detector_cues_function() -> ca.Function:
    """``land_detector_cues(y, range, imu, F_cmd, xg, p_guid, p_quad) -> cues``.

    :func:`detector_cues` as one Function, the flight code's
    (``ql_land_detector_form_cues``): ``range`` the range finder's packet
    (:data:`~quadland_symbolic.landing.navigation.RANGE`, the layout of its delivery
    record), ``imu`` this period's IMU, ``F_cmd`` the rotor commands acting now,
    ``xg`` the guidance's state, ``p_quad`` the controller's model of the quadrotor.
    """
    y, rng, imu = LANDING_MEASUREMENT.sym(), delivery_record("rangefinder").sym(), IMU.sym()
    F_cmd, xg, p_guid, p_quad = COMMAND.sym(), GUIDANCE_STATE.sym(), GUIDANCE_PARAMS.sym(), \
        QUADROTOR.sym()
    return ca.Function("land_detector_cues", [y, rng, imu, F_cmd, xg, p_guid, p_quad],
                       [_cues(y, rng, imu, F_cmd, xg, p_guid, p_quad)],
                       ["y", "range", "imu", "F_cmd", "xg", "p_guid", "p_quad"], ["cues"])


def _world_stage(xc_lay, pc_lay, contact: bool = True) -> ca.Function:
    """``sensed_world``: steps 1 and 2 up to the lines (the sensors: each one's record of
    this tick, :func:`~quadland_symbolic.landing.delivery.sensor_record`). ``contact =
    False``: the IMU's specific force of the plant without the gear's contact, the
    stage's :attr:`~quadland_symbolic.stages.Staged.free` function (the same values
    where the loop flies its free plant; the contact's exp, log1p and tanh a foot, some
    1,205 of the IMU record's 2,180 operations, not evaluated)."""
    xp, uh, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    xc, pc, n = xc_lay.sym(), pc_lay.sym(), SENSED_TICK.sym()
    ps, tick = pc_lay.unpack(pc), SENSED_TICK.unpack(n)
    records = [ca.densify(sensor_record(name, xp, uh, w, t, pp, ps["p_sens"], tick, contact))
               for name in SENSOR_NAMES]
    return ca.Function("sensed_world", [xp, xc, pc, t, uh, w, pp, n], records,
                       ["xp", "xc", "pc", "t", "uh_held", "w", "pp", "n"],
                       [f"record_{name}" for name in SENSOR_NAMES], {"cse": True})


def _imu_stage(xc_lay) -> ca.Function:
    """``sensed_imu``: step 3, this tick's IMU packet or the last one delivered."""
    xc, read = xc_lay.sym(), delivery_record("imu").sym("read_imu")
    imu_rec = delivery_record("imu").unpack(read)
    imu_now = ca.if_else(imu_rec["fresh"], ca.vertcat(*(imu_rec[f.name] for f in IMU.fields)),
                         xc_lay.unpack(xc)["imu_held"])
    return ca.Function("sensed_imu", [xc, read], [ca.densify(imu_now)], ["xc", "read_imu"],
                       ["imu_now"])


#: The filter's packets as the sensed loop's stages name them.
_PACKETS = ("vision", "gnss", "range", "datalink")


#: The filter's values as the sensed loop's stages name them (the rest ``nav_<name>``).
_FILTER_NAMES = dict(mem="nav", imu="imu_now", range="range", p_est="p_est", dt="dt", t="t",
                     mem_next="nav_next", y="y", diag="diag")


def _filter_stages() -> tuple[ca.Function, ca.Function]:
    """``sensed_filter`` and ``sensed_finish``: step 4, the filter's updates evaluated
    only when due, then its memory, measurements and diagnostics written where they go
    (:func:`~quadland_symbolic.landing.estimator_switch.conditional_step_stages`)."""
    return conditional_step_stages(
        N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING, names=("sensed_filter", "sensed_finish"),
        rename=lambda n: n if n in _PACKETS else _FILTER_NAMES.get(n, f"nav_{n}"))


def _flight_stage(l, xc_lay, pc_lay):
    """``sensed_flight``: steps 5 and 6 on the filter's output, and the recorded signals."""
    xp, uh, t, first = LANDING_PLANT_STATE.sym(), COMMAND.sym(), ca.SX.sym("t"), \
        ca.SX.sym("first")
    xc, pc, imu_now = xc_lay.sym(), pc_lay.sym(), IMU.sym("imu_now")
    rng = delivery_record("rangefinder").sym("range")
    nav_next, y = _NAV_MEMORY.sym("nav_next"), LANDING_MEASUREMENT.sym("y")
    diag = estimator_diagnostics().sym("diag")
    cs, ps = xc_lay.unpack(xc), pc_lay.unpack(pc)
    m, d = LANDING_MEASUREMENT.unpack(y), estimator_diagnostics().unpack(diag)
    xld_next, flags = land_detector_function()(
        cs["xld"], detector_cues(y, rng, imu_now, uh, cs, ps), ps["p_ld"], ps["dt"])
    fl = LAND_DETECTOR_FLAGS.unpack(flags)
    seen = d["fused"][[b.name for b in BLOCKS].index("vision")]
    marker_age = ca.if_else(seen >= 0.5, 0, ca.fmin(cs["marker_age"] + ps["dt"], TIME_CAP))
    switch = contact_switch(LANDING_PLANT_STATE.unpack(xp)["gear"])
    cues = ca.vertcat(fl["ground_contact"], marker_age, switch)
    _, xgm_next, rec, res = landing_flight_step(l, y, cues, cs, ps)
    sigma = ca.sqrt(ca.fmax(d["P_diag"][0:3], 0))
    nav = _NAV_MEMORY.unpack(nav_next)
    rec = ca.vertcat(rec, m["p_e"], m["v_e"], sigma, d["nis"], d["fused"], d["n_fused"],
                     d["n_rejected"], d["n_discarded"], d["n_dropped"], d["n_held"],
                     marker_age, fl["ground_contact"], fl["maybe_landed"], fl["landed"],
                     nav["x_h"], nav["P_h"], nav["t_h"])
    return ca.Function(
        "sensed_flight", [xp, xc, pc, first, t, uh, imu_now, rng, nav_next, y, diag],
        [ca.densify(v) for v in (xgm_next, xld_next, marker_age, res["F_cmd"], rec,
                                 res["tilt"])],
        ["xp", "xc", "pc", "first", "t", "uh_held", "imu_now", "range", "nav_next", "y",
         "diag"], ["xgm_next", "xld_next", "marker_age_next", "uh", "rec", "guard"],
        {"cse": True})


def _step_args(l, xc_lay, pc_lay) -> ca.Function:
    """The flight code's arguments, for the flight C behind the controller's signature."""
    xp, uh, w = LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    xc, pc, first, n = xc_lay.sym(), pc_lay.sym(), ca.SX.sym("first"), SENSED_TICK.sym()
    cs, ps, tick = xc_lay.unpack(xc), pc_lay.unpack(pc), SENSED_TICK.unpack(n)
    delays = dict(zip(SENSOR_NAMES, ca.vertsplit(ps["delay"]), strict=True))
    read, lines = {}, []
    for name in SENSOR_NAMES:
        read[name], line_next = deliver(name, xp, uh, w, t, pp, ps["p_sens"], tick,
                                         cs[f"line_{name}"], delays[name])
        lines.append(line_next)
    imu_rec = delivery_record("imu").unpack(read["imu"])
    imu_now = ca.if_else(imu_rec["fresh"], ca.vertcat(*(imu_rec[f.name] for f in IMU.fields)),
                         cs["imu_held"])
    packets = [read[name] for name in ("vision", "gnss", "rangefinder", "datalink")]
    plant_p = LANDING_PLANT_PARAMS.unpack(ps["pp"])
    args = dict(imu=imu_now, **dict(zip(_PACKETS, packets, strict=True)), nav=cs["nav"],
                p_est=ps["p_est"], dt=ps["dt"], time=t, F_cmd=uh, xld=cs["xld"],
                p_ld=ps["p_ld"], marker_age=cs["marker_age"], xg=cs["xg"], mem=cs["mem"],
                p_guid=ps["p_guid"], p_ctrl=ps["p_ctrl"], p_quad=plant_p["p_quad"],
                p_act=plant_p["p_act"],
                contact_switch=contact_switch(LANDING_PLANT_STATE.unpack(xp)["gear"]),
                **{f"line_{name}": line for name, line in zip(SENSOR_NAMES, lines,
                                                               strict=True)})
    return ca.Function("step_args", [xp, xc, pc, first, t, uh, w, pp, n], list(args.values()),
                       ["xp", "xc", "pc", "first", "t", "uh_held", "w", "pp", "n"], list(args))


@functools.cache
def landing_sensed_loop(l: int, welded: bool = False) -> LoopModel:
    """The landing loop for ``l`` RBF nodes flying on sensors and the filter (module docstring);
    ``welded`` as in :func:`~quadland_symbolic.landing.loop.landing_loop`.

    Its controller is an MX Function of stages (:class:`quadland_symbolic.stages.
    Staged`): ``sensed_world`` (step 1, each sensor's record of the tick),
    ``sensed_push_<name>`` (step 2, the record into its delay line: a ring in the
    compiled simulator, :attr:`~quadland_symbolic.stages.Staged.rings`),
    ``sensed_read_<name>`` (step 2's reading), ``sensed_imu`` (step 3),
    ``sensed_filter`` (step 4, each sensor's updates evaluated only when due),
    ``sensed_finish`` (its memory, measurements and diagnostics, written where they go)
    and ``sensed_flight`` (steps 5 and 6).
    """
    base, xc_lay, pc_lay = landing_loop(l, welded), sensed_loop_memory(l), sensed_loop_params(l)
    stages = Staged(
        "controller",
        (_world_stage(xc_lay, pc_lay), *(push_stage(name) for name in SENSOR_NAMES),
         *(read_stage(name) for name in SENSOR_NAMES),
         _imu_stage(xc_lay), *_filter_stages(), _flight_stage(l, xc_lay, pc_lay)),
        inputs=(("xp", LANDING_PLANT_STATE.size), ("xc", xc_lay.size), ("pc", pc_lay.size),
                ("first", 1), ("t", 1), ("uh_held", COMMAND.size),
                ("w", LANDING_DISTURBANCE.size), ("pp", LANDING_PLANT_PARAMS.size),
                ("n", SENSED_TICK.size)),
        # the memory's fields in order (sensed_loop_memory): xg and mem, nav, imu_held,
        # xld, marker_age, the lines
        outputs=(("xc_next", ("xgm_next", "nav_next", "imu_now", "xld_next",
                              "marker_age_next", *(f"line_{s}" for s in SENSOR_NAMES))),
                 ("uh", ("uh",)), ("rec", ("rec",)), ("guard", ("guard",))),
        slices=(*((n, src, lay.slice(f).start, lay.slice(f).stop)
                  for n, src, lay, f in (("nav", "xc", xc_lay, "nav"),
                                         ("p_est", "pc", pc_lay, "p_est"),
                                         ("dt", "pc", pc_lay, "dt"))),
                *((f"delay_{s}", "pc", pc_lay.slice("delay").start + i,
                   pc_lay.slice("delay").start + i + 1)
                  for i, s in enumerate(SENSOR_NAMES)),
                *((f"past_{s}", "xc", xc_lay.slice(f"line_{s}").start,
                   xc_lay.slice(f"line_{s}").stop) for s in SENSOR_NAMES)),
        # each line a ring in the compiled simulator: no shift of 3,200 values a tick
        rings=tuple((f"line_{s}", f"record_{s}", f"past_{s}") for s in SENSOR_NAMES),
        # far from the deck the IMU's truth without the gear's contact, as the plant's
        free=() if welded else (("sensed_world", _world_stage(xc_lay, pc_lay, False)),))
    controller = stages.function()
    xp, xc = LANDING_PLANT_STATE.sym(), xc_lay.sym()
    cs = xc_lay.unpack(xc)
    assemble = ca.Function("assemble", [xp, xc], [ca.vertcat(xp, cs["xg"], cs["mem"])],
                           ["xp", "xc"], ["x"])
    ride_rhs, ride_row = landing_ride_functions(l, SENSED_RECORDED) if welded else (None, None)
    # the plant, the outputs, the event and the envelope are the unsensed loop's own
    return dataclasses.replace(
        base, name="landing_sensed_welded" if welded else "landing_sensed",
        controller_state=xc_lay, controller_params=pc_lay,
        recorded=SENSED_RECORDED, controller=controller, assemble=assemble,
        step_args=_step_args(l, xc_lay, pc_lay),
        flight="landing_sensed_flight_controller.c.jinja",
        ride_rhs=ride_rhs, ride_row=ride_row, tick_inputs=SENSED_TICK,
        controller_stages=stages)

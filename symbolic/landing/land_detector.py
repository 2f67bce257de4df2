"""Land detector: debounced, multi-cue touchdown in three stages.

The guidance of today (:mod:`quadland_symbolic.landing.guidance`) declares the
touchdown on one measured gear-gap sample at or below zero. Read from a
navigation filter's estimate instead of the truth, one noisy sample would
idle the rotors above the deck. This detector, modelled on PX4's multicopter
land detector, asks several independent cues to agree, each for a whole
window, in three stages (docs/land_detector.md gives the design, the
defaults' sources and what PX4 does differently):

1. **ground contact**: the estimated gear gap within ``gap_max``, the
   estimated vertical speed relative to the deck within ``vz_max``, the range
   finder (while it is fresh) agreeing on the gap, and a descent commanded
   (until maybe landed); held for ``contact_time``;
2. **maybe landed**: ground contact and the collective thrust at or below
   ``thrust_low`` of hover (the deck carries the weight); held for
   ``maybe_time``;
3. **landed**: maybe landed, held for ``landed_time``; then latched.

A window is met when the cue's uninterrupted time ``t`` reaches it within half
a step, ``t >= W - dt / 2``: ``W`` rounded to the nearest whole number of
steps. Any break resets that stage's time to zero. Without a fresh range and
without a touchdown spike of the accelerometer in the last ``spike_window``,
every window is ``no_range_factor`` times longer (PX4 triples its windows
when the range finder it has is not valid). While a stage is set, its gap and
speed thresholds widen by ``hold_factor``, so that the stage is not dropped
by the noise that could not set it (hysteresis); a stage drops at once when a
cue fails even so, taking the later stages with it, until landed latches.

Everything is branch-free (``if_else``, ``fmin``, ``fmax``), one CasADi SX
Function (:func:`land_detector_function`). A non-finite cue fails its test
and never enters the memory; for finite inputs every output is finite. The
zero vector is the initial state.
"""

from __future__ import annotations

import types

import casadi as ca

from quadland_symbolic.layout import Field, Layout

__all__ = ["LAND_DETECTOR_STATE", "LAND_DETECTOR_CUES", "LAND_DETECTOR_PARAMS",
           "LAND_DETECTOR_DEFAULTS", "LAND_DETECTOR_SOURCES", "LAND_DETECTOR_FLAGS", "TIME_CAP",
           "land_detector_step", "land_detector_function"]

#: Largest value a timer holds, s: a bound that keeps the memory finite.
TIME_CAP = 1.0e6


def _flag(name: str, doc: str) -> Field:
    return Field(name, 1, "0 or 1", doc)


#: The detector's memory; the zero vector is the start (and a reset).
LAND_DETECTOR_STATE = Layout("xld", (
    Field("t_contact", 1, "s", "time the ground-contact cues have held without a break"),
    Field("t_maybe", 1, "s", "time the maybe-landed cues have held without a break"),
    Field("t_landed", 1, "s", "time maybe landed has held without a break"),
    _flag("ground_contact", "stage 1 set"),
    _flag("maybe_landed", "stage 2 set"),
    _flag("landed", "stage 3 set (latched)"),
    Field("range_gap", 1, "m", "gear gap of the last fresh valid range"),
    Field("range_hold", 1, "s", "time left during which that range counts as fresh"),
    Field("f_z_mean", 1, "m/s^2", "low-passed specific force along body z"),
    Field("spike_hold", 1, "s", "time left during which the last spike counts"),
    Field("age", 1, "s", "time since the start (0: the first step initialises f_z_mean)"),
), "land detector memory")

#: What the detector reads each control step.
LAND_DETECTOR_CUES = Layout("c_ld", (
    Field("range_gap", 1, "m", "range finder's gear gap: distance along -b3 minus gear height"),
    _flag("range_valid", "1 when range_gap is a fresh, valid range this step"),
    Field("est_gap", 1, "m", "gear gap from the navigation filter's estimate"),
    Field("est_vz", 1, "m/s", "estimated vertical speed relative to the deck (up)"),
    Field("thrust_ratio", 1, "-", "collective thrust command over hover thrust"),
    Field("f_z", 1, "m/s^2", "accelerometer's specific force along body z"),
    _flag("in_descend", "1 while the guidance commands the descent"),
), "land detector cues")

#: The detector's parameters; defaults :data:`LAND_DETECTOR_DEFAULTS`.
LAND_DETECTOR_PARAMS = Layout("p_ld", (
    Field("gap_max", 1, "m", "largest gear gap (estimated or ranged) that reads as contact"),
    Field("vz_max", 1, "m/s", "largest vertical speed relative to the deck that reads as still"),
    Field("thrust_low", 1, "-", "largest thrust ratio that reads as the deck carrying the weight"),
    Field("contact_time", 1, "s", "window of stage 1, ground contact"),
    Field("maybe_time", 1, "s", "window of stage 2, maybe landed"),
    Field("landed_time", 1, "s", "window of stage 3, landed"),
    Field("hold_factor", 1, "-", "widening of gap_max and vz_max while a stage is set"),
    Field("no_range_factor", 1, "-", "lengthening of every window without range or spike"),
    Field("range_timeout", 1, "s", "time a valid range counts as fresh"),
    Field("spike_min", 1, "m/s^2", "smallest jump of f_z from its mean that is a touchdown"),
    Field("spike_window", 1, "s", "time a spike counts as corroboration"),
    Field("accel_tau", 1, "s", "time constant of f_z's running mean"),
    Field("contact_thrust", 1, "0/1", "1: ground contact also needs the thrust at or below "
          "thrust_low (so a hover near the deck is no contact); 0: gap, still and descent"),
), "land detector parameters")

#: Default parameters (docs/land_detector.md, "Defaults").
LAND_DETECTOR_DEFAULTS = types.MappingProxyType(dict(
    gap_max=0.1, vz_max=0.25, thrust_low=0.6,
    contact_time=1.0 / 3.0, maybe_time=1.0 / 3.0, landed_time=1.0 / 3.0,
    hold_factor=2.5, no_range_factor=3.0, range_timeout=0.1,
    spike_min=3.0, spike_window=1.0, accel_tau=0.5, contact_thrust=0.0,
))

#: Where each default comes from (PX4-Autopilot, or a reasoned assumption).
LAND_DETECTOR_SOURCES = types.MappingProxyType(dict(
    gap_max="assumption: 3 sigma of the range finder's noise on the deck (0.031 m)",
    vz_max="PX4 LNDMC_Z_VEL_MAX = 0.25 m/s (touchdown_speed 0.3 m/s / 1.2, PX4's margin)",
    thrust_low="PX4 low-thrust test: 0.6 of the min-to-hover range with a valid hover "
               "thrust, the minimum taken as 0",
    contact_time="PX4 LNDMC_TRIG_TIME = 1.0 s over three stages, a third each",
    maybe_time="PX4 LNDMC_TRIG_TIME / 3",
    landed_time="PX4 LNDMC_TRIG_TIME / 3",
    hold_factor="PX4: speed and rotation thresholds widened 2.5 times once (maybe) landed",
    no_range_factor="PX4: windows tripled while a range finder is fitted but not valid",
    range_timeout="assumption: 12 periods of the 125 Hz range finder",
    spike_min="assumption: a tenth of a 0.3 m/s touchdown on docs/contact.md's gear "
              "(about 30 m/s^2), 8.6 times PX4's EKF2_ACC_NOISE",
    spike_window="assumption: LNDMC_TRIG_TIME, the whole detection",
    accel_tau="assumption: 16 times the 30 ms touchdown pulse, faster than the outer loop",
    contact_thrust="PX4: ground contact needs low thrust as well as a commanded descent "
                   "(MulticopterLandDetector.cpp, the ground-contact state); off by default, "
                   "the detector of before",
))

#: What the detector reports each step (every entry 0 or 1).
LAND_DETECTOR_FLAGS = Layout("f_ld", (
    _flag("ground_contact", "stage 1"),
    _flag("maybe_landed", "stage 2"),
    _flag("landed", "stage 3 (latched)"),
    _flag("gap_cue", "the estimated gap within its threshold"),
    _flag("range_fresh", "a valid range within range_timeout"),
    _flag("range_cue", "a fresh range within the gap threshold"),
    _flag("still_cue", "the estimated vertical speed within its threshold"),
    _flag("thrust_cue", "the thrust ratio at or below thrust_low"),
    _flag("spike_cue", "an accelerometer spike within spike_window"),
    _flag("slow_windows", "neither range nor spike corroborates: windows lengthened"),
), "land detector flags")


def _finite(x):
    """1 where ``x`` is finite (NaN and +-inf fail)."""
    return ca.fabs(x) < ca.inf


def _run(cond, t, dt):
    """A stage's uninterrupted time: ``t + dt`` while ``cond`` holds, else 0."""
    return ca.if_else(cond, ca.fmin(t + dt, TIME_CAP), 0)


def _reached(t, window, dt):
    """Whether ``t`` reaches ``window`` to within half a step."""
    return t >= window - dt / 2


def _corroboration(s, c, p, dt):
    """The range's and the accelerometer's memories and verdicts this step."""
    range_ok = ca.logic_and(c["range_valid"] >= 0.5, _finite(c["range_gap"]))
    range_gap = ca.if_else(range_ok, c["range_gap"], s["range_gap"])
    range_hold = ca.if_else(range_ok, p["range_timeout"], ca.fmax(s["range_hold"] - dt, 0))

    first = s["age"] <= 0
    f_ok = _finite(c["f_z"])
    jump = ca.logic_or(c["f_z"] - s["f_z_mean"] >= p["spike_min"],
                       s["f_z_mean"] - c["f_z"] >= p["spike_min"])
    spike = ca.logic_and(ca.logic_and(ca.logic_not(first), f_ok), jump)
    spike_hold = ca.if_else(spike, p["spike_window"], ca.fmax(s["spike_hold"] - dt, 0))
    # the running mean: exact first-order low pass over dt, seeded by the first sample
    # (clamped between the two: the sum of two huge finite terms could round past them)
    alpha = 1 - ca.exp(-dt / ca.fmax(p["accel_tau"], 1e-12))
    mixed = (1 - alpha) * s["f_z_mean"] + alpha * c["f_z"]
    mixed = ca.fmin(ca.fmax(mixed, ca.fmin(s["f_z_mean"], c["f_z"])),
                    ca.fmax(s["f_z_mean"], c["f_z"]))
    f_mean = ca.if_else(f_ok, ca.if_else(first, c["f_z"], mixed), s["f_z_mean"])
    return range_gap, range_hold, f_mean, spike_hold


def land_detector_step(xld, cues, p_ld, dt):
    """One detector step of length ``dt`` (s).

    Parameters
    ----------
    xld : casadi.SX, (11,)
        :data:`LAND_DETECTOR_STATE` at the start of the step.
    cues : casadi.SX, (7,)
        :data:`LAND_DETECTOR_CUES` of this step.
    p_ld : casadi.SX, (13,)
        :data:`LAND_DETECTOR_PARAMS`.
    dt : casadi.SX
        Step length, s (a negative one counts as 0).

    Returns
    -------
    xld_next : casadi.SX, (11,)
    flags : casadi.SX, (10,)
        :data:`LAND_DETECTOR_FLAGS`, each 0 or 1.
    """
    s, c = LAND_DETECTOR_STATE.unpack(xld), LAND_DETECTOR_CUES.unpack(cues)
    p = LAND_DETECTOR_PARAMS.unpack(p_ld)
    dt = ca.fmax(dt, 0)
    gc, ml, ld = s["ground_contact"] >= 0.5, s["maybe_landed"] >= 0.5, s["landed"] >= 0.5
    range_gap, range_hold, f_mean, spike_hold = _corroboration(s, c, p, dt)
    range_fresh = range_hold > dt / 2
    spike_cue = spike_hold > dt / 2

    # stage 1: thresholds widened while set (hysteresis)
    widen = ca.if_else(gc, p["hold_factor"], 1)
    gap_max, vz_max = p["gap_max"] * widen, p["vz_max"] * widen
    gap_cue = c["est_gap"] <= gap_max
    range_cue = ca.logic_and(range_fresh, range_gap <= gap_max)
    still_cue = ca.fabs(c["est_vz"]) <= vz_max
    slow = ca.logic_not(ca.logic_or(range_fresh, spike_cue))
    factor = ca.if_else(slow, p["no_range_factor"], 1)
    descend = ca.logic_or(c["in_descend"] >= 0.5, ca.logic_or(ml, ld))
    # with contact_thrust, the deck must carry the weight already (PX4's low thrust)
    thrust_cue = c["thrust_ratio"] <= p["thrust_low"]
    carried = ca.logic_or(thrust_cue, p["contact_thrust"] < 0.5)
    contact = ca.logic_and(ca.logic_and(ca.logic_and(gap_cue, still_cue), carried),
                           ca.logic_and(ca.logic_or(range_cue, ca.logic_not(range_fresh)),
                                        descend))
    t_contact = _run(contact, s["t_contact"], dt)
    gc_next = ca.logic_or(ld, ca.logic_and(contact, ca.logic_or(
        gc, _reached(t_contact, p["contact_time"] * factor, dt))))

    # stage 2: the deck carries the weight
    maybe = ca.logic_and(gc_next, thrust_cue)
    t_maybe = _run(maybe, s["t_maybe"], dt)
    ml_next = ca.logic_or(ld, ca.logic_and(maybe, ca.logic_or(
        ml, _reached(t_maybe, p["maybe_time"] * factor, dt))))

    # stage 3: maybe landed for a whole window, then latched
    t_landed = _run(ml_next, s["t_landed"], dt)
    ld_next = ca.logic_or(ld, ca.logic_and(ml_next, _reached(
        t_landed, p["landed_time"] * factor, dt)))

    age = ca.fmin(s["age"] + dt, TIME_CAP)
    xld_next = ca.vertcat(t_contact, t_maybe, t_landed, gc_next, ml_next, ld_next,
                          range_gap, range_hold, f_mean, spike_hold, age)
    flags = ca.vertcat(gc_next, ml_next, ld_next, gap_cue, range_fresh, range_cue, still_cue,
                       thrust_cue, spike_cue, slow)
    return xld_next, flags


def land_detector_function() -> ca.Function:
    """``land_detector(xld, cues, p_ld, dt) -> (xld_next, flags)``, one SX Function."""
    xld, cues = LAND_DETECTOR_STATE.sym(), LAND_DETECTOR_CUES.sym()
    p_ld, dt = LAND_DETECTOR_PARAMS.sym(), ca.SX.sym("dt")
    xld_next, flags = land_detector_step(xld, cues, p_ld, dt)
    return ca.Function("land_detector", [xld, cues, p_ld, dt], [xld_next, flags],
                       ["xld", "cues", "p_ld", "dt"], ["xld_next", "flags"])

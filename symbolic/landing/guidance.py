"""Landing guidance: phases, descent profile, touchdown and abort in one sampled step.

The guidance runs at the control rate on the relative state in the deck
frame (position ``p_e``, velocity ``v_e``; z up, the pad's centre at the
origin) and produces the reference the position loop tracks. Its state is
:data:`GUIDANCE_STATE`: the phase, a dwell timer, the descent reference height,
the abort count, the commit flag, the contact switch's arming and the quiescence
averages. Phases (:data:`PHASES`):

0. **approach**: the reference is the hover point ``[0, 0, z_ref]``, ``z_ref``
   the hover height (see "The marker" for where it differs); it leaves when the
   quadrotor is within ``align_radius`` of it;
1. **align**: hold the hover point until the horizontal offset is within
   half of ``max_offset`` and the horizontal relative speed within half of
   ``max_relative_speed`` for ``dwell_time`` without a break;
2. **descend**: the reference height falls (to the wait height, then, once
   committed, on: see "The wait height and the commit") at ``clamp(h / descent_time,
   touchdown_speed, descent_speed)`` with ``h`` its height above touchdown
   (the gear on the deck), a rate that is large high up and the crawl
   ``touchdown_speed`` for the last part, which goes on below the touchdown
   height until contact (PX4 lands at 0.7 m/s and crawls at 0.3 m/s for the
   last metre); the horizontal reference stays at the pad. The reference
   falls only while the align criteria's offset and speed bands hold (half
   of ``max_offset`` and of ``max_relative_speed``): a gust that pushes the
   quadrotor out of them pauses the descent at its height, and it goes on
   once they hold again, so that the contact is made aligned, with no climb
   back and no dwell again. The crawl (``h`` at or below ``touchdown_speed x
   descent_time``) is committed: it does not pause, so that the quadrotor
   never hovers within centimetres of the deck, where the land detector
   would read a hover as a touchdown; there a touchdown out of the limits is
   aborted (below). With ``crawl_pause`` the align band pauses the crawl too. With
   ``crawl_gate`` the crawl also pauses while the horizontal offset predicted at the
   contact, ``p_e + v_e min(h / touchdown_speed, crawl_gate_time)`` (``h`` the reference's
   height above touchdown, 0 below it), lies farther than ``crawl_gate`` from the pad
   (:func:`~quadland_symbolic.landing.crawl_gate.gate_holds`), and with ``crawl_gate_rise``
   only while the deck's vertical speed at the pad is within it.
   The heights above touchdown count from ``touchdown_height + contact_drop``
   (:func:`contact_height`: where a body leaning into the airflow meets the deck);
3. **touchdown**: entered from the descent when the flight stack reports
   the gear on the deck (:data:`GUIDANCE_CUES`' ``touchdown``: on perfect
   sensing the measured gear gap at or below zero, on sensors the land
   detector's verdict, :mod:`quadland_symbolic.landing.land_detector`), or
   its ``contact_switch`` (the gear's switch) closes: the switch counts only once
   it has read open in this descent (the state's ``armed``), so that a switch
   closed before the descent (the gear grazing the deck at the handover, a deck
   rising into it; the plant's switch stays closed) is not a touchdown. The
   reference holds; the flight stack idles the rotors. With the touchdown
   policy that flies on until the lock-down holds (``fly_on``,
   :mod:`quadland_symbolic.landing.touchdown_policy`) the reference crawls on
   into the deck, and the reference carries the policy's flare, level-out and
   cut (:data:`POSITION_REFERENCE`'s last fields) from the descent on.
4. **landed**: ``settle_time`` after touchdown.

**The marker.** The descent starts only while the landing marker is seen:
the align criteria hold only while :data:`GUIDANCE_CUES`' ``marker_age`` (the
time since the navigation last fused a marker detection) is within
``marker_timeout``. A quadrotor in align that has not seen the marker for
longer climbs to ``search_height``, where the camera's cone covers more of
the deck, at ``descent_speed``, and comes back down to ``hover_height`` once
the marker is seen again (a GNSS bias larger than the camera's footprint at
the hover point would otherwise hold it beside the pad). In the approach the
hover point's height holds until the marker is seen: the flight stack starts
it at the handover height, when that is above ``hover_height``, so that no
descent is flown on a height only GNSS knows.

**The wait height and the commit** (quiescent-period prediction,
:mod:`quadland_symbolic.landing.quiescence`). The descent's reference falls
only to the wait height ``touchdown_height + commit_height`` until the final
descent is *committed*; it holds there (the position loop keeps the quadrotor
on the deck's motion, as at the hover point) until the deck's vertical speed,
predicted ``commit_horizon`` ahead from the pad's velocity and acceleration
the flight stack knows (the broadcast, or the filter's estimate of them), stays
within ``calm_speed`` (and ``max_deck_rise``, so that a commit is never its own
abort): a calm window. The step whose fall reaches the wait
height commits when the window is calm then, so that a deck at rest (a car's
roof) commits without a pause. The averages the prediction keeps are updated
at every step before touchdown and held on the deck. (The commit to the final
descent is not the committed crawl: the crawl is its last part.) With the deck
tilt's cues (the flight code's step passes them) the window must also be calm
in tilt: the deck's normal, predicted at the contact, within ``calm_tilt`` of
the flare's worst lean (:mod:`quadland_symbolic.landing.deck_tilt`; ``pi``,
the default, always is). With ``swerve_accel`` > 0 the window must also be calm
sideways: the pad's horizontal acceleration as the aircraft knows it
(:func:`quadland_symbolic.landing.swerve.pad_swerve`, the flight code's step passes it)
within ``swerve_accel``; a committed descent is withdrawn while it is not, as for a
rising deck (below), so that no contact is made while the vehicle manoeuvres (a car
changing lane). 0, the default, holds nothing. The commit also needs the quadrotor's
lean averaged over ``lean_time`` within ``calm_lean`` (a gust the flare's tilt limit
cannot hold; ``pi / 2``, the default, no limit; with ``lean_withdraw`` such a gust also
withdraws the committed descent, as a rising deck).

**Abort.** In the committed crawl, when the horizontal offset exceeds
``max_offset`` or the horizontal relative speed ``max_relative_speed``
(the criteria of a good touchdown could no longer be met), the phase goes
back to align, the reference climbs back to the hover height, and the abort
count grows by one, unless the gear is within ``abort_floor`` of the deck (the
estimate: :mod:`~quadland_symbolic.landing.abort_floor`). (Above the crawl an offset or a
speed out of the align band pauses the descent instead.) When, once committed, the deck rises faster
than ``max_deck_rise`` (the prediction missed), the commit is withdrawn: the
descent goes on uncommitted, its reference climbs back to the wait height at
``descent_speed`` to wait for the next calm window, and the abort count grows
by one (so does a swerve past ``swerve_accel``), unless the reference is at
or below ``withdraw_height`` above touchdown (the default, -1000 m, never is: the
withdrawal holds down to the contact). Once the descent's abort count has reached
``withdraw_budget`` (a retry budget; the default, 1e6, never is), nothing withdraws the
committed crawl either (``touchdown_speed x descent_time`` above touchdown): it crawls on
into the deck, as below ``withdraw_height``, instead of retrying until the time runs out.
Above the wait height a moving deck aborts nothing.

All logic is branch-free (``if_else``), so that the step is one CasADi
Function, generated into C like the controller.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.landing.abort_floor import out_of_limits
from quadland_symbolic.landing.crawl_gate import crawl_timer_next, fall_band, gate_holds
from quadland_symbolic.landing.deck_tilt import (
    DECK_TILT_STATE,
    TILT_CUES,
    descent_duration,
    lean_calm,
    relative_tilt_cos,
    tilt_ahead,
    tilt_frequency,
    tilt_update,
)
from quadland_symbolic.landing.guidance_params import GUIDANCE_PARAMS
from quadland_symbolic.landing.quiescence import (
    QUIESCENCE_STATE,
    deck_frequency,
    predicted_speed,
    quiescence_update,
)
from quadland_symbolic.landing.swerve import swerving
from quadland_symbolic.landing.touchdown_policy import (
    TOUCHDOWN_COMMANDS,
    touchdown_commands,
    touchdown_crawl,
)
from quadland_symbolic.layout import Field, Layout

__all__ = ["PHASES", "PHASE_DOCS", "APPROACH", "ALIGN", "DESCEND", "TOUCHDOWN", "LANDED",
           "GUIDANCE_STATE", "GUIDANCE_PARAMS", "GUIDANCE_CUES", "POSITION_REFERENCE",
           "guidance_step", "contact_height",
           "guidance_function"]

#: Phase numbers, as written to trajectory.csv's ``phase`` column.
PHASES = ("approach", "align", "descend", "touchdown", "landed")
#: What happens in each phase (the C API's comments).
PHASE_DOCS = ("fly to the hover point above the pad",
              "hold the hover point until offset and speed are within half their limits",
              "descend along the profile, committing the last part in a calm window of the "
              "deck; abort back to align when a limit is exceeded",
              "the flight stack reports the gear on the deck: rotors idle (or, flying on, "
              "level out and cut once the lock holds), the reference holds",
              "settle_time after touchdown")
APPROACH, ALIGN, DESCEND, TOUCHDOWN, LANDED = range(len(PHASES))

#: The guidance's memory.
GUIDANCE_STATE = Layout("xg", (
    Field("phase", 1, "-", "phase number (PHASES)"),
    Field("timer", 1, "s", "time the align criteria have held without a break; in the crawl "
          "with crawl_gate, the time the gate has held it; after touchdown, the time since"),
    Field("z_ref", 1, "m", "descent reference height of the centre above the pad"),
    Field("aborts", 1, "-", "number of aborted descents"),
    Field("committed", 1, "0/1", "1 once the final descent is committed (a calm window "
          "predicted at the wait height)"),
    Field("armed", 1, "0/1", "1 once the gear's contact switch has read open in this descent "
          "(only then does its closing count as the touchdown)"),
    *QUIESCENCE_STATE.fields,
    *DECK_TILT_STATE.fields,
), "landing guidance state")

#: What the rest of the flight stack tells the guidance each step.
GUIDANCE_CUES = Layout("c_guid", (
    Field("touchdown", 1, "0/1", "1 when the gear is on the deck (perfect sensing: the measured "
          "gear gap at or below zero; sensors: the land detector's verdict)"),
    Field("marker_age", 1, "s", "time since the navigation last fused the landing marker "
          "(0 on perfect sensing)"),
    Field("contact_switch", 1, "0/1", "1 while the gear's contact switch reads closed; it "
          "counts only once it has read open in the descent (the state's armed)"),
), "landing guidance cues")

#: What the position loop tracks: the reference and its first two derivatives
#: in the deck frame.
POSITION_REFERENCE = Layout("r_pos", (
    Field("p_ref", 3, "m", "reference position", elements=("x_ref", "y_ref", "z_ref")),
    Field("v_ref", 3, "m/s", "its rate", elements=("vx_ref", "vy_ref", "vz_ref")),
    Field("a_ref", 3, "m/s^2", "its acceleration", elements=("ax_ref", "ay_ref", "az_ref")),
    *TOUCHDOWN_COMMANDS.fields,
), "position reference in the deck frame and the touchdown policy's commands")


def contact_height(p):
    """The centre's height above the pad at which the profile expects the contact, m:
    ``touchdown_height`` (the level gear below the centre) plus ``contact_drop`` (a body
    leaning ``th`` into the airflow meets the deck on its front feet, ``fx sin th + hc cos
    th`` below its centre; docs/landing.md, "highway_100: the observer and the leash").
    ``p`` the unpacked :data:`GUIDANCE_PARAMS`."""
    return p["touchdown_height"] + p["contact_drop"]


def _descent_rate(h, p):
    """clamp(h / descent_time, touchdown_speed, descent_speed), m/s (down)."""
    return ca.fmin(ca.fmax(h / p["descent_time"], p["touchdown_speed"]), p["descent_speed"])


def _glide(z, target, p, dt):
    """The reference height one step of descent_speed toward ``target`` (there if nearer)."""
    step = p["descent_speed"] * dt
    return z + ca.fmin(ca.fmax(target - z, -step), step)


def _calm(g, p, deck_rise, deck_rise_rate, dt, tilt, swerve):
    """The quiescence and deck tilt averages after the step (held on the deck), whether
    the deck's vertical speed predicted over commit_horizon stays within calm_speed and
    max_deck_rise (so that a commit is never its own abort) and its tilt within
    calm_tilt and the gust's lean within calm_lean (:func:`_tilt_calm`) with the pad not
    swerving; and what withdraws a committed descent besides a rising deck: a swerve
    (:func:`~quadland_symbolic.landing.swerve.swerving`; never without ``swerve``) or, with
    ``lean_withdraw``, the gust's lean past calm_lean."""
    held = ca.SX(0) if swerve is None else swerving(swerve, p["swerve_accel"])
    xq = ca.vertcat(g["ms_rise"], g["ms_rise_rate"])
    xq_next = quiescence_update(xq, deck_rise, deck_rise_rate, dt, p["motion_time"])
    speed = predicted_speed(deck_rise, deck_rise_rate, deck_frequency(xq_next),
                            p["commit_horizon"])
    xt_held, tilt_calm, lean_ok = _tilt_calm(g, p, tilt, dt)
    return (ca.vertcat(ca.if_else(g["phase"] >= TOUCHDOWN, xq, xq_next), xt_held),
            ca.logic_and(ca.logic_and(speed <= ca.fmin(p["calm_speed"], p["max_deck_rise"]),
                                      tilt_calm), ca.logic_not(held)),
            ca.logic_or(held, ca.logic_and(p["lean_withdraw"] >= 0.5, ca.logic_not(lean_ok))))


def _withdrawn(flying, g, p, deck_rise, cause, h, crawl):
    """1 (CasADi) when the committed descent is withdrawn: the deck rises past
    max_deck_rise or ``cause`` (a swerve, a gust's lean: :func:`_calm`), above
    withdraw_height, and, once the descent's abort count has reached withdraw_budget, above
    the crawl. ``h`` is the reference's height above the contact, ``crawl`` whether it is
    in the crawl (``touchdown_speed x descent_time`` above the contact), the step's own."""
    spent = ca.logic_and(g["aborts"] >= p["withdraw_budget"], crawl)
    return ca.logic_and(ca.logic_and(flying, g["committed"] >= 0.5), ca.logic_and(
        ca.logic_or(deck_rise > p["max_deck_rise"], cause),
        ca.logic_and(h > p["withdraw_height"], ca.logic_not(spent))))


def _tilt_calm(g, p, tilt, dt):
    """The deck tilt averages after the step (held on the deck) and whether the deck's
    normal predicted at the contact (the profile's time from the wait height) lies within
    calm_tilt of the flare's worst lean, toward the average lean
    (:mod:`~quadland_symbolic.landing.deck_tilt`), and the gust's lean within calm_lean
    (both, then the lean's alone); without ``tilt`` the averages hold and both are true."""
    xt = ca.vertcat(*(g[n] for n in DECK_TILT_STATE.names()))
    if tilt is None:
        return xt, ca.SX(1), ca.SX(1)
    c = TILT_CUES.unpack(tilt)
    xt_next = tilt_update(xt, c["n_h_dot"], c["n_h_ddot"], c["b_h"], dt, p["motion_time"],
                          p["lean_time"])
    lean = DECK_TILT_STATE.unpack(xt_next)
    duration = descent_duration(p["commit_height"], p["descent_time"], p["touchdown_speed"],
                                p["descent_speed"])
    d_h = tilt_ahead(c["n_h"], c["n_h_dot"], tilt_frequency(xt_next), duration)
    deck = relative_tilt_cos(ca.vertcat(lean["lean_x"], lean["lean_y"]), d_h,
                             p["flare_tilt"]) >= ca.cos(p["calm_tilt"])
    lean_ok = lean_calm(lean["lean_gust"], p["calm_lean"])
    return ca.if_else(g["phase"] >= TOUCHDOWN, xt, xt_next), ca.logic_and(deck, lean_ok), lean_ok


def _touchdown_cue(c, g):
    """The touchdown's cue in the descent: the flight stack's verdict, or the contact switch
    once armed (it has read open in this descent: one closed before the descent, the gear
    grazing the deck at the handover or a deck rising into it, is no touchdown)."""
    return ca.logic_or(c["touchdown"] >= 0.5,
                       ca.logic_and(c["contact_switch"] >= 0.5, g["armed"] >= 0.5))


def _armed_next(c, g, in_descend, phase_next):
    """The state's ``armed`` after the step: the next phase is the descent, and the switch
    reads open now or was armed earlier in this descent."""
    return ca.logic_and(phase_next == DESCEND, ca.logic_or(
        ca.logic_and(in_descend, g["armed"] >= 0.5), c["contact_switch"] < 0.5))


def _reference_height(z_ref, p, f, dt):
    """The reference height's next value and the step's reference.

    ``f`` holds the step's flags (CasADi 0/1): ``flying`` (descending, no contact, no
    abort back to align), ``falling`` (the profile's fall: in the align band or the
    committed crawl, and committed or above the wait height), ``hold`` (where the
    reference glides when flying and not falling: the wait height, or its own height
    for a pause), ``align`` (the phase), ``abort`` (back to align), ``seen`` (the
    marker), ``landing`` (the next phase touchdown or landed), ``touchdown`` and
    ``descending_next`` (the next phase touchdown, the descent), and ``timer_next``
    (the guidance's timer after the step), for the touchdown policy
    (:mod:`~quadland_symbolic.landing.touchdown_policy`); ``z`` the quadrotor's height, for
    ``descent_leash`` (below ``leash_height`` above touchdown).
    """
    # the descent reference falls only while falling: to the wait height until committed,
    # then on at the crawl below the touchdown height until contact (a heaving deck may
    # have moved away, and the quadrotor must meet it); out of the align band, above the
    # crawl, the descent pauses at its height (no climb); uncommitted below the wait
    # height (a rising deck withdrew the commit) it glides back up to it; an abort
    # resets it to the hover height, as does the start of a descent
    h = z_ref - contact_height(p)
    rate = _descent_rate(h, p)
    falling = f["falling"]
    # before the descent the hover point's height glides at descent_speed: to
    # hover_height while the marker is seen; without it, it holds in the approach
    # and climbs to search_height in align (exactly hover_height once there:
    # hover + 0, and so always on perfect sensing)
    hover = p["hover_height"]
    target = ca.if_else(f["seen"], hover, ca.if_else(f["align"], p["search_height"], z_ref))
    # after the touchdown the reference crawls on into the deck while the policy flies on
    crawl = touchdown_crawl(f["touchdown"], p)
    # the leash: below leash_height the fall stops where the reference would lead the
    # quadrotor down by more than the leash
    leash = p["descent_leash"]
    fall = ca.if_else(ca.logic_and(leash > 0, h <= p["leash_height"]),
                      ca.fmax(z_ref - rate * dt, ca.fmin(z_ref, f["z"] - leash)),
                      z_ref - rate * dt)
    z_next = ca.if_else(f["flying"],
                        ca.if_else(falling, fall, _glide(z_ref, f["hold"], p, dt)),
                        ca.if_else(f["landing"], z_ref - crawl * dt,
                                   ca.if_else(f["abort"], hover, _glide(z_ref, target, p, dt))))

    vz = ca.if_else(falling, -rate, -crawl)
    # d/dt of -rate: the rate is h / descent_time where it is not clamped
    unclamped = ca.logic_and(h / p["descent_time"] > p["touchdown_speed"],
                             h / p["descent_time"] < p["descent_speed"])
    az = ca.if_else(ca.logic_and(falling, unclamped), rate / p["descent_time"], 0)
    reference = ca.vertcat(0, 0, z_ref, 0, 0, vz, 0, 0, az, touchdown_commands(
        f["landing"], f["descending_next"], f["timer_next"], z_next, p))
    return z_next, reference


def guidance_step(xg, p_e, v_e, deck_rise, deck_rise_rate, cues, dt, p_guid, tilt=None,
                  swerve=None):
    """One guidance step of length ``dt`` (s).

    Parameters
    ----------
    xg : casadi.SX
        :data:`GUIDANCE_STATE` at the start of the step.
    p_e, v_e : casadi.SX, (3,)
        Relative position and velocity in the deck frame, m, m/s.
    deck_rise, deck_rise_rate : casadi.SX
        The deck's vertical velocity at the pad, m/s (up), and its rate, m/s^2.
    cues : casadi.SX, (3,)
        :data:`GUIDANCE_CUES`: the touchdown verdict, the marker's age, the contact switch.
    dt, p_guid : casadi.SX
        Step length, s; :data:`GUIDANCE_PARAMS`.
    tilt, swerve : casadi.SX, optional
        :data:`~quadland_symbolic.landing.deck_tilt.TILT_CUES` (``calm_tilt``; without it
        the commit's tilt condition holds and its averages stay); the pad's horizontal
        acceleration, m/s^2 (``swerve_accel``, :mod:`~.swerve`; without it no hold).

    Returns
    -------
    xg_next, reference : casadi.SX
        :data:`POSITION_REFERENCE` for the step, the touchdown policy's commands with it.
    """
    g, p, c = (L.unpack(v) for L, v in ((GUIDANCE_STATE, xg), (GUIDANCE_PARAMS, p_guid),
                                        (GUIDANCE_CUES, cues)))
    phase, timer, z_ref, aborts = g["phase"], g["timer"], g["z_ref"], g["aborts"]
    offset, speed, h = ca.norm_2(p_e[0:2]), ca.norm_2(v_e[0:2]), z_ref - contact_height(p)
    to_hover = ca.norm_2(p_e - ca.vertcat(0, 0, z_ref))

    in_approach, in_align, in_descend, in_touchdown = (
        phase == k for k in (APPROACH, ALIGN, DESCEND, TOUCHDOWN))
    seen = c["marker_age"] <= p["marker_timeout"]
    in_band = ca.logic_and(offset <= p["max_offset"] / 2, speed <= p["max_relative_speed"] / 2)
    contact = ca.logic_and(in_descend, _touchdown_cue(c, g))
    flying = ca.logic_and(in_descend, ca.logic_not(contact))

    # the quiescent-period prediction (quiescence.py) and the commit at the wait height
    xq_held, calm, cause = _calm(g, p, deck_rise, deck_rise_rate, dt, tilt, swerve)
    z_fall = z_ref - _descent_rate(z_ref - contact_height(p), p) * dt
    wait = contact_height(p) + p["commit_height"]
    committed = ca.logic_and(in_descend, ca.logic_or(g["committed"] >= 0.5,
                                                     ca.logic_and(z_fall <= wait, calm)))
    # the crawl (h / descent_time <= touchdown_speed) pauses only with crawl_pause and aborts
    # out of the limits; above it the descent pauses out of the band; a rising deck withdraws
    crawl = h <= p["touchdown_speed"] * p["descent_time"]
    off_limits = ca.logic_and(ca.logic_and(flying, crawl), out_of_limits(
        offset, speed, p_e[2] - contact_height(p), p, aborts))
    gate = gate_holds(p_e, v_e, h, timer, deck_rise, p)
    timer_next = crawl_timer_next(g, dict(gate=gate, h=h, landed=phase == LANDED, counting=(
        ca.logic_or(ca.logic_and(in_align, ca.logic_and(in_band, seen)), in_touchdown)),
        gating=ca.logic_and(ca.logic_and(flying, crawl), ca.logic_not(off_limits))), p, dt)
    rising = _withdrawn(flying, g, p, deck_rise, cause, h, crawl)   # a rising deck, a swerve
    phase_next = ca.if_else(
        ca.logic_and(in_approach, to_hover <= p["align_radius"]), ALIGN,
        ca.if_else(ca.logic_and(in_align, timer_next >= p["dwell_time"]), DESCEND,
                   ca.if_else(contact, TOUCHDOWN,
                              ca.if_else(off_limits, ALIGN,
                                         ca.if_else(ca.logic_and(
                                             in_touchdown, timer_next >= p["settle_time"]),
                                             LANDED, phase)))))
    committed_next = ca.logic_and(ca.logic_and(phase_next == DESCEND, committed),
                                  ca.logic_not(rising))
    band = fall_band(in_band, crawl, gate, p)
    hold = ca.if_else(committed_next, z_ref, wait)
    falling = ca.logic_and(ca.logic_and(ca.logic_and(flying, ca.logic_not(
        ca.logic_or(off_limits, rising))), band), ca.logic_or(committed, z_fall > wait))
    # not falling: to the wait height (uncommitted, or withdrawn), else paused (never down)
    z_next, reference = _reference_height(
        z_ref, p, dict(flying=ca.logic_and(flying, ca.logic_not(off_limits)), falling=falling,
                       hold=ca.if_else(band, hold, ca.fmax(hold, z_ref)), align=in_align,
                       abort=off_limits, seen=seen, landing=phase_next >= TOUCHDOWN,
                       touchdown=phase_next == TOUCHDOWN,
                       descending_next=phase_next == DESCEND, timer_next=timer_next,
                       z=p_e[2]), dt)
    return ca.vertcat(phase_next, timer_next, z_next, aborts + ca.logic_or(off_limits, rising),
                      committed_next, _armed_next(c, g, in_descend, phase_next), xq_held), \
        reference


def guidance_function() -> ca.Function:
    """``guidance(xg, p_e, v_e, deck_rise, deck_rise_rate, cues, dt, p_guid) -> (xg_next,
    reference)``."""
    xg, p_e, v_e = GUIDANCE_STATE.sym(), ca.SX.sym("p_e", 3), ca.SX.sym("v_e", 3)
    deck_rise, deck_rise_rate = ca.SX.sym("deck_rise"), ca.SX.sym("deck_rise_rate")
    cues, dt, p_guid = GUIDANCE_CUES.sym(), ca.SX.sym("dt"), GUIDANCE_PARAMS.sym()
    xg_next, reference = guidance_step(xg, p_e, v_e, deck_rise, deck_rise_rate, cues, dt,
                                       p_guid)
    return ca.Function("guidance", [xg, p_e, v_e, deck_rise, deck_rise_rate, cues, dt, p_guid],
                       [xg_next, reference],
                       ["xg", "p_e", "v_e", "deck_rise", "deck_rise_rate", "cues", "dt",
                        "p_guid"],
                       ["xg_next", "reference"])

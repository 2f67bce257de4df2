"""The crawl's gate: the committed crawl pauses while the offset predicted at the contact lies
outside ``crawl_gate`` (:mod:`quadland_symbolic.landing.guidance`, docs/landing.md, "The offset
at contact: the estimate's wander and a gate on its prediction").

The guidance's offset at the contact is mostly the estimate's own wander about the pad, which
decorrelates within a few tenths of a second; the gate lets the crawl fall only while the
estimate, carried over the crawl's time left by the estimated velocity, is inside the gate.
Its pauses are counted on the guidance's timer and bounded by ``crawl_gate_wait``. Below
``crawl_gate_floor``, with ``crawl_gate_slow``, it slows the crawl instead of pausing it
(:func:`crawl_cap`).

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["crawl_cap", "crawl_timer_next", "fall_band", "gate_and_cap", "gate_holds"]


def gate_holds(p_e, v_e, h, timer, deck_rise, p):
    """Whether the crawl may fall on under ``crawl_gate``: the horizontal offset predicted at
    the contact, ``p_e + v_e t_go`` with ``t_go = max(h, 0) / touchdown_speed`` the crawl's
    time left (``h`` the reference's height above touchdown) but at most ``crawl_gate_time``
    (the wander decorrelates within a few tenths of a second: a longer extrapolation adds
    the velocity's noise, docs/landing.md), within ``crawl_gate`` of the pad; always with
    ``crawl_gate`` 0, at or below ``crawl_gate_floor`` (a pause within centimetres of the
    deck reads as a touchdown to the land detector) and once the gate has held this crawl for
    ``crawl_gate_wait`` (``timer``, :func:`crawl_timer_next`: a quadrotor that wanders on near the
    deck in strong turbulence would otherwise pause until it aborts); and while the deck's
    vertical speed at the pad, ``|deck_rise|``, exceeds ``crawl_gate_rise`` (the gate waits
    only on a quiescent deck: a pause over a heaving one is met by the deck, or withdrawn)."""
    return ca.logic_or(h <= p["crawl_gate_floor"],
                       ca.logic_not(_outside(p_e, v_e, h, timer, deck_rise, p)))


def _outside(p_e, v_e, h, timer, deck_rise, p):
    """Whether the gate is on (``crawl_gate`` > 0, its wait not spent, the deck quiescent)
    and its prediction at the contact lies outside it (:func:`gate_holds`), at any height."""
    t_go = ca.fmin(ca.fmax(h, 0) / p["touchdown_speed"], p["crawl_gate_time"])
    predicted = ca.norm_2(p_e[0:2] + v_e[0:2] * t_go)
    off = ca.logic_or(p["crawl_gate"] <= 0, ca.logic_or(
        timer >= p["crawl_gate_wait"], ca.fabs(deck_rise) > p["crawl_gate_rise"]))
    return ca.logic_and(ca.logic_not(off), predicted > p["crawl_gate"])


def crawl_cap(p_e, v_e, h, crawl, timer, deck_rise, p):
    """The largest rate the crawl's reference falls at this step, m/s: ``crawl_gate_slow``
    where the gate no longer pauses it for height alone (in the crawl, ``crawl``, at or
    below ``crawl_gate_floor``) but its prediction (:func:`gate_holds`, every other
    condition as there) lies outside ``crawl_gate``, else ``descent_speed`` (no cap: the
    profile's rate never exceeds it). A pause within centimetres of the deck stops a
    quadrotor coming down at ``touchdown_speed``; the loop's undershoot below the held
    reference meets the roof and its return lifts the foot (a bounce), and a quadrotor held
    there in strong turbulence wanders to an abort. A slower crawl neither stops it nor
    holds it, and lets the wander pass before the contact (docs/landing.md, "The crawl's
    gate slowed below its floor"). With ``crawl_gate_slow`` at ``touchdown_speed`` or
    above (1000, the default) the crawl is as without it."""
    slows = ca.logic_and(ca.logic_and(crawl, h <= p["crawl_gate_floor"]),
                         _outside(p_e, v_e, h, timer, deck_rise, p))
    return ca.if_else(slows, p["crawl_gate_slow"], p["descent_speed"])


def gate_and_cap(p_e, v_e, h, crawl, timer, deck_rise, p):
    """:func:`gate_holds` and :func:`crawl_cap`, for the guidance step."""
    return (gate_holds(p_e, v_e, h, timer, deck_rise, p),
            crawl_cap(p_e, v_e, h, crawl, timer, deck_rise, p))


def fall_band(in_band, crawl, gate, p):
    """Whether the reference may fall as far as the horizontal criteria go: in the align
    band, or in the crawl unless ``crawl_pause``; and in the crawl only while ``gate``
    (:func:`gate_holds`)."""
    return ca.logic_and(ca.logic_or(in_band, ca.logic_and(crawl, p["crawl_pause"] < 0.5)),
                        ca.logic_or(ca.logic_not(crawl), gate))


def crawl_timer_next(g, f, p, dt):
    """The guidance's timer after the step: the align criteria's dwell, then the time since
    touchdown (``f["counting"]``), held once landed; with ``crawl_gate`` on, in the crawl
    (``f["gating"]``: flying, no abort) the time the gate has held it (``f["gate"]`` false),
    which :func:`gate_holds` bounds by ``crawl_gate_wait``; else 0 (as without the gate)."""
    gating = ca.logic_and(f["gating"], p["crawl_gate"] > 0)
    return ca.if_else(f["counting"], g["timer"] + dt, ca.if_else(
        f["landed"], g["timer"],
        ca.if_else(gating, g["timer"] + dt * ca.logic_not(f["gate"]), 0)))

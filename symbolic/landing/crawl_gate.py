"""The crawl's gate: the committed crawl pauses while the offset predicted at the contact lies
outside ``crawl_gate`` (:mod:`quadland_symbolic.landing.guidance`, docs/landing.md, "The offset
at contact: the estimate's wander and a gate on its prediction").

The guidance's offset at the contact is mostly the estimate's own wander about the pad, which
decorrelates within a few tenths of a second; the gate lets the crawl fall only while the
estimate, carried over the crawl's time left by the estimated velocity, is inside the gate.
Its pauses are counted on the guidance's timer and bounded by ``crawl_gate_wait`` (with
``crawl_gate_wait_height``, only at and below that height).

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["crawl_timer_next", "fall_band", "gate_holds"]


def gate_holds(p_e, v_e, h, timer, deck_rise, p):
    """Whether the crawl may fall on under ``crawl_gate``: the horizontal offset predicted at
    the contact, ``p_e + v_e t_go`` with ``t_go = max(h, 0) / touchdown_speed`` the crawl's
    time left (``h`` the reference's height above touchdown) but at most ``crawl_gate_time``
    (the wander decorrelates within a few tenths of a second: a longer extrapolation adds
    the velocity's noise, docs/landing.md), within ``crawl_gate`` of the pad; always with
    ``crawl_gate`` 0, at or below ``crawl_gate_floor`` (a pause within centimetres of the
    deck reads as a touchdown to the land detector) and once the gate has held this crawl for
    ``crawl_gate_wait`` (``timer``, :func:`crawl_timer_next`: a quadrotor that wanders on near the
    deck in strong turbulence would otherwise pause until it aborts), where ``h`` is at or
    below ``crawl_gate_wait_height`` (1000, the default: at any height in the crawl; lower, the
    holds above it are counted but not bounded, so that a crawl that has held long up high
    is not held again near the deck, docs/landing.md, "The crawl's gate: a wait near the
    deck only"); and while the deck's
    vertical speed at the pad, ``|deck_rise|``, exceeds ``crawl_gate_rise`` (the gate waits
    only on a quiescent deck: a pause over a heaving one is met by the deck, or withdrawn)."""
    t_go = ca.fmin(ca.fmax(h, 0) / p["touchdown_speed"], p["crawl_gate_time"])
    predicted = ca.norm_2(p_e[0:2] + v_e[0:2] * t_go)
    off = ca.logic_or(ca.logic_or(p["crawl_gate"] <= 0, h <= p["crawl_gate_floor"]),
                      ca.logic_or(ca.logic_and(timer >= p["crawl_gate_wait"],
                                               h <= p["crawl_gate_wait_height"]),
                                  ca.fabs(deck_rise) > p["crawl_gate_rise"]))
    return ca.logic_or(off, predicted <= p["crawl_gate"])


def fall_band(in_band, crawl, gate, p):
    """Whether the reference may fall as far as the horizontal criteria go: in the align
    band, or in the crawl unless ``crawl_pause``; and in the crawl only while ``gate``
    (:func:`gate_holds`)."""
    return ca.logic_and(ca.logic_or(in_band, ca.logic_and(crawl, p["crawl_pause"] < 0.5)),
                        ca.logic_or(ca.logic_not(crawl), gate))


def crawl_timer_next(g, f, p, dt):
    """The guidance's timer after the step: the align criteria's dwell, then the time since
    touchdown (``f["counting"]``), held once landed; with ``crawl_gate`` on, in the crawl
    (``f["gating"]``: flying, no abort) the time the gate has held it (``f["gate"]`` false)
    with the reference's height above touchdown ``f["h"]`` at or below
    ``crawl_gate_count_height`` (1000, the default: every hold; at ``crawl_gate_wait_height``
    the holds up high do not spend the wait near the deck, which then guards the crawl's last
    part afresh, docs/landing.md, "turning: the last half second before contact"), which
    :func:`gate_holds` bounds by ``crawl_gate_wait``; else 0 (as without the gate)."""
    gating = ca.logic_and(f["gating"], p["crawl_gate"] > 0)
    held = ca.logic_and(ca.logic_not(f["gate"]), f["h"] <= p["crawl_gate_count_height"])
    return ca.if_else(f["counting"], g["timer"] + dt, ca.if_else(
        f["landed"], g["timer"],
        ca.if_else(gating, g["timer"] + dt * held, 0)))

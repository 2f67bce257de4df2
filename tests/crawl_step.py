"""One committed crawl step of the guidance, by hand (shared by the tests of the crawl's
abort bounds: ``abort_floor`` and ``crawl_abort_offset``, symbolic/landing/abort_floor.py),
and one committed step under a rising deck (shared by the tests of the withdrawal's bounds:
``withdraw_height`` and ``withdraw_budget``)."""

import numpy as np
from reference import GUIDANCE_P

from quadland_symbolic.landing.guidance import (
    ALIGN,
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)

DT = 0.004
H = 0.1            # the reference 0.1 m above the contact: in the crawl (0.3 m at 0.3 m/s x 1 s)


def crawl_step(gap, offset=0.0, speed=0.0, aborts=0.0, **params):
    """One committed crawl step with the reference ``H`` above the contact and the
    quadrotor's gear ``gap`` above it (the relative position's z is the contact's height
    plus ``gap``), its estimated horizontal offset along x and its horizontal speed along y,
    after ``aborts`` aborted descents. Returns the phase, the aborts and the reference height
    above the contact after the step."""
    p = dict(GUIDANCE_P, **params)
    contact = p["touchdown_height"] + p["contact_drop"]
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=contact + H, aborts=aborts,
                                  committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    xg_next, _ = guidance_function()(xg, [offset, 0.0, contact + gap], [0.0, speed, -0.3],
                                     0.0, 0.0, cues, DT, GUIDANCE_PARAMS.pack(p))
    g = GUIDANCE_STATE.unpack(np.asarray(xg_next, dtype=float).ravel())
    return g["phase"][0], g["aborts"][0], g["z_ref"][0] - contact


def aborted(p=GUIDANCE_P):
    """What the step gives on an abort, by hand: align, one abort, the reference at the
    hover height above the pad (hover_height less the contact's height above the contact)."""
    return ALIGN, 1.0, p["hover_height"] - p["touchdown_height"] - p.get("contact_drop", 0.0)


#: The crawl going on, by hand: the rate clamp(H / descent_time, touchdown_speed,
#: descent_speed) = 0.3 m/s over one step.
CRAWLED = (DESCEND, 0.0, H - GUIDANCE_P["touchdown_speed"] * DT)


def withdraw_step(h, rise, aborts=0.0, **params):
    """One step committed with the reference ``h`` above ``touchdown_height``, after
    ``aborts`` aborts, the quadrotor on the reference at rest, the deck rising at ``rise``;
    ``params`` replace the guidance's parameters. Returns z_ref, committed and aborts
    after it."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0,
                                  z_ref=GUIDANCE_P["touchdown_height"] + h, aborts=aborts,
                                  committed=1, armed=0.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, **params))
    xg_next, _ = guidance_function()(xg, [0.0, 0.0, GUIDANCE_P["touchdown_height"] + h],
                                     [0.0, 0.0, 0.0], rise, 0.0, cues, DT, pg)
    g = GUIDANCE_STATE.unpack(np.asarray(xg_next, dtype=float).ravel())
    return g["z_ref"][0], g["committed"][0], g["aborts"][0]

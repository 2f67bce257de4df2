"""The gear's contact switch counts as a touchdown only once it has read open in the descent
(issue 19; docs/landing.md, "A contact switch closed before the descent").

The plant's switch latches (its ``t_contact`` clock runs on once the gear's load impulse
closed it): a graze at the handover, or a deck rising into the gear before the descent,
would otherwise read as a touchdown the first step of the descent. Checked on the guidance
step against the rule written out by hand (each phase, each switch reading), and on the
flight that showed it: ``ship_ss5``'s run 200 on seed 7 handed over as drawn (the gear
grazing the deck at t = 0), where the touchdown phase came with the gear metres above the
deck. That flight is judged on its recorded true gear gap and phase columns alone.
"""

import numpy as np
import pytest
from reference import GUIDANCE_P
from ship_before import HEAVE_BEFORE

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import (
    ALIGN,
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    TOUCHDOWN,
    guidance_function,
)

DT = 0.002


def _step(phase, armed, switch, detector=0.0, timer=0.0):
    """One guidance step over the pad at the crawl, on the track; (phase, armed) after it."""
    p = dict(GUIDANCE_P)
    xg = GUIDANCE_STATE.pack(dict(phase=phase, timer=timer, z_ref=p["touchdown_height"],
                                  aborts=0, committed=1.0, armed=armed, ms_rise=0.0,
                                  ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                  lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=detector, marker_age=0.0,
                                   contact_switch=switch))
    xg_next, _ = guidance_function()(xg, [0.0, 0.0, p["touchdown_height"]], [0.0, 0.0, 0.0],
                                     0.0, 0.0, cues, DT, GUIDANCE_PARAMS.pack(p))
    s = GUIDANCE_STATE.unpack(np.asarray(xg_next, dtype=float).ravel())
    return int(s["phase"][0]), float(s["armed"][0])


@pytest.mark.parametrize("armed, switch, detector, want", [
    (0.0, 1.0, 0.0, (DESCEND, 0.0)),     # closed since before the descent: not a touchdown
    (0.0, 0.0, 0.0, (DESCEND, 1.0)),     # read open: armed
    (1.0, 0.0, 0.0, (DESCEND, 1.0)),     # stays armed
    (1.0, 1.0, 0.0, (TOUCHDOWN, 0.0)),   # closed in the descent: the touchdown
    (0.0, 1.0, 1.0, (TOUCHDOWN, 0.0)),   # the detector's verdict needs no arming
])
def test_in_the_descent_the_switch_counts_once_armed(armed, switch, detector, want):
    assert _step(DESCEND, armed, switch, detector) == want


@pytest.mark.parametrize("switch, armed", [(1.0, 0.0), (0.0, 1.0)])
def test_the_descent_begins_armed_only_on_an_open_switch(switch, armed):
    """The step from align into the descent (the dwell done) arms on an open switch."""
    dwell = GUIDANCE_P["dwell_time"]
    assert _step(ALIGN, 0.0, switch, timer=dwell) == (DESCEND, armed)


def test_outside_the_descent_the_switch_is_not_armed():
    """Align with the switch open: no arming carried into a later descent."""
    assert _step(ALIGN, 1.0, 0.0) == (ALIGN, 0.0)


@pytest.mark.slow
def test_a_switch_closed_at_the_handover_is_no_touchdown():
    """``ship_ss5`` run 200, seed 7, handed over as drawn (clearance 0): the switch closed
    at t = 0 from the graze. No row in the touchdown phase has the true gear gap above
    0.5 m (it came at 2.94 m before the fix); the touchdown phase comes with the gear on
    the deck (the gap at the first such row within 1 cm). Flown on the pad's heave of before
    (:data:`HEAVE_BEFORE`; with the oscillator in the crawl that gap is 1.3 cm)."""
    seed7 = ["campaign.seed=7"]
    d = draws(campaign_spec_of(load_scenario("ship_ss5", seed7)), [200])[0]
    sc = load_scenario("ship_ss5", [*seed7, *d.overrides(), "initial.handover_clearance=0",
                                    *HEAVE_BEFORE])
    r = quadland.simulate(sc)
    phase, gap = np.asarray(r["phase"]), np.asarray(r["gear_gap"])
    assert gap[0] < 0.0                  # the graze at the handover
    down = phase >= TOUCHDOWN
    assert down.any() and not np.any(down & (gap > 0.5))
    assert gap[np.flatnonzero(down)[0]] < 0.01

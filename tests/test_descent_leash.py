"""The descent's reference on a leash: ``landing.descent_leash`` (issue 19, highway).

A gust in the committed crawl can lean the quadrotor past the point where its vertical
thrust holds it on the falling reference; the reference falls on at the crawl speed, the
quadrotor falls behind it, and the position loop catches up at ``v_ref + k1p z1``, which it
can still be flying at the contact (highway's campaign runs 122 and 166: 0.549 and 0.537
m/s against the 0.5 m/s limit; docs/landing.md, "highway: integral action from the hover
point on"). With a leash ``l > 0`` the falling reference stops where it would lead the
quadrotor down by more than ``l``: ``z_next = max(z_ref - rate dt, min(z_ref, z - l))``, so
the catch-up is at most ``v_ref + k1p l``. ``l = 0``: no limit, the guidance of before.
Checked here against that rule by hand, and on the two runs replayed from the campaign's
draws, whose rows the campaign recorded.
"""

import numpy as np
import pytest
from highway_before import BEFORE
from reference import GUIDANCE_P, HANDOVER_COLD

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)

DT = 0.1
Z_REF = 1.0            # 0.8 m above touchdown (0.2 m): the descent rate is 0.7 m/s
RATE = 0.7


def _z_next(leash, z):
    """The reference height after one step of a committed descent over the pad, the
    quadrotor at height ``z`` and at rest horizontally (in the align band)."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=Z_REF, aborts=0,
                                  committed=1, armed=0.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                  lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, descent_leash=leash))
    xg_next, ref = (np.asarray(v, dtype=float).ravel() for v in guidance_function()(
        xg, [0.0, 0.0, z], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
    return GUIDANCE_STATE.unpack(xg_next)["z_ref"][0], ref[5]


@pytest.mark.parametrize(("leash", "z", "expected"), [
    (0.0, 1.2, Z_REF - RATE * DT),        # no leash: the fall, 0.93 m
    (0.05, 0.9, Z_REF - RATE * DT),       # the quadrotor below the reference: the fall
    (0.05, 0.97, Z_REF - RATE * DT),      # 0.93 m is within 5 cm below it: the fall
    (0.05, 1.0, 0.95),                    # on the reference: the step's 7 cm fall stops at 5
    (0.05, 1.03, 0.98),                   # 3 cm behind: the fall stops 5 cm below it
    (0.05, 1.2, Z_REF),                   # 20 cm behind: the reference waits (never climbs)
])
def test_the_falling_reference_leads_the_quadrotor_down_by_at_most_the_leash(leash, z,
                                                                               expected):
    z_next, vz = _z_next(leash, z)
    assert z_next == pytest.approx(expected, abs=1e-12)
    assert vz == pytest.approx(-RATE, abs=1e-12)       # the reference's rate is the profile's


def _run(index, *overrides):
    sc = load_scenario("highway")
    d = draws(campaign_spec_of(sc), [index])[0]
    return touchdown_report(quadland.simulate(load_scenario("highway", [
        *d.overrides(), *BEFORE, *HANDOVER_COLD, *overrides])))


@pytest.mark.parametrize(("index", "sink_before", "sink_leash"),
                         [(122, 0.5493, 0.3070), (166, 0.5372, 0.2468)])
def test_the_campaigns_two_sink_rate_failures_land_on_a_5_cm_leash(index, sink_before,
                                                                     sink_leash):
    """Runs 122 and 166 of highway's campaign (default seed), whose rows in `quadland
    campaign --scenario highway --runs 300` record sink rates of 0.549 and 0.537 m/s: with
    highway's touchdown of before (`highway_before.BEFORE`: no leash, the rotors cut at the
    contact switch) they replay those rows; on a 5 cm leash they land (the
    leash's sink rates are the flights' own, pinned as reproducers; the independent check is
    the outcome and the limit)."""
    before = _run(index)
    assert before.sink_rate == pytest.approx(sink_before, abs=1e-4)
    assert not before.success and before.failures == ["sink_rate"]
    now = _run(index, "landing.descent_leash=0.05")
    assert now.sink_rate == pytest.approx(sink_leash, abs=1e-4)
    assert now.success and now.secured and now.on_pad

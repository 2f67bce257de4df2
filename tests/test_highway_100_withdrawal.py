"""highway_100's withdrawal through the lane change, down to the front feet's contact (issue 19).

``landing.withdraw_height`` 0.18 m and ``landing.swerve_accel`` 0.2 m/s^2 (docs/landing.md,
"highway_100: the lane change's withdrawal down to the front feet's contact"). Checked
against a hand derivation (the height over the level gear's touchdown at which a body at the
flare's lean meets the roof on its front feet), the guidance's step on both sides of the
floor and of the swerve's limit, the closed form of the lane change's lateral acceleration
(when it passes the limit), and a campaign run that the shipped file lands and the file of
before (``HIGHWAY_100_MARKER``) loses to a climb after a contact.
"""

import math

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P, HIGHWAY_100_MARKER

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
    guidance_step,
)
from quadland_symbolic.landing.swerve import pad_swerve

DT = 0.004
TD = GUIDANCE_P["touchdown_height"]


def _shipped():
    return load_scenario("highway_100").data


def test_the_floor_lies_over_the_front_feet_s_contact_at_the_flare_s_lean():
    """A body at the flare's tilt ``th`` (46 deg) meets the roof on its front feet
    ``fx sin th + hc cos th - hc`` over the level gear's touchdown: 0.300 x 0.7193 + 0.150 x
    0.6947 - 0.150 = 0.1700 m (fx 0.30 m, hc 0.15 m). The shipped floor lies over it and
    under the crawl's top (touchdown_speed x descent_time, 0.25 m), so the crawl's top is
    still withdrawn; the floor of before (0.25 m) covered the whole crawl."""
    d = _shipped()
    th = math.radians(d["touchdown"]["flare_tilt_deg"])
    fx, hc = d["gear"]["feet_x"], d["quadrotor"]["gear_height"]
    drop = fx * math.sin(th) + hc * math.cos(th) - hc
    assert drop == pytest.approx(0.1700, abs=5e-5)
    crawl = d["landing"]["touchdown_speed"] * d["landing"]["descent_time"]
    assert crawl == pytest.approx(0.25)
    assert drop < d["landing"]["withdraw_height"] == 0.18 < crawl
    before = dict(s.split("=") for s in HIGHWAY_100_MARKER)
    assert float(before["landing.withdraw_height"]) >= crawl


def _step_function():
    xg, p_e, a2E = GUIDANCE_STATE.sym(), ca.SX.sym("p_e", 3), ca.SX.sym("a2E", 3)
    p_guid = GUIDANCE_PARAMS.sym()
    cues = ca.DM(GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0)))
    xg_next, _ = guidance_step(xg, p_e, ca.DM.zeros(3), 0, 0, cues, DT, p_guid,
                               swerve=pad_swerve(a2E))
    return ca.Function("g", [xg, p_e, a2E, p_guid], [xg_next])


STEP = _step_function()


def _after(h, a_lat):
    """One committed step with the reference ``h`` over touchdown, the quadrotor on it at rest
    over the pad, the pad accelerating ``a_lat`` sideways; the shipped pair of keys."""
    lan = _shipped()["landing"]
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, swerve_accel=lan["swerve_accel"],
                                   withdraw_height=lan["withdraw_height"]))
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=TD + h, aborts=0,
                                  committed=1.0, armed=0.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    out = STEP(xg, [0.0, 0.0, TD + h], [0.0, a_lat, 0.0], pg)
    return GUIDANCE_STATE.unpack(np.asarray(out, dtype=float).ravel())


@pytest.mark.parametrize(("h", "a_lat", "withdrawn"), [
    (0.19, 0.21, True),     # over the floor, past the limit: withdrawn, one abort
    (0.17, 0.21, False),    # under the floor (the flare's front-foot contact): goes on
    (0.19, 0.19, False),    # within the limit: goes on
    (0.24, 0.25, True),     # the crawl's top in the lane change (0.3 of before: goes on)
])
def test_the_step_withdraws_over_the_floor_past_the_limit(h, a_lat, withdrawn):
    """Withdrawn: uncommitted, one abort, the reference glides up by descent_speed x dt; else
    the crawl goes on down at touchdown_speed, committed, no abort."""
    g = _after(h, a_lat)
    if withdrawn:
        assert (g["committed"][0], g["aborts"][0]) == (0.0, 1.0)
        assert g["z_ref"][0] == pytest.approx(TD + h + GUIDANCE_P["descent_speed"] * DT,
                                              rel=1e-12)
    else:
        assert (g["committed"][0], g["aborts"][0]) == (1.0, 0.0)
        assert g["z_ref"][0] == pytest.approx(TD + h - GUIDANCE_P["touchdown_speed"] * DT,
                                              rel=1e-12)


def test_the_lane_change_passes_the_limit_sooner():
    """The lane change's lateral acceleration, 2 pi L / T^2 sin(2 pi t / T) (3.5 m in 4 s,
    peak 1.374 m/s^2), passes s at t = T / (2 pi) asin(s T^2 / (2 pi L)): 0.0930 s for 0.2
    m/s^2 against 0.1401 s for 0.3."""
    peak = 2 * math.pi * 3.5 / 4.0 ** 2

    def onset(s):
        return 4.0 / (2 * math.pi) * math.asin(s / peak)
    assert onset(_shipped()["landing"]["swerve_accel"]) == pytest.approx(0.0930, abs=5e-5)
    assert onset(0.3) == pytest.approx(0.1401, abs=5e-5)


def test_seed_7_run_87_is_withdrawn_and_lands():
    """Seed 7's run 87: with the keys of before its front foot touches the roof at 12.53 s in
    the lane change's onset and the crawl's abort climbs away (judged bounced, not secured);
    with the shipped pair the swerve withdraws the crawl before the contact, and it lands on
    a later descent within every limit."""
    sc = load_scenario("highway_100", {"campaign.seed": 7})
    overrides = draws(campaign_spec_of(sc), [87])[0].overrides()

    def flown(*extra):
        res = quadland.simulate(load_scenario("highway_100", [*overrides, *extra]))
        return res, touchdown_report(res)

    before_res, before = flown(*HIGHWAY_100_MARKER)
    k0 = int(np.argmax(before_res["touched"] > 0.5))
    assert 12.5 < before_res["t"][k0] < 12.6
    assert not before.success and before.bounced and before.bounce > 1.0   # the climb: 2.68 m
    res, report = flown()
    k1 = int(np.argmax(res["touched"] > 0.5))
    assert res["t"][k1] > 15.0 and report.aborts >= 1
    assert report.success and report.secured

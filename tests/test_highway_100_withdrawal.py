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
from reference import GUIDANCE_P, HANDOVER_COLD, HIGHWAY_100_MARKER

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


def _lowest_foot_drop(th, phi, fx, fy, hc):
    """How far the lowest of the four feet ``(+-fx, +-fy, -hc)`` lies under the level gear's
    once the body is tilted ``th`` toward the direction ``phi`` off its x axis: the feet
    rotated by Rodrigues' formula about the horizontal axis normal to that direction (a
    second way to the closed form above, which holds for ``phi = 0`` only)."""
    u = np.array([-math.sin(phi), math.cos(phi), 0.0])
    k = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    r = np.eye(3) + math.sin(th) * k + (1 - math.cos(th)) * k @ k
    feet = np.array([[sx * fx, sy * fy, -hc] for sx in (1, -1) for sy in (1, -1)])
    return float(-np.min((feet @ r.T)[:, 2]) - hc)


def test_the_floor_s_margin_is_a_lean_4_deg_off_the_airflow():
    """The floor's 1 cm over the front feet's contact holds for a lean straight into the
    airflow only: a lean ``phi`` off the body's x axis puts the outer front foot ``sin th (fx
    cos phi + fy sin phi) + hc cos th - hc`` under the level gear, at the floor (0.18 m) for
    ``phi = atan(fy / fx) - acos((0.18 + hc - hc cos th) / (sin th sqrt(fx^2 + fy^2)))`` =
    33.69 - 29.47 = 4.22 deg at 46 deg (the replays' contacts lean 1-12 deg off it, 3-4 deg
    at 43-46 deg of tilt: the crosswind gust and the lane change; docs/landing.md, the
    section's review). By hand against the feet rotated (Rodrigues)."""
    d = _shipped()
    th = math.radians(d["touchdown"]["flare_tilt_deg"])
    fx, fy, hc = d["gear"]["feet_x"], d["gear"]["feet_y"], d["quadrotor"]["gear_height"]
    floor = d["landing"]["withdraw_height"]
    assert _lowest_foot_drop(th, 0.0, fx, fy, hc) == pytest.approx(0.1700, abs=5e-5)
    phi = math.atan2(fy, fx) - math.acos((floor + hc - hc * math.cos(th))
                                         / (math.sin(th) * math.hypot(fx, fy)))
    assert math.degrees(phi) == pytest.approx(4.22, abs=5e-3)
    assert _lowest_foot_drop(th, phi, fx, fy, hc) == pytest.approx(floor, abs=1e-9)
    assert _lowest_foot_drop(th, math.radians(6.0), fx, fy, hc) > floor


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
    m/s^2 against 0.1401 s for 0.3. This is the car's truth (the simulated car's, checked in
    the replay below); the guidance reads the filter's estimate, updated by the 10 Hz
    datalink and lagging the ramp by about 0.26 m/s^2 (tests/test_highway_100_lane_change.py),
    which on the replays passes both limits in the same 0.1 s update (seed 7's 87, the
    default's 154) or one update apart (the default's 227)."""
    peak = 2 * math.pi * 3.5 / 4.0 ** 2

    def onset(s):
        return 4.0 / (2 * math.pi) * math.asin(s / peak)
    assert onset(_shipped()["landing"]["swerve_accel"]) == pytest.approx(0.0930, abs=5e-5)
    assert onset(0.3) == pytest.approx(0.1401, abs=5e-5)


def test_seed_7_run_87_is_withdrawn_and_lands():
    """Seed 7's run 87: with the keys of before its front foot touches the roof at 12.53 s in
    the lane change's onset and the crawl's abort climbs away (judged bounced, not secured);
    with the shipped pair the swerve withdraws the crawl before the contact, and it lands on
    a later descent within every limit. The withdrawal starts at 12.40 s, 0.182 m over
    touchdown, and the body sinks on: its lowest foot passes 0.09 mm over the roof at
    12.55 s (docs/landing.md, the section's review), so a change of the numerics that moves
    the body by a tenth of a millimetre may flip this run, not the mechanism."""
    sc = load_scenario("highway_100", {"campaign.seed": 7})
    overrides = draws(campaign_spec_of(sc), [87])[0].overrides() + HANDOVER_COLD

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
    # the simulated car against the closed form above: its lateral acceleration (second
    # differences of its track, across its heading) first passes 0.2 and 0.3 m/s^2 within
    # one output step after 12 s + 0.0930 and + 0.1401 s
    t, psi = res["t"], res["psi2"]
    ax = np.gradient(np.gradient(res["x2"], t), t)
    ay = np.gradient(np.gradient(res["y2"], t), t)
    a_lat = np.abs(-np.sin(psi) * ax + np.cos(psi) * ay)
    step = float(np.median(np.diff(t)))
    for limit, onset in ((0.2, 0.0930), (0.3, 0.1401)):
        k = int(np.flatnonzero((t > 11.5) & (a_lat > limit))[0])
        assert 12.0 + onset - 1e-9 <= t[k] <= 12.0 + onset + step + 1e-9

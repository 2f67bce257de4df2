"""``landing.swerve_accel``: the guidance's hold while the pad swerves (symbolic/landing/swerve.py,
symbolic/landing/guidance.py; docs/landing.md, "highway_100: the guidance holds through the
lane change").

Checked against hand derivations: the held window of a lane change's sinusoidal lateral
acceleration (its closed form, step by step through the guidance), the withdrawal of a
committed descent by one step (the reference glides up at descent_speed, one abort) and
``withdraw_height`` keeping the crawl, the swerve's measure, and that at 0 (the default,
every scenario but highway_100) the step is the one without the swerve, value for value.
"""

import math

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland.scenario import ScenarioError, load_scenario
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, landing_guidance_function
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
WAIT = TD + GUIDANCE_P["commit_height"]
#: ISO 3888-1's lane offset in highway_100's 4 s from 12 s: a lateral acceleration
#: 2 pi L / T^2 sin(2 pi (t - T0) / T), peak 1.374 m/s^2 (docs/landing.md, "Cars that drive")
L_LANE, T_LANE, T0 = 3.5, 4.0, 12.0
A_PEAK = 2 * math.pi * L_LANE / T_LANE ** 2


def _step_function():
    """guidance_step with the swerve as an input: (xg, p_e, a2E, p_guid) -> xg_next, ref."""
    xg, p_e, a2E = GUIDANCE_STATE.sym(), ca.SX.sym("p_e", 3), ca.SX.sym("a2E", 3)
    p_guid = GUIDANCE_PARAMS.sym()
    cues = ca.DM(GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0)))
    xg_next, ref = guidance_step(xg, p_e, ca.DM.zeros(3), 0, 0, cues, DT, p_guid,
                                 swerve=pad_swerve(a2E))
    return ca.Function("g", [xg, p_e, a2E, p_guid], [xg_next, ref])


STEP = _step_function()


def _state(z_ref, committed):
    return GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                    committed=committed, armed=0.0, ms_rise=0.0,
                                    ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                    lean_x=0.0, lean_y=0.0, lean_gust=0.0))


def _after(z_ref, committed, a_lat, swerve_accel, withdraw_height=-1e3):
    """One step from the reference at ``z_ref``, the quadrotor on it at rest over the pad,
    the pad accelerating ``a_lat`` sideways (y, E). Returns the state after it."""
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, swerve_accel=swerve_accel,
                                   withdraw_height=withdraw_height))
    xg_next, _ = STEP(_state(z_ref, committed), [0.0, 0.0, z_ref], [0.0, a_lat, 0.0], pg)
    return GUIDANCE_STATE.unpack(np.asarray(xg_next, dtype=float).ravel())


def _lane_accel(t):
    return A_PEAK * math.sin(2 * math.pi * (t - T0) / T_LANE) if T0 <= t <= T0 + T_LANE else 0.0


@pytest.mark.parametrize("s", [0.3, 0.5, 1.0])
def test_the_hold_window_of_a_lane_change_by_hand(s):
    """At the wait height, uncommitted, the step commits exactly where |a| <= s: the lane
    change holds it over (T0 + d, T0 + T/2 - d) and (T0 + T/2 + d, T0 + T - d), with
    d = T / (2 pi) asin(s / A) (0.140 s at 0.3 m/s^2 and 1.374 m/s^2 peak), each edge
    to the step."""
    d = T_LANE / (2 * math.pi) * math.asin(s / A_PEAK)
    windows = [(T0 + d, T0 + T_LANE / 2 - d), (T0 + T_LANE / 2 + d, T0 + T_LANE - d)]
    times = np.arange(11.5, 16.5, DT)
    held = np.array([_after(WAIT, 0.0, _lane_accel(t), s)["committed"][0] == 0.0
                     for t in times])
    by_hand = np.array([any(lo < t < hi for lo, hi in windows) for t in times])
    edge = np.array([min(abs(t - e) for w in windows for e in w) for t in times]) <= DT
    assert held.any() and np.array_equal(held[~edge], by_hand[~edge])
    # the whole held time: T - 4 d, to two steps
    assert held.sum() * DT == pytest.approx(T_LANE - 4 * d, abs=2 * DT)


def test_a_swerve_withdraws_the_committed_descent_as_a_rising_deck_does():
    """Committed 0.6 m above touchdown, a swerve past the limit withdraws the commit: one
    abort, the reference glides up by descent_speed x dt; within it the reference falls at
    the profile's rate (0.6 / descent_time, under descent_speed)."""
    g = _after(TD + 0.6, 1.0, 0.31, 0.3)
    assert (g["committed"][0], g["aborts"][0]) == (0.0, 1.0)
    assert g["z_ref"][0] == pytest.approx(TD + 0.6 + GUIDANCE_P["descent_speed"] * DT,
                                          rel=1e-12)
    g = _after(TD + 0.6, 1.0, 0.29, 0.3)
    assert (g["committed"][0], g["aborts"][0]) == (1.0, 0.0)
    assert g["z_ref"][0] == pytest.approx(TD + 0.6 - 0.6 / GUIDANCE_P["descent_time"] * DT,
                                          rel=1e-12)


def test_the_crawl_below_withdraw_height_goes_on_through_a_swerve():
    """withdraw_height 0.25 m: the committed crawl at 0.1 m goes on at touchdown_speed
    through a swerve, no abort; at 0.6 m the swerve withdraws it."""
    g = _after(TD + 0.1, 1.0, 1.0, 0.3, withdraw_height=0.25)
    assert (g["committed"][0], g["aborts"][0]) == (1.0, 0.0)
    assert g["z_ref"][0] == pytest.approx(TD + 0.1 - GUIDANCE_P["touchdown_speed"] * DT,
                                          rel=1e-12)
    assert _after(TD + 0.6, 1.0, 1.0, 0.3, withdraw_height=0.25)["committed"][0] == 0.0


def test_the_swerve_is_the_horizontal_acceleration():
    """|a_h|: 0.3 and 0.4 m/s^2 across make 0.5; the vertical does not count."""
    assert float(pad_swerve(ca.DM([0.3, -0.4, 7.0]))) == pytest.approx(0.5, rel=1e-15)


def test_at_zero_the_step_is_the_one_without_the_swerve():
    """swerve_accel 0 (the default): on random states and a pad swerving at up to 10 m/s^2
    the step's state and reference equal those of the step without the swerve's input."""
    xg, p_e, v_e = GUIDANCE_STATE.sym(), ca.SX.sym("p_e", 3), ca.SX.sym("v_e", 3)
    rise, rate, cues = ca.SX.sym("r"), ca.SX.sym("a"), GUIDANCE_CUES.sym()
    a2E, pg = ca.SX.sym("a2E", 3), GUIDANCE_PARAMS.sym()
    without = ca.Function("w", [xg, p_e, v_e, rise, rate, cues, a2E, pg],
                          list(guidance_step(xg, p_e, v_e, rise, rate, cues, DT, pg)))
    with_s = ca.Function("s", [xg, p_e, v_e, rise, rate, cues, a2E, pg],
                         list(guidance_step(xg, p_e, v_e, rise, rate, cues, DT, pg,
                                            swerve=pad_swerve(a2E))))
    rng = np.random.default_rng(19)
    pgv = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, swerve_accel=0.0))
    for _ in range(200):
        h = rng.uniform(-0.1, 3.5)
        x = _state(TD + h, float(rng.integers(0, 2)))
        args = (x, [rng.normal(0, 0.1), rng.normal(0, 0.1), TD + h + rng.normal(0, 0.05)],
                rng.normal(0, 0.2, 3), rng.normal(0, 0.5), rng.normal(0, 1.0),
                [float(rng.integers(0, 2)), rng.uniform(0, 1), float(rng.integers(0, 2))],
                rng.uniform(-10, 10, 3), pgv)
        for a, b in zip(without(*args), with_s(*args), strict=True):
            assert np.array_equal(np.asarray(a), np.asarray(b))


def test_a_bad_value_is_one_clear_error_line():
    with pytest.raises(ScenarioError) as e:
        load_scenario("highway", ["landing.swerve_accel=-0.1"])
    assert "swerve_accel" in str(e.value) and "\n" not in str(e.value)


@pytest.mark.parametrize("name", ["highway", "turning", "ship", "ship_ss5"])
def test_the_other_landing_scenarios_hold_nothing(name):
    """Every other shipped landing scenario takes 0, no hold."""
    assert load_scenario(name)["landing.swerve_accel"] == 0.0


def _flight_guidance(a2E, v2E, swerve_accel):
    """The flight code's guidance step (``landing_guidance``: the measurement ``y`` as the
    flight code holds it, the filter's estimate on sensors) at the wait height, uncommitted,
    the quadrotor level over the pad: whether it commits."""
    y = LANDING_MEASUREMENT.pack(dict(p_e=[0.0, 0.0, WAIT], v_e=[0.0] * 3, eta1=[0.0] * 3,
                                      Omega1=[0.0] * 3, eta2=[0.0] * 3, v2E=v2E, a2E=a2E,
                                      w2E=[0.0] * 3, w2E_dot=[0.0] * 3))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, swerve_accel=swerve_accel))
    xg_next, _ = landing_guidance_function()(_state(WAIT, 0.0), y, cues, DT, pg)
    return GUIDANCE_STATE.unpack(np.asarray(xg_next, dtype=float).ravel())["committed"][0]


def test_the_flight_code_s_guidance_reads_the_measured_pad_acceleration():
    """The flight code's step passes the measurement's pad acceleration ``a2E`` (the
    filter's ``a_t`` on sensors, the broadcast on perfect sensing), its horizontal part:
    0.31 m/s^2 across holds the commit at 0.3, 0.29 does not, nor at 0 (no hold); the pad's
    100 km/h velocity holds nothing."""
    road = [27.8, 0.0, 0.0]
    assert _flight_guidance([0.0, 0.31, 0.0], road, 0.3) == 0.0
    assert _flight_guidance([0.0, 0.29, 0.0], road, 0.3) == 1.0
    assert _flight_guidance([0.0, 0.0, 0.0], road, 0.3) == 1.0
    assert _flight_guidance([0.0, 0.31, 0.0], road, 0.0) == 1.0

"""``calm_lean`` and ``lean_withdraw``: the gust's lean holds and withdraws the commit
(symbolic/landing/deck_tilt.py, symbolic/landing/guidance.py), against hand derivations.

The average is a first-order lag of ``|b_h|`` (the sine of the body z axis's tilt) with
the gain ``k = dt / lean_time`` per step, so that from ``a_0`` under a constant lean ``s``
it is ``s + (a_0 - s) (1 - k)^n`` after ``n`` steps; the commit and the withdrawal read it
against ``sin(calm_lean)``.
"""

import math

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland.exceptions import ScenarioError
from quadland.scenario import load_scenario
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, landing_guidance_function
from quadland_symbolic.landing.deck_tilt import (
    DECK_TILT_STATE,
    TILT_CUES,
    lean_calm,
    tilt_update,
)
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_step,
)

DEG = math.pi / 180
DT = 0.004


def _guidance():
    xg, pe, ve = GUIDANCE_STATE.sym(), ca.SX.sym("pe", 3), ca.SX.sym("ve", 3)
    v, a, dt, pg = ca.SX.sym("v"), ca.SX.sym("a"), ca.SX.sym("dt"), GUIDANCE_PARAMS.sym()
    cues, tilt = GUIDANCE_CUES.sym(), TILT_CUES.sym()
    return ca.Function("g", [xg, pe, ve, v, a, cues, dt, pg, tilt],
                       list(guidance_step(xg, pe, ve, v, a, cues, dt, pg, tilt)))


G = _guidance()
CUES = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
TOUCHDOWN = GUIDANCE_P["touchdown_height"]


def _state(z_ref, committed, lean_gust):
    return GUIDANCE_STATE.pack(dict(
        phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0, committed=committed, armed=0.0,
        ms_rise=0.0, ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0,
        lean_y=0.0, lean_gust=lean_gust))


def _tilt(lean_deg):
    """A level, still deck; the quadrotor leaning ``lean_deg`` toward +y."""
    return TILT_CUES.pack(dict(n_h=[0, 0], n_h_dot=[0, 0], n_h_ddot=[0, 0],
                               b_h=[0.0, math.sin(lean_deg * DEG)]))


def _step(xg, pg, z, lean_deg):
    xg_next, _ = G(xg, [0.0, 0.0, z], [0.0, 0.0, 0.0], 0.0, 0.0, CUES, DT, pg, _tilt(lean_deg))
    return np.asarray(xg_next, float).ravel()


def test_the_average_is_a_first_order_lag_of_the_leans_size():
    """From 0 under a constant lean b_h = (0.3, 0.4) (|b_h| = 0.5): 0.5 (1 - (1 - k)^n)
    after n steps, k = dt / lean_time; the other averages as before (lean_time does not
    enter them)."""
    xs, b = ca.SX.sym("x", DECK_TILT_STATE.size), ca.SX.sym("b", 2)
    step = ca.Function("s", [xs, b], [tilt_update(xs, ca.DM.zeros(2), ca.DM.zeros(2), b, DT,
                                                  20.0, 0.8)])
    x = DECK_TILT_STATE.zeros()
    for _ in range(250):
        x = step(x, [0.3, 0.4])
    q = DECK_TILT_STATE.unpack(np.asarray(x, float).ravel())
    k = DT / 0.8
    assert q["lean_gust"][0] == pytest.approx(0.5 * (1 - (1 - k) ** 250), rel=1e-12)
    kl = DT / 20.0
    assert q["lean_y"][0] == pytest.approx(0.4 * (1 - (1 - kl) ** 250), rel=1e-12)


def test_the_lean_condition_by_hand():
    """sin(calm_lean) is the bound, inclusive; from 90 deg on there is none (a lean of 1,
    lying flat, still passes)."""
    f = ca.Function("c", [a := ca.SX.sym("a"), c := ca.SX.sym("c")], [lean_calm(a, c)])
    assert float(f(math.sin(14.99 * DEG), 15 * DEG)) == 1.0
    assert float(f(math.sin(15.01 * DEG), 15 * DEG)) == 0.0
    assert float(f(1.0, 90 * DEG)) == 1.0 and float(f(1.0, math.pi)) == 1.0
    assert float(f(1.0, 89.9 * DEG)) == 0.0


def test_the_commit_waits_for_the_gust_to_pass():
    """At the wait height over a level, still deck (every other condition calm), the lean's
    average starting at sin 25 deg and the quadrotor leaning 10 deg: with calm_lean 18 deg
    the commit comes at the first step n with sin 10 + (sin 25 - sin 10)(1 - k)^n <=
    sin 18, k = dt / lean_time; with the default (90 deg) at the first step."""
    wait = TOUCHDOWN + GUIDANCE_P["commit_height"]
    s10, s18, s25 = (math.sin(d * DEG) for d in (10, 18, 25))
    k = DT / GUIDANCE_P["lean_time"]
    n_star = math.ceil(math.log((s18 - s10) / (s25 - s10)) / math.log(1 - k))
    assert s10 + (s25 - s10) * (1 - k) ** n_star <= s18 < \
        s10 + (s25 - s10) * (1 - k) ** (n_star - 1)
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, calm_lean=18 * DEG))
    xg = _state(wait, 0.0, s25)
    for n in range(1, n_star + 1):
        xg = _step(xg, pg, wait, 10.0)
        g = GUIDANCE_STATE.unpack(xg)
        assert g["committed"][0] == (1.0 if n == n_star else 0.0), n
        assert g["lean_gust"][0] == pytest.approx(s10 + (s25 - s10) * (1 - k) ** n, rel=1e-12)
        xg[GUIDANCE_STATE.slice("z_ref")] = wait     # held at the wait height for the check
    default = GUIDANCE_STATE.unpack(_step(_state(wait, 0.0, s25),
                                          GUIDANCE_PARAMS.pack(GUIDANCE_P), wait, 10.0))
    assert default["committed"][0] == 1.0


@pytest.mark.parametrize(("h", "lean", "withdraw", "withdraw_height", "expected"), [
    (0.6, 20.0, 0.0, 0.3, (1.0, 0.0)),     # lean_withdraw off: the gust holds no commit
    (0.6, 20.0, 1.0, 0.3, (0.0, 1.0)),     # on: withdrawn above withdraw_height, one abort
    (0.1, 20.0, 1.0, 0.3, (1.0, 0.0)),     # in the crawl, below withdraw_height: goes on
    (0.6, 17.0, 1.0, 0.3, (1.0, 0.0)),     # a lean within calm_lean withdraws nothing
    (0.1, 20.0, 1.0, -1e3, (0.0, 1.0)),    # the default withdraw_height: everywhere
])
def test_a_gust_withdraws_the_committed_descent(h, lean, withdraw, withdraw_height, expected):
    """Committed, the reference h above touchdown, the lean's average at the lean held
    (calm_lean 18 deg): the withdrawal by hand, and the reference after it (up at
    descent_speed when withdrawn, down at the profile's rate when not)."""
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, calm_lean=18 * DEG, lean_withdraw=withdraw,
                                   withdraw_height=withdraw_height))
    g = GUIDANCE_STATE.unpack(_step(_state(TOUCHDOWN + h, 1.0, math.sin(lean * DEG)), pg,
                                    TOUCHDOWN + h, lean))
    assert (g["committed"][0], g["aborts"][0]) == expected
    rate = min(max(h / GUIDANCE_P["descent_time"], GUIDANCE_P["touchdown_speed"]),
               GUIDANCE_P["descent_speed"])
    dz = GUIDANCE_P["descent_speed"] * DT if expected[1] else -rate * DT
    assert g["z_ref"][0] == pytest.approx(TOUCHDOWN + h + dz, rel=1e-12)


def test_the_keys_are_validated():
    """calm_lean_deg within [0, 90], lean_time above 0, lean_withdraw a boolean; the
    defaults are no limit."""
    sc = load_scenario("ship")
    assert (sc["landing.calm_lean_deg"], sc["landing.lean_time"],
            sc["landing.lean_withdraw"]) == (90.0, 1.0, False)
    for bad in ("landing.calm_lean_deg=91.0", "landing.calm_lean_deg=-1.0",
                "landing.lean_time=0.0", 'landing.lean_withdraw="yes"'):
        with pytest.raises(ScenarioError):
            load_scenario("ship", [bad])


def _flight_step(eta1_deg, eta2_deg, a_lat, committed, h, **keys):
    """The flight code's guidance step (``landing_guidance`` on the measurement ``y``: the
    IMU's attitude estimate ``eta1`` on sensors), the reference ``h`` above touchdown, the
    quadrotor on it over the pad, the pad accelerating ``a_lat`` sideways; lean_time 1 step
    (the average is the step's lean). Returns (committed, aborts, lean_gust) after it."""
    y = LANDING_MEASUREMENT.pack(dict(
        p_e=[0.0, 0.0, TOUCHDOWN + h], v_e=[0.0] * 3, eta1=np.multiply(eta1_deg, DEG),
        Omega1=[0.0] * 3, eta2=np.multiply(eta2_deg, DEG), v2E=[0.0] * 3,
        a2E=[0.0, a_lat, 0.0], w2E=[0.0] * 3, w2E_dot=[0.0] * 3))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, calm_lean=18 * DEG, lean_time=DT, **keys))
    xg_next, _ = landing_guidance_function()(_state(TOUCHDOWN + h, committed, 0.0), y, CUES,
                                             DT, pg)
    g = GUIDANCE_STATE.unpack(np.asarray(xg_next, float).ravel())
    return g["committed"][0], g["aborts"][0], g["lean_gust"][0]


def test_the_flight_code_s_guidance_reads_the_quadrotor_s_measured_lean():
    """The lean is the measurement's body attitude ``eta1`` (the IMU's estimate on sensors),
    not the deck's ``eta2``: rolled 25 deg (|b_h| = sin 25 deg, past sin 18 deg) it holds the
    commit at the wait height; level over a deck rolled 25 deg it commits (calm_tilt off);
    pitched 10 and rolled 10 deg, the body z axis's tilt is acos(cos 10 cos 10) deg."""
    wait = GUIDANCE_P["commit_height"]
    committed, _, lean = _flight_step([25.0, 0.0, 0.0], [0.0] * 3, 0.0, 0.0, wait)
    assert committed == 0.0 and lean == pytest.approx(math.sin(25 * DEG), rel=1e-12)
    committed, _, lean = _flight_step([0.0] * 3, [25.0, 0.0, 0.0], 0.0, 0.0, wait)
    assert committed == 1.0 and lean == 0.0
    tilt = math.acos(math.cos(10 * DEG) ** 2)
    assert _flight_step([10.0, 10.0, 30.0], [0.0] * 3, 0.0, 0.0, wait)[2] == \
        pytest.approx(math.sin(tilt), rel=1e-12)


@pytest.mark.parametrize(("lean", "a_lat", "withdraw", "expected"), [
    (20.0, 0.0, 0.0, (1.0, 0.0)),      # the lean alone, lean_withdraw off: goes on
    (20.0, 0.0, 1.0, (0.0, 1.0)),      # the lean alone with lean_withdraw: withdrawn
    (0.0, 0.31, 0.0, (0.0, 1.0)),      # the swerve alone withdraws, lean_withdraw or not
    (0.0, 0.31, 1.0, (0.0, 1.0)),
    (20.0, 0.31, 0.0, (0.0, 1.0)),     # both: one withdrawal, one abort
    (20.0, 0.31, 1.0, (0.0, 1.0)),
    (0.0, 0.29, 1.0, (1.0, 0.0)),      # neither
])
def test_the_swerve_and_the_lean_withdraw_as_one_cause(lean, a_lat, withdraw, expected):
    """Both keys on (swerve_accel 0.3 m/s^2, calm_lean 18 deg) through the flight code's
    step, committed 0.6 m above touchdown: a swerve withdraws whatever lean_withdraw says,
    the lean only with it; both together make one abort, not two."""
    got = _flight_step([lean, 0.0, 0.0], [0.0] * 3, a_lat, 1.0, 0.6, swerve_accel=0.3,
                       lean_withdraw=withdraw)
    assert got[:2] == expected

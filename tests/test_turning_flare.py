"""turning: a flare that bounds the tilt at contact, and the horizontal loop's slow tail
(issue 19's bar; docs/landing.md, "turning: the flare, and the observer alone").

The turning car's 300-run campaign landed 295 on ``bf41d33``: four runs met the roof
leaning 23.9 to 28.9 deg against the 23.3 deg limit (two of them then slid off the pad),
one never touched down. On the sensors' draws in blocks (issue 20) the settings of before
land 293 (five tilt failures, two sink rate), as shipped 298 (two offsets, 0.209 and
0.224 m). The shipped settings fly on through a 21 deg flare over the committed crawl;
the reproducers below are the tilt failures, replayed from the campaign's draws with the
settings of before (``BEFORE``, ``bf41d33``'s file to the bit) and as shipped.
"""

import math

import pytest
from reference import HANDOVER_COLD, TURNING_FILTER, TURNING_SEVENTEENTH
from turning_before import BEFORE

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

#: the pad of before the nested marker (docs/landing.md, "The nested marker").
PAD_BEFORE = "sensors.vision.small_range_max=0.0"
#: Still air, no force disturbance, the true state: nothing but the turn and the airflow.
CALM = ["sensors.enabled=false", "wind.turbulence_w20=0.0", "disturbance.noise=false",
        "disturbance.force_bias=[0.0, 0.0, 0.0]", "disturbance.force_amplitude=0.0"]
DEG = math.pi / 180


def _campaign_run(index, *overrides):
    """Run ``index`` of turning's campaign (default campaign seed), its draw replayed, with
    the crawl and land detector these rows were measured with
    (``TURNING_SEVENTEENTH``)."""
    d = draws(campaign_spec_of(load_scenario("turning")), [index])[0]
    return touchdown_report(quadland.simulate(load_scenario("turning", [
        *d.overrides(), *TURNING_SEVENTEENTH, *HANDOVER_COLD, *overrides])))


def test_the_flare_leaves_authority_over_the_steady_tilt_and_stays_under_the_limit():
    """The steady tilt in the turn is the contact limit less its 10 deg (13.3 deg: the
    10 m/s airflow's drag and the turn's 1 m/s^2, docs/landing.md). The flare's 21 deg
    is under the 23.3 deg limit by the attitude's 1-3 deg overshoot and leaves (tan 21 -
    tan 13.3) g = 1.45 m/s^2 of horizontal acceleration for the gusts; the flare covers
    the last two thirds of the committed crawl (touchdown_speed x descent_time = 0.3 m),
    0.2 m: 0.67 s at the crawl's 0.3 m/s (docs/landing.md, "turning: what the offset at
    contact is made of")."""
    d = load_scenario("turning").data
    land, td = d["landing"], d["touchdown"]
    steady = land["max_tilt_deg"] - 10.0
    assert steady == pytest.approx(13.3)
    assert td["policy"] == "secure" and td["flare_tilt_deg"] == 21.0
    assert land["max_tilt_deg"] - td["flare_tilt_deg"] == pytest.approx(2.3)
    left = (math.tan(td["flare_tilt_deg"] * DEG) - math.tan(steady * DEG)) * 9.8
    assert left == pytest.approx(1.445, abs=5e-4)
    crawl = land["touchdown_speed"] * land["descent_time"]
    assert crawl == pytest.approx(0.3)
    assert td["flare_height"] == pytest.approx(2 * crawl / 3)
    assert td["flare_height"] / land["touchdown_speed"] == pytest.approx(0.667, abs=5e-4)
    # the flare's limit stays inside the controller's own (45 deg, PX4's MPC_TILTMAX_AIR)
    assert d["controller"]["tilt_max_deg"] == 45.0 > td["flare_tilt_deg"]


def _crawl_lean_deg(sc, sink):
    """deg: the tilt that carries the quadrotor along the car's steady turn through still
    air while it sinks at ``sink`` m/s, solved by hand from the force balance
    ``m a = R (T e_z + f_body) - m g e_z`` for roll, pitch and thrust (yaw 0: the car's
    heading). ``u2`` = 10 m/s and ``r2`` = 0.1 rad/s come from eq. (4) with the file's
    forces, the turn's ``u2 r2`` = 1 m/s^2 toward its centre; ``f_body = -Kt V - Kq V |V|``
    per body axis, ``V`` the air's velocity past the body (docs/landing.md, "Real drag and
    thrust"). The command filter has unit gain at zero frequency: the lean does not depend
    on it."""
    import numpy as np
    import scipy.optimize

    m, g = sc["quadrotor.mass"], sc["quadrotor.gravity"]
    kt, kq = sc["quadrotor.drag_translational"][0], sc["quadrotor.drag_quadratic"][0]
    u = sc["vehicle.tau"][0] / sc["vehicle.d11"]   # eq. (4) steady: d11 u2 = tau_1
    r = sc["vehicle.tau"][2] / sc["vehicle.d33"]   # d33 r2 = tau_3
    v, a = np.array([u, 0.0, -sink]), np.array([0.0, u * r, 0.0])

    def balance(x):
        cp, sp, ct, st = math.cos(x[0]), math.sin(x[0]), math.cos(x[1]), math.sin(x[1])
        R = np.array([[ct, sp * st, cp * st], [0.0, cp, -sp], [-st, sp * ct, cp * ct]])
        vb = R.T @ v
        return R @ (np.array([0.0, 0.0, x[2]]) - kt * vb - kq * vb * np.abs(vb)) - [0, 0, m * g] \
            - m * a

    phi, theta, _ = scipy.optimize.fsolve(balance, [0.0, 0.2, m * g], xtol=1e-12)
    return math.degrees(math.acos(math.cos(phi) * math.cos(theta)))


def test_calm_air_steady_tilt_is_the_hand_derived_one():
    """In still air on the true state the turning car's landing meets its roof at the
    steady tilt of the hand derivation, 13.3 deg (to 0.05 deg), within the flare, on the
    command filter it was measured with (``TURNING_FILTER``, 10 rad/s: a replay of that
    file's flight). On the shipped 13 rad/s the contact comes at the lean the force balance
    asks at the crawl's sink rate (``landing.touchdown_speed``, 0.3 m/s): 13.47 deg, and
    13.38 deg at rest, by hand; flown, 13.40 deg (13.31 on 10 rad/s). The tolerance, 0.25
    deg, is half the swing the crawl's vertical transients make over its last second as
    flown on 13 rad/s, 13.17-13.70 deg (12.94-13.82 on 10 rad/s) (docs/landing.md, "Review
    of turning's command filter at the corners' bound")."""
    r = touchdown_report(quadland.simulate(load_scenario("turning", [*CALM, *TURNING_FILTER])))
    assert r.success and r.tilt_deg == pytest.approx(13.3, abs=0.05)
    sc = load_scenario("turning")
    crawl = _crawl_lean_deg(sc, sc["landing.touchdown_speed"])
    assert _crawl_lean_deg(sc, 0.0) == pytest.approx(13.38, abs=0.005)
    assert crawl == pytest.approx(13.47, abs=0.005)
    shipped = touchdown_report(quadland.simulate(load_scenario("turning", CALM)))
    assert shipped.success and shipped.tilt_deg == pytest.approx(crawl, abs=0.25)
    assert shipped.tilt_deg < sc["touchdown.flare_tilt_deg"]


#: The tilt failures of turning's 300-run campaign (default campaign seed) flown with the
#: settings of before, replayed: run, its tilt at contact before and as shipped (deg).
#: (On the sensors' draws of before, issue 20's blocks, the campaign of before failed
#: runs 11, 170, 200, 221 on the tilt, two of them then off the pad, and run 295 never
#: touched down; bf41d33's figures in docs/landing.md are those.)
#: (As shipped since "turning: what the offset at contact is made of", the filter's
#: ``q_acc``, ``q_at`` and the 0.2 m flare: each tilt is its row of that section's
#: 300-run campaign, runs.csv's ``tilt_deg``; 8.406, 19.557, 15.169, 20.300 and 21.244
#: deg with the filter's PX4 defaults and the 0.3 m flare.)
TILTED = [(19, 25.491, 14.497), (32, 28.825, 13.033), (36, 25.313, 19.020),
          (221, 25.056, 19.368), (294, 28.126, 20.250)]


@pytest.mark.parametrize(("index", "before_deg", "now_deg"), TILTED)
def test_the_campaigns_tilt_failures_of_before_land_inside_the_flare(index, before_deg,
                                                                     now_deg):
    """Each met the roof past turning's 23.3 deg limit (a gust in the committed crawl,
    the rotors cut at the switch, the 30 deg tilt limit); flown through the 21 deg flare
    it meets the roof under the limit (within the flare but for the attitude's overshoot,
    at most 0.25 deg here), on the pad and secured."""
    before = _campaign_run(index, *BEFORE)
    assert before.failures == ["tilt_deg"] and before.tilt_deg > 23.3
    assert before.tilt_deg == pytest.approx(before_deg, abs=5e-4)
    now = _campaign_run(index, PAD_BEFORE)                 # the campaign's pad
    assert now.success and now.on_pad and now.secured
    assert now.tilt_deg == pytest.approx(now_deg, abs=5e-4) and now.tilt_deg < 21.25
    nested = _campaign_run(index)                          # the nested marker
    assert nested.success and nested.on_pad and nested.secured and nested.tilt_deg < 21.25


def test_the_observer_alone_leaves_no_slow_tail_in_calm_air():
    """With the outer bias estimates on x and y (``ki_p`` 0.5) the handover's transient
    decays with the estimates' slow pole: in still air, with nothing to reject, the
    turning car's default seed meets its roof 0.041 m off the centre (0.036 m with the
    whole file of before). With the disturbance observer alone horizontally (``ki_p`` 0
    there; the observer learns a constant disturbance exactly, docs/landing.md) it is
    0.006 m: the law's equilibrium is the pad's centre. (Flown with the crawl without its
    gate: ``TURNING_SEVENTEENTH``, the file these were measured on.)"""
    assert touchdown_report(quadland.simulate(load_scenario(
        "turning", [*CALM, *BEFORE]))).offset == pytest.approx(0.0362, abs=5e-4)
    tail = touchdown_report(quadland.simulate(load_scenario(
        "turning", [*CALM, *TURNING_SEVENTEENTH, "controller.ki_p=[0.5, 0.5, 1.0]"])))
    assert tail.offset == pytest.approx(0.0405, abs=5e-4)
    now = touchdown_report(quadland.simulate(load_scenario(
        "turning", [*CALM, *TURNING_SEVENTEENTH])))
    assert now.offset == pytest.approx(0.0061, abs=5e-4)

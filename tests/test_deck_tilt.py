"""The deck tilt's commit condition (symbolic/landing/deck_tilt.py, ``calm_tilt``) against
hand derivations and finite differences.

The descent's duration from the wait height is the profile's closed form, checked against
the rate law integrated in small steps; the deck normal's rates against central differences
of ``R(eta2(t)) e_z``; the prediction is exact for one sinusoid on its own frequency; the
relative tilt is the spherical triangle's by hand; the guidance commits at the wait height
exactly where the hand predicate says, and with ``calm_tilt = pi`` (the default) the step
is the guidance of before, bit for bit.
"""

import math

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P, euler_rate_matrix, rotation

from quadland_symbolic.landing.deck_tilt import (
    DECK_TILT_STATE,
    TILT_CUES,
    descent_duration,
    relative_tilt_cos,
    tilt_ahead,
    tilt_cues,
    tilt_frequency,
    tilt_update,
)
from quadland_symbolic.landing.guidance import (
    ALIGN,
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_step,
)

DEG = math.pi / 180


def _num(x):
    return np.asarray(ca.evalf(x), dtype=float).ravel()


def test_the_descent_lasts_the_profiles_time():
    """From h0 = 1 m (descent_time 1 s, crawl 0.3 m/s, 0.7 m/s at most): 0.3 m at 0.7 m/s,
    then h' = -h from 0.7 to 0.3 m, ln(7/3) s, then 0.3 m at 0.3 m/s: 2.2759 s. The same
    law integrated in 10 us steps agrees to the step; h0 below the crawl's 0.3 m crawls only."""
    hand = 0.3 / 0.7 + math.log(0.7 / 0.3) + 1.0
    assert float(_num(descent_duration(1.0, 1.0, 0.3, 0.7))[0]) == pytest.approx(hand, 1e-12)
    assert hand == pytest.approx(2.27587, abs=1e-5)
    for h0 in (1.0, 0.5, 2.0):
        h, t, dt = h0, 0.0, 1e-5
        while h > 0:
            h -= min(max(h / 1.0, 0.3), 0.7) * dt
            t += dt
        assert float(_num(descent_duration(h0, 1.0, 0.3, 0.7))[0]) == pytest.approx(t, abs=2e-5)
    assert float(_num(descent_duration(0.2, 1.0, 0.3, 0.7))[0]) == pytest.approx(0.2 / 0.3)


def _eta2(t):
    """A rolling, pitching, turning deck: ZYX angles (phi, theta, psi)."""
    return np.array([0.12 * math.sin(0.9 * t), 0.05 * math.sin(1.3 * t + 0.3), 0.4 + 0.02 * t])


def _w2E(t, h=1e-5):
    """Angular velocity in E from the Euler rates: R(eta) Rr(eta)^-1 eta'."""
    eta, eta_dot = _eta2(t), (_eta2(t + h) - _eta2(t - h)) / (2 * h)
    return rotation(eta) @ np.linalg.solve(euler_rate_matrix(eta[0], eta[1]), eta_dot)


def test_the_deck_normals_rates_are_its_central_differences():
    """n = R(eta2) e_z; n' = w x n and n'' = w' x n + w x (w x n) against central
    differences of n(t) (w' itself a central difference of w)."""
    f = ca.Function("c", [ca.SX.sym("e1", 3), e2 := ca.SX.sym("e2", 3), w := ca.SX.sym("w", 3),
                          wd := ca.SX.sym("wd", 3)], [tilt_cues(ca.SX.zeros(3), e2, w, wd)])
    h = 1e-4
    for t in (0.0, 1.7, 4.2):
        n = [rotation(_eta2(t + k * h))[:, 2] for k in (-1, 0, 1)]
        wd = (_w2E(t + h) - _w2E(t - h)) / (2 * h)
        c = TILT_CUES.unpack(np.asarray(f([0, 0, 0], _eta2(t), _w2E(t), wd), float).ravel())
        np.testing.assert_allclose(c["n_h"], n[1][:2], atol=1e-14)
        np.testing.assert_allclose(c["n_h_dot"], ((n[2] - n[0]) / (2 * h))[:2], atol=1e-7)
        np.testing.assert_allclose(c["n_h_ddot"], ((n[2] - 2 * n[1] + n[0]) / h ** 2)[:2],
                                   atol=2e-5)


def test_one_sinusoid_is_predicted_exactly_on_its_frequency():
    """n_h = A sin(w t + p) per component: n_h(t + T) from n_h(t), n_h'(t) and w."""
    A, w, p, T = np.array([0.08, -0.03]), 1.1, np.array([0.4, 2.0]), 2.2759
    for t in (0.0, 0.9, 3.3):
        now, rate = A * np.sin(w * t + p), A * w * np.cos(w * t + p)
        np.testing.assert_allclose(_num(tilt_ahead(ca.DM(now), ca.DM(rate), w, T)),
                                   A * np.sin(w * (t + T) + p), atol=1e-15)


def test_the_frequency_of_a_rolling_deck_from_its_averages():
    """n_h = (0, -A sin(w t)) (small A): the averages of |n_h'|^2 = A^2 w^2 cos^2 and
    |n_h''|^2 = A^2 w^4 sin^2 over 200 s (motion_time 20 s) give w within the ripple's
    2 r / (1 - 2 r), r = 1 / (2 sqrt(1 + (2 w 20)^2)) (test_quiescence's bound); the lean
    average tends to the steady lean."""
    A, w, dt = 0.01, 0.9, 0.01
    xs, nd, ndd, b, dts, tm = (ca.SX.sym(n, k) for n, k in (
        ("x", 5), ("nd", 2), ("ndd", 2), ("b", 2), ("dt", 1), ("tm", 1)))
    x = tilt_update(xs, nd, ndd, b, dts, tm, 1.0)
    step = ca.Function("s", [xs, nd, ndd, b, dts, tm], [x, tilt_frequency(x)])
    xv = DECK_TILT_STATE.zeros()
    for k in range(int(200 / dt)):
        t = k * dt
        xv, om = step(xv, [0, -A * w * math.cos(w * t)], [0, A * w * w * math.sin(w * t)],
                      [0.0, 0.17], dt, 20.0)
    r = 1 / (2 * math.sqrt(1 + (2 * w * 20) ** 2))
    assert abs(float(om) / w - 1) <= 2 * r / (1 - 2 * r)
    lean = DECK_TILT_STATE.unpack(np.asarray(xv, float).ravel())
    assert lean["lean_y"][0] == pytest.approx(0.17, rel=1e-3) and lean["lean_x"][0] == 0


@pytest.mark.parametrize(("d_h", "angle"), [
    ((0.0, -math.sin(4.4 * DEG)), 19.4),         # rolled against the lean: the sum
    ((0.0, math.sin(4.4 * DEG)), 10.6),          # with it: the difference
    ((0.0, 0.0), 15.0),                          # level: the flare's lean
])
def test_the_relative_tilt_in_the_leans_plane(d_h, angle):
    """The lean 15 deg toward +y (whatever its length), the deck's normal in the same
    plane: the angles add or subtract."""
    c = float(_num(relative_tilt_cos(ca.DM([0.0, 0.02]), ca.DM(d_h), 15 * DEG))[0])
    assert math.degrees(math.acos(c)) == pytest.approx(angle, abs=1e-9)


def test_the_relative_tilt_across_the_leans_plane():
    """A deck tilted 4 deg about the lean's direction: the right spherical triangle,
    cos c = cos 15 cos 4."""
    c = float(_num(relative_tilt_cos(ca.DM([0.0, 0.3]), ca.DM([math.sin(4 * DEG), 0.0]),
                                     15 * DEG))[0])
    assert c == pytest.approx(math.cos(15 * DEG) * math.cos(4 * DEG), rel=1e-14)


def _guidance_with_tilt():
    xg, pe, ve = GUIDANCE_STATE.sym(), ca.SX.sym("pe", 3), ca.SX.sym("ve", 3)
    v, a, dt, pg = ca.SX.sym("v"), ca.SX.sym("a"), ca.SX.sym("dt"), GUIDANCE_PARAMS.sym()
    cues, tilt = GUIDANCE_CUES.sym(), TILT_CUES.sym()
    with_tilt = guidance_step(xg, pe, ve, v, a, cues, dt, pg, tilt)
    without = guidance_step(xg, pe, ve, v, a, cues, dt, pg)
    return ca.Function("g", [xg, pe, ve, v, a, cues, dt, pg, tilt], [*with_tilt, *without])


G = _guidance_with_tilt()


def test_the_default_is_the_guidance_of_before():
    """calm_tilt = pi: every result but the tilt's own averages equals the step without
    the tilt cues, bit for bit, over random states, measurements and decks."""
    rng = np.random.default_rng(19)
    pg = GUIDANCE_PARAMS.pack(GUIDANCE_P)
    n_old = GUIDANCE_STATE.size - DECK_TILT_STATE.size
    for _ in range(300):
        xg = GUIDANCE_STATE.pack(dict(
            phase=rng.integers(5), timer=rng.uniform(0, 2), z_ref=rng.uniform(0, 3),
            aborts=rng.integers(3), committed=rng.integers(2), armed=rng.integers(2),
            ms_rise=rng.uniform(0, 1), ms_rise_rate=rng.uniform(0, 2),
            ms_tilt_rate=rng.uniform(0, 0.01), ms_tilt_acc=rng.uniform(0, 0.02),
            lean_x=rng.uniform(-0.3, 0.3), lean_y=rng.uniform(-0.3, 0.3),
            lean_gust=rng.uniform(0, 0.5)))
        out = [np.asarray(o, float).ravel() for o in G(
            xg, rng.normal(size=3) * [0.1, 0.1, 1] + [0, 0, 1.2], rng.normal(size=3) * 0.2,
            rng.normal() * 0.3, rng.normal(), [rng.integers(2), 0, rng.integers(2)], 0.004, pg,
            rng.normal(size=8) * 0.1)]
        np.testing.assert_array_equal(out[0][:n_old], out[2][:n_old])
        np.testing.assert_array_equal(out[1], out[3])


def test_the_descent_commits_where_the_deck_will_lean_with_the_quadrotor():
    """A still heave, the deck rolling phi2 = A sin(w t) about E's x (A 6 deg, w 1 rad/s),
    the quadrotor leaning 10 deg toward +y (rolled -10 deg) and at its reference on the wait
    height, the averages at their steady values (omega w, the lean's). The worst lean is
    the flare's 15 deg toward +y, the deck's normal leans toward -y by phi2: the predicted
    angle is 15 + A sin(w (t + T)) deg, T the profile's 2.2759 s. With calm_tilt 17.9 deg
    the step commits iff 6 sin(w (t + T)) <= 2.9, up to the small-angle error of the
    averages (a band of 0.1 deg left out)."""
    A, w, flare, calm = 6 * DEG, 1.0, 15 * DEG, 17.9 * DEG
    T = 0.3 / 0.7 + math.log(0.7 / 0.3) + 1.0
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, flare_tilt=flare, calm_tilt=calm))
    wait = GUIDANCE_P["touchdown_height"] + GUIDANCE_P["commit_height"]
    lean = math.sin(10 * DEG)
    xg = GUIDANCE_STATE.pack(dict(
        phase=DESCEND, timer=0.0, z_ref=wait, aborts=0, committed=0, armed=0.0, ms_rise=0.0,
        ms_rise_rate=0.0, ms_tilt_rate=(A * w) ** 2 / 2, ms_tilt_acc=A ** 2 * w ** 4 / 2,
        lean_x=0.0, lean_y=lean, lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0, marker_age=0, contact_switch=0.0))
    f = ca.Function("c", [e2 := ca.SX.sym("e2", 3), wv := ca.SX.sym("w", 3),
                          wd := ca.SX.sym("wd", 3)],
                    [tilt_cues(ca.DM([-10 * DEG, 0, 0]), e2, wv, wd)])
    seen = set()
    for t in np.linspace(0, 2 * math.pi, 97):
        phi, rate, acc = A * math.sin(w * t), A * w * math.cos(w * t), -A * w * w * math.sin(
            w * t)
        tilt = f([phi, 0, 0], [rate, 0, 0], [acc, 0, 0])
        xg_next = np.asarray(G(xg, [0, 0, wait], [0, 0, 0], 0.0, 0.0, cues, 0.004, pg,
                               tilt)[0], float).ravel()
        predicted = flare + A * math.sin(w * (t + T))
        committed = GUIDANCE_STATE.unpack(xg_next)["committed"][0] >= 0.5
        if abs(predicted - calm) > 0.1 * DEG:
            assert committed == (predicted <= calm), (t, math.degrees(predicted))
            seen.add(committed)
        assert GUIDANCE_STATE.unpack(xg_next)["phase"][0] == DESCEND
    assert seen == {True, False}


def test_the_flight_codes_align_phase_keeps_the_averages_moving():
    """The averages update in every phase before touchdown (align here), as the heave's."""
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, calm_tilt=17.9 * DEG))
    xg = GUIDANCE_STATE.pack(dict(
        phase=ALIGN, timer=0.0, z_ref=3.0, aborts=0, committed=0, armed=0.0, ms_rise=0.0,
        ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    tilt = TILT_CUES.pack(dict(n_h=[0, 0], n_h_dot=[0.1, 0], n_h_ddot=[0, 0.2], b_h=[0, 0.1]))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0, marker_age=0, contact_switch=0.0))
    xg_next = GUIDANCE_STATE.unpack(np.asarray(G(xg, [0, 0, 3], [0, 0, 0], 0.0, 0.0, cues,
                                                 0.02, pg, tilt)[0], float).ravel())
    k = 0.02 / GUIDANCE_P["motion_time"]
    np.testing.assert_allclose([xg_next[n][0] for n in DECK_TILT_STATE.names()],
                               [k * 0.01, k * 0.04, 0.0, k * 0.1,
                                0.02 / GUIDANCE_P["lean_time"] * 0.1], rtol=1e-12)

"""The quiescent-period predictor (symbolic/landing/quiescence.py) against closed forms.

A pure sinusoid of the deck's heave is predicted exactly on its own frequency; on the
frequency the averages estimate, within the error their ripple allows (derived in each
test); a sum of two sinusoids within the bound of the extrapolation's error per
component. The guidance's commit rule is checked on synthetic records of the deck's rise.
"""

import math

import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)
from quadland_symbolic.landing.quiescence import (
    N_HORIZON,
    OMEGA_MAX,
    OMEGA_MIN,
    QUIESCENCE_STATE,
    quiescence_function,
)

DT = 0.004
TAU = 20.0                     # motion_time
Q = quiescence_function()


def _fly_predictor(v, a, horizon=2.5):
    """The predictor over the records v, a (one row a step): omega and speed per step."""
    xq = QUIESCENCE_STATE.zeros()
    vv, aa, dt, tm, hz = (np.asarray(x, dtype=float) for x in (v, a, DT, TAU, horizon))
    omegas, speeds = [], []
    for k in range(len(vv)):
        xq, om, sp = Q(xq, vv[k], aa[k], dt, tm, hz)
        omegas.append(float(om))
        speeds.append(float(sp))
    return np.array(omegas), np.array(speeds)


def _ahead(v, a, omega, tau):
    """The extrapolation v cos(omega tau) + a / omega sin(omega tau), in NumPy."""
    return v * np.cos(omega * tau) + a / omega * np.sin(omega * tau)


def test_a_pure_sinusoid_is_predicted_within_the_averages_ripple():
    """Heave z = Z sin(w t): v = Z w cos(w t), a = -Z w^2 sin(w t). The averages of
    cos^2 = 1/2 + cos(2 w t)/2 and sin^2 pass the 2w ripple with the gain
    1/sqrt(1 + (2 w TAU)^2) of the first-order average (the discrete one within
    O(w DT) of it), so their ratio is w^2 (1 - 2 r c)/(1 + 2 r c), |c| <= 1,
    r = 1/(2 sqrt(1 + (2 w TAU)^2)): |w_hat / w - 1| <= 2 r / (1 - 2 r) once the start
    has decayed (t >> TAU). The extrapolation with w_hat misses v(t + tau) =
    V cos(w tau + phi) by at most V (|w - w_hat| tau + |w / w_hat - 1|)."""
    Z, w = 0.5, 1.4
    t = DT * np.arange(int(150 / DT))
    v, a = Z * w * np.cos(w * t), -Z * w ** 2 * np.sin(w * t)
    omega, _ = _fly_predictor(v, a)
    r = 1 / (2 * math.sqrt(1 + (2 * w * TAU) ** 2))
    rel = 2 * r / (1 - 2 * r) * 1.01          # 1 % for the discrete average's O(w DT)
    late = t > 100
    assert np.max(np.abs(omega[late] / w - 1)) <= rel
    V, tau = Z * w, 2.5
    steps = int(round(tau / DT))
    idx = np.flatnonzero(late)[:-steps]
    err = np.abs(_ahead(v[idx], a[idx], omega[idx], tau) - v[idx + steps])
    bound = V * (np.abs(w - omega[idx]) * tau + np.abs(w / omega[idx] - 1))
    assert np.all(err <= bound + 1e-12)
    # stated: within 8 % of the velocity's amplitude at 2.5 s ahead (here 1.8 % of w)
    assert np.max(err) <= 0.08 * V
    # and exact on the true frequency: the extrapolation of one sinusoid is its identity
    np.testing.assert_allclose(_ahead(v[idx], a[idx], w, tau), v[idx + steps], atol=1e-12)


def test_two_sinusoids_within_the_extrapolations_bound():
    """v = V1 cos(w1 t) + V2 cos(w2 t + 1): each component's extrapolation on the one
    w_hat misses by at most Vi (|wi - w_hat| tau + |wi / w_hat - 1|). w_hat settles
    between the components' frequencies (about sqrt(sum Vi^2 wi^2 / sum Vi^2) = 1.29
    rad/s, the averages' ratio, with the cross term's ripple), where the bound at 1 s
    ahead is largest at w_hat = w2: V1 (0.4 + 0.25) = 0.325 m/s of the peak 0.75."""
    V1, w1, V2, w2 = 0.5, 1.2, 0.25, 1.6
    t = DT * np.arange(int(150 / DT))
    v = V1 * np.cos(w1 * t) + V2 * np.cos(w2 * t + 1)
    a = -V1 * w1 * np.sin(w1 * t) - V2 * w2 * np.sin(w2 * t + 1)
    omega, _ = _fly_predictor(v, a)
    late = t > 100
    assert np.all((omega[late] > w1) & (omega[late] < w2))
    tau = 1.0
    steps = int(round(tau / DT))
    idx = np.flatnonzero(late)[:-steps]
    om = omega[idx]
    err = np.abs(_ahead(v[idx], a[idx], om, tau) - v[idx + steps])
    bound = sum(Vi * (np.abs(wi - om) * tau + np.abs(wi / om - 1))
                for Vi, wi in ((V1, w1), (V2, w2)))
    assert np.all(err <= bound + 1e-12)
    assert np.max(bound) <= V1 * ((w2 - w1) * tau + 1 - w1 / w2) + 1e-12


def test_the_predicted_speed_is_the_largest_sample_and_a_still_deck_has_none():
    """The speed is max |v(t + tau_k)| over tau_k = k horizon / N_HORIZON, k = 0..N, by
    hand; a motionless deck (a car's roof) predicts 0 at the lowest frequency."""
    v, a, horizon = 0.3, -0.8, 2.5
    xq0 = QUIESCENCE_STATE.pack(dict(ms_rise=0.25, ms_rise_rate=0.49))   # w = 1.4 after
    xq, om, sp = (np.asarray(x, dtype=float).ravel() for x in Q(xq0, v, a, DT, TAU, horizon))
    k = DT / TAU
    ms_v, ms_a = 0.25 + k * (v ** 2 - 0.25), 0.49 + k * (a ** 2 - 0.49)
    np.testing.assert_allclose(xq, [ms_v, ms_a], rtol=1e-15)
    w = math.sqrt(ms_a / ms_v)
    assert om[0] == pytest.approx(w, rel=1e-14)
    taus = horizon * np.arange(N_HORIZON + 1) / N_HORIZON
    assert sp[0] == pytest.approx(np.max(np.abs(_ahead(v, a, w, taus))), rel=1e-14)
    _, om, sp = Q(QUIESCENCE_STATE.zeros(), 0.0, 0.0, DT, TAU, horizon)
    assert float(om) == OMEGA_MIN and float(sp) == 0.0
    _, om, _ = Q(QUIESCENCE_STATE.zeros(), 0.0, 5.0, DT, TAU, horizon)
    assert float(om) == OMEGA_MAX


# ---------------------------------------------------------------- the commit rule

P = dict(GUIDANCE_P, max_deck_rise=0.5, motion_time=TAU)
GUIDANCE = guidance_function()


def _descend(deck, n, z_ref=1.5):
    """A quadrotor on the reference over the pad from a descent at z_ref; deck(k) -> (v, a)
    the deck's rise and its rate. Returns z_ref, committed and aborts per step."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=0, armed=0.0, ms_rise=0, ms_rise_rate=0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                  lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    pg, cues = GUIDANCE_PARAMS.pack(P), GUIDANCE_CUES.pack(
        dict(touchdown=0, marker_age=0, contact_switch=0.0))
    out = []
    for k in range(n):
        g = GUIDANCE_STATE.unpack(xg)
        out.append((g["z_ref"][0], g["committed"][0], g["aborts"][0], g["phase"][0]))
        v, a = deck(k)
        xg = np.asarray(GUIDANCE(xg, [0, 0, g["z_ref"][0]], [0, 0, 0], v, a, cues, DT, pg)[0],
                        dtype=float).ravel()
    return np.array(out)


def _sine(V, w=1.4):
    return lambda k: (V * math.cos(w * k * DT), -V * w * math.sin(w * k * DT))


def test_a_heaving_deck_holds_the_descent_at_the_wait_height():
    """0.6 m/s of heave rate: every prediction over 2.5 s (more than half the 4.5 s
    period) reaches at least 0.6 cos(w 0.25 / 2) = 0.59 m/s > calm_speed: the reference
    falls to touchdown_height + commit_height = 1.2 m and holds there, uncommitted, and
    the deck's rise (above max_deck_rise each crest) aborts nothing."""
    rows = _descend(_sine(0.6), int(30 / DT))
    z, committed, aborts = rows[:, 0], rows[:, 1], rows[:, 2]
    assert not committed.any() and not aborts.any() and np.all(rows[:, 3] == DESCEND)
    k = int(np.argmax(z <= 1.2))
    assert k * DT == pytest.approx(0.3 / 0.7, abs=2 * DT)    # 0.3 m at 0.7 m/s
    np.testing.assert_allclose(z[k:], 1.2, rtol=1e-12)


def test_a_calm_window_commits_the_final_descent():
    """The heave rate's amplitude drops from 0.6 to 0.3 m/s at 20 s (phase continuous):
    the prediction is then at most 0.3 (1 + 2.5 |w_hat - w| + |w/w_hat - 1|) < 0.4, and
    the descent commits within the step and falls on at the profile's rate."""
    k20 = int(20 / DT)
    sines = _sine(0.6), _sine(0.3)
    rows = _descend(lambda k: sines[k >= k20](k), k20 + 100)
    z, committed = rows[:, 0], rows[:, 1]
    assert not committed[:k20 + 1].any() and committed[k20 + 1:].all()
    assert z[k20] == pytest.approx(1.2, rel=1e-12)
    # h = 1.0 m: the rate is min(h / descent_time, descent_speed) = 0.7 m/s
    np.testing.assert_allclose(z[k20 + 2] - z[k20 + 1], -0.7 * DT, rtol=1e-9)


def test_a_rising_deck_after_the_commit_aborts_back_to_the_wait_height():
    """Committed at 0.6 m, a deck rising at 0.8 m/s (> max_deck_rise) aborts once: the
    descent goes on uncommitted, its reference climbs at descent_speed back to the wait
    height, and commits again when calm."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=0.6, aborts=0, committed=1,
                                  armed=0.0, ms_rise=0, ms_rise_rate=0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                  lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    pg, cues = GUIDANCE_PARAMS.pack(P), GUIDANCE_CUES.pack(
        dict(touchdown=0, marker_age=0, contact_switch=0.0))
    zs = []
    for k in range(1000):
        g = GUIDANCE_STATE.unpack(xg)
        zs.append(g["z_ref"][0])
        rise = 0.8 if k == 10 else 0.0
        xg = np.asarray(GUIDANCE(xg, [0, 0, zs[-1]], [0, 0, 0], rise, 0.0, cues, DT, pg)[0],
                        dtype=float).ravel()
        g = GUIDANCE_STATE.unpack(xg)
        if k == 10:
            assert g["aborts"][0] == 1 and g["committed"][0] == 0 and g["phase"][0] == DESCEND
            assert g["z_ref"][0] == pytest.approx(zs[-1] + 0.7 * DT, rel=1e-12)
    # the rise's square keeps the prediction above calm for a while, then it commits again
    assert GUIDANCE_STATE.unpack(xg)["aborts"][0] == 1

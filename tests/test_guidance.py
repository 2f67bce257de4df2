"""Landing guidance on scripted relative trajectories, against hand-worked timings."""

import math

import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland_symbolic.landing.guidance import (
    ALIGN,
    APPROACH,
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    LANDED,
    TOUCHDOWN,
    guidance_function,
)

P = GUIDANCE_P
DT = 0.002
GUIDANCE = guidance_function()


def _xg(committed=0, **state):
    """A guidance state; the quiescence averages at zero (a deck at rest so far)."""
    return GUIDANCE_STATE.pack(dict(state, committed=committed, armed=0.0, ms_rise=0.0,
                                    ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                    lean_x=0.0, lean_y=0.0, lean_gust=0.0))


def _run(script, n, xg=None, p=P):
    """Step the guidance n times; script(k, z_ref) -> (p_e, v_e, deck_rise[, gear_gap[,
    marker_age]]).

    Without a gear gap the gear is well above the deck (1 m); the touchdown cue is the
    gap at or below zero, as on perfect sensing. Without a marker age the marker is seen
    (0 s)."""
    xg = _xg(phase=APPROACH, timer=0.0, z_ref=p["hover_height"], aborts=0) \
        if xg is None else xg
    pg = GUIDANCE_PARAMS.pack(p)
    rows = []
    for k in range(n):
        z_ref = GUIDANCE_STATE.unpack(xg)["z_ref"][0]
        p_e, v_e, rise, *more = script(k, z_ref)
        gap, age = (more + [1.0, 0.0][len(more):])
        cues = GUIDANCE_CUES.pack(dict(touchdown=float(gap <= 0), marker_age=age,
                                       contact_switch=0.0))
        xg_next, ref = (np.asarray(v, dtype=float).ravel()
                        for v in GUIDANCE(xg, p_e, v_e, rise, 0.0, cues, DT, pg))
        rows.append((xg, ref))
        xg = xg_next
    return rows, xg


def _on_track(k, z_ref):
    """A quadrotor that tracks the reference exactly, over the pad."""
    return [0.0, 0.0, z_ref], [0.0, 0.0, 0.0], 0.0


def test_approach_ends_within_the_align_radius():
    def script(k, z_ref):              # flies in along x at 1 m/s from 5 m out
        return [-5.0 + k * DT, 0.0, 3.0], [1.0, 0.0, 0.0], 0.0
    rows, _ = _run(script, 3000)
    phases = [GUIDANCE_STATE.unpack(xg)["phase"][0] for xg, _ in rows]
    k = phases.index(ALIGN)
    # within 0.5 m of the hover point: -5 + k dt >= -0.5 at the step before
    assert math.isclose((k - 1) * DT, 4.5, abs_tol=DT)
    ref = rows[0][1]
    np.testing.assert_allclose(ref[0:3], [0, 0, 3.0])   # the hover point
    np.testing.assert_allclose(ref[3:9], 0)


def test_align_dwells_then_descends_and_a_break_restarts_the_dwell():
    xg = _xg(phase=ALIGN, timer=0.0, z_ref=3.0, aborts=0)

    def script(k, z_ref):              # drifts out of the half-limit band for 10 steps
        off = 0.15 if 200 <= k < 210 else 0.05
        return [off, 0.0, 3.0], [0.0, 0.0, 0.0], 0.0
    rows, _ = _run(script, 1000, xg)
    phases = [GUIDANCE_STATE.unpack(x)["phase"][0] for x, _ in rows]
    k = phases.index(DESCEND)
    # the timer restarts after the break (step 209) and needs 1 s = 500 steps
    assert k == 210 + 500


def test_descent_profile_against_its_closed_form():
    """Rate min(max(h / T, v_td), v_max): linear at 0.7 m/s down to h = 0.7 m, then
    exponential h = 0.7 exp(-(t - t1) / T) down to h = 0.3 m, then the 0.3 m/s crawl."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=3.0, aborts=0)
    rows, _ = _run(_on_track, 3000, xg)
    t = DT * np.arange(len(rows))
    z = np.array([GUIDANCE_STATE.unpack(x)["z_ref"][0] for x, _ in rows])
    h0, T, vmax, vtd = 3.0 - 0.2, 1.0, 0.7, 0.3
    t1 = (h0 - vmax * T) / vmax                     # linear part ends at h = v_max T
    t2 = t1 + T * math.log(vmax / vtd)              # exponential part ends at h = v_td T
    h = np.where(t <= t1, h0 - vmax * t,
                 np.where(t <= t2, vmax * T * np.exp(-(t - t1) / T),
                          vtd * T - vtd * (t - t2)))
    np.testing.assert_allclose(z - 0.2, h, atol=3 * DT)    # Euler of the rate: O(dt)
    # the reference's rate and acceleration are the profile's
    vz = np.array([ref[5] for _, ref in rows])
    az = np.array([ref[8] for _, ref in rows])
    mid = (t > t1 + 0.05) & (t < t2 - 0.05)
    np.testing.assert_allclose(vz[mid], -(z[mid] - 0.2) / T, rtol=1e-12)
    np.testing.assert_allclose(az[mid], (z[mid] - 0.2) / T ** 2, rtol=1e-12)
    assert np.all(az[t < t1 - 0.05] == 0) and np.all(az[t > t2 + 0.05] == 0)
    assert z[-1] < 0.2 - 0.3                             # crawls on below contact height


@pytest.mark.parametrize("cause", ["offset", "speed"])
def test_the_descent_pauses_out_of_the_align_band_and_goes_on_within_it(cause):
    """From 2 m (h = 1.8 m, the linear part at 0.7 m/s: 1.4 mm a 2 ms step), steps 100-199
    out of the align band but within the abort's limits (offset 0.15 m, half the limit
    0.1; speed 0.3 m/s, half 0.25): the reference holds at its height with no climb, no
    abort, a zero rate; back in the band it falls at 0.7 m/s again."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=2.0, aborts=0)

    def script(k, z_ref):
        out = 100 <= k < 200
        return ([0.15 if out and cause == "offset" else 0.0, 0.0, z_ref],
                [0.3 if out and cause == "speed" else 0.0, 0.0, 0.0], 0.0)
    rows, _ = _run(script, 300, xg)
    st = [GUIDANCE_STATE.unpack(x) for x, _ in rows]
    z = np.array([s["z_ref"][0] for s in st])
    assert all(s["phase"][0] == DESCEND and s["aborts"][0] == 0 for s in st)
    step = 0.7 * DT
    np.testing.assert_allclose(z[:101], 2.0 - step * np.arange(101), atol=1e-12)
    assert np.all(z[101:201] == z[100])                  # paused at 2 - 100 steps
    np.testing.assert_allclose(z[201:], z[100] - step * np.arange(1, 100), atol=1e-12)
    vz = np.array([ref[5] for _, ref in rows])
    assert np.all(vz[100:200] == 0) and np.all(vz[:100] == -0.7) and np.all(vz[200:] == -0.7)


def test_the_crawl_is_committed_out_of_the_align_band():
    """Below h = touchdown_speed x descent_time = 0.3 m the descent does not pause: from
    z_ref = 0.4 m (h = 0.2 m) with the offset at 0.15 m, out of the band, it crawls on at
    0.3 m/s (0.6 mm a step), never hovering over the deck."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=0.4, aborts=0)
    rows, _ = _run(lambda k, z: ([0.15, 0.0, z], [0.0, 0.0, 0.0], 0.0), 50, xg)
    z = np.array([GUIDANCE_STATE.unpack(x)["z_ref"][0] for x, _ in rows])
    np.testing.assert_allclose(z, 0.4 - 0.3 * DT * np.arange(50), atol=1e-12)


@pytest.mark.parametrize("cause", ["offset", "speed"])
def test_above_the_crawl_a_touchdown_limit_exceeded_pauses_and_does_not_abort(cause):
    """At 2 m (h = 1.8 m, above the crawl's 0.3 m) an offset of 0.25 m or a speed of 0.6
    m/s, past the touchdown limits (0.2 m, 0.5 m/s), for one step: the reference holds its
    height for that step, no abort, and falls again after it."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=2.0, aborts=0)

    def script(k, z_ref):
        bad = k == 100
        return ([0.25 if bad and cause == "offset" else 0.0, 0.0, z_ref],
                [0.6 if bad and cause == "speed" else 0.0, 0.0, 0.0], 0.0)
    rows, last = _run(script, 102, xg)
    z = [GUIDANCE_STATE.unpack(x)["z_ref"][0] for x, _ in rows] + [
        GUIDANCE_STATE.unpack(last)["z_ref"][0]]
    assert all(GUIDANCE_STATE.unpack(x)["phase"][0] == DESCEND for x, _ in rows)
    assert GUIDANCE_STATE.unpack(last)["aborts"][0] == 0
    assert z[101] == z[100] and z[102] == pytest.approx(z[101] - 0.7 * DT, abs=1e-12)


@pytest.mark.parametrize("cause", ["offset", "speed"])
def test_abort_climbs_back_to_hover_and_counts(cause):
    """In the committed crawl (from z_ref = 0.4 m, h = 0.2 m) a touchdown limit exceeded
    aborts (a rising deck aborts only a committed final descent: tests/test_quiescence.py
    and test_a_moving_deck_aborts_only_the_committed_descent below)."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=0.4, aborts=0)

    def script(k, z_ref):
        bad = k == 100
        p_e = [0.25 if bad and cause == "offset" else 0.0, 0.0, z_ref]
        v_e = [0.6 if bad and cause == "speed" else 0.0, 0.0, 0.0]
        return p_e, v_e, 0.0
    rows, _ = _run(script, 102, xg)
    after = GUIDANCE_STATE.unpack(rows[101][0])
    assert after["phase"][0] == ALIGN and after["aborts"][0] == 1
    assert after["z_ref"][0] == 3.0                       # back to the hover height
    before = GUIDANCE_STATE.unpack(rows[100][0])
    assert before["phase"][0] == DESCEND and before["z_ref"][0] < 0.4


def test_a_moving_deck_aborts_only_the_committed_descent():
    """Above the wait height (touchdown_height + commit_height = 1.2 m) the descent is not
    committed: a deck rising at 1 m/s aborts nothing and the reference falls on (the
    committed case is tests/test_quiescence.py's)."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=2.0, aborts=0)
    rows, last = _run(lambda k, z_ref: ([0.0, 0.0, z_ref], [0.0, 0.0, 0.0], 1.0), 200, xg)
    g = GUIDANCE_STATE.unpack(last)
    assert g["phase"][0] == DESCEND and g["aborts"][0] == 0 and g["committed"][0] == 0
    assert g["z_ref"][0] == pytest.approx(2.0 - 0.7 * 200 * DT, rel=1e-12)


@pytest.mark.parametrize("cause", ["offset", "speed", "deck"])
def test_contact_is_touchdown_not_abort(cause):
    """The gear meets the deck while an abort criterion holds: the contact wins."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=0.1, aborts=0)

    def script(k, z_ref):
        bad = k == 3
        p_e = [0.25 if bad and cause == "offset" else 0.0, 0.0, 0.2]
        v_e = [0.6 if bad and cause == "speed" else 0.0, 0.0, -0.3]
        return p_e, v_e, 1.0 if bad and cause == "deck" else 0.0, 0.0 if bad else 0.01
    rows, _ = _run(script, 5, xg)
    phases = [GUIDANCE_STATE.unpack(x)["phase"][0] for x, _ in rows]
    assert phases == [DESCEND] * 4 + [TOUCHDOWN]
    after = GUIDANCE_STATE.unpack(rows[4][0])
    assert after["phase"][0] == TOUCHDOWN and after["aborts"][0] == 0 and after["timer"][0] == 0
    before = GUIDANCE_STATE.unpack(rows[3][0])
    assert after["z_ref"][0] == before["z_ref"][0]          # the reference holds


def test_descent_touches_down_when_the_gap_closes_then_lands_after_settling():
    """The gap closes at step 40; touchdown, then landed settle_time (50 steps) later."""
    xg = _xg(phase=DESCEND, timer=0.0, z_ref=0.5, aborts=0)
    rows, last = _run(lambda k, z: ([0.0, 0.0, z], [0.0, 0.0, -0.3], 0.0,
                                    0.3 - k * DT * 0.3 if k < 40 else -1e-9), 120, xg)
    phases = np.array([GUIDANCE_STATE.unpack(x)["phase"][0] for x, _ in rows])
    assert np.all(phases[:41] == DESCEND) and phases[41] == TOUCHDOWN
    k_landed = int(np.argmax(phases == LANDED))
    assert k_landed == 41 + 50                         # settle_time 0.1 s at 2 ms
    np.testing.assert_array_equal(rows[k_landed][1][3:9], 0)  # the reference is at rest
    # the touchdown policy off (fly_on = 0): its commands are inert throughout
    commands = np.array([ref[9:] for _, ref in rows])
    np.testing.assert_array_equal(commands, [[math.pi / 2, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0,
                                              math.pi / 2]]
                                  * len(rows))
    z = [GUIDANCE_STATE.unpack(x)["z_ref"][0] for x, _ in rows[41:]]
    assert len(set(z)) == 1


def test_landed_is_held():
    xg = _xg(phase=LANDED, timer=0.3, z_ref=0.1, aborts=2)
    rows, last = _run(lambda k, z: ([1.0, 1.0, 5.0], [3.0, 0, 0], 2.0, -1.0), 10, xg)
    np.testing.assert_array_equal(last, xg)


def test_align_waits_for_the_marker_and_climbs_to_search_for_it():
    """Unseen for 0.6 s > marker_timeout: no dwell, the hover point climbs at descent_speed
    (0.7 m/s: 1.4 mm per 2 ms step) to search_height; seen again from step 2000, it
    dwells 1 s and descends, the hover point gliding back down meanwhile."""
    xg = _xg(phase=ALIGN, timer=0.0, z_ref=3.0, aborts=0)
    step = 0.7 * DT
    k_seen = 2000

    def script(k, z_ref):              # over the pad, still; the marker lost, then found
        age = 0.6 + k * DT if k < k_seen else 0.0
        return [0.0, 0.0, z_ref], [0.0, 0.0, 0.0], 0.0, 1.0, age
    rows, _ = _run(script, k_seen + 600, xg)
    st = [GUIDANCE_STATE.unpack(x) for x, _ in rows]
    z = np.array([s["z_ref"][0] for s in st])
    phases = np.array([s["phase"][0] for s in st])
    timer = np.array([s["timer"][0] for s in st])
    assert np.all(phases[:k_seen + 1] == ALIGN) and np.all(timer[:k_seen + 1] == 0)
    # the climb: 3 m -> 6 m in ceil(3 / 1.4 mm) = 2143 steps would pass k_seen: it is
    # still climbing at k_seen, z_ref = 3 + k step
    np.testing.assert_allclose(z[:k_seen + 1], 3.0 + np.arange(k_seen + 1) * step, atol=1e-9)
    # seen: it glides back down, one step a tick, and the dwell counts
    np.testing.assert_allclose(z[k_seen + 1:k_seen + 500] - z[k_seen:k_seen + 499], -step,
                               atol=1e-9)
    assert timer[k_seen + 1] == pytest.approx(DT)
    k_descend = int(np.argmax(phases == DESCEND))
    assert k_descend == k_seen + 500               # dwell_time 1 s = 500 steps


def test_the_climb_stops_at_the_search_height():
    xg = _xg(phase=ALIGN, timer=0.0, z_ref=5.99, aborts=0)
    rows, last = _run(lambda k, z: ([0.0, 0.0, z], [0.0, 0.0, 0.0], 0.0, 1.0, 10.0), 20, xg)
    assert GUIDANCE_STATE.unpack(last)["z_ref"][0] == 6.0
    assert GUIDANCE_STATE.unpack(last)["phase"][0] == ALIGN


def test_perfect_cues_are_the_measured_gear_gap():
    """measured_cues: touchdown where deck_gear_gap <= 0 (its hand formula
    z_e - h n2 . b3), the marker always seen."""
    from quadland_symbolic.kinematics import rotation
    from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, measured_cues_function

    fn = measured_cues_function()
    pg = GUIDANCE_PARAMS.pack(P)
    eta1, eta2 = np.array([0.1, -0.05, 0.3]), np.array([0.02, 0.04, 1.0])
    n2b3 = float(np.asarray(rotation(eta2))[:, 2] @ np.asarray(rotation(eta1))[:, 2])
    for dz in (-1e-6, 0.0, 1e-6):
        z_e = 0.2 * n2b3 + dz
        y = LANDING_MEASUREMENT.pack(dict(p_e=[0.1, 0.0, z_e], v_e=[0, 0, -0.3], eta1=eta1,
                                          Omega1=np.zeros(3), eta2=eta2, v2E=np.zeros(3),
                                          a2E=np.zeros(3), w2E=np.zeros(3),
                                          w2E_dot=np.zeros(3)))
        cues = GUIDANCE_CUES.unpack(np.asarray(fn(y, pg), dtype=float).ravel())
        assert cues["touchdown"][0] == (1.0 if dz < 0 else float(z_e - 0.2 * n2b3 <= 0))
        assert cues["marker_age"][0] == 0.0


def test_the_approach_holds_its_height_until_the_marker_is_seen():
    """Started 2 m above the hover height without the marker, the approach flies level
    (z_ref held); seen from step 100, the hover point glides down at descent_speed, and the
    approach ends within align_radius of [0, 0, z_ref] (not of the hover height)."""
    xg = _xg(phase=APPROACH, timer=0.0, z_ref=5.0, aborts=0)

    def script(k, z_ref):              # at the hover point's height, 1 m out
        return [-1.0 + k * 1e-3, 0.0, z_ref], [0.5, 0.0, 0.0], 0.0, 1.0, \
            (10.0 if k < 100 else 0.0)
    rows, _ = _run(script, 600, xg)
    st = [GUIDANCE_STATE.unpack(x) for x, _ in rows]
    z = np.array([s["z_ref"][0] for s in st])
    assert np.all(z[:101] == 5.0)
    np.testing.assert_allclose(z[101:500] - z[100:499], -0.7 * DT, atol=1e-12)
    # |-1 + k 1e-3| <= 0.5 first at step k = 500 (z_ref still 4.44 m there: 1.4 m above
    # the hover height, so a distance to [0, 0, hover_height] would not end it)
    phases = [s["phase"][0] for s in st]
    assert phases.index(ALIGN) == 501 and z[500] > 4.4

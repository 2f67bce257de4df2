"""The crawl's gate slowed below its floor (issue 19, ``landing.crawl_gate_slow``).

docs/landing.md, "The crawl's gate slowed below its floor". At or below
``crawl_gate_floor`` the gate no longer pauses the crawl; with ``crawl_gate_slow`` the
crawl's reference then falls at most that fast while the gate's prediction ``|p_h + v_h
t_go|`` lies outside ``crawl_gate`` (its wait and quiescent-deck conditions as for the
pause), at the profile's rate otherwise; 1000 (the default) is the crawl of before. Checked
against reference heights and rates worked by hand (one step, and a piecewise-linear fall
over many), the generated C step against the CasADi function, and the shipped scenarios'
values.
"""

import ctypes

import numpy as np
import pytest
from reference import GUIDANCE_P, have_compiler

from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
    guidance_function,
)
from quadland_symbolic.landing.loop import landing_loop_params

DT = 0.01
HC = 0.2          # m: the gear below the centre, the contact height on the level gear
H = 0.1           # m above the contact height: in the crawl (0.3 m/s x 1 s = 0.3 m)
GATE = dict(crawl_gate=0.05, crawl_gate_floor=0.11)   # H is below the floor
F = guidance_function()


def _state(h, timer=0.0):
    return GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=timer, z_ref=HC + h, aborts=0,
                                    committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                    ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                    lean_gust=0.0))


def _step(x, vx, h=H, timer=0.0, rise=0.0, **keys):
    """One committed crawl step from ``h`` above the contact height, the quadrotor on the
    reference ``x`` m ahead of the pad moving at ``vx`` m/s along x: the reference height
    after it, the step's reference rate ``vz_ref``, the phase and the timer after it."""
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC, **keys))
    xg_next, ref = (np.asarray(v, dtype=float).ravel() for v in F(
        _state(h, timer), [x, 0.0, HC + h], [vx, 0.0, 0.0], rise, 0.0, cues, DT, pg))
    g = GUIDANCE_STATE.unpack(xg_next)
    return (g["z_ref"][0], POSITION_REFERENCE.unpack(ref)["v_ref"][2], g["phase"][0],
            g["timer"][0])


def _fell(rate, h=H):
    """A step's fall at ``rate`` m/s from ``h``: (z_ref after, vz_ref)."""
    return (pytest.approx(HC + h - rate * DT, abs=1e-12), pytest.approx(-rate, abs=1e-12))


def test_below_the_floor_the_gate_slows_the_crawl_on_the_predicted_offset():
    """``t_go = 0.1 / 0.3 = 1/3`` s. 3 cm ahead moving away at 0.09 m/s: predicted 0.06 m,
    past the 0.05 m gate; below the 0.11 m floor the pause is off, and with
    ``crawl_gate_slow`` 0.1 m/s the reference falls one step of 0.1 m/s (vz_ref -0.1)
    instead of 0.3; moving back (predicted 0) or at rest (0.03 m) it falls at 0.3 m/s. The
    slowing is no pause: the timer, the gate's count of its holds, stays where it was."""
    z, vz, phase, timer = _step(0.03, 0.09, timer=0.2, crawl_gate_slow=0.1,
                                crawl_gate_wait=0.5, **GATE)
    assert (z, vz) == _fell(0.1) and phase == DESCEND
    assert timer == pytest.approx(0.2, abs=1e-12)
    assert _step(0.03, -0.09, crawl_gate_slow=0.1, **GATE)[:2] == _fell(0.3)
    assert _step(0.03, 0.0, crawl_gate_slow=0.1, **GATE)[:2] == _fell(0.3)
    # the estimate alone inside the gate would pass: it is the prediction that slows
    assert _step(0.06, 0.0, crawl_gate_slow=0.1, **GATE)[:2] == _fell(0.1)


def test_above_the_floor_the_gate_still_pauses_and_the_default_is_the_crawl_of_before():
    """Floor 0.09 m (H above it): the 0.06 m prediction holds the reference at its height
    (vz_ref 0), whatever ``crawl_gate_slow``. Below the floor with the default (1000 m/s)
    or a cap at or over the crawl's 0.3 m/s (0.3, 0.5) it falls at 0.3 m/s, as before the
    key; ``crawl_gate_slow`` 0 stops it (a pause with no count)."""
    for slow in (0.1, 1e3):
        z, vz, _, _ = _step(0.03, 0.09, crawl_gate=0.05, crawl_gate_floor=0.09,
                            crawl_gate_slow=slow)
        assert (z, vz) == (pytest.approx(HC + H, abs=1e-12), pytest.approx(0.0, abs=1e-12))
    for slow in (0.3, 0.5, 1e3):
        assert _step(0.03, 0.09, crawl_gate_slow=slow, **GATE)[:2] == _fell(0.3)
    assert _step(0.03, 0.09, crawl_gate_slow=0.0, **GATE)[:2] == _fell(0.0)


def test_the_slowing_keeps_the_gate_s_other_conditions():
    """No gate (``crawl_gate`` 0), its wait spent (timer 0.5 s = ``crawl_gate_wait``) or the
    deck past ``crawl_gate_rise`` (0.25 > 0.2 m/s up, max_deck_rise 0.8: no withdrawal):
    the 0.06 m prediction no longer slows the crawl; within them it does."""
    slow = dict(crawl_gate_slow=0.1, crawl_gate_floor=0.11)
    assert _step(0.03, 0.09, crawl_gate=0.0, **slow)[:2] == _fell(0.3)
    assert _step(0.03, 0.09, timer=0.5, crawl_gate=0.05, crawl_gate_wait=0.5,
                 **slow)[:2] == _fell(0.3)
    assert _step(0.03, 0.09, timer=0.49, crawl_gate=0.05, crawl_gate_wait=0.5,
                 **slow)[:2] == _fell(0.1)
    assert _step(0.03, 0.09, rise=0.25, crawl_gate=0.05, crawl_gate_rise=0.2,
                 **slow)[:2] == _fell(0.3)
    assert _step(0.03, 0.09, rise=0.15, crawl_gate=0.05, crawl_gate_rise=0.2,
                 **slow)[:2] == _fell(0.1)


def test_above_the_crawl_the_profile_is_not_capped():
    """0.6 m above the contact height is above the crawl (0.3 m/s x 1 s): the profile's
    rate is h / descent_time = 0.6 m/s, in the align band (0.06 m, 0.09 m/s). A floor of
    1000 m would put it below the floor, but the slowing is the crawl's alone: it falls
    one step of 0.6 m/s and its acceleration reference is the profile's 0.6 / 1 m/s^2."""
    z, vz, _, _ = _step(0.03, 0.09, h=0.6, crawl_gate=0.05, crawl_gate_floor=1e3,
                        crawl_gate_slow=0.1)
    assert (z, vz) == _fell(0.6, h=0.6)


def _crawl(n, n_in, slow):
    """The reference heights of ``n`` crawl steps from H with the gate 0.05 m, floor 0.11 m:
    the quadrotor 6 cm off the pad at rest (outside) for the first ``n_in`` steps, 2 cm off
    (inside) after, always on the reference's height (no leash, no contact)."""
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC, crawl_gate_slow=slow,
                                   **GATE))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    xg, out = _state(H), []
    for k in range(n):
        z = GUIDANCE_STATE.unpack(xg)["z_ref"][0]
        x = 0.06 if k < n_in else 0.02
        xg, _ = (np.asarray(v, dtype=float).ravel() for v in F(
            xg, [x, 0.0, z], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
        out.append(GUIDANCE_STATE.unpack(xg)["z_ref"][0])
    return np.array(out)


def test_a_slowed_crawl_is_piecewise_linear_to_the_contact_height_and_past_it():
    """40 steps outside at 0.1 m/s, then inside at 0.3 m/s: after step k the reference
    stands at HC + H - 0.1 min(k, 40) dt - 0.3 max(k - 40, 0) dt, worked by hand; it
    passes the contact height (the crawl goes on below it until contact) at step 40 +
    (0.1 - 0.04) / 0.003 = 60. The default falls at 0.3 m/s throughout."""
    k = np.arange(1, 81)
    z = _crawl(80, 40, 0.1)
    hand = HC + H - 0.1 * np.minimum(k, 40) * DT - 0.3 * np.maximum(k - 40, 0) * DT
    np.testing.assert_allclose(z, hand, rtol=0, atol=1e-12)
    assert z[59] == pytest.approx(HC, abs=1e-12)
    np.testing.assert_allclose(_crawl(80, 40, 1e3), HC + H - 0.3 * k * DT, rtol=0, atol=1e-12)


def _gate_slow(name):
    sc = load_scenario(name)
    v = landing_values(sc)
    p_guid = landing_loop_params(v.l).unpack(np.asarray(v.pc, dtype=float).ravel())["p_guid"]
    return sc["landing.crawl_gate_slow"], GUIDANCE_PARAMS.unpack(
        np.asarray(p_guid, dtype=float).ravel())["crawl_gate_slow"][0]


@pytest.mark.parametrize("name", ["turning", "ship", "ship_ss5", "highway_100"])
def test_the_other_shipped_scenarios_do_not_slow_the_crawl(name):
    """No other shipped file sets the key: the schema's default, 1000 m/s, reaches the
    flight's parameters."""
    assert _gate_slow(name) == (1e3, 1e3)


@pytest.mark.slow
@pytest.mark.skipif(not have_compiler(), reason="no C compiler")
@pytest.mark.parametrize("precision", ["double", "float"])
def test_the_c_step_slows_as_casadi(precision):
    """The generated guidance step against the CasADi function on committed crawl steps
    below a drawn floor with the key drawn in [0, 0.3] m/s: the phase and abort count the
    same, the reference height and the reference within the precision's rounding, and the
    key decides (slows) at least 50 of the 400 steps."""
    from quadland.kinds.landing.flight import load_landing_api
    from quadland_symbolic.landing.controller import (
        LANDING_MEASUREMENT,
        landing_guidance_function,
    )
    f = landing_guidance_function()
    api = load_landing_api(10, precision)
    d = np.float64 if precision == "double" else np.float32
    y, cues, gp, gs, ref = (api.LandingMeasurement(), api.GuidanceCues(), api.GuidanceParams(),
                            api.GuidanceState(), api.PositionReference())
    view = [np.frombuffer((ctypes.c_char * ctypes.sizeof(s)).from_buffer(s), dtype=d)
            for s in (y, cues, gp, ref)]
    vg = np.frombuffer((ctypes.c_char * ctypes.sizeof(gs)).from_buffer(gs), dtype=d, count=11)
    real_state = [1, 2, 4, 5, 6, 7, 8, 9, 10, 11, 12]
    rng = np.random.default_rng([17, precision == "float"])
    tol = 1e-12 if precision == "double" else 1e-6
    slowed = 0
    for _ in range(400):
        p = dict(GUIDANCE_P, crawl_gate=rng.uniform(0.01, 0.12),
                 crawl_gate_floor=rng.uniform(0.0, 0.3), crawl_gate_time=0.3,
                 crawl_gate_slow=rng.uniform(0.0, 0.3))
        xg = _state(rng.uniform(-0.02, 0.3), timer=rng.uniform(0, 0.5))
        ym = LANDING_MEASUREMENT.unpack(np.zeros(LANDING_MEASUREMENT.size))
        ym = {k: np.array(v, dtype=float).ravel() for k, v in ym.items()}
        ym["p_e"] = np.r_[rng.uniform(-0.12, 0.12, 2), HC + rng.uniform(-0.02, 0.25)]
        ym["v_e"] = np.r_[rng.uniform(-0.3, 0.3, 2), -0.3]
        pg = GUIDANCE_PARAMS.pack(dict(p, touchdown_height=HC))
        xg, yy, pg = (np.asarray(v, dtype=d).astype(float)
                      for v in (xg, LANDING_MEASUREMENT.pack(ym), pg))
        dt = float(d(0.004))
        view[0][:], view[1][:], view[2][:], vg[:] = yy, np.zeros(3), pg, xg[real_state]
        gs.phase, gs.aborts = int(xg[0]), int(xg[3])
        assert api.lib.ql_guidance_step(ctypes.byref(y), ctypes.byref(cues), ctypes.byref(gp),
                                        d(dt), ctypes.byref(gs), ctypes.byref(ref)) == 0
        xn, r = (np.asarray(v, dtype=float).ravel() for v in f(xg, yy, np.zeros(3), dt, pg))
        assert (gs.phase, gs.aborts) == (xn[0], xn[3])
        assert float(vg[1]) == pytest.approx(xn[2], abs=tol)
        np.testing.assert_allclose(view[3].astype(float), r, rtol=tol, atol=tol)
        p0 = GUIDANCE_PARAMS.pack(dict(GUIDANCE_PARAMS.unpack(pg), crawl_gate_slow=1e3))
        x0 = np.asarray(f(xg, yy, np.zeros(3), dt, p0)[0], dtype=float).ravel()
        slowed += x0[2] < xn[2] - 1e-9
    assert slowed >= 50

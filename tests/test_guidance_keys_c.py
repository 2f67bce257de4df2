"""The generated guidance step (double and float C) against its CasADi function with the
fifteenth session's keys on: ``abort_floor`` (symbolic/landing/abort_floor.py) and
``crawl_gate_rise`` (symbolic/landing/crawl_gate.py), and the eighteenth's
``crawl_abort_offset`` (the same module's ``fmin``; review) with the twentieth's
``crawl_abort_budget`` (the steps it decides, and those at a count one below it where the
tighter offset still fires, are counted; review). ``tests/test_fuzz_landing_step.py`` draws
the guidance's parameters around ``ql_guidance_params_init``'s defaults, where the floor
never holds and the gate is off; here the draws sit in the committed crawl with the gate on,
the gear within centimetres of the deck and the offset or speed past the limits, so that the
keys decide steps. The phase, the abort count and the commit must be the CasADi function's
in both precisions; the reference within the precision's rounding."""

import ctypes

import numpy as np
import pytest
from reference import GUIDANCE_P, have_compiler

from quadland.kinds.landing.flight import load_landing_api
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, landing_guidance_function
from quadland_symbolic.landing.guidance import DESCEND, GUIDANCE_PARAMS, GUIDANCE_STATE

pytestmark = [pytest.mark.skipif(not have_compiler(), reason="no C compiler"), pytest.mark.slow]

N = 600
#: the float state's members after the two ints: the CasADi state but phase (0) and aborts (3)
REAL_STATE = [1, 2, 4, 5, 6, 7, 8, 9, 10, 11, 12]


def _view(struct, dtype, count=None):
    n = ctypes.sizeof(struct) // np.dtype(dtype).itemsize if count is None else count
    return np.frombuffer((ctypes.c_char * ctypes.sizeof(struct)).from_buffer(struct),
                         dtype=dtype, count=n)


def _draws(rng, keys_on):
    """``N`` committed crawl steps: (xg, y, cues, dt, p_guid) each."""
    out = []
    for _ in range(N):
        p = dict(GUIDANCE_P, crawl_gate=rng.uniform(0.01, 0.12),
                 crawl_pause=float(rng.integers(2)))
        if keys_on:
            p.update(abort_floor=rng.choice([0.06, rng.uniform(-0.05, 0.2)]),
                     crawl_gate_rise=rng.choice([0.35, rng.uniform(0.0, 1.0)]),
                     crawl_abort_offset=rng.choice([0.1, rng.uniform(0.03, 0.3)]),
                     crawl_abort_budget=rng.choice([1e6, float(rng.integers(4))]))
        contact = p["touchdown_height"]
        xg = GUIDANCE_STATE.pack(dict(
            phase=DESCEND, timer=rng.uniform(0, 0.5), z_ref=contact + rng.uniform(0, 0.3),
            aborts=float(rng.integers(3)), committed=1.0, armed=0.0, ms_rise=0.0,
            ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
            lean_gust=0.0))
        y = LANDING_MEASUREMENT.unpack(np.zeros(LANDING_MEASUREMENT.size))
        y = {k: np.array(v, dtype=float).ravel() for k, v in y.items()}
        y["p_e"] = np.r_[rng.uniform(-0.12, 0.12, 2), contact + rng.uniform(-0.02, 0.25)]
        y["v_e"] = np.r_[rng.uniform(-0.3, 0.3, 2), -0.3]
        if rng.uniform() < 0.3:
            y["p_e"][0] = rng.uniform(0.15, 0.3)          # past max_offset 0.2
        if rng.uniform() < 0.3:
            y["v_e"][1] = rng.uniform(0.4, 0.7)           # past max_relative_speed 0.5
        y["v2E"] = np.r_[0.0, 0.0, rng.uniform(-1.0, 1.0)]  # the deck's rise
        out.append((xg, LANDING_MEASUREMENT.pack(y), np.zeros(3), 0.004,
                    GUIDANCE_PARAMS.pack(p)))
    return out


@pytest.mark.parametrize("precision", ["double", "float"])
def test_the_c_step_decides_as_casadi_with_the_floor_and_the_quiescent_gate(precision):
    f = landing_guidance_function()
    api = load_landing_api(10, precision)
    d = np.float64 if precision == "double" else np.float32
    y, cues, gp, gs, ref = (api.LandingMeasurement(), api.GuidanceCues(), api.GuidanceParams(),
                            api.GuidanceState(), api.PositionReference())
    vy, vc, vgp, vref = _view(y, d), _view(cues, d), _view(gp, d), _view(ref, d)
    vg = _view(gs, d, len(REAL_STATE))
    rng = np.random.default_rng([15, precision == "float"])
    decided = []
    for keys_on in (False, True):
        for xg, yy, cu, dt, p in _draws(rng, keys_on):
            xg, yy, p = (np.asarray(v, dtype=d).astype(float) for v in (xg, yy, p))
            dt = float(d(dt))
            vy[:], vc[:], vgp[:], vg[:] = yy, cu, p, xg[REAL_STATE]
            gs.phase, gs.aborts = int(xg[0]), int(xg[3])
            assert api.lib.ql_guidance_step(ctypes.byref(y), ctypes.byref(cues),
                                            ctypes.byref(gp), d(dt), ctypes.byref(gs),
                                            ctypes.byref(ref)) == 0
            xn, r = (np.asarray(v, dtype=float).ravel() for v in f(xg, yy, cu, dt, p))
            assert (gs.phase, gs.aborts, float(vg[2])) == (xn[0], xn[3], xn[4])
            tol = 1e-12 if precision == "double" else 1e-6
            np.testing.assert_allclose(vref.astype(float), r, rtol=tol, atol=tol)
            # the same step with the keys at their defaults, all or one: did a key decide it?
            p0 = GUIDANCE_PARAMS.unpack(p)
            x0, x1, x2, x3 = (np.asarray(f(xg, yy, cu, dt,
                                           GUIDANCE_PARAMS.pack(dict(p0, **k)))[0],
                                         dtype=float).ravel()
                              for k in (dict(abort_floor=-1e3, crawl_gate_rise=1e3,
                                             crawl_abort_offset=1e3, crawl_abort_budget=1e6),
                                        dict(crawl_abort_offset=1e3), dict(abort_floor=-1e3),
                                        dict(crawl_abort_budget=1e6)))
            # the budget's edge: the tighter offset fired with the count one below the budget
            edge = p0["crawl_abort_budget"][0] == xg[3] + 1 and xn[3] > x1[3]
            decided.append((keys_on, xn[3] != x0[3], xn[2] != x0[2], xn[3] > x1[3],
                            xn[3] < x2[3], xn[3] < x3[3], edge))
    decided = np.array(decided)
    on = decided[:, 0] > 0
    assert not decided[~on, 1:].any()                 # off: the keys decide nothing
    assert decided[on, 4].sum() >= 20                 # the floor held aborts
    assert (decided[on, 2] & ~decided[on, 1]).sum() >= 20   # the gate's rise moved z_ref
    assert decided[on, 3].sum() >= 20                 # the tighter offset started aborts
    assert decided[on, 5].sum() >= 10                 # the spent budget stopped some (review)
    assert decided[on, 6].sum() >= 5                  # and at count = budget - 1 it held

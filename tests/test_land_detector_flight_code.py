"""The land detector's generated C (``quadland_land_detector.h``) against its CasADi
functions and its documented contract (docs/codegen.md, "The land detector's API").

The double build's ``ql_land_detector_step`` equals ``land_detector_function()``
evaluated by CasADi bit for bit, and ``ql_land_detector_form_cues`` equals
``detector_cues_function()``: the C is CasADi's own code of the same expression
graphs, compiled without contraction into fused multiply-adds (``-std=c99``). The
stages' timing is checked against the windows counted by hand (docs/land_detector.md,
"The stages"), the cues against a level deck worked out by hand.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
from land_detector_c import Call, load, view
from reference import have_compiler

from quadland_symbolic.codegen import STATUS_CODES
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.guidance import DESCEND, GUIDANCE_PARAMS, GUIDANCE_STATE
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_CUES,
    LAND_DETECTOR_DEFAULTS,
    LAND_DETECTOR_FLAGS,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    land_detector_function,
)
from quadland_symbolic.landing.navigation import IMU, RANGE
from quadland_symbolic.landing.sensed_loop import detector_cues_function
from quadland_symbolic.parameters import QUADROTOR

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

STATUS = {name: value for name, value, _ in STATUS_CODES}
DT = 0.004
STAGES = [LAND_DETECTOR_FLAGS.index(n) for n in ("ground_contact", "maybe_landed", "landed")]

#: The documented ranges (docs/codegen.md), written out here, in struct order.
DOCUMENTED = {
    "gap_max": lambda v: v >= 0, "vz_max": lambda v: v >= 0, "thrust_low": lambda v: v >= 0,
    "contact_time": lambda v: v >= 0, "maybe_time": lambda v: v >= 0,
    "landed_time": lambda v: v >= 0, "hold_factor": lambda v: v >= 1,
    "no_range_factor": lambda v: v >= 1, "range_timeout": lambda v: v >= 0,
    "spike_min": lambda v: v >= 0, "spike_window": lambda v: v >= 0,
    "accel_tau": lambda v: v > 0, "contact_thrust": lambda v: v in (0.0, 1.0),
}


def first_bad(p) -> str | None:
    """The first member of ``p`` outside its documented range, or None."""
    with np.errstate(invalid="ignore"):
        for name, ok in DOCUMENTED.items():
            v = float(p[LAND_DETECTOR_PARAMS.index(name)])
            if not (math.isfinite(v) and ok(v)):
                return name
    return None


def _bits(v):
    return np.asarray(v, dtype=np.float64).view(np.uint64)


def _cues(**kw):
    """A cue vector: every cue holding (gap, range, still, thrust, descent), then ``kw``."""
    c = dict(range_gap=0.01, range_valid=1.0, est_gap=0.01, est_vz=0.0, thrust_ratio=0.3,
             f_z=9.8, in_descend=1.0)
    c.update(kw)
    return LAND_DETECTOR_CUES.pack(c)


@pytest.mark.parametrize("precision", ["double", "float"])
def test_defaults_are_the_symbolic_defaults(precision):
    c = Call(load(precision))
    want = LAND_DETECTOR_PARAMS.pack(dict(LAND_DETECTOR_DEFAULTS)).astype(c.api.dtype)
    np.testing.assert_array_equal(c.v["params"], want)
    assert c.check() == (STATUS["QL_OK"], None)
    assert not np.any(c.v["state"])                 # the start: every stage unset, times zero


@pytest.mark.parametrize("precision", ["double", "float"])
@pytest.mark.parametrize("ranged, steps", [(True, (83, 165, 247)), (False, (250, 499, 748))])
def test_stages_set_on_the_hand_counted_steps(precision, ranged, steps):
    """Every cue holding from step 1: the stages set on steps n1, n1 + n2 - 1 and
    n1 + n2 + n3 - 2, n = ceil(W / dt - 1/2) = 83 for W = 1/3 s at 250 Hz, and 250 for
    the tripled windows without range or spike (docs/land_detector.md)."""
    c = Call(load(precision))
    c.v["cues"][:] = _cues(range_valid=1.0 if ranged else 0.0)
    first = {}
    for k in range(1, 800):
        assert c.step(DT) == STATUS["QL_OK"]
        for i in STAGES:
            if c.v["flags"][i] == 1 and i not in first:
                first[i] = k
    assert tuple(first[i] for i in STAGES) == steps
    assert c.v["flags"][STAGES].tolist() == [1, 1, 1]


def _flight(rng, n=1400):
    """Cues of a descent onto the deck: the gap closing with noise, the range every other
    step, a touchdown spike, the thrust dropping, and stretches of non-finite cues."""
    rows = []
    for k in range(n):
        gap = max(1.0 - k * 0.003, 0.0) + rng.normal() * 0.02
        touched = k > 330
        c = dict(range_gap=gap + rng.normal() * 0.01, range_valid=float(k % 2 == 0),
                 est_gap=gap, est_vz=(0.0 if touched else -0.6) + rng.normal() * 0.05,
                 thrust_ratio=0.35 if touched else 1.0 + rng.normal() * 0.05,
                 f_z=9.8 + (25.0 if k == 331 else 0.0) + rng.normal() * 0.3,
                 in_descend=float(k < 600))
        if 400 <= k < 420:                          # the estimate jumps: stage 1 drops
            c["est_gap"] = 0.5
        if k in (150, 345, 900, 1100):              # before, in and after the contact
            c[rng.choice(list(c))] = rng.choice((math.nan, math.inf, -math.inf))
        rows.append(LAND_DETECTOR_CUES.pack(c))
    return rows


@pytest.mark.parametrize("contact_thrust", [0.0, 1.0])
def test_step_equals_its_casadi_function_bit_for_bit(contact_thrust):
    c = Call(load("double"))
    f = land_detector_function()
    c.v["params"][LAND_DETECTOR_PARAMS.index("contact_thrust")] = contact_thrust
    p = c.v["params"].copy()
    state = np.zeros(LAND_DETECTOR_STATE.size)
    seen = set()
    for cues in _flight(np.random.default_rng(11)):
        c.v["cues"][:] = cues
        assert c.step(DT) == STATUS["QL_OK"]
        state, flags = (np.asarray(v, dtype=float).ravel() for v in f(state, cues, p, DT))
        np.testing.assert_array_equal(_bits(c.v["state"]), _bits(state))
        np.testing.assert_array_equal(_bits(c.v["flags"]), _bits(flags))
        seen.add(tuple(flags[STAGES]))
    # the flight passed through every stage and dropped back once (the estimate's jump)
    assert {(0, 0, 0), (1, 0, 0), (1, 1, 0), (1, 1, 1)} <= seen


@pytest.mark.parametrize("precision", ["double", "float"])
def test_contact_thrust_keeps_a_hover_over_the_deck_out_of_contact(precision):
    """``contact_thrust`` in the C: the gear held 3 cm over the deck, still, descending,
    the range agreeing, at hover thrust (ratio 1.0 > thrust_low 0.6) is ground contact on
    the hand-counted step 83 without the key and never in 1,000 steps with it; with the
    weight on the deck (ratio 0.3) the key leaves the steps 83, 165 and 247."""
    hover = _cues(range_gap=0.03, est_gap=0.03, thrust_ratio=1.0)
    for key, cues, want in ((0.0, hover, 83), (1.0, hover, None), (1.0, _cues(), 83)):
        c = Call(load(precision))
        c.v["params"][LAND_DETECTOR_PARAMS.index("contact_thrust")] = key
        assert c.check() == (STATUS["QL_OK"], None)
        c.v["cues"][:] = cues
        first = {}
        for k in range(1, 1001):
            assert c.step(DT) == STATUS["QL_OK"]
            for i in STAGES:
                if c.v["flags"][i] == 1 and i not in first:
                    first[i] = k
        if want is None:
            assert first == {}
        else:
            assert first[STAGES[0]] == want
    assert tuple(first[i] for i in STAGES) == (83, 165, 247)


def test_float_build_gives_the_same_stages():
    """The float build flies the noise-free descent with the double's flags at every step
    and its times within float's rounding."""
    d, f = Call(load("double")), Call(load("float"))
    for k in range(900):
        gap = max(1.0 - k * 0.003, 0.0)
        cues = _cues(range_gap=gap, est_gap=gap, est_vz=0.0 if k > 330 else -0.6,
                     thrust_ratio=0.35 if k > 330 else 1.0)
        d.v["cues"][:], f.v["cues"][:] = cues, cues
        assert d.step(DT) == f.step(DT) == STATUS["QL_OK"]
        np.testing.assert_array_equal(f.v["flags"], d.v["flags"])
        np.testing.assert_allclose(f.v["state"], d.v["state"], rtol=1e-5, atol=1e-5)
    assert d.v["flags"][STAGES].tolist() == [1, 1, 1]


@pytest.mark.parametrize("precision", ["double", "float"])
def test_check_names_the_first_member_outside_its_range(precision):
    assert tuple(DOCUMENTED) == LAND_DETECTOR_PARAMS.names()
    c = Call(load(precision))
    p0 = c.v["params"].copy()
    rng = np.random.default_rng(5)
    seen = set()
    for _ in range(1500):
        c.v["params"][:] = p0
        for _ in range(rng.integers(1, 3)):
            c.v["params"][rng.integers(p0.size)] = rng.choice(
                (0.0, -0.0, -1.0, 0.5, 1.0, 1.5, 1e-30, math.nan, math.inf, -math.inf))
        bad = first_bad(c.v["params"])
        assert c.check() == ((STATUS["QL_ERR_PARAM"], bad) if bad else (STATUS["QL_OK"], None))
        seen.add(bad)
    assert seen == {None, *DOCUMENTED}


@pytest.mark.parametrize("case, status", [
    ("null_state", "QL_ERR_NULL"),
    ("nan_state", "QL_ERR_NONFINITE_INPUT"),
    ("inf_param", "QL_ERR_NONFINITE_INPUT"),
    ("nan_dt", "QL_ERR_NONFINITE_INPUT"),
    ("zero_dt", "QL_ERR_INVALID"),
    ("half_stage", "QL_ERR_INVALID"),
    ("negative_time", "QL_ERR_INVALID"),
    ("narrowing_hold", "QL_ERR_PARAM"),
    ("zero_tau", "QL_ERR_PARAM"),
])
def test_errors_leave_the_state_and_zero_the_flags(case, status):
    c = Call(load("double"))
    c.v["cues"][:] = _cues()
    for _ in range(100):                            # a memory in the middle of a contact
        assert c.step(DT) == STATUS["QL_OK"]
    dt, null = DT, ()
    s, p = c.v["state"], c.v["params"]
    if case == "null_state":
        null = ("state",)
    elif case == "nan_state":
        s[LAND_DETECTOR_STATE.index("f_z_mean")] = math.nan
    elif case == "inf_param":
        p[LAND_DETECTOR_PARAMS.index("spike_window")] = math.inf
    elif case == "nan_dt":
        dt = math.nan
    elif case == "zero_dt":
        dt = 0.0
    elif case == "half_stage":
        s[LAND_DETECTOR_STATE.index("maybe_landed")] = 0.5
    elif case == "negative_time":
        s[LAND_DETECTOR_STATE.index("spike_hold")] = -1e-9
    elif case == "narrowing_hold":
        p[LAND_DETECTOR_PARAMS.index("hold_factor")] = 0.9
    elif case == "zero_tau":
        p[LAND_DETECTOR_PARAMS.index("accel_tau")] = 0.0
    c.v["flags"][:] = 7.0
    before = bytes(c.s["state"])
    assert c.step(dt, null) == STATUS[status]
    assert bytes(c.s["state"]) == before
    assert not np.any(c.v["flags"])
    if status == "QL_ERR_PARAM":
        assert c.check()[1] == {"narrowing_hold": "hold_factor", "zero_tau": "accel_tau"}[case]


def test_non_finite_cues_are_not_errors():
    """A cue that is not finite fails its test and never enters the memory."""
    c = Call(load("double"))
    c.v["cues"][:] = _cues()
    for _ in range(50):
        assert c.step(DT) == STATUS["QL_OK"]
    mean = c.v["state"][LAND_DETECTOR_STATE.index("f_z_mean")]
    c.v["cues"][:] = _cues(est_gap=math.nan, f_z=math.inf)
    assert c.step(DT) == STATUS["QL_OK"]
    assert np.all(np.isfinite(c.v["state"]))
    assert c.v["state"][LAND_DETECTOR_STATE.index("f_z_mean")] == mean
    assert c.v["state"][LAND_DETECTOR_STATE.index("t_contact")] == 0.0   # the gap cue failed


# --- the cues ------------------------------------------------------------------

class _CuesCall:
    """The arguments of ``ql_land_detector_form_cues`` with NumPy views."""

    def __init__(self, api):
        self.api, st = api, api.structs
        self.s = dict(y=st["landing_measurement"](), range=st["range_packet"](), imu=st["imu"](),
                      gs=st["guidance_state"](), gp=st["guidance_params"](),
                      quad=st["quadrotor_params"](), cues=st["land_detector_cues"]())
        self.F = (api.real * 4)()
        self.v = {n: view(s, api.dtype) for n, s in self.s.items()}

    def __call__(self, null=()):
        a = [None if n in null else ctypes.byref(self.s[n]) for n in ("y", "range", "imu")]
        b = [None if n in null else ctypes.byref(self.s[n]) for n in ("gs", "gp", "quad",
                                                                        "cues")]
        return self.api.lib.ql_land_detector_form_cues(*a, self.F, *b)


def test_cues_on_a_level_deck_by_hand():
    """Level quadrotor over a level deck: the ranged gap s - h, the estimated gap z_e - h,
    the vertical speed v_e_z, the collective over m1 g, f_z, and the descent flag."""
    c = _CuesCall(load("double"))
    h, m1, g = 0.2, 2.0, 9.81
    c.v["gp"][:] = 1.0
    c.v["gp"][GUIDANCE_PARAMS.index("touchdown_height")] = h
    c.v["quad"][:] = 1.0
    c.v["quad"][QUADROTOR.index("m1")], c.v["quad"][QUADROTOR.index("g")] = m1, g
    y = dict(p_e=[0.1, -0.2, 0.5], v_e=[0.3, 0.0, -0.25])
    for name, value in y.items():
        c.v["y"][LANDING_MEASUREMENT.slice(name)] = value
    c.v["range"][:] = RANGE.pack(dict(fresh=1.0, tau=3.0, s=0.62, b3_E=[0.0, 0.0, 1.0]))
    c.v["imu"][:] = IMU.pack(dict(eta_hat=np.zeros(3), f_b=[0.1, -0.1, 11.5],
                                  omega=np.zeros(3)))
    c.F[:] = [4.0, 5.0, 4.5, 4.2]
    c.s["gs"].phase = DESCEND
    assert c() == STATUS["QL_OK"]
    want = dict(range_gap=0.62 - h, range_valid=1.0, est_gap=0.5 - h, est_vz=-0.25,
                thrust_ratio=17.7 / (m1 * g), f_z=11.5, in_descend=1.0)
    np.testing.assert_allclose(c.v["cues"], LAND_DETECTOR_CUES.pack(want), rtol=1e-15,
                               atol=1e-15)
    c.s["gs"].phase = DESCEND - 1
    assert c() == STATUS["QL_OK"] and c.v["cues"][LAND_DETECTOR_CUES.index("in_descend")] == 0


def test_cues_equal_their_casadi_function_and_refuse_bad_parameters():
    c = _CuesCall(load("double"))
    f = detector_cues_function()
    rng = np.random.default_rng(3)
    for _ in range(200):
        for n in ("y", "range", "imu", "gp", "quad"):
            c.v[n][:] = rng.normal(size=c.v[n].size) * rng.choice((0.1, 1.0, 10.0))
        c.v["quad"][:] = np.abs(c.v["quad"]) + 0.1
        c.F[:] = rng.uniform(0, 10, 4)
        c.s["gs"].phase, c.s["gs"].aborts = int(rng.integers(5)), int(rng.integers(3))
        c.s["gs"].timer, c.s["gs"].z_ref = rng.normal(), rng.normal()
        xg = GUIDANCE_STATE.pack(dict(phase=c.s["gs"].phase, timer=c.s["gs"].timer,
                                      z_ref=c.s["gs"].z_ref, aborts=c.s["gs"].aborts,
                                      committed=c.s["gs"].committed, armed=c.s["gs"].armed,
                                      ms_rise=c.s["gs"].ms_rise,
                                      ms_rise_rate=c.s["gs"].ms_rise_rate,
                                      ms_tilt_rate=c.s["gs"].ms_tilt_rate,
                                      ms_tilt_acc=c.s["gs"].ms_tilt_acc,
                                      lean_x=c.s["gs"].lean_x, lean_y=c.s["gs"].lean_y,
                                      lean_gust=c.s["gs"].lean_gust))
        assert c() == STATUS["QL_OK"]
        want = np.asarray(f(c.v["y"], c.v["range"], c.v["imu"], np.array(c.F[:]), xg,
                            c.v["gp"], c.v["quad"]), dtype=float).ravel()
        np.testing.assert_array_equal(_bits(c.v["cues"]), _bits(want))
    c.v["cues"][:] = 7.0
    c.v["quad"][QUADROTOR.index("g")] = math.nan
    assert c() == STATUS["QL_ERR_NONFINITE_INPUT"] and not np.any(c.v["cues"])
    c.v["cues"][:] = 7.0
    assert c(null=("imu",)) == STATUS["QL_ERR_NULL"] and not np.any(c.v["cues"])

"""The navigation filter's generated C (``quadland_estimator.h``) against its CasADi
functions and its documented contract (docs/codegen.md, "The navigation filter's API").

The double build's ``ql_estimator_step`` equals ``estimator_step_function(N_HIST,
FLIGHT_DEPTH, FLIGHT_COUPLING)`` evaluated by CasADi bit for bit: the C is CasADi's
own code of the same expression graph, compiled without contraction into fused
multiply-adds (``-std=c99``, x86-64's baseline has none), and the only libm calls
(``sin``, ``cos``) are the ones CasADi's virtual machine makes. The flights below
carry packets that are due, late (fused after the horizon passed them), too old
(discarded), rejected by the gate, from the future or not finite (dropped), and
garbage in packets that are not fresh.
"""

from __future__ import annotations

import ctypes
import math

import numpy as np
import pytest
from estimator_c import Call, load
from reference import have_compiler, rotation

from quadland_symbolic.codegen import STATUS_CODES
from quadland_symbolic.codegen.estimator_api import flight_memory
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_diagnostics,
    estimator_init_function,
    estimator_step_function,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    NAV,
    NAV_PACKETS,
    SENSORS,
    estimator_params,
)

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

STATUS = {name: value for name, value, _ in STATUS_CODES}
DT = 0.004
MEM = flight_memory()
DIAG = estimator_diagnostics()
N = NAV.size


def _bits(v):
    return np.asarray(v, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("precision", ["double", "float"])
def test_defaults_are_the_symbolic_defaults(precision):
    c = Call(load(precision))
    want = estimator_params().pack(dict(ESTIMATOR_DEFAULTS)).astype(c.api.dtype)
    np.testing.assert_array_equal(c.v["params"], want)
    assert c.check() == (STATUS["QL_OK"], None)


def test_init_equals_its_casadi_function_and_refuses_bad_input():
    c = Call(load("double"))
    f = estimator_init_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    rng = np.random.default_rng(7)
    x0, P0, deck0 = rng.normal(size=N), rng.uniform(0, 2, N), rng.normal(size=9) * 0.1
    assert c.init(x0, P0, deck0, 12.5) == STATUS["QL_OK"]
    want = np.asarray(f(x0, P0, deck0, 12.5)).ravel()
    np.testing.assert_array_equal(_bits(c.v["mem"]), _bits(want))
    # the handover, by hand: the state, the variances on the diagonal, the horizon at t0
    mem = MEM.unpack(c.v["mem"].copy())
    np.testing.assert_array_equal(mem["x_h"], x0)
    assert mem["t_h"] == mem["deck_tau"] == 12.5 and not np.any(mem["hist"])
    assert sorted(mem["P_h"][mem["P_h"] != 0]) == sorted(P0)
    assert c.init(x0, P0, None, 1.0) == STATUS["QL_OK"]              # NULL deck0: zeros
    np.testing.assert_array_equal(MEM.unpack(c.v["mem"].copy())["deck_eta2"], 0.0)
    before = bytes(c.s["mem"])
    bad_P0 = P0.copy()
    bad_P0[4] = -1e-9
    nan_x0 = x0.copy()
    nan_x0[3] = math.nan
    assert c.init(x0, bad_P0, deck0, 1.0) == STATUS["QL_ERR_INVALID"]
    assert c.init(nan_x0, P0, deck0, 1.0) == STATUS["QL_ERR_NONFINITE_INPUT"]
    assert c.init(x0, P0, deck0, math.inf) == STATUS["QL_ERR_NONFINITE_INPUT"]
    assert c.api.lib.ql_estimator_init(None, None, None, 0.0,
                                       ctypes.byref(c.s["mem"])) == STATUS["QL_ERR_NULL"]
    assert bytes(c.s["mem"]) == before


# --- a flight with every kind of packet ---------------------------------------

#: The truth: constant velocities, the pad's acceleration zero, a level deck turning.
P_R0, V1, V_T, BIAS = (np.array(v) for v in ([0.3, -0.2, 3.0], [0.2, -0.1, -0.3],
                                             [0.5, 0.1, 0.0], [0.1, 0.2, -0.1]))
ETA_HAT, YAW_RATE, G = np.array([0.02, -0.01, 0.5]), 0.05, ESTIMATOR_DEFAULTS["g"]
MAX_AGE = ESTIMATOR_DEFAULTS["max_age_vision"]


def _truth(sensor, tau, rng, outlier):
    """A packet's values at ``tau`` s after the handover."""
    p_r = P_R0 + (V1 - V_T) * tau
    if sensor == "vision":
        v = dict(r_E=-p_r + rng.normal(size=3) * 0.05)
    elif sensor == "gnss":
        v = dict(rel=-p_r + BIAS + rng.normal(size=3) * 0.2, v1=V1 + rng.normal(size=3) * 0.1,
                 vt=V_T + rng.normal(size=3) * 0.1)
    elif sensor == "range":
        b3 = rotation(ETA_HAT)[:, 2]
        v = dict(s=p_r[2] / b3[2] + rng.normal() * 0.02, b3_E=b3)
    else:
        v = dict(eta2=[0.0, 0.0, 0.3 + YAW_RATE * tau], v2E=V_T, a2E=np.zeros(3),
                 w2E=[0.0, 0.0, YAW_RATE], w2E_dot=np.zeros(3))
    if outlier:                                        # 100 m or m/s off: the gate rejects it
        key = next(iter(v))
        v[key] = np.asarray(v[key], dtype=float) + 100.0
    return v


def _packets(c, rng, t, t_h, t0, p_fresh=0.15):
    """Each sensor's packet of this step: fresh or not, and of which kind."""
    D = N_HIST * DT
    for layout in NAV_PACKETS:
        v = c.v[layout.name]
        if rng.uniform() > p_fresh:          # not fresh: garbage the step must not read
            v[:] = rng.choice((math.nan, math.inf, 1e30, -3.0), size=v.size)
            v[0] = 0.0
            continue
        kind = rng.choice(("due", "due", "due", "late", "old", "future", "nan", "outlier"))
        tau = {"due": t - rng.uniform(0, D - DT), "late": t_h - rng.uniform(0, MAX_AGE - DT),
               "old": t_h - MAX_AGE - rng.uniform(2 * DT, 0.1),
               "future": t + rng.uniform(DT, 0.1)}.get(kind, t - rng.uniform(0, D - DT))
        values = _truth(layout.name, tau - t0, rng, kind == "outlier")
        v[:] = layout.pack(dict(fresh=1.0, tau=tau, **values))
        if kind == "nan":
            v[rng.integers(2, v.size)] = math.nan
        if layout.name == "range" and kind == "due":        # n2 . b3 small: an invalid range
            v[layout.slice("b3_E")] = [1.0, 0.0, 0.1] if rng.uniform() < 0.1 else \
                v[layout.slice("b3_E")]


def _imu(c, rng):
    c.v["imu"][0:3] = ETA_HAT
    c.v["imu"][3:6] = rotation(ETA_HAT).T @ [0.0, 0.0, G] + rng.normal(size=3) * 0.05
    c.v["imu"][6:9] = rng.normal(size=3) * 0.01
    if rng.uniform() < 0.02:       # a non-finite specific force: counted, not an error
        c.v["imu"][3 + rng.integers(3)] = math.nan


def _fly(c, rng, steps, t0, oracle=None):
    """Run the C step; with an oracle, compare each step's results with it bit for bit."""
    # the tilt bias starts at 0 (appended: the draws of the other states are the same)
    x0 = np.r_[np.r_[P_R0, V1, V_T, np.zeros(9)] + rng.normal(size=18) * 0.05, np.zeros(3)]
    P0 = np.r_[[0.5] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.04] * 3, [0.01] * 3]
    assert c.init(x0, P0, [0, 0, 0.3, 0, 0, YAW_RATE, 0, 0, 0], t0) == STATUS["QL_OK"]
    t, rows = t0, []
    for _ in range(steps):
        t += DT
        t_h = float(c.v["mem"][MEM.slice("t_h")][0])
        _packets(c, rng, t, t_h, t0)
        _imu(c, rng)
        args = [c.v[n].astype(float) for n in ("mem", "imu", *SENSORS, "params")]
        assert c.step(DT, t) == STATUS["QL_OK"]
        if oracle is not None:
            mem_next, y, diag = (np.asarray(v).ravel() for v in oracle(*args, DT, t))
            np.testing.assert_array_equal(_bits(c.v["mem"]), _bits(mem_next))
            np.testing.assert_array_equal(_bits(c.v["y"]), _bits(y))
            np.testing.assert_array_equal(_bits(c.v["diag"]), _bits(diag))
        rows.append((c.v["y"].astype(float), c.v["diag"].astype(float), args[1]))
    return rows


@pytest.mark.slow
@pytest.mark.parametrize("seed, heave, height", [(1, False, 1e6), (2, False, 1e6),
                                                  (3, True, 1e6), (4, True, 2.88)])
def test_step_equals_its_casadi_function_bit_for_bit(seed, heave, height):
    """The C step against CasADi's; with ``heave`` the pad's z oscillates at a given
    1.3 rad/s in the prediction and the output (E17b: a still pad stays still); with
    ``height`` 2.88 m (``heave_height``) the gate opens halfway down the flight's 3.0 to
    2.76 m, so the C step is held to CasADi's on both sides of it."""
    c = Call(load("double"))
    lay = estimator_params()
    if heave:
        c.v["params"][lay.slice("heave_frequency")] = 1.3
        c.v["params"][lay.slice("heave_in_filter")] = 1.0
        c.v["params"][lay.slice("heave_height")] = height
    # the range fused wherever its beam points (E12a off): the random states are metres
    # from the pad, and every block must be fused at least once
    c.v["params"][lay.slice("range_deck_radius")] = 1e30
    c.v["params"][lay.slice("range_deck_sigmas")] = 0.0
    rng = np.random.default_rng(seed)
    oracle = estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    rows = _fly(c, rng, 4 * N_HIST, 7.0 + seed, oracle)
    last = DIAG.unpack(rows[-1][1])
    heights = np.array([NAV.unpack(DIAG.unpack(d)["x_h"])["p_r"][2] for _, d, _ in rows])
    assert height > 1e5 or (np.any(heights <= height) and np.any(heights > height))
    # every kind of packet happened (the counters are the filter's own, C equal to CasADi)
    assert np.all(last["n_fused"] > 0) and np.all(last["n_discarded"] > 0)
    assert np.all(last["n_dropped"] > 0) and last["n_imu_invalid"] > 0
    assert last["n_rejected"][[b.name for b in BLOCKS].index("vision")] > 0
    # only a range is ever held back before its gate (a grazing beam; E12a is off here)
    held = dict(zip([b.name for b in BLOCKS], last["n_held"], strict=True))
    held.pop("range")
    assert not any(held.values())
    # the IMU's attitude and rates pass through; a NaN there is the IMU's, nothing else is
    for y, d, imu in rows:
        yy = LANDING_MEASUREMENT.unpack(y)
        np.testing.assert_array_equal(_bits(yy["eta1"]), _bits(imu[0:3]))
        np.testing.assert_array_equal(_bits(yy["Omega1"]), _bits(imu[6:9]))
        others = np.r_[yy["p_e"], yy["v_e"], yy["eta2"], yy["v2E"], yy["a2E"], yy["w2E"]]
        assert np.all(np.isfinite(others)) and np.all(np.isfinite(d))
    # and the filter tracks the truth: within four of its own standard deviations
    t_end = 7.0 + seed + 4 * N_HIST * DT
    d = DIAG.unpack(rows[-1][1])
    t_h = float(d["t_h"][0])
    assert t_h == pytest.approx(t_end - (N_HIST + 1) * DT, abs=1e-9)   # before the prediction
    x, sd = NAV.unpack(d["x_h"]), NAV.unpack(np.sqrt(d["P_diag"]))
    truth = dict(p_r=P_R0 + (V1 - V_T) * (t_h - 7.0 - seed), v1=V1, v_t=V_T, b=BIAS)
    for name, want in truth.items():
        assert np.all(np.abs(x[name] - want) <= 4 * sd[name]), (name, x[name], want, sd[name])


@pytest.mark.slow
def test_float_build_flies_the_same_filter():
    """The float build on the same inputs: the relative position within 1 mm of double's."""
    out = {}
    for precision in ("double", "float"):
        c = Call(load(precision))
        out[precision] = _fly(c, np.random.default_rng(3), 3 * N_HIST, 2.0)
    for (yd, _, _), (yf, _, _) in zip(out["double"], out["float"], strict=True):
        a, b = LANDING_MEASUREMENT.unpack(yd), LANDING_MEASUREMENT.unpack(yf)
        np.testing.assert_allclose(b["p_e"], a["p_e"], atol=1e-3)
        np.testing.assert_allclose(b["v_e"], a["v_e"], atol=1e-3)


# --- rejected by the gate, or held back off the deck -------------------------

#: Ranges in the order they arrive, worked out by hand: the quadrotor 3 m above the
#: pad of a level deck (``p_r = (0, 0, 3)``, the deck's normal e_z), its position known
#: to 1 cm per axis (variances 1e-4 m^2), the beam tilted by ``deg`` about y
#: (``b3_E = (sin, 0, cos)``), the measured distance ``3 / cos + off``. The beam's
#: predicted deck point is ``3 tan(deg)`` from the pad centre, the margin
#: ``range_deck_sigmas sqrt(2e-4) = 0.028 m``, the deck radius 0.5 m (E12a);
#: ``range_min_cos`` 0.7 (E12); the gate 6.63 on ``NIS = off^2 / S`` with
#: ``S <= 1e-4 / cos^2 + 0.05^2`` (the variance only shrinks as ranges are fused).
HAND_RANGES = (
    (0, 0.0, "fused"),      # on the pad, NIS 0
    (0, 1.0, "rejected"),   # NIS >= 1 / 0.0026 = 385
    (5, 0.0, "fused"),      # deck point 0.262 + 0.028 <= 0.5
    (20, 0.0, "held"),      # deck point 1.092: the beam may miss the deck (E12a)
    (20, 1.0, "held"),      # off the deck and off the prediction: held, never gated
    (50, 0.0, "held"),      # cos 0.643 < 0.7: a beam grazing the deck (E12)
    (5, -0.5, "rejected"),  # NIS >= 0.25 / 0.0026 = 96
    (30, 1.0, "held"),      # deck point 1.73
    (0, 0.0, "fused"),
)


def _hand_ranges(c, oracle=None):
    """Fly :data:`HAND_RANGES`, one per step while the horizon stays at the handover (its
    buffer of empty periods filling), so each is due in the step it arrives."""
    t0 = 3.0
    x0, P0 = np.zeros(NAV.size), np.r_[[1e-4] * 3, [0.25] * (NAV.size - 3)]
    x0[2] = 3.0
    assert c.init(x0, P0, np.zeros(9), t0) == STATUS["QL_OK"]
    for layout in NAV_PACKETS:
        c.v[layout.name][:] = 0.0
    c.v["imu"][:] = np.r_[0.0, 0.0, 0.0, 0.0, 0.0, G, 0.0, 0.0, 0.0]
    flags = []
    for k, (deg, off, _) in enumerate(HAND_RANGES):
        a = math.radians(deg)
        c.v["range"][:] = [1.0, t0, 3.0 / math.cos(a) + off, math.sin(a), 0.0, math.cos(a)]
        t = t0 + (k + 1) * DT
        args = [c.v[n].astype(float) for n in ("mem", "imu", *SENSORS, "params")]
        assert c.step(DT, t) == STATUS["QL_OK"]
        if oracle is not None:
            for got, want in zip((c.v["mem"], c.v["y"], c.v["diag"]), oracle(*args, DT, t),
                                 strict=True):
                np.testing.assert_array_equal(_bits(got), _bits(np.asarray(want).ravel()))
        flags.append(DIAG.unpack(c.v["diag"].astype(float)))
    return flags


@pytest.mark.parametrize("precision", ["double", "float"])
def test_gate_rejections_and_ranges_off_the_deck_are_counted_apart(precision):
    """Each range of :data:`HAND_RANGES` fused, rejected by its gate or held back as its
    hand derivation says, in the step's flags and counters, C equal to CasADi."""
    c = Call(load(precision))
    oracle = (estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
              if precision == "double" else None)
    flags = _hand_ranges(c, oracle)
    r = [b.name for b in BLOCKS].index("range")
    for d, (deg, off, want) in zip(flags, HAND_RANGES, strict=True):
        got = [k for k in ("fused", "rejected", "held") if d[k][r] == 1]
        assert got == [want], (deg, off, got)
        others = np.delete(np.r_[d["fused"], d["rejected"], d["held"]], [r, r + 7, r + 14])
        assert not np.any(others)
    last = flags[-1]
    want = {k: sum(w == k for _, _, w in HAND_RANGES) for k in ("fused", "rejected", "held")}
    assert want == {"fused": 3, "rejected": 2, "held": 4}
    for k, n in want.items():
        np.testing.assert_array_equal(last[f"n_{k}"], np.eye(7)[r] * n)


# --- errors -------------------------------------------------------------------

def _running(c):
    rng = np.random.default_rng(11)
    _fly(c, rng, N_HIST + 5, 1.0)
    return 1.0 + (N_HIST + 6) * DT


@pytest.mark.parametrize("precision", ["double", "float"])
def test_errors_leave_the_memory_untouched_and_the_outputs_zero(precision):
    c = Call(load(precision))
    t = _running(c)
    count = MEM.slice("count_vision").start
    cases = [("dt = 0", dict(dt=0.0), "QL_ERR_INVALID"),
             ("dt < 0", dict(dt=-DT), "QL_ERR_INVALID"),
             ("dt NaN", dict(dt=math.nan), "QL_ERR_NONFINITE_INPUT"),
             ("t infinite", dict(t=math.inf), "QL_ERR_NONFINITE_INPUT"),
             ("memory NaN", dict(mem=(MEM.slice("P_h").start + 4, math.nan)),
              "QL_ERR_NONFINITE_INPUT"),
             ("count not whole", dict(mem=(count, 2.5)), "QL_ERR_INVALID"),
             ("count beyond depth", dict(mem=(count, FLIGHT_DEPTH[0] + 1)), "QL_ERR_INVALID"),
             ("count negative", dict(mem=(count, -1.0)), "QL_ERR_INVALID"),
             ("param NaN", dict(params=(0, math.nan)), "QL_ERR_NONFINITE_INPUT"),
             # passed on to y.eta1 and y.Omega1: a NaN would leave with QL_OK (review of
             # issue 17: "status codes and never NaN")
             ("attitude estimate NaN", dict(imu=(0, math.nan)), "QL_ERR_NONFINITE_INPUT"),
             ("gyro rate infinite", dict(imu=(8, -math.inf)), "QL_ERR_NONFINITE_INPUT"),
             ("param out of range", dict(params=(estimator_params().slice("range_sigma").start,
                                                 0.0)), "QL_ERR_PARAM")]
    for what, change, status in cases:
        mem0, p0, imu0 = c.v["mem"].copy(), c.v["params"].copy(), c.v["imu"].copy()
        for key in ("mem", "params", "imu"):
            if key in change:
                c.v[key][change[key][0]] = change[key][1]
        before = bytes(c.s["mem"])
        c.v["y"][:] = 5.0
        c.v["diag"][:] = 5.0
        got = c.step(change.get("dt", DT), change.get("t", t))
        assert got == STATUS[status], what
        assert bytes(c.s["mem"]) == before, what
        assert not np.any(c.v["y"]) and not np.any(c.v["diag"]), what
        c.v["mem"][:], c.v["params"][:], c.v["imu"][:] = mem0, p0, imu0
    for name in Call.ARGS:
        before = bytes(c.s["mem"])
        assert c.step(DT, t, null=(name,)) == STATUS["QL_ERR_NULL"], name
        assert bytes(c.s["mem"]) == before
    assert c.step(DT, t) == STATUS["QL_OK"]


@pytest.mark.parametrize("precision", ["double", "float"])
def test_bad_packets_and_imu_are_counted_not_errors(precision):
    c = Call(load(precision))
    t = _running(c)
    mem = MEM.unpack(c.v["mem"].astype(float))
    c.v["gnss"][:] = np.r_[1.0, t - 0.1, [math.nan] * 9]           # not finite: dropped
    c.v["vision"][:] = np.r_[1.0, t + 1.0, 0.0, 0.0, -3.0]         # from the future: dropped
    c.v["range"][0] = c.v["datalink"][0] = 0.0
    c.v["imu"][3] = math.inf
    assert c.step(DT, t) == STATUS["QL_OK"]
    d = DIAG.unpack(c.v["diag"].astype(float))
    np.testing.assert_array_equal(d["dropped"], [1, 1, 0, 0])
    np.testing.assert_array_equal(d["n_dropped"], mem["n_dropped"] + [1, 1, 0, 0])
    assert d["imu_invalid"] == 1 and d["n_imu_invalid"] == mem["n_imu_invalid"] + 1
    assert np.all(np.isfinite(c.v["diag"])) and np.all(np.isfinite(c.v["mem"]))


# --- the parameter check ------------------------------------------------------

def _pos(v):
    return v > 0


def _nonneg(v):
    return v >= 0


#: The documented range of every member of ql_estimator_params (docs/codegen.md),
#: written out here, not read from quadland_symbolic.codegen.estimator_api.
DOCUMENTED = {
    "g": _pos, "q_acc": _pos, "q_at": _pos, "q_b": _pos, "q_ab": _pos,
    "tilt_sigma": _nonneg, "tilt_tau": _pos, "tilt_levels_bias": lambda v: (v >= 0) & (v <= 1),
    "vision_sigma0": _pos, "vision_k_range": _nonneg, "vision_heading_sigma": _nonneg,
    "gnss_rel_sigma": _pos,
    "gnss_v1_sigma": _pos, "gnss_vt_sigma": _pos, "range_sigma": _pos,
    "range_k_range": _nonneg,
    "range_min_cos": lambda v: (v > 0) & (v <= 1), "range_deck_radius": _pos,
    "range_deck_sigmas": _nonneg, "datalink_v_sigma": _pos,
    "datalink_a_sigma": _pos, **{f"gate_{b.name}": _pos for b in BLOCKS}, "gate_lockout": _nonneg,
    **{f"max_age_{s}": _nonneg for s in SENSORS}, "deck_extrapolation_max": _nonneg,
    "heave_time": _nonneg, "heave_frequency": _nonneg,
    "heave_in_filter": lambda v: (v >= 0) & (v <= 1), "heave_height": _nonneg,
}


def first_bad(p) -> str | None:
    """The first member of ``p`` outside its documented range, or None."""
    lay = estimator_params()
    with np.errstate(invalid="ignore"):
        for name, ok in DOCUMENTED.items():
            v = np.atleast_1d(p[lay.slice(name)]).astype(float)
            if not (np.all(np.isfinite(v)) and np.all(ok(v))):
                return name
    return None


def _edges(name, ok):
    """Values just outside and at the inside edge of a documented range."""
    if name == "range_min_cos":
        return [0.0, 1.0 + 1e-9], [1e-9, 1.0]
    if ok is _pos:
        return [0.0, -1.0], [1e-9]
    return [-1e-9], [0.0]


@pytest.mark.parametrize("name", [n for n in DOCUMENTED if n not in ("g", "gate_lockout")])
def test_the_scenario_refuses_what_the_flight_code_refuses(name):
    """A scenario's [estimator] value outside the flight code's documented range is bad
    input (one line naming the key), not a flight that runs on casadi and fails at t = 0 on
    the C (review of issue 17: twelve keys, gates and sigmas at 0, range_min_cos 2, were
    admitted). ``g`` is the plant's gravity, not a key of [estimator]; ``gate_lockout`` has
    its own whole-number rule (test_scenario.py)."""
    from quadland import load_scenario
    from quadland.exceptions import ScenarioError

    size = estimator_params().slice(name).stop - estimator_params().slice(name).start
    text = (lambda v: f"[{v!r}, {v!r}, {v!r}]") if size == 3 else repr
    bad, good = _edges(name, DOCUMENTED[name])
    for v in bad:
        with pytest.raises(ScenarioError, match=rf"estimator\.{name}\b"):
            load_scenario("highway", [f"estimator.{name}={text(v)}"])
    for v in good:
        p = load_scenario("highway", [f"estimator.{name}={text(v)}"]).data["estimator"][name]
        assert np.all(np.asarray(p, dtype=float) == v)


@pytest.mark.parametrize("precision", ["double", "float"])
def test_check_names_the_first_member_outside_its_range(precision):
    assert tuple(DOCUMENTED) == estimator_params().names()
    c = Call(load(precision))
    p0 = c.v["params"].copy()
    rng = np.random.default_rng(5)
    seen = set()
    for _ in range(2000):
        c.v["params"][:] = p0
        for _ in range(rng.integers(1, 3)):
            c.v["params"][rng.integers(p0.size)] = rng.choice(
                (0.0, -0.0, -1.0, 1.0, 1.5, 1e-30, math.nan, math.inf, -math.inf))
        bad = first_bad(c.v["params"])
        assert c.check() == ((STATUS["QL_ERR_PARAM"], bad) if bad else (STATUS["QL_OK"], None))
        seen.add(bad)
    assert seen == {*DOCUMENTED, None}            # every member named, and valid draws

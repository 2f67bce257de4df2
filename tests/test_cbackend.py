"""The compiled generated C against the CasADi functions it came from."""

from __future__ import annotations

import ctypes
import math
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest
from reference import have_compiler

import quadland
from quadland import codegen
from quadland.engine import build
from quadland.engine.disturbance import disturbance_samples
from quadland.exceptions import CompilerNotFoundError
from quadland.kinds.landing import flight as landing_flight
from quadland.kinds.paper import flight as paper_flight
from quadland.kinds.paper.simulate import TRAJECTORY
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import (
    PAPER_PLANT_STATE,
    closed_loop_function,
    closed_loop_jacobian_function,
    closed_loop_params,
    closed_loop_state,
    plant_function,
)
from quadland_symbolic.codegen import (
    STATUS_CODES,
    CodegenConfig,
    generate_estimator,
    generate_land_detector,
)
from quadland_symbolic.control_step import control_step_function

pytestmark = pytest.mark.skipif(not have_compiler(), reason="no C compiler")

L = 100
STATUS = {name: value for name, value, _ in STATUS_CODES}


@pytest.fixture(scope="module")
def paper():
    return model_values(quadland.load_scenario("paper"))


@pytest.fixture(scope="module")
def api():
    # -O0: the Jacobian's 0.8 MB of straight-line code compiles in seconds.
    return paper_flight.load_api(L, "double", "-O0")


@pytest.fixture(scope="module", params=["double", "float"])
def step_api(request):
    """The step's API alone, as flight code builds it (-O2), in both precisions."""
    return paper_flight.load_api(L, request.param, "-O2", model=False)


def _finfo(api):
    return np.finfo(np.float64 if api.real is ctypes.c_double else np.float32)


def _inputs(rng, mv, l, scale=1.0):
    """Random inputs of the control step around the paper's operating range."""
    xq = rng.normal(size=10) * 0.4 * scale
    xq[0] = 1.0 + rng.normal()
    return [xq, np.array([0.1, rng.normal(), rng.normal() * 0.2]), rng.normal(size=12) * 0.1,
            rng.normal(size=(l, 4)), rng.normal(size=4), rng.normal(size=4) * 10, mv.p_quad,
            mv.p_ctrl, np.array([-50.0, 80.0]), rng.uniform(), 0.002]


def _boundary_inputs(mv, l):
    """Clipping at both limits, near-singular tilt, tiny and huge dt, zero state,
    hold compensation at both ends of its range."""
    base = [np.zeros(10), np.zeros(3), np.zeros(12), np.zeros((l, 4)), np.zeros(4),
            np.zeros(4), mv.p_quad, mv.p_ctrl, np.array([-500.0, 500.0]), 0.0, 0.002]
    cases = [base]
    tilt = [*base]
    tilt[0] = np.array([1.0, 0.3, math.pi / 2 - 2e-3, 0.1, 0, 0, 0, 0, 0, 0])
    cases.append(tilt)
    clip = [*base]
    clip[0] = np.array([5.0, 0.5, -0.4, 1.0, 2, -1, 3, 4, -5, 6])
    clip[8] = np.array([0.0, 1.0])
    cases.append(clip)
    for dt in (1e-9, 10.0):
        c = [*base]
        c[0] = np.array([1.0, 0.1, 0.2, 0.3, 0.5, 0.5, 0.1, 0.1, 0.1, 0.1])
        c[10] = dt
        cases.append(c)
    extrapolated = [*cases[-1]]
    extrapolated[5], extrapolated[9] = np.array([30.0, -20.0, 5.0, 1.0]), 1.0
    cases.append(extrapolated)
    return cases


def _assert_rel(actual, expected, rtol=1e-12):
    actual, expected = np.ravel(np.asarray(actual, float)), np.ravel(np.asarray(expected, float))
    scale = np.maximum(np.abs(expected), np.max(np.abs(expected), initial=0.0) * 1e-12)
    scale = np.where(scale == 0, 1.0, scale)
    assert np.all(np.abs(actual - expected) <= rtol * scale), \
        np.max(np.abs(actual - expected) / scale)


@pytest.mark.parametrize("l", [L, 7])
def test_control_step_matches_casadi(paper, l):
    mv = paper if l == L else model_values(quadland.load_scenario("paper", [f"rbf.nodes={l}"]))
    step, ref = paper_flight.load_control_step(l), control_step_function(l)
    rng = np.random.default_rng(l)
    cases = [_inputs(rng, mv, l, s) for s in (0.1, 1.0, 3.0)] + _boundary_inputs(mv, l)
    clipped = 0
    for args in cases:
        got, want = step(*args), ref(*args)
        for g, w in zip(got, want, strict=True):
            assert g.shape == np.asarray(w).shape
            _assert_rel(g, w)
        clipped += int(got[6].item())
    assert clipped > 0   # the boundary cases reach the limits


@pytest.mark.slow
def test_float_build_tracks_double(paper):
    rng = np.random.default_rng(1)
    args = _inputs(rng, paper, L, 0.5)
    d = paper_flight.load_control_step(L)(*args)
    f = paper_flight.load_control_step(L, "float")(*args)
    for a, b in zip(d, f, strict=True):
        assert np.allclose(a, b, rtol=1e-4, atol=1e-4 * np.max(np.abs(a), initial=1.0))


def _api_objects(api, mv, x):
    xq = api.QuadrotorState(x[0], (api.real * 3)(*x[1:4]), (api.real * 3)(*x[4:7]),
                            (api.real * 3)(*x[7:10]))
    yv = api.VehicleState(mv.p_veh[-1], x[12], x[15])
    ref = api.Reference()
    params = api.Params()
    state = api.AdaptiveState()
    api.lib.ql_params_init(ctypes.byref(params))
    api.lib.ql_reference_init(ctypes.byref(ref))
    api.lib.ql_adaptive_state_init(ctypes.byref(state))
    return xq, yv, ref, params, state, api.Output()


def _step(api, xq, yv, ref, params, dt, state, out):
    return api.lib.ql_control_step(ctypes.byref(xq), ctypes.byref(yv), ctypes.byref(ref),
                                   ctypes.byref(params), dt, ctypes.byref(state),
                                   ctypes.byref(out))


def _flat(struct):
    return np.frombuffer(bytes(struct), dtype=np.float64).copy()


def _state_reals(state):
    """[vec(W_hat), zeta_hat, u_prev] of a ql_adaptive_state."""
    return _flat(state)[:4 * L + 8]


def test_api_defaults_are_the_paper_scenario(api, paper):
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    flat = _flat(params)
    nq = paper.p_quad.size
    np.testing.assert_array_equal(flat[:nq], paper.p_quad)
    np.testing.assert_array_equal(flat[nq:nq + paper.p_ctrl.size], paper.p_ctrl)
    assert (params.rotor_force_min, params.rotor_force_max) == paper.rotor_limits
    assert params.hold_compensation == paper.hold == 0.5
    assert not _state_reals(state).any() and state.has_prev == 0 and not _flat(ref).any()
    vp = api.VehicleParams()
    api.lib.ql_vehicle_params_init(ctypes.byref(vp))
    p = np.zeros(closed_loop_params(L).size)
    api.lib.ql_pack_closed_loop_params(ctypes.byref(params), ctypes.byref(vp),
                                       ctypes.byref(ref), p.ctypes.data_as(
                                           ctypes.POINTER(ctypes.c_double)))
    np.testing.assert_array_equal(p, paper.p)


def test_api_step_matches_casadi(api, paper):
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    f = control_step_function(L)
    W, zeta, u_prev, hold = np.zeros((L, 4)), np.zeros(4), np.zeros(4), 0.0
    x = paper.x0
    for k in range(3):   # the adaptive state and the previous command are carried
        xq.Omega1[1] = x[8] + 0.3 * k     # the law's output moves between steps
        assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
        want = f([*x[0:8], x[8] + 0.3 * k, x[9]], [paper.p_veh[-1], x[12], x[15]], paper.ref,
                 W, zeta, u_prev, paper.p_quad, paper.p_ctrl, list(paper.rotor_limits), hold,
                 0.002)
        W, zeta, u_prev = (np.asarray(want[i]) for i in (3, 4, 5))
        _assert_rel(list(out.u), want[0])
        _assert_rel(list(out.u_law), want[5])
        _assert_rel(list(out.wrench), want[1])
        _assert_rel(list(out.rotor), want[2])
        _assert_rel(_state_reals(state), np.r_[W.ravel(order="F"), zeta.ravel(), u_prev.ravel()])
        assert state.has_prev == 1
        assert out.n_clipped == 0 and out.tilt == pytest.approx(float(want[7]), rel=1e-15)
        hold = paper.hold


def test_api_hold_compensation_extrapolates_the_law(step_api, paper):
    """u = u_law + kappa (u_law - u_law of the step before), from the second step on."""
    api = step_api
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    params.hold_compensation = 0.75
    state.u_prev[1] = math.nan          # not read while has_prev = 0
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    first = np.array(list(out.u_law))
    np.testing.assert_array_equal(list(out.u), first)      # nothing to extrapolate from
    np.testing.assert_array_equal(list(state.u_prev), first)
    assert state.has_prev == 1
    xq.eta1[1] += 0.01
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    second = np.array(list(out.u_law))
    assert np.max(np.abs(second - first)) > 0.1
    want = second + 0.75 * (second - first)
    tol = 1e-12 if api.real is ctypes.c_double else 1e-6
    np.testing.assert_allclose(list(out.u), want, rtol=tol, atol=tol * np.max(np.abs(want)))
    state.has_prev = 0                  # a gap: the next command is not extrapolated
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    np.testing.assert_array_equal(list(out.u), list(out.u_law))


def test_api_clipping_is_reported(step_api, paper):
    api = step_api
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    params.rotor_force_min, params.rotor_force_max = -2.0, 3.0
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    assert out.n_clipped > 0
    assert all(-2.0 <= f <= 3.0 for f in out.rotor)


@pytest.mark.parametrize("case, status", [
    ("nan_measurement", "QL_ERR_NONFINITE_INPUT"),
    ("inf_vehicle", "QL_ERR_NONFINITE_INPUT"),
    ("inf_center", "QL_ERR_NONFINITE_INPUT"),
    ("nan_gain", "QL_ERR_NONFINITE_INPUT"),
    ("inf_dt", "QL_ERR_NONFINITE_INPUT"),
    ("nan_W_hat", "QL_ERR_NONFINITE_INPUT"),
    ("inf_zeta_hat", "QL_ERR_NONFINITE_INPUT"),
    ("nan_u_prev", "QL_ERR_NONFINITE_INPUT"),
    ("nan_hold", "QL_ERR_NONFINITE_INPUT"),
    ("negative_hold", "QL_ERR_PARAM"),
    ("hold_above_one", "QL_ERR_PARAM"),
    ("zero_dt", "QL_ERR_INVALID"),
    ("swapped_limits", "QL_ERR_PARAM"),
    ("negative_mass", "QL_ERR_PARAM"),
    ("zero_arm", "QL_ERR_PARAM"),
    ("zero_c", "QL_ERR_PARAM"),
    ("zero_rho", "QL_ERR_PARAM"),
    ("negative_gamma1", "QL_ERR_PARAM"),
    ("negative_k1", "QL_ERR_PARAM"),
    ("half_nominal_model", "QL_ERR_PARAM"),
    ("tilt_min_one", "QL_ERR_PARAM"),
    ("vertical_pitch", "QL_ERR_TILT"),
    ("rolled_over", "QL_ERR_TILT"),
    ("overflow", "QL_ERR_NONFINITE_OUTPUT"),
    ("overflowed_rotor_force", "QL_ERR_NONFINITE_OUTPUT"),
])
def test_api_errors_leave_the_state_untouched(step_api, paper, case, status):
    api = step_api
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    dt = 0.002
    assert _step(api, xq, yv, ref, params, dt, state, out) == STATUS["QL_OK"]
    if case == "nan_measurement":
        xq.Omega1[1] = math.nan
    elif case == "inf_vehicle":
        yv.r2 = math.inf
    elif case == "inf_center":
        params.ctrl.centers[37][4] = -math.inf
    elif case == "nan_gain":
        params.ctrl.k2[3] = math.nan
    elif case == "inf_dt":
        dt = math.inf
    elif case == "nan_W_hat":
        state.W_hat[2][99] = math.nan
    elif case == "inf_zeta_hat":
        state.zeta_hat[0] = math.inf
    elif case == "nan_u_prev":
        state.u_prev[2] = math.nan
    elif case == "nan_hold":
        params.hold_compensation = math.nan
    elif case == "negative_hold":
        params.hold_compensation = -0.1
    elif case == "hold_above_one":
        params.hold_compensation = 1.5
    elif case == "zero_dt":
        dt = 0.0
    elif case == "swapped_limits":
        params.rotor_force_min, params.rotor_force_max = 10.0, -10.0
    elif case == "negative_mass":
        params.quad.m1 = -2.0
    elif case == "zero_arm":
        params.quad.arm = 0.0
    elif case == "zero_c":
        params.quad.c = -0.0
    elif case == "zero_rho":
        params.ctrl.rho = 0.0
    elif case == "negative_gamma1":
        params.ctrl.gamma1 = -0.05
    elif case == "negative_k1":
        params.ctrl.k1[2] = -1.0
    elif case == "half_nominal_model":
        params.ctrl.nominal_model = 0.5
    elif case == "tilt_min_one":
        params.tilt_min = 1.0
    elif case == "vertical_pitch":
        xq.eta1[1] = math.pi / 2
    elif case == "rolled_over":
        xq.eta1[0] = math.pi / 2 + 1e-4
    elif case == "overflow":
        xq.V1[2] = 100.0
        params.ctrl.k2[0] = _finfo(api).max / 2    # finite gain, overflowing product
    elif case == "overflowed_rotor_force":
        # u is finite, the moments I u overflow and the mixer makes NaN of them:
        # fmax(NaN, F_min) would have clipped it to F_min with QL_OK.
        xq.Omega1[0] = 1e307 if api.real is ctypes.c_double else 1e37
    before = bytes(state)
    assert _step(api, xq, yv, ref, params, dt, state, out) == STATUS[status]
    assert bytes(state) == before
    assert not any(list(out.u) + list(out.u_law) + list(out.wrench) + list(out.rotor))
    assert api.lib.ql_status_string(STATUS[status])


def _check_params(api, params):
    bad = ctypes.c_char_p()
    status = api.lib.ql_check_params(ctypes.byref(params), ctypes.byref(bad))
    return status, None if bad.value is None else bad.value.decode()


@pytest.mark.parametrize("member, value, name", [
    ("quad.m1", -2.0, "quad.m1"),
    ("quad.m1", math.nan, "quad.m1"),
    ("quad.I", 0.0, "quad.I"),
    ("quad.Kt", -1e-30, "quad.Kt"),
    ("quad.g", -9.8, "quad.g"),
    ("quad.arm", 0.0, "quad.arm"),
    ("quad.c", -0.0, "quad.c"),
    ("ctrl.k1", -3.0, "ctrl.k1"),
    ("ctrl.k2", math.inf, "ctrl.k2"),
    ("ctrl.gamma1", -0.05, "ctrl.gamma1"),
    ("ctrl.gamma2", 0.0, "ctrl.gamma2"),
    ("ctrl.k_w", 0.0, "ctrl.k_w"),
    ("ctrl.k_zeta", -0.1, "ctrl.k_zeta"),
    ("ctrl.rho", 0.0, "ctrl.rho"),
    ("ctrl.nominal_model", 2.0, "ctrl.nominal_model"),
    ("ctrl.centers", -math.inf, "ctrl.centers"),
    ("ctrl.widths", 0.0, "ctrl.widths"),
    ("rotor_force_min", math.nan, "rotor_force_min"),
    ("rotor_force_max", -600.0, "rotor_force_max"),
    ("tilt_min", -1e-3, "tilt_min"),
    ("tilt_min", 1.0, "tilt_min"),
    ("hold_compensation", 1.5, "hold_compensation"),
])
def test_check_params_names_the_bad_member(step_api, paper, member, value, name):
    api = step_api
    params = api.Params()
    api.lib.ql_params_init(ctypes.byref(params))
    assert _check_params(api, params) == (STATUS["QL_OK"], None)
    owner, _, field = member.rpartition(".")
    target = getattr(params, owner) if owner else params
    if isinstance(getattr(target, field), (int, float)):
        setattr(target, field, value)
    else:   # an array member: its last entry
        flat = getattr(target, field)
        while not isinstance(flat[len(flat) - 1], (int, float)):
            flat = flat[len(flat) - 1]
        flat[len(flat) - 1] = value
    assert _check_params(api, params) == (STATUS["QL_ERR_PARAM"], name)
    # The step refuses it too, but for the per-node widths (check_params only).
    xq, yv, ref, _, state, out = _api_objects(api, paper, paper.x0)
    status = _step(api, xq, yv, ref, params, 0.002, state, out)
    if name == "ctrl.widths":
        assert status == STATUS["QL_OK"]
    else:
        assert status in (STATUS["QL_ERR_PARAM"], STATUS["QL_ERR_NONFINITE_INPUT"])


def test_check_params_edges(step_api):
    """Boundaries that are valid, a NULL bad_field, a NULL params."""
    api = step_api
    params = api.Params()
    api.lib.ql_params_init(ctypes.byref(params))
    params.quad.Kt[0] = -0.0               # >= 0 holds for -0
    params.tilt_min = 0.0
    params.hold_compensation = 1.0
    params.ctrl.nominal_model = 1.0
    params.rotor_force_min = params.rotor_force_max = 7.0
    params.quad.m1 = float(_finfo(api).smallest_subnormal)
    assert _check_params(api, params) == (STATUS["QL_OK"], None)
    params.quad.m1 = 0.0
    assert api.lib.ql_check_params(ctypes.byref(params), None) == STATUS["QL_ERR_PARAM"]
    bad = ctypes.c_char_p(b"stale")
    assert api.lib.ql_check_params(None, ctypes.byref(bad)) == STATUS["QL_ERR_NULL"]
    assert bad.value is None


def test_api_accepts_huge_finite_parameters(step_api, paper):
    """Finite values whose sum overflows are not taken for infinities."""
    api = step_api
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    want = list(out.u) + list(out.rotor)
    xq, yv, ref, params, state, out = _api_objects(api, paper, paper.x0)
    huge = 0.9 * float(_finfo(api).max)
    params.rotor_force_max = huge           # never reached
    params.ctrl.centers[5][0] = huge        # a node so far away that Psi_5 = 0; W_hat = 0
    assert _step(api, xq, yv, ref, params, 0.002, state, out) == STATUS["QL_OK"]
    assert list(out.u) + list(out.rotor) == want


def test_api_null_pointer(api):
    out = api.Output()
    assert api.lib.ql_control_step(None, None, None, None, 0.002, None,
                                   ctypes.byref(out)) == STATUS["QL_ERR_NULL"]


def test_closed_loop_and_jacobian_match_casadi(api, paper):
    rng = np.random.default_rng(3)
    nx = closed_loop_state(L).size
    x = paper.x0 + 0.1 * rng.normal(size=nx)
    w = rng.normal(size=6)
    ptr = ctypes.POINTER(ctypes.c_double)

    def c(a):
        return np.ascontiguousarray(a, dtype=float).ctypes.data_as(ptr)

    xd = np.zeros(nx)
    api.lib.ql_closed_loop(c(x), c(w), c(paper.p), xd.ctypes.data_as(ptr))
    _assert_rel(xd, closed_loop_function(L)(x, w, paper.p))
    J = closed_loop_jacobian_function(L)(x, w, paper.p)
    nz = np.zeros(J.nnz())
    api.lib.ql_closed_loop_jacobian(c(x), c(w), c(paper.p), nz.ctypes.data_as(ptr))
    _assert_rel(nz, np.asarray(J.nonzeros()))
    sp = api.lib.ql_closed_loop_jacobian_sparsity()
    nrow, ncol = sp[0], sp[1]
    colind = [sp[2 + k] for k in range(ncol + 1)]
    assert (nrow, ncol) == (nx, nx) and colind == list(J.sparsity().colind())
    xp = np.concatenate([x[0:16], x[-2:]])
    xpd = np.zeros(18)
    wrench = rng.normal(size=4)
    api.lib.ql_plant(c(xp), c(wrench), c(w), c(paper.p_quad), c(paper.p_veh),
                     xpd.ctypes.data_as(ptr))
    _assert_rel(xpd, plant_function()(xp, wrench, w, paper.p_quad, paper.p_veh))


def test_jacobian_is_the_derivative(paper):
    """The generated Jacobian against central differences of the right-hand side."""
    rng = np.random.default_rng(4)
    f, J = closed_loop_function(L), closed_loop_jacobian_function(L)
    x, w = paper.x0 + 0.05 * rng.normal(size=paper.x0.size), rng.normal(size=6)
    v = rng.normal(size=x.size)
    h = 1e-6
    fd = (np.asarray(f(x + h * v, w, paper.p)) - np.asarray(f(x - h * v, w, paper.p))) / (2 * h)
    jv = np.asarray(ca.mtimes(J(x, w, paper.p), ca.DM(v)))
    np.testing.assert_allclose(jv, fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))


def _sim(overrides):
    return quadland.simulate(quadland.load_scenario("paper", overrides))


@pytest.mark.slow
def test_backends_fly_the_same_trajectory():
    common = ["controller.rate_hz=500.0", "simulation.duration=1.0"]
    a = _sim(common + ['controller.backend="casadi"'])
    b = _sim(common + ['controller.backend="c"'])
    assert np.max(np.abs(a.states - b.states)) <= 1e-9
    for name in ("F_total", "M_x", "F_1", "u_2"):
        assert np.max(np.abs(a[name] - b[name])) <= 1e-9 * max(1.0, np.max(np.abs(a[name])))


@pytest.mark.slow
def test_500_hz_stays_within_1_cm_and_1_mrad_of_the_continuous_loop():
    """The paper scenario over the whole flight, hold compensation as shipped (1/2)."""
    cont = _sim([])
    samp = _sim(["controller.rate_hz=500.0"])
    assert np.max(np.abs(samp["z_e"] - cont["z_e"])) <= 0.01
    for k in ("phi_e", "theta_e", "psi_e"):
        assert np.max(np.abs(samp[k] - cont[k])) <= 1e-3


@pytest.mark.slow
@pytest.mark.parametrize("hold, order", [(0.0, 1), (0.5, 2)])
def test_hold_compensation_raises_the_order_of_the_sampling_error(hold, order):
    """Doubling the rate divides the deviation from the continuous loop by 2**order.

    A plain zero-order hold delays the command by half a period on average:
    an error of first order in dt. Extrapolating by half a period cancels
    that term and leaves a second-order one.
    """
    base = ["simulation.duration=0.5", f"controller.hold_compensation={hold}"]
    cont = _sim(base)
    dev = []
    for rate in (250.0, 500.0, 1000.0):
        samp = _sim(base + [f"controller.rate_hz={rate}"])
        dev.append(max(np.max(np.abs(samp[k] - cont[k])) for k in ("phi_e", "theta_e", "psi_e")))
    ratios = np.array(dev[:-1]) / np.array(dev[1:])
    np.testing.assert_allclose(ratios, 2.0 ** order, rtol=0.05)


@pytest.fixture(scope="module")
def example(tmp_path_factory):
    """The example built from a copy of generated/ (nothing is written in the tree)."""
    if shutil.which("make") is None:
        pytest.skip("no make")
    root = tmp_path_factory.mktemp("generated")
    shutil.copytree(codegen.generated_dir(), root, dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("build", "closed_loop_jacobian.c"))
    cc = build.find_compiler()
    subprocess.run(["make", "-s", "-j2", f"CC={cc}", "build/fly"], cwd=root / "example",
                   check=True, capture_output=True)
    return root / "example" / "build" / "fly"


def _fly(fly, rate, duration):
    out = subprocess.run([str(fly), str(rate), str(duration)], check=True, capture_output=True,
                         text=True).stdout
    lines = out.splitlines()
    header = lines[0].split(",")
    data = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    return {h: data[:, i] for i, h in enumerate(header)}


#: The plant's states by name, as both CSVs name them (the layouts' element names).
PLANT_NAMES = PAPER_PLANT_STATE["xq"].element_names() + PAPER_PLANT_STATE["xv"].element_names()


def _rk4_closed_loop(scenario, h, n):
    """Classical RK4 of the CasADi closed loop: an independent reference."""
    mv = model_values(scenario)
    f = closed_loop_function(mv.l)
    w_all = disturbance_samples(scenario, h * np.arange(n + 1))
    x, xs = mv.x0.copy(), [mv.x0.copy()]
    for k in range(n):
        def rhs(y, k=k):
            return np.asarray(f(y, w_all[:, k], mv.p)).ravel()
        k1 = rhs(x)
        k2 = rhs(x + h / 2 * k1)
        k3 = rhs(x + h / 2 * k2)
        k4 = rhs(x + h * k3)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        xs.append(x.copy())
    return np.array(xs)


@pytest.mark.slow
def test_pure_c_continuous_flight_matches_rk4(example):
    """``fly 0``: the generated closed loop under classical RK4, 10 ms steps.

    quadland.simulate's continuous loop uses CasADi's "rk" integrator, which
    differs from classical RK4 on the same grid by up to ~3e-6 here; the C is
    therefore checked at 1e-9 against RK4 of the CasADi function, and
    against quadland.simulate at that integrator difference.
    """
    c = _fly(example, 0.0, 1.0)
    sc = quadland.load_scenario("paper", ["simulation.duration=1.0", "disturbance.noise=false"])
    X = _rk4_closed_loop(sc, 0.01, 100)
    x_names = closed_loop_state(L).element_names()
    for name in PLANT_NAMES:
        assert np.max(np.abs(c[name] - X[:, x_names.index(name)])) <= 1e-9, name
    py = quadland.simulate(sc)
    for name in ("z_e", "phi_e", "theta_e", "psi_e"):
        assert np.max(np.abs(c[name] - py[name])) <= 1e-5, name


@pytest.mark.slow
@pytest.mark.parametrize("rate", [500.0])
def test_pure_c_flight_matches_python(example, rate):
    c = _fly(example, rate, 1.0)
    py = _sim([f"controller.rate_hz={rate}", "simulation.duration=1.0",
               "disturbance.noise=false"])
    np.testing.assert_allclose(c["t"], py["t"], atol=1e-12)
    x_names = closed_loop_state(L).element_names()
    for name in PLANT_NAMES:
        assert np.max(np.abs(c[name] - py.states[:, x_names.index(name)])) <= 1e-9, name
    shared = [n for n in c if n in TRAJECTORY.element_names() and n != "t"]
    assert len(shared) == len(c) - len(("t", "u1", "v1", "w1", "p1", "q1", "r1", "n_clipped",
                                        "status"))
    for name in shared:
        scale = max(1.0, np.max(np.abs(py[name])))
        assert np.max(np.abs(c[name] - py[name])) <= 1e-9 * scale, name
    assert not c["status"].any()


@pytest.mark.slow
def test_sources_are_generated_not_read(tmp_path, monkeypatch):
    """One-way flow: the runtime's C comes from symbolic/, equal to generated/ for the
    shipped scenarios."""
    monkeypatch.setattr(codegen, "_package_parent", lambda: tmp_path)   # no checkout
    paper_flight._flight_files.cache_clear()
    landing_flight._flight_files.cache_clear()
    try:
        committed = codegen.generated_files()
        top = {k: v for k, v in committed.items()
               if "/" not in k and k not in (".gitignore", codegen.MANIFEST)}
        # the landing build is the whole tree (the paper's quadland.h with it, the
        # navigation filter's and the land detector's APIs, which have no scenario values),
        # l = 10
        assert landing_flight.flight_files(10) == top
        paper = paper_flight.flight_files(L)
        assert paper == {k: v for k, v in top.items() if k in paper}
        assert "quadland_landing.h" not in paper
        for extra in (generate_estimator, generate_land_detector):
            assert {k: top[k] for k in extra(CodegenConfig("double"))} == \
                extra(CodegenConfig("double"))
        floats = {k.removeprefix("float/"): v for k, v in committed.items()
                  if k.startswith("float/")}
        assert landing_flight.flight_files(10, "float") == floats
        assert "#define QL_RBF_NODES 7 " in paper_flight.flight_files(7)["quadland.h"]
        assert "#define QL_LANDING_RBF_NODES 7 " in \
            landing_flight.flight_files(7)["quadland_landing.h"]
    finally:
        paper_flight._flight_files.cache_clear()
        landing_flight._flight_files.cache_clear()


def test_no_compiler_is_one_clear_error(monkeypatch):
    monkeypatch.setenv("CC", "")
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(CompilerNotFoundError, match="no C compiler found"):
        build.find_compiler()

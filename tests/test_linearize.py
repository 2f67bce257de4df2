"""Operating points and linear models against the nonlinear closed loop."""

import control
import numpy as np
import pytest

from quadland.analysis import closed_loop_poles, freqresp
from quadland.exceptions import OperatingPointError
from quadland.kinds.paper.linearize import frozen_point, paper_equilibrium
from quadland.kinds.paper.values import model_values
from quadland.linearization import equilibrium, linear_models, sampled_models
from quadland.scenario import load_scenario
from quadland_symbolic.backstepping import controller_function
from quadland_symbolic.closed_loop import closed_loop_function, closed_loop_state
from quadland_symbolic.quadrotor import quadrotor_function

L_NODES = 4


@pytest.fixture(scope="module")
def small():
    return load_scenario("paper", ["rbf.nodes=4"])


@pytest.fixture(scope="module")
def eq_point(small):
    return equilibrium(small)


def _full_state(small, point, psi2=0.0):
    """Closed-loop state of quadland_symbolic.closed_loop at a point (psi1 = psi_e + psi2)."""
    lay = closed_loop_state(L_NODES)
    xq = point.xr.copy()
    xq[3] += psi2                                   # psi1 = psi_e + psi2
    return lay.pack(dict(xq=xq, xv=[0.0, 0.0, psi2, *point.vehicle],
                         W_hat=point.xc[:4 * L_NODES], zeta_hat=point.xc[4 * L_NODES:],
                         pos1=[0.0, 0.0]))


def _fd_jacobian(f, x, idx_in, h=1e-6):
    cols = []
    for i in idx_in:
        e = np.zeros_like(x)
        e[i] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.column_stack(cols)


def _loop_indices():
    lay = closed_loop_state(L_NODES)
    return np.r_[lay.slice("xq"), lay.slice("W_hat").start:lay.slice("zeta_hat").stop]


def test_equilibrium_is_a_steady_motion_of_the_nonlinear_loop(small, eq_point):
    mv = model_values(small)
    x = _full_state(small, eq_point, psi2=0.3)
    xdot = np.asarray(closed_loop_function(L_NODES)(x, eq_point.w, mv.p)).ravel()
    r2 = eq_point.vehicle[2]
    # the quadrotor yaws with the vehicle; everything else of the loop is at rest
    d = closed_loop_state(L_NODES).unpack(xdot)
    np.testing.assert_allclose(d["xq"], [0, 0, 0, r2, 0, 0, 0, 0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(d["W_hat"], 0, atol=1e-9)
    np.testing.assert_allclose(d["zeta_hat"], 0, atol=1e-9)
    np.testing.assert_allclose(d["xv"][2:6], [r2, 0, 0, 0], atol=1e-9)
    # vehicle in its steady turn: r2 = tau_z / d33 when m11 = m22 (eq. 4)
    assert r2 == pytest.approx(5.0 / 80.0, rel=1e-9)
    assert eq_point.residual < 1e-8


@pytest.mark.parametrize("where", ["equilibrium", "frozen"])
def test_closed_loop_matrix_matches_finite_differences(small, eq_point, where):
    point = eq_point if where == "equilibrium" else frozen_point(small, 0.2)
    mv = model_values(small)
    psi2 = 0.0 if where == "equilibrium" else 0.4
    x = _full_state(small, point, psi2)
    f_cl = closed_loop_function(L_NODES)
    idx = _loop_indices()

    def rhs(x):
        return np.asarray(f_cl(x, point.w, mv.p)).ravel()[idx]

    fd = _fd_jacobian(rhs, x, idx)
    A = linear_models(small, point).closed_loop.A
    np.testing.assert_allclose(A, fd, rtol=1e-5, atol=1e-6 * (1 + np.abs(fd).max()))


def test_plant_and_controller_match_finite_differences(small, eq_point):
    mv = model_values(small)
    models = linear_models(small, eq_point)
    xr, u0 = eq_point.xr, eq_point.u
    quad = quadrotor_function()
    m1, I = mv.p_quad[0], mv.p_quad[1:4]

    def plant(xu):
        x, u = xu[:10], xu[10:]
        # eq. 6 inverted by hand: F = m1 u1 / (cos theta cos phi), M = I u2..4
        wrench = np.r_[m1 * u[0] / (np.cos(x[1]) * np.cos(x[2])), I * u[1:]]
        xdot = np.asarray(quad(x, wrench, eq_point.w[:3], eq_point.w[3:], mv.p_quad)).ravel()
        xdot[3] -= eq_point.vehicle[2]
        return xdot

    fd = _fd_jacobian(plant, np.r_[xr, u0], range(14))
    np.testing.assert_allclose(models.plant.A, fd[:, :10], atol=1e-7)
    np.testing.assert_allclose(models.plant.B, fd[:, 10:], atol=1e-7)

    ctrl = controller_function(L_NODES)
    yv_rest = (mv.p_veh[-1], eq_point.vehicle[2])

    def u_of(v):
        y, xc = v[:10], v[10:]
        W = xc[:4 * L_NODES].reshape((L_NODES, 4), order="F")
        out = ctrl(y, [yv_rest[0], 0.0, yv_rest[1]], mv.ref, W, xc[4 * L_NODES:],
                   mv.p_quad, mv.p_ctrl)
        return np.asarray(out[0]).ravel()

    fd = _fd_jacobian(u_of, np.r_[xr, eq_point.xc], range(10 + 4 * L_NODES + 4))
    np.testing.assert_allclose(models.controller.D, fd[:, :10], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(models.controller.C, fd[:, 10:], rtol=1e-6, atol=1e-6)


def test_broken_loops_are_minus_KP_and_minus_PK(small, eq_point):
    models = linear_models(small, eq_point)
    w = np.array([0.03, 0.7, 4.0, 30.0])
    P = freqresp(models.plant, w)
    K = freqresp(models.controller, w)
    for G, ref in ((freqresp(models.loop_input, w), -K @ P),
                   (freqresp(models.loop_output, w), -P @ K)):
        scale = np.abs(ref).max(axis=(1, 2))
        assert np.all(np.abs(G - ref).max(axis=(1, 2)) <= 1e-9 * scale)
    # closing L_i with negative feedback gives the closed loop's poles
    p1 = np.sort_complex(closed_loop_poles(models.loop_input))
    p2 = np.sort_complex(np.linalg.eigvals(models.closed_loop.A))
    np.testing.assert_allclose(p1, p2, atol=1e-7)


def test_sampled_models_are_zero_order_holds(small, eq_point):
    plain = small.replace(**{"controller.hold_compensation": 0.0})
    models = linear_models(plain, eq_point)
    sampled = sampled_models(plain, eq_point, 50.0, delay_periods=0)
    ref = control.sample_system(models.plant, 0.02, method="zoh")
    np.testing.assert_allclose(sampled.plant.A, ref.A, atol=1e-12)
    np.testing.assert_allclose(sampled.plant.B, ref.B, atol=1e-12)
    ref_k = control.sample_system(models.controller, 0.02, method="zoh")
    np.testing.assert_allclose(sampled.controller.A, ref_k.A, atol=1e-12)
    np.testing.assert_allclose(sampled.controller.B, ref_k.B, atol=1e-12)
    assert sampled.loop_input.dt == 0.02


def test_newton_failure_is_reported(small):
    with pytest.raises(OperatingPointError, match="did not converge"):
        paper_equilibrium(small, max_iter=1, tol=1e-300)


def test_sampled_controller_extrapolates_by_the_hold_compensation(small, eq_point):
    """K_comp(z) = (1 + kappa - kappa / z) K_zoh(z).

    The step commands u = u_law + kappa (u_law - u_prev).
    """
    kappa = 0.5
    plain = sampled_models(small.replace(**{"controller.hold_compensation": 0.0}), eq_point, 50.0,
                           delay_periods=0)
    comp = sampled_models(small.replace(**{"controller.hold_compensation": kappa}), eq_point, 50.0,
                          delay_periods=0)
    assert comp.controller.nstates == plain.controller.nstates + 4
    w = np.array([0.1, 3.0, 40.0, 150.0])
    z = np.exp(1j * w * 0.02)
    want = (1 + kappa - kappa / z)[:, None, None] * freqresp(plain.controller, w)
    got = freqresp(comp.controller, w)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


@pytest.mark.parametrize("kappa", [0.0, 0.5])
@pytest.mark.parametrize("periods", [1, 2])
def test_computation_delay_holds_the_command(small, eq_point, kappa, periods):
    """K_delayed(z) = z^-periods K(z): the command computed at t_k acts from t_k+periods.

    Checked in the time domain: the delayed controller's impulse response is the
    prompt one's shifted by ``periods`` samples."""
    sc = small.replace(**{"controller.hold_compensation": kappa})
    prompt = sampled_models(sc, eq_point, 50.0, delay_periods=0).controller
    late = sampled_models(sc, eq_point, 50.0, delay_periods=periods)
    assert late.delay_periods == periods
    assert late.controller.nstates == prompt.nstates + 4 * periods
    assert late.controller.state_labels[-4:] == [f"u_delay{periods}[{k}]" for k in range(4)]
    n = 12
    timepts = np.arange(n) * 0.02
    for j in (0, 3, 7):
        u = np.zeros((10, n))
        u[j, 0] = 1.0
        y0 = control.forced_response(prompt, timepts, u).outputs
        y1 = control.forced_response(late.controller, timepts, u).outputs
        np.testing.assert_array_equal(y1[:, :periods], 0.0)
        np.testing.assert_allclose(y1[:, periods:], y0[:, :n - periods], rtol=1e-12,
                                   atol=1e-12 * np.abs(y0).max())

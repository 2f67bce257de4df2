"""Backstepping law (eq. 9-22) checked along simulated trajectories."""

import numpy as np
import pytest
from reference import error_rate_matrix

from quadland.kinds.paper.values import model_values
from quadland.scenario import load_scenario
from quadland.simulation import simulate
from quadland_symbolic.backstepping import controller_function, lyapunov_function
from quadland_symbolic.closed_loop import closed_loop_state, vehicle_measurement


@pytest.fixture(scope="module")
def fine_run():
    """1 kHz samples of the first 0.6 s (the fast transient), noise off."""
    sc = load_scenario("paper", ["simulation.duration=0.6", "simulation.output_rate_hz=1000",
                                 "disturbance.noise=false", "simulation.integrator=\"cvodes\"",
                                 "simulation.reltol=1e-12", "simulation.abstol=1e-12"])
    return sc, simulate(sc)


def _controller_signals(sc, res):
    mv = model_values(sc)
    ctrl = controller_function(mv.l).map(len(res["t"]))
    lay = closed_loop_state(mv.l)
    X = res.states.T
    assert lay.size == X.shape[0]
    xs = lay.unpack(X)
    yv = np.hstack([np.asarray(vehicle_measurement(xs["xv"][:, k], mv.p_veh))
                    for k in range(X.shape[1])])
    # the mapped function takes W_hat as l x 4 blocks side by side
    W_blocks = np.hstack([xs["W_hat"][:, :, k] for k in range(X.shape[1])])
    out = ctrl(xs["xq"], yv, mv.ref, W_blocks, xs["zeta_hat"], mv.p_quad, mv.p_ctrl)
    names = controller_function(mv.l).name_out()
    return {n: np.array(v) for n, v in zip(names, out, strict=True)}


def test_alpha_dot_matches_finite_difference(fine_run):
    """alpha_dot of eq. (18), formed symbolically, against a central difference of alpha."""
    sc, res = fine_run
    sig = _controller_signals(sc, res)
    t, alpha, alpha_dot = res["t"], sig["alpha"], sig["alpha_dot"]
    h = t[1] - t[0]
    fd = (alpha[:, 2:] - alpha[:, :-2]) / (2 * h)
    scale = np.abs(alpha_dot[:, 1:-1]).max(axis=1, keepdims=True)
    err = np.abs(fd - alpha_dot[:, 1:-1]) / scale
    assert err.max() < 2e-4        # O(h^2) with h = 1 ms against alpha_ddot ~ 1e2 scale


def test_error_definitions(fine_run):
    """z1 = e1 - e1d and z2 = e2 - alpha (eq. 9); alpha = R^-1(-k1 z1) with e1d = 0."""
    sc, res = fine_run
    sig = _controller_signals(sc, res)
    e1 = np.vstack([res[n] for n in ("z_e", "phi_e", "theta_e", "psi_e")])
    e2 = np.vstack([res[n] for n in ("dz_e", "p_e", "q_e", "r_e")])
    np.testing.assert_allclose(sig["bs_z1"], e1, atol=1e-14)
    np.testing.assert_allclose(sig["bs_z2"], e2 - sig["alpha"], atol=1e-12)
    k1 = np.array(sc["controller.k1"])
    k = 200
    R = error_rate_matrix(e1[1, k], e1[2, k])
    np.testing.assert_allclose(sig["alpha"][:, k], np.linalg.solve(R, -k1 * e1[:, k]), rtol=1e-12)


def test_lyapunov_v1_decreases_while_far(fine_run):
    """V1 = z1'z1/2 (eq. 12) falls over the transient, as eq. (15) predicts when z2 is small
    relative to k1 z1; checked as an overall drop rather than monotonicity."""
    sc, res = fine_run
    lyap = lyapunov_function(model_values(sc).l)
    sig = _controller_signals(sc, res)
    V1_start = float(lyap(sig["bs_z1"][:, 0], sig["bs_z2"][:, 0], 0, 0, 1, 1)[0])
    np.testing.assert_allclose(V1_start, 0.5 * np.sum(sig["bs_z1"][:, 0] ** 2))
    assert res["lyapunov_V1"][-1] < 0.5 * res["lyapunov_V1"][0]


def test_adaptive_law_by_hand(values, rng):
    """W_hat_dot = gamma1 (Psi z2' - k_w W_hat) and
    zeta_hat_dot = gamma2 (tanh(z2/rho) z2 - k_zeta zeta_hat) (eq. 22)."""
    l = values.l
    ctrl = controller_function(l)
    xq = np.concatenate([[1.0], rng.uniform(-0.5, 0.5, 3), rng.normal(size=6)])
    W, zeta = rng.normal(size=(l, 4)) * 0.1, rng.normal(size=4)
    out = dict(zip(ctrl.name_out(), ctrl(xq, [0, 0.3, 0.05], values.ref, W, zeta,
                                          values.p_quad, values.p_ctrl), strict=True))
    Psi, z2 = np.array(out["Psi"]).ravel(), np.array(out["bs_z2"]).ravel()
    g1, g2, kw, kz, rho = 0.05, 0.1, 5.0, 0.1, 0.1
    np.testing.assert_allclose(np.array(out["W_hat_dot"]), g1 * (np.outer(Psi, z2) - kw * W),
                               atol=1e-14)
    np.testing.assert_allclose(np.array(out["zeta_hat_dot"]).ravel(),
                               g2 * (np.tanh(z2 / rho) * z2 - kz * zeta), atol=1e-14)
    np.testing.assert_allclose(np.array(out["Delta_hat"]).ravel(), W.T @ Psi, atol=1e-14)


@pytest.mark.parametrize("nominal", [0.0, 1.0])
def test_control_law_by_hand(values, rng, nominal):
    """u of eq. (20), assembled here from its printed terms (plus -f_nominal when enabled)."""
    from quadland_symbolic.parameters import QUADROTOR, controller_layout

    l = values.l
    ctrl = controller_function(l)
    p_ctrl = values.p_ctrl.copy()
    lay = controller_layout(l)
    a, _ = lay.offsets()["nominal_model"]
    p_ctrl[a] = nominal
    xq = np.concatenate([[0.8], rng.uniform(-0.5, 0.5, 3), rng.normal(size=6)])
    yv = np.array([0.1, 0.2, 0.07])
    W, zeta = rng.normal(size=(l, 4)) * 0.1, rng.normal(size=4)
    values_out = ctrl(xq, yv, values.ref, W, zeta, values.p_quad, p_ctrl)
    out = {k: np.array(v) for k, v in zip(ctrl.name_out(), values_out, strict=True)}
    z1, z2, Psi = out["bs_z1"].ravel(), out["bs_z2"].ravel(), out["Psi"].ravel()
    k2, rho = np.array([2.0, 4, 10, 10]), 0.1
    phi, th = xq[1], xq[2]
    R = error_rate_matrix(phi, th)
    q = QUADROTOR.unpack(values.p_quad)
    I, m1, g = q["I"], q["m1"][0], q["g"][0]
    V, Om = xq[4:7], xq[7:10]
    J = np.array([-np.sin(th), np.cos(th) * np.sin(phi), np.cos(th) * np.cos(phi)])
    f_nom = np.concatenate([[-(J @ (q["Kt"] * V)) / m1 - g],
                            -q["Kr"] * Om / I - np.cross(Om, I * Om) / I])
    u = (-k2 * z2 - R.T @ z1 - W.T @ Psi - np.tanh(z2 / rho) * zeta
         + out["alpha_dot"].ravel() - nominal * f_nom)
    np.testing.assert_allclose(out["u"].ravel(), u, rtol=1e-12, atol=1e-12)
    # the wrench realises u (eq. 6)
    wrench = out["wrench"].ravel()
    np.testing.assert_allclose(np.cos(th) * np.cos(phi) * wrench[0] / m1, u[0], rtol=1e-12)
    np.testing.assert_allclose(wrench[1:] / I, u[1:], rtol=1e-12)

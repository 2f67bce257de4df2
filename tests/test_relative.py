"""Relative model (eq. 5-7) against Newton-Euler written here from eq. (1)-(4)."""

import numpy as np
import pytest
from reference import euler_rate_matrix, rotation

from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.relative import relative_function

REL = relative_function()




def _newton_euler(xq, xv, wrench, d_F, d_M, pq, pv):
    """State derivative of quadrotor and vehicle, written from eq. (1)-(4) with numpy."""
    m, I, Kt, Kr, g = pq["m1"][0], pq["I"], pq["Kt"], pq["Kr"], pq["g"][0]
    eta, V, Om = xq[1:4], xq[4:7], xq[7:10]
    R = rotation(eta)
    W = euler_rate_matrix(eta[0], eta[1])
    F = np.array([0, 0, wrench[0]])
    V_dot = (F - Kt * V - m * R.T @ np.array([0, 0, g]) + d_F) / m - np.cross(Om, V)
    Om_dot = (wrench[1:] - Kr * Om + d_M - np.cross(Om, I * Om)) / I
    xq_dot = np.concatenate([[R[2] @ V], W @ Om, V_dot, Om_dot])
    psi2, u2, v2, r2 = xv[2:6]
    m11, m22, m33 = pv["m11"][0], pv["m22"][0], pv["m33"][0]
    tx, ty, tz = pv["tau"]
    xv_dot = np.array([
        np.cos(psi2) * u2 - np.sin(psi2) * v2, np.sin(psi2) * u2 + np.cos(psi2) * v2, r2,
        (tx + m22 * v2 * r2 - pv["d11"][0] * u2) / m11,
        (ty - m11 * u2 * r2 - pv["d22"][0] * v2) / m22,
        # C2 V2 = (m22 v2 u2 - m11 u2 v2)
        (tz - m22 * v2 * u2 + m11 * u2 * v2 - pv["d33"][0] * r2) / m33])
    return xq_dot, xv_dot


def _relative_states(xq, xv, z2):
    """e1, e2 of eq. (5), written here."""
    phi, th = xq[1], xq[2]
    Winv = np.array([[1, 0, -np.sin(th)],
                     [0, np.cos(phi), np.sin(phi) * np.cos(th)],
                     [0, -np.sin(phi), np.cos(phi) * np.cos(th)]])
    e1 = np.array([xq[0] - z2, xq[1], xq[2], xq[3] - xv[2]])
    e2 = np.concatenate([[rotation(xq[1:4])[2] @ xq[4:7]], xq[7:10] - Winv @ [0, 0, xv[5]]])
    return e1, e2


@pytest.mark.parametrize("seed", range(8))
def test_relative_dynamics_against_newton_euler(values, seed):
    """e2_dot by a central difference along the Newton-Euler flow equals f + u + d."""
    rng = np.random.default_rng(seed)
    pv_vec = values.p_veh.copy()
    pv_vec[1] = 80.0                                          # m22 != m11 exercises C2
    pq, pv = QUADROTOR.unpack(values.p_quad), VEHICLE.unpack(pv_vec)
    xq = np.concatenate([[rng.normal()], rng.uniform(-1.0, 1.0, 3), rng.normal(size=6)])
    xv = np.concatenate([rng.normal(size=2), rng.uniform(-3, 3, 1), rng.normal(size=3)])
    wrench = rng.normal(size=4) * [20, 1, 1, 1]
    d_F, d_M = rng.normal(size=3), rng.normal(size=3) * 0.1
    xq_dot, xv_dot = _newton_euler(xq, xv, wrench, d_F, d_M, pq, pv)
    h = 1e-5
    z2 = pv["z2"][0]
    e1p, e2p = _relative_states(xq + h * xq_dot, xv + h * xv_dot, z2)
    e1m, e2m = _relative_states(xq - h * xq_dot, xv - h * xv_dot, z2)
    e2_dot_fd = (e2p - e2m) / (2 * h)
    e1_dot_fd = (e1p - e1m) / (2 * h)
    yv = [z2, xv[2], xv[5]]
    e1, e2, R, f, u, d = (np.array(v)
                          for v in REL(xq, xv, yv, wrench, d_F, d_M, values.p_quad, pv_vec))
    np.testing.assert_allclose((f + u + d).ravel(), e2_dot_fd, rtol=1e-6, atol=1e-7)
    # d/dt e1 = R e2 (eq. 10)
    np.testing.assert_allclose((R @ e2).ravel(), e1_dot_fd, rtol=1e-6, atol=1e-7)
    e1_ref, e2_ref = _relative_states(xq, xv, z2)
    np.testing.assert_allclose(e1.ravel(), e1_ref, atol=1e-14)
    np.testing.assert_allclose(e2.ravel(), e2_ref, atol=1e-14)


def test_virtual_input_by_hand(values):
    """u1 = cos(theta) cos(phi) F / m1, u_{2..4} = M / I (eq. 6)."""
    pq = QUADROTOR.unpack(values.p_quad)
    xq = np.zeros(10)
    xq[1:3] = [0.2, -0.3]
    wrench = [25.0, 1.0, -2.0, 0.5]
    u = np.array(REL(xq, np.zeros(6), np.zeros(3), wrench, np.zeros(3), np.zeros(3),
                     values.p_quad, values.p_veh)[4]).ravel()
    np.testing.assert_allclose(u, [np.cos(0.2) * np.cos(-0.3) * 25.0 / pq["m1"][0],
                                   *(np.array(wrench[1:]) / pq["I"])], rtol=1e-14)

"""Frames and kinematics (eq. 1, 3) against independent constructions."""

import casadi as ca
import numpy as np
import pytest

from quadland_symbolic.kinematics import kinematics_function

KIN = kinematics_function()


def _euler_zyx(phi, theta, psi):
    """Rz(psi) Ry(theta) Rx(phi) by elementary rotations (independent of symbolic/)."""
    def rot(axis, a):
        c, s = np.cos(a), np.sin(a)
        i, j = [(1, 2), (2, 0), (0, 1)][axis]
        m = np.eye(3)
        m[i, i] = m[j, j] = c
        m[i, j], m[j, i] = -s, s
        return m
    return rot(2, psi) @ rot(1, theta) @ rot(0, phi)


@pytest.mark.parametrize("seed", range(5))
def test_rotation_and_vertical_row(seed):
    rng = np.random.default_rng(seed)
    eta = rng.uniform(-1.2, 1.2, 3)
    R, Rr, Rr_inv, J, _ = (np.array(v) for v in KIN(eta, np.zeros(3)))
    R_ref = _euler_zyx(*eta)
    np.testing.assert_allclose(R, R_ref, atol=1e-14)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(J.ravel(), R_ref[2], atol=1e-14)     # J = last row of R
    np.testing.assert_allclose(Rr @ Rr_inv, np.eye(3), atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_euler_rates_match_rotation_derivative(seed):
    """eta_dot = Rr Omega reproduces R_dot = R S(Omega) (finite difference)."""
    rng = np.random.default_rng(seed)
    eta, Omega = rng.uniform(-1.0, 1.0, 3), rng.normal(size=3)
    R, Rr, _, _, S = (np.array(v) for v in KIN(eta, Omega))
    eta_dot = Rr @ Omega
    h = 1e-6
    R_dot = (_euler_zyx(*(eta + h * eta_dot)) - _euler_zyx(*(eta - h * eta_dot))) / (2 * h)
    np.testing.assert_allclose(R_dot, R @ S, atol=1e-8)
    np.testing.assert_allclose(S @ Omega, np.zeros(3), atol=1e-15)
    v = rng.normal(size=3)
    np.testing.assert_allclose(S @ v, np.cross(Omega, v), atol=1e-14)


def test_vertical_row_derivative_is_J_S():
    """J_dot = J S(Omega) (stated under eq. 1)."""
    eta, Omega = np.array([0.3, -0.4, 1.1]), np.array([0.7, -0.2, 0.5])
    _, Rr, _, J, S = (np.array(v) for v in KIN(eta, Omega))
    h = 1e-6
    eta_dot = Rr @ Omega
    Jp = np.array(KIN(eta + h * eta_dot, Omega)[3])
    Jm = np.array(KIN(eta - h * eta_dot, Omega)[3])
    np.testing.assert_allclose((Jp - Jm) / (2 * h), J @ S, atol=1e-8)


def test_kinematics_function_is_named():
    assert KIN.name() == "kinematics"
    assert KIN.name_out() == ["R", "Rr", "Rr_inv", "J", "S"]
    assert isinstance(KIN, ca.Function)

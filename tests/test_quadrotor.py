"""Quadrotor rigid-body model (eq. 2) and mixer."""

import numpy as np
import pytest

from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import mixer_function, quadrotor_function

QUAD = quadrotor_function()
MIX = mixer_function()


def test_hover_is_an_equilibrium(values):
    m1, g = values.p_quad[0], QUADROTOR.unpack(values.p_quad)["g"][0]
    xq = np.zeros(10)
    xq[0] = 3.0
    xq[3] = 0.7                                      # any yaw
    xdot = np.array(QUAD(xq, [m1 * g, 0, 0, 0], np.zeros(3), np.zeros(3), values.p_quad))
    np.testing.assert_allclose(xdot, 0.0, atol=1e-14)


def test_free_fall_and_drag(values):
    """Level, no thrust: w_dot = -g - Kt3 w / m1 and z_dot = w."""
    p = QUADROTOR.unpack(values.p_quad)
    xq = np.zeros(10)
    xq[6] = -2.0
    xdot = np.array(QUAD(xq, np.zeros(4), np.zeros(3), np.zeros(3), values.p_quad)).ravel()
    assert xdot[0] == pytest.approx(-2.0)
    assert xdot[6] == pytest.approx(-p["g"][0] + p["Kt"][2] * 2.0 / p["m1"][0])


def test_euler_equation_by_hand(values):
    """Omega_dot = I^-1 (T - Kr Omega - Omega x I Omega + d_M) computed here with numpy."""
    p = QUADROTOR.unpack(values.p_quad)
    rng = np.random.default_rng(3)
    xq = rng.normal(size=10) * 0.5
    wrench, d_M = rng.normal(size=4), rng.normal(size=3)
    I, Kr, Om = p["I"], p["Kr"], xq[7:10]
    expected = (wrench[1:] - Kr * Om - np.cross(Om, I * Om) + d_M) / I
    xdot = np.array(QUAD(xq, wrench, np.zeros(3), d_M, values.p_quad)).ravel()
    np.testing.assert_allclose(xdot[7:10], expected, rtol=1e-13)


def test_mixer_inverse(values, rng):
    for _ in range(5):
        rotor = rng.uniform(0, 20, 4)
        wrench, back = (np.array(v).ravel() for v in MIX(rotor, np.zeros(4), values.p_quad))
        _, rotor_back = (np.array(v).ravel() for v in MIX(np.zeros(4), wrench, values.p_quad))
        np.testing.assert_allclose(rotor_back, rotor, rtol=1e-13)


def test_mixer_by_hand(values):
    """Thrust alone splits evenly; a roll moment is a differential pair F2 - F4."""
    p = QUADROTOR.unpack(values.p_quad)
    d, c = p["arm"][0], p["c"][0]
    rotor = np.array(MIX(np.zeros(4), [20.0, 0, 0, 0], values.p_quad)[1]).ravel()
    np.testing.assert_allclose(rotor, [5, 5, 5, 5])
    rotor = np.array(MIX(np.zeros(4), [0, 1.0, 0, 0], values.p_quad)[1]).ravel()
    np.testing.assert_allclose(rotor, [0, 1 / (2 * d), 0, -1 / (2 * d)])
    wrench = np.array(MIX([1.0, 0, 0, 0], np.zeros(4), values.p_quad)[0]).ravel()
    np.testing.assert_allclose(wrench, [1, 0, -d, c])

"""The GNSS-aided attitude model (``sensors.imu.attitude_gnss_aided``) against an
independent derivation.

A navigation filter that corrects its attitude with GNSS velocity levels the
accelerometer it integrates: in steady flight its velocity stays on the GNSS's only if
its attitude rotates the biased specific force onto the vertical, so its roll and pitch
settle at the horizontal accelerometer bias over g (docs/sensors.md). The model draws
that tilt from the IMU's own drawn bias, ``[b_a_y, -b_a_x, 0] / g``, plus the
Gauss-Markov residual of ``attitude_sigma``. Checked here against a second model: a
velocity-aided levelling loop simulated on rotation matrices (its own ZYX rotation, its
own gains), whose steady state is also solved in closed form.
"""

import math

import numpy as np
import pytest
from hand_rotations import Rx, Ry, Rz

from quadland.exceptions import ScenarioError
from quadland.kinds.landing.sensing import draw_sensors
from quadland.kinds.landing.sensor_settings import STANDARD_GRAVITY, validate_settings
from quadland_symbolic.landing.navigation import acceleration_input

G = STANDARD_GRAVITY
AIDED = {"attitude_gnss_aided": True}
NO_RESIDUAL = {"attitude_gnss_aided": True, "attitude_sigma": [0.0, 0.0, 0.0],
               "attitude_white_sigma": 0.0}





def skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def rotation_of(w):
    """``exp([w x])`` by Rodrigues' formula."""
    a = np.linalg.norm(w)
    if a == 0.0:
        return np.eye(3)
    K = skew(w / a)
    return np.eye(3) + math.sin(a) * K + (1 - math.cos(a)) * K @ K


def zyx_angles(R):
    """Roll, pitch, yaw of ``R = Rz(psi) Ry(theta) Rx(phi)``."""
    return np.array([math.atan2(R[2, 1], R[2, 2]), -math.asin(R[2, 0]),
                     math.atan2(R[1, 0], R[0, 0])])


def levelling_loop(b, psi, seconds=80.0, dt=0.01, omega=0.4, zeta=0.8):
    """A velocity-aided levelling loop in a level hover at heading ``psi``: the
    accelerometer reads ``g e_z + b`` (body axes), the GNSS velocity is zero and the
    gyros are perfect. The filter integrates ``v' = R_hat f_b - g e_z - k1 v`` and turns
    its attitude by ``R_hat' = [w x] R_hat``, ``w = -k2 (e_z x v) / g`` (E axes), the
    gains of a second-order loop at ``omega`` rad/s. Returns the settled ``R_hat``."""
    k1, k2 = 2 * zeta * omega, omega ** 2
    ez, f_b = np.array([0.0, 0.0, 1.0]), G * np.array([0.0, 0.0, 1.0]) + b
    R_hat, v = Rz(psi), np.zeros(3)
    for _ in range(round(seconds / dt)):
        v = v + dt * (R_hat @ f_b - G * ez - k1 * v)
        R_hat = rotation_of(-k2 * np.cross(ez, v) / G * dt) @ R_hat
    return R_hat


def test_switched_off_the_draws_are_the_ahrs_s_bit_for_bit():
    ahrs = draw_sensors(None, 3.0, seed=11)
    off = draw_sensors({"imu": {"attitude_gnss_aided": False}}, 3.0, seed=11)
    for name in ahrs:
        np.testing.assert_array_equal(off[name].noise, ahrs[name].noise)


def test_aided_adds_the_bias_over_g_to_the_same_residual():
    """Every column but ``e_att`` is the AHRS draw's; ``e_att`` is the AHRS draw's (the
    same residual process) plus ``[b_a_y, -b_a_x, 0] / g`` of the same IMU sample, and
    the camera and rangefinder read the IMU's value at its instants."""
    ahrs, aided = draw_sensors(None, 3.0, seed=5), draw_sensors({"imu": AIDED}, 3.0, seed=5)
    imu0, imu1 = ahrs["imu"], aided["imu"]
    for f in ("b_a", "n_a", "b_g", "n_g"):
        np.testing.assert_array_equal(imu1.noise_of(f), imu0.noise_of(f))
    b = imu1.noise_of("b_a")
    level = np.column_stack([b[:, 1], -b[:, 0], np.zeros(len(b))]) / G
    np.testing.assert_allclose(imu1.noise_of("e_att") - imu0.noise_of("e_att"), level,
                               rtol=0, atol=1e-15)
    for name in ("vision", "rangefinder"):
        k = np.rint(aided[name].times * 250.0).astype(int)
        np.testing.assert_array_equal(aided[name].noise_of("e_att"), imu1.noise_of("e_att")[k])


def test_between_imu_samples_the_level_is_the_next_imu_sample_s():
    """A camera 1 ms off the IMU's grid: the residual is bridged as before, the level is
    the bias of the IMU sample after it (the bias moves 5e-5 m/s^2 in 4 ms)."""
    off = {"vision": {"phase": 0.001}}
    ahrs = draw_sensors(off, 3.0, seed=8)
    aided = draw_sensors({**off, "imu": AIDED}, 3.0, seed=8)
    k = np.ceil(aided["vision"].times * 250.0 - 1e-9).astype(int)
    b = aided["imu"].noise_of("b_a")[k]
    level = np.column_stack([b[:, 1], -b[:, 0], np.zeros(len(b))]) / G
    np.testing.assert_allclose(aided["vision"].noise_of("e_att")
                               - ahrs["vision"].noise_of("e_att"), level, rtol=0, atol=1e-15)


@pytest.mark.parametrize("seed, psi", [(3, 0.0), (17, 0.9), (29, -2.4)])
def test_velocity_aided_levelling_settles_at_the_model_s_tilt(seed, psi):
    """The loop's settled attitude (any heading) against the model's draw of the same
    bias: the loop levels the biased specific force exactly (closed form:
    ``phi = atan2(b_y, g + b_z)``, ``theta = -atan2(b_x, sqrt(b_y^2 + (g + b_z)^2))``,
    to 1e-9 rad; the loop's heading moves only at second order, under the product of the
    two tilts), and the model is its first order (``[b_y, -b_x, 0] / g``: the terms it
    drops, ``b_z / g`` and ``(b / g)^2`` of it, keep it within ``2 |b| / g`` of the loop,
    relative)."""
    draw = draw_sensors({"imu": NO_RESIDUAL}, 0.1, seed=seed)
    b, model = draw["imu"].noise_of("b_a")[0], draw["imu"].noise_of("e_att")[0]
    R_hat = levelling_loop(b, psi)
    err = zyx_angles(R_hat) - np.array([0.0, 0.0, psi])
    closed = np.array([math.atan2(b[1], G + b[2]),
                       -math.atan2(b[0], math.hypot(b[1], G + b[2])), 0.0])
    np.testing.assert_allclose(err[:2], closed[:2], rtol=0, atol=1e-9)
    np.testing.assert_allclose((R_hat @ (G * np.array([0, 0, 1.0]) + b))[:2], 0, atol=1e-8)
    assert np.max(np.abs(model)) > 1e-3
    np.testing.assert_allclose(model[:2], err[:2], rtol=2 * np.linalg.norm(b) / G, atol=0)
    assert abs(err[2]) < abs(err[0] * err[1])


def test_the_level_cancels_the_bias_in_the_filter_s_horizontal_input():
    """The estimate the model gives, ``eta_hat = eta1 + e_att``, rotates the biased
    accelerometer of a level hover (any heading) onto the vertical to second order:
    ``|R(eta_hat) (g e_z + b)|_h`` under ``2 |b|^2 / g`` (the vertical bias times the
    tilt; 2e-4 m/s^2 here), where the AHRS's, with the residual off, is the horizontal
    bias itself (above 1e-2 m/s^2 here)."""
    draw = draw_sensors({"imu": NO_RESIDUAL}, 0.1, seed=2)
    b, e = draw["imu"].noise_of("b_a")[0], draw["imu"].noise_of("e_att")[0]
    for psi in (0.0, 1.3, -2.0):
        eta_hat = np.array([0.0, 0.0, psi]) + e
        R_hat = Rz(eta_hat[2]) @ Ry(eta_hat[1]) @ Rx(eta_hat[0])
        f_b = G * np.array([0.0, 0.0, 1.0]) + b
        assert np.linalg.norm((R_hat @ f_b)[:2]) < 2 * np.dot(b, b) / G
        assert np.linalg.norm((Rz(psi) @ f_b)[:2]) > 1e-2


def test_the_switch_is_a_boolean():
    assert validate_settings("imu", AIDED)["attitude_gnss_aided"] is True
    assert validate_settings("imu")["attitude_gnss_aided"] is False
    with pytest.raises(ScenarioError, match="attitude_gnss_aided"):
        validate_settings("imu", {"attitude_gnss_aided": 1})


def test_the_filter_s_own_input_sees_the_bias_cancelled():
    """The same cancellation through the project's own code rather than this file's
    rotations: the navigation filter's input ``acceleration_input(eta_hat, f_b, g)``
    (``quadland_symbolic``'s ``rotation``, the convention ``sense_imu`` applies ``e_att``
    in) with ``eta_hat = eta1 + e_att`` and the level hover's ``f_b = g e_z + b_a``: its
    horizontal part is second order in the bias; the opposite sign would double it."""
    draw = draw_sensors({"imu": NO_RESIDUAL}, 0.1, seed=4)
    b, e = draw["imu"].noise_of("b_a")[0], draw["imu"].noise_of("e_att")[0]
    f_b = G * np.array([0.0, 0.0, 1.0]) + b
    for psi in (0.0, 0.8, -2.6):
        eta1 = np.array([0.0, 0.0, psi])
        a_in = np.array(acceleration_input(eta1 + e, f_b, G)).ravel()
        flipped = np.array(acceleration_input(eta1 - e, f_b, G)).ravel()
        assert np.linalg.norm(a_in[:2]) < 2 * np.dot(b, b) / G
        assert np.linalg.norm(flipped[:2]) == pytest.approx(2 * np.linalg.norm(b[:2]),
                                                             rel=2 * np.linalg.norm(b) / G)

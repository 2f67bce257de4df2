"""The moving-baseline RTK pair (``sensors.gnss.relative_rtk``) against the statistics of the
process it draws and against the receivers' draws of before.

With the key the relative position's error is white, ``relative_sigma`` per axis per fix,
and the quadrotor receiver's error is zero; the velocities' noise is the receivers' as
before. Off (the default, and every shipped scenario) the draws are the Gauss-Markov
receivers' to the bit.
"""

import numpy as np
import pytest
from scipy import stats

from quadland.engine.noise import gauss_markov
from quadland.exceptions import ScenarioError
from quadland.kinds.landing.sensed import sensor_settings
from quadland.kinds.landing.sensing import draw_sensors
from quadland.kinds.landing.sensor_settings import SENSOR_DEFAULTS
from quadland.scenario import load_scenario
from quadland_symbolic.landing.sensors import NOISES

LAYOUT = NOISES["gnss"]
ON = ["sensors.gnss.relative_rtk=true"]


def _gnss(overrides, duration, seed):
    return draw_sensors(sensor_settings(load_scenario("ship", overrides)), duration,
                        seed)["gnss"]


def test_the_default_is_off_and_the_receivers_draws_are_those_of_before():
    """A scenario that leaves the key out flies it false: the same draws as an explicit
    false, and its e_t the Gauss-Markov receiver's (its first sample the stationary
    ``sigma n_0``, the ratio of two samples the closed-form decay up to the new normal)."""
    assert SENSOR_DEFAULTS["gnss"]["relative_rtk"] is False
    a = _gnss([], 20.0, 5)
    b = _gnss(["sensors.gnss.relative_rtk=false"], 20.0, 5)
    np.testing.assert_array_equal(a.noise, b.noise)
    assert np.all(np.abs(a.noise[:, LAYOUT.slice("e_q")]) > 0.0)
    # the pad receiver's e_t by hand: the normals are the on-key draw's over relative_sigma
    # (the same seeded normals), the recursion the exact Gauss-Markov discretization
    on = _gnss(ON, 20.0, 5)
    np.testing.assert_array_equal(on.times, a.times)
    normals = on.noise[:, LAYOUT.slice("e_t")] / np.asarray(
        SENSOR_DEFAULTS["gnss"]["relative_sigma"])
    s = sensor_settings(load_scenario("ship"))["gnss"]
    sigma, tau = np.asarray(s["position_sigma"]), s["position_tau"]
    expected = np.empty_like(normals)
    expected[0] = sigma * normals[0]
    for k in range(1, len(normals)):
        phi = np.exp(-(a.times[k] - a.times[k - 1]) / tau)
        expected[k] = phi * expected[k - 1] + sigma * np.sqrt(1.0 - phi * phi) * normals[k]
    np.testing.assert_allclose(a.noise[:, LAYOUT.slice("e_t")], expected, rtol=1e-9,
                               atol=1e-12)


def test_the_relative_error_is_white_with_relative_sigma_per_axis():
    """Over 2000 s at 5 Hz: e_q is zero; each axis of e_t has the variance of
    ``relative_sigma`` (the sample variance's chi-square interval at 1e-6 each side) and no
    correlation from one fix to the next (|lag-1 autocorrelation| within 5 / sqrt(n), its
    normal approximation); the velocities' noise is the one the receivers draw without the
    key, the same normals."""
    on, off = _gnss(ON, 2000.0, 11), _gnss([], 2000.0, 11)
    sigma = np.asarray(SENSOR_DEFAULTS["gnss"]["relative_sigma"])
    np.testing.assert_allclose(sigma, [0.01 / 1.1774, 0.01 / 1.1774, 1.9 * 0.01 / 1.1774])
    e_q, e_t = on.noise[:, LAYOUT.slice("e_q")], on.noise[:, LAYOUT.slice("e_t")]
    assert np.all(e_q == 0.0)
    n = e_t.shape[0]
    assert n > 9000
    lo, hi = stats.chi2.ppf([1e-6, 1.0 - 1e-6], n - 1) / (n - 1)
    var = e_t.var(axis=0, ddof=1) / sigma ** 2
    assert np.all((lo < var) & (var < hi)), var
    assert np.all(np.abs(e_t.mean(axis=0) / sigma) < 5.0 / np.sqrt(n))
    x = (e_t - e_t.mean(axis=0)) / e_t.std(axis=0)
    lag1 = np.mean(x[1:] * x[:-1], axis=0)
    assert np.all(np.abs(lag1) < 5.0 / np.sqrt(n)), lag1
    for name in ("n_v1", "n_vt"):
        np.testing.assert_array_equal(on.noise[:, LAYOUT.slice(name)],
                                      off.noise[:, LAYOUT.slice(name)])


def test_relative_sigma_scales_the_same_normals_and_a_zero_sigma_is_the_truth():
    """The error is linear in ``relative_sigma``: doubling it doubles every draw (the same
    seeded normals); zero gives the true relative position. Against gauss_markov with
    tau = 0 (its documented white case), computed apart on the recovered normals."""
    a = _gnss(ON, 30.0, 3).noise[:, LAYOUT.slice("e_t")]
    b = _gnss(ON + ["sensors.gnss.relative_sigma=[0.017, 0.017, 0.032]"], 30.0,
              3).noise[:, LAYOUT.slice("e_t")]
    sigma = np.asarray(SENSOR_DEFAULTS["gnss"]["relative_sigma"])
    normals = a / sigma
    np.testing.assert_allclose(b, normals * [0.017, 0.017, 0.032], rtol=1e-12)
    t = np.arange(a.shape[0]) * 0.2
    np.testing.assert_allclose(gauss_markov(t, sigma, 0.0, normals), a, rtol=1e-12)
    zero = _gnss(ON + ["sensors.gnss.relative_sigma=[0.0, 0.0, 0.0]"], 30.0, 3)
    assert np.all(zero.noise[:, LAYOUT.slice("e_t")] == 0.0)


@pytest.mark.parametrize("value, message", [
    ("[-0.01, 0.01, 0.01]", "sensors.gnss.relative_sigma: must be in"),
    ("[0.01, 0.01]", "sensors.gnss.relative_sigma: expected a list of 3 numbers"),
    ("[nan, 0.01, 0.01]", "sensors.gnss.relative_sigma: must be finite"),
])
def test_a_bad_relative_sigma_is_refused(value, message):
    with pytest.raises(ScenarioError, match=message):
        _gnss(ON + [f"sensors.gnss.relative_sigma={value}"], 1.0, 1)


def test_relative_rtk_must_be_a_boolean():
    with pytest.raises(ScenarioError, match="sensors.gnss.relative_rtk: expected true or false"):
        _gnss(["sensors.gnss.relative_rtk=2"], 1.0, 1)

"""Wind: Dryden turbulence statistics against the spectrum, the 1-cosine gust's shape."""

import math

import numpy as np
import pytest

from quadland.engine.wind import (
    FT,
    DrydenTurbulence,
    OneCosineGust,
    dryden_low_altitude,
    gust_samples,
    turbulence_samples,
)


def test_low_altitude_scales_against_the_standard_by_hand():
    # h = 50 ft: 0.177 + 0.000823 * 50 = 0.21815
    d = dryden_low_altitude(7.7, 50 * FT, 14.0)
    base = 0.177 + 0.000823 * 50
    assert d.sigma[2] == pytest.approx(0.77)
    assert d.sigma[0] == pytest.approx(0.77 / base ** 0.4)
    assert d.scale[2] == pytest.approx(50 * FT)
    assert d.scale[0] == pytest.approx(50 / base ** 1.2 * FT)


def test_turbulence_has_the_spectrum_s_variance_and_correlation():
    """A first-order Dryden process has variance sigma^2 and autocorrelation
    exp(-V tau / L); measured on 200,000 samples (statistical error ~1 %)."""
    turb = DrydenTurbulence((1.5, 0.8, 0.5), (20.0, 20.0, 5.0), 10.0)
    dt = 0.01
    times = dt * np.arange(200_000)
    v = turbulence_samples(turb, times, np.random.default_rng(3))
    for axis in range(3):
        u = v[axis]
        sigma, L = turb.sigma[axis], turb.scale[axis]
        assert np.std(u) == pytest.approx(sigma, rel=0.05)
        for lag_s in (0.1, 0.5, 1.0):
            k = int(round(lag_s / dt))
            r = np.mean(u[:-k] * u[k:]) / np.var(u)
            assert r == pytest.approx(math.exp(-turb.airspeed * lag_s / L), abs=0.05)


def test_turbulence_is_repeated_by_its_seed():
    turb = dryden_low_altitude(7.7, 5.0, 14.0)
    t = 0.01 * np.arange(500)
    a = turbulence_samples(turb, t, np.random.default_rng(9))
    b = turbulence_samples(turb, t, np.random.default_rng(9))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - turbulence_samples(turb, t, np.random.default_rng(10))).max() > 0.1


def test_one_cosine_gust():
    g = OneCosineGust(start=2.0, half_length=1.5, amplitude=6.0, direction=(3.0, 4.0, 0.0))
    t = np.linspace(0, 8, 801)
    v = gust_samples(g, t)
    speed = v[0] / 0.6                                     # along the unit direction (0.6, 0.8)
    np.testing.assert_allclose(v[1], 0.8 * speed, atol=1e-12)
    np.testing.assert_array_equal(v[2], 0.0)
    assert np.all(speed[(t < 2.0) | (t > 5.0)] == 0)
    assert speed.max() == pytest.approx(6.0) and t[np.argmax(speed)] == pytest.approx(3.5)
    inside = (t >= 2.0) & (t <= 5.0)
    np.testing.assert_allclose(speed[inside], 3.0 * (1 - np.cos(np.pi * (t[inside] - 2.0) / 1.5)))


@pytest.mark.parametrize("compiled", [True, False])
def test_the_turbulence_recursion_is_scipys_lfilter_bit_for_bit(monkeypatch, compiled):
    # issue 20: scipy.signal cost most of a second to import in every landing process;
    # the recursion replacing its one call must give the same bits, in C
    # (quadland.engine.recursion) and over Python floats without a compiler
    import scipy.signal

    from quadland.engine import wind
    from quadland.engine.recursion import compiled_recursion
    from quadland.engine.wind import first_order_recursion

    if compiled:
        assert compiled_recursion() is not None
    else:
        monkeypatch.setattr(wind, "recursion", lambda *args: None)

    rng = np.random.default_rng(7)
    for a, b, n in ((0.99935, 0.0366, 4000), (0.957, 0.29, 1000), (0.0, 1.3, 10),
                    (1.0 - 1e-12, 1e-6, 100), (0.5, 2.0, 1)):
        x, u0 = rng.standard_normal(n), float(rng.standard_normal())
        ref = scipy.signal.lfilter([b], [1.0, -a], x, zi=[a * u0])[0]
        got = first_order_recursion(a, b, x, u0)
        assert got.tobytes() == ref.tobytes(), (a, b, n)
    assert first_order_recursion(0.5, 1.0, np.zeros(0), 1.0).shape == (0,)

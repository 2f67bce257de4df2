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


@pytest.mark.parametrize("compiled", [True, False])
def test_the_three_axes_in_one_call_are_scipys_lfilter_of_each_bit_for_bit(monkeypatch,
                                                                           compiled):
    # issue 20, seventeenth session: the axes' recursions share one call of the compiled
    # recursion (columns), and the normals may be handed in (an envelope keeps a
    # replicate's); each axis must still be its own first-order filter of its own draws,
    # as scipy.signal.lfilter computes it, an axis of zero intensity all +0.0

    from quadland.engine import wind

    if not compiled:
        monkeypatch.setattr(wind, "recursion", lambda *args: None)
    times = 0.01 * np.arange(4001)
    for turb in (dryden_low_altitude(7.7, 12.0, 23.4), dryden_low_altitude(0.3, 2.0, 0.05),
                 DrydenTurbulence((1.2, 0.0, 0.4), (30.0, 30.0, 3.0), 9.0)):
        normals = np.random.default_rng(5).standard_normal((len(times), 3))
        got = turbulence_samples(turb, times, np.random.default_rng(5))
        again = turbulence_samples(turb, times, normals=normals)
        assert got.shape == (3, len(times))
        assert _bits(got) == _bits(again)
        for axis in range(3):
            assert _bits(got[axis]) == _bits(_lfilter_axis(turb, axis, normals)), (turb, axis)
    assert turbulence_samples(DrydenTurbulence((1.0, 1.0, 1.0), (5.0, 5.0, 5.0), 3.0),
                              np.zeros(0), np.random.default_rng(1)).shape == (3, 0)
    one = turbulence_samples(DrydenTurbulence((1.0, 0.0, 2.0), (5.0, 5.0, 5.0), 3.0),
                             np.zeros(1), normals=np.array([[0.5, -0.7, 0.25]]))
    assert _bits(one) == _bits(np.array([[0.5], [0.0], [0.5]]))
    with pytest.raises(ValueError, match="normals of shape"):   # another count's draws
        turbulence_samples(turb, times[1:], normals=normals)


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint8).tobytes()


def _lfilter_axis(turb, axis, normals, dt=0.01):
    """One axis's turbulence on ``normals`` by scipy.signal.lfilter: the first-order
    Dryden recursion ``u_k = a u_(k-1) + b n_k`` seeded at ``sigma n_0`` (+0.0 on a still
    axis), the independent reference of the compiled and Python recursions."""
    import scipy.signal

    sigma, L = turb.sigma[axis], turb.scale[axis]
    if sigma == 0:
        return np.zeros(len(normals))
    a = math.exp(-turb.airspeed * dt / L)
    b = sigma * math.sqrt(1.0 - a * a)
    u0 = sigma * normals[0, axis]
    ref = scipy.signal.lfilter([b], [1.0, -a], normals[1:, axis], zi=[a * u0])[0]
    return np.concatenate([[u0], ref])


def test_the_three_axes_in_one_call_keep_nans_and_edge_values_as_lfilter_does(monkeypatch):
    # review of issue 20 (seventeenth session): NaN intensity on one axis, NaN and infinite
    # airspeed, a negative and subnormal intensities beside a still axis: the one compiled
    # call, the Python loop without a compiler and scipy.signal.lfilter of each axis are the
    # same bits (NaN where lfilter has NaN), the still axis +0.0

    from quadland.engine import wind

    times = 0.01 * np.arange(300)
    normals = np.random.default_rng(3).standard_normal((len(times), 3))
    compiled_call = wind.recursion
    for turb in (DrydenTurbulence((math.nan, 1.0, 0.0), (3.0, 3.0, 3.0), 5.0),
                 DrydenTurbulence((1.0, 1.0, 1.0), (3.0, 3.0, 3.0), math.nan),
                 DrydenTurbulence((1.0, 0.0, 1.0), (3.0, 3.0, 3.0), math.inf),
                 DrydenTurbulence((-1.0, 0.0, 2.0), (3.0, 3.0, 3.0), 5.0),
                 DrydenTurbulence((1e-300, 0.0, 5e-324), (3.0, 3.0, 3.0), 5.0)):
        monkeypatch.setattr(wind, "recursion", compiled_call)
        got = turbulence_samples(turb, times, normals=normals)
        monkeypatch.setattr(wind, "recursion", lambda *args: None)
        assert _bits(turbulence_samples(turb, times, normals=normals)) == _bits(got), turb
        for axis in range(3):
            assert _bits(got[axis]) == _bits(_lfilter_axis(turb, axis, normals)), (turb, axis)

"""The output predictor's oscillating deck (docs/estimator.md, E17a).

Checked against the pad's closed-form harmonic motion (NumPy's sin and cos of the
motion itself, not the predictor's factors), and at ``omega = 0`` against the
constant-acceleration predictor as it was before (its expressions copied here), bit
for bit, signs of zero included; the filter's frequency (the ratio of its averages)
against a sinusoid's own.
"""

import casadi as ca
import numpy as np
import pytest
from nav_reference import N, col, sl

from quadland_symbolic.landing.estimator import heave_frequency, output_predictor_function
from quadland_symbolic.landing.heave import heave_factors, sinc
from quadland_symbolic.landing.navigation import ESTIMATOR_DEFAULTS, NAV, estimator_params


def _pad_motion(Z, w, phi, t):
    """z, z', z'' of ``Z sin(w t + phi)``."""
    return (Z * np.sin(w * t + phi), Z * w * np.cos(w * t + phi),
            -Z * w**2 * np.sin(w * t + phi))


@pytest.mark.parametrize("w", [0.5, 0.939, 1.49, 6.0])
def test_the_pad_moves_as_the_closed_form_harmonic(w):
    """A pad heaving as ``Z sin(w t + phi)``, a quadrotor coasting with no input and no
    bias: after the buffer's periods the predictor's pad velocity and acceleration are
    the motion's at ``t0 + T`` and the relative position has lost the pad's rise; the
    horizontal target motion is the constant acceleration's."""
    rng = np.random.default_rng(19)
    n = 9
    dts = rng.uniform(0.002, 0.006, n)
    dts[3] = 0.0                                          # an empty period
    T = dts.sum()
    hist = np.vstack([np.zeros((3, n)), dts])
    Z, phi, t0 = 1.3, 0.7, 2.0
    z0, v0, a0 = _pad_motion(Z, w, phi, t0)
    zT, vT, aT = _pad_motion(Z, w, phi, t0 + T)
    x = rng.normal(size=N)
    x[sl("a_b")] = x[sl("a_tilt")] = 0.0
    x[sl("v_t")][2], x[sl("a_t")][2] = v0, a0
    x_now = col(output_predictor_function(n)(x, hist, w))
    assert x_now[sl("v_t")][2] == pytest.approx(vT, rel=1e-13, abs=1e-13)
    assert x_now[sl("a_t")][2] == pytest.approx(aT, rel=1e-13, abs=1e-13)
    rise = zT - z0
    assert x_now[sl("p_r")][2] == pytest.approx(x[sl("p_r")][2] + x[sl("v1")][2] * T - rise,
                                                rel=1e-13, abs=1e-13)
    for a in (0, 1):                                      # x, y: constant acceleration
        v, acc = x[sl("v_t")][a], x[sl("a_t")][a]
        assert x_now[sl("v_t")][a] == pytest.approx(v + T * acc, rel=1e-14)
        assert x_now[sl("a_t")][a] == acc
        assert x_now[sl("p_r")][a] == pytest.approx(
            x[sl("p_r")][a] + T * (x[sl("v1")][a] - v) - T**2 / 2 * acc, rel=1e-13, abs=1e-13)
    for name in ("v1", "b", "a_b", "a_tilt"):
        np.testing.assert_array_equal(x_now[sl(name)], x[sl(name)])


def test_a_quarter_period_turns_velocity_into_acceleration():
    """Hand derivation: over a quarter period ``omega T = pi / 2``, ``v(T) = a / omega``
    and ``a(T) = -omega v``; the rise is ``(v + a / omega) / omega``."""
    w, n = 2.0, 4
    hist = np.vstack([np.zeros((3, n)), np.full(n, np.pi / 2 / w / n)])
    x = np.zeros(N)
    x[sl("v_t")][2], x[sl("a_t")][2], x[sl("p_r")][2] = 0.3, -0.8, 1.0
    x_now = col(output_predictor_function(n)(x, hist, w))
    assert x_now[sl("v_t")][2] == pytest.approx(-0.8 / w, abs=1e-15)
    assert x_now[sl("a_t")][2] == pytest.approx(-w * 0.3, abs=1e-15)
    assert x_now[sl("p_r")][2] == pytest.approx(1.0 - (0.3 - 0.8 / w) / w, abs=1e-15)


def _old_predictor(n):
    """The constant-acceleration predictor before (E17a), its expressions as they were."""
    x_h, hist = NAV.sym("x_h"), ca.SX.sym("hist", 4, n)
    x = NAV.unpack(x_h)
    S1, S2, after = ca.DM.zeros(3), ca.DM.zeros(3), 0
    for k in reversed(range(n)):
        a_k, dt_k = hist[0:3, k], hist[3, k]
        S1 = S1 + a_k * dt_k
        S2 = S2 + a_k * (dt_k * (dt_k / 2 + after))
        after = after + dt_k
    T = after
    a_u = x["a_b"] + x["a_tilt"]
    v1 = x["v1"] + S1 - T * a_u
    p_r = x["p_r"] + T * (x["v1"] - x["v_t"]) + S2 - (T**2 / 2) * (a_u + x["a_t"])
    out = ca.vertcat(p_r, v1, x["v_t"] + T * x["a_t"], x["a_t"], x["b"], x["a_b"], x["a_tilt"])
    return ca.Function("old", [x_h, hist], [out])


@pytest.mark.parametrize("n", [0, 1, 50])
def test_a_flat_deck_is_the_constant_acceleration_to_the_bit(n):
    """``omega = 0``: the same bits as the predictor before (E17a), zeros' signs too."""
    rng = np.random.default_rng(n)
    new, old = output_predictor_function(n), _old_predictor(n)
    for trial in range(40):
        x = rng.normal(size=N) * 10.0 ** rng.integers(-6, 3, N)
        hist = np.vstack([rng.normal(size=(3, n)) * 3, rng.uniform(0, 0.005, n)])
        if trial % 4 == 1:                                 # exact zeros, both signs
            x[rng.uniform(size=N) < 0.5] = 0.0
            x[rng.uniform(size=N) < 0.3] = -0.0
            hist[:3, rng.uniform(size=n) < 0.3] = -0.0
        if trial % 4 == 2 and n:
            hist[3, :] = 0.0                              # the buffer at handover
        a, b = col(new(x, hist, 0.0)), col(old(x, hist))
        assert a.tobytes() == b.tobytes(), (trial, a - b)


def test_the_factors_are_the_closed_forms():
    """``c = cos x``, ``s = sin x / x``, ``h = 2 (1 - cos x) / x^2`` (NumPy), exactly 1 at
    ``x = 0``."""
    w, T = ca.SX.sym("w"), ca.SX.sym("T")
    f = ca.Function("f", [w, T], list(heave_factors(w, T)))
    for x in (1e-3, 0.2, 1.0, 3.0):
        c, s, h = (float(v) for v in f(x, 1.0))
        assert c == pytest.approx(np.cos(x), rel=1e-15)
        assert s == pytest.approx(np.sin(x) / x, rel=1e-15)
        assert h == pytest.approx(2 * (1 - np.cos(x)) / x**2, rel=1e-9 if x < 0.01 else 1e-14)
    assert [float(v) for v in f(0.0, 0.2)] == [1.0, 1.0, 1.0]
    assert [float(v) for v in f(1.5, 0.0)] == [1.0, 1.0, 1.0]
    assert float(ca.Function("g", [w], [sinc(w)])(0.0)) == 1.0


def _frequency_after(heave_time, w, steps, dt=0.004):
    """The filter's frequency after ``steps`` periods of a pad heaving at ``w``."""
    ms_s, x_s, dt_s = ca.SX.sym("ms", 2), NAV.sym("x"), ca.SX.sym("dt")
    p = estimator_params()
    p_s = p.sym()
    f = ca.Function("f", [ms_s, x_s, p_s, dt_s],
                    list(heave_frequency(ms_s, x_s, p.unpack(p_s), dt_s)))
    pv = p.pack({**ESTIMATOR_DEFAULTS, "heave_time": heave_time})
    ms, x = np.zeros(2), np.zeros(N)
    for k in range(steps):
        _, v, a = _pad_motion(0.8, w, 0.3, k * dt)
        x[sl("v_t")][2], x[sl("a_t")][2] = v, a
        ms, omega = (np.asarray(r).ravel() for r in f(ms, x, pv, dt))
    return float(omega[0])


@pytest.mark.parametrize("w", [0.6, 1.5, 3.0])
def test_the_frequency_of_a_sinusoid_is_its_own(w):
    """``sqrt(<a^2> / <v^2>)`` of one sinusoid is its frequency (``|a| = w |v|`` on average
    over whole periods). The averages (time constant ``tau`` = 20 s, after 120 s) ripple:
    each square is its mean times ``1 +- cos(2 w t)``, which the average passes at
    ``1 / sqrt(1 + (2 w tau)^2)``, ``v^2``'s and ``a^2``'s in opposite phase, so the
    ratio's square root ripples by at most that, to first order."""
    tau = 20.0
    ripple = 1 / np.sqrt(1 + (2 * w * tau) ** 2)
    assert _frequency_after(tau, w, 30_000) == pytest.approx(w, rel=ripple)


def test_no_averaging_time_is_the_constant_acceleration():
    """``heave_time = 0``: the frequency is exactly 0 whatever the pad does."""
    assert _frequency_after(0.0, 1.5, 50) == 0.0

"""The pad's heave oscillator in the filter's own prediction (docs/estimator.md, E17b).

Checked against the pad's closed-form harmonic motion (NumPy's sine and cosine of the
motion itself, not the transition's factors), against central differences of that
closed-form map, against a quarter period worked by hand, and at ``omega = 0``
against the random walk's prediction bit for bit; the given frequency against the
filter's own.
"""

import casadi as ca
import numpy as np
import pytest
from nav_reference import N, col, sl

from quadland_symbolic.landing.estimator import heave_frequency
from quadland_symbolic.landing.navigation import (
    ESTIMATOR_DEFAULTS,
    NAV,
    covariance_pattern,
    estimator_params,
    nav_predict,
)

_Z = [sl(f).start + 2 for f in ("p_r", "v_t", "a_t")]     # the pad's z entries


def _predict(coupling="axes", with_omega=True):
    """``(x, P, a_in, dt, p_est, turn[, omega]) -> (x_next, P_next)`` with (E17b)."""
    pattern = covariance_pattern(coupling)
    x, P = NAV.sym("x"), ca.SX.sym("P", N, N)
    a_in, dt, turn, w = ca.SX.sym("a", 3), ca.SX.sym("dt"), ca.SX.sym("turn", 3), ca.SX.sym("w")
    p = estimator_params().sym()
    Ps = pattern.unpack(pattern.pack(P))
    args = [x, P, a_in, dt, p, turn] + ([w] if with_omega else [])
    xn, Pn = nav_predict(x, Ps, a_in, dt, p, pattern, turn, w if with_omega else None)
    return ca.Function("f", args, [xn, ca.densify(Pn)])


def _pad_motion(Z, w, phi, t):
    """z, z', z'' of ``Z sin(w t + phi)``."""
    return (Z * np.sin(w * t + phi), Z * w * np.cos(w * t + phi),
            -Z * w**2 * np.sin(w * t + phi))


def _state(rng, v, a):
    """A random state with no input bias, the pad's z velocity and acceleration given."""
    x = rng.normal(size=N)
    x[sl("a_b")] = x[sl("a_tilt")] = 0.0
    x[sl("v_t")][2], x[sl("a_t")][2] = v, a
    return x


@pytest.mark.parametrize("w", [0.5, 1.41, 6.0])
def test_the_pad_follows_the_closed_form_harmonic_over_a_second(w):
    """250 predictions of 4 ms: the pad's z velocity and acceleration are the motion's at
    ``t0 + 1 s`` and the relative height has lost the pad's rise (no input, no bias: the
    quadrotor coasts); x and y keep the constant acceleration."""
    rng = np.random.default_rng(7)
    f, p = _predict(), estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    Z, phi, t0, dt, n = 1.1, 0.4, 3.0, 0.004, 250
    _, v0, a0 = _pad_motion(Z, w, phi, t0)
    x = x0 = _state(rng, v0, a0)
    P = np.eye(N)
    for _ in range(n):
        x = col(f(x, P, np.zeros(3), dt, p, np.zeros(3), w)[0])
    T = n * dt
    zT = _pad_motion(Z, w, phi, t0 + T)
    assert x[sl("v_t")][2] == pytest.approx(zT[1], abs=1e-12)
    assert x[sl("a_t")][2] == pytest.approx(zT[2], abs=1e-11)
    rise = zT[0] - _pad_motion(Z, w, phi, t0)[0]
    want = x0[sl("p_r")][2] + x0[sl("v1")][2] * T - rise
    assert x[sl("p_r")][2] == pytest.approx(want, abs=1e-12)
    for a in (0, 1):
        assert x[sl("a_t")][a] == x0[sl("a_t")][a]
        assert x[sl("v_t")][a] == pytest.approx(x0[sl("v_t")][a] + T * x0[sl("a_t")][a],
                                                abs=1e-12)


def test_a_quarter_period_by_hand():
    """``omega dt = pi / 2``: ``v+ = a / omega``, ``a+ = -omega v``, the rise
    ``(v + a / omega) / omega``."""
    w = 2.0
    dt = np.pi / 2 / w
    x = np.zeros(N)
    x[sl("v_t")][2], x[sl("a_t")][2], x[sl("p_r")][2] = 0.3, -0.8, 1.0
    p = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    xn = col(_predict()(x, np.eye(N), np.zeros(3), dt, p, np.zeros(3), w)[0])
    assert xn[sl("v_t")][2] == pytest.approx(-0.8 / w, abs=1e-15)
    assert xn[sl("a_t")][2] == pytest.approx(-w * 0.3, abs=1e-15)
    assert xn[sl("p_r")][2] == pytest.approx(1.0 - (0.3 - 0.8 / w) / w, abs=1e-15)


@pytest.mark.parametrize("coupling", ["axes", "full"])
def test_the_covariance_moves_with_the_differences_of_the_closed_form(coupling):
    """``P+ - Q`` is ``J P J^T`` with ``J`` the central differences of the closed-form
    motion over ``dt`` (the pad's z rows; NumPy's sin and cos) and the random walk's
    ``Phi`` elsewhere (the prediction at ``omega = 0``, whose ``J`` is its own)."""
    rng = np.random.default_rng(3)
    w, dt = 1.3, 0.004
    f, f0 = _predict(coupling), _predict(coupling, with_omega=False)
    p = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    zero = np.zeros(3)

    def step(x):                                     # the map x -> x+ at no input
        y = col(f0(x, np.zeros((N, N)), zero, dt, p, zero)[0])
        y = y.copy()
        v, a = x[_Z[1]], x[_Z[2]]
        y[_Z[1]] = v * np.cos(w * dt) + a * np.sin(w * dt) / w
        y[_Z[2]] = a * np.cos(w * dt) - w * v * np.sin(w * dt)
        rise = v * np.sin(w * dt) / w + a * (1 - np.cos(w * dt)) / w**2
        y[_Z[0]] += dt * v + dt**2 / 2 * a - rise      # the random walk's rise out, this in
        return y

    x0, eps = rng.normal(size=N), 1e-5
    J = np.column_stack([(step(x0 + eps * e) - step(x0 - eps * e)) / (2 * eps)
                         for e in np.eye(N)])
    A = rng.normal(size=(N, N))
    P = covariance_pattern(coupling).unpack_numeric(covariance_pattern(coupling)
                                                    .pack_numeric(A @ A.T + N * np.eye(N)))
    Q = np.asarray(f0(x0, np.zeros((N, N)), zero, dt, p, zero)[1])
    Pn = np.asarray(f(x0, P, zero, dt, p, zero, w)[1])
    want = covariance_pattern(coupling).unpack_numeric(
        covariance_pattern(coupling).pack_numeric(J @ P @ J.T + Q))
    np.testing.assert_allclose(Pn, want, rtol=1e-8, atol=1e-8)


def test_no_frequency_is_the_random_walk_to_the_bit():
    """``omega = 0``: the same bits as the prediction without (E17b), state and covariance."""
    rng = np.random.default_rng(11)
    f, f0 = _predict(), _predict(with_omega=False)
    p = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    for trial in range(40):
        x = rng.normal(size=N) * 10.0 ** rng.integers(-6, 3, N)
        A = rng.normal(size=(N, N))
        P = A @ A.T
        a_in, turn = rng.normal(size=3), rng.normal(size=3) * 1e-3
        dt = 0.0 if trial % 5 == 0 else rng.uniform(0.001, 0.006)
        got = [np.asarray(v) for v in f(x, P, a_in, dt, p, turn, 0.0)]
        want = [np.asarray(v) for v in f0(x, P, a_in, dt, p, turn)]
        for g, h in zip(got, want, strict=True):
            assert g.tobytes() == h.tobytes(), trial


def _omega(values):
    """The frequency the step uses, from the memory's averages ``(<v^2>, <a^2>)`` = (1, 2)."""
    ms_s, x_s, dt_s = ca.SX.sym("ms", 2), NAV.sym("x"), ca.SX.sym("dt")
    p = estimator_params()
    p_s = p.sym()
    f = ca.Function("f", [ms_s, x_s, p_s, dt_s],
                    [heave_frequency(ms_s, x_s, p.unpack(p_s), dt_s)[1]])
    x = np.zeros(N)
    x[sl("v_t")][2], x[sl("a_t")][2] = 1.0, np.sqrt(2.0)
    return float(f([1.0, 2.0], x, p.pack({**ESTIMATOR_DEFAULTS, **values}), 0.004))


def test_a_given_frequency_replaces_the_filters_own():
    """``heave_frequency > 0`` is the frequency whatever the averages say; at 0 the filter's
    own (``sqrt(2 / 1)`` here, the averages unmoved by a pad on them) or none."""
    assert _omega({"heave_time": 20.0}) == pytest.approx(np.sqrt(2.0), rel=1e-12)
    assert _omega({"heave_time": 20.0, "heave_frequency": 0.9}) == 0.9
    assert _omega({"heave_time": 0.0, "heave_frequency": 0.9}) == 0.9
    assert _omega({"heave_time": 0.0}) == 0.0


def test_the_levelled_bias_turned_and_the_heave_each_keep_their_own_entries():
    """(E2b)'s turn and (E17b)'s oscillator in one prediction (the hand-merged
    ``nav_predict``): its ``Phi`` is the turned prediction's (tests/test_tilt_levels_bias.py
    checks that one) except the pad's six z entries, which are the closed-form motion's
    (NumPy's sine and cosine), whatever the levelled share; ``P+`` is that ``Phi``'s."""
    w, dt = 1.3, 0.004
    turn = np.array([0.003, -0.002, 0.004])
    p = estimator_params().pack({**ESTIMATOR_DEFAULTS, "tilt_levels_bias": [0.5, 0.25, 0.75]})
    pattern = covariance_pattern("full")
    x, P, a_in = NAV.sym("x"), ca.SX.sym("P", N, N), ca.SX.sym("a", 3)
    Ps = pattern.unpack(pattern.pack(P))

    def jac(omega):
        xn, Pn = nav_predict(x, Ps, a_in, dt, p, pattern, turn, omega)
        return ca.Function("f", [x, P, a_in], [ca.jacobian(xn, x), ca.densify(Pn)])

    rng = np.random.default_rng(5)
    x0, a0 = rng.normal(size=N), rng.normal(size=3)
    A = rng.normal(size=(N, N))
    P0 = A @ A.T + N * np.eye(N)
    J_turn = np.asarray(jac(None)(x0, np.zeros((N, N)), a0)[0])
    J, Pn = (np.asarray(v) for v in jac(w)(x0, P0, a0))
    Q = np.asarray(jac(w)(x0, np.zeros((N, N)), a0)[1])
    want = J_turn.copy()
    ip, iv, ia = _Z
    c, s = np.cos(w * dt), np.sin(w * dt)
    want[iv, iv], want[iv, ia] = c, s / w
    want[ia, iv], want[ia, ia] = -w * s, c
    want[ip, iv], want[ip, ia] = -s / w, -(1 - c) / w**2
    assert np.abs(J_turn[sl("a_tilt"), sl("a_b")]).max() > 1e-3     # the share turns: on
    np.testing.assert_allclose(J, want, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(Pn, J @ P0 @ J.T + Q, rtol=1e-10)

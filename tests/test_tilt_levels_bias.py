"""(E2b): the filter's tilt that levels the accelerometer's bias (``estimator.tilt_levels_bias``).

A GNSS-aided attitude source levels its accelerometer's horizontal bias: its tilt error
is ``-l a_b`` plus a small independent residual ``r`` (docs/sensors.md, "A GNSS-aided
attitude"; docs/estimator.md, (E2b)). The filter keeps ``a_tilt`` as its state and
carries the correlation in its transition. Checked here against a second model written
independently: the same filter in the residual's coordinates ``y = [.., a_b, r]``,
``r = a_tilt + l a_b``, whose input bias is ``(1 - l) a_b + r`` and whose ``r`` is the
plain Gauss-Markov process, discretized by SciPy's ``expm`` and Van Loan's method and
mapped back by ``x = T y``; the prediction's Jacobian against central finite differences
of the flight function; and the hand derivation of what a levelled bias leaves in the
velocity (nothing) and in the tilt (the bias itself, as constant as it).
"""

import numpy as np
import pytest
from scipy.linalg import expm

from quadland_symbolic.landing.navigation import (
    ESTIMATOR_DEFAULTS,
    NAV,
    estimator_params,
    nav_predict_function,
    nav_transition_function,
)

N = NAV.size


def _params(levels, **over):
    values = {**ESTIMATOR_DEFAULTS, "q_acc": [0.02, 0.03, 0.01], "q_ab": [1e-3, 2e-3, 3e-3],
              "tilt_sigma": [0.005, 0.006, 0.0], "tilt_tau": 5.0,
              "tilt_levels_bias": list(levels), **over}
    return estimator_params().pack(values), values


def _sl(name):
    return NAV.slice(name)


def _skew(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def _residual_model(dt, q, turn=None):
    """``(Phi, Gamma, Q)`` in x's coordinates from the model in the residual's, by expm."""
    L = np.diag(q["tilt_levels_bias"])
    I3 = np.eye(3)
    A = np.zeros((N, N))
    A[_sl("p_r"), _sl("v1")], A[_sl("p_r"), _sl("v_t")] = I3, -I3
    A[_sl("v1"), _sl("a_b")] = -(I3 - L)                  # y's input bias: (1 - l) a_b + r
    A[_sl("v1"), _sl("a_tilt")] = -I3                     # (the slot holds r in y)
    A[_sl("v_t"), _sl("a_t")] = I3
    B = np.zeros((N, 3))
    B[_sl("v1"), :] = I3
    W = np.zeros((N, N))
    for name, key in (("v1", "q_acc"), ("a_t", "q_at"), ("b", "q_b"), ("a_b", "q_ab")):
        W[_sl(name), _sl(name)] = np.diag(q[key])
    M = np.zeros((N + 3, N + 3))
    M[:N, :N], M[:N, N:] = A, B
    E = expm(M * dt)
    V = expm(np.block([[-A, W], [np.zeros((N, N)), A.T]]) * dt)
    Phi, Gamma, Q = E[:N, :N].copy(), E[:N, N:], V[N:, N:].T @ V[:N, N:]
    a = np.exp(-dt / q["tilt_tau"])                       # r: the sampled Gauss-Markov
    i = _sl("a_tilt")
    Phi[i, :] *= a
    Q[i, :] *= a
    Q[:, i] *= a
    Q[i, i] += np.diag(np.asarray(q["tilt_sigma"]) ** 2 * (1 - a * a))
    if turn is not None:                                  # (E6a): a_b turns with the body
        Phi[_sl("a_b"), _sl("a_b")] = I3 + _skew(turn)
    T = np.eye(N)
    T[_sl("a_tilt"), _sl("a_b")] = -L                     # x = T y: a_tilt = r - l a_b
    Ti = np.linalg.inv(T)
    return T @ Phi @ Ti, T @ Gamma, T @ Q @ T.T


@pytest.mark.parametrize("levels", [(1.0, 1.0, 0.0), (0.5, 0.25, 0.75), (0.0, 0.0, 0.0)])
@pytest.mark.parametrize("dt", [0.004, 0.1])
def test_transition_is_the_residual_model_mapped_back(levels, dt):
    p, q = _params(levels)
    Phi, Gamma, Q = (np.array(m) for m in nav_transition_function()(dt, p))
    Phi_r, Gamma_r, Q_r = _residual_model(dt, q)
    assert np.allclose(Phi, Phi_r, rtol=1e-12, atol=1e-14)
    assert np.allclose(Gamma, Gamma_r, rtol=1e-12, atol=1e-14)
    assert np.allclose(Q, Q_r, rtol=1e-9, atol=1e-18)
    assert np.min(np.linalg.eigvalsh((Q + Q.T) / 2)) > -1e-18


@pytest.mark.parametrize("levels", [(1.0, 1.0, 0.0), (0.5, 0.25, 0.75)])
def test_prediction_jacobian_is_its_finite_differences_with_the_bias_turned(levels):
    """The flight function's ``x_next(x)`` differentiated numerically is the residual
    model's ``Phi`` with ``a_b`` turned by ``I + S(turn)`` (E6a): the levelled share
    turns with the bias (``Phi[a_tilt, a_b] = (e^(-dt/tau) - 1) l - l S(turn)``)."""
    p, q = _params(levels)
    f = nav_predict_function("full")
    dt, turn = 0.004, np.array([0.003, -0.002, 0.004])
    rng = np.random.default_rng(19)
    x0, a_in = rng.normal(size=N), rng.normal(size=3)
    P = np.eye(N)
    J = np.zeros((N, N))
    h = 1e-4
    for k in range(N):
        e = np.zeros(N)
        e[k] = h
        up = np.array(f(x0 + e, P, a_in, dt, p, turn)[0]).ravel()
        down = np.array(f(x0 - e, P, a_in, dt, p, turn)[0]).ravel()
        J[:, k] = (up - down) / (2 * h)
    Phi_r, _, _ = _residual_model(dt, q, turn)
    assert np.allclose(J, Phi_r, rtol=1e-8, atol=1e-9)


def test_a_levelled_bias_leaves_the_velocity_alone_and_the_tilt_at_the_bias():
    """By hand: with every bias levelled (``l = 1`` on x, y) and no residual, the input's
    error ``a_b + a_tilt`` is 0 horizontally, so the velocity and position do not move
    over a period and the tilt stays ``-a_b`` (it does not decay: it is the bias', not a
    5 s process); along z (``l = 0``) the bias drives the velocity by ``-a_b dt``."""
    p, _ = _params((1.0, 1.0, 0.0))
    f = nav_predict_function("full")
    b = np.array([0.06, -0.04, 0.02])
    x = np.zeros(N)
    x[_sl("a_b")], x[_sl("a_tilt")] = b, [-b[0], -b[1], 0.0]
    dt = 0.1
    x1 = np.array(f(x, np.eye(N), np.zeros(3), dt, p, np.zeros(3))[0]).ravel()
    assert np.allclose(x1[_sl("v1")], [0.0, 0.0, -b[2] * dt], rtol=0, atol=1e-15)
    assert np.allclose(x1[_sl("p_r")], [0.0, 0.0, -b[2] * dt**2 / 2], rtol=0, atol=1e-15)
    assert np.allclose(x1[_sl("a_tilt")], [-b[0], -b[1], 0.0], rtol=0, atol=1e-15)
    # the same state in the filter without the levelling (l = 0): the tilt is a 5 s
    # process apart from the bias, so it decays toward 0 and leaves the bias in the input
    p0, _ = _params((0.0, 0.0, 0.0))
    x0 = np.array(f(x, np.eye(N), np.zeros(3), dt, p0, np.zeros(3))[0]).ravel()
    decay = np.exp(-dt / 5.0)
    assert np.allclose(x0[_sl("a_tilt")][:2], -b[:2] * decay, rtol=1e-12)


def test_the_levelled_share_shrinks_the_velocity_noise_of_the_bias_walk():
    """Hand derivation of ``Q[v1, v1]`` per axis: ``q_acc dt + (1 - l)^2 q_ab dt^3 / 3``
    (the bias' random walk enters the input as ``(1 - l)`` of it; the residual is held
    over the period and its noise comes at the end)."""
    dt = 0.2
    for levels in ((1.0, 0.5, 0.0),):
        p, q = _params(levels)
        Q = np.array(nav_transition_function()(dt, p)[2])
        i = _sl("v1").start
        for a in range(3):
            want = q["q_acc"][a] * dt + (1 - levels[a]) ** 2 * q["q_ab"][a] * dt**3 / 3
            assert Q[i + a, i + a] == pytest.approx(want, rel=1e-12)


def _e2a_transition(dt, q):
    """(E2a) as the filter computed it before (E2b), written out here: one axis held,
    ``kron`` over x, y, z, then ``a_tilt``'s decay and noise set in place."""
    import casadi as ca

    from quadland_symbolic.kalman import nilpotent_discretization
    from quadland_symbolic.landing.navigation import axis_dynamics
    x7, a_in = ca.SX.sym("x", 7), ca.SX.sym("a_in")
    A7, B7 = (np.array(ca.evalf(ca.jacobian(axis_dynamics(x7, a_in), v))) for v in (x7, a_in))
    I3 = ca.DM.eye(3)
    Q = ca.SX(N, N)
    for a in range(3):
        W7 = ca.diag(ca.vertcat(0, q["q_acc"][a], 0, q["q_at"][a], q["q_b"][a], q["q_ab"][a], 0))
        Phi7, Gamma7, Q7 = nilpotent_discretization(A7, B7, W7, dt)
        Q += ca.kron(Q7, I3[:, a] @ I3[a, :])
    decay = ca.exp(-dt / q["tilt_tau"])
    i = _sl("a_tilt").start
    Phi = ca.kron(Phi7, I3)
    for a in range(3):
        Phi[i + a, i + a] = decay
        Q[i + a, i + a] = q["tilt_sigma"][a] ** 2 * (1 - decay**2)
    return tuple(np.array(ca.evalf(m)) for m in (Phi, ca.kron(Gamma7, I3), Q))


@pytest.mark.parametrize("dt", [0.004, 0.1, 0.37])
def test_the_default_is_e2a_to_the_bit(dt):
    """``l = 0`` (the default) gives (E2a)'s transition exactly, every entry the same
    double: the levelling's terms are multiplied by an exact zero (docs/estimator.md,
    (E2b)). ``Phi[a_tilt, a_b]`` is ``(e^(-dt/tau) - 1) 0 = -0.0`` where (E2a) had
    ``+0.0``, equal as numbers (a signed zero adds nothing to a product's sum)."""
    p, q = _params((0.0, 0.0, 0.0), tilt_sigma=[0.0855, 0.0855, 0.0])
    got = [np.array(m) for m in nav_transition_function()(dt, p)]
    for g, w in zip(got, _e2a_transition(dt, q), strict=True):
        assert np.all(np.isfinite(g)) and np.array_equal(g, w)
    Phi = got[0]
    assert np.count_nonzero(np.signbit(Phi) != np.signbit(_e2a_transition(dt, q)[0])) == 3


# --- the NEES on the hovers (docs/landing.md, issue 19, thirteenth) ----------------------

#: The VN-300 as the attitude source and the IMU (docs/sensors.md, "A dedicated GNSS/INS").
VN300 = {"sensors.imu.attitude_gnss_aided": True,
         "sensors.imu.attitude_sigma": [0.0005235987755982988, 0.0005235987755982988,
                                        0.03490658503988659],
         "sensors.imu.accel_noise_density": 0.001372931,
         "sensors.imu.gyro_noise_density": 6.108652381980153e-05,
         "sensors.imu.accel_bias_sigma": 0.08558,
         "estimator.p0_input_bias": [0.08558] * 3}
#: (E2b) with the residual and the levelling's pitch term (0.0269 m/s^2).
LEVELLED = {"estimator.tilt_levels_bias": [1.0, 1.0, 0.0],
            "estimator.tilt_sigma": [0.02694, 0.02694, 0.0],
            "estimator.p0_tilt_bias": [0.08972, 0.08972, 0.0]}
#: the same residual in a filter whose tilt is apart from the bias (l = 0)
UNCOUPLED = {"estimator.tilt_sigma": [0.005131, 0.005131, 0.0],
             "estimator.p0_tilt_bias": [0.005131, 0.005131, 0.0]}
_MEASURED = {"position": "3.50 against 2.66-3.36 (over-confident by 4 %)",
             "velocity": "2.20 against 2.77-3.24 (cautious)",
             "tilt": "3.01 against 1.63-2.41 (over-confident by 25 %)"}


@pytest.fixture(scope="module")
def hovers():
    from quadland.kinds.landing.consistency import consistency_monte_carlo
    from quadland.scenario import load_scenario
    base = load_scenario("highway")
    return {name: consistency_monte_carlo(base.replace(**VN300, **over), runs=100, duration=8.0)
            for name, over in (("levelled", LEVELLED), ("uncoupled", UNCOUPLED))}


@pytest.mark.slow
@pytest.mark.parametrize("group", [pytest.param(g, marks=pytest.mark.xfail(
    strict=True, reason=_MEASURED[g])) if g in _MEASURED else g
    for g in ("relative", "position", "velocity", "pad", "tilt")])
def test_the_levelled_filter_on_the_vn300_hovers_is_within_its_nees_bounds(hovers, group):
    """100 hovers of 8 s over highway's pad on the VN-300: the time-averaged NEES of each
    group within its correlation-aware 95 % bounds (issue 17's criterion); the groups it
    misses are marked with the measured values."""
    assert hovers["levelled"].nees_time_averaged(group).inside


@pytest.mark.slow
def test_carrying_the_levelled_bias_is_what_makes_the_tilt_credible(hovers):
    """The uncoupled filter takes the constant levelled tilt for a 5 s process the velocity
    tells apart from the bias: its tilt NEES is two orders of magnitude above its bound
    (measured 475), the levelled filter's within a factor 1.3 of it."""
    lo, hi = hovers["levelled"].nees_bounds("tilt")
    assert hovers["uncoupled"].nees_time_averaged("tilt").mean > 50 * hi
    assert hovers["levelled"].nees_time_averaged("tilt").mean < 1.3 * hi

"""The horizon predicted every ``predict_every`` control periods (E6b).

Against (E6) itself: one period a prediction is one prediction over the buffer's oldest
input, bit for bit (``nav_predict`` called on it, outside the step); two periods of a
constant input predicted at once are two predictions of one (the mean to rounding, the
covariance the continuous model's discretization over ``2 dt``: ``Phi Q(dt) Phi^T + Q(dt)
= Q(2 dt)``); two different inputs give the velocity exactly and the position off by the
closed form ``(a1 - a2) dt^2 / 2``. The step at ``N = 2`` holds its horizon one period,
then predicts over both, while its output (the present's state) stays that of the
``N = 1`` filter to rounding.
"""

from __future__ import annotations

import numpy as np
import pytest

from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    HIST_ROWS,
    N_HIST,
    estimator_init_function,
    estimator_memory,
    estimator_step_function,
)
from quadland_symbolic.landing.navigation import (
    ESTIMATOR_DEFAULTS,
    NAV,
    NAV_PACKETS,
    covariance_pattern,
    estimator_params,
    nav_predict_function,
)

DT = 0.004
SIZES = (N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)


def _bits(v):
    return np.asarray(v, dtype=np.float64).ravel().view(np.uint64)


def _p(every, held=False):
    """The default parameters, the horizon predicted every ``every`` periods; ``held``: the
    tilt bias held (:func:`_held_tilt`)."""
    lp = estimator_params()
    p = lp.pack(dict(ESTIMATOR_DEFAULTS))
    p[lp.slice("predict_every")] = every
    if held:
        p[lp.slice("tilt_tau")], p[lp.slice("tilt_sigma")] = 1e12, 0.0
    return p


def _memory(rng, turns=True):
    """A filter a horizon behind 7 s, its buffer full of periods of ``DT`` with random
    inputs (and turns, else none and no tilt bias), its covariance not diagonal."""
    lay, pattern = estimator_memory(*SIZES), covariance_pattern(FLIGHT_COUPLING)
    x0 = np.r_[0.3, -0.2, 3.0, 0.2, -0.1, -0.3, 0.5, 0.1, 0.0, rng.normal(size=12) * 0.05]
    P0 = np.r_[[0.5] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.04] * 3, [0.01] * 3]
    if not turns:
        x0[NAV.slice("a_tilt")] = 0.0
    mem = np.asarray(estimator_init_function(*SIZES)(x0, P0, np.zeros(9), 7.0)).ravel()
    hist = np.zeros((len(HIST_ROWS), N_HIST))
    hist[0:3] = rng.normal(size=(3, N_HIST)) * 0.5
    hist[3] = DT
    hist[4:7] = rng.normal(size=(3, N_HIST)) * 1e-3 * turns
    mem[lay.slice("hist")] = hist.ravel(order="F")
    L = np.tril(rng.normal(size=(NAV.size, NAV.size))) * 0.1 + np.diag(np.sqrt(P0))
    mem[lay.slice("P_h")] = pattern.pack_numeric(L @ L.T)
    return mem


def _quiet(t):  # noqa: ARG001
    """No packet fresh."""
    return [np.zeros(layout.size) for layout in NAV_PACKETS]


def _imu(rng):
    return np.r_[0.02, -0.01, 0.5, 0.0, 0.0, 9.8, rng.normal(size=3) * 0.01]


def _step(mem, rng, every, t, held=False):
    out = estimator_step_function(*SIZES)(mem, _imu(rng), *_quiet(t), _p(every, held), DT, t)
    return [np.asarray(v).ravel() for v in out]


@pytest.mark.parametrize("seed", [3, 4])
def test_one_period_a_prediction_is_one_prediction_of_the_oldest_input_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    lay, pattern = estimator_memory(*SIZES), covariance_pattern(FLIGHT_COUPLING)
    mem = _memory(rng)
    imu = _imu(rng)
    # the horizon after fusion and before any prediction: a step that never predicts
    held = estimator_step_function(*SIZES)(mem, imu, *_quiet(7.2), _p(1e9), DT, 7.2)
    held = lay.unpack(np.asarray(held[0]).ravel())
    m, got = lay.unpack(mem), lay.unpack(_step(mem, np.random.default_rng(seed), 1, 7.2)[0])
    col = m["hist"][:, 0]
    x, P = nav_predict_function(FLIGHT_COUPLING)(held["x_h"], pattern.unpack_numeric(
        held["P_h"]), col[0:3], col[3], _p(1), col[4:7])
    np.testing.assert_array_equal(_bits(got["x_h"]), _bits(x))
    np.testing.assert_array_equal(_bits(got["P_h"]), _bits(pattern.pack_numeric(np.asarray(P))))
    np.testing.assert_array_equal(_bits(got["t_h"]), _bits(m["t_h"] + col[3]))
    assert np.all(got["acc"] == 0)


def _held_tilt():
    """The parameters with the tilt bias held (no decay, no noise): (E2)'s nilpotent
    system, whose discretization composes exactly. (E2a)'s decay is applied after the
    held system's ``Phi`` and ``Q`` (its coupling into the velocity taken as held over
    the period), so there two periods and one of twice the length differ by
    ``O(dt / tilt_tau)`` in the tilt's rows."""
    return _p(1, held=True)


def _predict(x, P, a, dt, turn=(0.0, 0.0, 0.0)):
    x, P = nav_predict_function("full")(x, P, a, dt, _held_tilt(), turn)
    return np.asarray(x).ravel(), np.asarray(P)


def test_two_periods_at_once_are_two_predictions_of_one():
    rng = np.random.default_rng(5)
    x = rng.normal(size=NAV.size)
    x[NAV.slice("a_b")] = x[NAV.slice("a_tilt")] = 0.0
    L = np.tril(rng.normal(size=(NAV.size, NAV.size))) * 0.1 + np.eye(NAV.size)
    P, a = L @ L.T, rng.normal(size=3)
    x2, P2 = _predict(*_predict(x, P, a, DT), a, DT)
    x1, P1 = _predict(x, P, a, 2 * DT)
    np.testing.assert_allclose(x1, x2, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(P1, P2, rtol=1e-12, atol=1e-15)


def test_two_inputs_at_their_mean_move_the_position_by_the_closed_form():
    rng = np.random.default_rng(6)
    x = rng.normal(size=NAV.size)
    x[NAV.slice("a_b")] = x[NAV.slice("a_tilt")] = 0.0
    P, a1, a2 = np.eye(NAV.size), rng.normal(size=3), rng.normal(size=3)
    x2, _ = _predict(*_predict(x, P, a1, DT), a2, DT)
    x1, _ = _predict(x, P, (a1 + a2) / 2, 2 * DT)
    v, p = NAV.slice("v1"), NAV.slice("p_r")
    np.testing.assert_allclose(x1[v], x2[v], rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(x2[p] - x1[p], (a1 - a2) * DT**2 / 2, rtol=1e-6, atol=1e-16)


def test_every_second_period_the_horizon_holds_then_predicts_over_both():
    rng = np.random.default_rng(7)
    lay, pattern = estimator_memory(*SIZES), covariance_pattern(FLIGHT_COUPLING)
    mem1 = mem2 = _memory(rng, turns=False)     # the output predictor carries neither
    m0 = lay.unpack(mem2)
    t = 7.2
    for k in (1, 2):
        t += DT
        seed = int(rng.integers(1 << 30))
        mem1, y1, _ = _step(mem1, np.random.default_rng(seed), 1, t, held=True)
        mem2, y2, _ = _step(mem2, np.random.default_rng(seed), 2, t, held=True)
        # the present's state the controller reads: the same to rounding
        np.testing.assert_allclose(y2, y1, rtol=1e-11, atol=1e-11)
        got = lay.unpack(mem2)
        if k == 1:
            for f in ("x_h", "P_h", "t_h"):
                np.testing.assert_array_equal(_bits(got[f]), _bits(m0[f]))
            assert got["acc"][7] == 1 and got["acc"][3] == DT
    want = lay.unpack(mem1)
    assert got["t_h"][0] == pytest.approx(m0["t_h"][0] + 2 * DT, abs=1e-15)
    assert np.all(got["acc"] == 0)
    # the velocities exact to rounding; the position within the two inputs' difference
    hist = m0["hist"]
    bound = np.abs(hist[0:3, 0] - hist[0:3, 1]) * DT**2 / 2
    np.testing.assert_allclose(got["x_h"][3:], want["x_h"][3:], rtol=1e-9, atol=1e-10)
    assert np.all(np.abs(got["x_h"][0:3] - want["x_h"][0:3]) <= bound * 1.01 + 1e-12)
    np.testing.assert_allclose(pattern.unpack_numeric(got["P_h"]),
                               pattern.unpack_numeric(want["P_h"]), rtol=1e-12, atol=1e-15)

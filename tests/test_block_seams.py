"""The sensors' processes keep their joint law across the seams of their draws' blocks.

A sensor's draws come in blocks of ``BLOCK`` samples, each from its own generator
(``quadland.kinds.landing.sensing``); the processes run on across a seam from the last
value of the block before. Bit-for-bit prefix tests (``tests/test_tick_blocks.py``) do
not show that the law is right at the seam: a process restarted there, or continued from
the wrong value, is as reproducible as a right one. These tests check, over many seeds,
the transition at the seam (samples 1023 -> 1024) against the closed-form law of the
process and against the same statistics one step inside a block (1021 -> 1022):

* a Gauss-Markov process ``x' = -x / tau + w`` sampled every ``h``:
  ``x_(k+1) = a x_k + sigma sqrt(1 - a^2) n``, ``a = exp(-h / tau)``, so
  ``(x_(k+1) - a x_k) / (sigma sqrt(1 - a^2))`` is standard normal and independent of
  ``x_k``, and ``x_k / sigma`` is standard normal (stationary start);
* a random walk with density ``q``: ``(b_(k+1) - b_k) / (q sqrt(h))`` standard normal,
  independent of the step before it;
* the attitude error between two IMU samples (the vision off the IMU's grid): the
  Ornstein-Uhlenbeck bridge, mean ``(a1 (1 - a2^2) x_l + a2 (1 - a1^2) x_r) / (1 - a1^2
  a2^2)``, variance ``sigma^2 (1 - a1^2) (1 - a2^2) / (1 - a1^2 a2^2)``, with ``a1``,
  ``a2`` the factors of the distances to the left and right samples.

The bounds are four standard errors of each statistic for ``N`` independent seeds
(mean ``1 / sqrt(N)``, variance ``sqrt(2 / N)``, correlation ``1 / sqrt(N)``). A seam that
restarts the Gauss-Markov process from its stationary law gives the normalized step a
variance of ``(1 + a^2) / (1 - a^2)`` (12.5 at ``a = 0.923``): far outside them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from quadland.kinds.landing.sensing import BLOCK, draw_sensors
from quadland.kinds.landing.sensor_settings import SENSOR_DEFAULTS

RATE = 250.0                       # every sensor used here on the IMU's clock
H = 1.0 / RATE
TAU = 0.05                         # s: a = exp(-h / tau) = 0.923, far from 0 and 1
SEAM, INSIDE = BLOCK - 1, BLOCK - 3          # the steps k -> k + 1 compared
DURATION = (BLOCK + 4) * H
SETTINGS = {"gnss": {"rate_hz": RATE, "position_tau": TAU},
            "imu": {"attitude_tau": [TAU, TAU, TAU], "attitude_white_sigma": 0.0},
            "vision": {"rate_hz": RATE}, "rangefinder": {"rate_hz": RATE}}
SEEDS = range(2000)


def _check_standard_normal(w: np.ndarray, against: np.ndarray, what: str) -> None:
    n = len(w)
    assert abs(w.var() - 1) < 4 * math.sqrt(2 / n), (what, "variance", w.var())
    assert abs(w.mean()) < 4 / math.sqrt(n), (what, "mean", w.mean())
    r = np.corrcoef(w, against)[0, 1]
    assert abs(r) < 4 / math.sqrt(n), (what, "correlation", r)


@pytest.fixture(scope="module")
def runs():
    """Per seed: the GNSS's e_q_x, the IMU's b_a_x and e_att_phi, samples 0 to BLOCK+3."""
    cols = {"gnss": 0, "imu_b_a": 3, "imu_e_att": 0}
    out = {k: [] for k in cols}
    for seed in SEEDS:
        d = draw_sensors(SETTINGS, DURATION, seed=seed)
        assert len(d["imu"].times) > BLOCK + 1 and len(d["gnss"].times) > BLOCK + 1
        out["gnss"].append(d["gnss"].noise[:, cols["gnss"]])
        out["imu_b_a"].append(d["imu"].noise[:, cols["imu_b_a"]])
        out["imu_e_att"].append(d["imu"].noise[:, cols["imu_e_att"]])
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize("k", [INSIDE, SEAM], ids=["inside a block", "across the seam"])
@pytest.mark.parametrize("process,sigma", [
    ("gnss", SENSOR_DEFAULTS["gnss"]["position_sigma"][0]),
    ("imu_e_att", SENSOR_DEFAULTS["imu"]["attitude_sigma"][0])],
    ids=["GNSS position error", "attitude error"])
def test_a_gauss_markov_step_has_its_law(runs, k, process, sigma):
    """The Gauss-Markov step k -> k + 1 is the exact discretization's, at the seam as
    inside a block, and the process is stationary on both sides."""
    a = math.exp(-H / TAU)
    x = runs[process]
    w = (x[:, k + 1] - a * x[:, k]) / (sigma * math.sqrt(1 - a * a))
    _check_standard_normal(w, x[:, k], f"{process} step {k}")
    for j in (k, k + 1):
        s = x[:, j] / sigma
        assert abs(s.var() - 1) < 4 * math.sqrt(2 / len(s)), (process, j, s.var())


@pytest.mark.parametrize("k", [INSIDE, SEAM], ids=["inside a block", "across the seam"])
def test_a_random_walk_step_has_its_law(runs, k):
    """The accelerometer bias's step k -> k + 1 is ``q sqrt(h)`` times a standard normal,
    independent of the step before, at the seam as inside a block."""
    q = SENSOR_DEFAULTS["imu"]["accel_bias_random_walk"]
    b = runs["imu_b_a"]
    step = (b[:, k + 1] - b[:, k]) / (q * math.sqrt(H))
    before = b[:, k] - b[:, k - 1]
    _check_standard_normal(step, before, f"b_a step {k}")


@pytest.mark.slow
def test_the_attitude_error_between_imu_samples_is_the_bridge_at_the_seam():
    """The vision's attitude error halfway between two IMU samples (its own draws'
    seam at its sample BLOCK, the IMU's at its sample BLOCK): the normalized residual
    from the Ornstein-Uhlenbeck bridge's mean is standard normal, and independent of
    the left value."""
    settings = dict(SETTINGS, vision={"rate_hz": RATE, "phase": H / 2})
    sigma = SENSOR_DEFAULTS["imu"]["attitude_sigma"][0]
    a_half = math.exp(-(H / 2) / TAU)
    mean_l = a_half * (1 - a_half**2) / (1 - a_half**4)
    sd = sigma * math.sqrt((1 - a_half**2) ** 2 / (1 - a_half**4))
    res = {INSIDE: [], SEAM + 1: []}
    left = {INSIDE: [], SEAM + 1: []}
    for seed in range(400):
        d = draw_sensors(settings, DURATION, seed=seed)
        imu, vis = d["imu"].noise[:, 0], d["vision"].noise[:, 0]
        for j in res:                       # vision j at (j + 1/2) h: IMU j and j + 1
            res[j].append((vis[j] - mean_l * (imu[j] + imu[j + 1])) / sd)
            left[j].append(imu[j])
    for j in res:
        _check_standard_normal(np.array(res[j]), np.array(left[j]), f"bridge at {j}")

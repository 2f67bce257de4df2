"""The sensors' random parts: sample times, delivery, noise.

The sensors' truth models are CasADi Functions
(:mod:`quadland_symbolic.landing.sensors`, ``sense_<name>(xp, uh, w, t, pp, p_sens,
noise)``) that take their noise as an input. This module draws that noise,
seeded, for a whole run and tells when each sample is taken and when (and
whether) it arrives:

* **sample times** ``t_k = phase + k / rate_hz`` below ``duration``, the loop's clock rule
  (:class:`quadland.engine.loop.Clock`: as the control step ticks);
* **arrival times** ``t_k + latency``;
* **delivered**: each sample is lost with probability ``dropout``
  (Bernoulli, independent);
* **noise**: one row per sample, columns laid out as the sensor's noise
  layout (:data:`quadland_symbolic.landing.sensors.NOISES`). Gauss-Markov processes
  are simulated exactly at the sample times,
  ``x_(k+1) = a x_k + sigma sqrt(1 - a^2) n_k`` with
  ``a = exp(-(t_(k+1) - t_k) / tau)``, started in their stationary
  distribution; random walks add ``q sqrt(dt) n_k``; white noise is
  ``sigma n_k``; outliers add ``outlier_sigma n`` with probability
  ``outlier_rate``.

The attitude estimator's error ``e_att`` is ONE process: it is simulated on
the IMU's times, and the vision and rangefinder samples that fall between
them are drawn from its exact conditional distribution given the
neighbouring values (the process is Markov), so a sample taken at the same
instant as the IMU's reads the same ``e_att`` and all of them are one
realization of the process.

Each sensor draws from its own generator, derived from the run's seed by a
fixed spawn key (:func:`sensor_seed`), with one sub-stream per part
(delivery, noise, outliers), so the draws of one sensor do not change when
another sensor's settings do (the vision's and rangefinder's ``e_att``
between IMU samples are the exception: they are conditioned on the IMU's
times, and the rangefinder's also on the vision's, as one process must be).

``random=False`` turns every random part off (no noise, biases, dropouts or
outliers): the Functions then return the exact truth, at the same times.

Settings are plain dicts like a scenario's ``[sensors.<name>]`` table,
checked over their defaults by :mod:`quadland.kinds.landing.sensor_settings`; the
processes are :mod:`quadland.engine.noise`'s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

from quadland.engine.loop import GRID_TOL
from quadland.engine.noise import gauss_markov, gauss_markov_fill, random_walk, sample_times
from quadland.exceptions import ScenarioError
from quadland.kinds.landing.sensor_settings import GNSS_RTK, validate_settings
from quadland_symbolic.landing.sensors import NOISES, SENSOR_NAMES
from quadland_symbolic.layout import Layout

__all__ = ["SENSOR_STREAM", "SensorSamples", "sensor_seed", "draw_sensors"]


#: First spawn-key entry of every sensor stream: keeps the sensors' draws
#: apart from the run's other children of the same seed.
SENSOR_STREAM = 0x53454E53          # "SENS"
_ATTITUDE = len(SENSOR_NAMES)        # the attitude estimator's stream index
_DELIVERY, _NOISE, _OUTLIER = 0, 1, 2


@dataclasses.dataclass(frozen=True, eq=False)
class SensorSamples:
    """One sensor's samples over a run.

    Attributes
    ----------
    name : str
        One of :data:`quadland_symbolic.landing.sensors.SENSOR_NAMES`.
    times : numpy.ndarray
        Sample times ``t_k``, s: evaluate ``sense_<name>`` at the state then.
    arrival : numpy.ndarray
        ``t_k + latency``, s: when the packet reaches the flight computer.
    delivered : numpy.ndarray of bool
        False for a lost packet (dropout).
    noise : numpy.ndarray
        Shape ``(len(times), layout.size)``: the Function's ``noise`` per sample.
    layout : Layout
        The columns of ``noise``.
    """

    name: str
    times: np.ndarray
    arrival: np.ndarray
    delivered: np.ndarray
    noise: np.ndarray
    layout: Layout

    def noise_of(self, field: str) -> np.ndarray:
        """The columns of one noise field, shape ``(len(times), size)``."""
        return self.noise[:, self.layout.slice(field)]


def sensor_seed(seed, stream: int, part: int) -> np.random.SeedSequence:
    """The seed of one part of one sensor's draws.

    ``seed`` is the run's seed (an int) or a :class:`numpy.random.SeedSequence`;
    ``stream`` a sensor's index in ``SENSOR_NAMES`` (or ``len(SENSOR_NAMES)``
    for the attitude estimator); ``part`` the kind of draw. The spawn key
    ``(..., SENSOR_STREAM, stream, part)`` depends on nothing else.
    """
    base = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return np.random.SeedSequence(base.entropy,
                                  spawn_key=tuple(base.spawn_key) + (SENSOR_STREAM, stream,
                                                                     part))


def _rng(seed, stream: int, part: int) -> np.random.Generator:
    return np.random.default_rng(sensor_seed(seed, stream, part))


def _same_times(base, t):
    """Index of each ``t`` in ``base`` where they coincide, else -1.

    Coinciding is the loop's grid rule (:data:`quadland.engine.loop.GRID_TOL`
    of ``base``'s period): the instants one grid point would merge.
    """
    tol = GRID_TOL * (base[1] - base[0] if len(base) > 1 else 1.0)
    j = np.clip(np.searchsorted(base, t), 0, max(len(base) - 1, 0))
    out = np.full(len(t), -1)
    if len(base) == 0:
        return out
    for shift in (0, -1):
        k = np.clip(j + shift, 0, len(base) - 1)
        hit = np.abs(base[k] - t) <= tol
        out = np.where((out < 0) & hit, k, out)
    return out


class _Attitude:
    """The attitude estimator's error ``e_att``: one process, shared."""

    def __init__(self, imu: Mapping, times: np.ndarray, seed, random: bool):
        self.sigma = np.asarray(imu["attitude_sigma"], dtype=float)
        self.tau = np.asarray(imu["attitude_tau"], dtype=float)
        self.white = imu["attitude_white_sigma"]
        self.seed, self.random = seed, random
        self.t = times
        if random:
            rng = _rng(seed, _ATTITUDE, 0)
            self.gm = gauss_markov(times, self.sigma, self.tau,
                                   rng.standard_normal((len(times), 3)))
            self.wn = self.white * rng.standard_normal((len(times), 3))
        else:
            self.gm = self.wn = np.zeros((len(times), 3))

    def at(self, times: np.ndarray, stream: int) -> np.ndarray:
        """``e_att`` at a sensor's times; off-IMU times join the process."""
        out = np.zeros((len(times), 3))
        if not self.random:
            return out
        idx = _same_times(self.t, times)
        on = idx >= 0
        out[on] = self.gm[idx[on]] + self.wn[idx[on]]
        off = np.flatnonzero(~on)
        if off.size:
            rng = _rng(self.seed, _ATTITUDE, 1 + stream)
            gm = gauss_markov_fill(self.t, self.gm, times[off], self.sigma, self.tau,
                                   rng.standard_normal((off.size, 3)))
            wn = self.white * rng.standard_normal((off.size, 3))
            out[off] = gm + wn
            order = np.argsort(np.concatenate([self.t, times[off]]), kind="stable")
            self.t = np.concatenate([self.t, times[off]])[order]
            self.gm = np.concatenate([self.gm, gm])[order]
            self.wn = np.concatenate([self.wn, wn])[order]
        return out


def _outliers(rng, n, cols, rate, sigma):
    hit = rng.random(n) < rate
    return np.where(hit[:, None], sigma * rng.standard_normal((n, cols)), 0.0)


def _noise(name, s, times, seed, stream, attitude, random):
    """The noise matrix of one sensor (columns: its noise layout)."""
    n = len(times)
    layout = NOISES[name]
    if not random:
        return np.zeros((n, layout.size))
    rng = _rng(seed, stream, _NOISE)
    blocks = {}
    if name == "imu":
        blocks["e_att"] = attitude.at(times, stream)
        root_rate = math.sqrt(s["rate_hz"])
        for key, b, w in (("accel", "b_a", "n_a"), ("gyro", "b_g", "n_g")):
            start = s[f"{key}_bias_sigma"] * rng.standard_normal(3)
            blocks[b] = random_walk(times, start, s[f"{key}_bias_random_walk"],
                                    rng.standard_normal((n, 3)))
            blocks[w] = s[f"{key}_noise_density"] * root_rate * rng.standard_normal((n, 3))
    elif name in ("vision", "rangefinder"):
        k = 3 if name == "vision" else 1
        blocks["e_att"] = attitude.at(times, stream)
        blocks["n_r" if k == 3 else "n_s"] = rng.standard_normal((n, k))
        blocks["o_r" if k == 3 else "o_s"] = _outliers(_rng(seed, stream, _OUTLIER), n, k,
                                                       s["outlier_rate"], s["outlier_sigma"])
    elif name == "gnss":
        sigma = np.asarray(GNSS_RTK["position_sigma"] if s["rtk"] else s["position_sigma"])
        for e in ("e_q", "e_t"):
            blocks[e] = gauss_markov(times, sigma, s["position_tau"],
                                     rng.standard_normal((n, 3)))
        for v in ("n_v1", "n_vt"):
            blocks[v] = s["velocity_sigma"] * rng.standard_normal((n, 3))
    else:
        for f in layout.fields:
            sigma = np.asarray(s[f"{f.name[2:]}_sigma"], dtype=float)
            blocks[f.name] = sigma * rng.standard_normal((n, f.size))
    return np.column_stack([blocks[f.name] for f in layout.fields]) if n else \
        np.zeros((0, layout.size))


def draw_sensors(settings: Mapping[str, Mapping] | None, duration: float, seed,
                 random: bool = True) -> dict[str, SensorSamples]:
    """Every sensor's samples, arrivals, deliveries, noise for a run.

    Parameters
    ----------
    settings : mapping or None
        ``{sensor: {key: value}}`` over :data:`SENSOR_DEFAULTS` (a missing
        sensor or key takes its default).
    duration : float
        s; samples are taken on ``[0, duration]``.
    seed : int or numpy.random.SeedSequence
        The run's seed (:func:`sensor_seed`).
    random : bool
        False: no noise, biases, dropouts or outliers (exact truth).

    Returns
    -------
    dict
        ``{name: SensorSamples}`` for every name in ``SENSOR_NAMES``.

    Examples
    --------
    >>> s = draw_sensors(None, 1.0, seed=7)
    >>> len(s["vision"].times), s["vision"].noise.shape[1]
    (25, 9)
    """
    settings = settings or {}
    unknown = sorted(set(settings) - set(SENSOR_NAMES))
    if unknown:
        raise ScenarioError(f"sensors.{unknown[0]}: unknown sensor; sensors are "
                            f"{', '.join(SENSOR_NAMES)}")
    s = {name: validate_settings(name, settings.get(name)) for name in SENSOR_NAMES}
    times = {name: sample_times(s[name]["rate_hz"], duration, s[name]["phase"])
             for name in SENSOR_NAMES}
    attitude = _Attitude(s["imu"], times["imu"], seed, random)
    out = {}
    for stream, name in enumerate(SENSOR_NAMES):
        t = times[name]
        delivered = np.ones(len(t), dtype=bool)
        if random:
            delivered = _rng(seed, stream, _DELIVERY).random(len(t)) >= s[name]["dropout"]
        out[name] = SensorSamples(name, t, t + s[name]["latency"], delivered,
                                  _noise(name, s[name], t, seed, stream, attitude, random),
                                  NOISES[name])
    return out

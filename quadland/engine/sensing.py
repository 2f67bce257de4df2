"""The sensors' random parts: sample times, delivery, noise.

The sensors' truth models are CasADi Functions
(:mod:`quadland_symbolic.landing.sensors`, ``sense_<name>(xp, uh, w, t, pp, p_sens,
noise)``) that take their noise as an input. This module draws that noise,
seeded, for a whole run and tells when each sample is taken and when (and
whether) it arrives:

* **sample times** ``t_k = phase + k / rate_hz`` on ``[0, duration]``;
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

Settings are plain dicts like a scenario's ``[sensors.<name>]`` table;
:data:`SENSOR_DEFAULTS` holds the defaults (docs/sensors.md cites each) and
:data:`SETTINGS` every key's unit, meaning and physical range.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from quadland.exceptions import ScenarioError
from quadland_symbolic.landing.sensors import NOISES, SENSOR_NAMES, SENSOR_PARAMS
from quadland_symbolic.layout import Layout

__all__ = ["Setting", "SETTINGS", "SENSOR_DEFAULTS", "GNSS_RTK", "SENSOR_STREAM",
           "SensorSamples", "validate_settings", "sensor_params", "sensor_seed", "sample_times",
           "gauss_markov", "gauss_markov_fill", "random_walk", "draw_sensors"]

_DEG = math.pi / 180.0
_G0 = 9.80665                       # m/s^2, standard gravity: datasheets' "g"


class Setting(NamedTuple):
    """One key of a ``[sensors.<name>]`` table.

    Attributes
    ----------
    unit, doc : str
    lo, hi : float
        Physical range of every value, ``lo <= v <= hi``.
    length : int or None
        None for a scalar, 3 for a list of three (x, y, z or roll, pitch, yaw).
    """

    unit: str
    doc: str
    lo: float
    hi: float
    length: int | None = None


def _common(rate_hi: float) -> dict[str, Setting]:
    return {
        "rate_hz": Setting("Hz", "samples per second", 1e-3, rate_hi),
        "latency": Setting("s", "from sample to arrival at the flight computer", 0.0, 10.0),
        "phase": Setting("s", "time of the first sample", 0.0, 10.0),
        "dropout": Setting("-", "probability that a sample is lost", 0.0, 1.0),
    }


_OUTLIERS = {
    "outlier_rate": Setting("-", "probability that a sample is an outlier", 0.0, 1.0),
    "outlier_sigma": Setting("m", "standard deviation of an outlier's offset per axis", 0.0,
                             1e3),
}

#: Every key of every sensor's table: unit, meaning, physical range (and length).
SETTINGS: Mapping[str, Mapping[str, Setting]] = MappingProxyType({
    "imu": MappingProxyType({
        **_common(1e5),
        "gyro_noise_density": Setting("rad/s/sqrt(Hz)", "gyro white-noise density", 0.0, 1.0),
        "gyro_bias_sigma": Setting("rad/s", "std of the gyro's turn-on bias per axis", 0.0,
                                   1.0),
        "gyro_bias_random_walk": Setting("rad/s/sqrt(s)", "gyro bias random-walk density",
                                         0.0, 1.0),
        "accel_noise_density": Setting("m/s^2/sqrt(Hz)", "accelerometer white-noise density",
                                       0.0, 10.0),
        "accel_bias_sigma": Setting("m/s^2", "std of the accelerometer's turn-on bias per "
                                    "axis", 0.0, 10.0),
        "accel_bias_random_walk": Setting("m/s^2/sqrt(s)", "accelerometer bias random-walk "
                                          "density", 0.0, 10.0),
        "attitude_sigma": Setting("rad", "std of the attitude estimator's Gauss-Markov error "
                                  "(roll, pitch, yaw)", 0.0, 1.0, 3),
        "attitude_tau": Setting("s", "its time constants (roll, pitch, yaw)", 1e-3, 1e9, 3),
        "attitude_white_sigma": Setting("rad", "std of its white part per axis", 0.0, 1.0),
    }),
    "vision": MappingProxyType({
        **_common(1e3), **_OUTLIERS,
        "sigma0": Setting("m", "noise per axis at zero range", 0.0, 100.0),
        "sigma_per_m": Setting("m/m", "growth of the noise per metre of range", 0.0, 10.0),
        "half_angle": Setting("rad", "half-angle of the field-of-view cone", 0.0, math.pi / 2),
        "range_min": Setting("m", "nearest range at which the marker is detected", 0.0, 1e4),
        "range_max": Setting("m", "farthest range at which the marker is detected", 0.0, 1e4),
        "small_range_min": Setting("m", "nearest range of the second, smaller marker", 0.0,
                                   1e4),
        "small_range_max": Setting("m", "farthest range of the second marker (0: none)", 0.0,
                                   1e4),
    }),
    "gnss": MappingProxyType({
        **_common(1e3),
        "position_sigma": Setting("m", "std of each receiver's position error (x, y, z)",
                                  0.0, 1e3, 3),
        "position_tau": Setting("s", "time constant of each receiver's position error", 1e-3,
                                1e9),
        "velocity_sigma": Setting("m/s", "std of each velocity's white noise per axis", 0.0,
                                  100.0),
    }),
    "rangefinder": MappingProxyType({
        **_common(1e5), **_OUTLIERS,
        "sigma0": Setting("m", "noise at zero distance", 0.0, 100.0),
        "sigma_per_m": Setting("m/m", "growth of the noise per metre", 0.0, 10.0),
        "range_min": Setting("m", "shortest distance reported", 0.0, 1e4),
        "range_max": Setting("m", "longest distance reported", 0.0, 1e4),
        "deck_half_length": Setting("m", "deck extent along its x axis from the pad centre",
                                    0.0, 1e4),
        "deck_half_width": Setting("m", "deck extent along its y axis from the pad centre", 0.0,
                                   1e4),
    }),
    "datalink": MappingProxyType({
        **_common(1e3),
        "eta2_sigma": Setting("rad", "std of the broadcast deck attitude (roll, pitch, yaw)",
                              0.0, 1.0, 3),
        "v2E_sigma": Setting("m/s", "std of the broadcast velocity per axis", 0.0, 100.0),
        "a2E_sigma": Setting("m/s^2", "std of the broadcast acceleration per axis", 0.0, 100.0),
        "w2E_sigma": Setting("rad/s", "std of the broadcast angular rate per axis", 0.0, 10.0),
        "w2E_dot_sigma": Setting("rad/s^2", "std of the broadcast angular acceleration per "
                                 "axis", 0.0, 100.0),
    }),
})

#: Default settings of each sensor; docs/sensors.md gives every value's source.
SENSOR_DEFAULTS: Mapping[str, Mapping] = MappingProxyType({
    # TDK ICM-42688-P (DS-000347), PX4's attitude_estimator_q, VectorNav VN-100:
    # docs/sensors.md, "IMU and attitude estimate".
    "imu": MappingProxyType({
        "rate_hz": 250.0, "latency": 0.0, "phase": 0.0, "dropout": 0.0,
        "gyro_noise_density": 2.8e-3 * _DEG,              # 2.8 mdps/sqrt(Hz)
        "gyro_bias_sigma": 0.005 * 20.0 * _DEG,           # 0.005 dps/degC over 20 degC
        "gyro_bias_random_walk": 0.005 * 10.0 * _DEG / math.sqrt(300.0),
        "accel_noise_density": 70e-6 * _G0,               # 70 ug/sqrt(Hz)
        "accel_bias_sigma": 0.15e-3 * 20.0 * _G0,         # 0.15 mg/degC over 20 degC
        "accel_bias_random_walk": 0.15e-3 * 10.0 * _G0 / math.sqrt(300.0),
        "attitude_sigma": (0.5 * _DEG, 0.5 * _DEG, 2.0 * _DEG),
        "attitude_tau": (5.0, 5.0, 10.0),                 # 1 / ATT_W_ACC, 1 / ATT_W_MAG
        "attitude_white_sigma": 0.01 * _DEG,
    }),
    # docs/sensors.md, "Vision": issue 17's minimums, a pinhole model of a
    # Raspberry Pi Camera Module 3 Wide and a 0.6 m marker.
    "vision": MappingProxyType({
        "rate_hz": 25.0, "latency": 0.06, "phase": 0.0, "dropout": 0.05,
        "outlier_rate": 0.01, "outlier_sigma": 0.5,
        "sigma0": 0.02, "sigma_per_m": 0.01, "half_angle": 33.5 * _DEG,
        "range_min": 0.45, "range_max": 12.0, "small_range_min": 0.08, "small_range_max": 0.0,
    }),
    # u-blox NEO-M9N, Beard & McLain's GNSS error model, PX4's EKF2_GPS_DELAY:
    # docs/sensors.md, "GNSS".
    "gnss": MappingProxyType({
        "rate_hz": 5.0, "latency": 0.11, "phase": 0.0, "dropout": 0.01,
        "position_sigma": (1.5 / 1.1774, 1.5 / 1.1774, 1.9 * 1.5 / 1.1774),
        "position_tau": 1100.0, "velocity_sigma": 0.05,
    }),
    # Benewake TFmini-S, PX4's EKF2_RNG_DELAY: docs/sensors.md, "Rangefinder".
    "rangefinder": MappingProxyType({
        "rate_hz": 125.0, "latency": 0.005, "phase": 0.0, "dropout": 0.01,
        "outlier_rate": 0.0, "outlier_sigma": 1.0,
        "sigma0": 0.03, "sigma_per_m": 0.005, "range_min": 0.1, "range_max": 7.0,
        "deck_half_length": 1.0, "deck_half_width": 0.7,
    }),
    # A GNSS-aided MEMS INS on the vehicle and issue 17's minimums:
    # docs/sensors.md, "Datalink".
    "datalink": MappingProxyType({
        "rate_hz": 10.0, "latency": 0.1, "phase": 0.0, "dropout": 0.02,
        "eta2_sigma": (0.1 * _DEG, 0.1 * _DEG, 0.2 * _DEG),
        "v2E_sigma": 0.05, "a2E_sigma": 0.05, "w2E_sigma": 0.002, "w2E_dot_sigma": 0.03,
    }),
})

#: Overrides of ``[sensors.gnss]`` for RTK (u-blox ZED-F9P, docs/sensors.md).
GNSS_RTK: Mapping = MappingProxyType({
    "position_sigma": (0.01 / 1.1774, 0.01 / 1.1774, 1.9 * 0.01 / 1.1774),
})

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


def validate_settings(name: str, values: Mapping | None = None) -> dict:
    """A sensor's settings over its defaults, checked.

    ``values`` (a ``[sensors.<name>]`` table) over :data:`SENSOR_DEFAULTS`.

    Raises
    ------
    ScenarioError
        One line naming ``sensors.<name>.<key>``: an unknown sensor or key,
        a value of the wrong kind or length, or out of its physical range.
    """
    if name not in SETTINGS:
        raise ScenarioError(f"sensors.{name}: unknown sensor; sensors are "
                            f"{', '.join(SENSOR_NAMES)}")
    schema, out = SETTINGS[name], dict(SENSOR_DEFAULTS[name])
    for key, v in (values or {}).items():
        where = f"sensors.{name}.{key}"
        if key not in schema:
            raise ScenarioError(f"{where}: unknown key; keys are {', '.join(schema)}")
        s = schema[key]
        items = v if s.length is not None else [v]
        if s.length is not None and (not isinstance(v, list | tuple) or len(v) != s.length):
            raise ScenarioError(f"{where}: must be a list of {s.length} numbers ({s.unit})")
        for x in items:
            if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
                raise ScenarioError(f"{where}: must be a finite number ({s.unit}), got {x!r}")
            if not s.lo <= x <= s.hi:
                raise ScenarioError(f"{where}: must be in [{s.lo:g}, {s.hi:g}] {s.unit}, "
                                    f"got {x!r}")
        out[key] = tuple(float(x) for x in v) if s.length is not None else float(v)
    for lo, hi in (("range_min", "range_max"), ("small_range_min", "small_range_max")):
        if lo in out and out[hi] > 0 and out[lo] > out[hi]:
            raise ScenarioError(f"sensors.{name}.{lo}: must not exceed {hi} ({out[hi]:g} m)")
    return out


def sensor_params(settings: Mapping[str, Mapping] | None = None) -> np.ndarray:
    """The Functions' ``p_sens`` from the sensors' settings.

    :data:`SENSOR_PARAMS` from the vision and rangefinder settings
    (defaults for whatever is missing).
    """
    settings = settings or {}
    v = validate_settings("vision", settings.get("vision"))
    r = validate_settings("rangefinder", settings.get("rangefinder"))
    values = {f"vision_{k}": v[k] for k in ("sigma0", "sigma_per_m", "half_angle", "range_min",
                                           "range_max", "small_range_min", "small_range_max")}
    values.update({f"rangefinder_{k}": r[k] for k in ("sigma0", "sigma_per_m", "range_min",
                                                      "range_max")})
    values.update(deck_half_length=r["deck_half_length"], deck_half_width=r["deck_half_width"])
    return SENSOR_PARAMS.pack(values)


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


def sample_times(rate_hz: float, duration: float, phase: float = 0.0) -> np.ndarray:
    """Sample times ``phase + k / rate_hz`` on ``[0, duration]``, s.

    Examples
    --------
    >>> sample_times(4.0, 1.0).tolist()
    [0.0, 0.25, 0.5, 0.75, 1.0]
    """
    if duration < phase:
        return np.zeros(0)
    n = int(math.floor((duration - phase) * rate_hz * (1 + 1e-12) + 1e-9)) + 1
    return phase + np.arange(n) / rate_hz


def _decay(dt, tau):
    """``exp(-dt / tau)``: 1 for ``tau = inf``, 0 for ``tau = 0``."""
    tau = np.asarray(tau, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(tau > 0, np.asarray(dt, dtype=float) / np.where(tau > 0, tau, 1.0),
                     np.inf)
    return np.exp(-np.where(np.asarray(dt) > 0, r, 0.0))


def gauss_markov(times, sigma, tau, normals) -> np.ndarray:
    """A first-order Gauss-Markov process at ``times``, exactly.

    ``x_0 = sigma n_0`` (stationary), ``x_(k+1) = a_k x_k + sigma sqrt(1 -
    a_k^2) n_(k+1)``, ``a_k = exp(-(t_(k+1) - t_k) / tau)``: the exact
    discretization of ``dx = -x / tau dt + sigma sqrt(2 / tau) dW``.

    Parameters
    ----------
    times : array_like, shape (n,)
        Non-decreasing, s.
    sigma, tau : array_like, shape (m,)
        Stationary standard deviation and time constant of each column
        (``tau = inf``: a random constant; ``tau = 0``: white noise).
    normals : array_like, shape (n, m)
        Standard normal draws.

    Returns
    -------
    numpy.ndarray, shape (n, m)
    """
    normals = np.asarray(normals, dtype=float)
    n, m = normals.shape
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (m,))
    tau = np.broadcast_to(np.asarray(tau, dtype=float), (m,))
    x = np.empty((n, m))
    if n == 0:
        return x
    a = _decay(np.diff(np.asarray(times, dtype=float))[:, None], tau[None, :])
    b = sigma * np.sqrt(np.clip(1.0 - a * a, 0.0, None))
    x[0] = sigma * normals[0]
    for k in range(n - 1):
        x[k + 1] = a[k] * x[k] + b[k] * normals[k + 1]
    return x


def gauss_markov_fill(known_t, known_x, new_t, sigma, tau, normals) -> np.ndarray:
    """A Gauss-Markov process at new times, given known values.

    The same process at ``new_t``, given its values at ``known_t``.

    Each new value is drawn from its exact conditional distribution given
    its nearest known neighbours (the process is Markov), the new points
    in time order, each joining the known ones: the result is one
    realization of the process on the union of the times.

    Parameters
    ----------
    known_t : array_like, shape (n,)
        Increasing, s.
    known_x : array_like, shape (n, m)
    new_t : array_like, shape (p,)
        Increasing, none equal to a ``known_t``, s.
    sigma, tau : array_like, shape (m,)
    normals : array_like, shape (p, m)
        Standard normal draws.
    """
    known_t = np.asarray(known_t, dtype=float)
    known_x = np.asarray(known_x, dtype=float)
    normals = np.asarray(normals, dtype=float)
    m = normals.shape[1]
    sigma = np.broadcast_to(np.asarray(sigma, dtype=float), (m,))
    var = sigma ** 2
    out = np.empty((len(new_t), m))
    last_t, last_x = -np.inf, None
    for i, t in enumerate(np.asarray(new_t, dtype=float)):
        j = int(np.searchsorted(known_t, t))
        if j > 0 and known_t[j - 1] > last_t:
            ta, xa = known_t[j - 1], known_x[j - 1]
        else:
            ta, xa = last_t, last_x
        has_right = j < len(known_t)
        if xa is None:                       # nothing before: the stationary law
            ta, xa = -np.inf, np.zeros(m)
        a1 = _decay(t - ta, tau) if np.isfinite(ta) else np.zeros(m)
        P = var * (1.0 - a1 * a1)            # from the left neighbour
        mean, cvar = a1 * xa, P
        if has_right:
            a2 = _decay(known_t[j] - t, tau)
            R = var * (1.0 - a2 * a2)
            den = a2 * a2 * P + R
            ok = den > 0
            K = np.where(ok, P * a2 / np.where(ok, den, 1.0), 0.0)
            mean = mean + K * (known_x[j] - a2 * mean)
            cvar = np.where(ok, P * R / np.where(ok, den, 1.0), 0.0)
        out[i] = mean + np.sqrt(np.clip(cvar, 0.0, None)) * normals[i]
        last_t, last_x = t, out[i]
    return out


def random_walk(times, start, density, normals) -> np.ndarray:
    """A random walk at ``times`` from ``start``.

    ``b_0 = start``, ``b_(k+1) = b_k + density sqrt(t_(k+1) - t_k) n_(k+1)``.

    ``start`` and ``density`` per column; ``normals`` shape ``(n, m)`` (the
    first row is unused).
    """
    normals = np.asarray(normals, dtype=float)
    steps = np.zeros_like(normals)
    if len(normals) > 1:
        dt = np.diff(np.asarray(times, dtype=float))[:, None]
        steps[1:] = np.asarray(density, dtype=float) * np.sqrt(dt) * normals[1:]
    return np.asarray(start, dtype=float) + np.cumsum(steps, axis=0)


def _same_times(base, t, tol=1e-9):
    """Index of each ``t`` in ``base`` where they coincide, else -1."""
    j = np.clip(np.searchsorted(base, t), 0, max(len(base) - 1, 0))
    out = np.full(len(t), -1)
    if len(base) == 0:
        return out
    for shift in (0, -1):
        k = np.clip(j + shift, 0, len(base) - 1)
        hit = np.abs(base[k] - t) <= tol * np.maximum(1.0, np.abs(t))
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
        sigma = np.asarray(s["position_sigma"])
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
    (26, 9)
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

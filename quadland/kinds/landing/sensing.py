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

The draws come in **blocks** of :data:`BLOCK` samples of a sensor (its samples
``k`` with ``k // BLOCK == b``), each block from its own generator, derived from the
run's seed, the sensor and the block's index by a fixed spawn key
(:func:`sensor_seed`), drawn in a fixed order (the deliveries' uniforms, the outliers'
uniforms, then every standard normal of the block). The processes run across the
blocks, each continued from the last value of the one before. So the draws of a
sample depend on the seed and its index alone: a table drawn to 12 s is the first
12 s of one drawn to 40 s, bit for bit, and :class:`SensorDraws` draws a run's
blocks only as far as its flight goes. The processes are defined on the sensors'
unbounded clocks (``phase + k / rate_hz`` for every ``k``): a duration only cuts a
window of them. The draws of one sensor do not change when another sensor's
settings do (the vision's and rangefinder's ``e_att`` between IMU samples are the
exception: they are conditioned on the IMU's values, and on each other's, in time
order, as one process must be).

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
from quadland.engine.noise import bridge, gauss_markov_after
from quadland.exceptions import ScenarioError
from quadland.kinds.landing.growing_rows import GrowingRows
from quadland.kinds.landing.sensor_clock import SensorClock, on_clock
from quadland.kinds.landing.sensor_settings import STANDARD_GRAVITY, gnss_errors, validate_settings
from quadland_symbolic.landing.sensors import NOISES, SENSOR_NAMES
from quadland_symbolic.layout import Layout

__all__ = ["SENSOR_STREAM", "BLOCK", "SensorSamples", "SensorDraws", "sensor_seed",
           "draw_sensors"]


#: First spawn-key entry of every sensor stream: keeps the sensors' draws
#: apart from the run's other children of the same seed.
SENSOR_STREAM = 0x53454E53          # "SENS"
#: Samples of a sensor per block of its draws.
BLOCK = 1024
_BLOCKS = 3                          # the spawn key's part of the blocks' draws


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


def sensor_seed(seed, stream: int, *part: int) -> np.random.SeedSequence:
    """The seed of one part of one sensor's draws.

    ``seed`` is the run's seed (an int) or a :class:`numpy.random.SeedSequence`;
    ``stream`` a sensor's index in ``SENSOR_NAMES`` (or ``len(SENSOR_NAMES) + 1`` for
    the filter's initial error); ``part`` the kind of draw (a block's: ``3, block``;
    the attitude error's draws are in the IMU's blocks). The spawn key
    ``(..., SENSOR_STREAM, stream, *part)`` depends on nothing else.
    """
    if not isinstance(seed, np.random.SeedSequence):    # an int's entropy is itself, its
        return np.random.SeedSequence(seed, spawn_key=(SENSOR_STREAM, stream, *part))  # key ()
    return np.random.SeedSequence(seed.entropy,
                                  spawn_key=tuple(seed.spawn_key) + (SENSOR_STREAM, stream,
                                                                     *part))


def _block_rng(seed, stream: int, block: int) -> np.random.Generator:
    """``numpy.random.default_rng`` of the block's seed (the same PCG64 and Generator)."""
    return np.random.Generator(np.random.PCG64(sensor_seed(seed, stream, _BLOCKS, block)))


#: Standard normals per sample of a sensor's block: its noise's, then the IMU's six of
#: the attitude error's (the vision's and rangefinder's six, for their samples between
#: the IMU's, are drawn after them, in the blocks that hold such samples).
_NORMALS = {"imu": 12 + 6, "vision": 6, "gnss": 12, "rangefinder": 2, "datalink": 15}


class _Sensor:
    """One sensor's draws, block by block, and its noise computed as far as drawn."""

    def __init__(self, name: str, stream: int, s: Mapping, seed, random: bool,
                 imu: SensorClock | None = None):
        self.name, self.stream, self.s, self.seed, self.random = name, stream, s, seed, random
        self.clock = SensorClock(s["rate_hz"], s["phase"])
        self.imu = imu                              # the IMU's clock (vision, rangefinder)
        self.layout = NOISES[name]
        self.n = 0                                  # samples drawn
        self._open: dict = {}                       # the last block begun: its generator
        # the draws' rows, room to grow; `delivered`, `noise`, `att_normals` (the attitude
        # error's normals) are views of their first `n` rows
        self._rows = GrowingRows({"delivered": (bool, ()), "noise": (float, (self.layout.size,)),
                            "att_normals": (float, (6,))})
        self.delivered, self.noise, self.att_normals = self._rows.views(0)
        self.state: dict[str, np.ndarray] = {}

    def reserve(self, count: int) -> None:
        """Room for ``count`` samples' rows; the views follow the rows (moved if grown)."""
        self._rows.reserve(count)
        self.delivered, self.noise, self.att_normals = self._rows.views(self.n)

    def ensure(self, count: int) -> None:
        """Draw the samples until ``count`` are drawn, all at once: each block's draws from
        its generator, in their order, as far as the samples go (the block's generator
        kept for its rest), the noise of the new samples computed together."""
        if self.n >= count:
            return
        self._rows.reserve(count)
        self._draw(self.n, count, *(a[self.n:count] for a in self._rows.arrays))
        self.n = count
        self.delivered, self.noise, self.att_normals = self._rows.views(self.n)

    def _draw(self, k0: int, k1: int, delivered, noise, att) -> None:
        """Samples ``k0`` to ``k1`` into their rows: deliveries, noise, e_att's normals."""
        rows = k1 - k0
        if not self.random:
            delivered[:], noise[:], att[:] = True, 0.0, 0.0
            return
        hit = np.empty(rows, dtype=bool) if "outlier_rate" in self.s else None
        z = np.empty((rows, _NORMALS[self.name]))
        att[:] = 0.0
        times = self.clock.times(k0, k1)
        k = k0
        while k < k1:                               # block by block
            b, r0 = divmod(k, BLOCK)
            r1 = min(BLOCK, k1 - b * BLOCK)
            at, rb = slice(k - k0, k - k0 + r1 - r0), slice(r0, r1)
            block = self._open if r0 else self._start(b)
            delivered[at] = block["delivered"][rb]
            if hit is not None:
                hit[at] = block["hit"][rb]
            if block["z"] is None:                  # the block's normals as far as needed
                block["rng"].standard_normal(out=z[at])
            else:
                z[at], att[at] = block["z"][rb], block["att"][rb]
            k = b * BLOCK + r1
        getattr(self, f"_{self.name}")(times, z, hit, k0, noise)
        if self.name == "imu":
            att[:] = z[:, -6:]

    def _start(self, b: int) -> dict:
        """Block ``b``'s generator and its draws before the noise's normals (the
        deliveries' and outliers' uniforms, the IMU's turn-on biases); the whole block's
        normals when it holds a sample between the IMU's (the attitude error's normals
        come after the noise's)."""
        s, B = self.s, BLOCK
        rng = _block_rng(self.seed, self.stream, b)
        block = {"rng": rng, "delivered": rng.random(B) >= s["dropout"], "z": None}
        if "outlier_rate" in s:
            block["hit"] = rng.random(B) < s["outlier_rate"]
        if self.name == "imu" and b == 0:
            self.state["bias"] = np.concatenate([s["accel_bias_sigma"] * rng.standard_normal(3),
                                                 s["gyro_bias_sigma"] * rng.standard_normal(3)])
        times = self.clock.times(b * B, (b + 1) * B)
        if self.imu is not None and np.any(on_clock(self.imu, times) < 0):
            block["z"] = rng.standard_normal((B, _NORMALS[self.name]))
            block["att"] = rng.standard_normal((B, 6))   # e_att between the IMU's samples
        self._open = block
        return block

    def _imu(self, times, z, hit, k0, out):
        """Columns b_a, n_a, b_g, n_g (e_att is the attitude's, written after); the biases' random
        walk: the block's start (the last value of the block before) plus the sum of the
        block's steps so far (both biases' six columns summed at once, each down itself)."""
        s, st, lay = self.s, self.state, self.layout
        t_prev = st.get("t")
        dt = np.diff(times if t_prev is None else np.concatenate([[t_prev], times]))
        walk = np.repeat([s["accel_bias_random_walk"], s["gyro_bias_random_walk"]], 3)
        sums, first = np.empty((len(times), 6)), int(t_prev is None)    # b_0 = start
        np.multiply(walk * np.sqrt(dt)[:, None], z[first:, :6], out=sums[first:])
        sums[:first] = 0.0
        k, k1 = k0, k0 + len(times)
        while k < k1:                               # the walk, block by block
            r0 = k % BLOCK
            at = slice(k - k0, min(k1, k - r0 + BLOCK) - k0)
            if r0 == 0:                             # a block's first sample
                st["start"] = st.get("sum", st["bias"])
            else:                                   # the sums so far, continued
                sums[at.start] += st["c"]
            np.cumsum(sums[at], axis=0, out=sums[at])
            st["c"] = sums[at.stop - 1].copy()
            np.add(st["start"], sums[at], out=sums[at])
            st["sum"] = sums[at.stop - 1].copy()
            k = k - r0 + BLOCK
        st["t"] = times[-1]                         # (e_att: SensorDraws writes every row's)
        out[:, lay.slice("b_a")], out[:, lay.slice("b_g")] = sums[:, :3], sums[:, 3:]
        white = np.repeat([s["accel_noise_density"], s["gyro_noise_density"]], 3) * \
            math.sqrt(s["rate_hz"])
        np.multiply(white[:3], z[:, 6:9], out=out[:, lay.slice("n_a")])
        np.multiply(white[3:], z[:, 9:12], out=out[:, lay.slice("n_g")])

    def _outliers(self, z, hit, k, out):
        """Columns e_att (zeros: set by :class:`SensorDraws`), white noise, outliers."""
        out[:, :3], out[:, 3:3 + k] = 0.0, z[:, :k]
        out[:, 3 + k:] = np.where(hit[:, None], self.s["outlier_sigma"] * z[:, k:2 * k], 0.0)

    def _vision(self, times, z, hit, k0, out):
        self._outliers(z, hit, 3, out)

    def _rangefinder(self, times, z, hit, k0, out):
        self._outliers(z, hit, 1, out)

    def _gnss(self, times, z, hit, k0, out):
        """Columns e_q, e_t (Gauss-Markov; white with ``relative_rtk``), n_v1, n_vt."""
        if "errors" not in self.state:               # e_q, e_t: docs/sensors.md
            self.state["errors"] = gnss_errors(self.s)
        sigma, tau = self.state["errors"]
        e = gauss_markov_after(times, sigma, tau, z[:, :6], self.state.get("t"),
                               self.state.get("e"))
        self.state["e"], self.state["t"] = e[-1], times[-1]
        out[:, :6] = e
        np.multiply(self.s["velocity_sigma"], z[:, 6:12], out=out[:, 6:12])

    def _datalink(self, times, z, hit, k0, out):
        if "sigma" not in self.state:               # each column's sigma, once
            self.state["sigma"] = np.concatenate([np.broadcast_to(np.asarray(
                self.s[f"{f.name[2:]}_sigma"], dtype=float), (f.size,))
                for f in self.layout.fields])
        np.multiply(self.state["sigma"], z, out=out)


class _Attitude:
    """The attitude estimator's error ``e_att``: one process on the IMU's clock (driven by
    the IMU's blocks), joined in time order by the vision's and rangefinder's samples
    between the IMU's."""

    def __init__(self, imu: _Sensor):
        s = imu.s
        self.imu = imu
        self.sigma = np.asarray(s["attitude_sigma"], dtype=float)
        self.tau = np.asarray(s["attitude_tau"], dtype=float)
        self.white = s["attitude_white_sigma"]
        self.aided = bool(s["attitude_gnss_aided"]) and imu.random
        self.clock = imu.clock
        self.tol = GRID_TOL * self.clock.h
        self.n = 0
        self._rows = GrowingRows({"gm": (float, (3,)), "wn": (float, (3,))})
        self.gm, self.wn = self._rows.views(0)
        self.last = None                    # the last point filled in: (t, gm, wn)

    def ensure(self, count: int) -> None:
        """The process at the IMU's first ``count`` samples (or more: whole blocks)."""
        self.imu.ensure(count)
        if self.n >= self.imu.n:
            return
        k0, k1 = self.n, self.imu.n
        z = self.imu.att_normals[k0:k1]
        if self.imu.random:
            prev = (None, None) if k0 == 0 else (self.clock.times(k0 - 1, k0)[0], self.gm[-1])
            gm = gauss_markov_after(self.clock.times(k0, k1), self.sigma, self.tau, z[:, :3],
                                    *prev)
        else:
            gm = np.zeros((k1 - k0, 3))
        self._rows.reserve(k1)
        self._rows.put(k0, (gm, self.white * z[:, 3:]))
        self.gm, self.wn = self._rows.views(k1)
        self.n = k1

    def coupling(self, rows) -> np.ndarray:
        """The GNSS-aided estimator's tilt at the IMU's ``rows`` (drawn; indices or a
        slice): the roll and pitch that level the biased accelerometer, ``[b_a_y, -b_a_x,
        0] / g`` (the body's horizontal bias over gravity, docs/sensors.md), zeros for the
        AHRS model."""
        out = np.zeros((len(range(self.imu.n)[rows]) if isinstance(rows, slice) else len(rows),
                        3))
        if self.aided:
            b_a = self.imu.noise[rows, self.imu.layout.slice("b_a")]
            out[:, 0], out[:, 1] = b_a[:, 1] / STANDARD_GRAVITY, -b_a[:, 0] / STANDARD_GRAVITY
        return out

    def on_imu(self, times: np.ndarray) -> np.ndarray:
        """Each time's IMU sample where they coincide (the loop's grid rule), else -1."""
        return on_clock(self.clock, times)

    def fill(self, points) -> dict:
        """``e_att`` at the points between IMU samples, ``[(t, key, normals(6))]`` in time
        order: each drawn given its nearest known neighbours; equal instants read one
        value. Returns ``{key: e_att}``."""
        out = {}
        for t, key, z in points:
            if self.last is not None and abs(t - self.last[0]) <= self.tol:
                out[key] = self.last[1] + self.last[2] + self.last[3]
                continue
            j = max(int(np.floor((t - self.clock.phase) * self.clock.rate)) + 1, 0)  # after t
            self.ensure(j + 1)
            t_right = self.clock.phase + self.clock.h * j
            left = None
            if j > 0:
                left = (self.clock.phase + self.clock.h * (j - 1), self.gm[j - 1])
            if self.last is not None and (left is None or self.last[0] > left[0]):
                left = (self.last[0], self.last[1])
            gm = bridge(t, left, (t_right, self.gm[j]), self.sigma, self.tau, z[:3])
            self.last = (t, gm, self.white * z[3:], self.coupling(np.array([j]))[0])
            out[key] = gm + self.last[2] + self.last[3]
        return out


class SensorDraws:
    """Every sensor's draws of one run, drawn as far as asked (:func:`draw_sensors`'s).

    :meth:`extend` draws the samples before a horizon; a window of any horizon is the
    prefix of a longer one, bit for bit (the draws come in blocks seeded by their index).
    """

    def __init__(self, settings: Mapping[str, Mapping] | None, seed, random: bool = True):
        settings = settings or {}
        unknown = sorted(set(settings) - set(SENSOR_NAMES))
        if unknown:
            raise ScenarioError(f"sensors.{unknown[0]}: unknown sensor; sensors are "
                                f"{', '.join(SENSOR_NAMES)}")
        self.settings = {name: validate_settings(name, settings.get(name))
                         for name in SENSOR_NAMES}
        self.random = random
        imu = self.settings["imu"]
        imu_clock = SensorClock(imu["rate_hz"], imu["phase"])
        self.sensors = {name: _Sensor(name, i, self.settings[name], seed, random,
                                      imu_clock if name in ("vision", "rangefinder") else None)
                        for i, name in enumerate(SENSOR_NAMES)}
        self.attitude = _Attitude(self.sensors["imu"])
        self.ready = {name: 0 for name in SENSOR_NAMES}   # samples with their e_att
        self.att_rows = 0                                  # the IMU's rows with theirs

    def extend(self, horizon: float) -> dict[str, int]:
        """Draw every sample before ``horizon``, s; returns each sensor's count."""
        return self._extend({name: sen.clock.count(horizon)
                             for name, sen in self.sensors.items()})

    def extend_ticks(self, tick: int, rate: float) -> dict[str, int]:
        """Draw every sample on the ticks of a ``rate`` Hz clock (the control's) before
        ``tick``, counted in integers; returns each sensor's count."""
        return self._extend({name: sen.clock.before_tick(tick, rate)
                             for name, sen in self.sensors.items()})

    def room(self, tick: int, rate: float) -> None:
        """Room in each sensor's rows for its samples before ``tick`` of a ``rate`` Hz clock
        (a table's next extensions: no rows copied as they grow to it)."""
        for sen in self.sensors.values():
            sen.reserve(sen.clock.before_tick(tick, rate))

    def _extend(self, counts: dict[str, int]) -> dict[str, int]:
        for name, sen in self.sensors.items():
            sen.ensure(counts[name])
        if self.random:
            self._join(counts)
            imu, att = self.sensors["imu"], self.attitude
            att.ensure(imu.n)
            k0, self.att_rows = self.att_rows, imu.n      # the IMU's rows drawn since
            imu.noise[k0:imu.n, imu.layout.slice("e_att")] = (
                att.gm[k0:imu.n] + att.wn[k0:imu.n] + att.coupling(slice(k0, imu.n)))
        self.ready.update(counts)
        return counts

    def _join(self, counts) -> None:
        """The vision's and rangefinder's ``e_att`` of the samples newly drawn."""
        points = []
        for rank, name in enumerate(("vision", "rangefinder")):
            sen, k0, k1 = self.sensors[name], self.ready[name], counts[name]
            if k1 <= k0:
                continue
            times = sen.clock.times(k0, k1)
            idx = self.attitude.on_imu(times)
            self.attitude.ensure(int(idx.max()) + 1)
            cols = sen.layout.slice("e_att")
            on = idx >= 0
            block = sen.noise[k0:k1, cols]
            block[on] = (self.attitude.gm[idx[on]] + self.attitude.wn[idx[on]]
                         + self.attitude.coupling(idx[on]))
            sen.noise[k0:k1, cols] = block
            if not on.all():
                points += [(t, (rank, name, k0 + i), sen.att_normals[k0 + i])
                           for i, t in zip(np.flatnonzero(~on), times[~on], strict=True)]
        points.sort(key=lambda p: (p[0], p[1][0]))
        for (_, name, k), e in self.attitude.fill(points).items():
            self.sensors[name].noise[k, self.sensors[name].layout.slice("e_att")] = e

    def window(self, name: str, k0: int, k1: int):
        """Sensor ``name``'s samples ``k0`` to ``k1`` (drawn): times, delivered, noise."""
        sen = self.sensors[name]
        return sen.clock.times(k0, k1), sen.delivered[k0:k1], sen.noise[k0:k1]

    def samples(self, duration: float) -> dict[str, SensorSamples]:
        """Every sensor's samples before ``duration``, s."""
        counts = self.extend(duration)
        out = {}
        for name in SENSOR_NAMES:
            t, delivered, noise = self.window(name, 0, counts[name])
            out[name] = SensorSamples(name, t, t + self.settings[name]["latency"],
                                      delivered.copy(), noise.copy(), NOISES[name])
        return out


def draw_sensors(settings: Mapping[str, Mapping] | None, duration: float, seed,
                 random: bool = True) -> dict[str, SensorSamples]:
    """Every sensor's samples, arrivals, deliveries, noise for a run.

    Parameters
    ----------
    settings : mapping or None
        ``{sensor: {key: value}}`` over :data:`SENSOR_DEFAULTS` (a missing
        sensor or key takes its default).
    duration : float
        s; samples are taken on ``[0, duration)``: the first ones of
        :class:`SensorDraws`'s, the same bits for any duration.
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
    return SensorDraws(settings, seed, random).samples(duration)

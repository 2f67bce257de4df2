"""A landing scenario's sensors and navigation filter as the sensed loop's vectors.

With ``sensors.enabled = true`` a landing flies
:func:`quadland_symbolic.landing.sensed_loop.landing_sensed_loop`: the world's sensors
sampled on the control clock, their packets delivered after their latency, the
navigation filter's estimate in place of the true state. This module forms what that
loop needs beyond the unsensed one's vectors (:mod:`quadland.kinds.landing.values`):

* the controller parameters ``pc``: the unsensed loop's, the filter's tuning
  (``[estimator]`` and the gravity of the controller's model), the sensors' truth
  constants and each sensor's delivery delay in control periods;
* the memory ``xc0``: the unsensed loop's, the filter at handover (its estimate the
  truth plus an error drawn from its initial covariance, seeded), empty delay lines;
* the per-tick table ``N``: each control tick's sample and delivery flags and noise
  (:class:`quadland.kinds.landing.sensing.SensorDraws`, seeded by ``simulation.seed``),
  drawn as far as the flight goes (:class:`TickTable`): a landing that ends at 14 s of
  a 40 s ``simulation.duration`` fills the table's rows to 16.4 s (at 250 Hz: the first
  12.3 s, then 4.1 s at a time, each a block of the IMU's 1,024 samples; each sensor's
  draws come in such blocks), the same bits as the first rows of the whole table.

``sensors.random = false`` zeroes every draw of the world: no noise, biases,
dropouts or outliers (every sample taken is delivered, the exact truth), and the
filter's initial estimate is the truth (its initial covariance unchanged).
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator

import numpy as np

from quadland.engine.direct_call import DirectCall
from quadland.engine.kept import KEPT, kept_bytes
from quadland.kinds.landing.sensing import BLOCK, SensorDraws, sensor_seed
from quadland.kinds.landing.sensor_settings import sensor_params
from quadland.kinds.landing.values import LandingValues, deck_pose_values, rotation_values
from quadland.scenario import Scenario
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_init_function,
    estimator_memory,
)
from quadland_symbolic.landing.guidance import GUIDANCE_STATE
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    TIME_CAP,
)
from quadland_symbolic.landing.loop import landing_loop_memory, landing_loop_params
from quadland_symbolic.landing.navigation import BLOCKS, DECK_INIT, IMU, NAV, estimator_params
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.sensed_loop import (
    SENSED_TICK,
    delivery_delay,
    sensed_loop_memory,
    sensed_loop_params,
)
from quadland_symbolic.landing.sensors import SENSOR_NAMES

__all__ = ["INITIAL_ERROR_STREAM", "TICK_CHUNK", "FIRST_CHUNK", "TickTable", "sensor_settings",
           "sensors_enabled", "handover", "handover_velocity_sigma", "sensed_vectors",
           "tick_table", "estimator_p", "imu_at_rest", "table_key", "drawn_table"]

#: The random stream of the filter's initial error (beside the sensors').
INITIAL_ERROR_STREAM = len(SENSOR_NAMES) + 1
#: Control ticks the per-tick table is drawn ahead by, at least, each time the flight
#: needs more (2 s at 250 Hz), and the first time (10 s: the shipped landings touch down
#: after 9 s); by default both rounded up to whole blocks of the IMU's draws (a chunk
#: that ends inside a block pays a call for the block's rest: 1,024 ticks and 3,072 at
#: 250 Hz; a one-worker campaign's table 4.7 to 3.4 ms, issue 20).
TICK_CHUNK = 500
FIRST_CHUNK = 2500
#: Chunks of :data:`TICK_CHUNK` after the first; a flight that needs more draws twice
#: the rows drawn each time, at most the table's rest (past 20.5 s at 250 Hz: a landing
#: touches down by about 12 s and settles 2 s later; a 40 s table's rest is drawn at
#: once, while a ship's flight touching down at 25 s draws 41 s of its 180 s; each
#: extension costs its calls, issue 20).
CHUNKS_BEFORE_REST = 2

#: Each sensor's columns of :data:`SENSED_TICK`: its sample flag, delivery flag and noise.
_COLUMNS = {name: tuple(SENSED_TICK.slice(f"{name}_{c}") for c in ("sampled", "kept", "noise"))
            for name in SENSOR_NAMES}

#: ``[estimator]`` keys of the initial standard deviations, in the order of NAV's fields.
_P0_KEYS = ("p0_position", "p0_velocity", "p0_target_velocity", "p0_target_acceleration",
            "p0_bias", "p0_input_bias", "p0_tilt_bias")


def sensors_enabled(scenario: Scenario) -> bool:
    """True when the scenario's controller flies on its sensors and the filter."""
    return bool(scenario.data["sensors"]["enabled"])


def sensor_settings(scenario: Scenario) -> dict[str, dict]:
    """The ``[sensors.<name>]`` tables, by sensor."""
    return {name: dict(scenario.data[f"sensors.{name}"]) for name in SENSOR_NAMES}


def estimator_p(scenario: Scenario, g: float) -> np.ndarray:
    """The filter's parameters from ``[estimator]`` and the gravity ``g`` of its model."""
    e = scenario.data["estimator"]
    lay = estimator_params()
    return lay.pack({f.name: g if f.name == "g" else e[f.name] for f in lay.fields})


def handover(scenario: Scenario, lv: LandingValues,
             random: bool | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The filter's handover at t = 0: ``(x0, P0_diag, deck0)``.

    ``x0`` is the true relative motion plus a draw (seeded by ``simulation.seed``;
    none when ``random`` is False, by default when ``sensors.random`` is false):
    from ``P0`` for every state but the quadrotor's velocity ``v1``, whose estimate is
    the GNSS's velocity when ``estimator.handover_velocity`` is ``"gnss"`` (the
    shipped landing scenarios': the autopilot's GNSS-aided navigation hands over, as EKF2
    resets its velocity to the GNSS, docs/landing.md "The handover's velocity from the
    GNSS"), so its error is drawn at the world's ``sensors.gnss.velocity_sigma``;
    ``"p0"`` (the schema's default when the key is left out) draws it from
    ``p0_velocity`` (a cold start, the sessions before the twentieth). The draw's
    standard normals are the same either way. ``P0_diag`` is the ``[estimator]``'s
    initial variances, ``deck0`` the deck's rotation at t = 0.
    """
    e, seed = scenario.data["estimator"], scenario.data["simulation"]["seed"]
    if random is None:
        random = bool(scenario.data["sensors"]["random"])
    xs = LANDING_PLANT_STATE.unpack(lv.xp0)
    p = LANDING_PLANT_PARAMS.unpack(lv.pp)
    q = QUAD6_STATE.unpack(xs["x1q"])
    deck = deck_pose_values(xs["xv"], 0.0, p["p_veh"], p["p_deck"])
    dense = [np.asarray(v, dtype=float).ravel() for v in (deck.p2, deck.v2E, deck.a2E,
                                                          deck.eta2, deck.w2E, deck.w2E_dot)]
    p2, v2, a2, eta2, w2, w2_dot = dense
    v1 = rotation_values(q["eta1"]) @ q["V1"]
    truth = NAV.pack(dict(p_r=q["p1"] - p2, v1=v1, v_t=v2, a_t=a2, b=np.zeros(3),
                          a_b=np.zeros(3), a_tilt=np.zeros(3)))
    sigma = np.concatenate([np.asarray(e[k], dtype=float) for k in _P0_KEYS])
    error = np.zeros(NAV.size)
    if random:
        rng = np.random.default_rng(sensor_seed(seed, INITIAL_ERROR_STREAM, 0))
        z = rng.standard_normal(NAV.size)
        error = sigma * z
        if e["handover_velocity"] == "gnss":
            v1 = NAV.slice("v1")
            error[v1] = handover_velocity_sigma(scenario) * z[v1]
        for name in ("b", "a_b", "a_tilt"):   # the biases' truth is the sensors' draw
            error[NAV.slice(name)] = 0.0
    return truth + error, sigma ** 2, DECK_INIT.pack(dict(eta2=eta2, w2E=w2, w2E_dot=w2_dot))


def handover_velocity_sigma(scenario: Scenario) -> float:
    """The standard deviation, per axis, of the handover's velocity error from the GNSS.

    The GNSS's velocity noise, ``sensors.gnss.velocity_sigma`` (the world's, as a
    campaign draws it). The receiver's latency is not in it: the autopilot's filter
    resets its velocity on its delayed horizon and carries it to the present on the
    IMU, as EKF2's output predictor does; what that leaves (the accelerometer's error
    over the latency) is bounded in docs/landing.md and not drawn.
    """
    return float(scenario.data["sensors.gnss"]["velocity_sigma"])


def sensed_vectors(scenario: Scenario, lv: LandingValues) -> tuple[np.ndarray, np.ndarray]:
    """``(pc, xc0)`` of the sensed loop from the unsensed loop's values ``lv``."""
    l = lv.l
    base_pc = landing_loop_params(l).unpack(lv.pc)
    base_xc = landing_loop_memory(l).unpack(lv.xc0)
    rate = scenario.data["controller"]["rate_hz"]
    settings = sensor_settings(scenario)
    g = float(scenario.data["quadrotor"]["gravity"])
    pc = sensed_loop_params(l).pack(dict(
        pp=base_pc["pp"], p_ctrl=base_pc["p_ctrl"], p_guid=base_pc["p_guid"],
        dt=base_pc["dt"], p_est=estimator_p(scenario, g), p_sens=sensor_params(settings),
        delay=[delivery_delay(settings[n]["latency"], 1.0 / rate) for n in SENSOR_NAMES],
        p_ld=LAND_DETECTOR_PARAMS.pack(scenario.data["land_detector"])))
    hover = imu_at_rest(lv.xp0, g)
    lay = sensed_loop_memory(l)
    lines = {f"line_{n}": np.zeros(lay[f"line_{n}"].size) for n in SENSOR_NAMES}
    # the detector starts from zero; the marker is not seen before the first detection,
    # and the hover point starts at the handover's estimated height when that is higher
    # (no descent on a height only GNSS knows: the guidance's "The marker")
    x0, P0_diag, deck0 = handover(scenario, lv)
    nav = handover_streaks(scenario, _estimator_init()(x0, P0_diag, deck0, 0.0)[0].ravel())
    xg = GUIDANCE_STATE.unpack(base_xc["xg"])
    xg["z_ref"] = np.maximum(xg["z_ref"], NAV.unpack(x0)["p_r"][2])
    xc0 = lay.pack(dict(xg=GUIDANCE_STATE.pack(xg), mem=base_xc["mem"], nav=nav,
                        imu_held=hover, xld=LAND_DETECTOR_STATE.zeros(), marker_age=TIME_CAP,
                        **lines))
    return pc, xc0


def handover_streaks(scenario: Scenario, nav: np.ndarray) -> np.ndarray:
    """The filter's initial memory ``nav`` with the GNSS blocks' refusal streaks set.

    ``estimator.handover_lockout_gnss`` = k > 0 starts each GNSS block's streak (E8a) at
    ``gate_lockout - k``: a block refused from the handover on is re-admitted after k
    refusals, and its first fusion resets the streak, so the approach's gates are
    ``gate_lockout``'s again (docs/landing.md, "Two flights into the roof 1.9 s after the
    handover"). 0 leaves ``nav`` as it is.
    """
    e = scenario.data["estimator"]
    k = e.get("handover_lockout_gnss", 0.0)
    if not k:
        return nav
    nav = np.array(nav, dtype=float)
    streak = estimator_memory(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING).slice("streak")
    gnss = [i for i, b in enumerate(BLOCKS) if b.sensor == "gnss"]
    nav[np.arange(streak.start, streak.stop)[gnss]] = e["gate_lockout"] - k
    return nav


@functools.cache
def _estimator_init() -> DirectCall:
    """The filter's initial memory on numbers in place (no CasADi matrices)."""
    return DirectCall(estimator_init_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING))


def imu_at_rest(xp0, g: float) -> np.ndarray:
    """The IMU sample held before the first arrives: the initial attitude and rates, the
    specific force of a hover (``g`` along body z)."""
    q = QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(xp0)["x1q"])
    return IMU.pack(dict(eta_hat=q["eta1"], f_b=[0.0, 0.0, g], omega=q["Omega1"]))


class TickTable:
    """The per-tick table of :data:`SENSED_TICK`, drawn as the flight needs it.

    ``rows`` is the whole ``(n_ticks, width)`` array, unwritten (and never read) past
    ``filled``; each :meth:`more` zeroes the next rows, draws the sensors' next samples
    (:class:`SensorDraws`) and fills their ticks' rows, ``first`` ticks the first time and
    ``chunk`` ticks at a time after (by default :data:`FIRST_CHUNK` and
    :data:`TICK_CHUNK` rounded up to whole blocks of the IMU's draws,
    :data:`~quadland.kinds.landing.sensing.BLOCK` of its samples), after ``rest`` such
    chunks twice the rows drawn each time (at least a chunk, at most the table's rest;
    by default after :data:`CHUNKS_BEFORE_REST` with the default chunk, never with a given
    one). Every row is the same bits
    however far ahead it was drawn (the draws' blocks are seeded by their index): a
    flight on it is the flight on the whole table (the simulators' ``more``,
    :func:`quadland.engine.runs.tick_source`).
    """

    def __init__(self, scenario: Scenario, n_ticks: int, chunk: int | None = None,
                 first: int | None = None, rest: int | None = None):
        d = scenario.data
        self.rate = float(d["controller"]["rate_hz"])
        self.draws = SensorDraws(sensor_settings(scenario), d["simulation"]["seed"],
                                 random=bool(d["sensors"]["random"]))
        self.rows = np.empty((n_ticks, SENSED_TICK.size))   # zeroed as it is drawn
        block = BLOCK * max(1, round(self.rate / self.draws.settings["imu"]["rate_hz"]))
        chunk_default = chunk is None
        chunk = -(-TICK_CHUNK // block) * block if chunk is None else chunk
        first = -(-FIRST_CHUNK // block) * block if first is None else first
        self.filled, self.chunk, self.first = 0, max(int(chunk), 1), max(int(first), 1)
        self.placed = {name: 0 for name in SENSOR_NAMES}
        if rest is None:                    # the default chunks' rest; none with a chunk
            rest = CHUNKS_BEFORE_REST if chunk_default else n_ticks
        self.rest = self.first + max(int(rest), 0) * self.chunk   # then doubling

    @property
    def nbytes(self) -> int:
        """Bytes of the table's rows and of its draws' rows (their room included)."""
        arrays = [self.rows, self.draws.attitude.gm, self.draws.attitude.wn]
        for sen in self.draws.sensors.values():
            arrays += [sen.delivered, sen.noise, sen.att_normals]
        return sum((a if a.base is None else a.base).nbytes for a in arrays)

    def more(self, tick: int) -> int:
        """Fill the rows past ``tick`` (up to the next chunk's end, at most the table's);
        returns the rows filled."""
        n = self.rows.shape[0]
        end = self.first
        if tick >= self.first:
            end += ((tick - self.first) // self.chunk + 1) * self.chunk
        if tick >= self.rest:                               # twice the rows drawn
            end = max(end, 2 * self.filled)
        end = min(n, end)
        if end <= self.filled:
            return self.filled
        if not self.filled:                                 # room for the chunks' draws
            self.draws.room(min(n, max(end, self.rest)), self.rate)
        self.rows[self.filled:end] = 0.0                    # a row without a sample: zeros
        counts = self.draws.extend_ticks(end, self.rate)   # the samples before `end`
        for name in SENSOR_NAMES:
            k0, k1 = self.placed[name], counts[name]
            if k1 <= k0:                                    # no sample due in the chunk
                continue
            sen = self.draws.sensors[name]                  # its ticks: all before `end`
            self._place(name, sen.clock.ticks(k0, k1, self.rate), sen.delivered[k0:k1],
                        sen.noise[k0:k1])
            self.placed[name] = k1
        self.filled = end
        return end

    def _place(self, name: str, ticks, delivered, noise) -> None:
        """Write sensor ``name``'s samples into the rows of their ``ticks`` (a slice of the
        table's rows, or ticks ascending): through a strided view of the table where the
        ticks are evenly spaced (a sensor's clock), else row by row of ``ticks``."""
        cols = _COLUMNS[name]
        if isinstance(ticks, slice):
            at = ticks
        else:
            first, last = int(ticks[0]), int(ticks[-1])
            stride = (last - first) // (len(ticks) - 1) if len(ticks) > 1 else 1
            even = stride > 0 and np.array_equal(ticks, np.arange(first, last + 1, stride))
            at = slice(first, last + 1, stride) if even else ticks
        N = self.rows
        N[at, cols[0]] = 1.0
        N[at, cols[1]] = delivered[:, None]
        N[at, cols[2]] = noise


def tick_table(scenario: Scenario, n_ticks: int) -> np.ndarray:
    """Each control tick's row of :data:`SENSED_TICK`: sample flags, delivery, noise.

    A sensor's samples fall on control ticks (the schema checks that its rate divides
    the control rate and its phase is a whole number of periods). The first rows of
    a longer table, bit for bit (:class:`TickTable`).
    """
    table = TickTable(scenario, n_ticks, first=max(n_ticks, 1))
    if n_ticks:
        table.more(n_ticks - 1)
    return table.rows


def table_key(scenario: Scenario, n_ticks: int) -> tuple:
    """Everything a run's :class:`TickTable` of ``n_ticks`` rows is drawn from: the seed,
    ``sensors.random``, the control rate and every ``[sensors.<name>]`` setting (equal
    keys, equal tables)."""
    d = scenario.data
    settings = sorted((name, sorted(s.items())) for name, s in sensor_settings(scenario).items())
    return ("tick_table", d["simulation"]["seed"], bool(d["sensors"]["random"]),
            float(d["controller"]["rate_hz"]), int(n_ticks), repr(settings))


@contextlib.contextmanager
def drawn_table(scenario: Scenario, n_ticks: int) -> Iterator[TickTable]:
    """A run's :class:`TickTable`: within :func:`quadland.engine.kept.keeping`, the one
    kept for its :func:`table_key` (drawn by an earlier run as far as that run flew,
    the same bits), else a new one; kept again when the block returns (not when it
    raises: a table left in the middle of a draw is given up)."""
    key = table_key(scenario, n_ticks) if kept_bytes() else None
    table = None if key is None else KEPT.take(key)
    if table is None:
        table = TickTable(scenario, n_ticks)
    yield table
    if key is not None:
        KEPT.give(key, table, table.nbytes)

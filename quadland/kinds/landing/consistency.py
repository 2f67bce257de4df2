"""The navigation filter's consistency: NEES and NIS over a Monte Carlo of hovers.

A filter is consistent when its errors are as large as its covariance says
(Bar-Shalom, Li and Kirubarajan, *Estimation with Applications to Tracking and
Navigation*, 2001, sec. 5.4). :func:`consistency_monte_carlo` flies ``runs`` seeded
hovers of a landing scenario on its sensors (:func:`hover_scenario`: the quadrotor
handed over at the hover point above the moving pad and held there, the guidance never
descending) and measures, at each control tick of the filter's horizon:

* the **NEES** ``e^T P^-1 e`` of each group of :data:`NEES_GROUPS`: ``e`` the filter's
  state at its horizon ``t_h`` minus the truth then
  (:func:`~quadland_symbolic.landing.sensors.navigation_truth_function`, world-side),
  ``P`` the filter's own covariance of that state (the recorded memory, every stored
  entry: the full block, not its diagonal);
* the **NIS** of each measurement block fused at that horizon (the filter's own
  ``nu^T S^-1 nu``, due blocks only, rejected and held ones included), of the packets
  its measurement model describes. A range whose beam reads the ground beside the deck
  (:func:`~quadland_symbolic.landing.sensors.range_on_deck_function`, world-side at the
  packet's sample time) is an outlier of the world, not the noise (E12) models: its NIS
  is kept apart (:attr:`ConsistencyResult.outliers`) and reported, not averaged.

Averaged over the runs, a consistent filter's NEES of an ``n``-dimensional group lies
within the two-sided chi-square bounds ``chi2.ppf(0.025, N n) / N`` ..
``chi2.ppf(0.975, N n) / N`` for ``N`` runs at about 95 % of the times; likewise each
block's NIS with ``N`` the runs where it was due, and its average over every due packet
after the settling time within the bounds of that count. The share of the times inside
is itself a noisy criterion when the errors are correlated over seconds; beside it,
:meth:`ConsistencyResult.nees_time_averaged` tests the NEES averaged over the runs and
the settled times against bounds that count the correlation
(:mod:`quadland.kinds.landing.time_averaged_nees`). docs/estimator.md ("Consistency")
gives the measured numbers.
"""

from __future__ import annotations

import dataclasses
import types

import numpy as np

from quadland.exceptions import ScenarioError
from quadland.kinds.landing.sensed import sensor_settings, sensors_enabled, tick_table
from quadland.kinds.landing.sensor_settings import sensor_params
from quadland.kinds.landing.simulate import simulate_landing
from quadland.kinds.landing.time_averaged_nees import TimeAveragedNees, time_averaged_nees
from quadland.kinds.landing.values import landing_values
from quadland.scenario import Scenario
from quadland_symbolic.landing.deck import deck_pose
from quadland_symbolic.landing.estimator import FLIGHT_COUPLING
from quadland_symbolic.landing.navigation import BLOCKS, NAV, covariance_pattern
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE
from quadland_symbolic.landing.sensed_loop import SENSED_TICK
from quadland_symbolic.landing.sensors import (
    IMU_NOISE,
    NAV_TRUTH,
    navigation_truth_function,
    range_on_deck_function,
)

__all__ = ["NEES_GROUPS", "HOVER_SETTLE", "ConsistencyResult", "chi2_bounds",
           "hover_scenario", "run_errors", "consistency_monte_carlo"]

#: s: the time after the handover before the averages count (the handover's metre-scale
#: error, the marker's first detections and the buffer's filling, 0.2 s).
HOVER_SETTLE = 3.0


def _rows(*parts) -> np.ndarray:
    """Three rows over NAV: the ``(field, sign)`` parts' vectors summed."""
    T = np.zeros((3, NAV.size))
    for name, sign in parts:
        T[:, NAV.slice(name)] += sign * np.eye(3)
    return T


_TILT_XY = np.zeros((2, NAV.size))
_TILT_XY[:, NAV.slice("a_tilt").start + np.arange(2)] = np.eye(2)

#: Each group of states whose NEES is measured: the map ``T`` (rows over NAV) whose
#: ``T x`` is compared with the same combination of the truth. ``relative`` is the
#: relative position and velocity the controller flies on (E15).
NEES_GROUPS = types.MappingProxyType({
    "relative": np.vstack([_rows(("p_r", 1)), _rows(("v1", 1), ("v_t", -1))]),
    "position": _rows(("p_r", 1)),
    "velocity": _rows(("v1", 1), ("v_t", -1)),
    "pad": np.vstack([_rows(("v_t", 1)), _rows(("a_t", 1))]),
    "tilt": _TILT_XY,
})


def chi2_bounds(dof: int, n, level: float = 0.95):
    """Two-sided ``level`` bounds of the average of ``n`` chi-square draws of ``dof``.

    ``chi2.ppf((1 -+ level) / 2, n dof) / n``; ``n`` may be an array (NaN where 0).

    Examples
    --------
    >>> lo, hi = chi2_bounds(3, 100)
    >>> round(float(lo), 3), round(float(hi), 3)
    (2.539, 3.499)
    """
    # scipy.stats takes a second to import: on first use only
    from scipy.stats import chi2

    n = np.asarray(n, dtype=float)
    safe = np.where(n > 0, n, np.nan)
    a = (1.0 - level) / 2
    return chi2.ppf(a, safe * dof) / safe, chi2.ppf(1.0 - a, safe * dof) / safe


def hover_scenario(scenario: Scenario, duration: float = 15.0) -> Scenario:
    """``scenario`` handed over at its hover point and held there for ``duration``.

    The quadrotor starts ``landing.hover_height`` above the pad centre, moving with
    it, and ``landing.dwell_time`` exceeds the run, so the guidance aligns and never
    descends. One output row per control tick, so that every horizon time of the
    filter is a row. The camera's outliers are off: they are the gate's business, not
    the noise the filter models (the rangefinder's are off as shipped).

    Raises
    ------
    ScenarioError
        The scenario does not fly on its sensors, or ``duration`` is not shorter than
        the longest dwell time the schema allows.
    """
    if not sensors_enabled(scenario):
        raise ScenarioError("sensors.enabled: the filter's consistency needs a landing "
                            "flown on its sensors")
    d = scenario.data
    dwell = 1e3
    if not 0 < duration < dwell:
        raise ScenarioError(f"duration: the hover must last between 0 and {dwell:g} s, "
                            f"got {duration!r}")
    lv = landing_values(scenario)
    x, p = LANDING_PLANT_STATE.unpack(lv.xp0), LANDING_PLANT_PARAMS.unpack(lv.pp)
    p2 = np.asarray(deck_pose(x["xv"], 0.0, p["p_veh"], p["p_deck"]).p2, dtype=float).ravel()
    return scenario.replace(**{
        "simulation.duration": float(duration),
        "simulation.output_rate_hz": float(d["controller"]["rate_hz"]),
        "initial.position1": [float(p2[0]), float(p2[1])],
        "initial.z1": float(p2[2] + d["landing"]["hover_height"]),
        "initial.relative_velocity": [0.0, 0.0, 0.0],
        "landing.dwell_time": dwell,
        "sensors.vision.outlier_rate": 0.0,
    })


def _covariances(result) -> np.ndarray:
    """The filter's recorded covariance at each row, ``(rows, n, n)``."""
    pattern = covariance_pattern(FLIGHT_COUPLING)
    i, j = (np.array(k) for k in zip(*pattern.entries, strict=True))
    values = np.column_stack([result[n] for n in pattern.element_names("P_h")])
    P = np.zeros((values.shape[0], NAV.size, NAV.size))
    P[:, i, j] = values
    P[:, j, i] = values
    return P


def _truth_rows(result) -> np.ndarray:
    """The truth of :data:`NAV_TRUTH` at every row, spread over NAV, ``(rows, n)``."""
    scenario, t = result.scenario, result["t"]
    xp = result.states[:, :LANDING_PLANT_STATE.size]
    ticks = tick_table(scenario, len(t))
    e_att = ticks[:, SENSED_TICK.slice("imu_noise")][:, IMU_NOISE.slice("e_att")]
    f = navigation_truth_function().map(len(t))
    truth = np.asarray(f(xp.T, t[None, :], landing_values(scenario).pp, e_att.T),
                       dtype=float).T
    out = np.full((len(t), NAV.size), np.nan)
    for field in NAV_TRUTH.fields:
        out[:, NAV.slice(field.name)] = truth[:, NAV_TRUTH.slice(field.name)]
    return out


def run_errors(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One hover's ``(t_h, e, P)``: the horizon times, errors and covariances.

    Row ``k`` holds the filter's memory after step ``k``: its state and covariance at
    the horizon ``t_h`` (the prior of step ``k + 1``), compared with the truth at the
    row of that time. ``result`` must have one row per control tick from ``t = 0``
    (:func:`hover_scenario`); ``e`` is NaN for the states without a truth (``b``,
    ``a_b``).
    """
    t, t_h = result["t"], result["t_h"]
    k = np.searchsorted(t, t_h - 1e-9)
    if np.any(k >= len(t)) or not np.allclose(t[np.minimum(k, len(t) - 1)], t_h,
                                              rtol=0, atol=1e-9):
        raise ValueError("run_errors: the result needs a row at every horizon time "
                         "(one output row per control tick, hover_scenario)")
    x = np.column_stack([result[f"x_h_{n}"] for n in NAV.element_names()])
    return t_h, x - _truth_rows(result)[k], _covariances(result)


def _nees(e: np.ndarray, P: np.ndarray, T: np.ndarray) -> np.ndarray:
    """``(T e)^T (T P T^T)^-1 (T e)`` at each row (``e`` read where ``T`` reads it)."""
    used = np.any(T != 0, axis=0)
    te = e[:, used] @ T[:, used].T
    S = T @ P @ T.T
    return np.einsum("ni,ni->n", te, np.linalg.solve(S, te[..., None])[..., 0])


def _on_deck(result) -> np.ndarray:
    """1 at each row where the true range beam meets the deck (world-side)."""
    scenario, t = result.scenario, result["t"]
    xp = result.states[:, :LANDING_PLANT_STATE.size]
    f = range_on_deck_function().map(len(t))
    ps = sensor_params(sensor_settings(scenario))
    return np.asarray(f(xp.T, t[None, :], landing_values(scenario).pp, ps),
                      dtype=float).ravel() > 0.5


def _nis(result) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """``(nis, outliers)``: each block's NIS of the step after each row (it fused on
    that row's prior, packets sampled at that row's horizon time), NaN where the block
    was not due or its NIS not finite; the range's split by its beam, on the deck
    (``nis``) or beside it (``outliers``, NaN elsewhere)."""
    out, outliers = {}, {}
    k = np.searchsorted(result["t"], result["t_h"] - 1e-9)
    on_deck = _on_deck(result)[np.minimum(k, len(result["t"]) - 1)]
    for b in BLOCKS:
        v = np.append(result[f"nis_{b.name}"][1:], 0.0)
        v = np.where(v > 0, v, np.nan)
        off = np.zeros(len(v), bool) if b.name != "range" else ~on_deck
        out[b.name] = np.where(off, np.nan, v)
        outliers[b.name] = np.where(off, v, np.nan)
    return out, outliers


@dataclasses.dataclass(frozen=True, eq=False)
class ConsistencyResult:
    """NEES and NIS of the filter over a Monte Carlo of hovers.

    Attributes
    ----------
    scenario : Scenario
        The hover flown (:func:`hover_scenario`), its first run's seed.
    seeds : tuple of int
        Each run's ``simulation.seed``.
    settle : float
        s: the averages count from this horizon time on.
    times : numpy.ndarray
        The filter's horizon times, s (one per control tick).
    nees : dict of str to numpy.ndarray
        ``(runs, times)`` per group of :data:`NEES_GROUPS`.
    nis : dict of str to numpy.ndarray
        ``(runs, times)`` per measurement block, NaN where not due or an outlier.
    outliers : dict of str to numpy.ndarray
        ``(runs, times)`` per block: the NIS of the due packets its model does not
        describe (a range whose beam reads the ground beside the deck), NaN elsewhere.
    """

    scenario: Scenario
    seeds: tuple[int, ...]
    settle: float
    times: np.ndarray
    nees: dict
    nis: dict
    outliers: dict

    @property
    def runs(self) -> int:
        """The number of runs."""
        return len(self.seeds)

    @property
    def settled(self) -> np.ndarray:
        """The times that count: after :attr:`settle`."""
        return self.times >= self.settle

    def nees_dof(self, group: str) -> int:
        """The dimension of a NEES group."""
        return NEES_GROUPS[group].shape[0]

    def nees_mean(self, group: str) -> np.ndarray:
        """The average NEES over the runs at each time."""
        return self.nees[group].mean(axis=0)

    def nees_bounds(self, group: str, level: float = 0.95) -> tuple[float, float]:
        """Its two-sided bounds for :attr:`runs` runs."""
        lo, hi = chi2_bounds(self.nees_dof(group), self.runs, level)
        return float(lo), float(hi)

    def nees_inside(self, group: str, level: float = 0.95) -> float:
        """The share of the settled times whose average NEES lies within its bounds."""
        lo, hi = self.nees_bounds(group, level)
        m = self.nees_mean(group)[self.settled]
        return float(np.mean((m >= lo) & (m <= hi)))

    def nees_time_averaged(self, group: str, level: float = 0.95) -> TimeAveragedNees:
        """The correlation-aware criterion: the NEES averaged over the runs and the
        settled times, against bounds with the effective number of independent times
        measured from the batch's own autocorrelation
        (:func:`~quadland.kinds.landing.time_averaged_nees.time_averaged_nees`)."""
        return time_averaged_nees(self.nees[group][:, self.settled], self.nees_dof(group),
                                  level)

    def nis_count(self, block: str) -> np.ndarray:
        """The runs in which the block was due, at each time."""
        return np.sum(np.isfinite(self.nis[block]), axis=0)

    def nis_mean(self, block: str) -> np.ndarray:
        """The average NIS over the runs where it was due, at each time (NaN: none)."""
        n = self.nis_count(block)
        total = np.nansum(self.nis[block], axis=0)
        return np.where(n > 0, total / np.maximum(n, 1), np.nan)

    def nis_bounds(self, block: str, level: float = 0.95):
        """Its two-sided bounds at each time, for that time's count."""
        return chi2_bounds(_dim(block), self.nis_count(block), level)

    def nis_inside(self, block: str, level: float = 0.95) -> float:
        """The share of the settled times with the block due whose average NIS lies
        within the bounds of that time's count."""
        lo, hi = self.nis_bounds(block, level)
        due = self.settled & (self.nis_count(block) > 0)
        m = self.nis_mean(block)[due]
        return float(np.mean((m >= lo[due]) & (m <= hi[due])))

    def nis_pooled(self, block: str, level: float = 0.95) -> tuple[float, int, float, float]:
        """``(mean, n, lo, hi)``: the average of every settled due NIS, their count and
        the bounds of that count."""
        v = self.nis[block][:, self.settled]
        v = v[np.isfinite(v)]
        lo, hi = chi2_bounds(_dim(block), len(v), level)
        return float(v.mean()) if v.size else float("nan"), int(v.size), float(lo), float(hi)

    def outlier_count(self, block: str) -> tuple[int, int]:
        """``(outliers, due)``: the settled due packets of the block its model does not
        describe, and all its settled due packets."""
        n_out = int(np.isfinite(self.outliers[block][:, self.settled]).sum())
        return n_out, n_out + int(np.isfinite(self.nis[block][:, self.settled]).sum())

    def summary(self, level: float = 0.95) -> dict:
        """Every figure as plain data: per group and per block."""
        return {
            "runs": self.runs, "settle": self.settle, "level": level,
            "nees": {g: {"dof": self.nees_dof(g),
                         "mean": float(self.nees_mean(g)[self.settled].mean()),
                         "bounds": self.nees_bounds(g, level),
                         "inside": self.nees_inside(g, level),
                         "time_averaged": dataclasses.asdict(self.nees_time_averaged(g, level))
                         | {"inside": self.nees_time_averaged(g, level).inside}}
                     for g in self.nees},
            "nis": {b: dict(zip(("mean", "n", "lo", "hi"), self.nis_pooled(b, level),
                                strict=True))
                    | {"dof": _dim(b), "inside": self.nis_inside(b, level)}
                    for b in self.nis},
            "outliers": {b: dict(zip(("n", "due"), self.outlier_count(b), strict=True))
                         | {"median_nis": _median(self.outliers[b][:, self.settled])}
                         for b in self.outliers},
        }


def _median(v: np.ndarray) -> float:
    v = v[np.isfinite(v)]
    return float(np.median(v)) if v.size else float("nan")


def _dim(block: str) -> int:
    return next(b.dim for b in BLOCKS if b.name == block)


def consistency_monte_carlo(scenario: Scenario, runs: int = 100, duration: float = 15.0,
                            seed: int | None = None,
                            settle: float = HOVER_SETTLE) -> ConsistencyResult:
    """The filter's NEES and NIS over ``runs`` seeded hovers of ``scenario``.

    Parameters
    ----------
    scenario : Scenario
        A landing scenario flown on its sensors (its filter tuning, its sensors).
    runs : int
        Hovers; run ``i`` flies with ``simulation.seed = seed + i`` (sensor noise,
        dropouts, the handover's error, turbulence).
    duration : float
        s, each hover (:func:`hover_scenario`).
    seed : int, optional
        The first run's seed; by default the scenario's ``simulation.seed``.
    settle : float
        s of horizon time before the averages count.

    Returns
    -------
    ConsistencyResult

    Raises
    ------
    ScenarioError
        As :func:`hover_scenario`, or ``runs`` below 1.
    quadland.exceptions.SimulationError
        A hover failed.
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise ScenarioError(f"runs: must be a whole number of at least 1, got {runs!r}")
    base = hover_scenario(scenario, duration)
    first = base.data["simulation"]["seed"] if seed is None else int(seed)
    seeds = tuple(first + i for i in range(runs))
    nees = {g: [] for g in NEES_GROUPS}
    nis = {b.name: [] for b in BLOCKS}
    outliers = {b.name: [] for b in BLOCKS}
    times = None
    for s in seeds:
        result = simulate_landing(base.replace(**{"simulation.seed": s}))
        t_h, e, P = run_errors(result)
        if times is not None and len(t_h) != len(times):
            raise ScenarioError(f"simulation.seed={s}: the hover ended at t = "
                                f"{result['t'][-1]:.4g} s, before its duration")
        for g, T in NEES_GROUPS.items():
            nees[g].append(_nees(e, P, T))
        inside, outside = _nis(result)
        for b in nis:
            nis[b].append(inside[b])
            outliers[b].append(outside[b])
        times = t_h if times is None else times
    return ConsistencyResult(base.replace(**{"simulation.seed": first}), seeds, float(settle),
                             times, {g: np.array(v) for g, v in nees.items()},
                             {b: np.array(v) for b, v in nis.items()},
                             {b: np.array(v) for b, v in outliers.items()})

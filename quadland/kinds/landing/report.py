"""How a landing ended: the touchdown report, summary.json's figures, the campaign metrics."""

from __future__ import annotations

import dataclasses

import numpy as np

from quadland.engine.result import SimulationResult
from quadland.kinds.landing.values import rotor_force_max
from quadland.metrics import Metric
from quadland_symbolic.landing.guidance import PHASES, TOUCHDOWN
from quadland_symbolic.landing.relative import (
    TOUCHDOWN_FIGURES,
    TOUCHDOWN_LIMITS,
    touchdown_figures_function,
)

__all__ = ["TOUCHDOWN_LIMITS", "TouchdownReport", "touchdown_report", "landing_summary",
           "LANDING_METRICS", "landing_run_metrics", "touchdown_limits"]




def touchdown_limits(scenario) -> dict[str, float]:
    """The limits a landing's figures draw: :data:`TOUCHDOWN_LIMITS` and ``F_max`` (N)."""
    g = scenario.data["landing"]
    return {**{k: float(g[k]) for k in TOUCHDOWN_LIMITS}, "F_max": rotor_force_max(scenario)}


@dataclasses.dataclass(frozen=True)
class TouchdownReport:
    """How a landing ended: the contact's figures against the scenario's limits.

    Attributes
    ----------
    touchdown : bool
        The landing gear met the deck.
    time : float or None
        When, s.
    sink_rate : float or None
        Relative vertical speed at contact, m/s, positive down: ``-dz_e``,
        the quadrotor centre's velocity relative to the deck point under
        it, along the deck normal.
    offset : float or None
        Horizontal distance of the centre from the pad centre in the deck
        frame, ``hypot(x_e, y_e)``, m.
    relative_speed : float or None
        Horizontal relative speed in the deck frame, ``hypot(dx_e, dy_e)``, m/s.
    tilt_deg : float or None
        Angle between the body z axis and the deck normal, deg.
    aborts : int
        Descents aborted before the touchdown (or the end).
    success : bool
        A touchdown with every figure within its limit.
    limits : dict
        ``max_sink_rate``, ``max_offset``, ``max_tilt_deg``,
        ``max_relative_speed``: the scenario's ``[landing]`` limits.
    """

    touchdown: bool
    time: float | None
    sink_rate: float | None
    offset: float | None
    relative_speed: float | None
    tilt_deg: float | None
    aborts: int
    success: bool
    limits: dict

    def to_dict(self) -> dict:
        """The report as plain JSON data."""
        return dataclasses.asdict(self)


def touchdown_report(result: SimulationResult) -> TouchdownReport:
    """The touchdown's figures, read at the touchdown row of a landing's result.

    The touchdown row is the first of phase 3 (``quadland_symbolic.landing.guidance.TOUCHDOWN``),
    at the instant the gear met the deck; the figures are
    ``quadland_symbolic.landing.relative.touchdown_figures`` of its relative position
    and velocity and both attitudes (the generated C example computes them
    with the same function).
    """
    g = result.scenario.data["landing"]
    limits = {k: g[k] for k in TOUCHDOWN_LIMITS}
    rows = np.flatnonzero(result["phase"] == TOUCHDOWN)
    if rows.size == 0:
        aborts = int(result["aborts"][-1]) if len(result["t"]) else 0
        return TouchdownReport(False, None, None, None, None, None, aborts, False, limits)
    k = int(rows[0])

    def row(*names):
        return [float(result[n][k]) for n in names]

    figures = np.asarray(touchdown_figures_function()(
        row("x_e", "y_e", "z_e"), row("dx_e", "dy_e", "dz_e"), row("phi1", "theta1", "psi1"),
        row("phi2", "theta2", "psi2")), dtype=float).ravel()
    f = {name: float(v) for name, v in zip(TOUCHDOWN_FIGURES.names(), figures, strict=True)}
    success = all(f[k.removeprefix("max_")] <= limits[k] for k in TOUCHDOWN_LIMITS)
    return TouchdownReport(True, float(result["t"][k]), f["sink_rate"], f["offset"],
                           f["relative_speed"], f["tilt_deg"], int(result["aborts"][k]),
                           bool(success), limits)


def landing_summary(result: SimulationResult) -> dict:
    """summary.json's figures of a landing: the ``landing`` object, phases and rotors.

    ``phases``: the time each phase was first entered (s), by name;
    ``rotors``: the extreme rotor forces and the limit ``F_max`` (N).
    """
    t = result["t"]
    phases = {}
    for number, name in enumerate(PHASES):
        rows = np.flatnonzero(result["phase"] == number)
        phases[name] = float(t[rows[0]]) if rows.size else None
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    return {"landing": touchdown_report(result).to_dict(), "phases": phases,
            "rotors": {"min": float(rotors.min()) if rotors.size else None,
                       "max": float(rotors.max()) if rotors.size else None,
                       "F_max": rotor_force_max(result.scenario)}}


#: The metrics of a landing run, in the order of runs.csv's columns; the first
#: four are limited by the scenario's ``[landing]`` keys.
LANDING_METRICS = (
    Metric("sink_rate", "m/s", "relative vertical speed at contact, positive down",
           "landing.max_sink_rate"),
    Metric("offset", "m", "horizontal distance from the pad centre at contact",
           "landing.max_offset"),
    Metric("relative_speed", "m/s", "horizontal speed relative to the deck at contact",
           "landing.max_relative_speed"),
    Metric("tilt_deg", "deg", "body z axis from the deck normal at contact",
           "landing.max_tilt_deg"),
    Metric("touchdown_time", "s", "when the gear met the deck"),
    Metric("aborts", "-", "descents aborted before the touchdown"),
    Metric("rotor_max", "N", "largest rotor force"),
)


def landing_run_metrics(result) -> dict[str, float | None]:
    """A finished landing's metrics, by name (None where undefined)."""
    report = touchdown_report(result)
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    return {"sink_rate": report.sink_rate, "offset": report.offset,
            "relative_speed": report.relative_speed, "tilt_deg": report.tilt_deg,
            "touchdown_time": report.time, "aborts": report.aborts,
            "rotor_max": float(rotors.max()) if rotors.size else None}



"""Figures of merit of a simulated landing, for summary.json."""

from __future__ import annotations

import dataclasses

import numpy as np

from quadland.simulate import SimulationResult

__all__ = ["settling_time", "summarize", "SETTLING_FRACTION", "SETTLING_FLOOR",
           "TOUCHDOWN_LIMITS", "TouchdownReport", "touchdown_report", "landing_summary"]

#: Settling band as a fraction of the initial error (the 2 % criterion).
SETTLING_FRACTION = 0.02
#: Smallest band per channel (m, rad), so that a tiny initial error or the
#: noise-driven ripple does not make the criterion meaningless.
SETTLING_FLOOR = {"z_e": 0.01, "phi_e": np.deg2rad(0.1), "theta_e": np.deg2rad(0.1),
                  "psi_e": np.deg2rad(0.1)}

#: The ``[landing]`` limits a touchdown is held to, in the report's order: each
#: is ``max_`` and the name of a ``quadland_symbolic.landing.relative.TOUCHDOWN_FIGURES``.
TOUCHDOWN_LIMITS = ("max_sink_rate", "max_offset", "max_tilt_deg", "max_relative_speed")

E1 = ("z_e", "phi_e", "theta_e", "psi_e")
E2 = ("dz_e", "p_e", "q_e", "r_e")


def settling_time(t: np.ndarray, e: np.ndarray, band: float) -> float | None:
    """First time after which ``|e| <= band`` for the rest of the run.

    Returns 0.0 when the error starts and stays inside the band and None
    when it is outside the band at the last sample.
    """
    outside = np.flatnonzero(np.abs(e) > band)
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    if last == len(t) - 1:
        return None
    return float(t[last + 1])


def _peak(t, x):
    k = int(np.argmax(np.abs(x)))
    return {"value": float(x[k]), "time": float(t[k])}


def summarize(result: SimulationResult) -> dict:
    """Figures of merit of a run (see :func:`_summarize`); a diverged run's huge
    values give infinities, reported as such, not as warnings."""
    with np.errstate(over="ignore", invalid="ignore"):
        return _summarize(result)


def _summarize(result: SimulationResult) -> dict:
    """Settling times, peak and final errors, peak inputs and estimation error.

    The reference is subtracted from ``e1`` before the settling band is
    applied (the band is 2 % of the initial error, at least
    ``SETTLING_FLOOR``).
    """
    t = result["t"]
    e1d = result.scenario.data["reference"]["e1d"]
    errors = {}
    for i, name in enumerate(E1):
        err = result[name] - e1d[i]
        band = max(SETTLING_FRACTION * abs(err[0]), SETTLING_FLOOR[name])
        errors[name] = {
            "settling_time": settling_time(t, err, band),
            "settling_band": band,
            "peak": _peak(t, err),
            "final": float(err[-1]),
        }
    for name in E2:
        errors[name] = {"peak": _peak(t, result[name]), "final": float(result[name][-1])}
    inputs = {name: _peak(t, result[name])
              for name in ("u_1", "u_2", "u_3", "u_4", "F_total", "M_x", "M_y", "M_z")}
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    inputs["rotor_min"] = float(rotors.min())
    inputs["rotor_max"] = float(rotors.max())
    half = t >= t[-1] / 2
    estimation = {}
    for i in range(1, 5):
        target, est = result[f"Delta_target_{i}"][half], result[f"Delta_hat_{i}"][half]
        rms_target = float(np.sqrt(np.mean(target ** 2)))
        rms_err = float(np.sqrt(np.mean((target - est) ** 2)))
        estimation[f"channel_{i}"] = {
            "rms_target": rms_target,
            "rms_error": rms_err,
            "relative_rms_error": rms_err / rms_target if rms_target > 0 else None,
        }
    return {"errors": errors, "inputs": inputs,
            "estimation_second_half": estimation,
            "landed_below_deck": bool(np.any(result["z_e"] < 0))}


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
    from quadland_symbolic.landing.guidance import TOUCHDOWN
    from quadland_symbolic.landing.relative import TOUCHDOWN_FIGURES, touchdown_figures_function

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
    from quadland_symbolic.landing.guidance import PHASES

    t = result["t"]
    phases = {}
    for number, name in enumerate(PHASES):
        rows = np.flatnonzero(result["phase"] == number)
        phases[name] = float(t[rows[0]]) if rows.size else None
    q = result.scenario.data["quadrotor"]
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    return {"landing": touchdown_report(result).to_dict(), "phases": phases,
            "rotors": {"min": float(rotors.min()) if rotors.size else None,
                       "max": float(rotors.max()) if rotors.size else None,
                       "F_max": q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4}}

"""The paper loop's figures of merit: settling, peaks, estimation error; its metrics."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from quadland.engine.result import SimulationResult
from quadland.metrics import Metric, settling_time

__all__ = ["SETTLING_FRACTION", "SETTLING_FLOOR", "PAPER_METRICS", "summarize",
           "paper_run_metrics", "paper_result_lines"]

#: Settling band as a fraction of the initial error (the 2 % criterion).
SETTLING_FRACTION = 0.02
#: Smallest band per channel (m, rad), so that a tiny initial error or the
#: noise-driven ripple does not make the criterion meaningless.
SETTLING_FLOOR = {"z_e": 0.01, "phi_e": np.deg2rad(0.1), "theta_e": np.deg2rad(0.1),
                  "psi_e": np.deg2rad(0.1)}

E1 = ("z_e", "phi_e", "theta_e", "psi_e")
E2 = ("dz_e", "p_e", "q_e", "r_e")


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



#: The metrics of a paper run, in the order of runs.csv's columns; their limits
#: come from the campaign's ``[campaign.limits]`` table.
PAPER_METRICS = (
    Metric("settling_time_z_e", "s", "relative altitude within its 2 % band for good"),
    Metric("settling_time_phi_e", "s", "relative roll within its band for good"),
    Metric("settling_time_theta_e", "s", "relative pitch within its band for good"),
    Metric("settling_time_psi_e", "s", "relative yaw within its band for good"),
    Metric("deck_penetration", "m", "deepest relative altitude below the reference "
           "(0 when never below)"),
    Metric("final_abs_z_e", "m", "|z_e - reference| at the end"),
    Metric("final_abs_attitude_deg", "deg", "largest |attitude error| at the end"),
    Metric("rotor_max", "N", "largest rotor force"),
)


def paper_run_metrics(result) -> dict[str, float | None]:
    """A finished paper run's metrics, by name (None where undefined)."""
    summary = summarize(result)
    errors = summary["errors"]
    e1d = result.scenario.data["reference"]["e1d"]
    z_err = result["z_e"] - e1d[0]
    out = {f"settling_time_{n}": errors[n]["settling_time"]
           for n in ("z_e", "phi_e", "theta_e", "psi_e")}
    out["deck_penetration"] = float(max(0.0, -np.min(z_err)))
    out["final_abs_z_e"] = abs(errors["z_e"]["final"])
    out["final_abs_attitude_deg"] = float(np.degrees(max(
        abs(errors[n]["final"]) for n in ("phi_e", "theta_e", "psi_e"))))
    out["rotor_max"] = summary["inputs"]["rotor_max"]
    return {k: None if v is None or not np.isfinite(v) else float(v) for k, v in out.items()}


def paper_result_lines(summary: Mapping[str, Any]) -> list[str]:
    """The paper loop's settling figures and flags, for the terminal
    (:meth:`quadland.kinds.base.LoopKind.result_lines`)."""
    errors = summary["errors"]
    parts = []
    for name in ("z_e", "phi_e", "theta_e", "psi_e"):
        e = errors[name]
        settled = "never" if e["settling_time"] is None else f"{e['settling_time']:.2f} s"
        parts.append(f"{name} {settled}")
    lines = ["paper loop: settling (within the band to the end): " + ", ".join(parts)]
    z = errors["z_e"]
    lines.append(f"  z_e: peak {z['peak']['value']:.3g} m at {z['peak']['time']:.2f} s, final "
                 f"{z['final']:.3g} m (band {z['settling_band']:g} m)")
    if summary.get("landed_below_deck"):
        lines.append("  flag: landed_below_deck: z_e went below the deck (z_e < 0)")
    return lines

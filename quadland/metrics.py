"""Figures of merit of a simulated landing, for summary.json."""

from __future__ import annotations

import numpy as np

from quadland.simulate import SimulationResult

__all__ = ["settling_time", "summarize", "SETTLING_FRACTION", "SETTLING_FLOOR"]

#: Settling band as a fraction of the initial error (the 2 % criterion).
SETTLING_FRACTION = 0.02
#: Smallest band per channel (m, rad), so that a tiny initial error or the
#: noise-driven ripple does not make the criterion meaningless.
SETTLING_FLOOR = {"z_e": 0.01, "phi_e": np.deg2rad(0.1), "theta_e": np.deg2rad(0.1),
                  "psi_e": np.deg2rad(0.1)}

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

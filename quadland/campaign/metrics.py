"""The figures a campaign records of each run, and their limits.

A landing run is judged by its touchdown (``quadland.metrics.touchdown_report``):
sink rate, offset, relative speed and tilt against the scenario's
``[landing]`` limits. A paper run by its settling times and errors, against
the upper limits of the campaign's ``[campaign.limits]`` table. Every metric
is "lower is better"; an undefined one (no touchdown, never settled) is
beyond any limit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

__all__ = ["Metric", "METRICS", "metric_names", "run_metrics", "limits_of", "violations"]


@dataclasses.dataclass(frozen=True)
class Metric:
    """One figure of a run.

    Attributes
    ----------
    name, unit, doc : str
    limit : str or None
        The scenario key that holds its upper limit, if any.
    """

    name: str
    unit: str
    doc: str
    limit: str | None = None


#: The metrics of each model, in the order of runs.csv's columns.
METRICS: Mapping[str, tuple[Metric, ...]] = {
    "landing": (
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
    ),
    "paper": (
        Metric("settling_time_z_e", "s", "relative altitude within its 2 % band for good"),
        Metric("settling_time_phi_e", "s", "relative roll within its band for good"),
        Metric("settling_time_theta_e", "s", "relative pitch within its band for good"),
        Metric("settling_time_psi_e", "s", "relative yaw within its band for good"),
        Metric("deck_penetration", "m", "deepest relative altitude below the reference "
               "(0 when never below)"),
        Metric("final_abs_z_e", "m", "|z_e - reference| at the end"),
        Metric("final_abs_attitude_deg", "deg", "largest |attitude error| at the end"),
        Metric("rotor_max", "N", "largest rotor force"),
    ),
}


def metric_names(model: str) -> list[str]:
    """The metric names of a model's runs."""
    return [m.name for m in METRICS[model]]


def limits_of(scenario, extra: Mapping[str, float] | None = None) -> dict[str, float]:
    """Each limited metric's upper limit: the scenario's own, then ``extra``'s."""
    out = {m.name: scenario[m.limit] for m in METRICS[scenario.model] if m.limit}
    out.update(extra or {})
    return out


def violations(metrics: Mapping[str, float | None], limits: Mapping[str, float],
               units: Mapping[str, str] | None = None) -> list[str]:
    """Every limit a run misses, as ``"offset 0.23 > 0.2 m"`` (or ``"offset undefined"``)."""
    out = []
    for name, limit in limits.items():
        value = metrics.get(name)
        unit = "" if units is None or units.get(name, "-") == "-" else f" {units[name]}"
        if value is None:
            out.append(f"{name} undefined")
        elif not value <= limit:
            out.append(f"{name} {value:.4g} > {limit:.4g}{unit}")
    return out


def run_metrics(result) -> dict[str, float | None]:
    """A finished run's metrics, by name (None where undefined)."""
    if result.scenario.model == "landing":
        return _landing(result)
    return _paper(result)


def _landing(result) -> dict[str, float | None]:
    from quadland.metrics import touchdown_report

    report = touchdown_report(result)
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    return {"sink_rate": report.sink_rate, "offset": report.offset,
            "relative_speed": report.relative_speed, "tilt_deg": report.tilt_deg,
            "touchdown_time": report.time, "aborts": report.aborts,
            "rotor_max": float(rotors.max()) if rotors.size else None}


def _paper(result) -> dict[str, float | None]:
    from quadland.metrics import summarize

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

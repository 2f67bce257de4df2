"""How a landing ended: the touchdown report, summary.json's figures, the campaign metrics."""

from __future__ import annotations

import dataclasses
import functools
import weakref
from collections.abc import Mapping
from typing import Any

import numpy as np

from quadland.engine.direct_call import DirectCall
from quadland.engine.result import SimulationResult
from quadland.kinds.landing.contact_report import FAILURES, contact_figures
from quadland.kinds.landing.values import rotor_force_max
from quadland.metrics import Metric
from quadland_symbolic.landing.guidance import PHASES, TOUCHDOWN
from quadland_symbolic.landing.relative import (
    TOUCHDOWN_FIGURES,
    TOUCHDOWN_LIMITS,
    touchdown_figures_function,
)

__all__ = ["TOUCHDOWN_LIMITS", "GEAR_LIMITS", "TouchdownReport", "touchdown_report",
           "landing_summary", "false_touchdown", "navigation_summary", "CONTACT_GAP",
           "landing_result_lines",
           "LANDING_METRICS", "GEAR_METRICS", "landing_run_metrics", "gear_violations",
           "touchdown_limits"]




#: The ``[landing]`` limits of a landing on the gear's contact, beside :data:`TOUCHDOWN_LIMITS`.
GEAR_LIMITS = ("max_gear_load", "max_bounce", "max_friction_margin", "pad_radius")


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
        ``max_relative_speed`` and, on the gear's contact, ``max_gear_load``,
        ``max_bounce``, ``max_friction_margin``: the scenario's ``[landing]`` limits.
    secured, bounced, tipped : bool or None
        On the gear's contact (:mod:`quadland.kinds.landing.contact_report`): held
        by the lock or by friction at the end; rebounded above ``max_bounce``;
        rolled or pitched past the tip-over angle. None: the welded idealization
        (``gear.welded``), or no touchdown.
    peak_gear_force : float or None
        The gear's peak total normal load, N, over every RK4 substep.
    impact_energy : float or None
        ``m1 v_n^2 / 2`` of the lowest foot's sink rate ``v_n`` at first contact, J.
    bounce : float or None
        The lowest foot's highest rebound above the deck with every foot off it, m.
    tip_over_deg : float or None
        The gear's static tip-over angle in the direction of the tilt at the first
        contact, deg: the tilt there is judged against it beside ``max_tilt_deg``
        (failure ``tilted``).
    on_pad : bool or None
        Every foot within ``pad_radius`` of the pad centre for ``settle_time`` after
        the contact.
    failures : list of str
        Why the landing failed: the first-contact figures over their limits, then
        :data:`~quadland.kinds.landing.contact_report.FAILURES`'s.
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
    secured: bool | None = None
    bounced: bool | None = None
    tipped: bool | None = None
    peak_gear_force: float | None = None
    impact_energy: float | None = None
    bounce: float | None = None
    tip_over_deg: float | None = None
    on_pad: bool | None = None
    failures: list = dataclasses.field(default_factory=list)

    def to_dict(self) -> dict:
        """The report as plain JSON data."""
        return dataclasses.asdict(self)


#: m: a true gear gap this small is contact (the simulator locates the touchdown's zero
#: crossing to far below it; the ride after it keeps the gap at zero).
CONTACT_GAP = 1e-6


def touchdown_report(result: SimulationResult) -> TouchdownReport:
    """The touchdown's figures, read at the touchdown row of a landing's result.

    The touchdown row is the first of phase 3 (``quadland_symbolic.landing.guidance.TOUCHDOWN``)
    whose true gear gap is closed (within :data:`CONTACT_GAP` m), the instant the gear met
    the deck (a flight code that declared touchdown above the deck, on its estimate, is
    :func:`false_touchdown`'s); the figures are
    ``quadland_symbolic.landing.relative.touchdown_figures`` of its relative position
    and velocity and both attitudes (the generated C example computes them
    with the same function).
    """
    g = result.scenario.data["landing"]
    contact = "touched" in result
    limits = {k: g[k] for k in TOUCHDOWN_LIMITS + (GEAR_LIMITS if contact else ())}
    if contact:
        rows = np.flatnonzero(result["touched"] > 0.5)
    else:
        rows = np.flatnonzero((result["phase"] == TOUCHDOWN)
                              & (result["gear_gap"] <= CONTACT_GAP))
    if rows.size == 0:
        aborts = int(result["aborts"][-1]) if len(result["t"]) else 0
        return TouchdownReport(False, None, None, None, None, None, aborts, False, limits,
                               failures=["no touchdown"])
    k = int(rows[0])

    def row(*names):
        return [float(result[n][k]) for n in names]

    figures = _touchdown_figures()(
        row("x_e", "y_e", "z_e"), row("dx_e", "dy_e", "dz_e"), row("phi1", "theta1", "psi1"),
        row("phi2", "theta2", "psi2"))[0].ravel()
    f = {name: float(v) for name, v in zip(TOUCHDOWN_FIGURES.names(), figures, strict=True)}
    failures = [n for n in TOUCHDOWN_FIGURES.names() if not f[n] <= limits["max_" + n]]
    gear = {}
    if contact:
        gear = contact_figures(result, limits, result.scenario.data["quadrotor"]["mass"])
        failures += gear.pop("failures")
        gear = {k: gear[k] for k in ("secured", "bounced", "tipped", "peak_gear_force",
                                     "impact_energy", "bounce", "tip_over_deg", "on_pad")}
    return TouchdownReport(True, float(result["t"][k]), f["sink_rate"], f["offset"],
                           f["relative_speed"], f["tilt_deg"], int(result["aborts"][k]),
                           not failures, limits, **gear, failures=failures)


@functools.cache
def _touchdown_figures() -> DirectCall:
    """``touchdown_figures`` on the row's numbers in place (no CasADi matrices)."""
    return DirectCall(touchdown_figures_function())


#: The last result :func:`_report` judged (a weak reference) and its report.
_LAST: tuple = (None, None)


def _report(result: SimulationResult) -> TouchdownReport:
    """``touchdown_report(result)``, shared by this module's readers of one result (a
    result is read-only): a campaign run's metrics, its false touchdown and its gear's
    failures read one report, not three. None of them changes it."""
    global _LAST
    ref, report = _LAST
    if ref is None or ref() is not result:
        report = touchdown_report(result)
        _LAST = (weakref.ref(result), report)
    return report


def landing_summary(result: SimulationResult) -> dict:
    """summary.json's figures of a landing: the ``landing`` object, phases and rotors.

    ``phases``: the time each phase was first entered (s), by name; on the gear's
    contact, ``landed`` is when the report judged the landing landed and secured
    (``settle_time`` after the first contact, the last row; None when not secured),
    whatever the flight code's guidance, whose touchdown verdict lags the contact,
    had entered by then;
    ``rotors``: the extreme rotor forces and the limit ``F_max`` (N).
    """
    t = result["t"]
    phases = {}
    for number, name in enumerate(PHASES):
        rows = np.flatnonzero(result["phase"] == number)
        phases[name] = float(t[rows[0]]) if rows.size else None
    report = _report(result)
    if report.secured is not None:
        phases["landed"] = float(t[-1]) if report.secured else None
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    out = {"landing": report.to_dict(), "phases": phases,
           "rotors": {"min": float(rotors.min()) if rotors.size else None,
                      "max": float(rotors.max()) if rotors.size else None,
                      "F_max": rotor_force_max(result.scenario)}}
    if "x_e_hat" in result:
        out["navigation"] = navigation_summary(result)
    return out


def false_touchdown(result: SimulationResult) -> float | None:
    """The true gear gap (m) where the flight code declared touchdown before the gear met
    the deck (its guidance entered the touchdown phase with the gap still open), or None.

    The simulator's own touchdown is the gap's zero crossing: its row and the ride after
    it are the touchdown phase by construction, so only rows before it can be false.
    """
    report = _report(result)
    flying = result["t"] < report.time if report.touchdown else np.ones(len(result["t"]), bool)
    early = np.flatnonzero(flying & (result["phase"] >= TOUCHDOWN))
    return float(result["gear_gap"][early[0]]) if early.size else None


def navigation_summary(result: SimulationResult) -> dict:
    """summary.json's ``navigation`` object of a landing flown on its sensors.

    The estimation error of the relative position and velocity (deck frame; the filter's
    estimate at each output row against the truth) as an rms over the flight and at
    touchdown, m and m/s; each measurement block's counts of fused, rejected by its gate
    and held back before the gate as unusable (a range whose beam grazes the deck or may
    miss it, E12 and E12a), and each sensor's discarded and dropped packets (the filter's
    counters at the end of the flight); the false touchdown (:func:`false_touchdown`).
    """
    report = _report(result)
    t = result["t"]
    rows = np.flatnonzero(t <= report.time) if report.touchdown else np.arange(len(t))
    err = {}
    for what, true, est in (("position", ("x_e", "y_e", "z_e"),
                             ("x_e_hat", "y_e_hat", "z_e_hat")),
                            ("velocity", ("dx_e", "dy_e", "dz_e"),
                             ("vx_e_hat", "vy_e_hat", "vz_e_hat"))):
        e = np.column_stack([result[b][rows] - result[a][rows]
                             for a, b in zip(true, est, strict=True)])
        norm = np.linalg.norm(e, axis=1)
        err[what] = {"rms": float(np.sqrt(np.mean(norm ** 2))) if norm.size else None,
                     "at_touchdown": float(norm[-1]) if report.touchdown and norm.size
                     else None}
    last = rows[-1] if rows.size else None

    def counts(prefix):
        names = [n for n in result if n.startswith(prefix)]
        return {n.removeprefix(prefix): (int(result[n][last]) if last is not None else 0)
                for n in names}

    gap = false_touchdown(result)
    return {"error": err,
            "blocks": {b: {"fused": f, "rejected": r, "held": h} for (b, f), r, h in zip(
                counts("n_fused_").items(), counts("n_rejected_").values(),
                counts("n_held_").values(), strict=True)},
            "sensors": {s: {"discarded": d, "dropped": p} for (s, d), p in zip(
                counts("n_discarded_").items(), counts("n_dropped_").values(), strict=True)},
            "false_touchdown": gap is not None, "false_touchdown_gap": gap}


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
    Metric("false_touchdown", "-", "1 when the flight code declared touchdown above the deck",
           counted="false touchdowns"),
    Metric("peak_gear_force", "N", "the gear's peak total normal load (gear contact)",
           "landing.max_gear_load"),
    Metric("bounce", "m", "the lowest foot's highest rebound with every foot off the deck",
           "landing.max_bounce"),
    Metric("impact_energy", "J", "m1 v_n^2 / 2 of the lowest foot's sink rate at first contact"),
    Metric("secured", "-", "1 when held by the lock-down or by friction at the end"),
    Metric("tipped", "-", "1 when the quadrotor tipped over on the deck", counted="tipped over"),
)

#: The gear contact's metrics: undefined (None) for the welded idealization, whose limits
#: then do not apply.
GEAR_METRICS = ("peak_gear_force", "bounce", "impact_energy", "secured", "tipped")


def landing_run_metrics(result) -> dict[str, float | None]:
    """A finished landing's metrics, by name (None where undefined)."""
    report = _report(result)
    rotors = np.vstack([result[f"F_{i}"] for i in range(1, 5)])
    return {"sink_rate": report.sink_rate, "offset": report.offset,
            "relative_speed": report.relative_speed, "tilt_deg": report.tilt_deg,
            "touchdown_time": report.time, "aborts": report.aborts,
            "rotor_max": float(rotors.max()) if rotors.size else None,
            "false_touchdown": float(false_touchdown(result) is not None),
            "peak_gear_force": report.peak_gear_force, "bounce": report.bounce,
            "impact_energy": report.impact_energy,
            "secured": None if report.secured is None else float(report.secured),
            "tipped": None if report.tipped is None else float(report.tipped)}


def gear_violations(result, metrics: Mapping[str, float | None]) -> list[str]:
    """The gear contact's failures a campaign row names beside its limits' (tipped, off the
    pad, not secured: the bounce and the gear load are limited metrics)."""
    if metrics.get("secured") is None:
        return []
    return [f for f in _report(result).failures
            if f in FAILURES and f not in ("bounced", "gear load")]




#: How ``quadland simulate`` names each touchdown figure, its unit and its limit's key.
_PRINTED = (("sink rate", "sink_rate", "m/s", "max_sink_rate"),
            ("offset", "offset", "m", "max_offset"),
            ("relative speed", "relative_speed", "m/s", "max_relative_speed"),
            ("tilt", "tilt_deg", "deg", "max_tilt_deg"))


def landing_result_lines(summary: Mapping[str, Any]) -> list[str]:
    """The landing's verdict and first-contact figures against their limits, for the
    terminal (:meth:`quadland.kinds.base.LoopKind.result_lines`)."""
    land = summary["landing"]
    aborts = f"{land['aborts']} abort{'' if land['aborts'] == 1 else 's'}"
    if not land["touchdown"]:
        return [f"landing: FAILED: no touchdown ({aborts})"]
    over = [f"{name} {land[key]:.3g} > {land['limits'][lim]:g} {unit}"
            for name, key, unit, lim in _PRINTED if land[key] > land["limits"][lim]]
    gear = land.get("secured") is not None
    if gear:
        over += [_gear_reason(land, f) for f in land.get("failures", []) if f in FAILURES]
    verdict = "success" if land["success"] else "FAILED: " + "; ".join(over)
    what = "first contact" if gear else "touchdown"
    lines = [f"landing: {verdict} ({what} at {land['time']:.2f} s, {aborts})"]
    for name, key, unit, lim in _PRINTED:
        mark = "  over" if land[key] > land["limits"][lim] else ""
        tip = ""
        if gear and key == "tilt_deg":          # judged against the gear's tip-over angle too
            tip = f", tip-over {land['tip_over_deg']:.1f}"
            mark = "  over" if mark or "tilted" in land["failures"] else ""
        lines.append(f"  {name:<15}{land[key]:8.3f} {unit:<4} limit {land['limits'][lim]:g}"
                     f"{tip}{mark}")
    if gear:
        lines += _gear_lines(land)
    nav = summary.get("navigation")
    if nav is not None:
        err = nav["error"]["position"]["at_touchdown"]
        lines.append(f"  navigation: position error at touchdown "
                     f"{'-' if err is None else f'{100 * err:.1f} cm'}, false touchdown "
                     f"{'yes' if nav['false_touchdown'] else 'no'}")
    return lines


def _gear_reason(land: Mapping[str, Any], failure: str) -> str:
    """One failure of the gear contact's, with its figure."""
    lim = land["limits"]
    return {"tilted": f"tilt {land['tilt_deg']:.1f} deg at contact past the gear's tip-over "
                      f"angle {land['tip_over_deg']:.1f} deg",
            "bounced": f"bounced {100 * land['bounce']:.1f} cm > {100 * lim['max_bounce']:g} cm",
            "tipped": "tipped over on the deck",
            "gear load": f"gear load {land['peak_gear_force']:.0f} > "
                         f"{lim['max_gear_load']:g} N",
            "off the pad": f"off the pad ({lim['pad_radius']:g} m): a foot left it or the run "
                           "ended before the settle time",
            "not secured": "not secured (a foot off the deck or the friction margin, the "
                           f"lock's pull included, not below {lim['max_friction_margin']:g})"
            }[failure]


def _gear_lines(land: Mapping[str, Any]) -> list[str]:
    """The gear contact's figures, for the terminal."""
    lim = land["limits"]

    def mark(bad):
        return "  over" if bad else ""

    return [f"  {'peak gear load':<15}{land['peak_gear_force']:8.1f} N    limit "
            f"{lim['max_gear_load']:g}{mark(land['peak_gear_force'] > lim['max_gear_load'])}",
            f"  {'impact energy':<15}{land['impact_energy']:8.3f} J",
            f"  {'bounce':<15}{land['bounce']:8.4f} m    limit {lim['max_bounce']:g}"
            f"{mark(land['bounced'])}",
            f"  secured {'yes' if land['secured'] else 'NO'}, tipped "
            f"{'YES' if land['tipped'] else 'no'}, on the pad "
            f"{'yes' if land['on_pad'] else 'NO'}"]

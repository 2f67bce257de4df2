"""Build a margin review: linearize at the operating point, break the loop, analyse it."""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from quadland.exceptions import MarginsError
from quadland.margins.report import (
    LoopMargins,
    LoopReport,
    MarginReport,
    MultiloopDiskMargin,
    Pole,
    PoleSummary,
    Requirement,
    decibels,
)

if TYPE_CHECKING:
    from quadland.analysis import DiskMargin, Margins
    from quadland.linear import Realization
    from quadland.scenario import Scenario

__all__ = ["MAX_LOOP_STATES", "loop_states", "check_request", "margin_report"]

#: Most states of a linearized loop the review analyses: its cost grows about as the
#: cube of the states (poles, frequency responses, disk margins). Measured on a loaded
#: 2-core x86-64 with one BLAS thread, as the command line runs: the highway loop with 300
#: delay periods (1,292 states) 65 s and 0.4 GB, with 400 (1,692) 172 s; the paper's
#: continuous loop at l = 350 (1,410 states) 22 s and 0.5 GB.
MAX_LOOP_STATES = 1500



def _pole(p: complex) -> Pole:
    wn = abs(p)
    return Pole(real=float(p.real), imag=float(p.imag), natural_frequency=float(wn),
                damping=float(-p.real / wn) if wn > 0 else 1.0,
                time_constant=float(-1.0 / p.real) if p.real < 0 else math.inf)


def _pole_summary(poles: np.ndarray, dt: float, count: int = 3) -> PoleSummary:
    s = np.log(poles.astype(complex)) / dt if dt else poles.astype(complex)
    upper = s[s.imag >= -1e-12]
    slow = upper[np.argsort(-upper.real)][:count]
    osc = upper[upper.imag > 1e-9]
    zeta = -osc.real / np.abs(osc)
    least = osc[np.argsort(zeta)][:count]
    return PoleSummary(count=int(poles.size), slowest=tuple(_pole(p) for p in slow),
                       least_damped=tuple(_pole(p) for p in least),
                       spectral_radius=float(np.max(np.abs(poles))) if dt else None)


def _loop_margins(name: str, cm: Margins, dm: DiskMargin, req: Requirement) -> LoopMargins:
    gms = np.asarray(cm.gain_margin, dtype=float)
    up, down = gms[gms >= 1.0], gms[gms < 1.0]
    gm_up = float(up.min()) if up.size else math.inf
    gm_down = float(down.max()) if down.size else 0.0
    w_up = cm.gm_frequency[int(np.flatnonzero(gms == gm_up)[0])] if up.size else None
    w_down = cm.gm_frequency[int(np.flatnonzero(gms == gm_down)[0])] if down.size else None
    if cm.phase_margin:
        k = int(np.argmin(cm.phase_margin))
        pm, w_pm = cm.phase_margin[k], cm.pm_frequency[k]
        j = int(np.argmin(cm.delay_margin))
        dmg, w_dm = cm.delay_margin[j], cm.dm_frequency[j]
    else:
        pm, w_pm, dmg, w_dm = math.inf, None, math.inf, None
    ok = (cm.stable and decibels(gm_up) >= req.gain_margin_db
          and -decibels(gm_down) >= req.gain_margin_db and pm >= req.phase_margin_deg)
    return LoopMargins(name, decibels(gm_up), w_up, decibels(gm_down), w_down, pm, w_pm, dmg, w_dm,
                       crossings=cm, disk=dm, stable=cm.stable, passed=bool(ok))


def _loop_report(L: Realization, names, req: Requirement, rate_hz: float | None = None,
                 delay_periods: int | None = None) -> tuple[LoopReport, np.ndarray]:
    from quadland.analysis import allmargin, closed_loop_poles, diskmargin

    classical = allmargin(L)
    per_loop, multi = diskmargin(L)
    loops = tuple(_loop_margins(name, cm, dm, req)
                  for name, cm, dm in zip(names, classical, per_loop, strict=True))
    multi_ok = (decibels(multi.gain_margin[1]) >= req.gain_margin_db
                and multi.phase_margin >= req.phase_margin_deg)
    stable = bool(classical[0].stable)
    poles = closed_loop_poles(L)
    report = LoopReport(stable=stable, loops=loops,
                        multiloop_disk=MultiloopDiskMargin(multi, bool(multi_ok)),
                        poles=_pole_summary(poles, float(L.dt) if L.dt else 0.0),
                        passed=bool(stable and multi_ok and all(m.passed for m in loops)),
                        rate_hz=rate_hz,
                        computation_delay_periods=delay_periods)
    return report, poles


def _with_extras(section: LoopReport, models, scenario: Scenario,
                 requirement: Requirement) -> LoopReport:
    """The section with its sensitivity peaks and sensor margins (:mod:`.sensitivity`)."""
    from quadland.margins.sensitivity import section_extras

    sens, sensors = section_extras(models, scenario, requirement)
    return dataclasses.replace(section, sensitivity=sens, sensors=sensors)


def _filtered_section(kind, scenario: Scenario, point, rate: float, delay_periods: int,
                      requirement: Requirement):
    """The sampled loop with the navigation filter in it and its models, when the kind
    has one for the scenario (its ``filtered_models``); ``(None, None)`` otherwise. No
    sensor-side margins: the filter time-stamps its packets (docs/margins.md)."""
    make = getattr(kind, "filtered_models", None)
    models = None if make is None else make(scenario, point, rate, delay_periods)
    if models is None:
        return None, None
    from quadland.analysis.sensitivity import sensitivity_peaks
    from quadland.margins.sensitivity import SensitivityReport

    loop = models.realizations["loop_input"]
    section, _ = _loop_report(loop, models.loop_names, requirement, rate_hz=rate,
                              delay_periods=delay_periods)
    per_loop, multi = sensitivity_peaks(loop)
    return dataclasses.replace(section, sensitivity=SensitivityReport(
        tuple(zip(models.loop_names, per_loop, strict=True)), multi)), models


def check_request(scenario: Scenario, at: float | None = None,
                  delay_periods: int | None = None) -> None:
    """Refuse, before any work, a request :func:`margin_report` cannot answer.

    Raises
    ------
    MarginsError
        Naming the parameter (``"at: ..."``, ``"delay_periods: ..."``).
    """
    if at is not None and not (math.isfinite(at) and at >= 0):
        raise MarginsError(f"at: must be a finite time >= 0 s, got {at}")
    if delay_periods is None:
        from quadland.kinds import kind_of

        delay_periods = kind_of(scenario).computation_delay(scenario)
    if isinstance(delay_periods, bool) or not isinstance(delay_periods, int | np.integer) \
            or delay_periods < 0:
        raise MarginsError(f"delay_periods: must be an integer >= 0, got {delay_periods!r}")
    base, per_period = loop_states(scenario)
    if base > MAX_LOOP_STATES:
        raise MarginsError(
            f"rbf.nodes: the loop of {scenario.data['rbf']['nodes']} nodes has {base:,} states, "
            f"over the {MAX_LOOP_STATES:,} the margin review analyses (its cost grows as the "
            "cube of the states); lower rbf.nodes")
    if float(scenario.data["controller"]["rate_hz"]) > 0:
        most = (MAX_LOOP_STATES - base) // per_period
        if delay_periods > most:
            raise MarginsError(
                f"delay_periods: must be at most {most} for this loop (each period adds "
                f"{per_period} states to its {base:,}, and the margin review analyses at most "
                f"{MAX_LOOP_STATES:,}), got {delay_periods}")
    if at is not None:
        from quadland.kinds import kind_of

        kind_of(scenario).check_operating_time(scenario, at)


def loop_states(scenario: Scenario) -> tuple[int, int]:
    """States of the scenario's loop, and how many each period of delay adds.

    The loop's state in the simulators (its kind's ``loop_model``, sized by its
    ``loop_sizes``: plant and controller, at least as many as the linearization
    keeps), plus the
    held previous command with ``controller.hold_compensation > 0``; a
    period of computation delay adds one held command (4 inputs).

    Returns
    -------
    tuple of int
        ``(states, states per delay period)``.
    """
    from quadland.kinds import kind_of

    states, m = kind_of(scenario).loop_sizes(int(scenario.data["rbf"]["nodes"]))
    hold = float(scenario.data["controller"].get("hold_compensation", 0.0))
    return states + (m if hold else 0), m


def margin_report(scenario: Scenario, at: float | None = None,
                  requirement: Requirement = Requirement(),
                  delay_periods: int | None = None, filtered: bool = True) -> MarginReport:
    """Linearize a scenario's loop and compute the margin review.

    Parameters
    ----------
    scenario : Scenario
        A paper scenario, or a landing scenario (``scenario.model =
        "landing"``): its loop hovering ``landing.hover_height`` above the
        pad, broken at the wrench into the mixer
        (the kind's ``operating_point``).
    at : float, optional
        s: linearize about the simulated state at this time instead of the
        equilibrium (paper scenarios only).
    requirement : Requirement, optional
        Default 6 dB and 45 deg.
    delay_periods : int, optional
        Control periods from sampling to commanding in the sampled loop;
        default: the kind's ``computation_delay`` (the landing's
        ``controller.delay_periods``, the paper's 1: flight code sends its
        command one period after it samples); see the kind's
        ``sampled_models``.
    filtered : bool, optional
        Also review the sampled loop with the navigation filter in it, if the kind
        has one (``filtered_models``); its verdict is then the review's.

    Returns
    -------
    MarginReport

    Raises
    ------
    MarginsError
        ``at`` is not a finite time >= 0, or given for a landing scenario
        (the message starts with ``"at: "``); ``delay_periods`` is not an
        integer >= 0.
    OperatingPointError
        No equilibrium was found, or the point is unusable.

    Notes
    -----
    The computation is a few hundred small dense factorizations. It runs
    under ``threadpoolctl.threadpool_limits(1)`` whatever the caller's BLAS
    threads: a multithreaded BLAS on a busy machine makes it several times
    slower, and a different thread count changes the last bits of the
    reported numbers (a review is the same number for number in every
    process).

    Examples
    --------
    >>> import quadland
    >>> from quadland.margins import margin_report
    >>> report = margin_report(quadland.load_scenario("paper", ["rbf.nodes=5"]))
    >>> [m.name for m in report.continuous.loops]
    ['altitude', 'roll', 'pitch', 'yaw']
    >>> report.passed
    True
    """
    # threadpoolctl limits the libraries loaded when it is called: SciPy's own OpenBLAS
    # loads with scipy.linalg, which the analysis imports, so load it first.
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        return _review(scenario, at, requirement, delay_periods, filtered)


def _review(scenario: Scenario, at: float | None, requirement: Requirement,
            delay_periods: int | None, filtered: bool) -> MarginReport:
    """margin_report's work, on one BLAS thread."""
    from quadland.kinds import kind_of

    kind = kind_of(scenario)
    if delay_periods is None:
        delay_periods = kind.computation_delay(scenario)
    check_request(scenario, at, delay_periods)
    point = kind.operating_point(scenario, at)
    models = kind.linear_models(scenario, point)
    continuous, poles = _loop_report(models.realizations["loop_input"], models.loop_names,
                                     requirement)
    continuous = _with_extras(continuous, models, scenario, requirement)
    rate = float(scenario.data["controller"]["rate_hz"])
    sampled = discrete = None
    if rate > 0:
        discrete = kind.sampled_models(scenario, point, rate, int(delay_periods))
        sampled, _ = _loop_report(discrete.realizations["loop_input"], discrete.loop_names,
                                  requirement,
                                  rate_hz=rate, delay_periods=int(delay_periods))
        sampled = _with_extras(sampled, discrete, scenario, requirement)
    flown, flown_models = _filtered_section(kind, scenario, point, rate, int(delay_periods),
                                            requirement) if rate > 0 and filtered else (None, None)
    return MarginReport(scenario, point, requirement, continuous, sampled, models, discrete,
                        poles, flown, flown_models)



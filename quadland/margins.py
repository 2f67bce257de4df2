"""Margin review of a scenario's closed loop, as typed results.

:func:`margin_report` linearizes the closed loop at an operating point (the
equilibrium, or the simulated state at time ``at``), breaks it at the plant
input u, and reports per loop (altitude, roll, pitch, yaw; for a landing
scenario thrust, roll, pitch, yaw at the wrench into the mixer) the
classical margins with the other loops closed, the loop-at-a-time and
multiloop disk margins, the closed-loop poles, and pass or fail against a
:class:`Requirement`. With ``controller.rate_hz > 0`` (always for a landing
scenario) the sampled-data loop, with its computation delay, is reported
beside the continuous one. :meth:`MarginReport.to_dict` is the
content of ``margins.json``; :func:`format_report` the table that
``quadland margins`` prints.

The text table lives here rather than in a module of its own: it reads
nothing but these dataclasses, and they and their one text form are read
and changed together. The figures need matplotlib and are in
:mod:`quadland.plots.margins`.

The margin mathematics (:mod:`quadland.analysis`) and the loop kinds'
linearization (:mod:`quadland.kinds`) are imported when a report is built, so
that the command line can read :class:`Requirement`'s defaults without loading
python-control.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from quadland.exceptions import MarginsError
from quadland.output import json_ready

if TYPE_CHECKING:
    import control

    from quadland.analysis import DiskMargin, Margins
    from quadland.linear import LinearModels, OperatingPoint
    from quadland.scenario import Scenario

__all__ = ["MAX_LOOP_STATES", "loop_states", "check_request", "Requirement", "LoopMargins",
           "MultiloopDiskMargin", "Pole", "PoleSummary", "LoopReport", "MarginReport",
           "margin_report", "format_report"]

#: Most states of a linearized loop the review analyses: its cost grows about as the
#: cube of the states (poles, frequency responses, disk margins). Measured on a loaded
#: 2-core x86-64 with one BLAS thread, as the command line runs: the highway loop with 300
#: delay periods (1,292 states) 65 s and 0.4 GB, with 400 (1,692) 172 s; the paper's
#: continuous loop at l = 350 (1,410 states) 22 s and 0.5 GB.
MAX_LOOP_STATES = 1500



@dataclasses.dataclass(frozen=True)
class Requirement:
    """Margin requirement of the review.

    Attributes
    ----------
    gain_margin_db : float
        dB, required gain margin in both directions (finite, >= 0).
    phase_margin_deg : float
        deg, required phase margin, in [0, 180).

    Raises
    ------
    MarginsError
        A value out of range; the message starts with the field's name.
    """

    gain_margin_db: float = 6.0
    phase_margin_deg: float = 45.0

    def __post_init__(self):
        if not (math.isfinite(self.gain_margin_db) and self.gain_margin_db >= 0):
            raise MarginsError(f"gain_margin_db: must be a finite number >= 0, "
                               f"got {self.gain_margin_db}")
        if not (math.isfinite(self.phase_margin_deg) and 0 <= self.phase_margin_deg < 180):
            raise MarginsError(f"phase_margin_deg: must lie in [0, 180), "
                               f"got {self.phase_margin_deg}")


@dataclasses.dataclass(frozen=True)
class LoopMargins:
    """Margins of one loop, broken at its input with the others closed.

    Attributes
    ----------
    name : str
        ``"altitude"``, ``"roll"``, ``"pitch"`` or ``"yaw"``.
    gain_margin_up_db : float
        dB, the smallest tolerated gain increase; ``inf`` without one.
    gain_margin_up_frequency : float or None
        rad/s, its phase crossover.
    gain_margin_down_db : float
        dB (<= 0), the largest tolerated gain reduction; ``-inf`` without one.
    gain_margin_down_frequency : float or None
        rad/s, its phase crossover.
    phase_margin_deg : float
        deg, the smallest phase margin; ``inf`` without a gain crossing.
    crossover_frequency : float or None
        rad/s, the gain crossover of that phase margin.
    delay_margin_s : float
        s, the smallest delay margin; ``inf`` without a gain crossing.
    delay_margin_frequency : float or None
        rad/s, its gain crossover.
    crossings : Margins
        Every crossing (:func:`quadland.analysis.allmargin`).
    disk : DiskMargin
        Loop-at-a-time disk margin (:func:`quadland.analysis.diskmargin`).
    stable : bool
        Whether the closed loop (all loops closed) is stable.
    passed : bool
        Stable, and both gain margins and the phase margin reach the
        requirement.
    """

    name: str
    gain_margin_up_db: float
    gain_margin_up_frequency: float | None
    gain_margin_down_db: float
    gain_margin_down_frequency: float | None
    phase_margin_deg: float
    crossover_frequency: float | None
    delay_margin_s: float
    delay_margin_frequency: float | None
    crossings: Margins
    disk: DiskMargin
    stable: bool
    passed: bool

    def to_dict(self) -> dict:
        """The loop's entry of ``margins.json`` (infinities kept)."""
        return dict(
            gain_margin_up_db=self.gain_margin_up_db,
            gain_margin_up_frequency=self.gain_margin_up_frequency,
            gain_margin_down_db=self.gain_margin_down_db,
            gain_margin_down_frequency=self.gain_margin_down_frequency,
            phase_margin_deg=self.phase_margin_deg,
            crossover_frequency=self.crossover_frequency,
            delay_margin_s=self.delay_margin_s,
            delay_margin_frequency=self.delay_margin_frequency,
            all_crossings={k: list(v) for k, v in dataclasses.asdict(self.crossings).items()
                           if k != "stable"},
            disk=dataclasses.asdict(self.disk), stable=self.stable, passed=self.passed)


@dataclasses.dataclass(frozen=True)
class MultiloopDiskMargin:
    """Disk margin for independent perturbations in every loop at once.

    Attributes
    ----------
    disk : DiskMargin
        A guaranteed lower bound (:func:`quadland.analysis.diskmargin`).
    passed : bool
        Its gain interval (dB, upper side) and phase reach the requirement.
    """

    disk: DiskMargin
    passed: bool

    def to_dict(self) -> dict:
        """The ``multiloop_disk`` entry of ``margins.json`` (infinities kept)."""
        return dict(dataclasses.asdict(self.disk), passed=self.passed)


@dataclasses.dataclass(frozen=True)
class Pole:
    """One closed-loop pole in the s-plane.

    Attributes
    ----------
    real : float
        1/s.
    imag : float
        rad/s.
    natural_frequency : float
        rad/s, ``|s|``.
    damping : float
        ``-Re s / |s|`` (1 for a pole at 0).
    time_constant : float
        s, ``-1 / Re s``; ``inf`` for a pole on or right of the axis.
    """

    real: float
    imag: float
    natural_frequency: float
    damping: float
    time_constant: float


@dataclasses.dataclass(frozen=True)
class PoleSummary:
    """The closed-loop poles a review looks at.

    Attributes
    ----------
    count : int
        Number of closed-loop poles (states).
    slowest : tuple of Pole
        Upper half plane, largest real part first.
    least_damped : tuple of Pole
        Complex poles (upper half plane), smallest damping first.
    spectral_radius : float or None
        ``max |z|`` of a sampled loop's poles; None for continuous time.

    Notes
    -----
    Poles of a sampled loop are mapped to the s-plane by ``s = log(z) / dt``.
    """

    count: int
    slowest: tuple[Pole, ...]
    least_damped: tuple[Pole, ...]
    spectral_radius: float | None = None

    def to_dict(self) -> dict:
        """The ``poles`` entry of ``margins.json`` (infinities kept)."""
        out = dict(count=self.count, slowest=[dataclasses.asdict(p) for p in self.slowest],
                   least_damped=[dataclasses.asdict(p) for p in self.least_damped])
        if self.spectral_radius is not None:
            out["spectral_radius"] = self.spectral_radius
        return out


@dataclasses.dataclass(frozen=True)
class LoopReport:
    """Margins of the continuous-time or of the sampled-data loop.

    Attributes
    ----------
    stable : bool
        Whether the closed loop is stable.
    loops : tuple of LoopMargins
        One per loop, in the order of the virtual inputs.
    multiloop_disk : MultiloopDiskMargin
    poles : PoleSummary
    passed : bool
        Stable and every loop passed (the multiloop disk margin has its own
        verdict and is not part of this one).
    rate_hz : float or None
        Hz, the controller's rate of a sampled loop; None for continuous time.
    computation_delay_periods : int or None
        Control periods from sampling to commanding modelled in a sampled
        loop (a ``z^-1`` on the command each); None for continuous time.
    """

    stable: bool
    loops: tuple[LoopMargins, ...]
    multiloop_disk: MultiloopDiskMargin
    poles: PoleSummary
    passed: bool
    rate_hz: float | None = None
    computation_delay_periods: int | None = None

    @property
    def computation_delay_s(self) -> float | None:
        """s, the computation delay of a sampled loop; None for continuous time."""
        if self.rate_hz is None or self.computation_delay_periods is None:
            return None
        return self.computation_delay_periods / self.rate_hz

    def loop(self, name: str) -> LoopMargins:
        """The margins of the loop called ``name``."""
        for m in self.loops:
            if m.name == name:
                return m
        raise KeyError(name)

    @property
    def failed(self) -> tuple[str, ...]:
        """Names of the loops that did not pass."""
        return tuple(m.name for m in self.loops if not m.passed)

    def to_dict(self) -> dict:
        """The ``continuous`` or ``sampled`` entry of ``margins.json`` (infinities kept)."""
        out = dict(stable=self.stable, loops={m.name: m.to_dict() for m in self.loops},
                   multiloop_disk=self.multiloop_disk.to_dict(), passed=self.passed,
                   poles=self.poles.to_dict())
        if self.rate_hz is not None:
            out["rate_hz"] = self.rate_hz
        if self.computation_delay_periods is not None:
            out["computation_delay_periods"] = self.computation_delay_periods
            out["computation_delay_s"] = self.computation_delay_s
        return out


@dataclasses.dataclass(frozen=True)
class MarginReport:
    """The margin review of one scenario at one operating point.

    Attributes
    ----------
    scenario : Scenario
    point : OperatingPoint
    requirement : Requirement
    continuous : LoopReport
        The continuous-time controller.
    sampled : LoopReport or None
        The sampled-data controller at ``controller.rate_hz``, if > 0.
    models : LinearModels
        Continuous-time models.
    sampled_models : LinearModels or None
        Zero-order-hold models at ``controller.rate_hz``, if > 0.
    poles : ndarray
        Poles of the continuous closed loop, 1/s.
    """

    scenario: Scenario
    point: OperatingPoint
    requirement: Requirement
    continuous: LoopReport
    sampled: LoopReport | None
    models: LinearModels
    sampled_models: LinearModels | None
    poles: np.ndarray

    @property
    def passed(self) -> bool:
        """Every loop of every reported controller passed."""
        return self.continuous.passed and (self.sampled is None or self.sampled.passed)

    def to_dict(self) -> dict:
        """The JSON-ready review, as ``margins.json`` holds it.

        Returns
        -------
        dict
            ``scenario``, ``overrides``, ``operating_point``,
            ``requirement``, ``loop_break``, ``continuous`` and (for a
            sampled controller) ``sampled``; ``quadland margins`` adds
            ``runtime_s``.

        Notes
        -----
        JSON has no infinity: every infinite value becomes None (``null``),
        meaning unbounded because there is no crossing. That is an upper
        gain margin of ``inf`` dB, a lower one of ``-inf`` dB, a phase or
        delay margin of ``inf``, a disk's upper gain ``inf`` (``alpha >=
        2``) and a pole's time constant ``inf``. Tuples become lists, NumPy
        scalars Python numbers.
        """
        from quadland.kinds import kind_of

        loop_break = kind_of(self.scenario).loop_break
        data = dict(scenario=self.scenario.name, overrides=list(self.scenario.overrides),
                    operating_point=self.point.to_dict(),
                    requirement=dataclasses.asdict(self.requirement),
                    loop_break=loop_break, continuous=self.continuous.to_dict())
        if self.sampled is not None:
            data["sampled"] = self.sampled.to_dict()
        return json_ready(data)


def _db(ratio: float) -> float:
    return 20.0 * math.log10(ratio) if ratio > 0 else -math.inf


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
    ok = (cm.stable and _db(gm_up) >= req.gain_margin_db
          and -_db(gm_down) >= req.gain_margin_db and pm >= req.phase_margin_deg)
    return LoopMargins(name, _db(gm_up), w_up, _db(gm_down), w_down, pm, w_pm, dmg, w_dm,
                       crossings=cm, disk=dm, stable=cm.stable, passed=bool(ok))


def _loop_report(L: control.StateSpace, names, req: Requirement, rate_hz: float | None = None,
                 delay_periods: int | None = None) -> tuple[LoopReport, np.ndarray]:
    from quadland.analysis import allmargin, closed_loop_poles, diskmargin

    classical = allmargin(L)
    per_loop, multi = diskmargin(L)
    loops = tuple(_loop_margins(name, cm, dm, req)
                  for name, cm, dm in zip(names, classical, per_loop, strict=True))
    multi_ok = (_db(multi.gain_margin[1]) >= req.gain_margin_db
                and multi.phase_margin >= req.phase_margin_deg)
    stable = bool(classical[0].stable)
    poles = closed_loop_poles(L)
    report = LoopReport(stable=stable, loops=loops,
                        multiloop_disk=MultiloopDiskMargin(multi, bool(multi_ok)),
                        poles=_pole_summary(poles, float(L.dt) if L.dt else 0.0),
                        passed=bool(stable and all(m.passed for m in loops)), rate_hz=rate_hz,
                        computation_delay_periods=delay_periods)
    return report, poles


def check_request(scenario: Scenario, at: float | None = None, delay_periods: int = 1) -> None:
    """Refuse, before any work, a request :func:`margin_report` cannot answer.

    Raises
    ------
    MarginsError
        Naming the parameter (``"at: ..."``, ``"delay_periods: ..."``).
    """
    if at is not None and not (math.isfinite(at) and at >= 0):
        raise MarginsError(f"at: must be a finite time >= 0 s, got {at}")
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

    The loop's state in the simulators (its kind's ``loop_model``: plant
    and controller, at least as many as the linearization keeps), plus the
    held previous command with ``controller.hold_compensation > 0``; a
    period of computation delay adds one held command (4 inputs).

    Returns
    -------
    tuple of int
        ``(states, states per delay period)``.
    """
    from quadland.kinds import kind_of

    loop = kind_of(scenario).loop_model(int(scenario.data["rbf"]["nodes"]))
    m = loop.held.size
    hold = float(scenario.data["controller"].get("hold_compensation", 0.0))
    return loop.state.size + (m if hold else 0), m


def margin_report(scenario: Scenario, at: float | None = None,
                  requirement: Requirement = Requirement(),
                  delay_periods: int = 1) -> MarginReport:
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
        Control periods from sampling to commanding in the sampled loop
        (default 1: flight code sends its command one period after it
        samples); see the kind's ``sampled_models``.

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
    The computation is a few hundred small dense factorizations; a
    multithreaded BLAS on a busy machine can make it several times slower.
    The command line runs it under ``threadpoolctl.threadpool_limits(1)``;
    do the same when calling it in a loop.

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
    check_request(scenario, at, delay_periods)
    from quadland.kinds import kind_of

    kind = kind_of(scenario)
    point = kind.operating_point(scenario, at)
    models = kind.linear_models(scenario, point)
    continuous, poles = _loop_report(models.loop_input, models.loop_names, requirement)
    rate = float(scenario.data["controller"]["rate_hz"])
    sampled = discrete = None
    if rate > 0:
        discrete = kind.sampled_models(scenario, point, rate, int(delay_periods))
        sampled, _ = _loop_report(discrete.loop_input, discrete.loop_names, requirement,
                                  rate_hz=rate, delay_periods=int(delay_periods))
    return MarginReport(scenario, point, requirement, continuous, sampled, models, discrete,
                        poles)


def _fmt(x, spec=".3g", none="-"):
    if x is None:
        return none
    if isinstance(x, float) and math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return format(x, spec)


def _verdict(passed: bool) -> str:
    return "pass" if passed else "FAIL"


def _table(section: LoopReport, title: str, req: Requirement) -> list[str]:
    lines = [title,
             f"  {'loop':<9}{'GM up':>8}{'GM down':>9}{'PM':>8}{'w_c':>9}{'DM':>9}"
             f"{'w_180':>9}{'disk a':>8}{'disk GM':>9}{'disk PM':>9}  verdict",
             f"  {'':<9}{'dB':>8}{'dB':>9}{'deg':>8}{'rad/s':>9}{'s':>9}"
             f"{'rad/s':>9}{'':>8}{'+-dB':>9}{'deg':>9}"]
    for r in section.loops:
        d = r.disk
        tighter_up = r.gain_margin_up_db <= -r.gain_margin_down_db
        w180 = r.gain_margin_up_frequency if tighter_up else r.gain_margin_down_frequency
        lines.append(
            f"  {r.name:<9}{_fmt(r.gain_margin_up_db, '.1f'):>8}"
            f"{_fmt(r.gain_margin_down_db, '.1f'):>9}{_fmt(r.phase_margin_deg, '.1f'):>8}"
            f"{_fmt(r.crossover_frequency, '.3g'):>9}{_fmt(r.delay_margin_s, '.3g'):>9}"
            f"{_fmt(w180, '.3g'):>9}{d.disk_margin:>8.3f}"
            f"{_fmt(_db(d.gain_margin[1]), '.1f'):>9}{d.phase_margin:>9.1f}"
            f"  {_verdict(r.passed)}")
    m = section.multiloop_disk.disk
    lines.append(f"  multiloop disk margin: alpha = {m.disk_margin:.3f}, gain "
                 f"[{m.gain_margin[0]:.3f}, {_fmt(m.gain_margin[1], '.3f')}] "
                 f"(+-{_fmt(_db(m.gain_margin[1]), '.1f')} dB), phase +-"
                 f"{m.phase_margin:.1f} deg, at {m.frequency:.3g} rad/s: "
                 f"{_verdict(section.multiloop_disk.passed)}")
    p = section.poles
    slow = ", ".join(f"{q.real:.4g}{q.imag:+.4g}j" for q in p.slowest)
    least = ", ".join(f"{q.real:.4g}{q.imag:+.4g}j (zeta {q.damping:.3f})"
                      for q in p.least_damped) or "none (all real)"
    lines.append(f"  closed loop ({p.count} states): "
                 f"{'stable' if section.stable else 'UNSTABLE'}")
    lines.append(f"  slowest poles (s-plane): {slow}")
    lines.append(f"  least damped poles:      {least}")
    lines.append(f"  requirement {req.gain_margin_db:g} dB / {req.phase_margin_deg:g} deg "
                 f"on every loop: {'PASS' if section.passed else 'FAIL'}")
    return lines


def format_report(report: MarginReport) -> str:
    """The margin review as a plain-text table.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    str
        The operating point, then per controller (continuous, sampled) one
        row per loop (gain margins up and down, phase margin, crossover,
        delay margin, phase crossover, loop-at-a-time disk margin, verdict),
        the multiloop disk margin, stability, the slowest and least damped
        poles and the verdict; ends with a newline.
    """
    from quadland.kinds import kind_of

    lines, title = kind_of(report.scenario).describe_point(report.scenario, report.point)
    lines += _table(report.continuous, title, report.requirement)
    if report.sampled is not None:
        sd = report.sampled
        delay = sd.computation_delay_periods
        lines += [""] + _table(sd, f"sampled-data controller, zero-order hold at "
                                   f"{sd.rate_hz:g} Hz, computation delay {delay} "
                                   f"period{'' if delay == 1 else 's'} "
                                   f"({1e3 * sd.computation_delay_s:.3g} ms)",
                               report.requirement)
    return "\n".join(lines) + "\n"

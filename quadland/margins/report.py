"""The margin review's typed results: requirement, per-loop margins, poles, report."""

from __future__ import annotations

import dataclasses
import html
import math
from typing import TYPE_CHECKING

import numpy as np

from quadland.exceptions import MarginsError
from quadland.output import json_ready

if TYPE_CHECKING:
    from quadland.analysis import DiskMargin, Margins
    from quadland.linear import LinearModels, OperatingPoint
    from quadland.margins.sensitivity import SensitivityReport, SensorMargin
    from quadland.scenario import Scenario

__all__ = ["Requirement", "LoopMargins", "MultiloopDiskMargin", "Pole", "PoleSummary",
           "LoopReport", "MarginReport", "decibels"]


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
        The requirement met: stable, every loop (with the others closed), and
        the multiloop disk margin.
    rate_hz : float or None
        Hz, the controller's rate of a sampled loop; None for continuous time.
    computation_delay_periods : int or None
        Control periods from sampling to commanding modelled in a sampled
        loop (a ``z^-1`` on the command each); None for continuous time.
    sensitivity : SensitivityReport or None
        Ms and Mt at the plant input, per loop and multiloop.
    sensors : tuple of SensorMargin
        The latency each of the kind's sensors tolerates (none: the kind
        names no sensors).
    """

    stable: bool
    loops: tuple[LoopMargins, ...]
    multiloop_disk: MultiloopDiskMargin
    poles: PoleSummary
    passed: bool
    rate_hz: float | None = None
    computation_delay_periods: int | None = None
    sensitivity: SensitivityReport | None = None
    sensors: tuple[SensorMargin, ...] = ()

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
        """Names of the loops that did not pass, then ``"multiloop disk"`` if it did not."""
        return tuple(m.name for m in self.loops if not m.passed) + (
            () if self.multiloop_disk.passed else ("multiloop disk",))

    @property
    def worst_gain_margin(self) -> tuple[float, str]:
        """dB and ``"<loop> up"`` or ``"<loop> down"``: the smallest gain margin of any
        loop either way (the lower one as a magnitude, ``-gain_margin_down_db``)."""
        return min(((g, f"{m.name} {way}") for m in self.loops for g, way in
                    ((m.gain_margin_up_db, "up"), (-m.gain_margin_down_db, "down"))),
                   key=lambda c: c[0])

    @property
    def worst_phase_margin(self) -> tuple[float, str]:
        """deg and the loop: the smallest phase margin of any loop."""
        m = min(self.loops, key=lambda m: m.phase_margin_deg)
        return m.phase_margin_deg, m.name

    def title(self) -> str:
        """``continuous``, or ``sampled 250 Hz, delay 1 period``."""
        if self.rate_hz is None:
            return "continuous"
        k = self.computation_delay_periods
        return f"sampled {self.rate_hz:g} Hz, delay {k} period{'' if k == 1 else 's'}"

    def digest(self) -> dict[str, str]:
        """The section in a few words: stability, worst margins, multiloop disk, verdict
        (:meth:`MarginReport.__repr__`'s line)."""
        gm, gm_at = self.worst_gain_margin
        pm, pm_at = self.worst_phase_margin
        disk = self.multiloop_disk.disk
        failed = ", ".join(self.failed)
        return dict(stable="stable" if self.stable else "UNSTABLE",
                    gain=f"{_number(gm)} dB ({gm_at})", phase=f"{_number(pm)} deg ({pm_at})",
                    disk=f"+-{_number(decibels(disk.gain_margin[1]))} dB / "
                         f"{_number(disk.phase_margin)} deg",
                    verdict="pass" if self.passed else
                    f"FAIL ({failed})" if failed else "FAIL")

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
        if self.sensitivity is not None:
            out["sensitivity"] = self.sensitivity.to_dict()
        if self.sensors:
            out["sensors"] = {s.sensor: s.to_dict() for s in self.sensors}
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
    filtered : LoopReport or None
        The sampled loop with the navigation filter in it (a landing scenario
        flying its sensors, ``sensors.enabled``): the flown loop, whose verdict is
        the review's (:attr:`passed`).
    filtered_models : LinearModels or None
        Its models (:func:`quadland.kinds.landing.filter_loop.hover_filter_models`).
    """

    scenario: Scenario
    point: OperatingPoint
    requirement: Requirement
    continuous: LoopReport
    sampled: LoopReport | None
    models: LinearModels
    sampled_models: LinearModels | None
    poles: np.ndarray
    filtered: LoopReport | None = None
    filtered_models: LinearModels | None = None

    @property
    def passed(self) -> bool:
        """The flown loop passed: the loop with the filter when there is one (the
        perfect-sensing sections are then for reference), else every loop of every
        reported controller."""
        if self.filtered is not None:
            return self.filtered.passed
        return self.continuous.passed and (self.sampled is None or self.sampled.passed)

    def _sections(self) -> list[tuple[str, LoopReport]]:
        titled = [(self.continuous.title(), self.continuous)]
        if self.sampled is not None:
            titled.append((self.sampled.title(), self.sampled))
        if self.filtered is not None:
            titled.append((f"{self.filtered.title()}, filter in the loop", self.filtered))
        return titled

    def _heading(self) -> str:
        at = self.point.kind if self.point.time is None else \
            f"{self.point.kind} at t = {self.point.time:g} s"
        req = self.requirement
        return (f"MarginReport of {self.scenario.name!r} ({at}): "
                f"{'PASS' if self.passed else 'FAIL'} against {req.gain_margin_db:g} dB / "
                f"{req.phase_margin_deg:g} deg")

    _HINT = ("print(quadland.margins.format_report(report)) for every margin, "
             "report.to_dict() for margins.json")

    def __repr__(self) -> str:
        """A few lines: the scenario, the verdict, each controller's worst margins.

        One line per controller (continuous, then sampled): stability, the
        smallest gain margin of any loop either way and the smallest phase
        margin with their loops, the multiloop disk margin and the verdict
        with what failed; then where the rest is.
        """
        lines = [f"<{self._heading()}"]
        for title, section in self._sections():
            d = section.digest()
            lines.append(f"  {title}: {d['stable']}, GM {d['gain']}, "
                         f"PM {d['phase']}, multiloop disk {d['disk']}: {d['verdict']}")
        lines.append(f"  {self._HINT}>")
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        """The same as a table, for a notebook."""
        head = "".join(f"<th>{h}</th>" for h in ("controller", "closed loop", "worst GM",
                                                 "worst PM", "multiloop disk", "verdict"))
        rows = []
        for title, section in self._sections():
            d = section.digest()
            cells = (title, d["stable"], d["gain"], d["phase"], d["disk"],
                     d["verdict"])
            rows.append("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in cells) + "</tr>")
        return (f"<p><b>{html.escape(self._heading())}</b></p><table><tr>{head}</tr>"
                f"{''.join(rows)}</table><p><code>{html.escape(self._HINT)}</code></p>")

    @property
    def judged(self) -> tuple[tuple[str, LoopReport], ...]:
        """The sections :attr:`passed` judges, with their labels."""
        if self.filtered is not None:
            return (("sampled, filter in the loop", self.filtered),)
        return tuple((label, s) for label, s in (("continuous", self.continuous),
                                                 ("sampled", self.sampled)) if s is not None)

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
        if self.filtered is not None:
            data["filtered"] = self.filtered.to_dict()
        data["verdict_from"] = [label for label, _ in self.judged]
        return json_ready(data)


def _number(x: float) -> str:
    """``x`` to one decimal, ``inf`` or ``-inf``."""
    return ("inf" if x > 0 else "-inf") if math.isinf(x) else f"{x:.1f}"


def decibels(ratio: float) -> float:
    """``20 log10(ratio)``, ``-inf`` for a ratio of zero."""
    return 20.0 * math.log10(ratio) if ratio > 0 else -math.inf

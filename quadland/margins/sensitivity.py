"""The review's sensitivity peaks and sensor-side delay margins, as typed results.

Two additions to each section (continuous, sampled) of a margin review:

* :class:`SensitivityReport`: Ms and Mt at the plant input, each loop with
  the others closed (``|S_ii|``, ``|1 - S_ii|``) and multiloop
  (``sigma_max`` of S and T), with their frequencies
  (:func:`quadland.analysis.sensitivity.sensitivity_peaks`);
* :class:`SensorMargin`: per sensor of the loop kind
  (:meth:`quadland.kinds.base.LoopKind.sensor_channels`), the latency its
  measurements tolerate, the loop broken at the sensor's outputs with every
  other measurement on time
  (:func:`quadland.analysis.sensitivity.group_delay_margin`), and the latency
  that leaves the requirement's phase margin there.

:func:`section_extras` computes both for one section's models;
:func:`extras_lines` prints them under the section's table.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from quadland.analysis.sensitivity import SensitivityPeaks
    from quadland.linear import LinearModels
    from quadland.margins.report import Requirement
    from quadland.scenario import Scenario

__all__ = ["SensitivityReport", "SensorMargin", "section_extras", "extras_lines"]


def _peaks_dict(p: SensitivityPeaks) -> dict:
    return dict(ms=p.ms.value, ms_db=p.ms.db, ms_frequency=p.ms.frequency,
                mt=p.mt.value, mt_db=p.mt.db, mt_frequency=p.mt.frequency)


@dataclasses.dataclass(frozen=True)
class SensitivityReport:
    """Sensitivity peaks at the plant input.

    Attributes
    ----------
    loops : tuple of (str, SensitivityPeaks)
        Per loop, broken at its input with the others closed: ``Ms = max_w
        |S_ii|``, ``Mt = max_w |1 - S_ii|``.
    multiloop : SensitivityPeaks
        ``max_w sigma_max(S)`` and ``max_w sigma_max(T)``, ``S = (I + L)^-1``.
    """

    loops: tuple[tuple[str, SensitivityPeaks], ...]
    multiloop: SensitivityPeaks

    def loop(self, name: str) -> SensitivityPeaks:
        """The peaks of the loop called ``name``."""
        for n, p in self.loops:
            if n == name:
                return p
        raise KeyError(name)

    def to_dict(self) -> dict:
        """The ``sensitivity`` entry of ``margins.json`` (infinities kept)."""
        return dict(loops={n: _peaks_dict(p) for n, p in self.loops},
                    multiloop=_peaks_dict(self.multiloop))


@dataclasses.dataclass(frozen=True)
class SensorMargin:
    """The latency one sensor's measurements tolerate.

    Attributes
    ----------
    sensor : str
    outputs : tuple of str
        The measured outputs it feeds (none: not in any loop at the point).
    delay_margin_s : float
        s, the smallest latency on all its outputs at once that makes the
        closed loop unstable, the others on time; ``inf`` without a crossing.
    frequency : float or None
        rad/s, where.
    phase_margin_deg : float
        deg, the phase margin of that crossing (an eigenvalue of the loop seen
        at the sensor's outputs, others closed, on the unit circle).
    latency_to_requirement_s : float
        s, the latency that leaves the requirement's phase margin at the
        tightest crossing; negative where a crossing has less already.
    flown_latency_s : float
        s, the scenario's ``sensors.<name>.latency``, for scale: the flown
        loop's filter fuses each packet at its sample time and predicts to the
        present, which this perfect-sensing linearization does not model.
    """

    sensor: str
    outputs: tuple[str, ...]
    delay_margin_s: float
    frequency: float | None
    phase_margin_deg: float
    latency_to_requirement_s: float
    flown_latency_s: float

    def to_dict(self) -> dict:
        """The sensor's entry of ``margins.json``'s ``sensors`` (infinities kept)."""
        out = dataclasses.asdict(self)
        del out["sensor"]
        return out


def section_extras(models: LinearModels, scenario: Scenario, requirement: Requirement
                   ) -> tuple[SensitivityReport, tuple[SensorMargin, ...]]:
    """The sensitivity peaks and the sensor margins of one section's models."""
    from quadland.analysis.sensitivity import group_delay_margin, sensitivity_peaks
    from quadland.kinds import kind_of

    loop_input, loop_output = models.realizations["loop_input"], models.realizations["loop_output"]
    per_loop, multi = sensitivity_peaks(loop_input)
    sens = SensitivityReport(tuple(zip(models.loop_names, per_loop, strict=True)), multi)
    outputs = list(loop_output.input_labels)
    sensors = []
    for name, (feeds, latency) in kind_of(scenario).sensor_channels(scenario).items():
        if not feeds:
            sensors.append(SensorMargin(name, (), math.inf, None, math.inf, math.inf, latency))
            continue
        dm = group_delay_margin(loop_output, [outputs.index(f) for f in feeds])
        sensors.append(SensorMargin(name, tuple(feeds), dm.delay_margin, dm.frequency,
                                    dm.phase_margin,
                                    dm.delay_to(requirement.phase_margin_deg), latency))
    return sens, tuple(sensors)


def _num(x, spec) -> str:
    if x is None:
        return "-"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return format(x, spec)


def extras_lines(sens: SensitivityReport | None, sensors: tuple[SensorMargin, ...],
                 requirement: Requirement) -> list[str]:
    """The lines printed under a section's table (none when there is nothing)."""
    lines = []
    if sens is not None:
        lines.append(f"  sensitivity peaks at the plant input  {'Ms':>6}{'dB':>6}"
                     f"{'w rad/s':>9}{'Mt':>8}{'dB':>6}{'w rad/s':>9}")
        for name, p in (*sens.loops, ("multiloop (sigma_max)", sens.multiloop)):
            lines.append(f"    {name:<35}{_num(p.ms.value, '.3f'):>6}{_num(p.ms.db, '.1f'):>6}"
                         f"{_num(p.ms.frequency, '.3g'):>9}{_num(p.mt.value, '.3f'):>8}"
                         f"{_num(p.mt.db, '.1f'):>6}{_num(p.mt.frequency, '.3g'):>9}")
    if sensors:
        req = f"to {requirement.phase_margin_deg:g} deg"
        lines.append("  latency each sensor tolerates, the loop broken at its outputs (others "
                     "on time):")
        lines.append(f"    {'sensor':<12}{'DM s':>8}{'w rad/s':>9}{'PM deg':>8}{req + ' s':>14}"
                     f"{'flown s':>9}  outputs")
        for s in sensors:
            lines.append(f"    {s.sensor:<12}{_num(s.delay_margin_s, '.3g'):>8}"
                         f"{_num(s.frequency, '.3g'):>9}{_num(s.phase_margin_deg, '.1f'):>8}"
                         f"{_num(s.latency_to_requirement_s, '.3g'):>14}"
                         f"{_num(s.flown_latency_s, '.3g'):>9}  "
                         f"{', '.join(s.outputs) or 'none (not in a loop at this point)'}")
    return lines

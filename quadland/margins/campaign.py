"""Margins over a campaign: the review of every draw of a scenario's ``[campaign]`` table.

:func:`campaign_margins` takes run ``i``'s dispersed values exactly as ``quadland
campaign`` flies them (:func:`quadland.campaign.sampling.iter_draws`, the same
campaign seed, index and run count, so the same bits), applies them to the
scenario as :func:`quadland.campaign.fly.fly` does, and runs the margin review
(:func:`quadland.margins.margin_report`) of each. The result holds each
draw's figures (:data:`FIGURES`), their distribution (median and worst) and the
worst draws with the command that flies each again (the replay command
``quadland campaign`` prints) and the one that reviews it alone.

Draws the scenario refuses are ``invalid``; draws without an operating point
(no equilibrium, a singular attitude) are ``failed``; both are counted apart.
"""

from __future__ import annotations

import dataclasses
import math
import shlex
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from quadland.exceptions import (
    MarginsError,
    OperatingPointError,
    ScenarioError,
    SingularAttitudeError,
)
from quadland.margins.report import Requirement, decibels

if TYPE_CHECKING:
    from quadland.campaign.spec import CampaignSpec
    from quadland.margins.report import MarginReport
    from quadland.scenario import Scenario

__all__ = ["FIGURES", "WORST_DRAWS", "DrawMargins", "CampaignMargins", "campaign_margins",
           "check_campaign_request"]

#: Draws listed as the worst, by multiloop disk margin.
WORST_DRAWS = 5


@dataclasses.dataclass(frozen=True)
class _Figure:
    """One number of a draw's review: its unit, and whether smaller is worse."""

    unit: str
    smaller_is_worse: bool


def _loop_figures(name: str) -> dict[str, _Figure]:
    return {f"{name}.phase_margin_deg": _Figure("deg", True),
            f"{name}.gain_margin_up_db": _Figure("dB", True),
            f"{name}.gain_margin_down_db": _Figure("dB", False),
            f"{name}.delay_margin_s": _Figure("s", True),
            f"{name}.ms": _Figure("", False), f"{name}.mt": _Figure("", False)}


#: The figures of a draw that do not depend on the loop kind (per-loop and
#: per-sensor figures are added from the first review: ``<loop>.<figure>``,
#: ``sensor.<name>.delay_margin_s``).
FIGURES = {"multiloop_disk.alpha": _Figure("", True),
           "multiloop_disk.gain_margin_db": _Figure("dB", True),
           "multiloop_disk.phase_margin_deg": _Figure("deg", True),
           "multiloop.ms": _Figure("", False), "multiloop.mt": _Figure("", False)}


@dataclasses.dataclass(frozen=True)
class DrawMargins:
    """The margin review of one draw.

    Attributes
    ----------
    index, seed : int
        The run's index and seed, as ``quadland campaign`` numbers them.
    status : str
        ``"ok"`` (reviewed), ``"invalid"`` (the scenario refuses the draw) or
        ``"failed"`` (no operating point).
    passed : bool
        Reviewed, and the requirement met (:attr:`MarginReport.passed`).
    figures : mapping of str to float
        The review's numbers by name (empty unless ``ok``).
    columns : mapping of str to str
        The dispersed values, as runs.csv holds them.
    overrides : tuple of str
        The dispersed values as ``--set`` texts.
    message : str
        Why not ``ok``, or the sections that missed the requirement.
    replay : str
        The ``quadland simulate`` command that flies the draw.
    review : str
        The ``quadland margins`` command that reviews it alone.
    """

    index: int
    seed: int
    status: str
    passed: bool
    figures: Mapping[str, float]
    columns: Mapping[str, str]
    overrides: tuple[str, ...]
    message: str
    replay: str
    review: str


@dataclasses.dataclass(frozen=True)
class CampaignMargins:
    """The margin review over a campaign's draws.

    Attributes
    ----------
    scenario : str
    section : str
        ``"sampled"`` (the loop at ``controller.rate_hz`` with its delay) or
        ``"continuous"`` (a loop without a rate): whose figures are kept.
    requirement : Requirement
    campaign : mapping
        The table's identity (seed, sampling, dispersions), and ``runs``.
    draws : tuple of DrawMargins
        In index order.
    units : mapping of str to str
        Each figure's unit.
    distribution : mapping of str to mapping
        Per figure over the reviewed draws: ``median``, ``worst`` and
        ``worst_index`` (the draw), ``n``.
    worst : tuple of DrawMargins
        Draws without an operating point first, then the smallest multiloop
        disk margins (:data:`WORST_DRAWS` in all).
    runtime_s : float
    """

    scenario: str
    section: str
    requirement: Requirement
    campaign: Mapping
    draws: tuple[DrawMargins, ...]
    units: Mapping[str, str]
    distribution: Mapping[str, Mapping]
    worst: tuple[DrawMargins, ...]
    runtime_s: float

    def count(self, status: str) -> int:
        """Draws of that status."""
        return sum(d.status == status for d in self.draws)

    @property
    def passed(self) -> int:
        """Draws that meet the requirement."""
        return sum(d.passed for d in self.draws)

    @property
    def all_passed(self) -> bool:
        """Every draw reviewed and meeting the requirement."""
        return self.passed == len(self.draws)

    def to_dict(self) -> dict:
        """``margins_campaign.json`` (infinities as null)."""
        from quadland.output import json_ready

        return json_ready(dict(
            scenario=self.scenario, section=self.section,
            requirement=dataclasses.asdict(self.requirement), campaign=dict(self.campaign),
            draws=len(self.draws), reviewed=self.count("ok"), invalid=self.count("invalid"),
            failed=self.count("failed"), passed=self.passed, units=dict(self.units),
            distribution={k: dict(v) for k, v in self.distribution.items()},
            worst_draws=[_draw_dict(d) for d in self.worst],
            every_draw=[_draw_dict(d) for d in self.draws], runtime_s=self.runtime_s))


def _draw_dict(d: DrawMargins) -> dict:
    out = dataclasses.asdict(d)
    out["figures"], out["columns"] = dict(d.figures), dict(d.columns)
    return out


def _section_figures(report: MarginReport) -> tuple[str, dict[str, float], dict[str, _Figure]]:
    """Which section is kept, its numbers and their kinds."""
    name = "sampled" if report.sampled is not None else "continuous"
    sec = report.sampled if report.sampled is not None else report.continuous
    kinds, values = dict(FIGURES), {}
    disk = sec.multiloop_disk.disk
    values.update({"multiloop_disk.alpha": disk.disk_margin,
                   "multiloop_disk.gain_margin_db": decibels(disk.gain_margin[1]),
                   "multiloop_disk.phase_margin_deg": disk.phase_margin,
                   "multiloop.ms": sec.sensitivity.multiloop.ms.value,
                   "multiloop.mt": sec.sensitivity.multiloop.mt.value})
    for lm in sec.loops:
        kinds.update(_loop_figures(lm.name))
        peaks = sec.sensitivity.loop(lm.name)
        values.update({f"{lm.name}.phase_margin_deg": lm.phase_margin_deg,
                       f"{lm.name}.gain_margin_up_db": lm.gain_margin_up_db,
                       f"{lm.name}.gain_margin_down_db": lm.gain_margin_down_db,
                       f"{lm.name}.delay_margin_s": lm.delay_margin_s,
                       f"{lm.name}.ms": peaks.ms.value, f"{lm.name}.mt": peaks.mt.value})
    for s in sec.sensors:
        if s.outputs:
            kinds[f"sensor.{s.sensor}.delay_margin_s"] = _Figure("s", True)
            values[f"sensor.{s.sensor}.delay_margin_s"] = s.delay_margin_s
    return name, {k: float(values[k]) for k in kinds}, kinds


def _commands(scenario_arg: str, overrides: Sequence[str], draw: Sequence[str]
              ) -> tuple[str, str]:
    from quadland.campaign.summary import replay_command

    words = ["quadland", "margins", "--scenario", scenario_arg]
    for text in (*overrides, *draw):
        words += ["--set", text]
    return replay_command(scenario_arg, overrides, draw), shlex.join(words)


def check_campaign_request(base: Scenario, runs: int | None, delay_periods: int | None
                           ) -> tuple[CampaignSpec, int]:
    """Refuse, before any work, a request :func:`campaign_margins` cannot answer.

    Returns
    -------
    tuple
        ``(spec, runs)``: the validated campaign table and the run count.

    Raises
    ------
    CampaignError
        The scenario has no ``[campaign]`` table.
    ScenarioError
        The table is invalid (one line naming the entry).
    MarginsError
        ``runs`` out of range; ``delay_periods`` invalid.
    """
    from quadland.campaign.spec import MAX_RUNS, campaign_spec_of
    from quadland.margins.review import check_request

    spec = campaign_spec_of(base)
    n = spec.runs if runs is None else runs
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or not 1 <= n <= MAX_RUNS:
        raise MarginsError(f"runs: must be in [1, {MAX_RUNS}], got {n}")
    check_request(base, None, delay_periods)
    return spec, int(n)


def _review_draw(base, draw, requirement, delay_periods, commands):
    """One draw's :class:`DrawMargins`, its figures' kinds and its section's name."""
    from quadland.margins.review import margin_report

    replay, review = commands
    common = dict(index=draw.index, seed=draw.seed, columns=dict(draw.columns),
                  overrides=tuple(draw.overrides()), replay=replay, review=review)
    try:
        scenario = base.replace(**draw.values)
    except ScenarioError as exc:
        return DrawMargins(status="invalid", passed=False, figures={},
                           message=" ".join(str(exc).split()), **common), {}, None
    try:
        report = margin_report(scenario, None, requirement, delay_periods, filtered=False)
    except ScenarioError as exc:
        return DrawMargins(status="invalid", passed=False, figures={},
                           message=" ".join(str(exc).split()), **common), {}, None
    except (OperatingPointError, SingularAttitudeError, MarginsError) as exc:
        return DrawMargins(status="failed", passed=False, figures={},
                           message=" ".join(str(exc).split()), **common), {}, None
    section, values, kinds = _section_figures(report)
    missed = [f"{label}: {', '.join(sec.failed) or 'unstable'}"
              for label, sec in (("continuous", report.continuous), ("sampled", report.sampled))
              if sec is not None and not sec.passed]
    return DrawMargins(status="ok", passed=report.passed, figures=values,
                       message="; ".join(missed), **common), kinds, section


def campaign_margins(base: Scenario, runs: int | None = None,
                     requirement: Requirement = Requirement(),
                     delay_periods: int | None = None, scenario_arg: str | None = None,
                     overrides: Sequence[str] = (),
                     progress: Callable[[int, int], None] | None = None) -> CampaignMargins:
    """The margin review of every draw of a scenario's campaign.

    Parameters
    ----------
    base : Scenario
        A scenario with a ``[campaign]`` table (its seed, sampling and
        dispersions as ``quadland campaign`` reads them).
    runs : int, optional
        Draws ``0 .. runs - 1`` (default ``campaign.runs``): the runs of
        ``quadland campaign --runs runs``.
    requirement : Requirement, optional
    delay_periods : int, optional
        As for :func:`quadland.margins.margin_report`.
    scenario_arg : str, optional
        How the commands name the scenario (default: its file's stem).
    overrides : sequence of str
        The ``--set`` texts the commands repeat before each draw's values.
    progress : callable, optional
        Called as ``progress(done, runs)`` after each draw.

    Returns
    -------
    CampaignMargins

    Raises
    ------
    CampaignError, ScenarioError, MarginsError
        Before any draw: see :func:`check_campaign_request`.
    """
    from quadland.campaign.sampling import iter_draws

    start = time.perf_counter()
    spec, n = check_campaign_request(base, runs, delay_periods)
    arg = scenario_arg or Path(base.source).stem
    given = [o for o in overrides if not o.startswith("campaign.")]
    draws, kinds, section = [], {}, None
    for k, draw in enumerate(iter_draws(spec, range(n), n)):
        result, draw_kinds, draw_section = _review_draw(
            base, draw, requirement, delay_periods, _commands(arg, given, draw.overrides()))
        draws.append(result)
        kinds.update(draw_kinds)
        section = section or draw_section
        if progress is not None:
            progress(k + 1, n)
    return CampaignMargins(base.name, section or "none", requirement,
                           {**spec.identity(), "runs": n}, tuple(draws),
                           {k: v.unit for k, v in kinds.items()},
                           _distribution(draws, kinds), _worst(draws),
                           time.perf_counter() - start)


def _distribution(draws: Sequence[DrawMargins], kinds: Mapping[str, _Figure]) -> dict:
    ok = [d for d in draws if d.status == "ok"]
    out = {}
    for name, kind in kinds.items():
        values = np.array([d.figures.get(name, math.nan) for d in ok], dtype=float)
        have = ~np.isnan(values)
        if not have.any():
            continue
        v, idx = values[have], [d.index for d, h in zip(ok, have, strict=True) if h]
        j = int(np.argmin(v) if kind.smaller_is_worse else np.argmax(v))
        out[name] = dict(median=float(np.median(v)), worst=float(v[j]), worst_index=idx[j],
                         n=int(v.size))
    return out


def _worst(draws: Sequence[DrawMargins]) -> tuple[DrawMargins, ...]:
    failed = [d for d in draws if d.status == "failed"]
    ok = sorted((d for d in draws if d.status == "ok"),
                key=lambda d: (d.figures["multiloop_disk.alpha"], d.index))
    return tuple((failed + ok)[:WORST_DRAWS])

"""One run of a campaign: the dispersed scenario, flown, judged against its limits."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from quadland.campaign.dispersed import dispersed
from quadland.campaign.sampling import RunDraw
from quadland.campaign.spec import campaign_spec_of
from quadland.engine.kept import keeping
from quadland.exceptions import ScenarioError, SimulationError
from quadland.kinds import kind_of
from quadland.scenario import Scenario

__all__ = ["RunOutcome", "fly", "STATUSES", "warm_up"]

#: A run's status: flown to the end, stopped by a numerical failure, or not
#: flyable (a draw outside a key's range or the resource limits).
STATUSES = ("ok", "failed", "invalid")


@dataclasses.dataclass(frozen=True)
class RunOutcome:
    """What one run gave.

    Attributes
    ----------
    index, seed : int
    status : str
        One of :data:`STATUSES`.
    success : bool
        Flown to the end with every limited metric defined and within its limit.
    metrics : mapping of str to float or None
        Empty unless ``status == "ok"``.
    message : str
        Why it failed or missed its limits ("" for a success): one line.
    columns : mapping of str to str
        The draw's runs.csv columns.
    """

    index: int
    seed: int
    status: str
    success: bool
    metrics: Mapping[str, float | None]
    message: str
    columns: Mapping[str, str]


def fly(base: Scenario, draw: RunDraw, limits: Mapping[str, float] | None = None,
        keep: int = 0) -> RunOutcome:
    """Fly run ``draw.index`` of the campaign of ``base``.

    Parameters
    ----------
    base : Scenario
        The campaign's scenario.
    draw : RunDraw
        The run's seed and dispersed values.
    limits : mapping of str to float, optional
        The campaign's ``limits`` (``CampaignSpec.limits``); default: those
        of ``base``'s ``[campaign]`` table, validated here.
    keep : int
        Bytes of draws this process may keep for its next runs
        (:func:`quadland.engine.kept.keeping`: an envelope's, whose replicates fly in
        every cell); 0, a campaign's: none.

    Returns
    -------
    RunOutcome
        A run that leaves the model's domain is an outcome (``"failed"``),
        as is one whose draws the scenario refuses (``"invalid"``); other
        errors propagate.
    """
    def outcome(status, success=False, metrics=None, message=""):
        return RunOutcome(draw.index, draw.seed, status, success, metrics or {},
                          " ".join(message.split()), draw.columns)

    kind = kind_of(base)
    try:
        scenario = dispersed(base, draw.values)
    except ScenarioError as exc:
        return outcome("invalid", message=str(exc))
    try:
        with keeping(keep):
            result = kind.simulate(scenario)
    except ScenarioError as exc:
        return outcome("invalid", message=str(exc))
    except SimulationError as exc:
        return outcome("failed", message=str(exc))
    metrics = kind.run_metrics(result)
    if limits is None:
        limits = campaign_spec_of(base).limits if base.campaign_table is not None else {}
    missed = kind.judge(result, metrics, kind.limits(scenario, limits))
    return outcome("ok", not missed, metrics, "; ".join(missed))


def warm_up(base: Scenario) -> None:
    """Build (or load) the compiled simulator of ``base``'s loop in this process."""
    short = base.replace(**{"simulation.duration": min(base["simulation.duration"], 0.05)})
    try:
        kind_of(base).simulate(short)
    except SimulationError:
        pass

"""``quadland margins --campaign`` as a library call: review every draw, write the folder."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path

from quadland.margins.campaign import CampaignMargins, campaign_margins, check_campaign_request
from quadland.margins.campaign_text import draws_csv
from quadland.margins.report import Requirement

__all__ = ["CAMPAIGN_FILES", "run_campaign_margins"]

#: The files a campaign's margin review writes.
CAMPAIGN_FILES = ("margins_campaign.json", "margins_draws.csv", "scenario.toml")


def run_campaign_margins(scenario: str | Path = "highway", overrides: Sequence[str] = (),
                         runs: int | None = None, out: str | Path | None = None,
                         requirement: Requirement = Requirement(),
                         delay_periods: int | None = None,
                         progress: Callable[[int, int], None] | None = None
                         ) -> tuple[CampaignMargins, Path]:
    """Review every draw of a scenario's campaign and write :data:`CAMPAIGN_FILES`.

    Parameters
    ----------
    scenario : str or Path
        A shipped scenario's name or a TOML file, with a ``[campaign]`` table.
    overrides : sequence of str
        ``--set`` texts (``campaign.seed=3`` changes the draws, as for
        ``quadland campaign``).
    runs : int, optional
        Draws ``0 .. runs - 1`` (default ``campaign.runs``).
    out : path-like, optional
        The folder (default a new ``<scenario>-margins-campaign-<stamp>``).
    requirement, delay_periods
        As for :func:`quadland.margins.margin_report`.
    progress : callable, optional
        ``progress(done, runs)`` after each draw.

    Returns
    -------
    (CampaignMargins, Path)
        The result and the folder written.

    Raises
    ------
    QuadlandError
        Before anything is written: a bad scenario, table, run count or
        delay, or an output path that is not a folder.
    """
    from threadpoolctl import threadpool_limits

    from quadland.output import output_folder, strict_json
    from quadland.run import versions
    from quadland.scenario import load_scenario

    start = time.perf_counter()
    base = load_scenario(scenario, list(overrides))
    check_campaign_request(base, runs, delay_periods)      # nothing claimed before this
    with output_folder(out, base.name, "margins-campaign") as folder, threadpool_limits(1):
        result = campaign_margins(base, runs, requirement, delay_periods,
                                  scenario_arg=str(scenario), overrides=list(overrides),
                                  progress=progress)
        data = dict(result.to_dict(), runtime_s=time.perf_counter() - start,
                    versions=versions())
        folder.write({"margins_campaign.json": strict_json(data),
                      "margins_draws.csv": draws_csv(result),
                      "scenario.toml": base.to_toml().encode("utf-8")})
    return result, folder.path

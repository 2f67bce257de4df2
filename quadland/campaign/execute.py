"""Running a campaign: local processes or a Dask cluster, recorded run by run, resumable.

:func:`run_campaign` loads the scenario and its ``[campaign]`` table,
claims the folder (:class:`~quadland.campaign.journal.CampaignFolder`),
refuses an earlier campaign of another scenario, dispersions or code there,
builds the compiled simulator once, then flies only the runs the journal
does not hold: in this process (one worker), in a pool of local processes
(``forkserver``: CasADi objects are built per process, never shared between
threads), or on a ``dask.distributed`` cluster. Each finished run is
appended to ``runs.csv`` and made durable before it counts. When all are
recorded, ``runs.csv`` is rewritten sorted by index and the summary and
figures are written (:func:`~quadland.campaign.summary.summarize_campaign`).

The jobs are modules of their own: :mod:`~quadland.campaign.local` (this
process and local processes), :mod:`~quadland.campaign.cluster` (Dask),
:mod:`~quadland.campaign.resume` (the folder's identity and what may be
resumed), :mod:`~quadland.campaign.journal` (the folder's files) and
:mod:`~quadland.campaign.summary`.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import shlex
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from quadland import interrupt
from quadland.campaign.cluster import (
    check_address,
    connect,
    dask_runs,
    disconnect,
    quiet_cluster_logs,
)
from quadland.campaign.fly import RunOutcome, warm_up
from quadland.campaign.journal import CampaignFolder, new_folder
from quadland.campaign.local import (
    MAX_WORKERS,
    chunk_size,
    local_workers,
    pool_runs,
    serial_runs,
    start_pool_server,
)
from quadland.campaign.resume import campaign_manifest, check_folder
from quadland.campaign.sampling import format_value, iter_draws
from quadland.campaign.spec import MAX_RUNS, campaign_spec_of
from quadland.campaign.summary import campaign_figures, summarize_campaign
from quadland.exceptions import CampaignError
from quadland.kinds import kind_of
from quadland.scenario import SCENARIO_DIR, Scenario, load_scenario

__all__ = ["CampaignResult", "CampaignInterrupted", "run_campaign", "campaign_header"]


class CampaignInterrupted(KeyboardInterrupt):
    """Ctrl-C stopped a campaign; the runs recorded so far stay in its folder.

    Attributes
    ----------
    folder : Path
    recorded, runs : int
    """

    def __init__(self, folder: Path, recorded: int, runs: int):
        super().__init__(f"{recorded} of {runs} runs recorded in {folder}; run the same "
                         f"command with --out {shlex.quote(str(folder))} to fly the rest")
        self.folder, self.recorded, self.runs = folder, recorded, runs


@dataclasses.dataclass(frozen=True)
class CampaignResult:
    """What :func:`run_campaign` did.

    Attributes
    ----------
    folder : Path
    runs : int
        Runs of the campaign.
    recorded : int
        Runs in runs.csv now.
    flown : int
        Runs flown by this call (the others were recorded before).
    elapsed : float
        Wall time of this call's runs, s.
    summary : dict or None
        summary.json, once every run is recorded.
    invalid : int
        Runs recorded by this call as ``invalid``: their draws made no valid
        scenario, so they were not flown (not counted in ``flown``).
    """

    folder: Path
    runs: int
    recorded: int
    flown: int
    elapsed: float
    summary: dict | None
    invalid: int = 0

    @property
    def complete(self) -> bool:
        """Every run is recorded."""
        return self.recorded == self.runs


def campaign_header(spec, model: str) -> list[str]:
    """The columns of runs.csv."""
    return ["index", "seed", "status", "success", *spec.columns(),
            *(m.name for m in kind_of(model).metrics), "message"]


def _recorded(durable, rows: dict, bar) -> None:
    """Count the runs the journal made durable: in ``rows`` (by index) and the bar."""
    rows.update((int(r[0]), r) for r in durable)
    if bar is not None and durable:
        bar.update(len(durable))


def _row(outcome: RunOutcome, header: Sequence[str]) -> list[str]:
    texts = {"index": str(outcome.index), "seed": str(outcome.seed), "status": outcome.status,
             "success": "true" if outcome.success else "false", "message": outcome.message,
             **outcome.columns}
    for name, value in outcome.metrics.items():
        texts[name] = "" if value is None else format_value(value)
    return [texts.get(name, "") for name in header]


def _scenario_argument(scenario: Scenario, given) -> str:
    """How the replay commands name the scenario: as it was given, or by its file."""
    if isinstance(given, str | os.PathLike):
        return str(given)
    source = Path(scenario.source)
    return source.stem if source.parent.resolve() == SCENARIO_DIR.resolve() else str(source)


def run_campaign(scenario: str | Path | Scenario = "paper", overrides=None,
                 runs: int | None = None, out: str | Path | None = None,
                 workers: int | None = None, scheduler: str | None = None,
                 progress: bool = False, plots: bool = True) -> CampaignResult:
    """Fly a scenario's campaign, or the runs of it that its folder does not hold yet.

    Parameters
    ----------
    scenario : str, Path or Scenario
        A shipped scenario's name, a TOML file or a loaded scenario, with a
        ``[campaign]`` table.
    overrides : list of str or dict, optional
        Scenario overrides (``campaign.seed=3`` too).
    runs : int, optional
        Number of runs (default ``campaign.runs``).
    out : path-like, optional
        The campaign folder (default a new ``<scenario>-campaign-<stamp>``).
        Running again into it flies only the missing runs.
    workers : int, optional
        Local processes (default: every core, as many as the available
        memory holds; 1 flies in this process). Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a ``dask.distributed`` scheduler (``tcp://HOST:PORT``).
    progress : bool
        Show a progress bar with an ETA on standard error.
    plots : bool
        Write the figures once the campaign is complete.

    Returns
    -------
    CampaignResult

    Raises
    ------
    ScenarioError, CampaignError
        Before anything is written or created: a bad scenario or campaign
        table, more workers than the memory holds, a folder that holds
        something else or another campaign (the message says what changed)
        or a damaged one, a scheduler that cannot be reached.
    CampaignStopped
        A worker died or the scheduler was lost; the recorded runs stay.
    KeyboardInterrupt
        The recorded runs stay; running again resumes.
    """

    base = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    spec = campaign_spec_of(base)
    n_runs = spec.runs if runs is None else runs
    if isinstance(n_runs, bool) or not isinstance(n_runs, int) or not 1 <= n_runs <= MAX_RUNS:
        raise CampaignError(f"runs: must be in [1, {MAX_RUNS}], got {n_runs}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or not 1 <= workers <= MAX_WORKERS):
        raise CampaignError(f"workers: must be in [1, {MAX_WORKERS}], got {workers}")
    kind_of(base).check(base)
    if scheduler is not None:
        check_address(scheduler)
        local = 0
    else:
        local = local_workers(base, workers, n_runs)
    # scenario.toml of the folder holds the table as validated (defaults filled in)
    base = dataclasses.replace(base, campaign_table=spec.table)
    header = campaign_header(spec, base.model)
    manifest = campaign_manifest(base, spec, n_runs)
    path = None if out is None else Path(out).absolute()
    done = {}
    if path is not None:                        # refused now, before the cluster and the build
        done = check_folder(CampaignFolder(path), manifest, header)
    given = [o for o in (_override_texts(overrides)) if not o.startswith("campaign.")]
    scenario_arg = _scenario_argument(base, scenario)
    if local > 1 and n_runs - sum(0 <= i < n_runs for i in done) > 1:
        start_pool_server()             # a pool's: its imports beside the simulator's load
    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            stack.enter_context(quiet_cluster_logs())
            connection = connect(scheduler)
            stack.callback(disconnect, connection)
        else:
            connection = None
        return _fly_campaign(base, spec, n_runs, header, manifest, path, connection, local,
                             scheduler, scenario_arg, given, progress, plots)


def _fly_campaign(base, spec, n_runs, header, manifest, path, connection, local, scheduler,
                  scenario_arg, given, progress, plots) -> CampaignResult:
    """:func:`run_campaign` once every check has passed: build, claim, fly, summarize."""
    warm_up(base)                               # the compiled simulator, built or loaded
    folder = (CampaignFolder(path).claim() if path is not None
              else new_folder(base.name, "campaign"))
    with folder:
        rows = check_folder(folder, manifest, header)  # again, now that it is ours
        folder.start(manifest, header, {"scenario.toml": base.to_toml().encode("utf-8")})
        pending = [i for i in range(n_runs) if i not in rows]
        todo = iter_draws(spec, pending, n_runs)
        bar = _progress_bar(progress, n_runs, len(rows))
        start, flown, invalid = time.perf_counter(), 0, 0
        try:
            if connection is not None:
                batches = dask_runs(connection, base, todo, spec.limits)
            elif local == 1 or len(pending) <= 1:
                batches = serial_runs(base, todo, spec.limits)
            else:
                workers = min(local, len(pending))
                batches = pool_runs(base, todo, workers, spec.limits,
                                    chunk_size(len(pending), workers))
            try:
                for batch in batches:
                    _recorded(folder.append([_row(o, header) for o in batch]), rows, bar)
                    invalid += sum(o.status == "invalid" for o in batch)
                    flown += sum(o.status != "invalid" for o in batch)
                    interrupt.check()           # one a library swallowed (the runs are kept)
            finally:
                batches.close()                 # workers and tasks stopped before the folder
                _recorded(folder.sync(), rows, bar)   # every run written: recorded
        except KeyboardInterrupt:
            raise CampaignInterrupted(folder.path, len(rows), n_runs) from None
        except Exception as exc:
            # a Ctrl-C while ctypes converted a run's arguments (NumPy's ndpointer, in
            # Python) arrives as its ArgumentError: the same interrupt, the same message
            if not interrupt.wrapped_by_ctypes(exc):
                raise
            raise CampaignInterrupted(folder.path, len(rows), n_runs) from None
        finally:
            if bar is not None:
                bar.close()
        elapsed = time.perf_counter() - start
        summary = None
        if len(rows) == n_runs:
            ordered = [rows[i] for i in range(n_runs)]
            summary = summarize_campaign(base, header, ordered, scenario_arg, given)
            summary["last_session"] = {
                "runs_flown": flown, "invalid_draws": invalid, "wall_s": elapsed,
                "runs_per_s": flown / elapsed if flown and elapsed > 0 else None,
                "where": scheduler or f"{max(local, 1)} local process(es)"}
            from quadland.output import strict_json
            from quadland.run import provenance

            summary["provenance"] = provenance(base)
            files = {"summary.json": strict_json(summary)}
            if plots:
                files.update(campaign_figures(base, header, ordered, summary))
            folder.finish(header, ordered, files)
        return CampaignResult(folder.path, n_runs, len(rows), flown, elapsed, summary, invalid)


def _override_texts(overrides) -> list[str]:
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        from quadland.scenario import toml_value

        return [f"{k}={toml_value(v)}" for k, v in overrides.items()]
    return [str(o) for o in overrides]


def _progress_bar(show: bool, total: int, done: int):
    if not show:
        return None
    from tqdm import tqdm

    return tqdm(total=total, initial=done, unit="run", file=sys.stderr, dynamic_ncols=True,
                desc="campaign", smoothing=0.1)

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
figures are written (:func:`summarize_campaign`).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import dataclasses
import hashlib
import math
import multiprocessing
import multiprocessing.connection
import os
import shlex
import signal
import sys
import threading
import time
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

from quadland.campaign.fly import RunOutcome, fly, warm_up
from quadland.campaign.journal import MANIFEST, CampaignFolder, damaged_manifest, json_kind
from quadland.campaign.sampling import RunDraw, format_value, iter_draws
from quadland.campaign.spec import MAX_RUNS, CampaignSpec, campaign_spec_of
from quadland.campaign.statistics import (
    clopper_pearson,
    lower_confidence_bound,
    order_statistic,
    separation,
)
from quadland.exceptions import CampaignError, CampaignStopped
from quadland.kinds import kind_of
from quadland.scenario import SCENARIO_DIR, Scenario, load_scenario

__all__ = ["CampaignResult", "CampaignInterrupted", "run_campaign", "summarize_campaign",
           "campaign_header", "code_fingerprint", "replay_command", "check_address",
           "local_workers", "worker_memory", "available_memory", "CAMPAIGN_FIGURES",
           "CONFIDENCE", "QUANTILES", "WORST_RUNS", "MAX_WORKERS", "WORKER_MEMORY",
           "NO_WORKER_GRACE_S", "SCHEDULER_TIMEOUT_S", "quiet_cluster_logs"]

#: Confidence level of the success rate's interval and bound.
CONFIDENCE = 0.95
#: The order statistics summary.json gives of every metric.
QUANTILES = {"p50": 0.5, "p90": 0.9, "p99": 0.99, "max": 1.0}
#: Runs listed in summary.json's ``worst_runs``.
WORST_RUNS = 5
#: The figures of a finished campaign.
CAMPAIGN_FIGURES = ("metrics_cdf.png", "failures.png")
#: Most local worker processes one campaign may ask for.
MAX_WORKERS = 1024
#: Memory of one local worker process with its simulator loaded, before the
#: arrays of its run, bytes. Measured on the shipped landing campaigns: 70 MiB
#: of its own (USS), 120 MiB resident (RSS, with the pages it shares with the
#: forkserver); the paper's, 20 and 55 MiB (docs/campaign.md).
WORKER_MEMORY = 128 * 2**20
#: Longest wait for a Dask scheduler's handshake, s (its client gets twice that to connect).
SCHEDULER_TIMEOUT_S = 5.0
#: How long a Dask cluster may be left without a worker before the campaign stops, s.
NO_WORKER_GRACE_S = 20.0
#: Runs queued ahead on each local worker process or Dask thread.
_AHEAD = 4
#: Format of campaign.json.
_FORMAT = 1


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


def _row(outcome: RunOutcome, header: Sequence[str]) -> list[str]:
    texts = {"index": str(outcome.index), "seed": str(outcome.seed), "status": outcome.status,
             "success": "true" if outcome.success else "false", "message": outcome.message,
             **outcome.columns}
    for name, value in outcome.metrics.items():
        texts[name] = "" if value is None else format_value(value)
    return [texts.get(name, "") for name in header]


def code_fingerprint() -> str:
    """A hash of the source files of ``quadland`` and ``quadland_symbolic`` (Python, templates)."""
    import quadland
    import quadland_symbolic

    digest = hashlib.sha256()
    for package in (quadland, quadland_symbolic):
        root = Path(package.__file__).parent
        for path in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".jinja")):
            digest.update(str(path.relative_to(root.parent)).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _manifest(scenario: Scenario, spec: CampaignSpec, runs: int) -> dict:
    from importlib.metadata import version

    from quadland import __version__
    from quadland.engine.build import compiler_version

    return {"format": _FORMAT, "quadland": __version__, "code": code_fingerprint(),
            "libraries": {name: version(name) for name in ("casadi", "numpy", "scipy")},
            "c_compiler": compiler_version(), "runs": runs,
            "campaign": spec.identity(), "scenario": scenario.to_dict()}


#: The type each entry of campaign.json must have (format 1).
_MANIFEST_TYPES = {"quadland": (str,), "code": (str,), "libraries": (dict,),
                   "c_compiler": (str, type(None)), "runs": (int,), "campaign": (dict,),
                   "scenario": (dict,)}


def _check_manifest(old: dict, path: Path) -> None:
    """Refuse a manifest of this format whose entries are not what quadland writes."""
    for key, kinds in _MANIFEST_TYPES.items():
        if key not in old:
            raise damaged_manifest(path, f"no \"{key}\"")
        value = old[key]
        if isinstance(value, bool) or not isinstance(value, kinds):
            raise damaged_manifest(path, f"\"{key}\" is {json_kind(value)}")
    if old["runs"] < 1:
        raise damaged_manifest(path, f"\"runs\" is {old['runs']}")
    if not all(isinstance(v, str) for v in old["libraries"].values()):
        raise damaged_manifest(path, "\"libraries\" holds something else than versions")
    for section, table in old["scenario"].items():
        if not isinstance(table, dict):
            raise damaged_manifest(path, f"\"scenario.{section}\" is {json_kind(table)}")


def _differences(old: Mapping, new: Mapping, prefix: str = "") -> list[str]:
    out = []
    for key in sorted(set(old) | set(new), key=str):
        a, b = old.get(key, "(absent)"), new.get(key, "(absent)")
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += _differences(a, b, f"{prefix}{key}.")
        elif a != b:
            out.append(f"{prefix}{key}: {_short(a)} there, {_short(b)} here")
    return out


def _short(value) -> str:
    """A value of campaign.json, shortened for a message."""
    if isinstance(value, Mapping):
        text = str(dict(value))
    else:
        try:
            text = format_value(value)
        except (TypeError, ValueError):         # a null in a damaged campaign.json
            text = json_kind(value) if value is None else repr(value)
    text = " ".join(text.split())
    return text if len(text) <= 40 else text[:37] + "..."


def _check_resumable(old: dict, new: dict, path: Path) -> None:
    """Refuse, naming the first difference, a folder of another campaign or a damaged one."""
    manifest = path / MANIFEST
    if "format" not in old:
        raise damaged_manifest(manifest, "no \"format\"")
    if old["format"] != _FORMAT:
        raise CampaignError(f"out: {path} holds another campaign (it was written by another "
                            f"quadland: campaign format {_short(old['format'])}); choose a new "
                            "folder or run the campaign it holds")
    _check_manifest(old, manifest)
    why = None
    if old["quadland"] != new["quadland"]:
        why = f"quadland {' '.join(old['quadland'].split())[:40]} made it, this is " \
            f"{new['quadland']}"
    elif old["code"] != new["code"]:
        why = "quadland's source code changed since (its runs would not be comparable)"
    elif old["libraries"] != new["libraries"] or old["c_compiler"] != new["c_compiler"]:
        diff = _differences({**old["libraries"], "c_compiler": old["c_compiler"]},
                            {**new["libraries"], "c_compiler": new["c_compiler"]})
        why = f"a library changed: {diff[0]}"
    elif old["scenario"] != new["scenario"]:
        diff = _differences(old["scenario"], new["scenario"])
        why = f"the scenario changed: {diff[0]}" + \
            (f" (and {len(diff) - 1} more)" if len(diff) > 1 else "")
    elif old["campaign"] != new["campaign"]:
        diff = _differences(old["campaign"], new["campaign"], "campaign.")
        what = "the dispersions" if diff[0].startswith("campaign.dispersions") else \
            "the campaign"
        why = f"{what} changed: {diff[0]}"
    elif new["runs"] < old["runs"]:
        why = f"it holds a campaign of {old['runs']} runs; --runs can only grow"
    elif new["runs"] != old["runs"] and new["campaign"].get("sampling") == "lhs":
        why = (f"it holds a Latin hypercube of {old['runs']} runs, whose points depend on "
               "the number of runs")
    if why:
        raise CampaignError(f"out: {path} holds another campaign ({why}); choose a new folder "
                            "or run the campaign it holds")


def _scenario_argument(scenario: Scenario, given) -> str:
    """How the replay commands name the scenario: as it was given, or by its file."""
    if isinstance(given, str | os.PathLike):
        return str(given)
    source = Path(scenario.source)
    return source.stem if source.parent.resolve() == SCENARIO_DIR.resolve() else str(source)


def replay_command(scenario_arg: str, overrides: Sequence[str], draw_overrides: Sequence[str]
                   ) -> str:
    """The ``quadland simulate`` command that flies one run of a campaign again."""
    words = ["quadland", "simulate", "--scenario", scenario_arg]
    for text in (*overrides, *draw_overrides):
        words += ["--set", text]
    return shlex.join(words)


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
    manifest = _manifest(base, spec, n_runs)
    path = None if out is None else Path(out).absolute()
    if path is not None:                        # refused now, before the cluster and the build
        _check_folder(CampaignFolder(path), manifest, header)
    given = [o for o in (_override_texts(overrides)) if not o.startswith("campaign.")]
    scenario_arg = _scenario_argument(base, scenario)
    with contextlib.ExitStack() as stack:
        if scheduler is not None:
            stack.enter_context(quiet_cluster_logs())
            connection = _connect(scheduler)
            stack.callback(_disconnect, connection)
        else:
            connection = None
        return _fly_campaign(base, spec, n_runs, header, manifest, path, connection, local,
                             scheduler, scenario_arg, given, progress, plots)


def _fly_campaign(base, spec, n_runs, header, manifest, path, connection, local, scheduler,
                  scenario_arg, given, progress, plots) -> CampaignResult:
    """:func:`run_campaign` once every check has passed: build, claim, fly, summarize."""
    warm_up(base)                               # the compiled simulator, built or loaded
    folder = CampaignFolder(path).claim() if path is not None else _new_folder(base.name)
    with folder:
        rows = _check_folder(folder, manifest, header)  # again, now that it is ours
        folder.start(manifest, header, {"scenario.toml": base.to_toml().encode("utf-8")})
        pending = [i for i in range(n_runs) if i not in rows]
        todo = iter_draws(spec, pending, n_runs)
        bar = _progress_bar(progress, n_runs, len(rows))
        start, flown, invalid = time.perf_counter(), 0, 0
        try:
            if connection is not None:
                batches = _dask_runs(connection, base, todo, spec.limits)
            elif local == 1 or len(pending) <= 1:
                batches = _serial_runs(base, todo, spec.limits)
            else:
                batches = _pool_runs(base, todo, min(local, len(pending)), spec.limits)
            try:
                for batch in batches:
                    new = [_row(o, header) for o in batch]
                    folder.append(new)
                    rows.update((int(r[0]), r) for r in new)
                    invalid += sum(o.status == "invalid" for o in batch)
                    flown += sum(o.status != "invalid" for o in batch)
                    if bar is not None:
                        bar.update(len(new))
            finally:
                batches.close()                 # workers and tasks stopped before the folder
        except KeyboardInterrupt:
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
                files.update(_figures(base, header, ordered, summary))
            folder.finish(header, ordered, files)
        return CampaignResult(folder.path, n_runs, len(rows), flown, elapsed, summary, invalid)


def _check_folder(folder: CampaignFolder, manifest: dict, header: Sequence[str]
                  ) -> dict[int, list[str]]:
    """The runs a folder of this campaign holds; refuse a folder that is not this
    campaign's, or whose journal is damaged (read only: nothing is created or changed)."""
    folder.check()
    old = folder.manifest()
    if old is not None:
        _check_resumable(old, manifest, folder.path)
    return folder.read_runs(header, manifest["runs"] if old is None else old["runs"])


def _new_folder(name: str) -> CampaignFolder:
    """A new folder ``<name>-campaign-<YYYYmmdd-HHMMSS>[-N]`` here, claimed."""
    import datetime

    stem = f"{name}-campaign-{datetime.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    for n in range(1, 1000):
        path = Path.cwd() / (stem if n == 1 else f"{stem}-{n}")
        if path.exists():
            continue
        try:
            return CampaignFolder(path).claim()
        except CampaignError:               # taken meanwhile by a campaign started with it
            if not path.parent.is_dir() or not os.access(path.parent, os.W_OK):
                raise
    raise CampaignError(f"out: no free folder name {stem}-N in {Path.cwd()}")


def _override_texts(overrides) -> list[str]:
    if overrides is None:
        return []
    if isinstance(overrides, Mapping):
        from quadland.scenario import toml_value

        return [f"{k}={toml_value(v)}" for k, v in overrides.items()]
    return [str(o) for o in overrides]


def _cores() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


def available_memory() -> int | None:
    """Memory the system can give new processes without swapping, bytes (None: unknown).

    Linux's ``MemAvailable`` (``/proc/meminfo``), else the free pages.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):
        return None


def worker_memory(base: Scenario) -> int:
    """Memory one local worker process of a campaign of ``base`` takes, bytes (estimate).

    :data:`WORKER_MEMORY` (a process with the simulator loaded) plus the
    arrays of one run (its kind's ``plan``).
    """
    return WORKER_MEMORY + kind_of(base).plan(base).memory_bytes


def local_workers(base: Scenario, workers: int | None, runs: int) -> int:
    """How many local processes fly a campaign of ``runs`` runs of ``base``.

    ``workers`` (default: one per core), no more than the runs, and no more
    than the available memory holds (:func:`worker_memory` each): asked for
    explicitly, too many is refused; by default, fewer are started.

    Raises
    ------
    CampaignError
        ``workers: ...``: more than the memory holds, with what they would take.
    """
    wanted = min(workers or _cores(), runs)
    if wanted == 1:
        return 1                                # flies in this process
    each = worker_memory(base)
    available = available_memory()
    if available is None:
        return wanted
    fit = max(1, available // each)
    if wanted <= fit:
        return wanted
    if workers is None:
        return fit
    what = f"{wanted} local processes" + ("" if wanted == workers else
                                          f" (of the {workers} asked: one per run)")
    raise CampaignError(f"workers: {what} need about "
                        f"{wanted * each / 2**30:.1f} GiB (about {each / 2**20:.0f} MiB each), "
                        f"over the {available / 2**30:.1f} GiB of memory available; use "
                        f"--workers {fit} or fewer")


def _progress_bar(show: bool, total: int, done: int):
    if not show:
        return None
    from tqdm import tqdm

    return tqdm(total=total, initial=done, unit="run", file=sys.stderr, dynamic_ncols=True,
                desc="campaign", smoothing=0.1)


class _Queue:
    """The runs still to submit: ``pop()`` the next, truthy while one is left."""

    def __init__(self, todo: Iterator[RunDraw]):
        self._todo, self._next = todo, next(todo, None)

    def __bool__(self) -> bool:
        return self._next is not None

    def pop(self) -> RunDraw:
        item, self._next = self._next, next(self._todo, None)
        return item


def _serial_runs(base: Scenario, todo: Iterable[RunDraw], limits: Mapping[str, float]
                 ) -> Iterator[list[RunOutcome]]:
    for draw in todo:
        yield [fly(base, draw, limits)]


@dataclasses.dataclass(frozen=True)
class _Raised:
    """An exception a worker's run raised (not a run's outcome), sent to the campaign."""

    error: BaseException


def _worker_main(conn, lifeline, base: Scenario, limits: Mapping[str, float]) -> None:
    """A local worker process: fly the draws ``conn`` brings, send back each outcome.

    Ctrl-C is the campaign's to handle (the forkserver, and so every worker,
    starts with SIGINT ignored; set again here for a forkserver started by
    another caller). Warnings stay silent: the campaign's process has given
    each once, building the same simulator. ``lifeline`` is the read end of a
    pipe whose only write end the campaign's process holds: it reads end of
    file when that process ends, however it ends (a SIGKILL included), and
    the worker exits at once, even in the middle of a run.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    warnings.simplefilter("ignore")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)                        # one BLAS thread per process

    def watch():
        try:
            lifeline.recv()
        except (EOFError, OSError):
            pass
        os._exit(1)

    threading.Thread(target=watch, name="quadland-lifeline", daemon=True).start()
    while True:
        try:
            draw = conn.recv()
        except (EOFError, OSError):
            return
        if draw is None:
            return
        try:
            result = fly(base, draw, limits)
        except Exception as exc:                # a bug, or out of memory: the campaign's
            result = _Raised(exc)               # process raises it
        try:
            conn.send(result)
        except (OSError, ValueError):
            return
        except Exception as exc:                # an exception that does not pickle
            conn.send(_Raised(RuntimeError(f"{type(exc).__name__}: {exc}")))


def _start_forkserver() -> None:
    """Start the forkserver with SIGINT ignored, so that it and every worker ignore Ctrl-C.

    A Ctrl-C meant for the campaign reaches its whole process group: a
    forkserver still importing its preloaded modules, or a worker not yet
    running its first line, would print a traceback. A process started with
    SIGINT ignored keeps it ignored (Python installs its handler only over
    the default). SIGINT is blocked meanwhile in this process, so that a
    Ctrl-C in that moment is delivered here afterwards, not lost.
    """
    from multiprocessing import forkserver, resource_tracker

    resource_tracker.ensure_running()           # it unblocks SIGINT itself when it starts
    if threading.current_thread() is not threading.main_thread():
        forkserver.ensure_running()
        return
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        if signal.SIGINT in signal.sigpending():
            return                              # raised as KeyboardInterrupt when unblocked
        handler = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            forkserver.ensure_running()
        finally:
            signal.signal(signal.SIGINT, signal.SIG_DFL if handler is None else handler)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


class _Worker:
    """A local worker process, its end of the pipe and the runs sent to it."""

    def __init__(self, context, lifeline, base: Scenario, limits: Mapping[str, float]):
        self.conn, theirs = context.Pipe()
        self.process = context.Process(target=_worker_main, name="quadland-campaign-worker",
                                       args=(theirs, lifeline, base, limits), daemon=True)
        self.process.start()
        theirs.close()
        self.busy = 0

    def send(self, draw: RunDraw) -> None:
        self.conn.send(draw)
        self.busy += 1


def _pool_runs(base: Scenario, todo: Iterator[RunDraw], workers: int,
               limits: Mapping[str, float]) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on ``workers`` local processes; yield outcomes as they finish.

    Each worker is a process of the ``forkserver`` (no fork of a process
    that holds threads) fed through its own pipe, at most :data:`_AHEAD`
    runs ahead. Only pipes connect them: no semaphore that a SIGKILLed
    campaign would leave to the resource tracker.
    """
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["quadland.campaign.execute"])
    _start_forkserver()
    queue = _Queue(todo)
    lifeline, keep = context.Pipe(duplex=False)
    pool: list[_Worker] = []
    try:
        for _ in range(workers):
            pool.append(_Worker(context, lifeline, base, limits))
        lifeline.close()
        for worker in pool:
            while queue and worker.busy < _AHEAD:
                worker.send(queue.pop())
        while any(w.busy for w in pool):
            ready = multiprocessing.connection.wait([w.conn for w in pool if w.busy])
            outcomes, lost = [], None
            for worker in pool:
                if worker.conn not in ready:
                    continue
                try:
                    result = worker.conn.recv()
                except (EOFError, OSError):
                    lost = worker
                    continue
                worker.busy -= 1
                if isinstance(result, _Raised):
                    raise result.error
                outcomes.append(result)
                try:
                    while queue and worker.busy < _AHEAD:
                        worker.send(queue.pop())
                except OSError:
                    lost = worker
            if outcomes:
                yield outcomes
            if lost is not None:
                lost.process.join(1.0)
                code = lost.process.exitcode
                how = f"killed by signal {-code}" if code is not None and code < 0 else \
                    "killed, or out of memory"
                raise CampaignStopped(f"a worker process died ({how}); the finished runs are "
                                      "recorded: run the same command to resume")
    finally:
        keep.close()                            # every worker exits, even mid-run
        for worker in pool:
            worker.conn.close()
        for worker in pool:
            worker.process.join(5.0)
            if worker.process.exitcode is None:
                worker.process.kill()
                worker.process.join()


def check_address(address) -> None:
    """Refuse, in one line, a scheduler address that is not ``[PROTOCOL://]HOST:PORT``."""
    import re

    match = re.fullmatch(r"(?:(tcp|tls|ws|wss|ucx)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+)"
                         r":([0-9]{1,5})", str(address))
    if match is None or not 1 <= int(match.group(3)) <= 65535:
        from quadland.scenario import toml_value

        raise CampaignError(f"scheduler: expected tcp://HOST:PORT (or HOST:PORT; also tls, "
                            f"ws, wss, ucx), got {toml_value(str(address))[:80]}")


def _connect(address: str):
    """A ``distributed.Client`` of the scheduler at ``address``, with the workers checked."""
    try:
        from distributed import Client
    except ImportError:
        raise CampaignError("scheduler: needs the dask.distributed package "
                            "(pip install 'dask[distributed]')") from None
    _reachable(address)
    _handshake(address)
    try:
        client = Client(address, timeout=f"{2 * SCHEDULER_TIMEOUT_S:g}s", set_as_default=False)
    except Exception as exc:                    # OSError, TimeoutError, or a protocol's
        raise CampaignError(f"scheduler: cannot connect to {address}: "
                            f"{' '.join(str(exc).split()) or type(exc).__name__}") from None
    try:
        client.wait_for_workers(1, timeout=30)
        mine = _identity()
        for worker, theirs in client.run(_identity).items():
            if theirs != mine:
                raise CampaignError(f"scheduler: worker {worker} runs another quadland "
                                    f"({theirs}, here {mine})")
    except (OSError, TimeoutError) as exc:
        _disconnect(client)
        raise CampaignError(f"scheduler: {address} has no worker ({exc})") from None
    except BaseException:
        _disconnect(client)
        raise
    return client


@contextlib.contextmanager
def quiet_cluster_logs():
    """Silence the log lines of dask.distributed, tornado and asyncio meanwhile.

    A lost or failing scheduler connection makes them log (a refused
    handshake, a closed stream, a task never awaited) beside the campaign's
    one line. Their loggers' levels are set above CRITICAL, and set back
    after.
    """
    import logging

    try:
        import distributed  # noqa: F401  (its import sets its loggers' levels)
    except ImportError:
        pass
    names = ["distributed", "tornado", "asyncio"] + [
        n for n in logging.root.manager.loggerDict
        if n.startswith(("distributed.", "tornado."))]
    saved = {n: logging.getLogger(n).level for n in names}
    for name in names:
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for name, level in saved.items():
            logging.getLogger(name).setLevel(level)


def _handshake(address: str) -> None:
    """Refuse a TCP address whose listener does not answer as a Dask scheduler.

    ``distributed.Client`` waits for the scheduler's handshake without a
    bound: a server that accepts and says nothing (or an HTTP server, or
    anything else) would hold the campaign forever. Here the handshake is
    tried first, in a thread of its own, for :data:`SCHEDULER_TIMEOUT_S`.
    """
    scheme, _, _ = address.rpartition("://")
    if scheme not in ("", "tcp"):
        return
    import asyncio

    from distributed.comm import connect

    answer: dict = {}

    async def probe():
        comm = await connect(address if scheme else f"tcp://{address}",
                             timeout=SCHEDULER_TIMEOUT_S)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    def run():
        try:
            answer["info"] = asyncio.run(asyncio.wait_for(probe(), SCHEDULER_TIMEOUT_S))
        except BaseException as exc:            # reported below, in this thread
            answer["error"] = exc

    thread = threading.Thread(target=run, name="quadland-scheduler-handshake", daemon=True)
    thread.start()
    thread.join(SCHEDULER_TIMEOUT_S + 1.0)
    info = answer.get("info")
    if isinstance(info, dict) and info.get("type") == "Scheduler":
        return
    error = answer.get("error")
    if "info" in answer:
        why = "its answer is not a scheduler's"
    elif error is None or isinstance(error, TimeoutError):
        why = f"no answer within {SCHEDULER_TIMEOUT_S:g} s"
    else:
        why = " ".join(str(error).split())[:120] or type(error).__name__
    raise CampaignError(f"scheduler: {address} does not answer as a Dask scheduler: {why}")


def _reachable(address: str) -> None:
    """Refuse at once a TCP address where nothing listens (the client would retry 15 s)."""
    import socket

    scheme, _, location = address.rpartition("://")
    if scheme not in ("", "tcp"):
        return
    host, _, port = location.rpartition(":")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=5.0).close()
    except OSError as exc:
        raise CampaignError(f"scheduler: cannot connect to {address}: "
                            f"{exc.strerror or exc}") from None


def _disconnect(client) -> None:
    """Close a client quickly, whether or not its scheduler is still there."""
    try:
        client.close(timeout=2)
    except Exception:                           # the scheduler is gone: nothing to tell it
        pass


def _identity() -> str:
    from quadland import __version__

    return f"quadland {__version__}, code {code_fingerprint()}"


def _cluster_error(exc: BaseException) -> bool:
    """The exception is the cluster's (a lost worker, scheduler or connection)."""
    return type(exc).__module__.split(".")[0] in ("distributed", "tornado") or \
        isinstance(exc, OSError | TimeoutError | cf.CancelledError)


def _stopped(why: str) -> CampaignStopped:
    return CampaignStopped(f"{why}; the finished runs are recorded: run the same command to "
                           "resume")


def _dask_runs(client, base: Scenario, todo: Iterator[RunDraw], limits: Mapping[str, float]
               ) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on the cluster's workers; yield outcomes as they finish.

    A run lost with its worker is flown again by another (Dask reschedules
    it); the campaign stops (:class:`CampaignStopped`) when a run fails for
    the cluster's sake (a worker killed while flying it too often), when
    the scheduler is lost, or when no worker is left for
    :data:`NO_WORKER_GRACE_S` seconds.
    """
    from distributed import as_completed

    pending = None
    try:
        try:
            client.run(warm_up, base)           # each worker builds or loads its simulator
            threads = sum(client.nthreads().values())
            base_future = client.scatter(base, broadcast=True, hash=False)
        except Exception as exc:
            if not _cluster_error(exc):
                raise
            raise _stopped(f"the cluster failed while preparing its workers "
                           f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]})") \
                from None
        queue = _Queue(todo)
        pending = as_completed(loop=client.loop)

        def submit(k):
            for _ in range(k):
                if queue:
                    pending.add(client.submit(fly, base_future, queue.pop(), limits,
                                              pure=False))

        submit(_AHEAD * max(threads, 1))
        quiet_since = alone_since = time.monotonic()
        while not pending.is_empty():
            if not pending.has_ready():
                with pending.thread_condition:
                    pending.thread_condition.wait(timeout=0.25)
            done = pending.next_batch(block=False)
            outcomes, why = [], None
            for future in done:
                if future.status in ("lost", "pending"):
                    pending.add(future)         # its worker died with its result: flown again
                    continue
                try:
                    outcomes.append(future.result(timeout=30))
                    continue
                except Exception as exc:        # failed, cancelled, or lost meanwhile
                    error = exc
                if not _cluster_error(error):
                    raise error
                why = why or _loss(client, error)
            if outcomes:
                yield outcomes
            if why is not None:
                raise _stopped(why)
            submit(len(done))
            now = time.monotonic()
            if done:
                quiet_since = alone_since = now
                continue
            if now - quiet_since < 1.0:
                continue
            quiet_since = now                   # a second without a result: ask the cluster
            if client.status != "running":
                raise _stopped("the cluster's scheduler was lost")
            try:
                workers = len(client.nthreads())
            except Exception as exc:
                if not _cluster_error(exc):
                    raise
                raise _stopped("the cluster's scheduler was lost") from None
            if workers:
                alone_since = now
            elif now - alone_since > NO_WORKER_GRACE_S:
                raise _stopped(f"the cluster has had no worker for {NO_WORKER_GRACE_S:g} s")
    finally:
        if pending is not None:
            leftover = list(pending.futures)
            pending.clear()
            if leftover and client.status == "running":
                try:
                    client.cancel(leftover, force=True)
                except Exception:               # the scheduler is gone with its tasks
                    pass


def _loss(client, error: BaseException) -> str:
    """Why a run was lost on the cluster, in words."""
    text = " ".join(str(error).split())
    if client.status != "running" or "connection" in text.lower():
        return "the cluster's scheduler was lost"
    name = type(error).__name__
    if name == "KilledWorker":
        return f"the cluster lost a run with its worker ({name}: {text[:160]})"
    if "Cancelled" in name:
        return "the cluster cancelled a run: a worker was lost"
    return f"the cluster lost a run ({name}: {text[:160]})"
def _parse(rows: Sequence[Sequence[str]], header: Sequence[str]) -> dict[str, list[str]]:
    return {name: [r[k] for r in rows] for k, name in enumerate(header)}


def _floats(texts: Iterable[str]) -> np.ndarray:
    return np.array([float(t) if t != "" else np.nan for t in texts])


def _severity(cols: Mapping[str, list[str]], limits: Mapping[str, float], n: int) -> np.ndarray:
    """Each run's largest metric / limit ratio (inf when undefined or not flown to the end)."""
    out = np.zeros(n)
    ok = np.array([s == "ok" for s in cols["status"]])
    for name, limit in limits.items():
        ratio = _floats(cols[name]) / limit
        out = np.maximum(out, np.where(np.isnan(ratio), np.inf, ratio))
    return np.where(ok, out, np.inf)


def _dispersed_numbers(spec, cols: Mapping[str, list[str]]) -> dict[str, np.ndarray]:
    """Each varying dispersed column as numbers (a choice as its position in ``values``)."""
    out = {}
    for disp in spec.dispersions:
        if disp.distribution == "seed":
            continue
        for col in disp.columns():
            if disp.distribution == "choice":
                texts = [format_value(v) for v in disp.values]
                out[col] = np.array([texts.index(t) if t in texts else -1 for t in cols[col]],
                                    dtype=float)
            else:
                out[col] = _floats(cols[col])
    return out


def summarize_campaign(base: Scenario, header: Sequence[str], rows: Sequence[Sequence[str]],
                       scenario_arg: str | None = None, overrides: Sequence[str] = ()
                       ) -> dict:
    """summary.json of a finished campaign, from its runs.csv rows (sorted by index).

    Success rate with its exact (Clopper-Pearson) 95 % interval and
    one-sided lower bound over the runs flown (``ok`` or ``failed``; an
    ``invalid`` run is counted apart); p50, p90, p99 and max (order
    statistics) of every metric; the worst runs with the command that
    replays each; the dispersed column that best separates failures.
    Without a flown run (every draw invalid) the rate, its interval and the
    separation are null and ``note`` says so; without a failure (or a
    success) ``separation`` is null and ``most_correlated`` names the column
    the severity follows most.
    """
    spec, model = campaign_spec_of(base), base.model
    cols = _parse(rows, header)
    n_all = len(rows)
    status = np.array(cols["status"])
    success = np.array([s == "true" for s in cols["success"]])
    flown = status != "invalid"
    n, k = int(flown.sum()), int((success & flown).sum())
    limits = kind_of(base).limits(base, spec.limits)
    summary: dict = {"scenario": base.name, "model": model, "runs": n_all, "flown": n,
                     "invalid": int((~flown).sum()), "successes": k, "failures": n - k,
                     "numerical_failures": int((status == "failed").sum())}
    summary["success_rate"] = summary["confidence"] = None
    if n:
        lo, hi = clopper_pearson(k, n, CONFIDENCE)
        summary["success_rate"] = k / n
        summary["confidence"] = {
            "level": CONFIDENCE, "method": "Clopper-Pearson (exact binomial)",
            "interval": [lo, hi],
            "lower_bound_one_sided": lower_confidence_bound(k, n, CONFIDENCE)}
    else:
        summary["note"] = (f"no run was flown: the draws of all {n_all} were invalid (each "
                           "row's message says why); no success rate, no figures")
    metrics = {}
    for m in kind_of(model).metrics:
        x = _floats(cols[m.name])
        x = x[~np.isnan(x)]
        entry = {"unit": m.unit, "doc": m.doc, "limit": limits.get(m.name), "n": int(x.size),
                 "undefined": int(n - x.size)}
        if m.name in limits:
            entry["within_limit"] = int(np.sum(x <= limits[m.name]))
        for label, q in QUANTILES.items():
            entry[label] = order_statistic(x, q) if x.size else None
        metrics[m.name] = entry
    summary["metrics"] = metrics
    severity = _severity(cols, limits, n_all)
    order = sorted((i for i in range(n_all) if flown[i]),
                   key=lambda i: (status[i] != "failed", -severity[i], i))
    worst = []
    arg = scenario_arg or Path(base.source).stem
    draw_cols = spec.columns()
    for i in order[:WORST_RUNS]:
        values = _row_values(spec, cols, i)
        worst.append({
            "index": i, "seed": int(cols["seed"][i]), "status": status[i],
            "success": bool(success[i]), "message": cols["message"][i],
            "severity": severity[i],
            "metrics": {m.name: (None if cols[m.name][i] == "" else float(cols[m.name][i]))
                        for m in kind_of(model).metrics},
            "dispersed": {c: cols[c][i] for c in draw_cols},
            "command": replay_command(arg, overrides, values)})
    summary["worst_runs"] = worst
    numbers = _dispersed_numbers(spec, cols)
    fail = ~success[flown]
    sep = separation({c: v[flown] for c, v in numbers.items()}, fail) if n else None
    summary["separation"] = None if sep is None else {
        "parameter": sep.parameter, "ks_statistic": sep.statistic,
        "failures": int(fail.sum()), "successes": int((~fail).sum())}
    if sep is None and numbers and n:
        name, rho = _most_correlated({c: v[flown] for c, v in numbers.items()},
                                     severity[flown])
        summary["most_correlated"] = {"parameter": name, "spearman_rho": rho}
    summary["campaign"] = {**spec.identity(), "runs": n_all}
    summary["severity_definition"] = "largest metric / limit of a run; > 1 misses a limit"
    return summary


def _row_values(spec, cols: Mapping[str, list[str]], i: int) -> list[str]:
    """Run ``i``'s dispersed values as ``--set`` texts, from its runs.csv row."""
    out = []
    for disp in spec.dispersions:
        if disp.distribution in ("seed", "choice"):
            out.append(f"{disp.key}={cols[disp.key][i]}")
            continue
        for target in disp.targets:
            texts = [cols[c][i] for c in target.columns()]
            value = texts[0] if target.scalar else "[" + ", ".join(texts) + "]"
            out.append(f"{target.key}={value}")
    return out


def _figures(base: Scenario, header, rows, summary) -> dict[str, bytes]:
    from quadland.output import figure_png
    from quadland.plots.campaign import failures_figure, metrics_cdf_figure

    spec = campaign_spec_of(base)
    cols = _parse(rows, header)
    limits = kind_of(base).limits(base, spec.limits)
    success = np.array([s == "true" for s in cols["success"]])
    flown = np.array([s != "invalid" for s in cols["status"]])
    if not flown.any():
        return {}                               # nothing to draw: summary.json's note says so
    metric_values = {m.name: _floats(cols[m.name])[flown] for m in kind_of(base).metrics
                     if m.name in limits}
    units = {m.name: m.unit for m in kind_of(base).metrics}
    files = {}
    if metric_values:
        files["metrics_cdf.png"] = figure_png(metrics_cdf_figure(metric_values, limits, units))
    numbers = {c: v[flown] for c, v in _dispersed_numbers(spec, cols).items()}
    severity = _severity(cols, limits, len(rows))[flown]
    if summary["separation"] is not None:
        sep = summary["separation"]
        name, title = sep["parameter"], (f"Failures against {sep['parameter']}, the parameter "
                                         f"that best separates them (KS D = "
                                         f"{sep['ks_statistic']:.2f})")
    elif "most_correlated" in summary:
        corr = summary["most_correlated"]
        name = corr["parameter"]
        rho = corr["spearman_rho"]
        title = (f"No {'failure' if success[flown].all() else 'success'}: the runs against "
                 + (f"{name}, the parameter the severity follows most (Spearman rho = "
                    f"{rho:.2f})" if rho is not None else f"{name} (the severity is constant)"))
    else:
        return files
    files["failures.png"] = figure_png(failures_figure(numbers[name], severity,
                                                       ~success[flown], name, title))
    return files


def _most_correlated(numbers: Mapping[str, np.ndarray], severity: np.ndarray
                     ) -> tuple[str, float | None]:
    """The column whose ranks follow the severity's most closely, and its Spearman rho."""
    from scipy.stats import rankdata

    s = rankdata(np.where(np.isfinite(severity), severity, np.inf))
    best, best_r = next(iter(numbers)), None
    for name, x in numbers.items():
        if np.ptp(x) == 0 or np.ptp(s) == 0:
            continue
        r = float(np.corrcoef(rankdata(x), s)[0, 1])
        if math.isfinite(r) and (best_r is None or abs(r) > abs(best_r)):
            best, best_r = name, r
    return best, best_r

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
import dataclasses
import hashlib
import math
import multiprocessing
import os
import shlex
import signal
import sys
import threading
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

from quadland.campaign.fly import RunOutcome, fly, warm_up
from quadland.campaign.journal import CampaignFolder
from quadland.campaign.metrics import METRICS, limits_of
from quadland.campaign.sampling import RunDraw, format_value, iter_draws
from quadland.campaign.spec import MAX_RUNS
from quadland.campaign.statistics import (
    clopper_pearson,
    lower_confidence_bound,
    order_statistic,
    separation,
)
from quadland.exceptions import CampaignError, CampaignStopped
from quadland.scenario import SCENARIO_DIR, Scenario, load_scenario

__all__ = ["CampaignResult", "CampaignInterrupted", "run_campaign", "summarize_campaign",
           "campaign_header", "code_fingerprint", "replay_command", "CAMPAIGN_FIGURES",
           "CONFIDENCE", "QUANTILES", "WORST_RUNS"]

#: Confidence level of the success rate's interval and bound.
CONFIDENCE = 0.95
#: The order statistics summary.json gives of every metric.
QUANTILES = {"p50": 0.5, "p90": 0.9, "p99": 0.99, "max": 1.0}
#: Runs listed in summary.json's ``worst_runs``.
WORST_RUNS = 5
#: The figures of a finished campaign.
CAMPAIGN_FIGURES = ("metrics_cdf.png", "failures.png")
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
    """

    folder: Path
    runs: int
    recorded: int
    flown: int
    elapsed: float
    summary: dict | None

    @property
    def complete(self) -> bool:
        """Every run is recorded."""
        return self.recorded == self.runs


def campaign_header(spec, model: str) -> list[str]:
    """The columns of runs.csv."""
    return ["index", "seed", "status", "success", *spec.columns(),
            *(m.name for m in METRICS[model]), "message"]


def _row(outcome: RunOutcome, header: Sequence[str]) -> list[str]:
    texts = {"index": str(outcome.index), "seed": str(outcome.seed), "status": outcome.status,
             "success": "true" if outcome.success else "false", "message": outcome.message,
             **outcome.columns}
    for name, value in outcome.metrics.items():
        texts[name] = "" if value is None else format_value(value)
    return [texts.get(name, "") for name in header]


def code_fingerprint() -> str:
    """A hash of the source files of ``quadland`` and ``symbolic`` (Python and templates)."""
    import quadland
    import symbolic

    digest = hashlib.sha256()
    for package in (quadland, symbolic):
        root = Path(package.__file__).parent
        for path in sorted(p for p in root.rglob("*") if p.suffix in (".py", ".jinja")):
            digest.update(str(path.relative_to(root.parent)).encode() + b"\0")
            digest.update(path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


def _manifest(scenario: Scenario, runs: int) -> dict:
    from importlib.metadata import version

    from quadland import __version__
    from quadland.build import compiler_version

    return {"format": _FORMAT, "quadland": __version__, "code": code_fingerprint(),
            "libraries": {name: version(name) for name in ("casadi", "numpy", "scipy")},
            "c_compiler": compiler_version(), "runs": runs,
            "campaign": scenario.campaign.identity(), "scenario": scenario.to_dict()}


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
    text = format_value(value) if not isinstance(value, Mapping) else str(dict(value))
    return text if len(text) <= 40 else text[:37] + "..."


def _check_resumable(old: dict, new: dict, path: Path) -> None:
    """Refuse, naming the first difference, a folder of another campaign."""
    why = None
    if old.get("format") != _FORMAT:
        why = f"it was written by another quadland (campaign format {old.get('format')})"
    elif old.get("quadland") != new["quadland"]:
        why = f"quadland {old.get('quadland')} made it, this is {new['quadland']}"
    elif old.get("code") != new["code"]:
        why = "quadland's source code changed since (its runs would not be comparable)"
    elif old.get("libraries") != new["libraries"] or old.get("c_compiler") != new["c_compiler"]:
        diff = _differences({**old.get("libraries", {}), "c_compiler": old.get("c_compiler")},
                            {**new["libraries"], "c_compiler": new["c_compiler"]})
        why = f"a library changed: {diff[0]}"
    elif old.get("scenario") != new["scenario"]:
        diff = _differences(old.get("scenario", {}), new["scenario"])
        why = f"the scenario changed: {diff[0]}" + \
            (f" (and {len(diff) - 1} more)" if len(diff) > 1 else "")
    elif old.get("campaign") != new["campaign"]:
        diff = _differences(old.get("campaign", {}), new["campaign"], "campaign.")
        what = "the dispersions" if diff[0].startswith("campaign.dispersions") else \
            "the campaign"
        why = f"{what} changed: {diff[0]}"
    elif new["runs"] < old.get("runs", 0):
        why = f"it holds a campaign of {old['runs']} runs; --runs can only grow"
    elif new["runs"] != old.get("runs") and new["campaign"].get("sampling") == "lhs":
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
        Local processes (default: every core; 1 flies in this process).
        Ignored with ``scheduler``.
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
        Before any run: a bad scenario or campaign table, a folder that
        holds something else or another campaign (the message says what
        changed), a scheduler that cannot be reached.
    CampaignStopped
        A worker died or the scheduler was lost; the recorded runs stay.
    KeyboardInterrupt
        The recorded runs stay; running again resumes.
    """
    base = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    if base.campaign is None:
        raise CampaignError(f"scenario: {base.name} has no [campaign] table "
                            "(docs/campaign.md shows one)")
    n_runs = base.campaign.runs if runs is None else runs
    if not isinstance(n_runs, int) or not 1 <= n_runs <= MAX_RUNS:
        raise CampaignError(f"runs: must be in [1, {MAX_RUNS}], got {n_runs}")
    if workers is not None and not 1 <= workers <= 1024:
        raise CampaignError(f"workers: must be in [1, 1024], got {workers}")
    from quadland.output import output_folder
    from quadland.simulate import check_plan

    check_plan(base)
    path = output_folder(out, base.name, "campaign").path
    given = [o for o in (_override_texts(overrides)) if not o.startswith("campaign.")]
    scenario_arg = _scenario_argument(base, scenario)
    with CampaignFolder(path) as folder:
        manifest = _manifest(base, n_runs)
        old = folder.manifest()
        if old is not None:
            _check_resumable(old, manifest, folder.path)
        header = campaign_header(base.campaign, base.model)
        connection = _connect(scheduler) if scheduler else None
        try:
            warm_up(base)
            folder.start(manifest, header, {"scenario.toml": base.to_toml().encode("utf-8")})
            rows = folder.read_runs(header)
            pending = [i for i in range(n_runs) if i not in rows]
            todo = iter_draws(base.campaign, pending, n_runs)
            bar = _progress_bar(progress, n_runs, len(rows))
            start, flown = time.perf_counter(), 0
            try:
                if connection is not None:
                    batches = _dask_runs(connection, base, todo)
                elif (workers or _cores()) == 1 or len(pending) <= 1:
                    batches = _serial_runs(base, todo)
                else:
                    batches = _pool_runs(base, todo, min(workers or _cores(), len(pending)))
                for batch in batches:
                    new = [_row(o, header) for o in batch]
                    folder.append(new)
                    rows.update((int(r[0]), r) for r in new)
                    flown += len(new)
                    if bar is not None:
                        bar.update(len(new))
            except KeyboardInterrupt:
                raise CampaignInterrupted(folder.path, len(rows), n_runs) from None
            finally:
                if bar is not None:
                    bar.close()
            elapsed = time.perf_counter() - start
        finally:
            if connection is not None:
                connection.close()
        summary = None
        if len(rows) == n_runs:
            ordered = [rows[i] for i in range(n_runs)]
            summary = summarize_campaign(base, header, ordered, scenario_arg, given)
            summary["last_session"] = {
                "runs_flown": flown, "wall_s": elapsed,
                "runs_per_s": flown / elapsed if flown and elapsed > 0 else None,
                "where": scheduler or f"{workers or _cores()} local process(es)"}
            from quadland.output import strict_json
            from quadland.run import provenance

            summary["provenance"] = provenance(base)
            files = {"summary.json": strict_json(summary)}
            if plots:
                files.update(_figures(base, header, ordered, summary))
            folder.finish(header, ordered, files)
        return CampaignResult(folder.path, n_runs, len(rows), flown, elapsed, summary)


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


def _serial_runs(base: Scenario, todo: Iterable[RunDraw]) -> Iterator[list[RunOutcome]]:
    for draw in todo:
        yield [fly(base, draw)]


def _worker_init(lifeline) -> None:
    """A pool process: Ctrl-C is the parent's to handle; exit when the parent is gone.

    ``lifeline`` is the read end of a pipe whose only write end the campaign's
    process holds: it reads end of file when that process ends, however it
    ends (a SIGKILL included), and the worker exits instead of waiting for
    work forever.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)                        # one BLAS thread per process

    def watch():
        try:
            lifeline.recv()
        except (EOFError, OSError):
            pass
        os._exit(1)

    threading.Thread(target=watch, name="quadland-lifeline", daemon=True).start()


def _pool_runs(base: Scenario, todo: Iterator[RunDraw], workers: int
               ) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on ``workers`` local processes; yield outcomes as they finish."""
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["quadland.campaign.fly"])
    queue = _Queue(todo)
    ahead = 4 * workers                         # runs queued per process, for throughput
    lifeline, keep = context.Pipe(duplex=False)
    pool = cf.ProcessPoolExecutor(workers, mp_context=context, initializer=_worker_init,
                                  initargs=(lifeline,))
    running: set[cf.Future] = set()
    try:
        while queue or running:
            while queue and len(running) < ahead:
                running.add(pool.submit(fly, base, queue.pop()))
            done, running = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            try:
                yield [f.result() for f in done]
            except cf.process.BrokenProcessPool:
                raise CampaignStopped("a worker process died (killed, or out of memory); "
                                      "the finished runs are recorded: run the same "
                                      "command to resume") from None
    finally:
        pool.shutdown(wait=False, cancel_futures=True)
        lifeline.close()
        keep.close()


def _connect(address: str):
    """A ``distributed.Client`` of the scheduler at ``address``, with the workers checked."""
    try:
        from distributed import Client
    except ImportError:
        raise CampaignError("scheduler: needs the dask.distributed package "
                            "(pip install 'dask[distributed]')") from None
    try:
        client = Client(address, timeout="15s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise CampaignError(f"scheduler: cannot connect to {address}: "
                            f"{' '.join(str(exc).split()) or type(exc).__name__}") from None
    try:
        client.wait_for_workers(1, timeout=30)
    except (OSError, TimeoutError) as exc:
        client.close()
        raise CampaignError(f"scheduler: {address} has no worker ({exc})") from None
    mine = _identity()
    for worker, theirs in client.run(_identity).items():
        if theirs != mine:
            client.close()
            raise CampaignError(f"scheduler: worker {worker} runs another quadland "
                                f"({theirs}, here {mine})")
    return client


def _identity() -> str:
    from quadland import __version__

    return f"quadland {__version__}, code {code_fingerprint()}"


def _dask_runs(client, base: Scenario, todo: Iterator[RunDraw]) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on the cluster's workers; yield outcomes as they finish."""
    from distributed import as_completed

    client.run(warm_up, base)                   # each worker builds or loads its simulator
    threads = sum(client.nthreads().values())
    base_future = client.scatter(base, broadcast=True, hash=False)
    queue = _Queue(todo)
    first = []
    while queue and len(first) < 4 * threads:
        first.append(client.submit(fly, base_future, queue.pop(), pure=False))
    pending = as_completed(first, with_results=True, loop=client.loop)
    try:
        for batch in pending.batches():
            outcomes = [outcome for _, outcome in batch]
            for _ in outcomes:
                if queue:
                    pending.add(client.submit(fly, base_future, queue.pop(), pure=False))
            yield outcomes
    except Exception as exc:
        if type(exc).__module__.split(".")[0] != "distributed" and \
                not isinstance(exc, OSError | TimeoutError):
            raise
        raise CampaignStopped(f"the cluster lost a run ({type(exc).__name__}: "
                              f"{' '.join(str(exc).split())[:200]}); the finished runs are "
                              "recorded: run the same command to resume") from None
    finally:
        leftover = list(pending.futures)
        pending.clear()
        if leftover:
            client.cancel(leftover, force=True)


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
    """
    spec, model = base.campaign, base.model
    cols = _parse(rows, header)
    n_all = len(rows)
    status = np.array(cols["status"])
    success = np.array([s == "true" for s in cols["success"]])
    flown = status != "invalid"
    n, k = int(flown.sum()), int((success & flown).sum())
    limits = limits_of(base, spec.limits)
    summary: dict = {"scenario": base.name, "model": model, "runs": n_all, "flown": n,
                     "invalid": int((~flown).sum()), "successes": k, "failures": n - k,
                     "numerical_failures": int((status == "failed").sum())}
    if n:
        lo, hi = clopper_pearson(k, n, CONFIDENCE)
        summary["success_rate"] = k / n
        summary["confidence"] = {
            "level": CONFIDENCE, "method": "Clopper-Pearson (exact binomial)",
            "interval": [lo, hi],
            "lower_bound_one_sided": lower_confidence_bound(k, n, CONFIDENCE)}
    metrics = {}
    for m in METRICS[model]:
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
                        for m in METRICS[model]},
            "dispersed": {c: cols[c][i] for c in draw_cols},
            "command": replay_command(arg, overrides, values)})
    summary["worst_runs"] = worst
    numbers = _dispersed_numbers(spec, cols)
    fail = ~success[flown]
    sep = separation({c: v[flown] for c, v in numbers.items()}, fail)
    summary["separation"] = None if sep is None else {
        "parameter": sep.parameter, "ks_statistic": sep.statistic,
        "failures": int(fail.sum()), "successes": int((~fail).sum())}
    if sep is None and numbers:
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

    cols = _parse(rows, header)
    limits = limits_of(base, base.campaign.limits)
    success = np.array([s == "true" for s in cols["success"]])
    flown = np.array([s != "invalid" for s in cols["status"]])
    metric_values = {m.name: _floats(cols[m.name])[flown] for m in METRICS[base.model]
                     if m.name in limits}
    units = {m.name: m.unit for m in METRICS[base.model]}
    files = {}
    if metric_values:
        files["metrics_cdf.png"] = figure_png(metrics_cdf_figure(metric_values, limits, units))
    numbers = {c: v[flown] for c, v in _dispersed_numbers(base.campaign, cols).items()}
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

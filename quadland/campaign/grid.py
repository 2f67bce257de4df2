"""An envelope: a grid of two scenario keys, each cell a small campaign (``quadland envelope``).

:func:`run_envelope` checks the axes (:mod:`~quadland.campaign.axes`), the
scenario's ``[campaign]`` table and every cell's scenario before anything is
written, then flies ``runs_per_cell`` runs in each cell with the campaign's
machinery: the same draws (run ``r`` of every cell is run ``r`` of the
scenario's campaign, the axes' values in place of what it drew for those
keys: common random numbers, so that neighbouring cells differ by the axes
alone), the same journal (``runs.csv``, one row per run, appended and made
durable as each finishes), the same local processes or Dask cluster, the same
resumption (an interrupted envelope flies only the runs its folder does not
hold). Run ``g`` of the envelope is replicate ``g % K`` of cell ``g // K``,
cells in row-major order (the first axis slowest). When every run is
recorded, :mod:`~quadland.campaign.cells` counts each cell and writes
``envelope.json`` and ``envelope.png``.

The runs fly replicate by replicate (:func:`flight_order`: replicate 0 of every cell,
then replicate 1, ...), and each process that flies them keeps up to
:data:`KEEP_BYTES` of what a run draws from its seed and from keys the axes do not
set (:mod:`quadland.engine.kept`: a landing's sensors' table, its force and moment
noise, its turbulence's normals and its gust), so that each is drawn about once per
replicate and process instead of once per run; runs.csv is the same bytes (its rows are
written sorted by index).
"""

from __future__ import annotations

import contextlib
import dataclasses
import itertools
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from quadland import interrupt
from quadland.campaign.axes import Axis, apply_cell, parse_axis
from quadland.campaign.cells import envelope_files
from quadland.campaign.cluster import (
    check_address,
    connect,
    dask_runs,
    disconnect,
    quiet_cluster_logs,
)
from quadland.campaign.dispersed import dispersed
from quadland.campaign.execute import CampaignInterrupted
from quadland.campaign.fly import warm_up
from quadland.campaign.journal import CampaignFolder, new_folder
from quadland.campaign.local import (
    MAX_WORKERS,
    chunk_size,
    local_workers,
    pool_runs,
    serial_runs,
)
from quadland.campaign.resume import campaign_manifest, check_folder
from quadland.campaign.sampling import RunDraw, draws, format_value
from quadland.campaign.spec import MAX_RUNS, CampaignSpec, campaign_spec_of
from quadland.engine.kept import KEPT
from quadland.exceptions import CampaignError, ScenarioError
from quadland.kinds import kind_of
from quadland.scenario import Scenario, load_scenario

__all__ = ["EnvelopeResult", "Envelope", "plan_envelope", "run_envelope", "envelope_header",
           "cell_draws", "flight_order", "ENVELOPE_FORMAT", "MAX_RUNS_PER_CELL", "KEEP_BYTES"]

#: Format of the ``envelope`` entry of an envelope's campaign.json.
ENVELOPE_FORMAT = 1
#: Most runs in one cell.
MAX_RUNS_PER_CELL = 100_000
#: Bytes of draws each process flying an envelope's runs keeps for its next runs
#: (:mod:`quadland.engine.kept`): a ``highway`` run's sensors' table, drawn to 40 s, is
#: 8.8 MB with its draws' rows and their room (``ship_ss5``'s to 180 s about 37 MB), its
#: force and moment noise 0.2 MB, its wind's normals and gust 0.1 MB each. Flown replicate
#: by replicate, a local worker needs one table at a time.
KEEP_BYTES = 64 * 2**20


@dataclasses.dataclass(frozen=True)
class Envelope:
    """A checked envelope: its scenario, campaign, axes and runs.

    Attributes
    ----------
    base : Scenario
        The scenario (its ``[campaign]`` table as validated).
    spec : CampaignSpec
    axes : tuple of Axis
        Two axes.
    runs_per_cell : int
    hold : tuple of str
        Dispersed keys held at the scenario's value.
    polar : bool
        Drawn as a polar map (an axis of directions in degrees as the angle).
    """

    base: Scenario
    spec: CampaignSpec
    axes: tuple[Axis, ...]
    runs_per_cell: int
    hold: tuple[str, ...] = ()
    polar: bool = False

    @property
    def cells(self) -> list[tuple[float, ...]]:
        """Each cell's values on the axes, row-major (the first axis slowest)."""
        return list(itertools.product(*(a.values for a in self.axes)))

    @property
    def runs(self) -> int:
        """Runs of the whole envelope."""
        return len(self.cells) * self.runs_per_cell

    def identity(self) -> dict:
        """What must not change for its folder to be resumed (campaign.json's ``envelope``)."""
        return {"format": ENVELOPE_FORMAT, "axes": [a.to_dict() for a in self.axes],
                "runs_per_cell": self.runs_per_cell, "hold": list(self.hold)}


@dataclasses.dataclass(frozen=True)
class EnvelopeResult:
    """What :func:`run_envelope` did.

    Attributes
    ----------
    folder : Path
    runs, recorded, flown, invalid : int
        Runs of the envelope, recorded in runs.csv now, flown by this call,
        recorded by this call as invalid draws.
    elapsed : float
        Wall time of this call's runs, s.
    envelope : dict or None
        envelope.json, once every run is recorded.
    """

    folder: Path
    runs: int
    recorded: int
    flown: int
    elapsed: float
    envelope: dict | None
    invalid: int = 0

    @property
    def complete(self) -> bool:
        """Every run is recorded."""
        return self.recorded == self.runs


def envelope_header(env: Envelope) -> list[str]:
    """The columns of an envelope's runs.csv."""
    return ["index", "cell", *(f"axis.{a.name}" for a in env.axes), "seed", "status",
            "success", *env.spec.columns(), *(m.name for m in kind_of(env.base.model).metrics),
            "message"]


def plan_envelope(scenario, overrides, axes: Sequence[str], runs_per_cell: int | None,
                  hold: Sequence[str] = (), polar: bool = False) -> Envelope:
    """Check an envelope's scenario, axes and cells; nothing is flown or written.

    Raises
    ------
    ScenarioError, CampaignError
        One line: a bad scenario or campaign table, an axis that is not
        ``KEY=LO:HI:N`` of a numeric key, not two axes, a cell whose scenario
        is refused (the message names the cell).
    """
    base = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    spec = campaign_spec_of(base)
    if len(axes) != 2:
        raise CampaignError(f"axis: an envelope has two axes (--axis KEY=LO:HI:N twice), "
                            f"got {len(axes)}")
    parsed = tuple(parse_axis(a, base.data, base.model) for a in axes)
    if parsed[0].name == parsed[1].name or (
            parsed[0].key == parsed[1].key and parsed[0].element == parsed[1].element
            and not (parsed[0].derived and parsed[1].derived)):
        raise CampaignError(f"axis: both axes set {parsed[0].name}")
    if any(a.derived for a in parsed) and any(
            a.key == "wind.mean" and a.element in (0, 1) for a in parsed):
        raise CampaignError("axis: the wind over the deck sets wind.mean[0] and wind.mean[1] "
                            "itself; choose one or the other")
    k = spec.runs if runs_per_cell is None else runs_per_cell
    if isinstance(k, bool) or not isinstance(k, int) or not 1 <= k <= MAX_RUNS_PER_CELL:
        raise CampaignError(f"runs_per_cell: must be in [1, {MAX_RUNS_PER_CELL}], got {k}")
    drawn = {t.key for d in spec.dispersions for t in d.targets}
    for key in hold:
        if key not in drawn:
            raise CampaignError(f"hold: {key} is not dispersed by the scenario's [campaign]")
    if polar and sum(a.angle for a in parsed) != 1:
        raise CampaignError("polar: needs exactly one axis of angles in degrees (a key "
                            "ending in _deg) as the map's angle")
    env = Envelope(dataclasses.replace(base, campaign_table=spec.table), spec, parsed, k,
                   tuple(hold), polar or _over_deck_pair(parsed))
    if env.runs > MAX_RUNS:
        raise CampaignError(f"runs_per_cell: {len(env.cells)} cells of {k} runs make "
                            f"{env.runs} runs, over the {MAX_RUNS} a campaign may fly")
    # every cell's nominal scenario is valid: checked as far as the cell changes it
    # (``dispersed``: the refusal ``replace`` gives, a tenth of its time; 400 cells 0.6 s)
    for cell in env.cells:
        try:
            dispersed(base, apply_cell({}, parsed, cell, base.data, spec, env.hold))
        except ScenarioError as exc:
            where = ", ".join(f"{a.name} = {v:g}" for a, v in zip(parsed, cell, strict=True))
            raise CampaignError(f"axis: the cell {where} is no valid scenario: {exc}") \
                from None
    return env


def _over_deck_pair(axes: Sequence[Axis]) -> bool:
    return all(a.derived for a in axes)


def cell_draws(env: Envelope, indices: Sequence[int]) -> Iterator[RunDraw]:
    """Each run's draw: its replicate's campaign draw, the cell's values in place."""
    k = env.runs_per_cell
    replicates = draws(env.spec, range(k), k)
    cells = env.cells
    for g in indices:
        c, r = divmod(g, k)
        d = replicates[r]
        values = apply_cell(d.values, env.axes, cells[c], env.base.data, env.spec, env.hold)
        columns = {"cell": str(c), **{f"axis.{a.name}": format_value(
            int(v) if a.integer else v) for a, v in zip(env.axes, cells[c], strict=True)},
            **d.columns}
        for disp in env.spec.dispersions:       # the values flown, not those drawn
            for t in disp.targets if disp.distribution not in ("seed", "choice") else ():
                value = values[t.key]
                columns.update(zip(t.columns(), map(format_value, [value] if t.scalar
                                                    else value), strict=True))
        yield RunDraw(g, d.seed, values, columns)


def flight_order(env: Envelope, indices: Sequence[int]) -> list[int]:
    """The runs ``indices`` in the order they fly: replicate by replicate (replicate 0 of
    every cell, then 1, ...), cells in order within each: consecutive runs, and the
    chunks of them a worker is sent, share their replicate's draws.

    Examples
    --------
    >>> env = Envelope(None, None, (), 3)
    >>> flight_order(env, range(9))
    [0, 3, 6, 1, 4, 7, 2, 5, 8]
    """
    k = env.runs_per_cell
    return sorted(indices, key=lambda g: (g % k, g // k))


def run_envelope(scenario, overrides=None, axes: Sequence[str] = (),
                 runs_per_cell: int | None = None, out=None, workers: int | None = None,
                 scheduler: str | None = None, hold: Sequence[str] = (), polar: bool = False,
                 progress: bool = False, plots: bool = True) -> EnvelopeResult:
    """Fly an envelope, or the runs of it that its folder does not hold yet.

    Parameters
    ----------
    scenario : str, Path or Scenario
        With a ``[campaign]`` table: its dispersions fly in every cell.
    overrides : list of str, optional
        Scenario overrides (``campaign.seed=3`` too).
    axes : sequence of str
        Two ``KEY=LO:HI:N``.
    runs_per_cell : int, optional
        Default: ``campaign.runs``.
    out : path-like, optional
        The folder (default a new ``<scenario>-envelope-<stamp>``).
    workers, scheduler, progress, plots
        As :func:`quadland.campaign.run_campaign`'s.
    hold : sequence of str
        Dispersed keys held at the scenario's value in every run.
    polar : bool
        Draw a polar map (automatic for the wind over the deck's two axes).

    Returns
    -------
    EnvelopeResult

    Raises
    ------
    ScenarioError, CampaignError
        Before anything is written: bad input, a folder of something else.
    CampaignStopped
        A worker or the scheduler was lost; the recorded runs stay.
    CampaignInterrupted
        Ctrl-C; the recorded runs stay and the same command resumes.
    """
    env = plan_envelope(scenario, overrides, list(axes), runs_per_cell, hold, polar)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or not 1 <= workers <= MAX_WORKERS):
        raise CampaignError(f"workers: must be in [1, {MAX_WORKERS}], got {workers}")
    kind_of(env.base).check(env.base)
    if scheduler is not None:
        check_address(scheduler)
        local = 0
    else:
        local = local_workers(env.base, workers, env.runs, kept=KEEP_BYTES)
    header = envelope_header(env)
    manifest = dict(campaign_manifest(env.base, env.spec, env.runs), envelope=env.identity())
    path = None if out is None else Path(out).absolute()
    if path is not None:
        _check_envelope_folder(CampaignFolder(path), manifest, header)
    with contextlib.ExitStack() as stack:
        connection = None
        if scheduler is not None:
            stack.enter_context(quiet_cluster_logs())
            connection = connect(scheduler)
            stack.callback(disconnect, connection)
        return _fly(env, header, manifest, path, connection, local, scheduler, progress,
                    plots)


def _check_envelope_folder(folder: CampaignFolder, manifest: dict, header) -> dict:
    """The runs a folder of this envelope holds; refuse one of another envelope or campaign."""
    folder.check()
    old = folder.manifest()
    if old is not None and old.get("envelope") != manifest["envelope"]:
        what = "a campaign" if "envelope" not in old else \
            "another envelope (other axes, runs per cell or held keys)"
        raise CampaignError(f"out: {folder.path} holds {what}; choose a new folder or run "
                            "what it holds")
    return check_folder(folder, manifest, header)


def _batches(env, todo, connection, local, pending):
    if connection is not None:
        return dask_runs(connection, env.base, todo, env.spec.limits, KEEP_BYTES)
    if local == 1 or len(pending) <= 1:
        return serial_runs(env.base, todo, env.spec.limits, KEEP_BYTES)
    workers = min(local, len(pending))
    return pool_runs(env.base, todo, workers, env.spec.limits,
                     chunk_size(len(pending), workers), KEEP_BYTES)


def _fly(env, header, manifest, path, connection, local, scheduler, progress, plots
         ) -> EnvelopeResult:
    """:func:`run_envelope` once every check has passed: build, claim, fly, count."""
    warm_up(env.base)
    folder = (CampaignFolder(path).claim() if path is not None
              else new_folder(env.base.name, "envelope"))
    with folder:
        rows = _check_envelope_folder(folder, manifest, header)
        folder.start(manifest, header, {"scenario.toml": env.base.to_toml().encode("utf-8")})
        pending = flight_order(env, [g for g in range(env.runs) if g not in rows])
        bar = _progress_bar(progress, env.runs, len(rows))
        start, flown, invalid = time.perf_counter(), 0, 0
        try:
            batches = _batches(env, cell_draws(env, pending), connection, local, pending)
            try:
                for batch in batches:
                    _recorded(folder.append([_row(o, header) for o in batch]), rows, bar)
                    invalid += sum(o.status == "invalid" for o in batch)
                    flown += sum(o.status != "invalid" for o in batch)
                    interrupt.check()
            finally:
                batches.close()
                KEPT.clear()                    # this process's (one worker: it flew them)
                _recorded(folder.sync(), rows, bar)   # every run written: recorded
        except KeyboardInterrupt:
            raise CampaignInterrupted(folder.path, len(rows), env.runs) from None
        except Exception as exc:
            # a Ctrl-C while ctypes converted a run's arguments (NumPy's ndpointer, in
            # Python) arrives as its ArgumentError: the same interrupt, the same message
            if not interrupt.wrapped_by_ctypes(exc):
                raise
            raise CampaignInterrupted(folder.path, len(rows), env.runs) from None
        finally:
            if bar is not None:
                bar.close()
        elapsed = time.perf_counter() - start
        data = None
        if len(rows) == env.runs:
            ordered = [rows[g] for g in range(env.runs)]
            session = {"runs_flown": flown, "invalid_draws": invalid, "wall_s": elapsed,
                       "runs_per_s": flown / elapsed if flown and elapsed > 0 else None,
                       "where": scheduler or f"{max(local, 1)} local process(es)"}
            data, files = envelope_files(env, header, ordered, session, plots)
            folder.finish(header, ordered, files)
        return EnvelopeResult(folder.path, env.runs, len(rows), flown, elapsed, data, invalid)


def _recorded(durable, rows: dict, bar) -> None:
    """Count the runs the journal made durable: in ``rows`` (by index) and the bar."""
    rows.update((int(r[0]), r) for r in durable)
    if bar is not None and durable:
        bar.update(len(durable))


def _row(outcome, header: Sequence[str]) -> list[str]:
    texts = {"index": str(outcome.index), "seed": str(outcome.seed), "status": outcome.status,
             "success": "true" if outcome.success else "false", "message": outcome.message,
             **outcome.columns}
    for name, value in outcome.metrics.items():
        texts[name] = "" if value is None else format_value(value)
    return [texts.get(name, "") for name in header]


def _progress_bar(show: bool, total: int, done: int):
    if not show:
        return None
    import sys

    from tqdm import tqdm

    return tqdm(total=total, initial=done, unit="run", file=sys.stderr, dynamic_ncols=True,
                desc="envelope", smoothing=0.1)



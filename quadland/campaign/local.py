"""A campaign's runs in this process or in a pool of local processes.

One worker flies in this process (:func:`serial_runs`); more are processes
of the ``forkserver`` (no fork of a process that holds threads; CasADi
objects are built per process, never shared between threads), each fed
through its own pipe at most :data:`AHEAD` runs ahead (:func:`pool_runs`).
:func:`local_workers` bounds their number by the cores, the runs and the
memory available.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import multiprocessing.connection
import os
import signal
import threading
import warnings
from collections.abc import Iterable, Iterator, Mapping

from quadland.campaign.fly import RunOutcome, fly
from quadland.campaign.sampling import RunDraw
from quadland.engine.heap import keep_freed_memory
from quadland.exceptions import CampaignError, CampaignStopped
from quadland.kinds import kind_of
from quadland.scenario import Scenario

__all__ = ["MAX_WORKERS", "WORKER_MEMORY", "AHEAD", "CHUNK", "RunQueue", "available_memory",
           "worker_memory", "local_workers", "serial_runs", "pool_runs", "chunk_size",
           "start_pool_server"]

#: Most local worker processes one campaign may ask for.
MAX_WORKERS = 1024


#: Memory of one local worker process with its simulator loaded, before the
#: arrays of its run, bytes. Measured on the shipped landing campaigns: 70 MiB
#: of its own (USS), 120 MiB resident (RSS, with the pages it shares with the
#: forkserver); the paper's, 20 and 55 MiB (docs/campaign.md).
WORKER_MEMORY = 128 * 2**20


#: Runs queued ahead on each local worker process or Dask thread.
AHEAD = 4

#: Most runs a local worker process flies per message (:func:`chunk_size`).
CHUNK = 8


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


def worker_memory(base: Scenario, kept: int = 0) -> int:
    """Memory one local worker process of a campaign of ``base`` takes, bytes (estimate).

    :data:`WORKER_MEMORY` (a process with the simulator loaded) plus the
    arrays of one run (its kind's ``plan``) and the ``kept`` bytes of draws it may keep
    for its next runs (an envelope's).
    """
    return WORKER_MEMORY + kind_of(base).plan(base).memory_bytes + kept


def local_workers(base: Scenario, workers: int | None, runs: int, kept: int = 0) -> int:
    """How many local processes fly a campaign of ``runs`` runs of ``base``.

    ``workers`` (default: one per core), no more than the runs, and no more
    than the available memory holds (:func:`worker_memory` each, with ``kept``): asked for
    explicitly, too many is refused; by default, fewer are started.

    Raises
    ------
    CampaignError
        ``workers: ...``: more than the memory holds, with what they would take.
    """
    wanted = min(workers or _cores(), runs)
    if wanted == 1:
        return 1                                # flies in this process
    each = worker_memory(base, kept)
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


class RunQueue:
    """The runs still to submit: ``pop()`` the next, truthy while one is left."""

    def __init__(self, todo: Iterator[RunDraw]):
        self._todo, self._next = todo, next(todo, None)

    def __bool__(self) -> bool:
        return self._next is not None

    def pop(self) -> RunDraw:
        item, self._next = self._next, next(self._todo, None)
        return item


def chunk_size(runs: int, workers: int) -> int:
    """Runs per message to a local worker: up to :data:`CHUNK`, so that every worker
    still gets at least :data:`AHEAD` messages' worth (the last ones balance the load).

    Examples
    --------
    >>> chunk_size(300, 2), chunk_size(40, 2), chunk_size(8, 2)
    (8, 5, 1)
    """
    return max(1, min(CHUNK, runs // max(1, workers * AHEAD)))


def serial_runs(base: Scenario, todo: Iterable[RunDraw], limits: Mapping[str, float],
                kept: int = 0) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` in this process, one run a batch (``kept``: :func:`fly`'s ``keep``)."""
    for draw in todo:
        yield [fly(base, draw, limits, kept)]


@dataclasses.dataclass(frozen=True)
class _Raised:
    """An exception a worker's run raised (not a run's outcome), sent to the campaign."""

    error: BaseException


def _worker_main(conn, lifeline, base: Scenario, limits: Mapping[str, float],
                 kept: int = 0) -> None:
    """A local worker process: fly the chunks of draws ``conn`` brings (lists), send back
    each chunk's outcomes (a list).

    Ctrl-C is the campaign's to handle: the worker ignores it (it starts with
    SIGINT blocked, inherited from the forkserver, :func:`_start_forkserver`;
    ignoring it discards one already pending). Warnings stay silent: the
    campaign's process has given each once, building the same simulator.
    ``lifeline`` is the read end of a pipe whose only write end the campaign's
    process holds: it reads end of file when that process ends, however it ends
    (a SIGKILL included), and the worker exits at once, even in the middle of a
    run.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    warnings.simplefilter("ignore")
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)                        # one BLAS thread per process
    keep_freed_memory()                         # each run's arrays in the last one's pages

    def watch():
        try:
            lifeline.recv()
        except (EOFError, OSError):
            pass
        os._exit(1)

    threading.Thread(target=watch, name="quadland-lifeline", daemon=True).start()
    while True:
        try:
            chunk = conn.recv()
        except (EOFError, OSError):
            return
        if chunk is None:
            return
        try:
            result = [fly(base, draw, limits, kept) for draw in chunk]
        except Exception as exc:                # a bug, or out of memory: the campaign's
            result = _Raised(exc)               # process raises it
        try:
            conn.send(result)
        except (OSError, ValueError):
            return
        except Exception as exc:                # an exception that does not pickle
            conn.send(_Raised(RuntimeError(f"{type(exc).__name__}: {exc}")))


def start_pool_server():
    """Start the ``forkserver`` the local workers are forked from (if it is not running),
    with this module preloaded; returns its multiprocessing context.

    The server imports its preload (0.2 s of CPU) in a process of its own: a campaign
    starts it as soon as it knows it flies on local processes, so that the import runs
    on another core while this process checks the folder and loads the simulator
    (:func:`pool_runs` then finds it running).
    """
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(["quadland.campaign.local",
                                    "quadland.campaign.forkserver_hook"])
    _start_forkserver()
    return context


def _start_forkserver() -> None:
    """Start the forkserver with SIGINT blocked, so that neither it nor a worker sees Ctrl-C.

    A Ctrl-C meant for the campaign reaches its whole process group: a
    forkserver still importing its preloaded modules, or a worker not yet
    running its first line, would print a traceback. The signal mask is
    inherited through fork and exec: the forkserver starts with SIGINT blocked,
    a Ctrl-C stays pending there until it ignores SIGINT itself (which discards
    it), and each worker inherits the mask until :func:`_worker_main` ignores it
    too. Only this thread's mask changes, never the process's disposition: a
    Ctrl-C arriving meanwhile is taken by another thread of this process (a
    BLAS thread) and raised here as usual. (Ignoring SIGINT for the start
    instead lost such a Ctrl-C: with the disposition SIG_IGN the kernel discards
    it in a thread that does not block it.)
    """
    from multiprocessing import forkserver, resource_tracker

    resource_tracker.ensure_running()           # it unblocks SIGINT itself when it starts
    if threading.current_thread() is not threading.main_thread():
        forkserver.ensure_running()
        return
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        forkserver.ensure_running()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


class _Worker:
    """A local worker process, its end of the pipe and the runs sent to it."""

    def __init__(self, context, lifeline, base: Scenario, limits: Mapping[str, float],
                 kept: int = 0):
        self.conn, theirs = context.Pipe()
        self.process = context.Process(target=_worker_main, name="quadland-campaign-worker",
                                       args=(theirs, lifeline, base, limits, kept), daemon=True)
        self.process.start()
        theirs.close()
        self.busy = 0

    def send(self, queue: RunQueue, chunk: int) -> None:
        """Send the next ``chunk`` runs of ``queue`` (fewer at its end) as one message."""
        draws = [queue.pop()]
        while queue and len(draws) < chunk:
            draws.append(queue.pop())
        self.conn.send(draws)
        self.busy += 1


def pool_runs(base: Scenario, todo: Iterator[RunDraw], workers: int,
              limits: Mapping[str, float], chunk: int = 1, kept: int = 0
              ) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on ``workers`` local processes; yield outcomes as they finish.

    Each worker is a process of the ``forkserver`` (no fork of a process
    that holds threads), started once with the scenario, and fed through its
    own pipe chunks of ``chunk`` runs (:func:`chunk_size`), at most
    :data:`AHEAD` chunks ahead; a chunk's outcomes come back together. Only
    pipes connect them: no semaphore that a SIGKILLed campaign would leave to
    the resource tracker. ``kept``: bytes of draws each worker may keep for its next
    runs (:func:`fly`'s ``keep``).
    """
    context = start_pool_server()
    lifeline, keep = context.Pipe(duplex=False)
    pool: list[_Worker] = []
    try:
        for _ in range(workers):
            pool.append(_Worker(context, lifeline, base, limits, kept))
        lifeline.close()
        # the first draws (SciPy's import, 0.5 s) while the workers start, not before
        queue = RunQueue(todo)
        for worker in pool:
            while queue and worker.busy < AHEAD:
                worker.send(queue, chunk)
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
                outcomes.extend(result)
                try:
                    while queue and worker.busy < AHEAD:
                        worker.send(queue, chunk)
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

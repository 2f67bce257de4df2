"""A campaign's runs on a ``dask.distributed`` cluster.

:func:`check_address` refuses a malformed address; :func:`connect` refuses,
within seconds, an address where nothing listens or where what listens is
no Dask scheduler, then checks that the workers run this quadland;
:func:`dask_runs` flies the runs and stops the campaign
(:class:`~quadland.exceptions.CampaignStopped`) when the cluster loses a run,
its scheduler, or every worker for too long. :func:`quiet_cluster_logs`
keeps the cluster's libraries from logging beside the campaign's one line.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import threading
import time
from collections.abc import Iterator, Mapping

from quadland.campaign.fly import RunOutcome, fly, warm_up
from quadland.campaign.local import AHEAD, RunQueue
from quadland.campaign.resume import code_fingerprint
from quadland.campaign.sampling import RunDraw
from quadland.engine.kept import forget
from quadland.exceptions import CampaignError, CampaignStopped
from quadland.scenario import Scenario

__all__ = ["SCHEDULER_TIMEOUT_S", "NO_WORKER_GRACE_S", "check_address", "connect",
           "disconnect", "dask_runs", "quiet_cluster_logs"]

#: Longest wait for a Dask scheduler's handshake, s (its client gets twice that to connect).
SCHEDULER_TIMEOUT_S = 5.0


#: How long a Dask cluster may be left without a worker before the campaign stops, s.
NO_WORKER_GRACE_S = 20.0


def check_address(address) -> None:
    """Refuse, in one line, a scheduler address that is not ``[tcp://]HOST:PORT``.

    Only plain TCP: a ``tls://`` scheduler needs a security context (certificates)
    and ``ucx://`` a transport that quadland does not configure, so both would
    fail inside ``distributed`` after a long wait. ``HOST`` is a bracketed IP
    address or a DNS name of labels of 1 to 63 letters, digits or hyphens.
    """
    import re

    from quadland.scenario import toml_value

    text = str(address)
    scheme, sep, _ = text.partition("://")
    if sep and scheme != "tcp":
        raise CampaignError(f"scheduler: only tcp:// schedulers are supported (tls and ucx "
                            f"need security contexts or transports quadland does not "
                            f"configure), got {toml_value(text)[:80]}")
    match = re.fullmatch(r"(?:tcp://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):([0-9]{1,5})",
                         text)
    host = match.group(1) if match else ""
    labels_ok = host.startswith("[") or (
        len(host) <= 253 and all(1 <= len(label) <= 63 for label in host.split(".")))
    if match is None or not labels_ok or not 1 <= int(match.group(2)) <= 65535:
        raise CampaignError(f"scheduler: expected tcp://HOST:PORT (or HOST:PORT), "
                            f"got {toml_value(text)[:80]}")


def connect(address: str):
    """A ``distributed.Client`` of the scheduler at ``address``, with the workers checked."""
    try:
        from distributed import Client
    except ImportError:
        raise CampaignError("scheduler: needs the dask.distributed package "
                            "(pip install 'quadland[cluster]')") from None
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
        disconnect(client)
        raise CampaignError(f"scheduler: {address} has no worker ({exc})") from None
    except BaseException:
        disconnect(client)
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
    except UnicodeError:
        raise CampaignError(f"scheduler: cannot connect to {address}: the host name is not "
                            "a valid DNS name") from None
    except OSError as exc:
        raise CampaignError(f"scheduler: cannot connect to {address}: "
                            f"{exc.strerror or exc}") from None


def disconnect(client) -> None:
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


def _prepare(client, base: Scenario):
    """Each worker's simulator built or loaded, and ``base`` on every worker: the cluster's
    threads and the scenario's future."""
    try:
        client.run(warm_up, base)
        threads = sum(client.nthreads().values())
        return threads, client.scatter(base, broadcast=True, hash=False)
    except Exception as exc:
        if not _cluster_error(exc):
            raise
        raise _stopped(f"the cluster failed while preparing its workers "
                       f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]})") from None


def dask_runs(client, base: Scenario, todo: Iterator[RunDraw], limits: Mapping[str, float],
              kept: int = 0) -> Iterator[list[RunOutcome]]:
    """Fly ``todo`` on the cluster's workers; yield outcomes as they finish.

    A run lost with its worker is flown again by another (Dask reschedules it); the
    campaign stops (:class:`CampaignStopped`) when a run fails for the cluster's sake (a
    worker killed while flying it too often), when the scheduler is lost, or when no
    worker is left for :data:`NO_WORKER_GRACE_S` seconds. ``kept``: bytes of draws each
    worker process may keep for its next runs (``fly``'s ``keep``, its threads sharing).
    """
    from distributed import as_completed

    pending = None
    try:
        threads, base_future = _prepare(client, base)
        queue = RunQueue(todo)
        pending = as_completed(loop=client.loop)

        def submit(k):
            for _ in range(k):
                if queue:
                    pending.add(client.submit(fly, base_future, queue.pop(), limits, kept,
                                              pure=False))

        submit(AHEAD * max(threads, 1))
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
        if kept:
            _forget_kept(client)


def _forget_kept(client) -> None:
    """The draws the cluster's workers kept for an envelope's runs, given up."""
    if client.status == "running":
        try:
            client.run(forget)
        except Exception:                       # a worker or the scheduler is gone
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

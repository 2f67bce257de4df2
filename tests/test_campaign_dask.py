"""Campaigns on a real dask.distributed cluster that loses its worker or its scheduler.

A scheduler and a worker are started as processes on 127.0.0.1 (the
loopback interface only, random free ports), as a user would start them,
and killed with SIGKILL in the middle of a campaign. The campaign must stop
with exit status 4 and one line, keep every finished run, and the same
command must finish it (on the cluster once a worker is back, or locally)
with the runs.csv of an uninterrupted campaign, byte for byte.
"""

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from quadland.campaign.execute import run_campaign

pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[1]
#: Short paper runs: about 1 ms of CPU each, so that a campaign is mid-way for seconds.
FAST = ["simulation.duration=1.0"]
RUNS = 400


def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")]).rstrip(
        os.pathsep)
    return env


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_listening(port: int, proc, timeout: float = 60.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        assert proc.poll() is None, proc.communicate()
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
            return
        except OSError:
            time.sleep(0.1)
    raise AssertionError(f"nothing listens on port {port}")


def _scheduler(port: int):
    proc = subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1",
                             "--port", str(port), "--no-dashboard"], env=_env(),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _wait_listening(port, proc)
    return proc


def _worker(port: int):
    """One worker process (no nanny: SIGKILL ends it), one thread."""
    return subprocess.Popen([sys.executable, "-m", "dask", "worker", f"tcp://127.0.0.1:{port}",
                             "--host", "127.0.0.1", "--nthreads", "1", "--no-nanny",
                             "--no-dashboard"], env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def _campaign(out, *flags):
    return subprocess.Popen([sys.executable, "-m", "quadland", "campaign", "--runs", str(RUNS),
                             "--out", str(out), "--no-plots", *(f for x in FAST
                                                                for f in ("--set", x)),
                             *flags], env=_env(), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _rows(out) -> int:
    path = out / "runs.csv"
    return path.read_bytes().count(b"\n") - 1 if path.exists() else 0


def _wait_rows(out, at_least: int, proc, timeout: float = 120.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if _rows(out) >= at_least:
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.005)
    raise AssertionError("the campaign recorded too few runs in time")


def _kill(proc) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=30)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = tmp_path_factory.mktemp("ref") / "campaign"
    result = run_campaign("paper", FAST, runs=RUNS, out=out, workers=1, plots=False)
    assert result.complete
    return (out / "runs.csv").read_bytes()


@pytest.mark.slow
def test_a_lost_worker_or_scheduler_stops_with_status_4_and_resumes(reference, tmp_path):
    port = _free_port()
    scheduler = _scheduler(port)
    workers = [_worker(port)]
    address = f"tcp://127.0.0.1:{port}"
    try:
        # the worker is killed mid-campaign: exit 4, one line, the finished runs kept
        out = tmp_path / "worker"
        proc = _campaign(out, "--scheduler", address)
        _wait_rows(out, 20, proc)
        _kill(workers[0])
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 4, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("quadland: error: the cluster"), err
        assert "run the same command to resume" in lines[0]
        kept = _rows(out)
        assert 20 <= kept < RUNS and not (out / "summary.json").exists()
        # a worker is back: the same command flies the rest, as if never stopped
        workers.append(_worker(port))
        proc = _campaign(out, "--scheduler", address)
        text, err = proc.communicate(timeout=300)
        assert proc.returncode == 0, err
        assert f"flew {RUNS - kept} runs" in text
        assert (out / "runs.csv").read_bytes() == reference

        # the scheduler is killed mid-campaign: exit 4, one line; resumed here, locally
        out = tmp_path / "scheduler"
        proc = _campaign(out, "--scheduler", address)
        _wait_rows(out, 20, proc)
        _kill(scheduler)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 4, err
        assert err.strip().splitlines() == ["quadland: error: the cluster's scheduler was lost; "
                                            "the finished runs are recorded: run the same "
                                            "command to resume"]
        proc = _campaign(out, "--workers", "1")
        _, err = proc.communicate(timeout=300)
        assert proc.returncode == 0, err
        assert (out / "runs.csv").read_bytes() == reference
    finally:
        for p in (*workers, scheduler):
            _kill(p)


@pytest.mark.slow
def test_a_bad_or_unreachable_scheduler_is_one_line_and_creates_nothing(tmp_path):
    # V13: "foo" gave the right line, then a 30 s hang and a traceback from
    # Client.__del__; V16: the refused campaign had created the parents of --out
    closed = _free_port()                      # nothing listens there
    for address, message in [
            ("foo", 'quadland: error: --scheduler: expected tcp://HOST:PORT (or HOST:PORT), '
                    'got "foo"'),
            ("tcp://127.0.0.1:99999", "quadland: error: --scheduler: expected tcp://HOST:PORT"),
            # a host name no DNS name can be: an empty label, a label over 63 characters
            ("tcp://a..b:1", 'quadland: error: --scheduler: expected tcp://HOST:PORT (or '
                             'HOST:PORT), got "tcp://a..b:1"'),
            (f"tcp://{'a' * 300}:1", "quadland: error: --scheduler: expected tcp://HOST:PORT"),
            # tls and ucx failed inside distributed after 20 s, with Client.__del__'s traceback
            ("tls://127.0.0.1:8799", "quadland: error: --scheduler: only tcp:// schedulers are "
                                     "supported (tls and ucx need security contexts"),
            ("ucx://127.0.0.1:8799", "quadland: error: --scheduler: only tcp:// schedulers"),
            (f"tcp://127.0.0.1:{closed}", f"quadland: error: --scheduler: cannot connect to "
                                          f"tcp://127.0.0.1:{closed}: Connection refused")]:
        out = tmp_path / "a" / "b" / "c"
        proc = _campaign(out, "--scheduler", address)
        text, err = proc.communicate(timeout=120)
        assert proc.returncode == 2, err
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(message), err
        assert text == "" and os.listdir(tmp_path) == []


def _serve(kind: str):
    """A TCP server on the loopback that is no Dask scheduler: silent, HTTP or an echo."""
    import http.server
    import socketserver
    import threading

    class Silent(socketserver.BaseRequestHandler):
        def handle(self):
            time.sleep(30)

    class Echo(socketserver.BaseRequestHandler):
        def handle(self):
            while data := self.request.recv(65536):
                self.request.sendall(data)

    handler = {"silent": Silent, "echo": Echo,
               "http": http.server.SimpleHTTPRequestHandler}[kind]
    server = socketserver.ThreadingTCPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


@pytest.mark.parametrize("kind, why", [
    ("silent", "no answer within 5 s"),
    ("http", None),
    ("echo", "its answer is not a scheduler's"),
])
@pytest.mark.slow
def test_a_listener_that_is_no_scheduler_is_one_line_within_seconds(tmp_path, kind, why):
    # D6: something listening that is not a Dask scheduler held the campaign forever (the
    # client waits for the handshake without a bound); an echo answered the handshake and
    # gave an AssertionError traceback and a 30 s wait in Client.__del__ (D7: beside lines
    # of distributed's and tornado's)
    server = _serve(kind)
    address = f"tcp://127.0.0.1:{server.server_address[1]}"
    try:
        out = tmp_path / "a" / "b"
        start = time.monotonic()
        proc = _campaign(out, "--scheduler", address)
        text, err = proc.communicate(timeout=120)
        took = time.monotonic() - start
    finally:
        server.shutdown()
        server.server_close()
    assert proc.returncode == 2, err
    lines = err.splitlines()
    prefix = f"quadland: error: --scheduler: {address} does not answer as a Dask scheduler: "
    assert len(lines) == 1 and lines[0].startswith(prefix), err
    if why is not None:
        assert lines[0] == prefix + why
    assert text == "" and os.listdir(tmp_path) == [] and took < 30


def test_the_cluster_s_loggers_are_silent_meanwhile_and_restored(capfd):
    import logging

    from quadland.campaign.cluster import quiet_cluster_logs

    names = ("distributed.client", "distributed.comm.tcp", "tornado.application",
             "tornado.general", "asyncio")
    levels = {n: logging.getLogger(n).level for n in names}
    with quiet_cluster_logs():
        for name in names:
            logging.getLogger(name).critical("lost the scheduler")
    assert capfd.readouterr().err == ""
    assert {n: logging.getLogger(n).level for n in names} == levels

"""Campaigns end to end: reproducible runs, nothing lost, refusals, summary, Dask.

Short paper runs (0.5 s of flight, about 2 ms each) keep the file under a minute.
"""

import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from ctypes_interrupt import ctrl_c_wrapped_by_ctypes

from quadland.campaign.execute import campaign_header, run_campaign
from quadland.campaign.spec import campaign_spec_of
from quadland.campaign.statistics import clopper_pearson, lower_confidence_bound
from quadland.cli import main
from quadland.exceptions import CampaignError
from quadland.scenario import SCENARIO_DIR, load_scenario

FAST = ["simulation.duration=0.5"]
RUNS = 24
PAPER = (SCENARIO_DIR / "paper.toml").read_text().split("\n[campaign]")[0]


def _rows(folder):
    with open(folder / "runs.csv", newline="") as fh:
        return list(csv.reader(fh))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted campaign flown in this process."""
    out = tmp_path_factory.mktemp("ref") / "campaign"
    result = run_campaign("paper", FAST, runs=RUNS, out=out, workers=1)
    assert result.complete and result.flown == RUNS
    return out


@pytest.mark.slow
def test_worker_count_and_order_do_not_change_a_run(reference, tmp_path):
    out = tmp_path / "two"
    run_campaign("paper", FAST, runs=RUNS, out=out, workers=2)
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()
    # a campaign grown from 10 runs to 24 (the first 10 recorded before) is the same too
    grown = tmp_path / "grown"
    first = run_campaign("paper", FAST, runs=10, out=grown, workers=2)
    assert first.complete and first.flown == 10
    second = run_campaign("paper", FAST, runs=RUNS, out=grown, workers=1)
    assert second.flown == RUNS - 10
    assert (grown / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()
    again = run_campaign("paper", FAST, runs=RUNS, out=grown, workers=2)
    assert again.flown == 0 and again.complete


def test_files_and_summary_against_runs_csv(reference):
    names = sorted(p.name for p in reference.iterdir())
    assert names == ["campaign.json", "failures.png", "metrics_cdf.png", "runs.csv",
                     "scenario.toml", "summary.json"]
    rows = _rows(reference)
    header, body = rows[0], rows[1:]
    sc = load_scenario("paper", FAST)
    assert header == campaign_header(campaign_spec_of(sc), "paper")
    assert [int(r[0]) for r in body] == list(range(RUNS))
    summary = json.loads((reference / "summary.json").read_text())
    col = {name: [r[k] for r in body] for k, name in enumerate(header)}
    k = sum(s == "true" for s in col["success"])
    assert summary["successes"] == k and summary["flown"] == RUNS
    assert summary["confidence"]["interval"] == list(clopper_pearson(k, RUNS))
    assert summary["confidence"]["lower_bound_one_sided"] == lower_confidence_bound(k, RUNS)
    for name, entry in summary["metrics"].items():
        x = np.array([float(v) for v in col[name] if v != ""])
        if x.size == 0:
            assert entry["p50"] is None
            continue
        for label, q in (("p50", 50), ("p90", 90), ("p99", 99), ("max", 100)):
            assert entry[label] == np.percentile(x, q, method="inverted_cdf")
    # success means every limited metric within its limit
    for r in body:
        ok = all(col_v != "" and float(col_v) <= 1.5 for col_v in
                 (r[header.index(f"settling_time_{c}")] for c in ("phi_e", "theta_e", "psi_e")))
        assert (r[header.index("success")] == "true") == ok
    # the scenario written beside the runs repeats the campaign
    again = load_scenario(reference / "scenario.toml")
    assert again.data == sc.data and again.campaign_table == sc.campaign_table


def test_a_worst_run_replays_with_its_command(reference, tmp_path, capsys):
    summary = json.loads((reference / "summary.json").read_text())
    worst = summary["worst_runs"][0]
    import shlex

    words = shlex.split(worst["command"])
    assert words[:2] == ["quadland", "simulate"]
    assert main(words[1:] + ["--out", str(tmp_path / "replay"), "--no-plots"]) == 0
    run = json.loads((tmp_path / "replay" / "summary.json").read_text())
    for channel in ("phi_e", "theta_e", "psi_e"):
        assert run["errors"][channel]["settling_time"] == \
            worst["metrics"][f"settling_time_{channel}"]
    assert abs(run["errors"]["z_e"]["final"]) == worst["metrics"]["final_abs_z_e"]


def _copy(reference, tmp_path):
    out = tmp_path / "copy"
    shutil.copytree(reference, out)
    return out


def test_changed_scenario_dispersions_or_version_are_refused(reference, tmp_path):
    out = _copy(reference, tmp_path)
    with pytest.raises(CampaignError, match="the scenario changed: quadrotor.mass: 2.0 there, "
                                            "2.1 here"):
        run_campaign("paper", [*FAST, "quadrotor.mass=2.1"], runs=RUNS, out=out)
    with pytest.raises(CampaignError, match="campaign.seed: 20191121 there, 5 here"):
        run_campaign("paper", [*FAST, "campaign.seed=5"], runs=RUNS, out=out)
    path = tmp_path / "other.toml"
    path.write_text(PAPER + "\n[campaign]\nruns = 24\nseed = 20191121\n[campaign.dispersions]\n"
                    "\"quadrotor.mass\" = {distribution = \"normal\", std = 0.1}\n"
                    "[campaign.limits]\nsettling_time_phi_e = 1.5\n"
                    "settling_time_theta_e = 1.5\nsettling_time_psi_e = 1.5\n")
    with pytest.raises(CampaignError, match="the dispersions changed: "
                                            "campaign.dispersions.quadrotor.inertia"):
        run_campaign(path, FAST, runs=RUNS, out=out)
    with pytest.raises(CampaignError, match="--runs can only grow"):
        run_campaign("paper", FAST, runs=RUNS - 1, out=out)
    manifest = json.loads((out / "campaign.json").read_text())
    (out / "campaign.json").write_text(json.dumps({**manifest, "quadland": "0.0.1"}))
    with pytest.raises(CampaignError, match="quadland 0.0.1 made it, this is"):
        run_campaign("paper", FAST, runs=RUNS, out=out)
    (out / "campaign.json").write_text(json.dumps({**manifest, "code": "0" * 16}))
    with pytest.raises(CampaignError, match="source code changed"):
        run_campaign("paper", FAST, runs=RUNS, out=out)
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("mine")
    with pytest.raises(CampaignError, match="not a quadland campaign"):
        run_campaign("paper", FAST, runs=RUNS, out=foreign)
    assert (foreign / "notes.txt").read_text() == "mine" and len(list(foreign.iterdir())) == 1


@pytest.mark.slow
def test_numerical_failures_and_invalid_draws_are_rows(tmp_path, capsys):
    path = tmp_path / "rough.toml"
    path.write_text(PAPER + "\n[campaign]\nruns = 16\nseed = 3\n[campaign.dispersions]\n"
                    "\"controller.k1\" = {distribution = \"choice\", values = "
                    "[[3.0, 5.0, 10.0, 10.0], [1000.0, 1000.0, 1000.0, 1000.0]]}\n"
                    "\"quadrotor.mass\" = {distribution = \"normal\", std = 3.0}\n")
    out = tmp_path / "rough"
    assert main(["campaign", "--scenario", str(path), "--out", str(out), "--workers", "2",
                 "--set", "simulation.duration=0.5"]) == 0
    text = capsys.readouterr().out
    rows = _rows(out)
    header, body = rows[0], rows[1:]
    status = [r[header.index("status")] for r in body]
    assert {"ok", "failed", "invalid"} <= set(status)
    for r in body:
        message = r[header.index("message")]
        if r[header.index("status")] == "failed":
            assert message.startswith("flight failed at t = ") and \
                r[header.index("controller.k1")] == "[1000.0, 1000.0, 1000.0, 1000.0]"
        if r[header.index("status")] == "invalid":
            assert message.startswith("quadrotor.mass: must be in")
            assert float(r[header.index("quadrotor.mass")]) < 1e-3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["invalid"] == status.count("invalid")
    assert summary["numerical_failures"] == status.count("failed")
    assert summary["flown"] == 16 - status.count("invalid")
    invalid = status.count("invalid")           # the last line counts as summary.json does
    assert f"of {16 - invalid} runs within limits" in text
    assert f"; flew {16 - invalid} runs in " in text and \
        text.rstrip().endswith(f", {invalid} invalid draw{'s' if invalid > 1 else ''} recorded")
    assert summary["separation"]["parameter"] == "controller.k1"
    assert summary["worst_runs"][0]["status"] == "failed"


def _campaign_process(out, runs, duration=5.0):
    return subprocess.Popen(
        [sys.executable, "-m", "quadland", "campaign", "--runs", str(runs), "--out", str(out),
         "--workers", "2", "--no-plots", "--set", f"simulation.duration={duration}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for_rows(out, at_least, proc, timeout=60.0):
    path, end = out / "runs.csv", time.monotonic() + timeout
    while time.monotonic() < end:
        if path.exists() and path.read_bytes().count(b"\n") - 1 >= at_least:
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.005)
    raise AssertionError("the campaign recorded too few runs in time")


@pytest.mark.slow
def test_interrupt_and_sigkill_lose_nothing_recorded(tmp_path):
    import psutil

    runs = 300
    whole = tmp_path / "whole"
    run_campaign("paper", ["simulation.duration=5.0"], runs=runs, out=whole, workers=1,
                 plots=False)
    out = tmp_path / "stopped"
    # Ctrl-C: one line, status 130, the runs recorded so far kept
    proc = _campaign_process(out, runs)
    _wait_for_rows(out, 20, proc)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().startswith("quadland: interrupted: ") and len(err.strip().splitlines()) == 1
    assert "run the same command" in err and not (out / "summary.json").exists()
    # SIGKILL of the campaign's process: its workers leave by themselves
    proc = _campaign_process(out, runs)
    recorded = len(_rows(out)) - 1
    _wait_for_rows(out, recorded + 40, proc)
    children = psutil.Process(proc.pid).children(recursive=True)
    proc.kill()
    _, err = proc.communicate()                 # returns once every child closed stderr
    # V19: the pool's semaphores were left to the resource tracker, which warned
    assert err == "", err
    gone, alive = psutil.wait_procs(children, timeout=10)
    for p in alive:
        p.kill()
    assert not alive, "worker processes outlived the killed campaign"
    rows = _rows(out)
    assert 1 + recorded + 40 <= len(rows) < 1 + runs
    with open(out / "runs.csv", "ab") as fh:                 # a line cut short
        fh.write(b"299,123,ok,tr")
    proc = _campaign_process(out, runs)
    out_text, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert f"flew {runs - len(rows) + 1} runs" in out_text
    assert (out / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore")
def test_dask_cluster_gives_the_same_runs(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=50) as cluster:
        out = tmp_path / "dask"
        result = run_campaign("paper", FAST, runs=RUNS, out=out,
                              scheduler=cluster.scheduler_address)
        assert result.complete and result.flown == RUNS
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["last_session"]["where"].startswith("tcp://127.0.0.1:")


def test_command_line_errors_are_one_line(tmp_path, capsys):
    from quadland.scenario import SCENARIO_DIR

    # every shipped scenario has a [campaign] table: turning's file without it
    plain = tmp_path / "plain" / "turning.toml"
    plain.parent.mkdir()
    plain.write_text((SCENARIO_DIR / "turning.toml").read_text().split("\n[campaign]")[0])
    assert main(["campaign", "--scenario", str(plain), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    shipped = SCENARIO_DIR / "highway.toml"    # what an installed package holds
    assert shipped.is_file() and "\n[campaign]" in shipped.read_text()
    assert err == ["quadland: error: --scenario: turning has no [campaign] table (the "
                   f"shipped {shipped} has one)"]
    assert main(["campaign", "--runs", "0", "--out", str(tmp_path / "r")]) == 2
    assert capsys.readouterr().err.strip() == \
        "quadland: error: --runs: must be in [1, 1000000], got 0"
    assert main(["campaign", "--workers", "0", "--out", str(tmp_path / "w")]) == 2
    assert "--workers: must be in [1, 1024]" in capsys.readouterr().err
    assert not any((tmp_path / n).exists() for n in "trw")
    assert os.listdir(tmp_path) == ["plain"]


def test_campaign_md_lists_every_metric_and_its_unit():
    from pathlib import Path

    from quadland.kinds import KINDS

    text = (Path(__file__).resolve().parents[1] / "docs" / "campaign.md").read_text()
    for kind in KINDS.values():
        for m in kind.metrics:
            assert f"| `{m.name}` | {m.unit} |" in text, m.name


@pytest.mark.slow
def test_progress_bar_with_eta_on_a_terminal_only(tmp_path):
    import fcntl
    import pty
    import select
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 120, 0, 0))
    proc = subprocess.Popen(
        [sys.executable, "-m", "quadland", "campaign", "--runs", "40", "--workers", "1",
         "--out", str(tmp_path / "tty"), "--no-plots", "--set", "simulation.duration=0.5"],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=slave)
    os.close(slave)
    screen = b""
    while True:
        ready, _, _ = select.select([master], [], [], 0.5)
        if ready:
            try:
                data = os.read(master, 4096)
            except OSError:
                break
            if not data:
                break
            screen += data
        elif proc.poll() is not None:
            break
    os.close(master)
    assert proc.wait(timeout=60) == 0
    last = screen.replace(b"\r", b"\n").decode().split("\n")
    bar = [line for line in last if line.startswith("campaign:")]
    assert bar and "40/40" in bar[-1] and "<" in bar[-1] and "run/s" in bar[-1], bar
    assert b"campaign:" not in proc.stdout.read()


def _env(**extra):
    from pathlib import Path

    env = dict(os.environ, **extra)
    root = str(Path(__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join([root, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


@pytest.mark.slow
def test_workers_stay_silent_without_a_compiler(tmp_path):
    # V17: each worker printed a raw two-line QuadlandWarning beside the command's own line
    proc = subprocess.run(
        [sys.executable, "-m", "quadland", "campaign", "--runs", "8", "--workers", "2",
         "--out", str(tmp_path / "c"), "--no-plots", "--set", "simulation.duration=0.5"],
        env=_env(CC="", PATH="/nonexistent", XDG_CACHE_HOME=str(tmp_path / "x")),
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.splitlines() == ["quadland: warning: no C compiler found (set CC or "
                                        "install gcc): simulating on CasADi's virtual machine, "
                                        "several times slower"]


def _has_forkserver(pid: int) -> bool:
    """The process ``pid`` has started the forkserver of its workers."""
    import psutil

    try:
        children = psutil.Process(pid).children()
    except psutil.Error:
        return False
    for child in children:
        try:
            if "forkserver" in " ".join(child.cmdline()):
                return True
        except psutil.Error:                    # a compiler run that just ended
            pass
    return False


@pytest.mark.slow
def test_ctrl_c_at_any_moment_of_start_up_is_one_line(tmp_path):
    # V12: Ctrl-C (SIGINT to the whole process group, as a terminal sends it) while the
    # parser imported its modules, or while the forkserver preloaded them, printed 12 to 32
    # lines of traceback. The moments are seeded, spread from the command's first line
    # (once the quadland package is imported: Python's own start and that import are
    # before any of quadland's code can run) through the workers' start to the first runs.
    import random

    rng = random.Random(20261123)
    code = ("import sys\nfrom quadland.cli import main\nprint('ready', flush=True)\n"
            "sys.exit(main(sys.argv[1:]))\n")
    for trial in range(8):
        out = tmp_path / f"c{trial}"
        proc = subprocess.Popen(
            [sys.executable, "-c", code, "campaign", "--scenario", "ship", "--runs", "300",
             "--workers", "2", "--no-plots", "--out", str(out)], env=_env(),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
        assert proc.stdout.readline() == "ready\n"
        if trial % 2:                           # from the parser's imports to the first runs
            time.sleep(rng.uniform(0.0, 2.0))
        else:                                   # while the forkserver and its workers start
            while proc.poll() is None and not _has_forkserver(proc.pid):
                time.sleep(0.002)
            time.sleep(rng.uniform(0.0, 0.4))
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)  # once every process of the group is gone
        lines = err.strip().splitlines()
        # or -SIGINT, which a shell shows as 130 too: CPython 3.11 remembers a
        # KeyboardInterrupt that ended code run through PyRun_String (as some extension
        # modules do while they load), even when the command caught it, and then ends the
        # process by SIGINT (_Py_UnhandledKeyboardInterrupt)
        assert proc.returncode in (130, -signal.SIGINT) and len(lines) == 1, (trial, err)
        assert lines[0].startswith("quadland: interrupted"), (trial, err)


def test_a_ctrl_c_ctypes_wraps_in_a_run_keeps_the_runs_and_says_so(reference, tmp_path,
                                                                   monkeypatch, capsys):
    """A Ctrl-C while ctypes converts a call's arguments (NumPy's ``ndpointer`` checks them
    in Python; a serial campaign flies its runs in its own process) reaches the campaign as
    ``ctypes.ArgumentError("argument N: KeyboardInterrupt: ")``: the runs recorded stay,
    the line says how many and how to resume (it said only "interrupted"), and the resume
    ends on the uninterrupted campaign's bytes."""
    import quadland.campaign.execute as execute

    real = execute.serial_runs

    def cut_short(base, todo, limits, kept=0):
        for n, batch in enumerate(real(base, todo, limits, kept)):
            if n == 5:                          # five runs recorded, the sixth flown
                ctrl_c_wrapped_by_ctypes()
            yield batch

    monkeypatch.setattr(execute, "serial_runs", cut_short)
    out = tmp_path / "stopped"
    assert main(_argv(out)) == 130
    assert capsys.readouterr().err == (
        f"quadland: interrupted: 5 of {RUNS} runs recorded in {out}; run the same command "
        f"with --out {out} to fly the rest\n")
    assert len(_rows(out)) == 1 + 5 and not (out / "summary.json").exists()
    monkeypatch.setattr(execute, "serial_runs", real)
    assert main(_argv(out)) == 0
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()


def test_an_all_invalid_campaign_is_summarized(tmp_path, capsys):
    # V2: every run invalid crashed the summary (np.ptp of an empty array) and every resume
    # crashed again; V6: non-finite draws left nan in runs.csv with exit 0
    out = tmp_path / "r1"
    argv = ["campaign", "--scenario", "highway", "--runs", "2", "--workers", "1", "--out",
            str(out), "--set", 'campaign.dispersions={"quadrotor.mass"={distribution="normal",'
            'std=1e300}}']
    for resume in (False, True):
        assert main(argv) == 0
        captured = capsys.readouterr()
        assert captured.err == ""
        assert captured.out.startswith(f"quadland: wrote {out}: no run flown, the draws of all 2 "
                                       "were invalid")
        assert ("no run left to fly" in captured.out) == resume
    summary = json.loads((out / "summary.json").read_text())
    assert summary["flown"] == 0 and summary["invalid"] == 2
    assert summary["success_rate"] is None and summary["confidence"] is None
    assert summary["separation"] is None and summary["worst_runs"] == []
    assert summary["note"].startswith("no run was flown")
    assert sorted(p.name for p in out.iterdir()) == ["campaign.json", "runs.csv",
                                                     "scenario.toml", "summary.json"]
    rows = _rows(out)
    header = rows[0]
    for r in rows[1:]:
        assert r[header.index("status")] == "invalid"
        assert all(v not in ("nan", "inf", "-inf") for v in r)
        assert abs(float(r[header.index("quadrotor.mass")])) > 1e4
    # a draw that overflows is refused before anything is written
    bad = tmp_path / "r6"
    assert main(["campaign", "--scenario", "highway", "--runs", "2", "--workers", "1", "--out",
                 str(bad), "--set", 'campaign.dispersions={"initial.relative_velocity"='
                 '{distribution="normal",mode="relative",std=1e308}}']) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ['quadland: error: campaign.dispersions."initial.relative_velocity".std: the '
                   'draws overflow (they reach -inf to inf); use a smaller spread']
    assert not bad.exists()


@pytest.mark.parametrize("text, why", [
    ("[]", "an array, not a JSON object"),
    ("null", "null, not a JSON object"),
    ('"campaign"', "a string, not a JSON object"),
    ("{}", 'no "format"'),
    ("not json", "cannot be read (Expecting value"),
    ("[" * 100000 + "]" * 100000, "cannot be read"),
])
def test_a_damaged_manifest_is_one_line(reference, tmp_path, text, why):
    # V14: valid JSON that is not a manifest gave tracebacks, and null was taken for none:
    # the folder was resumed without its identity check
    out = _copy(reference, tmp_path)
    (out / "campaign.json").write_text(text)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    with pytest.raises(CampaignError) as info:
        run_campaign("paper", FAST, runs=RUNS, out=out)
    message = str(info.value)
    assert message.startswith(f"out: {out / 'campaign.json'} ") and why in message, message
    assert "\n" not in message
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before


@pytest.mark.parametrize("key, value, why", [
    ("runs", None, '"runs" is null'),
    ("runs", "24", '"runs" is a string'),
    ("runs", True, '"runs" is a boolean'),
    ("runs", 0, '"runs" is 0'),
    ("scenario", 5, '"scenario" is a number'),
    ("scenario", {"quadrotor": 5}, '"scenario.quadrotor" is a number'),
    ("campaign", [], '"campaign" is an array'),
    ("libraries", {"numpy": 2}, '"libraries" holds something else than versions'),
    ("code", None, '"code" is null'),
    ("quadland", None, '"quadland" is null'),
    ("format", None, "campaign format null"),
])
def test_a_manifest_with_a_damaged_entry_is_one_line(reference, tmp_path, capsys, key, value,
                                                      why):
    out = _copy(reference, tmp_path)
    manifest = json.loads((out / "campaign.json").read_text())
    manifest[key] = value
    (out / "campaign.json").write_text(json.dumps(manifest))
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["campaign", "--out", str(out), "--runs", str(RUNS), "--set",
                 "simulation.duration=0.5"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"quadland: error: --out: {out}") and \
        why in err[0], err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    del manifest[key]
    (out / "campaign.json").write_text(json.dumps(manifest))
    with pytest.raises(CampaignError, match=f"damaged \\(no \"{key}\"\\)"):
        run_campaign("paper", FAST, runs=RUNS, out=out)


def test_workers_are_bounded_by_memory(tmp_path, monkeypatch, capsys):
    # V21: --workers 1000 was accepted with no memory bound (about 120 MB each)
    from quadland.campaign import local
    from quadland.simulation import simulation_plan

    sc = load_scenario("highway")
    each = local.WORKER_MEMORY + simulation_plan(sc).memory_bytes
    assert local.worker_memory(sc) == each
    monkeypatch.setattr(local, "available_memory", lambda: 10 * each + each // 2)
    assert local.local_workers(sc, 10, 300) == 10
    assert local.local_workers(sc, 3, 2) == 2               # no more than the runs
    assert local.local_workers(sc, None, 300) == min(10, local._cores())
    monkeypatch.setattr(local, "_cores", lambda: 64)
    assert local.local_workers(sc, None, 300) == 10          # the default fits the memory
    assert local.local_workers(sc, 1, 300) == 1              # in this process: no new one
    with pytest.raises(CampaignError, match=r"workers: 11 local processes need about "
                                            r"[0-9.]+ GiB \(about [0-9]+ MiB each\), over the "
                                            r"[0-9.]+ GiB of memory available; use --workers 10 "
                                            r"or fewer"):
        local.local_workers(sc, 11, 300)
    out = tmp_path / "a" / "w"
    assert main(["campaign", "--scenario", "highway", "--workers", "1000", "--out",
                 str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("quadland: error: --workers: 300 local "
                                               "processes (of the 1000 asked: one per run) "
                                               "need about"), err
    assert os.listdir(tmp_path) == []                          # V16: nothing created


# --- a second review of the commands (issue 16: D8, D9, D10, D14, D16) ----------------

def _bytes(folder):
    return {p.name: (p.is_symlink(), p.read_bytes() if p.is_file() and not p.is_symlink()
                     else None) for p in folder.iterdir()}


def _one_error(capsys, status, argv):
    assert main(argv) == status
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1, captured.err
    return err[0]


def _argv(out, *extra, runs=RUNS):
    return ["campaign", "--out", str(out), "--runs", str(runs), "--workers", "1",
            "--set", "simulation.duration=0.5", *extra]


def test_a_summary_that_is_no_file_is_refused_before_any_run(reference, tmp_path, capsys):
    # a summary.json that is a folder let the resume fly every remaining run, then stop
    # with exit 4 and advice to run it again, forever
    out = _copy(reference, tmp_path)
    (out / "summary.json").unlink()
    (out / "summary.json").mkdir()
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    line = _one_error(capsys, 2, _argv(out))
    assert line == (f"quadland: error: --out: {out / 'summary.json'} is not a regular file "
                    "(a folder); it cannot be resumed: choose a new folder")
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


def test_a_refused_resume_changes_no_byte_of_the_folder(reference, tmp_path, capsys):
    # D8: a resume refused for its journal (here: --runs grown, a run recorded twice) had
    # already rewritten campaign.json (with the new number of runs) and scenario.toml
    out = _copy(reference, tmp_path)
    with open(out / "runs.csv", "ab") as fh:
        fh.write(_rows_bytes(out)[1])
    before = _bytes(out)
    line = _one_error(capsys, 2, _argv(out, runs=RUNS + 6))
    assert line == (f"quadland: error: --out: {out / 'runs.csv'} line {RUNS + 2} holds run "
                    "0 again (line 2); it cannot be resumed: choose a new folder")
    assert _bytes(out) == before
    assert json.loads((out / "campaign.json").read_text())["runs"] == RUNS
    # another --set, another scenario: refused, nothing changed either
    for extra in (["--set", "quadrotor.mass=2.1"], ["--scenario", "highway"]):
        assert main(_argv(out, *extra)) == 2
        assert "holds another campaign" in capsys.readouterr().err
        assert _bytes(out) == before


def _rows_bytes(folder):
    return (folder / "runs.csv").read_bytes().splitlines(keepends=True)


@pytest.mark.parametrize("index, why", [
    (RUNS, f"line 4 holds run {RUNS}, not one of this campaign's {RUNS} (0 to {RUNS - 1})"),
    (1000, f"line 4 holds run 1000, not one of this campaign's {RUNS} (0 to {RUNS - 1})"),
    (-1, f"line 4 holds run -1, not one of this campaign's {RUNS} (0 to {RUNS - 1})"),
    (5, "line 7 holds run 5 again (line 4)"),       # the rows are in the order of the runs
])
def test_a_journal_row_of_another_run_is_refused(reference, tmp_path, capsys, index, why):
    # D9: a run index >= --runs, negative or repeated was accepted on resume (a campaign
    # of 24 runs holding 25 rows, none summarized)
    out = _copy(reference, tmp_path)
    lines = _rows_bytes(out)
    fields = lines[3].decode().split(",")
    lines[3] = ",".join([str(index), *fields[1:]]).encode()
    (out / "runs.csv").write_bytes(b"".join(lines))
    before = _bytes(out)
    line = _one_error(capsys, 2, _argv(out, runs=RUNS + 10))
    assert line == (f"quadland: error: --out: {out / 'runs.csv'} {why}; it cannot be "
                    "resumed: choose a new folder")
    assert _bytes(out) == before


@pytest.mark.parametrize("name", ["runs.csv", "campaign.json"])
@pytest.mark.parametrize("kind, why", [
    ("zero", "is a symbolic link"),
    ("link", "is a symbolic link"),
    ("folder", "is not a regular file (a folder)"),
    ("fifo", "is not a regular file (a named pipe)"),
    ("huge", None),
])
def test_a_journal_or_manifest_that_is_no_regular_file_is_one_line(reference, tmp_path,
                                                                   capsys, name, kind, why):
    # D10: a link to /dev/zero read forever (memory), a FIFO blocked, a folder gave an
    # IsADirectoryError traceback
    from quadland.campaign.journal import MAX_MANIFEST_BYTES, MAX_ROW_BYTES

    out = _copy(reference, tmp_path)
    path = out / name
    if kind == "huge":
        if name == "runs.csv":
            path.write_bytes(path.read_bytes() + b"0," * (MAX_ROW_BYTES // 2 + 1))
            why = "line 26 is longer than 1 MiB"
        else:
            path.write_bytes(b" " * (MAX_MANIFEST_BYTES + 1))
            why = "is larger than 16 MiB, more than a campaign writes"
    else:
        keep = tmp_path / "kept"
        path.rename(keep)
        if kind == "zero":
            path.symlink_to("/dev/zero")
        elif kind == "link":
            path.symlink_to(keep)
        elif kind == "folder":
            path.mkdir()
        else:
            os.mkfifo(path)
    before = _bytes(out)
    line = _one_error(capsys, 2, _argv(out))
    assert line == (f"quadland: error: --out: {path} {why}; it cannot be resumed: choose a "
                    "new folder")
    assert _bytes(out) == before


def test_a_full_disk_stops_with_status_4_and_the_resume_finishes(reference, tmp_path,
                                                                   capsys, monkeypatch):
    # D14: a full disk while runs.csv was appended to was exit 2 ("bad input"), and while
    # the summary was written too; the runs before are kept and the same command resumes
    import errno

    from quadland.campaign import journal

    out = tmp_path / "full"
    real = journal._write_all
    calls = []

    def fill_up(fd, data):
        calls.append(len(data))
        if len(calls) == 5:                     # half the line written, then the disk is full
            os.write(fd, data[:len(data) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(fd, data)

    monkeypatch.setattr(journal, "_write_all", fill_up)
    line = _one_error(capsys, 4, _argv(out))
    assert line == (f"quadland: error: --out: cannot write {out / 'runs.csv'}: No space left "
                    "on device; the runs recorded before are kept: free some space and run "
                    "the same command to resume")
    lines = _rows_bytes(out)                    # the header, 4 runs and the cut line
    assert len(lines) == 6 and not lines[-1].endswith(b"\n")
    assert not (out / "summary.json").exists()
    monkeypatch.setattr(journal, "_write_all", real)
    # ... and the summary cannot be written either
    real_atomic = journal.write_bytes_atomic

    def no_summary(path, data):
        if path.name == "summary.json":
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real_atomic(path, data)

    monkeypatch.setattr(journal, "write_bytes_atomic", no_summary)
    line = _one_error(capsys, 4, _argv(out))
    assert line == (f"quadland: error: --out: cannot write {out / 'summary.json'}: No space "
                    "left on device; every run is recorded: free some space and run the same "
                    "command to resume")
    assert not (out / "summary.json").exists()
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()
    monkeypatch.setattr(journal, "write_bytes_atomic", real_atomic)
    assert main(_argv(out)) == 0
    assert "no run left to fly" in capsys.readouterr().out
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()
    assert json.loads((out / "summary.json").read_text())["flown"] == RUNS


def test_the_last_line_of_an_all_invalid_campaign_agrees_with_its_summary(tmp_path, capsys):
    # D16: "no run flown, the draws of all 2 were invalid (runs.csv says why); flew 2 runs
    # in 0.0 s (3355.4 runs/s)"
    out = tmp_path / "invalid"
    argv = ["campaign", "--scenario", "highway", "--runs", "2", "--workers", "1", "--out",
            str(out), "--set", 'campaign.dispersions={"quadrotor.mass"={distribution="normal",'
            'std=1e300}}']
    assert main(argv) == 0
    text = capsys.readouterr().out.strip()
    assert re.fullmatch(f"quadland: wrote {re.escape(str(out))}: no run flown, the draws of "
                        r"all 2 were invalid \(runs.csv says why\); 2 invalid draws recorded "
                        r"in [0-9.]+ s", text), text
    session = json.loads((out / "summary.json").read_text())["last_session"]
    assert session["runs_flown"] == 0 and session["invalid_draws"] == 2
    assert session["runs_per_s"] is None


def test_the_forkserver_hook_silences_only_a_truncated_start():
    # V13: Ctrl-C while the campaign sent a worker its process object left the forkserver's
    # child an EOFError, whose traceback multiprocessing printed under the one line. The
    # hook the forkserver preloads ends that child silently; any other exception prints.
    for exc, printed in (("EOFError('Ran out of input')", False), ("ValueError('x')", True)):
        proc = subprocess.run(
            [sys.executable, "-c", "import quadland.campaign.forkserver_hook\n"
             f"raise {exc}\n"], capture_output=True, text=True, env=_env(), timeout=60)
        assert proc.returncode == 1
        assert ("Traceback" in proc.stderr) is printed, proc.stderr
    import inspect

    import quadland.campaign.local as local
    # the pool's forkserver is started (its preload set) by start_pool_server, which
    # pool_runs calls (run_campaign calls it earlier, once the campaign is checked)
    assert '"quadland.campaign.forkserver_hook"' in inspect.getsource(local.start_pool_server)
    assert "start_pool_server()" in inspect.getsource(local.pool_runs)

"""The command line, end to end on a short horizon."""

import csv
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from ctypes_interrupt import ctrl_c_wrapped_by_ctypes, labs_of_a_long

from quadland.cli import main
from quadland.margins import Requirement
from quadland.plots import MARGIN_FIGURES, SIMULATION_FIGURES

FIGURES = SIMULATION_FIGURES
PNG = b"\x89PNG\r\n\x1a\n"


def _run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "quadland", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


@pytest.mark.slow
def test_simulate_writes_everything(tmp_path):
    out = tmp_path / "run"
    proc = _run("simulate", "--set", "simulation.duration=0.3", "--set",
                "controller.nominal_model=true", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    names = {p.name for p in out.iterdir()}
    assert names == {"trajectory.csv", "columns.json", "summary.json", "scenario.toml",
                     ".quadland-output", *FIGURES}
    for fig in FIGURES:
        assert (out / fig).read_bytes()[:8] == PNG
    with open(out / "trajectory.csv") as fh:
        rows = list(csv.reader(fh))
    header = [h.split(" [")[0] for h in rows[0]]
    for col in ("t", "z_e", "phi_e", "theta_e", "psi_e", "dz_e", "p_e", "q_e", "r_e",
                "u_1", "u_4", "F_total", "M_x", "M_z", "F_1", "F_4", "Delta_1", "Delta_4",
                "Delta_hat_1", "Delta_hat_4", "x1", "y1", "x2", "y2"):
        assert col in header
    assert len(rows) == 1 + 31
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenario"]["controller"]["nominal_model"] is True
    assert summary["scenario"]["simulation"]["duration"] == 0.3
    assert summary["seed"] == 2019
    assert summary["versions"]["casadi"] == "3.8.2"
    assert summary["status"] == "ok"
    assert {"numpy", "scipy", "control", "matplotlib", "python"} <= set(summary["versions"])
    assert summary["overrides"] == ["simulation.duration=0.3", "controller.nominal_model=True"]
    assert set(summary["errors"]) >= {"z_e", "phi_e", "theta_e", "psi_e"}


def test_no_plots_and_default_folder(tmp_path):
    proc = _run("simulate", "--set", "simulation.duration=0.1", "--no-plots", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    (folder,) = list(tmp_path.iterdir())
    assert folder.name.startswith("paper-")
    assert {p.name for p in folder.iterdir()} == {"trajectory.csv", "columns.json",
                                                  "summary.json", "scenario.toml",
                                                  ".quadland-output"}


BAD = [
    (["--scenario", "papr"], "unknown scenario 'papr' (did you mean 'paper'?)"),
    (["--scenario", "missing.toml"], "missing.toml: scenario file not found"),
    (["--set", "quadrotor.masss=3"], "did you mean 'quadrotor.mass'?"),
    (["--set", "quadrotor.mass=0"], "quadrotor.mass: must be in [0.001, 10000] kg"),
    (["--set", "simulation.duration=nan"], "simulation.duration: must be finite"),
    (["--set", "initial.eta1_deg=[0, 90, 0]"], "initial.eta1_deg"),
    (["--set", "rbf.nodes=0"], "rbf.nodes: must be in [1, 1000]"),
    (["--set", "simulation.duration=90000"], "over the 2 GiB limit"),
    (["--set", "scenario.name=\"../escape\""], "scenario.name: must be 1 to 64"),
]


@pytest.mark.slow
@pytest.mark.parametrize("args, message", BAD)
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, args, message):
    out = tmp_path / "out"
    proc = _run("simulate", *args, "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("quadland: error: ")
    assert message in lines[0]
    assert "Traceback" not in proc.stderr
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []



HIGHWAY = Path(__file__).resolve().parents[1] / "quadland" / "scenarios" / "highway.toml"

#: A misspelt sensor section or key by each path: the scenario file, --set and a campaign's
#: dispersion key (the command, the file's change or override, the line's end).
MISSPELT = [
    ("simulate", ("[sensors.vision]\n", "[sensors.visoin]\n"), None,
     "unknown section 'sensors.visoin' (did you mean 'sensors.vision'?)"),
    ("simulate", ("[sensors.vision]\nrate_hz", "[sensors.vision]\nratehz"), None,
     "unknown key 'sensors.vision.ratehz' (did you mean 'sensors.vision.rate_hz'?)"),
    ("simulate", ("[estimator]", "[estimatr]"), None,
     "unknown section 'estimatr' (did you mean 'estimator'?)"),
    ("simulate", None, "sensors.gnss.latncy=0.1",
     "--set sensors.gnss.latncy: unknown key 'sensors.gnss.latncy' "
     "(did you mean 'sensors.gnss.latency'?)"),
    ("simulate", None, "sensors.visoin.latency=0.1",
     "--set sensors.visoin.latency: unknown section 'sensors.visoin' "
     "(did you mean 'sensors.vision'?)"),
    ("campaign", ('"sensors.vision.latency"', '"sensors.visoin.latency"'), None,
     "campaign.dispersions.\"sensors.visoin.latency\": not a key of this scenario's "
     "schema (did you mean 'sensors.vision.latency'?)"),
    ("campaign", None, "sensors.vision.latncy=0.1",
     "--set sensors.vision.latncy: unknown key 'sensors.vision.latncy' "
     "(did you mean 'sensors.vision.latency'?)"),
]


@pytest.mark.slow
@pytest.mark.parametrize("command, change, override, message", MISSPELT)
def test_a_misspelt_sensor_is_one_line_exit_2_and_writes_nothing(tmp_path, command, change,
                                                                 override, message):
    scenario, made = "highway", []
    if change is not None:
        text = HIGHWAY.read_text()
        assert text.count(change[0]) == 1
        scenario = tmp_path / "s.toml"
        scenario.write_text(text.replace(*change))
        made = [scenario]
    args = [command, "--scenario", str(scenario), "--out", str(tmp_path / "out"),
            *(["--set", override] if override else []), *(["--runs", "2"]
                                                          if command == "campaign" else [])]
    proc = _run(*args, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.splitlines()
    where = f"{scenario}: " if change and command == "simulate" else ""
    assert line == f"quadland: error: {where}{message}"
    assert proc.stdout == "" and list(tmp_path.iterdir()) == made

def test_malformed_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[simulation\n")
    proc = _run("simulate", "--scenario", str(bad), cwd=tmp_path)
    assert proc.returncode == 2
    assert "malformed TOML" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


@pytest.mark.slow
def test_existing_outputs_survive_bad_input(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("{\"keep\": true}\n")
    proc = _run("simulate", "--set", "quadrotor.mass=-1", "--out", str(out))
    assert proc.returncode == 2
    assert (out / "summary.json").read_text() == "{\"keep\": true}\n"


def test_help():
    proc = _run("--help")
    assert proc.returncode == 0
    assert "simulate" in proc.stdout
    proc = _run("simulate", "--help")
    assert "--set" in proc.stdout and "--no-plots" in proc.stdout


def test_simulate_out_is_a_file(tmp_path):
    out = tmp_path / "out"
    out.write_text("keep\n")
    proc = _run("simulate", "--set", "simulation.duration=0.1", "--out", str(out))
    assert proc.returncode == 2
    assert proc.stderr == f"quadland: error: --out: {out} exists and is not a folder\n"
    assert out.read_text() == "keep\n"


def test_a_name_no_file_system_holds_is_one_line(tmp_path, capsys, monkeypatch):
    """A file name over the file system's limit (errno 36) gave a 30-line traceback from
    every command; now one line naming the path, shortened, and nothing written."""
    monkeypatch.chdir(tmp_path)
    long = "x" * 5000
    for argv in (["simulate", "--scenario", long], ["simulate", "--out", "y" * 300],
                 ["codegen", "--out", "z" * 300],
                 ["margins", "--out", "/".join(["w" * 200] * 30)]):
        assert main(argv) == 2, argv
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].endswith("File name too long"), err
        assert len(err[0]) < 200 or "cannot read" in err[0]
    assert os.listdir(tmp_path) == []


def test_a_ctrl_c_that_breaks_a_module_s_import_is_one_line(capsys, monkeypatch):
    """A Ctrl-C during an extension module's initialization reaches the command as
    ImportError from the KeyboardInterrupt (seen once under load): one line, 130.
    Any other ImportError is not hidden."""
    import quadland.cli as cli

    def cut_short(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as ki:
            raise ImportError("initialization failed") from ki

    monkeypatch.setattr(cli, "_dispatch", cut_short)
    assert main(["simulate", "--no-plots"]) == 130
    assert capsys.readouterr().err == "quadland: interrupted\n"

    def broken(args):
        raise ImportError("no module named foo")

    monkeypatch.setattr(cli, "_dispatch", broken)
    with pytest.raises(ImportError, match="foo"):
        main(["simulate", "--no-plots"])


def test_a_ctrl_c_while_ctypes_converts_an_argument_is_one_line(capsys, monkeypatch):
    """A Ctrl-C while ctypes converts a call's arguments (NumPy's ``ndpointer`` checks
    them in Python) reaches the command as ``ctypes.ArgumentError("argument 6:
    KeyboardInterrupt: ")``, without cause or context (it printed a traceback once, in a
    campaign's start under load): one line, 130. Any other ArgumentError is not hidden."""
    import ctypes

    import quadland.cli as cli

    def cut_short(args):
        ctrl_c_wrapped_by_ctypes()

    with pytest.raises(ctypes.ArgumentError) as raised:     # what ctypes makes of it
        cut_short(None)
    assert str(raised.value) == "argument 1: KeyboardInterrupt: "
    assert raised.value.__cause__ is None and raised.value.__context__ is None
    monkeypatch.setattr(cli, "_dispatch", cut_short)
    assert main(["simulate", "--no-plots"]) == 130
    assert capsys.readouterr().err == "quadland: interrupted\n"

    def wrong_type(args):
        labs_of_a_long()("three")

    monkeypatch.setattr(cli, "_dispatch", wrong_type)
    with pytest.raises(ctypes.ArgumentError, match="argument 1: TypeError"):
        main(["simulate", "--no-plots"])


def test_a_ctrl_c_swallowed_then_raised_again_is_one_line(capsys, monkeypatch):
    """One SIGINT landing where Python cannot raise (a module lock while a lazy import
    loads: printed as unraisable and dropped), then raised again by the command's
    ``interrupt.check()`` and reported: one line, 130 (it printed the line twice, once
    in CI under load)."""
    import types

    import quadland.cli as cli
    from quadland import interrupt

    def swallow():                             # what Python does with it there
        sys.unraisablehook(types.SimpleNamespace(
            exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt(), exc_traceback=None,
            err_msg=None, object=None))

    def handler(args):
        swallow()
        interrupt._noted = True                # as the SIGINT handler notes it
        interrupt.check()

    monkeypatch.setattr(cli, "_run_simulate", handler)
    assert main(["simulate", "--no-plots"]) == 130
    assert capsys.readouterr().err == "quadland: interrupted\n"

    def swallowed_only(args):                  # the command never saw it: raised after
        swallow()
        return 0

    monkeypatch.setattr(cli, "_run_simulate", swallowed_only)
    assert main(["simulate", "--no-plots"]) == 130
    assert capsys.readouterr().err == "quadland: interrupted\n"


# margins, in process (its exit status is main's return value) on a small network

SMALL = ["--set", "rbf.nodes=5"]


def _margins(tmp_path, *args, name="out"):
    out = tmp_path / name
    return main(["margins", *SMALL, "--out", str(out), *args]), out


@pytest.mark.slow
def test_margins_writes_json_figures_and_table(tmp_path, capsys):
    # at 70 Hz the sampled loop meets the requirement with its multiloop disk margin
    # (+-8.9 dB, 50.3 deg); at 50 Hz every loop passes but that margin (36.5 deg) fails
    status, out = _margins(tmp_path, "--set", "controller.rate_hz=70")
    assert status == 0
    assert {p.name for p in out.iterdir()} == {"margins.json", "scenario.toml",
                                               ".quadland-output", *MARGIN_FIGURES}
    for fig in MARGIN_FIGURES:
        assert (out / fig).read_bytes()[:8] == PNG
    data = json.loads((out / "margins.json").read_text())
    assert data["continuous"]["passed"] and data["sampled"]["passed"]
    std = capsys.readouterr()
    assert ("requirement 6 dB / 45 deg, each loop with the others closed and the multiloop "
            "disk margin: PASS") in std.out
    assert "zero-order hold at 70 Hz" in std.out
    assert std.out.splitlines()[-1].startswith(f"quadland: wrote {out} (")
    assert std.err == ""


def test_margins_fail_exits_1_and_names_the_loops(tmp_path, capsys):
    status, out = _margins(tmp_path, "--no-plots", "--gain-margin-db", "60")
    assert status == 1
    data = json.loads((out / "margins.json").read_text())
    assert data["requirement"]["gain_margin_db"] == 60.0
    failed = [n for n, v in data["continuous"]["loops"].items() if not v["passed"]]
    assert failed                                  # GM down of altitude is -41 dB
    assert not data["continuous"]["multiloop_disk"]["passed"]     # +-12.8 dB
    failed.append("multiloop disk")
    std = capsys.readouterr()
    assert "and the multiloop disk margin: FAIL" in std.out
    assert std.err == (f"quadland: margins below the requirement 60 dB / 45 deg: "
                       f"continuous: {', '.join(failed)}\n")


@pytest.mark.slow
def test_margins_unstable_loop_fails(tmp_path, capsys):
    """The frozen state 0.1 s into the landing (30 deg tilt) of the 5-node network has
    unstable closed-loop poles: every loop fails, the figures are still written."""
    status, out = _margins(tmp_path, "--at", "0.1", "--set", "controller.rate_hz=50")
    assert status == 1
    assert {p.name for p in out.iterdir()} == {"margins.json", "scenario.toml",
                                               ".quadland-output", *MARGIN_FIGURES}
    data = json.loads((out / "margins.json").read_text())
    assert data["operating_point"]["kind"] == "frozen"
    assert data["operating_point"]["time_s"] == 0.1
    assert data["continuous"]["stable"] is False
    loops = ", ".join([*data["continuous"]["loops"], "multiloop disk"])
    assert not data["continuous"]["multiloop_disk"]["passed"]
    assert capsys.readouterr().err == (
        f"quadland: margins below the requirement 6 dB / 45 deg: "
        f"continuous (closed loop unstable): {loops}; sampled (closed loop unstable): {loops}\n")


@pytest.mark.parametrize("args, message", [
    (["--at", "-1"], "--at: must be a finite time >= 0 s, got -1.0"),
    (["--at", "inf"], "--at: must be a finite time >= 0 s, got inf"),
    (["--at", "1e-9"], "--at: must be 0 or in [0.001, 100000] s, got 1e-09"),
    (["--at", "1e6"], "--at: must be 0 or in [0.001, 100000] s, got 1e+06"),
    (["--at", "90000"], "--at: reaching 90000 s takes 9,000,001 output rows"),
    (["--gain-margin-db", "-3"], "--gain-margin-db: must be a finite number >= 0, got -3.0"),
    (["--phase-margin-deg", "200"], "--phase-margin-deg: must lie in [0, 180), got 200.0"),
    (["--set", "rbf.nodes=0"], "rbf.nodes: must be in [1, 1000]"),
    (["--delay-periods", "-1"], "--delay-periods: must be an integer >= 0, got -1"),
    (["--scenario", "ship", "--at", "2"], "--at: the landing loop is analysed at its hover"),
])
def test_margins_bad_input_names_the_flag_and_writes_nothing(tmp_path, capsys, args, message):
    status, out = _margins(tmp_path, "--no-plots", *args)
    assert status == 2
    err = capsys.readouterr().err
    assert err.startswith(f"quadland: error: {message}")
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.slow
def test_margins_of_a_landing_scenario(tmp_path, capsys):
    """The landing loop at hover: the same files and table; the exit status follows the
    verdict, and the failed loops are named per controller."""
    status, out = _margins(tmp_path, "--scenario", "highway")
    assert {p.name for p in out.iterdir()} == {"margins.json", "scenario.toml",
                                               ".quadland-output", *MARGIN_FIGURES}
    data = json.loads((out / "margins.json").read_text())
    assert data["operating_point"]["model"] == "landing"
    assert list(data["sampled"]["loops"]) == ["thrust", "roll", "pitch", "yaw"]
    assert data["sampled"]["computation_delay_periods"] == 1
    # the verdict is the loop with the navigation filter's (the flown loop)
    assert data["verdict_from"] == ["sampled, filter in the loop"]
    passed = data["filtered"]["passed"]
    assert status == (0 if passed else 1)
    std = capsys.readouterr()
    assert "hover 3 m above the pad" in std.out
    def missed(k):
        return [n for n, v in data[k]["loops"].items() if not v["passed"]] + (
            [] if data[k]["multiloop_disk"]["passed"] else ["multiloop disk"])
    failed = [f"sampled, filter in the loop: {', '.join(missed('filtered'))}"] \
        if not passed else []
    assert std.err == ("" if passed else "quadland: margins below the requirement 6 dB / "
                                         f"45 deg: {'; '.join(failed)}\n")


def test_margins_delay_periods(tmp_path, capsys):
    status, out = _margins(tmp_path, "--no-plots", "--set", "controller.rate_hz=100",
                           "--delay-periods", "2")
    data = json.loads((out / "margins.json").read_text())
    assert data["sampled"]["computation_delay_periods"] == 2
    assert data["sampled"]["computation_delay_s"] == pytest.approx(0.02)
    assert "computation delay 2 periods (20 ms)" in capsys.readouterr().out


def test_margins_out_is_a_file(tmp_path, capsys):
    out = tmp_path / "out"
    out.write_text("keep\n")
    assert main(["margins", *SMALL, "--no-plots", "--out", str(out)]) == 2
    assert capsys.readouterr().err == f"quadland: error: --out: {out} exists and is not a folder\n"
    assert out.read_text() == "keep\n"


def test_margins_default_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["margins", *SMALL, "--no-plots"]) == 0
    (folder,) = list(tmp_path.iterdir())
    assert re.fullmatch(r"paper-margins-\d{8}-\d{6}", folder.name)
    assert sorted(p.name for p in folder.iterdir()) == [".quadland-output", "margins.json",
                                                        "scenario.toml"]


def test_margins_help_shows_the_requirement_defaults(capsys):
    with pytest.raises(SystemExit):
        main(["margins", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert f"(default: {Requirement.gain_margin_db:g} dB)" in text
    assert f"(default: {Requirement.phase_margin_deg:g} deg)" in text


def _strict(text):
    def refuse(token):
        raise AssertionError(f"non-strict JSON token {token}")
    return json.loads(text, parse_constant=refuse)


@pytest.mark.slow
def test_scenario_toml_repeats_the_run_bit_for_bit(tmp_path):
    first, second = tmp_path / "a", tmp_path / "b"
    proc = _run("simulate", "--set", "simulation.duration=0.2", "--set", "simulation.seed=7",
                "--no-plots", "--out", str(first))
    assert proc.returncode == 0, proc.stderr
    proc = _run("simulate", "--scenario", str(first / "scenario.toml"), "--no-plots",
                "--out", str(second))
    assert proc.returncode == 0, proc.stderr
    assert (first / "trajectory.csv").read_bytes() == (second / "trajectory.csv").read_bytes()
    assert _strict((second / "summary.json").read_text())["seed"] == 7


@pytest.mark.slow
def test_failed_flight_exits_3_with_the_partial_trajectory(tmp_path):
    out = tmp_path / "out"
    proc = _run("simulate", "--set", "controller.k1=[1000.0, 1000.0, 1000.0, 1000.0]",
                "--set", "controller.k2=[1000.0, 1000.0, 1000.0, 1000.0]", "--set",
                "simulation.duration=2", "--no-plots", "--out", str(out))
    assert proc.returncode == 3, proc.stderr
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("quadland: error: flight failed at t = ")
    assert "rk_steps_per_interval" in line              # the fixed step is the likely cause
    summary = _strict((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["failure"] in line
    with open(out / "trajectory.csv") as fh:
        rows = list(csv.reader(fh))
    assert 1 < len(rows) < 201
    assert all(v not in ("nan", "inf", "-inf") for row in rows[1:] for v in row)


def test_a_folder_in_use_is_refused(tmp_path):
    from quadland.output import OutputFolder

    out = tmp_path / "busy"
    with OutputFolder(out):
        proc = _run("simulate", "--set", "simulation.duration=0.1", "--no-plots",
                    "--out", str(out))
    assert proc.returncode == 2
    assert "is in use by another quadland run" in proc.stderr
    assert not out.exists()


@pytest.mark.slow
def test_no_plots_replaces_an_earlier_set_whole(tmp_path):
    out = tmp_path / "out"
    assert _run("simulate", "--set", "simulation.duration=0.1", "--out", str(out)).returncode == 0
    assert (out / "ground_track.png").exists()
    proc = _run("simulate", "--set", "simulation.duration=0.1", "--no-plots", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert not list(out.glob("*.png"))
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_folder_of_other_files_is_never_replaced(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    proc = _run("simulate", "--set", "simulation.duration=0.1", "--no-plots",
                "--out", str(tmp_path))
    assert proc.returncode == 2
    assert "not a quadland output" in proc.stderr
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_unwritable_target_is_found_before_any_work(tmp_path):
    # a folder under a regular file cannot be made, whoever runs the test (root too)
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    proc = _run("simulate", "--set", "simulation.duration=5", "--out", str(blocker / "out"))
    assert proc.returncode == 2
    (line,) = proc.stderr.strip().splitlines()
    assert "cannot write to" in line and "Traceback" not in proc.stderr


def test_margins_validates_before_claiming_its_folder(tmp_path, capsys):
    status = main(["margins", "--set", "rbf.nodes=5", "--at", "1e-9", "--out",
                   str(tmp_path / "newp" / "sub")])
    assert status == 2
    assert not (tmp_path / "newp").exists()


@pytest.mark.slow
def test_a_cvodes_failure_is_one_line(tmp_path):
    proc = _run("simulate", "--set", 'simulation.integrator="cvodes"', "--set",
                "initial.eta1_deg=[80, 80, 0]", "--set", "controller.k1=[1e5, 1e5, 1e5, 1e5]",
                "--set", "simulation.reltol=1e-14", "--set", "simulation.abstol=1e-14",
                "--set", "simulation.duration=0.5", "--no-plots", "--out", str(tmp_path / "o"))
    assert proc.returncode == 3
    (line,) = proc.stderr.strip().splitlines()
    assert line.startswith("quadland: error: flight failed at t = 0 s: the integrator cvodes "
                           "failed: CV_")
    # the rows before the failing interval are written: here the initial state alone
    with open(tmp_path / "o" / "trajectory.csv") as f:
        assert len(f.read().splitlines()) == 2


# A command line that does not parse: one line naming the flag, exit 2 (argparse alone
# prints its usage and a second line).

@pytest.mark.parametrize("args, line", [
    (["campaign", "--runs", "abc"], "--runs: must be an integer, got 'abc'"),
    (["campaign", "--workers", "-"], "--workers: must be an integer, got '-'"),
    (["margins", "--delay-periods", "1.5"], "--delay-periods: must be an integer, got '1.5'"),
    (["margins", "--at", "x"], "--at: must be a number, got 'x'"),
    (["margins", "--gain-margin-db", "six"], "--gain-margin-db: must be a number, got 'six'"),
    (["simulate", "--out"], "--out: expected one argument"),
    (["simulate", "--bogus"], "unrecognized arguments: --bogus (see quadland simulate --help)"),
    (["codegen", "stray"], "unrecognized arguments: stray (see quadland codegen --help)"),
    ([], "a command is required: simulate, codegen, margins, campaign or envelope"),
    (["fly"], "unknown command 'fly': the commands are simulate, codegen, margins, campaign "
              "or envelope"),
])
def test_a_bad_command_line_is_one_line(tmp_path, capsys, monkeypatch, args, line):
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    std = capsys.readouterr()
    assert std.out == ""
    assert std.err.startswith(f"quadland: error: {line}")
    assert len(std.err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_a_bad_flag_type_through_the_console():
    proc = _run("campaign", "--runs", "abc")
    assert proc.returncode == 2
    assert proc.stderr == "quadland: error: --runs: must be an integer, got 'abc'\n"
    assert proc.stdout == ""
    proc = _run("margins", "--help")                    # help is unchanged
    assert proc.returncode == 0 and proc.stdout.startswith("usage: quadland margins")
    assert proc.stderr == ""


@pytest.mark.slow
def test_animate_a_failed_flight_exits_3_with_the_partial_data(tmp_path):
    """The pad's position reaches 1e296 m before the state is infinite: the animation
    stopped with ``Axis limits -inf, inf``; now every file of a failed run is written."""
    out = tmp_path / "out"
    proc = _run("simulate", "--scenario", "turning", "--set", "vehicle.tau=[1e8,1e8,1e8]",
                "--animate", "--out", str(out))
    assert proc.returncode == 3, proc.stderr
    (line,) = proc.stderr.splitlines()
    assert line.startswith("quadland: error: flight failed at t = ")
    assert _strict((out / "summary.json").read_text())["status"] == "failed"
    assert (out / "landing.gif").read_bytes()[:6] == b"GIF89a"
    from quadland.plots import LANDING_FIGURES

    for name in LANDING_FIGURES:
        assert (out / name).read_bytes()[:8] == PNG


def _broken_home(tmp_path):
    """An environment whose home cannot hold matplotlib's or quadland's folders, even for
    root: a regular file on the path."""
    import os

    afile = tmp_path / "afile"
    afile.write_text("")
    env = {k: v for k, v in os.environ.items()
           if k not in ("XDG_CONFIG_HOME", "XDG_CACHE_HOME", "MPLCONFIGDIR")}
    return {**env, "HOME": str(afile / "home"), "TMPDIR": str(tmp_path)}


@pytest.mark.slow
def test_an_unwritable_home_adds_no_line_of_matplotlib(tmp_path):
    """matplotlib said 2 lines of its temporary folder, even with --no-plots."""
    env = _broken_home(tmp_path)
    for args in (["margins", *SMALL, "--no-plots"], ["margins", *SMALL],
                 ["simulate", "--scenario", "highway", "--set", "simulation.duration=0.1",
                  "--no-plots"]):
        out = tmp_path / f"out{len(list(tmp_path.iterdir()))}"
        proc = subprocess.run([sys.executable, "-m", "quadland", *args, "--out", str(out)],
                              capture_output=True, text=True, cwd=tmp_path, env=env,
                              timeout=600)
        assert proc.returncode == 0, proc.stderr
        lines = proc.stderr.splitlines()
        assert len(lines) <= 1 and all(ln.startswith("quadland: warning: cannot use the "
                                                     "build cache") for ln in lines), lines
    assert not list(tmp_path.glob("quadland-matplotlib-*"))       # removed at exit


def test_a_run_without_figures_does_not_import_matplotlib(tmp_path):
    code = ("import sys; from quadland.run import run_simulation; "
            f"run_simulation('highway', ['simulation.duration=0.1'], {str(tmp_path / 'o')!r}, "
            "plots=False); print('matplotlib' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300)
    assert proc.stdout == "False\n", proc.stderr


# --- a second review of the commands (issue 16: D13, D14, D15, D17) --------------------

@pytest.mark.parametrize("override, line", [
    ("campaign.limits.x=1", "--set campaign.limits.x: only the [campaign] table's own keys "
                            "can be set (runs, seed, sampling, dispersions, limits); give "
                            "campaign.limits whole (campaign.limits={...}) or edit the "
                            "scenario file"),
    ("campaign.dispersions.quadrotor.mass=1", "--set campaign.dispersions.quadrotor.mass: "
                                              "only the [campaign] table's own keys"),
    ("campaign.limit=1", "--set campaign.limit: unknown key campaign.limit (the [campaign] "
                         "table's keys: runs, seed, sampling, dispersions, limits); did you "
                         "mean 'campaign.limits'?"),
])
def test_a_campaign_sub_key_set_is_blamed_on_set(tmp_path, capsys, override, line):
    # D13: "--set campaign.limits.x=1" was "<...>/highway.toml: unknown key campaign.limits.x"
    out = tmp_path / "c"
    assert main(["campaign", "--scenario", "highway", "--runs", "2", "--out", str(out),
                 "--set", override]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith(f"quadland: error: {line}"), err
    assert not out.exists()


@pytest.mark.parametrize("override, shown, code", [
    ("quadrotor.mass=1\n2", r"quadrotor.mass=1\n2", "U+000A"),
    ("quadrotor.mass=1\x1b[31m", r"quadrotor.mass=1\x1b[31m", "U+001B"),
    ("quadrotor.mass\x1b]0;x\x07=1", r"quadrotor.mass\x1b]0;x\x07=1", "U+001B"),
    ("scenario.description=\"\"\"a\nb\"\"\"", r'scenario.description="""a\nb"""', "U+000A"),
])
def test_a_control_character_in_set_is_refused_unechoed(tmp_path, capsys, override, shown,
                                                          code):
    # D15: the escape sequence went out raw in the message ("got 1\x1b[31m"), and a newline
    # could be written into scenario.toml
    out = tmp_path / "s"
    assert main(["simulate", "--no-plots", "--out", str(out), "--set", override]) == 2
    err = capsys.readouterr().err
    assert err == (f"quadland: error: --set {shown}: holds a control character ({code}); an "
                   "override is one line of printable text\n")
    assert not out.exists()


def test_a_control_character_a_toml_escape_makes_is_never_echoed(tmp_path, capsys):
    # D15: the value's own check refuses it; the message shows it escaped
    out = tmp_path / "s"
    assert main(["simulate", "--no-plots", "--out", str(out), "--set",
                 'scenario.name="a\\u001b[31mb"']) == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and err.count("\n") == 1
    assert err.startswith("quadland: error: scenario.name: must be 1 to 64 letters") and \
        err.endswith(r"got a\x1b[31mb" + "\n"), err
    assert not out.exists()


def test_a_full_disk_while_simulate_writes_is_one_line_and_leaves_nothing(tmp_path, capsys,
                                                                         monkeypatch):
    # D14: the set is written into a hidden folder and swapped in whole: a full disk
    # leaves neither a partial set nor the hidden folder, and an earlier set stays whole
    import errno

    from quadland import output

    out = tmp_path / "run"
    argv = ["simulate", "--no-plots", "--set", "simulation.duration=0.2", "--out", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real = output._write_synced

    def full(path, data, mode):
        if path.name == "trajectory.csv":
            with open(path, "xb") as fh:
                fh.write(data[:len(data) // 3])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(path, data, mode)

    monkeypatch.setattr(output, "_write_synced", full)
    for target in (out, tmp_path / "new"):
        assert main([*argv[:-1], str(target)]) == 2
        assert capsys.readouterr().err == (f"quadland: error: --out: cannot write {target}: "
                                           "No space left on device\n")
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


@pytest.mark.slow
def test_ctrl_c_while_the_command_imports_is_one_line(tmp_path):
    # D17: a SIGINT while `python -m quadland` imported its modules (before quadland's
    # code could catch it) printed a 15 to 30 line traceback. Here it arrives exactly while
    # quadland.cli is being found, and at seeded moments of the first half second.
    import random
    import signal

    code = ("import os, signal, sys\nimport quadland.__main__ as m\n"
            "class Hook:\n    def find_spec(self, name, path=None, target=None):\n"
            "        if name == 'quadland.cli':\n"
            "            os.kill(os.getpid(), signal.SIGINT)\n        return None\n"
            "sys.meta_path.insert(0, Hook())\nsys.exit(m.main(sys.argv[1:]))\n")
    proc = subprocess.run([sys.executable, "-c", code, "simulate", "--no-plots", "--out",
                           str(tmp_path / "a")], capture_output=True, text=True, timeout=120)
    assert (proc.returncode, proc.stderr, proc.stdout) == (130, "quadland: interrupted\n", "")
    rng = random.Random(20261126)
    ready = ("import sys\nimport quadland.__main__ as m\nprint('ready', flush=True)\n"
             "sys.exit(m.main(sys.argv[1:]))\n")
    for trial in range(6):
        # a run long enough to be under way at every moment drawn (the paper's 10 s flies in
        # about 0.4 s once the simulator is cached: a Ctrl-C after its end is not this test's)
        p = subprocess.Popen([sys.executable, "-c", ready, "simulate", "--no-plots", "--set",
                              "simulation.duration=200", "--out",
                              str(tmp_path / f"b{trial}")], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)
        assert p.stdout.readline() == "ready\n"
        time.sleep(rng.uniform(0.0, 0.5))
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=120)
        # -SIGINT: CPython 3.11 ends by SIGINT after a KeyboardInterrupt some extension
        # module's loading code saw (see tests/test_campaign_execute.py)
        assert p.returncode in (130, -signal.SIGINT), (trial, err)
        assert err == "quadland: interrupted\n", (trial, err)


def test_the_console_script_is_the_early_entry_point():
    import tomllib
    from pathlib import Path

    project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    # run: main (its SIGINT handler before any heavy import), then the heap left at exit
    assert project["project"]["scripts"]["quadland"] == "quadland.__main__:run"


def test_simulate_prints_the_verdict_and_figures(tmp_path, capsys):
    """A landing's verdict and first-contact figures against their limits, and the paper
    loop's settling and its below-deck flag, as summary.json holds them (issue 21)."""
    out = tmp_path / "hw"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    land = json.loads((out / "summary.json").read_text())["landing"]
    assert lines[0] == f"quadland: wrote {out}"
    assert lines[1] == f"landing: success (first contact at {land['time']:.2f} s, 0 aborts)"
    assert lines[2].split() == ["sink", "rate", f"{land['sink_rate']:.3f}", "m/s", "limit",
                                "0.5"]
    assert lines[5].split()[:2] == ["tilt", f"{land['tilt_deg']:.3f}"]
    # the tilt is judged against the gear's tip-over angle in its direction too
    assert lines[5].endswith(f"limit 32.6, tip-over {land['tip_over_deg']:.1f}")
    # landed and secured: the gear's figures (issue 18)
    assert lines[6].split() == ["peak", "gear", "load", f"{land['peak_gear_force']:.1f}", "N",
                                "limit", "424"]
    assert lines[7].split() == ["impact", "energy", f"{land['impact_energy']:.3f}", "J"]
    assert lines[8].split()[:2] == ["bounce", f"{land['bounce']:.4f}"]
    assert lines[9] == "  secured yes, tipped no, on the pad yes"
    assert lines[10].startswith("  navigation: position error at touchdown ")
    # a limit the touchdown misses is named, and its row marked: half the flight's own sink
    # rate (a judge's limit only, so the flight is the same)
    limit = float(f"{land['sink_rate'] / 2:.1g}")
    out2 = tmp_path / "hw2"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(out2), "--set",
                 f"landing.max_sink_rate={limit}"]) == 0
    lines = capsys.readouterr().out.splitlines()
    flown, land = land, json.loads((out2 / "summary.json").read_text())["landing"]
    assert land["sink_rate"] == flown["sink_rate"] and land["time"] == flown["time"]
    assert land["sink_rate"] > limit
    assert lines[1].startswith(
        f"landing: FAILED: sink rate {land['sink_rate']:.3g} > {limit:g} m/s")
    assert lines[2].endswith(f"limit {limit:g}  over")
    out3 = tmp_path / "paper"
    assert main(["simulate", "--no-plots", "--out", str(out3), "--set",
                 "simulation.duration=2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    errors = json.loads((out3 / "summary.json").read_text())["errors"]
    settle = errors["phi_e"]["settling_time"]
    assert lines[1].startswith("paper loop: settling (within the band to the end): z_e ")
    assert (f"phi_e {settle:.2f} s" if settle is not None else "phi_e never") in lines[1]


def test_scenarios_lists_each_shipped_one_and_help_names_them(capsys):
    import tomllib
    from pathlib import Path

    folder = Path(__file__).resolve().parents[1] / "quadland" / "scenarios"
    files = sorted(folder.glob("*.toml"))
    assert main(["scenarios"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == len(files)
    for line, path in zip(lines, files, strict=True):
        table = tomllib.loads(path.read_text())["scenario"]
        name, model, text = line.split(None, 2)
        assert name == path.stem and model == table.get("model", "paper")
        assert text == table["description"]
    with pytest.raises(SystemExit):
        main(["--help"])
    assert f"shipped scenarios: {', '.join(p.stem for p in files)}" in \
        " ".join(capsys.readouterr().out.split())

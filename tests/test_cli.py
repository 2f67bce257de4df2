"""The command line, end to end on a short horizon."""

import csv
import json
import subprocess
import sys

import pytest

from quadland.plots import FIGURES


def _run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "quadland", *args], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


def test_simulate_writes_everything(tmp_path):
    out = tmp_path / "run"
    proc = _run("simulate", "--set", "simulation.duration=0.3", "--set",
                "controller.nominal_model=true", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    names = {p.name for p in out.iterdir()}
    assert names == {"trajectory.csv", "summary.json", *FIGURES}
    for fig in FIGURES:
        assert (out / fig).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
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
    assert summary["overrides"] == ["simulation.duration=0.3", "controller.nominal_model=True"]
    assert set(summary["errors"]) >= {"z_e", "phi_e", "theta_e", "psi_e"}


def test_no_plots_and_default_folder(tmp_path):
    proc = _run("simulate", "--set", "simulation.duration=0.1", "--no-plots", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    (folder,) = list(tmp_path.iterdir())
    assert folder.name.startswith("paper-")
    assert {p.name for p in folder.iterdir()} == {"trajectory.csv", "summary.json"}


BAD = [
    (["--scenario", "papr"], "unknown scenario 'papr' (did you mean 'paper'?)"),
    (["--scenario", "missing.toml"], "missing.toml: scenario file not found"),
    (["--set", "quadrotor.masss=3"], "did you mean 'quadrotor.mass'?"),
    (["--set", "quadrotor.mass=0"], "quadrotor.mass: must be > 0"),
    (["--set", "simulation.duration=nan"], "simulation.duration: must be finite"),
    (["--set", "initial.eta1_deg=[0, 90, 0]"], "initial.eta1_deg"),
    (["--set", "rbf.nodes=0"], "rbf.nodes: must be >= 1"),
]


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


def test_malformed_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[simulation\n")
    proc = _run("simulate", "--scenario", str(bad), cwd=tmp_path)
    assert proc.returncode == 2
    assert "malformed TOML" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


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

"""The ``quadland margins`` command, end to end on a small network."""

import json
import math

import pytest

from quadland.cli import main
from quadland.margins import FIGURES

SMALL = ["--set", "rbf.nodes=5"]


def _run(tmp_path, *args, name="out"):
    out = tmp_path / name
    return main(["margins", *SMALL, "--out", str(out), *args]), out


def test_writes_json_and_table(tmp_path, capsys):
    status, out = _run(tmp_path, "--no-plots")
    assert status == 0
    assert {p.name for p in out.iterdir()} == {"margins.json"}
    data = json.loads((out / "margins.json").read_text())
    cont = data["continuous"]
    assert set(cont["loops"]) == {"altitude", "roll", "pitch", "yaw"}
    assert cont["stable"] is True
    assert data["operating_point"]["kind"] == "equilibrium"
    assert data["requirement"] == {"gain_margin_db": 6.0, "phase_margin_deg": 45.0}
    for loop in cont["loops"].values():
        # delay margin = phase margin (rad) / crossover frequency
        assert loop["delay_margin_s"] == pytest.approx(
            math.radians(loop["phase_margin_deg"]) / loop["crossover_frequency"], rel=1e-9)
        d = loop["disk"]
        assert d["phase_margin"] == pytest.approx(
            math.degrees(2 * math.atan(d["disk_margin"] / 2)), rel=1e-9)
        # the disk margin never promises more than the loop-at-a-time classical phase margin
        assert d["phase_margin"] <= loop["phase_margin_deg"] + 1e-9
    # the multiloop disk cannot exceed any single loop's disk
    alphas = [v["disk"]["disk_margin"] for v in cont["loops"].values()]
    assert cont["multiloop_disk"]["disk_margin"] <= min(alphas) + 1e-9
    assert "sampled" not in data
    table = capsys.readouterr().out
    for word in ("altitude", "roll", "pitch", "yaw", "multiloop disk margin",
                 "least damped", "slowest"):
        assert word in table


def test_requirement_decides_the_verdict(tmp_path, capsys):
    status, out = _run(tmp_path, "--no-plots", "--phase-margin-deg", "89")
    assert status == 0
    data = json.loads((out / "margins.json").read_text())
    assert data["continuous"]["passed"] is False
    assert all(not v["passed"] for v in data["continuous"]["loops"].values())
    assert "FAIL" in capsys.readouterr().out


def test_sampled_loop_and_figures(tmp_path):
    status, out = _run(tmp_path, "--set", "controller.rate_hz=50", "--at", "0.1",
                       "--set", "controller.hold_compensation=0.0")
    assert status == 0
    assert {p.name for p in out.iterdir()} == {"margins.json", *FIGURES}
    for fig in FIGURES:
        assert (out / fig).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    data = json.loads((out / "margins.json").read_text())
    assert data["operating_point"]["kind"] == "frozen"
    assert data["operating_point"]["time_s"] == 0.1
    assert data["sampled"]["rate_hz"] == 50.0
    # a zero-order hold adds phase lag: the sampled loop has less phase margin
    for name, loop in data["sampled"]["loops"].items():
        assert loop["phase_margin_deg"] < data["continuous"]["loops"][name]["phase_margin_deg"]


@pytest.mark.parametrize("args,message", [
    (["--at", "-1"], "--at"),
    (["--gain-margin-db", "-3"], "--gain-margin-db"),
    (["--phase-margin-deg", "200"], "--phase-margin-deg"),
    (["--set", "rbf.nodes=0"], "nodes"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, message):
    status, out = _run(tmp_path, "--no-plots", *args)
    assert status == 2
    err = capsys.readouterr().err
    assert err.startswith("quadland: error:") and message in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_hold_compensation_trades_nyquist_gain_for_phase(tmp_path):
    """At z = -1 the extrapolation 1 + k - k/z is exactly 1 + 2k and real: with
    k = 1/2 the gain margin at the Nyquist frequency shrinks by 20 log10(2) dB,
    while the phase lost to the hold is recovered near crossover."""
    runs = {}
    for hold in (0.0, 0.5):
        plots = ["--no-plots"] if hold == 0 else []          # the shipped value draws too
        status, out = _run(tmp_path, *plots, "--set", "controller.rate_hz=50",
                           "--set", f"controller.hold_compensation={hold}", name=f"h{hold}")
        assert status == 0
        runs[hold] = json.loads((out / "margins.json").read_text())
    assert {p.name for p in out.iterdir()} == {"margins.json", *FIGURES}
    nyquist = math.pi * 50
    for name, cont in runs[0.0]["continuous"]["loops"].items():
        at_nyquist = []
        for hold in (0.0, 0.5):
            crossings = runs[hold]["sampled"]["loops"][name]["all_crossings"]
            k = [i for i, w in enumerate(crossings["gm_frequency"])
                 if w == pytest.approx(nyquist, rel=1e-9)]
            assert len(k) == 1
            at_nyquist.append(crossings["gain_margin"][k[0]])
        assert at_nyquist[0] / at_nyquist[1] == pytest.approx(2.0, rel=1e-9)
        pm = {h: runs[h]["sampled"]["loops"][name]["phase_margin_deg"] for h in (0.0, 0.5)}
        lag = {h: abs(pm[h] - cont["phase_margin_deg"]) for h in pm}
        assert lag[0.5] < 0.1 * lag[0.0]

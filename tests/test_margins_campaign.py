"""``quadland margins --campaign``: the draws ``quadland campaign`` flies, reviewed."""

import csv
import json
import shlex

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from quadland.cli import main
from quadland.margins import margin_report
from quadland.scenario import load_scenario

PAPER = ["--set", "rbf.nodes=5", "--set", "simulation.duration=0.5"]


def _csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


@pytest.fixture(scope="module")
def highway(tmp_path_factory):
    """Four draws of highway's campaign, reviewed by the command."""
    out = tmp_path_factory.mktemp("mc") / "highway"
    with threadpool_limits(1):
        status = main(["margins", "--scenario", "highway", "--campaign", "--runs", "4",
                       "--out", str(out)])
    return status, out


def test_the_draws_are_those_the_campaign_flies(tmp_path, capsys):
    """Index, seed and every dispersed value as runs.csv of ``quadland campaign`` holds them,
    and the same replay command for each run summary.json lists."""
    flown, reviewed = tmp_path / "flown", tmp_path / "reviewed"
    assert main(["campaign", "--scenario", "paper", "--runs", "3", "--workers", "1",
                 "--no-plots", "--out", str(flown), *PAPER]) == 0
    assert main(["margins", "--scenario", "paper", "--campaign", "--runs", "3", "--out",
                 str(reviewed), *PAPER]) == 0
    capsys.readouterr()
    h_f, rows_f = _csv(flown / "runs.csv")
    h_r, rows_r = _csv(reviewed / "margins_draws.csv")
    dispersed = ["index", "seed", "quadrotor.mass", "quadrotor.inertia[0]",
                 "quadrotor.inertia[1]", "quadrotor.inertia[2]", "simulation.seed"]
    for col in dispersed:
        assert [r[h_f.index(col)] for r in rows_f] == [r[h_r.index(col)] for r in rows_r], col
    summary = json.loads((flown / "summary.json").read_text())
    data = json.loads((reviewed / "margins_campaign.json").read_text())
    replay = {d["index"]: d["replay"] for d in data["every_draw"]}
    assert summary["worst_runs"]
    for run in summary["worst_runs"]:
        assert replay[run["index"]] == run["command"]


def test_a_draw_s_figures_are_its_own_review(highway):
    """The margins command printed for a draw reviews the same loop: its figures again."""
    status, out = highway
    assert status == 0                      # issue 19's gains meet 6 dB / 45 deg on every draw
    data = json.loads((out / "margins_campaign.json").read_text())
    worst = data["worst_draws"][0]
    words = shlex.split(worst["review"])
    assert words[:4] == ["quadland", "margins", "--scenario", "highway"]
    overrides = words[5::2]
    assert words[4::2] == ["--set"] * len(overrides)
    with threadpool_limits(1):
        report = margin_report(load_scenario("highway", overrides))
    sec = report.sampled
    f = worst["figures"]
    assert f["multiloop_disk.alpha"] == sec.multiloop_disk.disk.disk_margin
    assert f["pitch.phase_margin_deg"] == sec.loop("pitch").phase_margin_deg
    assert f["multiloop.ms"] == sec.sensitivity.multiloop.ms.value
    imu = {s.sensor: s for s in sec.sensors}["imu"]
    assert f["sensor.imu.delay_margin_s"] == imu.delay_margin_s


def test_distribution_and_worst_draws(highway):
    """Median and worst of each figure from the CSV's columns; the worst draws by alpha."""
    _, out = highway
    data = json.loads((out / "margins_campaign.json").read_text())
    header, rows = _csv(out / "margins_draws.csv")
    assert data["draws"] == len(rows) == 4 and data["reviewed"] == 4
    assert data["section"] == "sampled"
    for name, smaller_is_worse in [("multiloop_disk.alpha", True), ("multiloop.mt", False),
                                   ("roll.phase_margin_deg", True), ("pitch.ms", False),
                                   ("sensor.gnss.delay_margin_s", True)]:
        x = np.array([float(r[header.index(name)]) for r in rows])
        d = data["distribution"][name]
        assert d["median"] == np.median(x)
        assert d["worst"] == (x.min() if smaller_is_worse else x.max())
        assert d["worst_index"] == int(np.argmin(x) if smaller_is_worse else np.argmax(x))
    alphas = [d["figures"]["multiloop_disk.alpha"] for d in data["worst_draws"]]
    assert alphas == sorted(alphas)
    # a draw passes where its own figures meet 6 dB / 45 deg: every loop's and the multiloop
    # disk's (with issue 19's gains, all four)
    col = {name: np.array([float(r[header.index(name)]) for r in rows]) for name in header
           if name.endswith(("phase_margin_deg", "gain_margin_up_db", "gain_margin_down_db",
                             "disk.gain_margin_db"))}
    meets = np.ones(len(rows), bool)
    for name, x in col.items():
        if name.startswith("sensor."):
            continue
        meets &= (x >= 45) if name.endswith("phase_margin_deg") else (
            (x <= -6) if name.endswith("down_db") else (x >= 6))
    assert [d["passed"] for d in data["every_draw"]] == meets.tolist() == [True] * 4
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [
        "margins_campaign.json", "margins_draws.csv", "scenario.toml"]


def test_invalid_draws_are_counted_apart(tmp_path, capsys):
    out = tmp_path / "bad"
    assert main(["margins", "--scenario", "highway", "--campaign", "--runs", "2", "--out",
                 str(out), "--set", 'campaign.dispersions={"quadrotor.mass"='
                 '{distribution="normal",std=1e300}}']) == 1
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [
        "quadland: margins below the requirement 6 dB / 45 deg: 2 of 2 draws (2 invalid, 0 "
        "without an operating point)"]
    data = json.loads((out / "margins_campaign.json").read_text())
    assert data["invalid"] == 2 and data["distribution"] == {} and data["worst_draws"] == []
    assert all(d["message"].startswith("quadrotor.mass") for d in data["every_draw"])


@pytest.mark.parametrize("args, line", [
    (["--scenario", "highway", "--runs", "3"],
     "--runs: counts the draws of --campaign; add --campaign"),
    (["--scenario", "highway", "--campaign", "--runs", "0"],
     "--runs: must be in [1, 1000000], got 0"),
    (["--scenario", "paper", "--campaign", "--at", "1"],
     "--at: a campaign's draws are reviewed at their equilibrium; drop --at"),
    (["--scenario", "highway", "--campaign", "--delay-periods", "-1"],
     "--delay-periods: must be an integer >= 0, got -1"),
    (["--scenario", "highway", "--campaign", "--set", "campaign.runs=0"],
     "campaign.runs: must be in [1, 1000000], got 0"),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, args, line):
    out = tmp_path / "never"
    assert main(["margins", *args, "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [f"quadland: error: {line}"]
    assert not out.exists()


def test_a_scenario_without_a_campaign_is_one_line(tmp_path, capsys):
    from quadland.scenario import SCENARIO_DIR

    # every shipped scenario has a [campaign] table: turning's file without it
    plain = tmp_path / "turning.toml"
    plain.write_text((SCENARIO_DIR / "turning.toml").read_text().split("\n[campaign]")[0])
    out = tmp_path / "never"
    assert main(["margins", "--scenario", str(plain), "--campaign", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("quadland: error: --scenario: turning has no "
                                               "[campaign] table")
    assert not out.exists()

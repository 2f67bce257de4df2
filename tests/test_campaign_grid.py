"""quadland envelope: axes, cells, statistics, resumption, bad input, the map.

Short paper runs (0.5 s of flight, a few ms each) keep the file fast.
"""

import csv
import json
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from ctypes_interrupt import ctrl_c_wrapped_by_ctypes

from quadland.campaign import axes as axes_mod
from quadland.campaign.axes import over_deck_wind, parse_axis, wind_over_deck
from quadland.campaign.cells import cell_statistics, failure_modes
from quadland.campaign.execute import CampaignInterrupted, run_campaign
from quadland.campaign.grid import plan_envelope, run_envelope
from quadland.cli import main
from quadland.exceptions import CampaignError
from quadland.scenario import load_scenario

FAST = ["simulation.duration=0.5"]
# tau[0] and k1[0] are not dispersed by the paper's campaign; 15 and 3 are their nominal
AXES = ["vehicle.tau[0]=15:25:2", "controller.k1[0]=3:4:2"]


def _rows(folder):
    with open(folder / "runs.csv", newline="") as fh:
        return list(csv.reader(fh))


# ------------------------------------------------------------------ statistics


HEADER = ["index", "cell", "axis.a", "axis.b", "seed", "status", "success", "m", "message"]


def _row(i, cell, status, success, message=""):
    return [str(i), str(cell), "0", "0", "1", status, "true" if success else "false", "",
            message]


def test_cell_statistics_against_a_hand_count():
    rows = [_row(0, 0, "ok", True), _row(1, 0, "ok", True), _row(2, 0, "ok", True),
            _row(3, 0, "ok", False, "touchdown_offset 0.3 > 0.2 m; sink_rate 0.9 > 0.5 m/s"),
            _row(4, 0, "failed", False, "the flight left its envelope at t = 3.2 s"),
            _row(5, 0, "invalid", False, "quadrotor.mass: must be in (0, 1e+04] kg"),
            _row(6, 1, "ok", False, "no touchdown by t = 40 s"),
            _row(7, 1, "ok", False, "touchdown_offset 0.25 > 0.2 m")]
    stats = cell_statistics(HEADER, rows, 3)
    # cell 0: 5 flown (3 ok successes, 1 ok miss, 1 numerical failure), 1 invalid
    assert stats[0]["runs"] == 5 and stats[0]["invalid"] == 1 and stats[0]["successes"] == 3
    assert stats[0]["success_rate"] == 3 / 5
    assert stats[0]["failure_modes"] == {"invalid draw": 1, "numerical failure": 1,
                                         "sink_rate": 1, "touchdown_offset": 1}
    assert stats[1]["runs"] == 2 and stats[1]["successes"] == 0
    assert stats[1]["failure_modes"] == {"no touchdown": 1, "touchdown_offset": 1}
    # a cell without a run: no rate, no interval
    assert stats[2] == {"runs": 0, "invalid": 0, "successes": 0, "success_rate": None,
                        "interval": None, "failure_modes": {}}
    # a 0/1 column counted per cell over the flown runs (the invalid run's 1 is not)
    flags = ["1.0", "0.0", "1.0", "", "", "1.0", "1.0", "0.0"]
    flagged = [r[:7] + [flag] + r[8:] for r, flag in zip(rows, flags, strict=True)]
    counted = cell_statistics(HEADER, flagged, 3, counted=["m"])
    assert [c["counts"] for c in counted] == [{"m": 2}, {"m": 1}, {"m": 0}]


@pytest.mark.parametrize("n", [1, 2, 7, 30])
def test_clopper_pearson_of_a_cell_against_closed_forms(n):
    """0 of n: [0, 1 - 0.025^(1/n)]; n of n: [0.025^(1/n), 1]; 1 of n's low end:
    1 - 0.975^(1/n) (the beta quantiles with a parameter 1 are powers)."""
    rows = [_row(i, 0, "ok", False, "m 2 > 1") for i in range(n)]
    rows += [_row(n + i, 1, "ok", True) for i in range(n)]
    rows += [_row(2 * n + i, 2, "ok", i == 0, "" if i == 0 else "m 2 > 1") for i in range(n)]
    stats = cell_statistics(HEADER, rows, 3)
    lo, hi = stats[0]["interval"]
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-12)
    lo, hi = stats[1]["interval"]
    assert lo == pytest.approx(0.025 ** (1 / n), rel=1e-12) and hi == 1.0
    assert stats[2]["interval"][0] == pytest.approx(1 - 0.975 ** (1 / n), rel=1e-12)


def test_failure_modes_keep_the_phrase_without_its_numbers():
    assert failure_modes("ok", True, "") == []
    assert failure_modes("ok", False, "offset 0.23 > 0.2 m; tilt -3 > 2 deg") == \
        ["offset", "tilt"]
    assert failure_modes("ok", False, "settling_time_phi_e undefined") == \
        ["settling_time_phi_e undefined"]
    assert failure_modes("failed", False, "diverged at t = 1 s") == ["numerical failure"]


# ------------------------------------------------------------------------ axes


def test_axis_grid_and_element():
    sc = load_scenario("ship")
    ax = parse_axis("wind.mean[1]=-10:10:5", sc.data, sc.model)
    assert (ax.key, ax.element, ax.values, ax.unit) == \
        ("wind.mean", 1, (-10.0, -5.0, 0.0, 5.0, 10.0), "m/s")
    ax = parse_axis("deck.sea_state=2:5:4", sc.data, sc.model)
    assert ax.values == (2.0, 3.0, 4.0, 5.0) and ax.integer
    ax = parse_axis("vehicle.tau[2]=0:1:1".replace("0:1:1", "7:7:1"), sc.data, sc.model)
    assert ax.values == (7.0,) and ax.unit == "N m"


def test_wind_over_the_deck_closed_forms():
    # a ship making 5 m/s on heading 0: 5 m/s over the deck from the bow is still air
    assert over_deck_wind(5.0, 0.0, (5.0, 0.0), 0.0) == (0.0, 0.0)
    # at rest, 4 m/s from starboard (y is port): the air moves toward +y
    wx, wy = over_deck_wind(4.0, 90.0, (0.0, 0.0), 0.0)
    assert wx == pytest.approx(0.0, abs=1e-15) and wy == pytest.approx(4.0, rel=1e-15)
    # the ship scenario's wind [0, -5] at 5 m/s: 5 sqrt(2) from 45 deg off the port bow
    speed, direction = wind_over_deck((0.0, -5.0), (5.0, 0.0), 0.0)
    assert speed == pytest.approx(5 * math.sqrt(2), rel=1e-14)
    assert direction == pytest.approx(-45.0, rel=1e-14)
    # heading 90 deg (E's y): a head wind blows toward -y in E
    wx, wy = over_deck_wind(3.0, 0.0, (2.0, 0.0), 90.0)
    assert wx == pytest.approx(0.0, abs=1e-15) and wy == pytest.approx(-1.0, rel=1e-14)
    for args in [(7.0, 30.0, (3.0, 1.0), 20.0), (2.0, -120.0, (0.0, 0.5), -75.0)]:
        wind = over_deck_wind(*args)
        speed, direction = wind_over_deck(wind, args[2], args[3])
        assert speed == pytest.approx(args[0], rel=1e-12)
        assert direction == pytest.approx(args[1], rel=1e-12)


def test_a_speed_axis_moves_the_drive_force_that_holds_it():
    """highway disperses initial.velocity2 with also = vehicle.tau: tau = d11 v."""
    env = plan_envelope("highway", None, ["initial.velocity2[0]=10:20:2", "wind.mean[1]=0:8:2"],
                        1)
    sc = env.base
    values = axes_mod.apply_cell({}, env.axes, (20.0, 8.0), sc.data, env.spec)
    assert values["initial.velocity2"] == [20.0, 0.0]
    assert values["vehicle.tau"][0] == pytest.approx(150.0 * 20.0, rel=1e-12)
    assert values["vehicle.tau"][1:] == [0.0, 0.0]
    assert values["wind.mean"] == [0.0, 8.0, 0.0]


def test_the_over_deck_axes_set_the_wind_from_the_drawn_ship():
    env = plan_envelope("ship", None, ["wind.over_deck_speed=0:10:3",
                                       "wind.over_deck_direction_deg=0:270:4"], 1)
    assert env.polar                            # the two derived axes: a polar map
    drawn = {"initial.velocity2": [6.0, 0.0], "wind.mean": [1.0, 2.0, 0.3]}
    values = axes_mod.apply_cell(drawn, env.axes, (10.0, 90.0), env.base.data, env.spec)
    # 10 m/s from starboard over a deck making 6 m/s: the wind is (6, 10), w_z kept
    assert values["wind.mean"][0] == pytest.approx(6.0, rel=1e-14)
    assert values["wind.mean"][1:] == [pytest.approx(10.0, rel=1e-14), 0.3]


# ------------------------------------------------------------------- bad input


@pytest.mark.parametrize("axis, message", [
    ("vehicle.spede=1:2:2", "--axis: vehicle.spede=1:2:2: vehicle.spede is not a key of this "
                            "scenario's schema"),
    ("quadrotor.mass=2:1:3", "--axis: quadrotor.mass=2:1:3: LO must be below HI, got 2 and 1"),
    ("quadrotor.mass=1:2:0", "--axis: quadrotor.mass=1:2:0: N must be in [1, 1000], got 0"),
    ("quadrotor.mass=1:2:1.5", "--axis: quadrotor.mass=1:2:1.5: N must be an integer, "
                               "got 1.5"),
    ("quadrotor.mass=1:2:1", "--axis: quadrotor.mass=1:2:1: one value (N = 1) needs LO = HI, "
                             "got 1 and 2"),
    ("quadrotor.mass=a:2:3", "--axis: quadrotor.mass=a:2:3: LO and HI must be numbers, got a "
                             "and 2"),
    ("quadrotor.mass=1:2", "--axis: quadrotor.mass=1:2: expected KEY=LO:HI:N (N values from "
                           "LO to HI)"),
    ("quadrotor.mass=-1:2:2", "--axis: quadrotor.mass=-1:2:2: quadrotor.mass = -1 is outside "
                              "its range [0.001, 10000] kg"),
    ("controller.backend=1:2:2", "--axis: controller.backend=1:2:2: controller.backend holds "
                                 "text, not numbers"),
    ("controller.nominal_model=0:1:2", "--axis: controller.nominal_model=0:1:2: "
                                       "controller.nominal_model holds true or false, "
                                       "not numbers"),
    ("quadrotor.inertia=1:2:2", "--axis: quadrotor.inertia=1:2:2: quadrotor.inertia is a list "
                                "of 3 numbers: name one element, e.g. quadrotor.inertia[0]"),
    ("quadrotor.inertia[3]=1:2:2", "--axis: quadrotor.inertia[3]=1:2:2: quadrotor.inertia has "
                                   "3 elements (0 to 2), not [3]"),
    ("quadrotor.mass[0]=1:2:2", "--axis: quadrotor.mass[0]=1:2:2: quadrotor.mass is a single "
                                "number, not a list"),
    ("wind.over_deck_speed=1:2:2", "--axis: wind.over_deck_speed=1:2:2: wind.over_deck_speed "
                                   "needs a landing scenario (a deck that moves)"),
])
def test_bad_axes_are_one_line_and_write_nothing(tmp_path, capsys, axis, message):
    out = tmp_path / "env"
    status = main(["envelope", "--scenario", "paper", "--axis", axis, "--axis",
                   "controller.k1[0]=3:4:2", "--runs-per-cell", "2", "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and err == [f"quadland: error: {message}"]
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("args, message", [
    (["--axis", "quadrotor.mass=1:2:2"], "--axis: an envelope has two axes (--axis "
                                          "KEY=LO:HI:N twice), got 1"),
    (["--axis", "quadrotor.mass=1:2:2", "--axis", "quadrotor.mass=1:3:2"],
     "--axis: both axes set quadrotor.mass"),
    (["--axis", "quadrotor.mass=1:2:2", "--axis", "vehicle.m11=1:2:2", "--runs-per-cell", "0"],
     "--runs-per-cell: must be in [1, 100000], got 0"),
    (["--axis", "quadrotor.mass=1:2:2", "--axis", "vehicle.m11=1:2:2", "--hold",
      "vehicle.m11"], "--hold: vehicle.m11 is not dispersed by the scenario's [campaign]"),
    (["--axis", "quadrotor.mass=1:2:2", "--axis", "vehicle.m11=1:2:2", "--polar"],
     "--polar: needs exactly one axis of angles in degrees (a key ending in _deg) as the "
     "map's angle"),
    (["--scenario", "ship", "--axis", "wind.over_deck_speed=1:2:2", "--axis",
      "wind.mean[1]=0:1:2"], "--axis: the wind over the deck sets wind.mean[0] and "
                             "wind.mean[1] itself; choose one or the other"),
    (["--axis", "quadrotor.mass=1:2:2", "--axis", "simulation.duration=0:1:2"],
     "--axis: simulation.duration=0:1:2: simulation.duration = 0 is outside its range "
     "[0.001, 100000] s"),
])
def test_bad_envelopes_are_one_line_and_write_nothing(tmp_path, capsys, args, message):
    status = main(["envelope", *([] if "--scenario" in args else ["--scenario", "paper"]),
                   *args, "--out", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and err == [f"quadland: error: {message}"]
    assert os.listdir(tmp_path) == []


def test_a_scenario_without_a_campaign_is_refused(tmp_path, capsys):
    from quadland.scenario import SCENARIO_DIR

    # every shipped scenario has a [campaign] table: turning's file without it
    plain = tmp_path / "plain" / "turning.toml"
    plain.parent.mkdir()
    plain.write_text((SCENARIO_DIR / "turning.toml").read_text().split("\n[campaign]")[0])
    status = main(["envelope", "--scenario", str(plain), "--axis", "quadrotor.mass=1:2:2",
                   "--axis", "wind.mean[1]=0:1:2", "--out", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and len(err) == 1 and "turning has no [campaign] table" in err[0]
    assert os.listdir(tmp_path) == ["plain"]


# ------------------------------------------------------------------- end to end


@pytest.fixture(scope="module")
def whole(tmp_path_factory):
    """A 2 x 2 envelope of 2 runs per cell, flown uninterrupted in this process."""
    out = tmp_path_factory.mktemp("whole") / "env"
    result = run_envelope("paper", FAST, AXES, 2, out, workers=1)
    assert result.complete and result.flown == 8
    return out


def test_a_tiny_envelope_end_to_end(whole):
    rows = _rows(whole)
    header, rows = rows[0], rows[1:]
    assert [int(r[0]) for r in rows] == list(range(8))
    assert [r[1] for r in rows] == ["0", "0", "1", "1", "2", "2", "3", "3"]
    col = {n: k for k, n in enumerate(header)}
    cells = [(r[col["axis.vehicle.tau[0]"]], r[col["axis.controller.k1[0]"]]) for r in rows]
    assert cells[::2] == [("15.0", "3.0"), ("15.0", "4.0"), ("25.0", "3.0"), ("25.0", "4.0")]
    data = json.loads((whole / "envelope.json").read_text())
    assert [a["values"] for a in data["axes"]] == [[15.0, 25.0], [3.0, 4.0]]
    for c, cell in enumerate(data["cells"]):    # counted again here from runs.csv
        mine = [r for r in rows if r[1] == str(c)]
        flown = [r for r in mine if r[col["status"]] != "invalid"]
        k = sum(r[col["success"]] == "true" for r in flown)
        assert (cell["runs"], cell["successes"]) == (len(flown), k)
    assert data["provenance"]["versions"]["casadi"] and data["scenario"] == "paper"
    assert (whole / "envelope.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (whole / "scenario.toml").is_file()


def test_replicate_r_of_a_nominal_cell_is_run_r_of_the_campaign(whole, tmp_path):
    """Common random numbers: cell 0 holds the axes at their nominal values."""
    campaign = tmp_path / "campaign"
    run_campaign("paper", FAST, runs=2, out=campaign, workers=1, plots=False)
    c_rows, e_rows = _rows(campaign), _rows(whole)
    c_col = {n: k for k, n in enumerate(c_rows[0])}
    for r in range(2):
        mine = dict(zip(e_rows[0], e_rows[1 + r], strict=True))
        theirs = c_rows[1 + r]
        for name, k in c_col.items():
            if name != "index":
                assert mine[name] == theirs[k], name


@pytest.mark.parametrize("wrapped", [False, True], ids=["ctrl-c", "ctrl-c-wrapped-by-ctypes"])
def test_an_interrupted_envelope_resumes_to_the_same_bytes(whole, tmp_path, monkeypatch,
                                                           capsys, wrapped):
    from quadland import interrupt

    out = tmp_path / "env"
    calls = []
    real = interrupt.check

    def stop_after_three():
        calls.append(1)
        if len(calls) == 3:
            if wrapped:                         # a serial envelope flies in this process
                ctrl_c_wrapped_by_ctypes()
            raise KeyboardInterrupt
        real()

    monkeypatch.setattr(interrupt, "check", stop_after_three)
    status = main(["envelope", "--scenario", "paper", "--set", FAST[0], "--axis", AXES[0],
                   "--axis", AXES[1], "--runs-per-cell", "2", "--workers", "1", "--out",
                   str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 130 and len(err) == 1
    assert err[0].startswith("quadland: interrupted: 3 of 8 runs recorded in ")
    assert len(_rows(out)) == 1 + 3 and not (out / "envelope.json").exists()
    monkeypatch.setattr(interrupt, "check", real)
    result = run_envelope("paper", FAST, AXES, 2, out, workers=1)
    assert result.flown == 5 and result.complete
    assert (out / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()
    mine, theirs = (json.loads((f / "envelope.json").read_text()) for f in (out, whole))
    for data in (mine, theirs):
        del data["last_session"]
    assert mine == theirs
    again = run_envelope("paper", FAST, AXES, 2, out, workers=1)
    assert again.flown == 0 and again.complete


def _envelope_process(out, axes, k, duration):
    return subprocess.Popen(
        [sys.executable, "-m", "quadland", "envelope", "--axis", axes[0], "--axis", axes[1],
         "--runs-per-cell", str(k), "--out", str(out), "--workers", "2", "--no-plots",
         "--set", f"simulation.duration={duration}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.slow
def test_ctrl_c_on_two_processes_keeps_the_runs_and_the_resume_is_the_same(tmp_path):
    axes, k, duration = ["vehicle.tau[0]=15:25:3", "controller.k1[0]=3:4:3"], 20, 3.0
    whole = tmp_path / "whole"
    run_envelope("paper", [f"simulation.duration={duration}"], axes, k, whole, workers=1,
                 plots=False)
    out = tmp_path / "stopped"
    proc = _envelope_process(out, axes, k, duration)
    end = time.monotonic() + 120
    while not ((out / "runs.csv").exists()
               and (out / "runs.csv").read_bytes().count(b"\n") - 1 >= 20):
        assert proc.poll() is None and time.monotonic() < end, proc.communicate()
        time.sleep(0.005)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("quadland: interrupted: ")
    recorded = len(_rows(out)) - 1
    assert 20 <= recorded < 9 * k and not (out / "envelope.json").exists()
    proc = _envelope_process(out, axes, k, duration)
    text, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert f"flew {9 * k - recorded} runs" in text
    assert (out / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore")
def test_a_dask_cluster_and_two_processes_give_the_same_runs(whole, tmp_path):
    distributed = pytest.importorskip("distributed")
    pool = tmp_path / "pool"
    run_envelope("paper", FAST, AXES, 2, pool, workers=2)
    assert (pool / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None,
                                  silence_logs=50) as cluster:
        out = tmp_path / "dask"
        result = run_envelope("paper", FAST, AXES, 2, out, scheduler=cluster.scheduler_address)
        assert result.complete and result.flown == 8
    assert (out / "runs.csv").read_bytes() == (whole / "runs.csv").read_bytes()
    assert json.loads((out / "envelope.json").read_text())["last_session"]["where"] \
        .startswith("tcp://127.0.0.1:")


def test_a_folder_of_another_envelope_or_a_campaign_is_refused(whole, tmp_path, capsys):
    before = {p.name: p.read_bytes() for p in whole.iterdir()}
    status = main(["envelope", "--scenario", "paper", "--set", FAST[0], "--axis",
                   "vehicle.tau[0]=15:25:3", "--axis", AXES[1], "--runs-per-cell", "2",
                   "--out", str(whole)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and err == [f"quadland: error: --out: {whole} holds another envelope "
                                   "(other axes, runs per cell or held keys); choose a new "
                                   "folder or run what it holds"]
    assert {p.name: p.read_bytes() for p in whole.iterdir()} == before
    campaign = tmp_path / "campaign"
    run_campaign("paper", FAST, runs=2, out=campaign, workers=1, plots=False)
    with pytest.raises(CampaignError, match="holds a campaign; choose a new folder"):
        run_envelope("paper", FAST, AXES, 2, campaign, workers=1)


def test_ctrl_c_is_a_campaign_interrupt():
    assert issubclass(CampaignInterrupted, KeyboardInterrupt)


# ------------------------------------------------------------------------ the map


@pytest.mark.parametrize("polar", [False, True])
def test_the_map_draws_each_cells_interval(polar):
    from quadland.plots.envelope_map import INTERVAL_LW, envelope_map_figure

    values = [np.array([0.0, 10.0, 20.0]), np.array([0.0, 90.0, 180.0, 270.0])]
    n = np.full((3, 4), 10.0)
    n[2, 3] = 0.0                               # a cell without a run: no interval
    k = np.minimum(n, np.arange(12).reshape(3, 4))
    with np.errstate(invalid="ignore"):
        rate = np.where(n > 0, k / np.where(n > 0, n, 1), np.nan)
    lo, hi = np.clip(rate - 0.1, 0, 1), np.clip(rate + 0.1, 0, 1)
    fig = envelope_map_figure(values, rate, lo, hi, k, n, ["speed (m/s)", "direction (deg)"],
                              polar=polar, angle=1 if polar else None)
    ax = fig.axes[0]
    assert (ax.name == "polar") == polar
    black = [ln for ln in ax.lines if ln.get_color() == "k" and ln.get_linewidth() == INTERVAL_LW]
    assert len(black) == 11                     # one interval bar per cell with runs
    assert sorted(t.get_text() for t in ax.texts if "/" in t.get_text()) == \
        sorted(f"{int(k.flat[i])}/10" for i in range(11))


@pytest.mark.slow
def test_a_landing_envelope_counts_false_touchdowns_and_tip_overs(tmp_path, capsys):
    """A landing envelope's cells and totals count the flown runs with each 0/1 flag set,
    as runs.csv has them, and its last line says so (review of issue 17: campaigns and
    envelope cells had only the flags' quantiles)."""
    out = tmp_path / "env"
    assert main(["envelope", "--scenario", "highway", "--axis", "wind.turbulence_w20=0:1:2",
                 "--axis", "quadrotor.mass=2:2:1", "--runs-per-cell", "1", "--workers",
                 "1", "--no-plots", "--out", str(out)]) == 0
    with open(out / "runs.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    env = json.loads((out / "envelope.json").read_text())
    for name in ("false_touchdown", "tipped"):
        by_hand = [sum(float(r[name] or 0) == 1.0 for r in rows if int(r["cell"]) == c)
                   for c in range(2)]
        assert [cell["counts"][name] for cell in env["cells"]] == by_hand
        assert env["counts"][name] == sum(by_hand)
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert (f"; false touchdowns {env['counts']['false_touchdown']}, tipped over "
            f"{env['counts']['tipped']}; flew 2 runs in ") in line

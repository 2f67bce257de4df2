"""Simulation: accuracy against a tighter run, reproducibility, result API."""

import csv
import io

import numpy as np
import pytest

from quadland.engine.result import columns_sidecar
from quadland.kinds.paper.simulate import COLUMNS, TRAJECTORY
from quadland.scenario import load_scenario
from quadland.simulation import simulate

E1 = ("z_e", "phi_e", "theta_e", "psi_e")


@pytest.fixture(scope="module")
def default_run():
    return simulate(load_scenario("paper"))


def test_default_integrator_accuracy(default_run):
    """The default fixed-step RK4 (one step per 10 ms hold) is within 1e-6 m / 1e-6 rad of
    cvodes at 1e-12 over the paper's 10 s (the accuracy stated in docs/simulation.md)."""
    tight = simulate(load_scenario("paper", ["simulation.integrator=\"cvodes\"",
                                             "simulation.reltol=1e-12", "simulation.abstol=1e-12"]))
    for name in E1:
        assert np.abs(default_run[name] - tight[name]).max() < 1e-6, name
    # halving the step cuts the RK4 error by ~16, so the coarse run is not just lucky
    fine = simulate(load_scenario("paper", ["simulation.rk_steps_per_interval=2"]))
    err_coarse = np.abs(default_run["z_e"] - tight["z_e"]).max()
    err_fine = np.abs(fine["z_e"] - tight["z_e"]).max()
    assert err_fine < err_coarse


def test_result_api(default_run):
    t = default_run["t"]
    assert t[0] == 0.0 and t[-1] == pytest.approx(10.0)
    assert len(t) == 1001
    for name, _ in COLUMNS:
        assert default_run[name].shape == t.shape
        assert np.all(np.isfinite(default_run[name]))
    assert set(dict(default_run)) == {n for n, _ in COLUMNS}
    # what a notebook shows: one line, not 57 arrays (1001 rows of 10 s at 100 Hz)
    assert repr(default_run) == (
        f"<SimulationResult of 'paper': 1001 rows over 0..10 s, {len(COLUMNS)} columns "
        f"(list(result)), {default_run.states.shape[1]} states; .to_pandas()>")


def test_initial_relative_state(default_run):
    """e1(0) = [1.5 m, 30, 30, 30 - 15 deg] from the printed initial conditions."""
    np.testing.assert_allclose([default_run[n][0] for n in E1],
                               [1.5, *np.deg2rad([30, 30, 15])], rtol=1e-14)


def test_csv_round_trip(default_run):
    text = default_run.to_csv()
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0][:5] == ["t", "z_e", "phi_e", "theta_e", "psi_e"]
    assert all(name.isidentifier() for name in rows[0])
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (1001, len(COLUMNS))
    np.testing.assert_allclose(data[:, 1], default_run["z_e"], rtol=1e-11, atol=1e-14)


def test_columns_sidecar_gives_every_column_a_unit():
    side = columns_sidecar(TRAJECTORY)["columns"]
    assert [c["name"] for c in side] == [n for n, _ in COLUMNS]
    units = {c["name"]: c["unit"] for c in side}
    assert (units["t"], units["z_e"], units["phi_e"], units["F_1"], units["M_x"]) == \
        ("s", "m", "rad", "N", "N m")
    assert units["u_1"] == "m/s^2" and units["u_2"] == "rad/s^2"
    # the Lyapunov function and the body velocity no longer share a name
    assert "lyapunov_V1" in units and "V1" not in units


def test_seed_fixes_the_noise():
    short = ["simulation.duration=0.5"]
    a = simulate(load_scenario("paper", short))
    b = simulate(load_scenario("paper", short))
    c = simulate(load_scenario("paper", short + ["simulation.seed=7"]))
    np.testing.assert_array_equal(a["z_e"], b["z_e"])
    assert np.abs(a["d_Fx"] - c["d_Fx"]).max() > 0.01
    quiet = simulate(load_scenario("paper", short + ["disturbance.noise=false"]))
    t = quiet["t"]
    np.testing.assert_allclose(quiet["d_Fx"], 0.5 + 0.5 * np.sin(0.2 * t), atol=1e-15)
    np.testing.assert_allclose(quiet["d_Mz"], 0.005 + 0.005 * np.sin(0.01 * t), atol=1e-15)


def test_noise_statistics():
    """The random part is N(0, sigma^2) held per 10 ms sample: check its spread."""
    res = simulate(load_scenario("paper", ["simulation.duration=20"]))
    t = res["t"]
    resid = res["d_Fx"] - (0.5 + 0.5 * np.sin(0.2 * t))
    assert np.std(resid) == pytest.approx(0.05, rel=0.1)
    assert abs(np.mean(resid)) < 0.01


def test_sampled_data_loop_converges_to_continuous():
    """Zero-order hold at 500 Hz stays within 1 cm of the continuous loop in altitude."""
    base = ["simulation.duration=3", "disturbance.noise=false"]
    cont = simulate(load_scenario("paper", base))
    samp = simulate(load_scenario("paper", base + ["controller.rate_hz=500"]))
    assert np.abs(samp["z_e"] - cont["z_e"]).max() < 0.01
    slow = simulate(load_scenario("paper", base + ["controller.rate_hz=100"]))
    assert np.abs(slow["z_e"] - cont["z_e"]).max() > np.abs(samp["z_e"] - cont["z_e"]).max()


def test_vehicle_reaches_its_steady_turn(default_run):
    """r2 -> tau_z / d33 = 5/80 rad/s (eq. 4 with m11 = m22)."""
    assert default_run["r2"][-1] == pytest.approx(5 / 80, rel=1e-3)


def test_simulate_takes_a_name_and_a_landing_imports_no_scipy():
    # issue 20: scipy.signal was most of a second of every landing process's start
    import subprocess
    import sys

    code = ("import sys, quadland\n"
            "r = quadland.simulate('highway')\n"
            "assert r.scenario.name == 'highway'\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'scipy'))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_a_result_is_read_only_and_converts_to_pandas():
    pd = pytest.importorskip("pandas")
    res = simulate(load_scenario("highway", ["simulation.duration=0.2"]))
    with pytest.raises(ValueError, match="read-only"):
        res["z_e"][0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        res.states[0, 0] = 1.0
    with pytest.raises(TypeError):
        res.columns["z_e"] = np.zeros(3)
    frame = res.to_pandas()
    # the CSV's columns, in its order, and its numbers (to the CSV's 12 digits)
    csv_frame = pd.read_csv(io.StringIO(res.to_csv()))
    assert list(frame.columns) == list(csv_frame.columns)
    np.testing.assert_allclose(frame.to_numpy(), csv_frame.to_numpy(), rtol=1e-11, atol=1e-300)
    assert frame.attrs["units"]["z_e"] == "m" and frame.attrs["scenario"] == "highway"
    frame.loc[0, "z_e"] = 5.0                       # a copy: the result is untouched
    assert res["z_e"][0] != 5.0
    # the states' columns are named: the landing loop's plant first
    assert len(res.state_labels) == res.states.shape[1]
    assert res.state_labels[:3] == ("x1", "y1", "z1")
    k = res.state_labels.index("z1")
    np.testing.assert_array_equal(res.states[:, k], res["z1"])
    picked = res.to_pandas(["t", "F_1"])
    assert list(picked.columns) == ["t", "F_1"] and len(picked) == len(res["t"])
    with pytest.raises(KeyError, match="no signal 'nope'"):
        res.to_pandas(["t", "nope"])
    # dict(result) is a plain dict of the same columns (tests/test_result.py: pd.DataFrame)
    assert pd.DataFrame(dict(res)).shape == (len(res["t"]), len(res))


def test_a_scheduler_without_dask_distributed_is_one_line(monkeypatch):
    import builtins

    from quadland.campaign.cluster import connect
    from quadland.exceptions import QuadlandError

    real = builtins.__import__

    def no_distributed(name, *args, **kwargs):
        if name.split(".")[0] == "distributed":
            raise ImportError("No module named 'distributed'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_distributed)
    with pytest.raises(QuadlandError) as err:
        connect("tcp://127.0.0.1:8786")
    assert str(err.value) == ("scheduler: needs the dask.distributed package "
                              "(pip install 'quadland[cluster]')")

"""Figures: each plot function returns a Figure that draws the result's own data."""

import subprocess
import sys

import numpy as np
import pytest
from matplotlib.figure import Figure

import quadland
from quadland.plots import (
    SIMULATION_FIGURES,
    control_inputs_plot,
    ground_track_plot,
    relative_errors_plot,
    simulation_figures,
    uncertainty_plot,
    velocity_errors_plot,
)


@pytest.fixture(scope="module")
def result():
    return quadland.simulate(quadland.load_scenario("paper", ["simulation.duration=0.5"]))


@pytest.fixture(autouse=True)
def _nothing_written(tmp_path, monkeypatch):
    """Drawing writes no file and leaves no pyplot figure behind."""
    monkeypatch.chdir(tmp_path)
    yield
    assert list(tmp_path.iterdir()) == []
    if "matplotlib.pyplot" in sys.modules:
        assert sys.modules["matplotlib.pyplot"].get_fignums() == []


def _data(line):
    return np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)


# simulation


def test_simulation_figures(result):
    figs = simulation_figures(result)
    assert list(figs) == list(SIMULATION_FIGURES)
    for name, fig in figs.items():
        assert isinstance(fig, Figure)
        title = fig.get_suptitle() or fig.axes[0].get_title()
        assert title == SIMULATION_FIGURES[name]
        assert any(t.get_text() == "scenario paper" for t in fig.texts)


@pytest.mark.parametrize("plot, first, rest", [
    (relative_errors_plot, "z_e", ("phi_e", "theta_e", "psi_e")),
    (velocity_errors_plot, "dz_e", ("p_e", "q_e", "r_e")),
])
def test_error_figures_plot_the_columns(result, plot, first, rest):
    fig = plot(result)
    assert isinstance(fig, Figure) and len(fig.axes) == 4
    expected = [result[first]] + [np.rad2deg(result[n]) for n in rest]
    for a, name, y in zip(fig.axes, (first, *rest), expected, strict=True):
        (line,) = a.lines
        x, yy = _data(line)
        np.testing.assert_array_equal(x, result["t"])
        np.testing.assert_allclose(yy, y, rtol=1e-15, atol=0)
        assert a.get_ylabel().startswith(name + " [")
    assert fig.axes[-1].get_xlabel() == "t [s]"
    assert "deg" in fig.axes[1].get_ylabel()


def test_control_inputs_plot(result):
    fig = control_inputs_plot(result)
    assert len(fig.axes) == 4
    for k, a in enumerate(fig.axes, start=1):
        (line,) = a.lines
        np.testing.assert_array_equal(_data(line)[1], result[f"u_{k}"])
        assert a.get_ylabel().startswith(f"u_{k} [")


@pytest.mark.parametrize("nominal", [False, True])
def test_uncertainty_plot(result, nominal):
    res = result if not nominal else quadland.simulate(quadland.load_scenario(
        "paper", ["simulation.duration=0.2", "controller.nominal_model=true"]))
    fig = uncertainty_plot(res)
    assert len(fig.axes) == 4
    for k, a in enumerate(fig.axes, start=1):
        names = [f"Delta_{k}"] + ([f"Delta_target_{k}"] if nominal else []) + [f"Delta_hat_{k}"]
        assert len(a.lines) == len(names)
        for line, name in zip(a.lines, names, strict=True):
            np.testing.assert_array_equal(_data(line)[1], res[name])
        assert a.lines[-1].get_linestyle() == "--"
        # the units of u_k, whose channel Delta_k is (Fig. 4's)
        assert a.get_ylabel() == f"Delta_{k} [{'m/s^2' if k == 1 else 'rad/s^2'}]"
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()][-1] == "W_hat^T Psi"


def test_ground_track_plot(result):
    fig = ground_track_plot(result)
    (a,) = fig.axes
    vehicle, quad, start = a.lines
    np.testing.assert_array_equal(_data(vehicle)[0], result["x2"])
    np.testing.assert_array_equal(_data(vehicle)[1], result["y2"])
    np.testing.assert_array_equal(_data(quad)[0], result["x1"])
    np.testing.assert_array_equal(_data(quad)[1], result["y1"])
    assert _data(start)[0][0] == result["x2"][0] and _data(start)[1][0] == result["y2"][0]


@pytest.mark.slow
def test_import_chooses_no_backend():
    code = ("import matplotlib; matplotlib.use('svg'); import quadland.plots.simulation, "
            "quadland.plots.margins; print(matplotlib.get_backend())")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "svg"


@pytest.mark.parametrize("plot", [relative_errors_plot, velocity_errors_plot,
                                  control_inputs_plot, uncertainty_plot])
def test_two_runs_overlay_on_one_figure(result, plot):
    """``ax=``: a second run drawn into the first one's axes adds one line per axis."""
    other = quadland.simulate(quadland.load_scenario("paper", ["simulation.duration=0.3"]))
    fig = plot(result)
    before = [len(a.lines) for a in fig.axes]
    assert plot(other, ax=fig.axes) is fig
    assert len(fig.axes) == 4
    for a, n in zip(fig.axes, before, strict=True):
        assert len(a.lines) == 2 * n
        np.testing.assert_array_equal(a.lines[n].get_xdata(), other["t"])


@pytest.mark.parametrize("plot", [relative_errors_plot, velocity_errors_plot,
                                  control_inputs_plot, uncertainty_plot])
def test_two_runs_of_one_scenario_keep_their_own_legend_names(result, plot):
    """Two runs of one scenario (other gains, say) overlaid: ``label=`` names each in
    the legend; without it both were the scenario's name, "paper" twice (review of
    issue 21)."""
    other = quadland.simulate(quadland.load_scenario(
        "paper", ["simulation.duration=0.3", "controller.k1=[1.5, 5.0, 10.0, 10.0]"]))
    fig = plot(result, label="k1_z = 3")
    plot(other, ax=fig.axes, label="k1_z = 1.5")
    legends = [a.get_legend() for a in fig.axes if a.get_legend() is not None]
    assert fig.axes[0].get_legend() in legends      # Fig. 5's legend is on its first axis
    for legend in legends:
        names = [t.get_text() for t in legend.get_texts()]
        mine = [n for n in names if "k1_z = 1.5" in n]
        theirs = [n for n in names if "k1_z = 3" in n]
        assert mine and theirs and len(mine) == len(theirs), names
    # by default a run is still named after its scenario
    fig = plot(result)
    plot(other, ax=fig.axes)
    assert any("paper" in t.get_text() for t in fig.axes[0].get_legend().get_texts())


def test_a_labelled_ground_track_overlay(result):
    fig = ground_track_plot(result, label="first")
    ground_track_plot(result, ax=fig.axes[0], label="second")
    labels = [ln.get_label() for ln in fig.axes[0].lines]
    assert labels.count("quadrotor (first)") == 1 and labels.count("quadrotor (second)") == 1


def test_two_ground_tracks_overlay(result):
    fig = ground_track_plot(result)
    assert ground_track_plot(result, ax=fig.axes[0]) is fig
    labels = [ln.get_label() for ln in fig.axes[0].lines]
    assert labels.count("quadrotor") == 1 and labels.count("quadrotor (paper)") == 1


def test_ax_of_the_wrong_count_is_refused(result):
    fig = relative_errors_plot(result)
    with pytest.raises(ValueError, match="4 axes expected, got 2"):
        relative_errors_plot(result, ax=fig.axes[:2])

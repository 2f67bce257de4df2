"""Two landings overlaid on one figure (issue 21): every landing figure takes ``ax=`` and
``label=``, each run's lines carry its label, the legend is drawn again with both, and
each labelled line holds its own run's data."""

import numpy as np
import pytest

import quadland
from quadland.plots import (
    landing_ground_track_plot,
    navigation_plot,
    relative_position_plot,
    rotor_forces_plot,
    trajectory_3d_plot,
)
from quadland.plots.overlay import redraw_legend, run_tag


@pytest.fixture(scope="module")
def runs():
    """The highway landing on its sensors, and the same with other noise draws (seed 7):
    two whole landings, each with its touchdown, their rows at different times."""
    return {"seed 2024": quadland.simulate("highway"),
            "seed 7": quadland.simulate(quadland.load_scenario("highway",
                                                               ["simulation.seed=7"]))}


def _legend(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def _line(ax, label):
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == label]
    return line


def _overlay(plot, runs, **kwargs):
    """The first run's figure with the second drawn into its axes, both labelled."""
    (a, res_a), (b, res_b) = runs.items()
    fig = plot(res_a, label=a, **kwargs)
    target = fig.axes[0] if len(fig.axes) == 1 else fig.axes
    assert plot(res_b, ax=target, label=b, **kwargs) is fig
    return fig


def test_relative_position_and_rotor_forces_overlay(runs):
    limits = {"max_sink_rate": 0.5, "max_offset": 0.2, "max_tilt_deg": 28.0,
              "max_relative_speed": 0.5, "F_max": 14.7}
    fig = _overlay(relative_position_plot, runs, limits=limits)
    for name, res in runs.items():
        t = np.asarray(res["t"])
        for axis, signal, column in ((1, "z_e", res["z_e"]),
                                     (0, "x_e", res["x_e"]),
                                     (3, "tilt from deck normal", res["tilt_deg"]),
                                     (2, "sink rate", -np.asarray(res["dz_e"]))):
            line = _line(fig.axes[axis], f"{signal} ({name})")
            np.testing.assert_array_equal(line.get_xdata(), t)
            np.testing.assert_array_equal(line.get_ydata(), column)
            assert f"{signal} ({name})" in _legend(fig.axes[axis])
    # a limit drawn for each run's touchdown is one legend entry
    assert _legend(fig.axes[2]).count("max_sink_rate") == 1
    assert len([ln for ln in fig.axes[2].get_lines() if ln.get_label() == "max_sink_rate"]) == 2
    fig = _overlay(rotor_forces_plot, runs, limits=limits)
    for name, res in runs.items():
        for k in range(1, 5):
            np.testing.assert_array_equal(_line(fig.axes[0], f"F_{k} ({name})").get_ydata(),
                                          res[f"F_{k}"])
        np.testing.assert_array_equal(_line(fig.axes[1], f"F_total ({name})").get_ydata(),
                                      res["F_total"])
        assert f"F_total ({name})" in _legend(fig.axes[1])
    assert _legend(fig.axes[1]).count("[0, 4 F_max]") == 1


def test_ground_tracks_and_3d_overlay_in_their_own_colours(runs):
    fig = _overlay(landing_ground_track_plot, runs)
    a = fig.axes[0]
    colours = set()
    for name, res in runs.items():
        line = _line(a, f"quadrotor ({name})")
        np.testing.assert_array_equal(line.get_xdata(), res["x1"])
        np.testing.assert_array_equal(line.get_ydata(), res["y1"])
        np.testing.assert_array_equal(_line(a, f"pad centre ({name})").get_xdata(), res["x2"])
        assert {f"quadrotor ({name})", f"quadrotor at touchdown ({name})"} <= set(_legend(a))
        colours.add(line.get_color())
    assert len(colours) == 2
    fig = _overlay(trajectory_3d_plot, runs)
    a = fig.axes[0]
    colours = set()
    for name, res in runs.items():
        line = _line(a, f"quadrotor ({name})")
        x, y, z = line.get_data_3d()
        np.testing.assert_array_equal(x, np.asarray(res["x1"]) - res["x2"])
        np.testing.assert_array_equal(z, np.asarray(res["z1"]) - res["z2"])
        assert f"pad at touchdown ({name})" in _legend(a)
        colours.add(line.get_color())
    assert len(colours) == 2 and _legend(a).count("pad centre") == 1


def test_navigation_overlay(runs):
    fig = _overlay(navigation_plot, runs)
    for name, res in runs.items():
        line = _line(fig.axes[2], f"estimate ({name})")
        # the filter's recorded estimate at new horizon times before touchdown
        t_h = np.asarray(res["t_h"])
        z = np.asarray(res["x_h_p_r_z"])
        keep = np.isfinite(t_h) & (np.asarray(res["phase"]) < 3)
        rows = np.flatnonzero(keep)
        rows = rows[np.r_[True, np.diff(t_h[rows]) > 0]]
        np.testing.assert_array_equal(line.get_xdata(), t_h[rows])
        np.testing.assert_array_equal(line.get_ydata(), z[rows])
        assert {f"estimate ({name})", f"truth ({name})"} <= set(_legend(fig.axes[2]))
    assert len({_line(fig.axes[0], f"estimate ({n})").get_color() for n in runs}) == 2


def test_a_run_alone_keeps_its_plain_labels(runs):
    res = runs["seed 2024"]
    assert run_tag(res, None, own=True) == ""
    assert run_tag(res, None, own=False) == " (highway)"
    assert run_tag(res, "A", own=True) == " (A)"
    fig = relative_position_plot(res)
    assert "z_e" in _legend(fig.axes[1])
    # redraw_legend: one entry per label, the first line of each
    from matplotlib.figure import Figure
    a = Figure().subplots()
    a.plot([0, 1], [0, 1], label="x")
    a.plot([0, 1], [1, 2], label="x")
    a.plot([0, 1], [2, 3], label="y")
    redraw_legend(a)
    assert _legend(a) == ["x", "y"]

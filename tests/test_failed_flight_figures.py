"""Figures of a failed flight: its last rows may be infinite or absurdly large."""

import numpy as np
import pytest

import quadland
from quadland.output import figure_png
from quadland.plots import landing_animation, landing_figures, simulation_figures
from quadland.plots.finite import DRAWABLE_MAX, drawable


class _Diverged:
    """A result whose last rows hold what a diverged flight leaves: huge, then infinite."""

    def __init__(self, result, keep=("t", "phase")):
        self.result, self.scenario, self.keep = result, result.scenario, keep

    def __getitem__(self, name):
        v = np.array(self.result[name])
        if name in self.keep or v.dtype.kind != "f":
            return v
        v[-4:] = [1e150, -1e296, np.inf, np.nan]
        return v


def test_drawable_leaves_out_exactly_the_values_a_figure_cannot_scale():
    class Result:
        scenario = None

        def __getitem__(self, name):
            return {"x": np.array([0.0, -DRAWABLE_MAX, 1.5e100, np.inf, -np.inf, np.nan]),
                    "phase": np.array([0, 1, 2, 3, 4, 4])}[name]

    view = drawable(Result())
    np.testing.assert_array_equal(view["x"], [0.0, -DRAWABLE_MAX, np.nan, np.nan, np.nan,
                                              np.nan])
    np.testing.assert_array_equal(view["phase"], [0, 1, 2, 3, 4, 4])
    assert drawable(view) is view


@pytest.fixture(scope="module")
def landing():
    return quadland.simulate(quadland.load_scenario("highway", ["simulation.duration=0.5"]))


def test_landing_figures_and_animation_of_a_diverged_flight(landing, tmp_path):
    bad = _Diverged(landing)
    with np.errstate(all="raise"):                     # nothing computed on the bad rows
        figs = {name: figure_png(fig) for name, fig in landing_figures(bad).items()}
        gif = landing_animation(bad, tmp_path / "a.gif")
    assert all(png[:8] == b"\x89PNG\r\n\x1a\n" for png in figs.values())
    assert gif.read_bytes()[:6] == b"GIF89a"


def test_the_animation_stops_at_the_last_sane_row(landing, tmp_path):
    """Rows past the first insane one are not drawn: the same file as the flight cut there."""
    n = len(landing["t"])

    class Cut:
        scenario = landing.scenario

        def __getitem__(self, name):
            return np.asarray(landing[name])[: n - 4]

    a = landing_animation(_Diverged(landing), tmp_path / "a.gif").read_bytes()
    b = landing_animation(Cut(), tmp_path / "b.gif").read_bytes()
    assert a == b


def test_simulation_figures_of_a_diverged_flight():
    res = quadland.simulate(quadland.load_scenario("paper", ["simulation.duration=0.2",
                                                             "rbf.nodes=5"]))
    figs = simulation_figures(_Diverged(res))
    assert all(figure_png(f)[:8] == b"\x89PNG\r\n\x1a\n" for f in figs.values())

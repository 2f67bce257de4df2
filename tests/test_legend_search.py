"""quadland.plots.legend_search.best_place: the place matplotlib's own search gives a
``loc="best"`` legend, for axes full of lines, markers, patches, bars and scatters.

The reference is ``Legend._find_best_position`` itself, called on the same legend with
the same box and renderer; whole figures are compared pixel for pixel with matplotlib's
own in ``tests/test_legend_place.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from quadland.plots import legend_search

pytestmark = pytest.mark.skipif(not legend_search.available(),
                                reason="this matplotlib's legend has not what the search reads")


def _axes(seed: int):
    rng = np.random.default_rng(seed)
    fig = Figure(figsize=(4, 3), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(xscale="log" if seed % 3 == 0 else "linear")
    x = np.geomspace(0.01, 100, 300) if seed % 3 == 0 else np.linspace(0, 10, 300)
    for k in range(int(rng.integers(1, 6))):
        y = rng.normal(size=x.size).cumsum() * rng.uniform(0.1, 2)
        if k == 1:
            y[::37] = np.nan                        # vertices that count nowhere
        ax.plot(x, y, label=f"curve {k}", marker="o" if k == 2 else None, markevery=20)
    if seed % 2:
        ax.bar(x[:5], rng.uniform(1, 3, 5), width=0.3, label="bars")
        ax.scatter(x[::30], rng.normal(size=10), label="points")
        ax.add_patch(Circle((x[150], 0.0), 1.5, alpha=0.3, label="disk"))
    if seed % 4 == 1:
        ax.set_xlim(x[40], x[200])                 # vertices outside the view
    legend = ax.legend(loc="best", fontsize="x-small")
    return fig, ax, legend


@pytest.mark.parametrize("seed", range(12))
def test_the_place_is_matplotlibs(seed):
    fig, ax, legend = _axes(seed)
    renderer = fig.canvas.get_renderer()
    fig.canvas.draw()
    box = legend.get_window_extent(renderer)
    for width, height in ((box.width, box.height), (40.0, 25.0), (150.0, 120.0),
                          (ax.bbox.width * 0.9, 30.0)):
        assert (legend_search.best_place(legend, width, height, renderer)
                == legend._find_best_position(width, height, renderer))


def test_an_empty_axes_takes_the_first_place():
    fig = Figure(figsize=(3, 2), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot([], [], label="nothing")
    legend = ax.legend(loc="best")
    renderer = fig.canvas.get_renderer()
    assert (legend_search.best_place(legend, 50.0, 20.0, renderer)
            == legend._find_best_position(50.0, 20.0, renderer))


def test_a_quick_figures_legends_search_with_it(monkeypatch):
    from figure_pixels import drawn_alike

    from quadland.plots import legend_place

    calls = []
    search = legend_place.best_place

    def counted(legend, *args):
        calls.append(legend)
        return search(legend, *args)

    monkeypatch.setattr(legend_place, "best_place", counted)

    def content(fig):
        for a, seed in zip(fig.subplots(1, 2), (1, 4), strict=True):
            rng = np.random.default_rng(seed)
            for k in range(3):
                a.plot(rng.normal(size=200).cumsum(), label=f"curve {k}")
            a.legend(loc="best", fontsize="x-small")
        fig.tight_layout()

    drawn_alike(content, (8.0, 3.0))            # the same pixels as matplotlib's figure
    assert len(calls) >= 2


def test_a_search_set_on_the_legend_is_its_own_at_every_draw():
    """A legend given a search of its own (on the instance) is placed by it, at the first
    draw and the later ones, as on matplotlib's own figure."""
    from figure_pixels import drawn_alike, pixels

    calls = []

    def content(fig):
        ax = fig.add_subplot()
        ax.plot(np.arange(10.0), label="rising")
        legend = ax.legend(loc="best")

        def lower_left(width, height, renderer):
            calls.append(fig)
            return ax.bbox.x0 + 3.0, ax.bbox.y0 + 3.0

        legend._find_best_position = lower_left

    mine = drawn_alike(content, (3.0, 2.0))
    drawn = len([c for c in calls if c is mine])
    assert drawn >= 1
    first = pixels(mine)
    assert np.array_equal(pixels(mine), first)              # drawn again: the same search
    assert len([c for c in calls if c is mine]) > drawn


def test_a_legend_data_without_the_renderer_is_not_searched(monkeypatch):
    """matplotlib 3.8's ``Legend._auto_legend_data`` takes no renderer (pyproject allows
    3.8): there the legend searches as matplotlib does rather than failing in the draw."""
    from matplotlib.legend import Legend

    def data_of_38(self):
        return [], [], []

    monkeypatch.setattr(Legend, "_auto_legend_data", data_of_38)
    assert not legend_search.available()

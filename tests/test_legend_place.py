"""quadland.plots.legend_place: a quick figure's legends placed as matplotlib places them,
each best place searched and each legend packed once per draw, and legends that fit
inside their axes left out of ``tight_layout`` only when that cannot move anything.

Each figure is drawn by matplotlib's own ``Figure`` on its own Agg canvas and by
:func:`quadland.plots.canvas.new_figure`'s, with the same content laid out by
``tight_layout``: the pixels must be equal.
"""

from __future__ import annotations

import numpy as np
from figure_pixels import drawn_alike, pixels
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend import Legend

from quadland.plots.canvas import new_figure
from quadland.plots.legend_place import legends_placed
from quadland.png import PNG_DPI


def _curves(ax, n: int, label: str = "curve") -> None:
    t = np.linspace(0, 1, 300)
    for k in range(n):
        ax.plot(t, np.sin(6 * t + k), label=f"{label} {k}: a label of some length")


def test_legends_inside_outside_and_too_big_draw_matplotlibspixels():
    """Best and fixed places inside the axes; a legend anchored outside its axes (which
    the layout must make room for); one too big for its small axes (it spills out, and
    the layout counts it as matplotlib's does)."""
    def content(fig):
        ax = fig.subplots(2, 2, squeeze=False)
        _curves(ax[0, 0], 3)
        ax[0, 0].legend(fontsize="x-small", loc="best")
        _curves(ax[0, 1], 2)
        ax[0, 1].legend(fontsize="small", loc="upper left")
        _curves(ax[1, 0], 2)
        ax[1, 0].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0))
        _curves(ax[1, 1], 12, "a much longer label, wider than the axes")
        ax[1, 1].legend(loc="best", fontsize="large")
        fig.tight_layout()

    mine = drawn_alike(content, (9, 7))
    assert all(lg.get_in_layout() for lg in (a.get_legend() for a in mine.axes))
    assert all("_find_best_position" not in vars(a.get_legend()) for a in mine.axes)


def test_a_legend_that_fits_is_left_out_of_the_layout_and_one_that_does_not_is_kept():
    fig = new_figure((8, 4))
    small, big = fig.subplots(1, 2)
    _curves(small, 2)
    small.legend(fontsize="x-small", loc="best")
    _curves(big, 15, "a label too long for these axes by far, really far")
    big.legend(loc="best", fontsize="large")
    anchored = fig.add_axes((0.1, 0.1, 0.2, 0.2))
    anchored.plot([0, 1], [0, 1], label="x")
    anchored.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0))
    with legends_placed(fig, layout=True):
        assert not small.get_legend().get_in_layout()
        assert big.get_legend().get_in_layout()
        assert anchored.get_legend().get_in_layout()
    assert small.get_legend().get_in_layout()


def test_the_best_place_is_searched_once_per_draw(monkeypatch):
    calls = []
    search = Legend._find_best_position

    def counted(self, *args):
        calls.append(self)
        return search(self, *args)

    monkeypatch.setattr(Legend, "_find_best_position", counted)

    def content(fig):
        ax = fig.subplots(1, 2)
        for a in ax:
            _curves(a, 3)
            a.legend(fontsize="x-small", loc="best")
        fig.tight_layout()

    theirs = Figure(figsize=(8, 3), dpi=PNG_DPI)
    FigureCanvasAgg(theirs)
    content(theirs)
    calls.clear()
    pixels(theirs)
    assert len(calls) == 4                      # matplotlib: twice per legend per draw
    mine = new_figure((8, 3))
    calls.clear()
    content(mine)
    assert calls == []                          # both fit: left out of the layout
    pixels(mine)
    assert sorted(map(id, calls)) == sorted(id(a.get_legend()) for a in mine.axes)
    calls.clear()
    mine.axes[0].set_xlim(0.5, 1.0)             # another view: searched again
    pixels(mine)
    assert len(calls) == 2


def test_each_legend_is_packed_once_per_draw(monkeypatch):
    """matplotlib packs a legend's rows again for its box, its frame and each level of its
    drawing; a quick figure packs each once per draw, and afresh at the next."""
    from matplotlib.offsetbox import VPacker

    packed = []
    pack = VPacker._get_bbox_and_child_offsets

    def counted(self, renderer):
        packed.append(id(self))
        return pack(self, renderer)

    monkeypatch.setattr(VPacker, "_get_bbox_and_child_offsets", counted)
    fig = new_figure((8, 3))
    for a in fig.subplots(1, 2):
        _curves(a, 3)
        a.legend(fontsize="x-small", loc="best")
    fig.tight_layout()
    boxes = [a.get_legend()._legend_box for a in fig.axes]
    for _ in range(2):
        packed.clear()
        pixels(fig)
        assert len(packed) == len(set(packed))          # each packer (rows, columns) once
        assert {id(b) for b in boxes} <= set(packed)     # and afresh at each draw


def test_an_expanded_legend_under_a_layout_engine_draws_matplotlibspixels():
    """A legend in mode "expand" across the top of its axes, in a figure whose layout
    engine (constrained, tight) runs inside the first draw: the engine packs the legend at
    its old width, then the legend's draw sets the width of the axes it moved, so the
    packing kept from the engine's pass must not be the one drawn."""
    for engine in ("constrained", "tight"):
        def content(fig, engine=engine):
            fig.set_layout_engine(engine)
            for a in fig.subplots(1, 2):
                _curves(a, 3)
                a.legend(loc="lower left", mode="expand", bbox_to_anchor=(0, 1.02, 1, 0.2),
                         ncols=2)

        drawn_alike(content, (8, 5))

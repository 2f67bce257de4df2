"""quadland.plots.tick_clone: an axis's new ticks copied from its first one draw the
pixels matplotlib's own ticks draw, and each copy is a tick of its own.

Each figure is drawn by matplotlib's own ``Figure`` on its own Agg canvas and by
:func:`quadland.plots.canvas.new_figure`'s (whose layouts and draws copy ticks), with
the same content: the pixels must be equal, before and after the ticks' parameters
change.
"""

from __future__ import annotations

import matplotlib.axis
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.plots.canvas import new_figure
from quadland.plots.tick_clone import ticks_cloned
from quadland.png import PNG_DPI


def _pixels(fig) -> np.ndarray:
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba()).copy()


def _content(fig):
    """Many ticks on linear, log and twin axes, styled ticks, labels on both sides,
    rotated labels, grids of both kinds."""
    ax = fig.subplots(2, 2, squeeze=False)
    w = np.logspace(-4, 4, 100)
    ax[0, 0].loglog(w, 1 / (1 + w ** 2))
    ax[0, 0].grid(True, which="both", alpha=0.3)
    ax[0, 1].plot(np.arange(40), np.sin(np.arange(40) / 3))
    ax[0, 1].set_xticks(np.arange(0, 41, 2))
    ax[0, 1].tick_params(axis="x", direction="inout", length=7, width=2, colors="tab:red",
                         labelrotation=45, labelsize=6)
    ax[0, 1].tick_params(axis="y", which="both", labelleft=False, labelright=True,
                         right=True, pad=8)
    ax[0, 1].grid(True, color="tab:green", linestyle="--", linewidth=0.5)
    ax[1, 0].plot([0, 1e5], [-3e-4, 5e-4])
    twin = ax[1, 0].twinx()
    twin.plot([0, 1e5], [10, 1000])
    twin.tick_params(axis="y", direction="in", labelcolor="tab:blue")
    ax[1, 1].bar(["a", "b", "c", "d", "e"], [3, 1, 4, 1, 5])
    ax[1, 1].minorticks_on()
    fig.tight_layout()


def _restyled(fig):
    """Ticks' parameters changed after the ticks were made (they apply to every tick)."""
    for a in fig.axes:
        a.tick_params(axis="both", labelsize=7, color="0.3", length=5)
    fig.axes[0].tick_params(axis="x", labelrotation=30)


def test_cloned_ticks_draw_matplotlibs_pixels():
    theirs = Figure(figsize=(8, 6), dpi=PNG_DPI)
    FigureCanvasAgg(theirs)
    _content(theirs)
    mine = new_figure((8, 6))
    _content(mine)
    assert np.array_equal(_pixels(mine), _pixels(theirs))
    for fig in (theirs, mine):
        _restyled(fig)
        for a in fig.axes:
            a.set_xlim(*a.get_xlim()[::-1])         # a new view: more ticks to make
    assert np.array_equal(_pixels(mine), _pixels(theirs))


def test_ticks_are_cloned_and_only_within_the_context():
    made = []
    original = matplotlib.axis.Tick.__init__

    def counted(self, *args, **kwargs):
        made.append(type(self).__name__)
        original(self, *args, **kwargs)

    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.plot([0, 100], [0, 1])
    matplotlib.axis.Tick.__init__ = counted
    try:
        with ticks_cloned(fig):
            ticks = ax.xaxis.get_major_ticks(12)
        assert made == []                           # every new one a copy of the first
        ax.yaxis.get_major_ticks(12)
        assert len(made) >= 1                       # outside: matplotlib's own
    finally:
        matplotlib.axis.Tick.__init__ = original
    assert "_get_tick" not in vars(ax.xaxis) and "_copy_tick_props" not in vars(ax.yaxis)
    assert len({id(t) for t in ticks}) == 12
    first, copy = ticks[0], ticks[5]
    for name in ("tick1line", "tick2line", "gridline", "label1", "label2"):
        assert getattr(copy, name) is not getattr(first, name)
        assert getattr(copy, name)._callbacks is not getattr(first, name)._callbacks
    # a copy changed alone leaves the first as it was
    size = first.label1.get_fontsize()
    copy.label1.set_fontsize(size * 2)
    assert first.label1.get_fontsize() == size
    copy.tick1line.set_fillstyle("none")
    assert first.tick1line.get_fillstyle() == "full"
    assert copy.tick1line.get_marker() == first.tick1line.get_marker()
    copy.update_position(42.0)
    assert first.get_loc() != 42.0 and copy.get_loc() == 42.0


def test_a_polar_axes_ticks_are_matplotlibs():
    """A polar axes's ticks (ThetaTick, RadialTick) keep transforms of their own that
    each tick moves: they are made by matplotlib, and drawn as its own figure does."""
    def content(fig):
        ax = fig.add_subplot(projection="polar")
        t = np.linspace(0, 2 * np.pi, 60)
        ax.plot(t, 1 + 0.5 * np.cos(3 * t))
        ax.set_rticks([0.5, 1, 1.5])
        fig.tight_layout()

    theirs = Figure(figsize=(4, 4), dpi=PNG_DPI)
    FigureCanvasAgg(theirs)
    content(theirs)
    mine = new_figure((4, 4))
    content(mine)
    assert np.array_equal(_pixels(mine), _pixels(theirs))

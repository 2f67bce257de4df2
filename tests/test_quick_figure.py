"""The margin figures' cuts (issue 20) draw the pixels matplotlib draws.

- :class:`quadland.plots.text_cache.TextCacheRenderer`: each distinct text laid
  out once per process, each font's height metrics read once;
- :func:`quadland.plots.tick_memo.ticks_memoized`: an axis's ticks computed once
  per layout or draw (:class:`quadland.plots.canvas.QuickFigure`).

Each figure is drawn twice, by matplotlib's own ``Figure`` on its own Agg canvas
and by :func:`quadland.plots.canvas.new_figure`'s, with the same content, laid out
by ``tight_layout`` on each: the pixels must be equal, and stay equal when drawn
again (every layout then from the cache).
"""

from __future__ import annotations

import numpy as np
from figure_pixels import drawn_alike, pixels
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.plots import text_cache
from quadland.plots.canvas import QuickFigure, new_figure
from quadland.plots.log_labels import plain_log_labels
from quadland.plots.log_minor import cheap_minor_ticks
from quadland.plots.tick_memo import ticks_memoized
from quadland.png import PNG_DPI


def _content(fig):
    """Shared log axes, an equal aspect (moved when applied), rotated and multi-line text,
    mathtext, superscripts, legends, annotations: what the margin figures hold and more."""
    ax = fig.subplots(2, 2, sharex="col", squeeze=False)
    w = np.logspace(-3, 3, 200)
    for a in ax[:, 0]:
        a.semilogx(w, 20 * np.log10(np.abs(1 / (1j * w + 1))), label="l (others closed)")
        a.grid(True, which="both", alpha=0.3)
        cheap_minor_ticks(a)
        plain_log_labels(a)
        a.legend(fontsize="x-small", loc="best")
    ax[0, 0].set_title("roll loop (others closed)")
    ax[1, 0].set_xlabel("frequency [rad/s]")
    ax[0, 0].set_ylabel("|l| [dB]")
    t = np.linspace(0, 2 * np.pi, 100)
    ax[0, 1].plot(np.cos(t), np.sin(t), "k:", label="unit circle")
    ax[0, 1].set_aspect("equal")
    ax[0, 1].set_title("Nyquist, zoom on -1\nsecond line")
    ax[0, 1].annotate("6 dB", (0.5, 0.2), fontsize="xx-small", rotation=30)
    ax[1, 1].plot([0, 1], [1e4, 2e4])
    ax[1, 1].set_ylabel(r"$\sigma$ [dB], $10^{-2}$")
    ax[1, 1].text(0.5, 1.5e4, "Ms 3.1 dB at 2.05 rad/s", ha="center")
    fig.suptitle("scenario paper")
    fig.tight_layout()


def _theirs() -> np.ndarray:
    fig = Figure(figsize=(8, 6), dpi=PNG_DPI)
    FigureCanvasAgg(fig)
    _content(fig)
    return pixels(fig)


def test_a_quick_figure_draws_matplotlibspixels():
    reference = _theirs()
    text_cache._LAYOUTS.clear()
    text_cache._HEIGHTS.clear()
    for _ in range(2):                          # the second from the text cache
        fig = new_figure((8, 6))
        assert isinstance(fig, QuickFigure)
        assert isinstance(fig.canvas.get_renderer(), text_cache.TextCacheRenderer)
        _content(fig)
        mine = pixels(fig)
        assert mine.shape == reference.shape
        assert np.array_equal(mine, reference)
        assert np.array_equal(pixels(fig), reference)      # drawn again
    assert text_cache._LAYOUTS and text_cache._HEIGHTS       # the caches were used


def test_the_tick_memo_leaves_the_axes_as_matplotlib_made_them():
    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.semilogx([1e-2, 1e2], [0, 1])
    with ticks_memoized(fig):
        first = ax.xaxis._update_ticks()
        assert ax.xaxis._update_ticks() is first            # kept for the same view
        ax.set_xlim(1e-1, 1e1)
        assert ax.xaxis._update_ticks() is not first        # a new view: computed again
    assert "_update_ticks" not in vars(ax.xaxis)
    assert "_get_ticklabel_bboxes" not in vars(ax.yaxis)
    assert ax.xaxis._update_ticks() is not ax.xaxis._update_ticks()     # matplotlib's own


def test_axes_sharing_a_formatter_keep_their_own_offset():
    """Two axes of different widths share x (and its formatters): each keeps the offset
    text and labels matplotlib gives it, though its ticks are computed once a pass."""
    def content(fig):
        grid = fig.add_gridspec(1, 2, width_ratios=[3, 1])
        a = fig.add_subplot(grid[0])
        b = fig.add_subplot(grid[1], sharex=a)
        x = np.linspace(1e5, 1e5 + 3.7, 50)
        a.plot(x, x * 1e-3)
        b.plot(x, -x)
        fig.tight_layout()

    mine = drawn_alike(content, (8, 3))
    assert [a.xaxis.offsetText.get_text() for a in mine.axes] == ["+1e5", "+1e5"]


def test_a_polar_axes_draws_matplotlibspixels():
    """A polar axes (its axes called "theta" and "radius", shared under "x" and "y", as
    ``quadland envelope --polar``'s map has) draws as matplotlib's own figure does."""
    def content(fig):
        ax = fig.add_subplot(projection="polar")
        t = np.linspace(0, 2 * np.pi, 60)
        ax.plot(t, 1 + 0.5 * np.cos(3 * t))
        ax.set_title("wind over the deck")
        fig.tight_layout()

    drawn_alike(content, (4, 4))


def test_a_quick_figure_is_named_a_figure():
    """Its repr is a matplotlib Figure's (a notebook shows it as a cell's result)."""
    theirs = Figure(figsize=(7, 8.2), dpi=PNG_DPI)
    theirs.subplots(2, 2)
    mine = new_figure((7, 8.2))
    mine.subplots(2, 2)
    assert repr(mine) == repr(theirs) == "<Figure size 770x902 with 4 Axes>"

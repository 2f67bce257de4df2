"""quadland.plots.tick_batch: an axis's tick marks and grid lines drawn in batches give the
pixels of matplotlib's own drawing, tick by tick.

Each figure is drawn by matplotlib's own ``Figure`` on its own Agg canvas (every tick
line its own artist) and by :func:`quadland.plots.canvas.new_figure`'s (whose draws
batch them), with the same content: the pixels must be equal. The batches are checked to
be drawn (matplotlib draws no tick line itself), to hold every drawn tick's place, and to
leave nothing on the axes after the draw.
"""

from __future__ import annotations

import matplotlib.lines
import numpy as np
import pytest
from figure_pixels import drawn_alike, pixels
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.plots import tick_batch
from quadland.plots.canvas import new_figure
from quadland.plots.log_minor import cheap_minor_ticks
from quadland.png import PNG_DPI


def _many(fig):
    """Grids of both kinds on linear, log, twin, shared and categorical axes, ticks in, out
    and both, on both sides, dashed and transparent grid lines, rotated labels, an equal
    aspect, more ticks on an axis than one batch holds."""
    ax = fig.subplots(2, 3, squeeze=False)
    w = np.logspace(-4, 4, 100)
    ax[0, 0].loglog(w, 1 / (1 + w ** 2))
    ax[0, 0].grid(True, which="both", alpha=0.3)
    ax[0, 1].plot(np.arange(200), np.sin(np.arange(200) / 9))
    ax[0, 1].set_xticks(np.arange(0, 201, 2))          # 101 ticks: three batches
    ax[0, 1].tick_params(axis="x", direction="inout", length=7, width=2, colors="tab:red",
                         labelsize=3, labelrotation=90)
    ax[0, 1].tick_params(axis="y", which="both", labelleft=False, labelright=True,
                         right=True, left=True, direction="in")
    ax[0, 1].grid(True, color="tab:green", linestyle="--", linewidth=0.5)
    ax[0, 2].plot([0, 1e5], [-3e-4, 5e-4])
    twin = ax[0, 2].twinx()
    twin.semilogy([0, 1e5], [10, 1000])
    twin.grid(True, which="minor", linestyle=":", linewidth=1.5)
    twin.tick_params(axis="y", which="minor", length=4, width=1, direction="inout")
    ax[1, 0].bar(["a", "b", "c", "d", "e"], [3, 1, 4, 1, 5])
    ax[1, 0].minorticks_on()
    ax[1, 0].grid(True, axis="y", which="both", linewidth=3, alpha=0.5)
    ax[1, 0].tick_params(top=True, labeltop=True)
    t = np.linspace(0, 2 * np.pi, 100)
    ax[1, 1].plot(np.cos(t), np.sin(t))
    ax[1, 1].set_aspect("equal")
    ax[1, 1].grid(True)
    ax[1, 2].semilogx(w, np.angle(1 / (1j * w + 1), deg=True))
    ax[1, 2].grid(True, which="both", alpha=0.3)
    cheap_minor_ticks(ax[1, 2])
    fig.tight_layout()


def test_batched_ticks_draw_matplotlibs_pixels(monkeypatch):
    batched = []
    original = tick_batch._batches

    def recorded(axis, renderer):
        out = original(axis, renderer)
        batched.append(out is not None)
        return out

    monkeypatch.setattr(tick_batch, "_batches", recorded)
    drawn_alike(_many, (11, 7))
    assert sum(batched) >= 7 and not all(batched)   # most axes batched, the dense ones not


def test_ticks_too_close_are_drawn_as_matplotlib_draws_them():
    """A log axis's minor grid lines a pixel apart (and a bar chart's wide minor grid
    lines): two of them in one batch would blend as one; the axis draws them one by one."""
    def content(fig):
        ax = fig.subplots()
        ax.loglog([1e-4, 10], [1e-4, 10])
        ax.grid(True, which="both", alpha=0.3)
        fig.tight_layout()

    fig = drawn_alike(content, (3, 5))
    renderer = fig.canvas.get_renderer()
    assert tick_batch._batches(fig.axes[0].yaxis, renderer) is None


def test_ticks_styled_one_by_one_are_drawn_in_runs_of_alike_ones():
    """A few ticks restyled alone (colour, width, visibility, marker fill) cut the batches;
    the pixels are still matplotlib's."""
    def content(fig):
        ax = fig.subplots()
        ax.plot(np.arange(30), np.arange(30) ** 0.5)
        ax.set_xticks(np.arange(0, 31, 3))
        ax.grid(True)
        fig.tight_layout()
        fig.canvas.draw()               # make the ticks, then restyle some of them
        ticks = ax.xaxis.get_major_ticks()
        ticks[2].gridline.set_color("tab:red")
        ticks[3].gridline.set_linewidth(4)
        ticks[5].tick1line.set_visible(False)
        ticks[6].tick1line.set_markeredgewidth(3)
        ticks[7].set_visible(False)
        ax.yaxis.get_major_ticks()[1].tick1line.set_marker(matplotlib.lines.TICKLEFT)

    drawn_alike(content, (6, 4))


def test_matplotlib_draws_no_tick_line_and_the_batches_hold_every_tick():
    fig = new_figure((6, 4))
    ax = fig.subplots()
    ax.plot([0, 10], [0, 100])
    ax.grid(True)
    fig.tight_layout()
    drawn: list = []
    original = matplotlib.lines.Line2D.draw

    def counted(self, renderer):
        drawn.append(self)
        return original(self, renderer)

    matplotlib.lines.Line2D.draw = counted
    try:
        pixels(fig)
    finally:
        matplotlib.lines.Line2D.draw = original
    tick_lines = {id(getattr(t, name)) for axis in (ax.xaxis, ax.yaxis)
                  for t in axis.get_major_ticks() for name in ("gridline", "tick1line")}
    assert not [line for line in drawn if id(line) in tick_lines]
    batches = [line for line in drawn if line not in ax.lines]
    # one grid batch and one mark batch per axis (the second marks are not visible)
    assert len(batches) == 4
    # the batches' vertices: every tick in the view, as matplotlib's locator places it
    for axis, column in ((ax.xaxis, 0), (ax.yaxis, 1)):
        lo, hi = sorted(axis.get_view_interval())
        locs = [v for v in axis.get_majorticklocs() if lo <= v <= hi]
        marks = [b for b in batches if b.get_linestyle() == "None"
                 and b.get_transform() is axis.get_major_ticks()[0].tick1line.get_transform()]
        assert len(marks) == 1
        assert np.array_equal(marks[0].get_xydata()[:, column][~np.isnan(
            marks[0].get_xydata()[:, column])], locs)
    assert not [a for a in (ax.xaxis, ax.yaxis) if "draw" in vars(a)]
    assert not [line for axis in (ax.xaxis, ax.yaxis) for t in axis.get_major_ticks()
                for line in (t.gridline, t.tick1line, t.tick2line) if "draw" in vars(line)]


@pytest.mark.parametrize("kind", ["polar", "svg"])
def test_other_ticks_and_renderers_draw_as_matplotlib_does(kind):
    """A polar axes's ticks are not batched (the same pixels); an SVG has one path per tick
    line, as matplotlib writes it."""
    def content(fig):
        ax = fig.add_subplot(projection="polar" if kind == "polar" else None)
        t = np.linspace(0, 2 * np.pi, 60)
        ax.plot(t, 1 + 0.5 * np.cos(3 * t))
        ax.grid(True)
        fig.tight_layout()

    if kind == "polar":
        drawn_alike(content, (4, 4))
        return
    import io

    svgs = []
    for fig in (Figure(figsize=(4, 4), dpi=PNG_DPI), new_figure((4, 4))):
        if not isinstance(fig.canvas, FigureCanvasAgg):
            FigureCanvasAgg(fig)
        content(fig)
        buf = io.BytesIO()
        fig.savefig(buf, format="svg", metadata={"Date": None})
        svgs.append(buf.getvalue())
    assert svgs[0].count(b"<path") == svgs[1].count(b"<path")


def test_the_batch_limit_keeps_matplotlibs_paths_unsimplified():
    """matplotlib simplifies a path of 128 vertices or more: a batch holds fewer (the 61
    grid lines of an axis in two batches), and the pixels are matplotlib's."""
    assert tick_batch.MAX_VERTICES < 128

    def content(fig):
        ax = fig.subplots()
        ax.plot([0, 600], [0, 1])
        ax.set_xticks(np.arange(0, 601, 10))                # 61 ticks, 20 px apart
        ax.tick_params(axis="x", labelbottom=False)
        ax.grid(True)
        fig.tight_layout()

    drawn: list = []
    original = tick_batch._Batch.draw

    def counted(self, renderer):
        drawn.append((self.kind, len(self.ticks), len(self.xy)))
        return original(self, renderer)

    tick_batch._Batch.draw = counted
    try:
        fig = drawn_alike(content, (14, 3))
    finally:
        tick_batch._Batch.draw = original
    ax = fig.axes[0]
    shown = [v for v in ax.get_yticks() if ax.get_ylim()[0] <= v <= ax.get_ylim()[1]]
    # each axis's grid lines and first marks (its second marks are not visible)
    assert sum(n for _, n, _ in drawn) == 2 * 61 + 2 * len(shown)
    assert len([n for kind, n, _ in drawn if kind == 0 and n > len(shown)]) == 2
    assert max(v for _, _, v in drawn) <= tick_batch.MAX_VERTICES


def _three_d(fig):
    ax = fig.add_subplot(projection="3d")
    t = np.linspace(0, 10, 100)
    ax.plot(np.cos(t), np.sin(t), t)


def _sketched(fig):
    with matplotlib.rc_context({"path.sketch": (1, 100, 2)}):
        ax = fig.subplots()
        ax.plot([0, 1], [0, 1])
        ax.grid(True)


def _axis_filtered(fig):
    ax = fig.subplots()
    ax.plot([0, 10], [0, 10])
    ax.grid(True)
    ax.xaxis.set_agg_filter(lambda image, dpi: (1 - image, 0, 0))


@pytest.mark.parametrize("content", [_three_d, _sketched, _axis_filtered],
                         ids=["3d", "sketch", "axis-filter"])
def test_axes_the_batches_cannot_draw_are_drawn_as_matplotlib_draws_them(content):
    """mplot3d's axes (whose ticks are XTicks placed in its own draw), sketched tick lines
    (their wiggles seeded per path) and an axis with its own filter: matplotlib's pixels."""
    drawn_alike(content, (5, 4))

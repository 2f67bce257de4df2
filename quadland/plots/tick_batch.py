"""An axis's tick marks and grid lines drawn as one line each (:func:`ticks_batched`).

matplotlib draws every tick of an axis as its own artist (``Tick.draw``): its grid line,
its two marks and its two labels, each line a ``Line2D`` drawn with its own graphics
context, path, transform and clip, 0.1 to 0.2 ms each; the margin figures draw about 280
ticks, 560 of these lines. Within :func:`ticks_batched`, on an Agg renderer, an axis
first draws the grid lines of all the ticks it draws as one line (the same style: one
copy of the first tick's grid line holding every tick's segment, the segments separated
by a NaN), then their first marks as one line of markers, then their second marks; then
matplotlib's own ``Axis.draw`` draws the axis with these lines left out (the labels, the
axis's label and offset text).

The pixels are those of matplotlib's drawing (``tests/test_tick_batch.py``): Agg draws a
line's markers one at a time at each of its vertices, as it draws a one-vertex line's; a
line's NaN vertices become moves, so that its segments are stroked as separate lines,
snapped to pixels as each is when drawn alone (vertical or horizontal segments, fewer
than 128 vertices a line, under which matplotlib does not simplify a path); and the
segments of different ticks cover different pixels, so that the order in which they are
blended does not matter. Ticks whose lines differ in any attribute but their data are
drawn in groups of alike ones; an axis that is not matplotlib's ``XAxis`` or ``YAxis``
(mplot3d's place their ticks' lines in their own draw), or is rasterized or filtered, an
axis whose ticks are not matplotlib's ``XTick`` and ``YTick``, or are rasterized or
filtered, or whose lines are sketched or have path effects, and every renderer but Agg's,
draw as matplotlib draws them.
"""

from __future__ import annotations

import contextlib

import numpy as np
from matplotlib.axis import XAxis, XTick, YAxis, YTick
from matplotlib.backends.backend_agg import RendererAgg
from matplotlib.lines import Line2D

from quadland.plots.tick_clone import clone_artist

__all__ = ["ticks_batched", "MAX_VERTICES"]

#: A tick's lines, in the order ``Tick.draw`` draws them (before its labels).
_LINES = ("gridline", "tick1line", "tick2line")

#: Vertices of one batched line, under matplotlib's path simplification threshold (128).
MAX_VERTICES = 127

#: A line's attributes that hold its data (or what is made from it), not its style.
_DATA = frozenset({"_x", "_y", "_xy", "_xorig", "_yorig", "_x_filled", "_path",
                   "_transformed_path", "_invalidx", "_invalidy", "_subslice", "_stale",
                   "_callbacks", "_sticky_edges", "ind_offset", "_marker"})


def _same(a, b) -> bool:
    """Equal values: the same object, or equal numbers, strings, arrays and sequences of
    such (any other object only when it is the same)."""
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and bool(np.array_equal(a, b))
    if isinstance(a, list | tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, int | float | str | bytes | complex):
        return a == b
    return False


def _marker_style(line) -> tuple:
    m = line._marker
    user = m.get_user_transform()
    return (m.get_marker(), m.get_fillstyle(), m.get_joinstyle(), m.get_capstyle(),
            None if user is None else tuple(user.get_matrix().ravel()))


def _alike(a, b) -> bool:
    """Whether two lines differ in nothing but their data."""
    da, db = a.__dict__, b.__dict__
    if da.keys() != db.keys():
        return False
    for key, value in da.items():
        other = db[key]
        if value is not other and key not in _DATA and not _same(value, other):
            return False
    return _marker_style(a) == _marker_style(b)


def _batchable(line) -> bool:
    # a sketch's wiggles are seeded per path and a path effect strokes the whole batch
    return (type(line) is Line2D and line.get_drawstyle() == "default"
            and line.get_markevery() is None and not line.get_rasterized()
            and line.get_agg_filter() is None and line.get_sketch_params() is None
            and not line.get_path_effects())


def _runs(lines: list) -> list[list[int]] | None:
    """Runs of alike lines' indices, each at most :data:`MAX_VERTICES` vertices with the
    NaNs between them (None if a line cannot be batched)."""
    runs: list[list[int]] = []
    size = 0
    for i, line in enumerate(lines):
        if not _batchable(line):
            return None
        n = len(line.get_xydata())
        if runs and _alike(lines[runs[-1][0]], line) and size + 1 + n <= MAX_VERTICES:
            runs[-1].append(i)
            size += 1 + n
        else:
            runs.append([i])
            size = n
    return runs


def _drawn(style: str) -> bool:
    return style not in ("None", "none", "", " ")


def _margin(line, renderer) -> float:
    """Pixels around a line's vertices that its drawing may touch: a marker's size and
    edge, half the line's width, a pixel of antialiasing and one of snapping."""
    margin = 0.0
    if line.get_marker() is not None and _drawn(str(line.get_marker())):
        margin = renderer.points_to_pixels(line.get_markersize() + line.get_markeredgewidth())
    if _drawn(line.get_linestyle()):
        margin = max(margin, renderer.points_to_pixels(line.get_linewidth()) / 2)
    return margin + 2.0


class _Batch:
    """One run of alike lines of one kind (0 grid, 1 first marks, 2 second marks): their
    vertices with a NaN between lines, and each line's box in pixels."""

    def __init__(self, lines: list, run: list[int], kind: int, renderer):
        self.first, self.kind, self.ticks = lines[run[0]], kind, run
        parts = [lines[i].get_xydata() for i in run]
        gap = np.full((1, 2), np.nan)
        self.xy = np.concatenate([p for part in parts for p in (gap, part)][1:])
        pixels = self.first.get_transform().transform(self.xy)
        margin = _margin(self.first, renderer)
        ends = np.cumsum([len(part) + 1 for part in parts])
        self.boxes = np.array([[*np.nanmin(pixels[e - len(p) - 1:e - 1], axis=0) - margin,
                                *np.nanmax(pixels[e - len(p) - 1:e - 1], axis=0) + margin]
                               for p, e in zip(parts, ends, strict=True)])

    def draw(self, renderer) -> None:
        batch = clone_artist(self.first)
        batch.stale_callback = None
        batch.set_data(self.xy[:, 0], self.xy[:, 1])
        batch.draw(renderer)


def _label_boxes(axis, ticks: list, drawn: list, renderer) -> tuple[np.ndarray, list]:
    """The drawn ticks' visible labels' boxes (pixels, 3 around) and their ticks' indices."""
    boxes, owners = [], []
    for side, extents in zip(("label1", "label2"),
                             axis._get_ticklabel_bboxes(ticks, renderer), strict=True):
        shown = [t for t in ticks if getattr(t, side).get_visible()]
        for tick, box in zip(shown, extents, strict=True):
            if id(tick) in drawn:
                boxes.append([box.x0 - 3, box.y0 - 3, box.x1 + 3, box.y1 + 3])
                owners.append(drawn[id(tick)])
    return np.array(boxes).reshape(-1, 4), owners


def _apart(batches: list, labels: np.ndarray, label_owners: list) -> bool:
    """Whether no two ticks' lines, nor a tick's line and another's label, may touch a
    common pixel (the order of their drawing then does not matter); two ticks' marks of
    one kind and two labels may: they are drawn one after the other as before."""
    visible = [b for b in batches if b.first.get_visible()]
    boxes = np.concatenate([b.boxes for b in visible] + [labels])
    owner = np.concatenate([np.asarray(b.ticks) for b in visible] + [np.asarray(label_owners,
                                                                                dtype=int)])
    kind = np.concatenate([np.full(len(b.ticks), b.kind) for b in visible]
                          + [np.full(len(labels), 3)])
    x0, y0, x1, y1 = (boxes[:, k] for k in range(4))
    touch = ((x0[:, None] < x1[None, :]) & (x0[None, :] < x1[:, None])
             & (y0[:, None] < y1[None, :]) & (y0[None, :] < y1[:, None]))
    alike_kind = (kind[:, None] == kind[None, :]) & (kind[:, None] > 0)
    return not (touch & (owner[:, None] != owner[None, :]) & ~alike_kind).any()


def _skip(renderer) -> None:
    """A tick line's draw while its axis's batch has drawn it."""


def _batches(axis, renderer) -> list | None:
    """The batches of the axis's drawn ticks' lines, or None where they cannot be drawn
    so (module docstring)."""
    ticks = axis._update_ticks()
    shown = [t for t in ticks if t.get_visible()]
    if not all(type(t) in (XTick, YTick) and not t.get_rasterized()
               and t.get_agg_filter() is None for t in shown):
        return None
    batches = []
    for kind, name in enumerate(_LINES):
        lines = [getattr(t, name) for t in shown]
        runs = _runs(lines)
        if runs is None:
            return None
        batches += [_Batch(lines, run, kind, renderer) for run in runs]
    labels, owners = _label_boxes(axis, ticks, {id(t): i for i, t in enumerate(shown)},
                                  renderer)
    return batches if _apart(batches, labels, owners) else None


def _batch_on(axis) -> None:
    draw = axis.draw

    def draw_axis(renderer):
        # another axis class (mplot3d's) places its ticks' lines in its own draw; an
        # axis's own filter or rasterization wraps matplotlib's draw only
        if (not axis.get_visible() or not isinstance(renderer, RendererAgg)
                or type(axis) not in (XAxis, YAxis) or axis.get_agg_filter() is not None
                or axis.get_rasterized()):
            return draw(renderer)
        batches = _batches(axis, renderer)
        if batches is None:
            return draw(renderer)
        for batch in batches:
            if batch.first.get_visible():
                batch.draw(renderer)
        lines = [getattr(t, name) for t in axis._update_ticks() if t.get_visible()
                 for name in _LINES]
        for line in lines:
            line.draw = _skip
        try:
            return draw(renderer)
        finally:
            for line in lines:
                line.__dict__.pop("draw", None)

    axis.draw = draw_axis


@contextlib.contextmanager
def ticks_batched(fig):
    """Within the context, the axes of ``fig`` draw their ticks' lines in batches on an Agg
    renderer (module docstring).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Its axes (not those of its subfigures); the ticks must not change within a draw
        (:func:`quadland.plots.tick_memo.ticks_memoized` keeps them).
    """
    axes = [axis for ax in fig.axes for axis in getattr(ax, "_axis_map", {}).values()]
    for axis in axes:
        _batch_on(axis)
    try:
        yield
    finally:
        for axis in axes:
            axis.__dict__.pop("draw", None)

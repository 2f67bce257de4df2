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
drawn in groups of alike ones; an axis whose ticks are not matplotlib's ``XTick`` and
``YTick``, or are rasterized or filtered, and every renderer but Agg's, draw as matplotlib
draws them.
"""

from __future__ import annotations

import contextlib

import numpy as np
from matplotlib.axis import XTick, YTick
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
    return (da.keys() == db.keys()
            and all(_same(da[k], db[k]) for k in da if k not in _DATA)
            and _marker_style(a) == _marker_style(b))


def _batchable(line) -> bool:
    return (type(line) is Line2D and line.get_drawstyle() == "default"
            and line.get_markevery() is None and not line.get_rasterized()
            and line.get_agg_filter() is None)


def _groups(lines: list) -> list[list] | None:
    """Runs of alike lines, each at most :data:`MAX_VERTICES` vertices with its NaNs."""
    groups: list[list] = []
    size = 0
    for line in lines:
        if not _batchable(line):
            return None
        n = len(line.get_xydata())
        if groups and _alike(groups[-1][0], line) and size + 1 + n <= MAX_VERTICES:
            groups[-1].append(line)
            size += 1 + n
        else:
            groups.append([line])
            size = n
    return groups


def _draw_group(lines: list, renderer) -> None:
    if not lines[0].get_visible():
        return
    gap = np.full((1, 2), np.nan)
    xy = np.concatenate([part for line in lines for part in (gap, line.get_xydata())][1:])
    batch = clone_artist(lines[0])
    batch.stale_callback = None
    batch.set_data(xy[:, 0], xy[:, 1])
    batch.draw(renderer)


def _skip(renderer) -> None:
    """A tick line's draw while its axis's batch has drawn it."""


def _batch_on(axis) -> None:
    draw = axis.draw

    def draw_axis(renderer):
        if not axis.get_visible() or not isinstance(renderer, RendererAgg):
            return draw(renderer)
        ticks = [t for t in axis._update_ticks() if t.get_visible()]
        if not all(type(t) in (XTick, YTick) and not t.get_rasterized()
                   and t.get_agg_filter() is None for t in ticks):
            return draw(renderer)
        batches = [_groups([getattr(t, name) for t in ticks]) for name in _LINES]
        if any(groups is None for groups in batches):
            return draw(renderer)
        for groups in batches:
            for group in groups:
                _draw_group(group, renderer)
        lines = [getattr(t, name) for t in ticks for name in _LINES]
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

"""An axis's new ticks copied from its first one (:func:`ticks_cloned`).

An axis makes a ``Tick`` for each location its locator returns: a new ``XTick`` or
``YTick`` (two tick lines, a grid line and two labels, each an artist built from the
rc parameters: 0.27 ms here), then given its first tick's properties
(``Axis._copy_tick_props``: each artist's ``update_from``, each tick line's marker
deep-copied). The margin figures make 368 of them, 0.1 to 0.15 s of CPU. Within
:func:`ticks_cloned`, a new tick is a copy of the axis's first tick instead: each of its
six artists a new object holding the first one's attributes, with its own callbacks,
path effects, font properties and marker, which is what the new tick would be after
``_copy_tick_props`` (each drawn tick's place and label are set afterwards, as
matplotlib does for every tick).

The first tick of an axis is still made by matplotlib, and so is every tick of an axis
whose ticks are not matplotlib's own ``XTick`` and ``YTick`` (a polar axis's move
transforms of their own in place) or whose first tick holds something a copy would share
(a label's box patch). The same
pixels as matplotlib's ticks (``tests/test_tick_clone.py``).
"""

from __future__ import annotations

import contextlib
import copy

from matplotlib import cbook
from matplotlib.axis import XTick, YTick
from matplotlib.lines import Line2D
from matplotlib.text import Text

__all__ = ["ticks_cloned", "clone_artist"]

#: The instance attributes set on each axis for the context (removed after it).
_CLONING = ("_get_tick", "_copy_tick_props")

#: A tick's artists, each copied.
_PARTS = ("tick1line", "tick2line", "gridline", "label1", "label2")


def _copy_marker(marker):
    new = copy.copy(marker)
    function = getattr(marker, "_marker_function", None)
    if function is not None:            # bound to the original: bind it to the copy
        new._marker_function = getattr(new, function.__name__)
    return new


def clone_artist(artist):
    """A new artist of ``artist``'s type holding its attributes (its parent's stale callback
    too), with its own callbacks, path effects, sticky edges, font properties (a text)
    and marker (a line)."""
    new = object.__new__(type(artist))
    new.__dict__.update(artist.__dict__)
    new._callbacks = cbook.CallbackRegistry(signals=["pchanged"])
    new._path_effects = list(artist._path_effects)
    if isinstance(artist, Text):
        new._fontproperties = artist._fontproperties.copy()
    if isinstance(artist, Line2D):
        new._marker = _copy_marker(artist._marker)
    sticky = artist.__dict__.get("_sticky_edges")
    if sticky is not None:
        new._sticky_edges = type(sticky)(list(sticky.x), list(sticky.y))
    return new


def _cloneable(tick) -> bool:
    parts = [getattr(tick, name, None) for name in _PARTS]
    # only matplotlib's own XTick and YTick: a polar axis's ticks keep transforms of
    # their own that each tick moves in place
    return (type(tick) in (XTick, YTick)
            and all(type(p) is Line2D for p in parts[:3])
            and all(type(p) is Text and p._bbox_patch is None for p in parts[3:]))


def _clone_tick(tick):
    new = clone_artist(tick)
    for name in _PARTS:
        setattr(new, name, clone_artist(getattr(tick, name)))
    return new


def _clone_on(axis) -> None:
    make, copy_props = axis._get_tick, axis._copy_tick_props
    made = []       # the (first tick, its copy) just made, for _copy_tick_props to skip

    def get_tick(major):
        ticks = axis.__dict__.get("majorTicks" if major else "minorTicks")
        if not ticks or not _cloneable(ticks[0]):
            return make(major=major)
        tick = _clone_tick(ticks[0])
        made[:] = [(ticks[0], tick)]
        return tick

    def copy_tick_props(src, dest):
        if made and made[0][0] is src and made[0][1] is dest:
            made.clear()                # a copy of src already
            return
        copy_props(src, dest)

    axis._get_tick, axis._copy_tick_props = get_tick, copy_tick_props


@contextlib.contextmanager
def ticks_cloned(fig):
    """Within the context, the axes of ``fig`` make their new ticks by copying their
    first tick (module docstring).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Its axes (not those of its subfigures).
    """
    axes = [axis for ax in fig.axes for axis in getattr(ax, "_axis_map", {}).values()]
    for axis in axes:
        _clone_on(axis)
    try:
        yield
    finally:
        for axis in axes:
            for name in _CLONING:
                axis.__dict__.pop(name, None)

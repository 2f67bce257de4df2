"""Each axis's ticks computed once per layout or draw of a figure (:func:`ticks_memoized`).

In one ``tight_layout`` or one draw, matplotlib asks each axis for its ticks
(``Axis._update_ticks``: the locator, the formatter, every tick moved and
relabelled) and for their labels' boxes five to seven times: for the axis's
box, its label's place, its offset text, the title's place, the draw itself.
Nothing they depend on changes within the pass except the axes' place (an
``equal`` aspect moves it when applied), so the first answer is kept for the
pass, by the axis's view limits and its axes' box and the figure's resolution,
and every later call with the same ones returns it (and sets the formatters,
which axes sharing the axis share, back to this axis's ticks, as computing them
again would). Outside the context the axes are as matplotlib made them.
"""

from __future__ import annotations

import contextlib

__all__ = ["ticks_memoized"]

#: The instance attributes set on each axis for the pass (removed after it).
_MEMOIZED = ("_update_ticks", "_get_ticklabel_bboxes")


def _pass_key(axis) -> tuple:
    return (tuple(axis.get_view_interval()), tuple(axis.axes.bbox.bounds),
            axis.axes.get_figure(root=True).dpi)


def _computed(axis, update) -> tuple[list, list]:
    """``update()`` and each ``(formatter, locs)`` it set, in order."""
    formatters = {id(t.formatter): t.formatter for t in (axis.major, axis.minor)}.values()
    given: list = []
    for formatter in formatters:
        def set_locs(locs, formatter=formatter):
            given.append((formatter, locs))
            type(formatter).set_locs(formatter, locs)

        formatter.set_locs = set_locs
    try:
        return update(), given
    finally:
        for formatter in formatters:
            formatter.__dict__.pop("set_locs", None)


def _memoize(axis, name: str) -> None:
    update, boxes = axis._update_ticks, axis._get_ticklabel_bboxes
    # the axes' own name of the axis ("x", "y", "z"): a polar axis calls itself "theta"
    # or "radius", shared under "x" or "y"
    shared = axis.axes._shared_axes.get(name)
    siblings = shared.get_siblings(axis.axes) if shared is not None else [axis.axes]
    kept: dict = {}

    def update_ticks():
        key = _pass_key(axis)
        if kept.get("ticks", (None,))[0] != key:
            ticks, given = _computed(axis, update)
            kept["ticks"] = (key, ticks, given)
            return ticks
        if len(siblings) > 1:
            # axes sharing this axis share its formatters: set them for this axis's
            # ticks again, as computing them again would (its offset text reads them)
            for formatter, locs in kept["ticks"][2]:
                formatter.set_locs(locs)
        return kept["ticks"][1]

    def ticklabel_bboxes(ticks, renderer):
        key = (_pass_key(axis), id(ticks), id(renderer))
        hit = kept.get("boxes")
        if hit is None or hit[0] != key or hit[1] is not ticks:
            kept["boxes"] = hit = (key, ticks, boxes(ticks, renderer))
        return hit[2]

    axis._update_ticks, axis._get_ticklabel_bboxes = update_ticks, ticklabel_bboxes


@contextlib.contextmanager
def ticks_memoized(fig):
    """Within the context, each axis of ``fig`` computes its ticks and their labels' boxes
    once per view and place (module docstring).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Its axes (not those of its subfigures) are memoized; nothing else may change
        their ticks, locators or formatters within the context.
    """
    named = [(name, axis) for ax in fig.axes for name, axis in getattr(ax, "_axis_map", {}).items()]
    axes = [axis for _, axis in named]
    for name, axis in named:
        _memoize(axis, name)
    try:
        yield
    finally:
        for axis in axes:
            for name in _MEMOIZED:
                axis.__dict__.pop(name, None)

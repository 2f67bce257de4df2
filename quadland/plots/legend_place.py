"""Each legend of a figure placed once per layout or draw (:func:`legends_placed`).

A legend at ``loc="best"`` tries each of its nine places against every line, patch
and text of its axes (``Legend._find_best_position``). matplotlib asks for the place
once in a ``tight_layout`` (the legend's box, for the axes' tight box) and twice in a
draw (the frame's box, then the entries' offset): twelve such legends in highway's
margin figures, each search a few thousand vertex counts.

Within :func:`legends_placed`, a legend searches its place with its vertices counted at
once (:func:`quadland.plots.legend_search.best_place`: the same place) and keeps it for
the pass, by its size,
the renderer, its axes' box and view limits (what the search reads besides the
artists, which do not change within a pass), and each packer of its entries (the rows
and columns of handles and texts, ``VPacker`` and ``HPacker``) keeps its box and its
children's offsets for the renderer and its own width and height (which a legend in
mode "expand" sets in its draw): matplotlib packs a legend again for its box, for its
frame and for each level of its entries' drawing, five times per draw. With ``layout=True`` (a
``tight_layout``) a legend placed inside its axes whose box fits within them (less
the border pad on each side, where every inside place puts it) is left out of the
layout: its box is within the axes' box, which the layout counts anyway, so the
layout is the same without searching its place. Outside the context the legends
are as matplotlib made them.
"""

from __future__ import annotations

import contextlib

from matplotlib.legend import Legend
from matplotlib.offsetbox import HPacker, VPacker

from quadland.plots.legend_search import available, best_place

__all__ = ["legends_placed"]

_OWN_SEARCH = available()
#: matplotlib's search, as imported: a legend class (or a test) with its own keeps it.
_MATPLOTLIBS_SEARCH = getattr(Legend, "_find_best_position", None)


def _legends(fig) -> list:
    return [ax.legend_ for ax in fig.axes if getattr(ax, "legend_", None) is not None]


def _search(legend):
    """The legend's search for its best place: :func:`~quadland.plots.legend_search.best_place`
    where matplotlib's own search is the legend's, else the legend's."""
    # the bound method's function: a legend's own (its class's, or one set on it) is kept
    own = getattr(legend._find_best_position, "__func__", None)
    if _OWN_SEARCH and own is not None and own is _MATPLOTLIBS_SEARCH:
        return lambda width, height, renderer: best_place(legend, width, height, renderer)
    return legend._find_best_position


def _memoize(legend) -> None:
    search = _search(legend)
    kept: dict = {}

    def best_position(width, height, renderer):
        ax = legend.axes
        key = (width, height, id(renderer), tuple(ax.bbox.bounds), tuple(ax.viewLim.bounds))
        if kept.get("key") != key:
            kept["key"], kept["place"] = key, search(width, height, renderer)
        return kept["place"]

    legend._find_best_position = best_position


def _packers(box) -> list:
    """The ``VPacker`` and ``HPacker`` boxes of a legend's box, itself included."""
    found = [box] if type(box) in (VPacker, HPacker) else []
    for child in box.get_children():
        found += _packers(child)
    return found


def _memoize_packing(packer) -> None:
    pack = packer._get_bbox_and_child_offsets
    kept: dict = {}

    def packed(renderer):
        # the box's own width and height too: a legend in mode "expand" sets them in its
        # draw, after a layout engine (constrained, tight) packed it within the same draw
        key = (id(renderer), renderer.dpi, packer.width, packer.height)
        if kept.get("key") != key:
            kept["key"], kept["packed"] = key, pack(renderer)
        bbox, offsets = kept["packed"]
        return bbox.frozen(), list(offsets)

    packer._get_bbox_and_child_offsets = packed


def _inside(legend, renderer) -> bool:
    """Whether the legend is placed at one of its axes' inside places and fits there."""
    ax = legend.axes
    if (ax is None or not isinstance(legend._loc, int) or legend._mode is not None
            or legend.get_bbox_to_anchor() is not ax.bbox):
        return False
    pad = 2 * legend.borderaxespad * renderer.points_to_pixels(legend._fontsize)
    box = legend._legend_box.get_bbox(renderer)
    return box.width <= ax.bbox.width - pad and box.height <= ax.bbox.height - pad


@contextlib.contextmanager
def legends_placed(fig, layout: bool = False):
    """Within the context, each legend of ``fig``'s axes searches its best place once per
    size and view, and with ``layout`` those that fit inside their axes are left out of
    the layout (module docstring).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Its axes' legends (not those of its subfigures, nor figure legends).
    layout : bool
        The context is a ``tight_layout``.
    """
    legends = _legends(fig)
    packers = [p for legend in legends for p in _packers(legend._legend_box)]
    # what a legend or packer had set on itself, restored after the context
    set_before = [(obj, name, obj.__dict__[name])
                  for objs, name in ((legends, "_find_best_position"),
                                     (packers, "_get_bbox_and_child_offsets"))
                  for obj in objs if name in obj.__dict__]
    for legend in legends:
        _memoize(legend)
    for packer in packers:
        _memoize_packing(packer)
    left_out = []
    try:
        if layout and legends:
            renderer = fig.canvas.get_renderer()
            left_out = [lg for lg in legends if lg.get_in_layout() and _inside(lg, renderer)]
            for legend in left_out:
                legend.set_in_layout(False)
        yield
    finally:
        for legend in left_out:
            legend.set_in_layout(True)
        for legend in legends:
            legend.__dict__.pop("_find_best_position", None)
        for packer in packers:
            packer.__dict__.pop("_get_bbox_and_child_offsets", None)
        for obj, name, value in set_before:
            setattr(obj, name, value)

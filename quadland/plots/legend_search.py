"""A ``loc="best"`` legend's place, its vertex counts in one array (:func:`best_place`).

matplotlib scores each of a legend's nine inside places by what the legend's box would
cover in its axes: the line and patch vertices strictly inside the box, the collections'
offsets inside it, the patches' boxes it overlaps and the lines its edges cross, and
takes the lowest score (the first place on a tie, the first place scoring zero at
once). It counts the vertices line by line, one NumPy call per line and place: about
1,600 small counts for highway's twelve such legends, a few microseconds of work each
behind tens of microseconds of call overhead.

:func:`best_place` scores the same places by the same counts, in matplotlib's order and
with its tie rule, reading the same data (``Legend._auto_legend_data``) and the same
boxes (``Legend._get_anchored_bbox``): only the vertex and offset counts are made on all
the vertices at once, a sum of the same integers. The crossings and overlaps are
matplotlib's own calls. Where this matplotlib's legend lacks these methods,
:func:`best_place` is None and the legend searches as matplotlib does.
"""

from __future__ import annotations

import inspect

import numpy as np
from matplotlib.legend import Legend
from matplotlib.transforms import Bbox

__all__ = ["best_place", "available"]


def _parameters(function) -> tuple:
    try:
        return tuple(inspect.signature(function).parameters)
    except (TypeError, ValueError):
        return ()


def available() -> bool:
    """Whether this matplotlib's legend has what :func:`best_place` reads, as it is called
    here (``_auto_legend_data`` takes the renderer from matplotlib 3.9 on: 3.8's takes
    none, and its texts are not among the data)."""
    return (all(hasattr(Legend, name) for name in
                ("_auto_legend_data", "_get_anchored_bbox", "codes", "get_bbox_to_anchor"))
            and _parameters(Legend._auto_legend_data) == ("self", "renderer")
            and _parameters(Legend._get_anchored_bbox) == (
                "self", "loc", "bbox", "parentbbox", "renderer"))


def _points(lines, offsets) -> np.ndarray:
    """Every line's vertices and every offset, one (n, 2) array of float."""
    parts = [np.asarray(line.vertices, dtype=float).reshape(-1, 2) for line in lines]
    parts.append(np.asarray(offsets, dtype=float).reshape(-1, 2))
    return np.concatenate(parts)


def best_place(legend, width: float, height: float, renderer) -> tuple[float, float]:
    """The lower left corner, pixels, of ``legend``'s best inside place for a box of
    ``width`` x ``height`` pixels: ``Legend._find_best_position``'s (module docstring).

    Parameters
    ----------
    legend : matplotlib.legend.Legend
        A legend of an axes.
    width, height : float
        Its box, pixels.
    renderer : RendererBase

    Returns
    -------
    (float, float)
    """
    bboxes, lines, offsets = legend._auto_legend_data(renderer)
    points = _points(lines, offsets)
    x, y = points[:, 0], points[:, 1]
    anchor = legend.get_bbox_to_anchor()
    box = Bbox.from_bounds(0, 0, width, height)
    best = None
    with np.errstate(invalid="ignore"):
        for code in range(1, len(legend.codes)):
            left, bottom = legend._get_anchored_bbox(code, box, anchor, renderer)
            place = Bbox.from_bounds(left, bottom, width, height)
            (x0, y0), (x1, y1) = place.min, place.max
            inside = int(np.count_nonzero((x0 < x) & (x < x1) & (y0 < y) & (y < y1)))
            score = (inside + place.count_overlaps(bboxes)
                     + sum(line.intersects_bbox(place, filled=False) for line in lines))
            if best is None or (score, code) < best[:2]:
                best = (score, code, (left, bottom))
            if score == 0:
                break
    return best[2]

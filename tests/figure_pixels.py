"""Pixels of a figure drawn by matplotlib's own ``Figure`` and by quadland's quick figure
(:func:`quadland.plots.canvas.new_figure`), for the tests that compare them."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.plots.canvas import QuickFigure, new_figure
from quadland.png import PNG_DPI


def pixels(fig) -> np.ndarray:
    """``fig`` drawn on its canvas: its RGBA pixels (a copy)."""
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba()).copy()


def drawn_alike(content, figsize) -> QuickFigure:
    """``content`` drawn on matplotlib's own figure and on :func:`new_figure`'s: the same
    pixels (returns the latter)."""
    theirs = Figure(figsize=figsize, dpi=PNG_DPI)
    FigureCanvasAgg(theirs)
    content(theirs)
    mine = new_figure(figsize)
    content(mine)
    assert np.array_equal(pixels(mine), pixels(theirs))
    return mine

"""A new figure drawn at the resolution it is written at (:func:`new_figure`).

A figure made as ``Figure(figsize=...)`` is laid out (``tight_layout``) by a
renderer of its own at 100 dpi, made for that one layout, and then drawn again
by the PNG's renderer at :data:`quadland.png.PNG_DPI`: every text's size is
measured twice, once per resolution, and every tick is laid out for both. A
figure made by :func:`new_figure` has the PNG's resolution and an Agg canvas
from the start, so the layout and the PNG share one renderer and its cache of
text sizes, and the layout is the one the PNG is drawn with.
"""

from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.png import PNG_DPI

__all__ = ["new_figure"]


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A figure of ``figsize`` inches at :data:`~quadland.png.PNG_DPI`, on an Agg canvas.

    Parameters
    ----------
    figsize : (float, float)
        Width and height, inches.

    Returns
    -------
    matplotlib.figure.Figure
        Not managed by pyplot (nothing is shown or kept); displayed in a
        notebook and written by :func:`quadland.output.figure_png` as any
        other figure.
    """
    fig = Figure(figsize=figsize, dpi=PNG_DPI)
    FigureCanvasAgg(fig)
    return fig

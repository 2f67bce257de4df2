"""A new figure drawn at the resolution it is written at (:func:`new_figure`).

A figure made as ``Figure(figsize=...)`` is laid out (``tight_layout``) by a
renderer of its own at 100 dpi, made for that one layout, and then drawn again
by the PNG's renderer at :data:`quadland.png.PNG_DPI`: every text's size is
measured twice, once per resolution, and every tick is laid out for both. A
figure made by :func:`new_figure` has the PNG's resolution and an Agg canvas
from the start, so the layout and the PNG share one renderer and its cache of
text sizes, and the layout is the one the PNG is drawn with.

Its canvas draws with :class:`quadland.plots.text_cache.TextCacheRenderer`
(each distinct text laid out once per process), and each of its layouts and
draws computes an axis's ticks once (:func:`quadland.plots.tick_memo.ticks_memoized`)
and makes an axis's new ticks as copies of its first
(:func:`quadland.plots.tick_clone.ticks_cloned`), and places each legend once
(:func:`quadland.plots.legend_place.legends_placed`); its draws on Agg draw an axis's
tick lines in batches (:func:`quadland.plots.tick_batch.ticks_batched`): the same
pixels, in less time.
"""

from __future__ import annotations

from matplotlib.figure import Figure

from quadland.plots.legend_place import legends_placed
from quadland.plots.text_cache import TextCacheCanvas
from quadland.plots.tick_batch import ticks_batched
from quadland.plots.tick_clone import ticks_cloned
from quadland.plots.tick_memo import ticks_memoized
from quadland.png import PNG_DPI

__all__ = ["QuickFigure", "new_figure"]


class QuickFigure(Figure):
    """A matplotlib Figure whose ``tight_layout`` and draws compute each axis's ticks once
    per pass (:func:`~quadland.plots.tick_memo.ticks_memoized`), copy its new ticks
    from its first (:func:`~quadland.plots.tick_clone.ticks_cloned`) and place each
    legend once (:func:`~quadland.plots.legend_place.legends_placed`)."""

    def draw(self, renderer):
        """Draw as :meth:`matplotlib.figure.Figure.draw`, the ticks and legends memoized."""
        with ticks_memoized(self), ticks_cloned(self), legends_placed(self), ticks_batched(self):
            super().draw(renderer)

    # Figure.draw already handles rasterization: do not wrap this one again
    draw._supports_rasterization = True

    def __repr__(self):
        """As a matplotlib Figure's (``<Figure size 700x820 with 4 Axes>``): what it shows
        and does is a Figure's, and a notebook names it so."""
        return f"<Figure{super().__repr__()[len('<' + type(self).__name__):]}"

    def tight_layout(self, **kwargs):
        """As :meth:`matplotlib.figure.Figure.tight_layout`, the ticks and legends memoized."""
        with ticks_memoized(self), ticks_cloned(self), legends_placed(self, layout=True):
            super().tight_layout(**kwargs)


def new_figure(figsize: tuple[float, float]) -> Figure:
    """A figure of ``figsize`` inches at :data:`~quadland.png.PNG_DPI`, on an Agg canvas.

    Parameters
    ----------
    figsize : (float, float)
        Width and height, inches.

    Returns
    -------
    QuickFigure
        A :class:`matplotlib.figure.Figure`, not managed by pyplot (nothing is shown
        or kept); displayed in a notebook and written by
        :func:`quadland.output.figure_png` as any other figure.
    """
    fig = QuickFigure(figsize=figsize, dpi=PNG_DPI)
    TextCacheCanvas(fig)
    return fig

"""A log frequency axis's minor ticks and grid lines, drawn as two artists.

matplotlib draws every tick of an axis as its own ``Tick``: two tick lines,
a grid line and two labels, each a full artist made and laid out at every
draw. A log axis over six decades has about 50 minor ticks, none labelled;
on the eight axes of a Bode figure they were most of its drawing time.
:func:`cheap_minor_ticks` draws the same ticks and grid lines (the axis's
own minor locator, its minor tick and grid style) as one marker line and
one line collection, placed at each draw from the current view, so a
figure zoomed in a notebook still shows them where matplotlib would.
"""

from __future__ import annotations

import numpy as np
from matplotlib.artist import Artist
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.ticker import NullLocator

__all__ = ["MinorTicks", "cheap_minor_ticks"]

#: ``gid`` of the artist :func:`cheap_minor_ticks` adds (one per axes).
GID = "minor-ticks"


class MinorTicks(Artist):
    """An x axis's minor ticks and grid lines, placed by its former minor locator.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes with a log x axis whose minor ticks are styled (grid on or off)
        as they should be drawn.
    locator : matplotlib.ticker.Locator
        The axis's minor locator, which this artist takes over (the axis is
        left a ``NullLocator``; axes sharing x share it).
    """

    def __init__(self, ax, locator):
        super().__init__()
        axis = ax.xaxis
        proto = axis.get_minor_ticks(1)[0]      # the style a minor tick would have
        self._axis, self._locator = axis, locator
        axis.set_minor_locator(NullLocator())
        self.set_zorder(axis.get_zorder())
        self.set_gid(GID)
        mark = proto.tick1line
        self._marks = Line2D([], [], linestyle="None", marker=mark.get_marker(),
                             markersize=mark.get_markersize(),
                             markeredgewidth=mark.get_markeredgewidth(),
                             color=mark.get_color(), transform=ax.get_xaxis_transform("tick1"),
                             visible=mark.get_visible())
        grid = proto.gridline
        self._grid = LineCollection([], colors=[grid.get_color()],
                                    linewidths=[grid.get_linewidth()],
                                    linestyles=[grid.get_linestyle()], alpha=grid.get_alpha(),
                                    transform=ax.get_xaxis_transform("grid"),
                                    visible=grid.get_visible())
        self._grid.set_clip_path(ax.patch)
        self._grid.set_snap(grid.get_snap())
        self._marks.set_snap(mark.get_snap())

    @property
    def locator(self):
        """The minor locator placing the ticks."""
        return self._locator

    def locations(self) -> np.ndarray:
        """Data coordinates of the minor ticks in the current view, as matplotlib's axis
        would place them (those on a major tick dropped)."""
        axis = self._axis
        self._locator.set_axis(axis)
        minor = np.asarray(self._locator(), dtype=float)
        if minor.size == 0:
            return minor
        scale = axis.get_transform()
        lo, hi = sorted(axis.get_view_interval())
        tr_lo, tr_hi = scale.transform([lo, hi])
        tr_minor = scale.transform(minor)
        major = np.asarray(axis.get_majorticklocs(), dtype=float)
        if axis.remove_overlapping_locs and major.size:
            tol = (tr_hi - tr_lo) * 1e-5
            minor = minor[~np.isclose(tr_minor[:, None], scale.transform(major)[None, :],
                                      atol=tol, rtol=0).any(axis=1)]
            tr_minor = scale.transform(minor)
        slack = (tr_hi - tr_lo) * 1e-10         # as matplotlib keeps a tick in the view
        return minor[(tr_minor >= tr_lo - slack) & (tr_minor <= tr_hi + slack)]

    def draw(self, renderer):
        """Place the marks and grid lines for the current view and draw them."""
        if not self.get_visible():
            return
        x = self.locations()
        self._marks.set_data(x, np.zeros_like(x))
        self._grid.set_segments([np.array([[v, 0.0], [v, 1.0]]) for v in x])
        self._grid.draw(renderer)
        self._marks.draw(renderer)
        self.stale = False


def cheap_minor_ticks(ax) -> None:
    """Draw the log x axis's minor ticks and grid lines of ``ax`` as two artists.

    Call it once the axis is styled (``grid``); calling it again on the same
    axes does nothing. Axes whose x axis is not logarithmic are left alone.
    """
    if ax.get_xscale() != "log" or _minor_ticks(ax) is not None:
        return
    locator = ax.xaxis.get_minor_locator()
    if isinstance(locator, NullLocator):        # taken over by an axes sharing x
        taken = [m for m in map(_minor_ticks, ax.get_shared_x_axes().get_siblings(ax))
                 if m is not None]
        if not taken:
            return
        locator = taken[0].locator
    ax.add_artist(MinorTicks(ax, locator))


def _minor_ticks(ax) -> MinorTicks | None:
    return next((a for a in ax.artists if isinstance(a, MinorTicks)), None)

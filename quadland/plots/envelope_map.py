"""The envelope as a map: success probability over two keys, its contours and intervals.

Made without pyplot, like the other figures (:mod:`quadland.plots`). A
polar map draws one axis of directions in degrees as the angle (0 at the
top, clockwise: the bow up, starboard to the right) and the other as the
radius, like a helicopter's ship operating limits diagram of wind over the
deck.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

__all__ = ["CONTOUR_LEVELS", "INTERVAL_LW", "envelope_map_figure", "cell_edges"]

#: The success probabilities drawn as contours.
CONTOUR_LEVELS = (0.5, 0.9, 0.99)
#: Line width of a cell's interval bar.
INTERVAL_LW = 2.0
_NOTE = ("contours: 50 % dotted, 90 % dashed, 99 % solid\nin each cell: its interval as a "
         "bar on the cell's own scale (bottom 0, top 1), a dot at its rate, successes/runs")
_ARC_STEPS = 16                             # straight pieces of a polar cell's arc
_LABELLED_CELLS = 144                       # above this many cells, no k/n in each


def cell_edges(values: np.ndarray) -> np.ndarray:
    """The edges of the cells centred on ``values``: midpoints, and half a step beyond.

    Examples
    --------
    >>> cell_edges(np.array([0.0, 1.0, 3.0])).tolist()
    [-0.5, 0.5, 2.0, 4.0]
    """
    v = np.asarray(values, dtype=float)
    if v.size == 1:
        half = max(abs(v[0]) * 0.1, 0.5)
        return np.array([v[0] - half, v[0] + half])
    mid = (v[1:] + v[:-1]) / 2
    return np.concatenate([[v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]])


def envelope_map_figure(values: Sequence[np.ndarray], rate: np.ndarray, low: np.ndarray,
                        high: np.ndarray, successes: np.ndarray, runs: np.ndarray,
                        labels: Sequence[str], polar: bool = False, angle: int | None = None,
                        title: str = "") -> Figure:
    """The success probability of each cell, with its contours and each cell's interval.

    Parameters
    ----------
    values : two arrays
        The axes' values; ``rate[i, j]`` is the cell at ``values[0][i]``,
        ``values[1][j]``.
    rate, low, high : ndarray
        Each cell's success rate and its confidence interval (NaN where no
        run was flown).
    successes, runs : ndarray
        Each cell's counts.
    labels : two str
        The axes' names with their units.
    polar : bool
        Draw axis ``angle`` (degrees) as the angle, the other as the radius.
    angle : int, optional
        Which axis holds the directions (polar).
    title : str

    Returns
    -------
    matplotlib.figure.Figure
        The map (a colour per cell), the 50, 90 and 99 % contours of the
        success rate, and in each cell a bar from the interval's low to its
        high end on the cell's own 0-to-1 scale (a tick at the rate); with
        few cells, ``successes/runs`` too.
    """
    fig = Figure(figsize=(8.0, 7.0) if polar else (8.5, 6.5), layout="constrained")
    if polar:
        if angle is None:
            raise ValueError("a polar map needs the index of its angle axis")
        ax = fig.add_subplot(projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        xv, yv = np.radians(values[angle]), np.asarray(values[1 - angle], dtype=float)
        grids = [g if angle == 0 else g.T for g in (rate, low, high, successes, runs)]
        title = f"{title}\nangle: {labels[angle]}; radius: {labels[1 - angle]}"
    else:
        ax = fig.add_subplot()
        xv, yv = (np.asarray(v, dtype=float) for v in values)
        grids = [rate, low, high, successes, runs]
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
    ax.set_title(f"{title}\n{_NOTE}", fontsize=8)
    rate_g, low_g, high_g, k_g, n_g = grids            # [x index, y index]
    xe, ye = cell_edges(xv), cell_edges(yv)
    fine = _ARC_STEPS if polar else 1           # a polar cell's sides are arcs
    xf = np.concatenate([np.linspace(a, b, fine, endpoint=False) for a, b in
                         zip(xe[:-1], xe[1:], strict=True)] + [xe[-1:]])
    mesh = ax.pcolormesh(xf, ye, np.ma.masked_invalid(np.repeat(rate_g, fine, axis=0).T),
                         cmap="RdYlGn", vmin=0.0, vmax=1.0, shading="flat")
    if polar:
        ax.set_rlabel_position(float(np.degrees(xe[min(3, len(xe) - 2)])))
    fig.colorbar(mesh, ax=ax, label="success probability (cell's rate)", shrink=0.8)
    _contours(ax, xv, yv, rate_g, polar)
    _intervals(ax, xv, yv, xe, ye, rate_g, low_g, high_g, k_g, n_g)
    return fig


def _contours(ax, xv, yv, rate, polar) -> None:
    """The 50, 90 and 99 % contours of the rate (a grid of at least 2 x 2)."""
    if len(xv) < 2 or len(yv) < 2 or not np.isfinite(rate).any():
        return
    x, z = xv, rate
    if polar and len(xv) > 2:                  # close the circle when the angles go round
        step = np.diff(xv).mean()
        if abs(xv[-1] + step - xv[0] - 2 * np.pi) < 1e-6 * step:
            x, z = np.append(xv, xv[0] + 2 * np.pi), np.vstack([rate, rate[:1]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")         # "no contour levels were found"
        cs = ax.contour(x, yv, np.ma.masked_invalid(z.T), levels=list(CONTOUR_LEVELS),
                        colors="navy", linewidths=1.4,
                        linestyles=("dotted", "dashed", "solid"))
    if cs.allsegs and any(len(s) for s in cs.allsegs):
        ax.clabel(cs, fmt=lambda v: f"{100 * v:g} %", fontsize=7, colors="navy")


def _intervals(ax, xv, yv, xe, ye, rate, low, high, k, n) -> None:
    """In each cell, its interval as a bar on the cell's own 0-to-1 scale, a dot at its rate."""
    label = rate.size <= _LABELLED_CELLS
    for i in range(len(xv)):
        for j in range(len(yv)):
            if not n[i, j] > 0:
                continue
            y0, h = ye[j], ye[j + 1] - ye[j]

            def at(p, y0=y0, h=h):
                return y0 + h * (0.15 + 0.7 * p)

            ax.plot([xv[i], xv[i]], [at(0.0), at(1.0)], color="w", lw=3.0, alpha=0.6,
                    solid_capstyle="butt")
            ax.plot([xv[i], xv[i]], [at(low[i, j]), at(high[i, j])], color="k", lw=INTERVAL_LW,
                    solid_capstyle="butt")
            ax.plot([xv[i]], [at(rate[i, j])], "o", color="k", ms=3.0)
            if label:
                ax.text(xv[i] + 0.06 * (xe[i + 1] - xe[i]), at(0.5),
                        f"{int(k[i, j])}/{int(n[i, j])}", fontsize=6, ha="left", va="center")

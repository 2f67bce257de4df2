"""Figures of the navigation filter: its estimate against the truth, and its consistency.

:func:`navigation_plot` draws a landing flown on its sensors: the filter's relative
position at its horizon, the truth at that time and the filter's 3-sigma band.
:func:`consistency_plot` draws a Monte Carlo of hovers
(``quadland.kinds.landing.consistency``): the average NEES and NIS against their
chi-square bounds. docs/estimator.md ("Consistency") explains both.
"""

from __future__ import annotations

import types

import numpy as np
from matplotlib.figure import Figure

from quadland.plots.finite import drawable
from quadland.plots.overlay import redraw_legend, run_index, run_tag
from quadland.plots.style import finish
from quadland_symbolic.landing.estimator import FLIGHT_COUPLING
from quadland_symbolic.landing.guidance import TOUCHDOWN
from quadland_symbolic.landing.navigation import NAV, covariance_pattern

__all__ = ["NAVIGATION_FIGURES", "CONSISTENCY_TITLE", "has_estimate", "navigation_plot",
           "consistency_plot"]

#: File name and title of the figure a landing flown on its sensors adds.
NAVIGATION_FIGURES = types.MappingProxyType({
    "navigation.png": "Relative position: the filter's estimate at its horizon, the truth, "
                      "3 sigma",
})

#: Title of :func:`consistency_plot`.
CONSISTENCY_TITLE = "Navigation filter consistency: average NEES and NIS, 95 % bounds"

_AXES = ("x", "y", "z")


def has_estimate(result) -> bool:
    """True when ``result`` holds the filter's recorded horizon state (a run on sensors)."""
    try:
        result["t_h"]
    except KeyError:
        return False
    return True


def _variance_names() -> tuple[str, ...]:
    """The recorded covariance entries of ``p_r``'s variances, x, y, z."""
    pattern = covariance_pattern(FLIGHT_COUPLING)
    names = dict(zip(pattern.entries, pattern.element_names("P_h"), strict=True))
    i = NAV.slice("p_r").start
    return tuple(names[(i + a, i + a)] for a in range(3))


def _horizon_rows(result) -> np.ndarray:
    """Rows of the flight (before touchdown) whose horizon time is new and finite."""
    t_h = np.asarray(result["t_h"], dtype=float)
    phase = np.asarray(result["phase"])
    keep = np.isfinite(t_h) & (phase < TOUCHDOWN)
    rows = np.flatnonzero(keep)
    if rows.size:
        new = np.r_[True, np.diff(t_h[rows]) > 0]
        rows = rows[new]
    return rows


def navigation_plot(result, ax=None, label: str | None = None) -> Figure:
    """The filter's relative position against the truth, with its 3-sigma band.

    Parameters
    ----------
    result : LandingResult
        A landing flown on its sensors: ``t``, ``phase``, both bodies' positions
        ``x1 .. z1``, ``x2 .. z2`` and the filter's recorded horizon (``t_h``, the state
        ``x_h_p_r_*`` and its covariance ``P_h_*``).
    ax : sequence of three matplotlib Axes, optional
        Where to draw, to overlay runs (each in its own colour, its lines
        labelled with ``label``, the legends drawn again); a new figure if
        None.
    label : str, optional
        The run's name in the legend; by default its scenario's name in an
        overlay, none alone.

    Returns
    -------
    matplotlib.figure.Figure
        Three time axes (x, y, z of ``p_r = p1 - p2`` in E, m) over the filter's horizon
        time ``t_h`` (0.2 s behind the flight), up to touchdown: the truth at ``t_h``
        (the logged positions, linearly interpolated between rows), the estimate
        ``x_h`` (the filter's memory after each step) and the band ``x_h +- 3 sigma``
        from its own variances. The controller's input is this estimate carried to the
        present (docs/estimator.md, (E17)), without a covariance.
    """
    result = drawable(result)                 # a failed flight's last rows may diverge
    rows = _horizon_rows(result)
    t = np.asarray(result["t"], dtype=float)
    t_h = np.asarray(result["t_h"], dtype=float)[rows]
    own = ax is None
    if own:
        fig = Figure(figsize=(7, 6.6))
        axes = fig.subplots(3, 1, sharex=True)
        fig.suptitle(NAVIGATION_FIGURES["navigation.png"], y=1 - 0.1 / fig.get_figheight(),
                     va="top")
    else:
        axes = list(np.ravel(np.asarray(ax, dtype=object)))
        fig = axes[0].figure
    tag, run = run_tag(result, label, own), run_index(axes[0], "estimate")
    color = f"C{run % 10}"
    for a, (ax, var) in enumerate(zip(axes, _variance_names(), strict=True)):
        body1, body2 = (np.asarray(result[f"{n}{b}"], dtype=float)
                        for n, b in ((_AXES[a], "1"), (_AXES[a], "2")))
        ok = np.isfinite(t) & np.isfinite(body1) & np.isfinite(body2)
        truth = np.interp(t_h, t[ok], (body1 - body2)[ok]) if ok.any() else t_h * np.nan
        est = np.asarray(result[f"x_h_p_r_{_AXES[a]}"], dtype=float)[rows]
        sigma = np.sqrt(np.clip(np.asarray(result[var], dtype=float)[rows], 0, None))
        ax.fill_between(t_h, est - 3 * sigma, est + 3 * sigma, color=color, alpha=0.25,
                        lw=0, label=f"estimate +- 3 sigma{tag}")
        ax.plot(t_h, est, color=color, label=f"estimate{tag}", gid="estimate")
        ax.plot(t_h, truth, color="k" if run == 0 else color, ls="--", lw=1,
                label=f"truth{tag}")
        ax.set_ylabel(f"p_r {_AXES[a]} [m]")
        redraw_legend(ax, loc="upper right", fontsize="small")
    if not own:
        return fig
    finish(fig, result, axes)
    axes[-1].set_xlabel("filter horizon time t_h [s]")
    return fig


def _band(ax, t, lo, hi, label):
    """The bounds as a shaded band (constant or per time)."""
    lo, hi = np.broadcast_to(lo, t.shape), np.broadcast_to(hi, t.shape)
    ax.fill_between(t, lo, hi, color="0.6", alpha=0.35, lw=0, step="mid", label=label)


def _nees_axis(ax, mc, groups, level):
    t, settled = mc.times, mc.settled
    lo, hi = mc.nees_bounds(groups[0], level)
    _band(ax, t[settled], lo, hi, f"{level:.0%} bounds, {mc.runs} runs")
    for g in groups:
        ax.plot(t[settled], mc.nees_mean(g)[settled], lw=1,
                label=f"{g} ({mc.nees_dof(g)}): {mc.nees_inside(g, level):.0%} inside")
    ax.set_ylabel("average NEES")
    ax.legend(loc="upper right", fontsize="x-small")


def _nis_axis(ax, mc, block, level):
    due = mc.settled & (mc.nis_count(block) > 0)
    t = mc.times[due]
    lo, hi = mc.nis_bounds(block, level)
    _band(ax, t, lo[due], hi[due], f"{level:.0%} bounds")
    mean, n, plo, phi = mc.nis_pooled(block, level)
    n_out, n_due = mc.outlier_count(block)
    apart = f"; {n_out} of {n_due} outliers apart" if n_out else ""
    ax.plot(t, mc.nis_mean(block)[due], ".", ms=2, color="C1",
            label=f"{mc.nis_inside(block, level):.0%} inside; all {n}: {mean:.3f} "
                  f"[{plo:.3f}, {phi:.3f}]{apart}")
    ax.set_ylabel(f"NIS {block}")
    ax.legend(loc="upper right", fontsize="x-small")


def consistency_plot(mc, level: float = 0.95) -> Figure:
    """The average NEES and NIS of a Monte Carlo of hovers against their bounds.

    Parameters
    ----------
    mc : ConsistencyResult
        ``quadland.kinds.landing.consistency.consistency_monte_carlo``'s result.
    level : float
        The bounds' two-sided confidence level.

    Returns
    -------
    matplotlib.figure.Figure
        From the settling time on, over the filter's horizon time: the average NEES of
        the relative position and velocity (6), then of the position and of the
        velocity (3 each), of the pad's velocity and acceleration (6) and of the tilt
        bias (2), each with the band of ``chi2.ppf`` bounds for the runs; then each
        measurement block's NIS averaged over the runs where it was due, with the bounds
        of that count at each time, and in its legend the average of every due packet
        with its bounds, and the outliers kept apart (a range beside the deck).
    """
    blocks = list(mc.nis)
    rows = 3 + (len(blocks) + 1) // 2
    fig = Figure(figsize=(10, 2.0 * rows + 0.6))
    grid = fig.add_gridspec(rows, 2)
    axes = [fig.add_subplot(grid[0, :])]
    axes += [fig.add_subplot(grid[1 + k // 2, k % 2], sharex=axes[0]) for k in range(4)]
    axes += [fig.add_subplot(grid[3 + k // 2, k % 2], sharex=axes[0])
             for k in range(len(blocks))]
    fig.suptitle(CONSISTENCY_TITLE, y=1 - 0.1 / fig.get_figheight(), va="top")
    _nees_axis(axes[0], mc, ["relative"], level)
    for ax, g in zip(axes[1:5], ("position", "velocity", "pad", "tilt"), strict=True):
        _nees_axis(ax, mc, [g], level)
    for ax, b in zip(axes[5:], blocks, strict=True):
        _nis_axis(ax, mc, b, level)
    for ax in axes:
        ax.grid(True)
    for ax in axes[-2:]:
        ax.set_xlabel("filter horizon time t_h [s]")
    fig.text(0.99, 0.005, f"scenario {mc.scenario.name}: {mc.runs} hovers, seeds "
             f"{mc.seeds[0]}-{mc.seeds[-1]}", ha="right", va="bottom", fontsize="x-small",
             color="0.4")
    fig.tight_layout()
    return fig

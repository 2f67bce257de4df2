"""Figures of the closed loop of a margin review: singular values of S and T, poles.

Both draw the sampled-data loop (zero-order hold and computation delay, the
one that fails its requirement first) beside the continuous one. Like the
other margin figures they take ``ax=`` and ``label=`` (:mod:`quadland.plots.margins`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure
from threadpoolctl import threadpool_limits

from quadland.analysis import (
    closed_loop_poles,
    frequency_grid,
    response_of,
    sensitivity_sigma,
)
from quadland.plots.canvas import new_figure
from quadland.plots.frequency import POINTS_PER_DECADE
from quadland.plots.log_labels import plain_log_labels
from quadland.plots.log_minor import cheap_minor_ticks
from quadland.plots.overlay import redraw_legend, run_index, run_tag

if TYPE_CHECKING:       # a figure draws a report it is given; it never builds one
    from quadland.margins import MarginReport

__all__ = ["SIGMA_FLOOR_DB", "RUN_GID", "sigma_plot", "pole_plot"]

#: The ``gid`` of one line per report on each axis of a margin figure: how many
#: reports the axes already show (:func:`quadland.plots.overlay.run_index`).
RUN_GID = "margin-report"

#: dB, the bottom of the singular value axes: the peaks that set the margins
#: (a few dB) stay readable; deep low-frequency attenuation is cut off.
SIGMA_FLOOR_DB = -40.0


def _sigma_curves(report: MarginReport):
    """``(label, style, colour, omega, sigma_S, sigma_T)`` of each loop of the report."""
    loop = report.models.realizations["loop_input"]
    resp = response_of(loop)
    omega = frequency_grid(resp, points_per_decade=POINTS_PER_DECADE, extra_poles=report.poles)
    out = [("continuous", "-", "C0", omega, *sensitivity_sigma(loop, omega))]
    if report.sampled_models is not None:
        wd = omega[omega < math.pi / report.sampled_models.dt]
        out.append(("sampled", "--", "C1", wd,
                    *sensitivity_sigma(report.sampled_models.realizations["loop_input"], wd)))
    if report.filtered_models is not None:
        wf = omega[omega < math.pi / report.filtered_models.dt]
        out.append(("filtered", ":", "C2", wf,
                    *sensitivity_sigma(report.filtered_models.realizations["loop_input"], wf)))
    return out


def _axes(ax, count: int, size) -> tuple[Figure, list]:
    if ax is None:
        fig = new_figure(size)
        return fig, list(np.ravel(fig.subplots(1, count)))
    axes = list(np.ravel(np.asarray(ax, dtype=object)))
    return axes[0].figure, axes


def sigma_plot(report: MarginReport, ax=None, label: str | None = None) -> Figure:
    """Singular values of S and T at the plant input, with their peaks.

    Parameters
    ----------
    report : MarginReport
    ax : sequence of two matplotlib Axes, optional
        Where to draw S and T; a new figure if None.
    label : str, optional
        This report's name in the labels when overlaid
        (:mod:`quadland.plots.margins`).

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the singular values (dB) of ``S = (I + L)^-1`` and of
        ``T = I - S`` against frequency (rad/s), one line per singular value,
        largest first, the continuous loop solid, the sampled loop dashed and the
        loop with the navigation filter in it dotted
        (up to its Nyquist frequency). Each loop's peak of the largest
        singular value (``Ms``, ``Mt`` on the grid) is marked and labelled;
        the axes run from :data:`SIGMA_FLOOR_DB` to 6 dB above the highest peak.
    """
    tag = run_tag(report, label, ax is None)
    fig, (a_S, a_T) = _axes(ax, 2, (13, 5))
    shift = 2 * run_index(a_S, RUN_GID) if tag else 0
    top = max([0.0] + [float(np.max(line.get_ydata()))          # the peaks already drawn
                       for line in [*a_S.get_lines(), *a_T.get_lines()]
                       if line.get_marker() == "v"])
    with threadpool_limits(1):      # see quadland.plots.frequency.loop_curves
        curves = _sigma_curves(report)
    for j, (name, style, _, w, sS, sT) in enumerate(curves):
        name, color = name + tag, f"C{(shift + j) % 10}"
        for a, sv, peak_name in ((a_S, sS, "Ms"), (a_T, sT, "Mt")):
            db = 20 * np.log10(sv)
            for k in range(db.shape[1]):
                a.semilogx(w, db[:, k], style, color=color, lw=1.6 if k == 0 else 0.8,
                           label=name if k == 0 else f"_{name} sigma {k + 1}",
                           gid=RUN_GID if j == 0 and k == 0 else None)
            i = int(np.argmax(db[:, 0]))
            a.plot([w[i]], [db[i, 0]], "v", color=color, ms=7, gid=f"{name}-{peak_name}",
                   label=f"{name} {peak_name} {db[i, 0]:.1f} dB at {w[i]:.3g} rad/s")
            top = max(top, float(db[i, 0]))
    for a, name in ((a_S, "S = (I + L)^-1"), (a_T, "T = I - S")):
        a.axhline(0, color="k", lw=0.6)
        a.set_ylim(SIGMA_FLOOR_DB, top + 6.0)
        a.set_title(f"singular values of {name} at the plant input")
        a.set_xlabel("frequency [rad/s]")
        a.set_ylabel("sigma [dB]")
        a.grid(True, which="both", alpha=0.3)
        cheap_minor_ticks(a)
        plain_log_labels(a)
        redraw_legend(a, fontsize="small", loc="lower left" if a is a_T else "lower right")
    fig.tight_layout()
    return fig


def _modulus(m: float) -> str:
    """``m`` as a title shows it: within 1e-3 of the unit circle as ``1 - d`` (or ``1 + d``),
    so that a slow pole's ``0.99996`` does not read ``1.0000``."""
    d = 1.0 - float(m)
    if 0 < abs(d) < 1e-3:
        return f"1 {'-' if d > 0 else '+'} {abs(d):.2g}"
    return f"{m:.4f}"


def pole_plot(report: MarginReport, ax=None, label: str | None = None) -> Figure:
    """Map of the closed loop's poles, continuous and sampled.

    Parameters
    ----------
    report : MarginReport
    ax : sequence of matplotlib Axes, optional
        Two (s-plane, zoom), or three with a sampled loop (and its z-plane);
        a new figure if None.
    label : str, optional
        This report's name in the labels when overlaid
        (:mod:`quadland.plots.margins`).

    Returns
    -------
    matplotlib.figure.Figure
        The s-plane with every continuous pole (x) and the sampled loop's
        poles mapped by ``s = log(z) / dt`` (+; those with ``|z| < exp(-pi)``,
        faster than the Nyquist frequency, are the computation delay's near
        ``z = 0``: not mapped, counted in the legend),
        a zoom on the slow adaptive and translational poles near the origin,
        and, for a sampled loop, its poles in the z-plane with the unit circle.
    """
    p = report.poles
    z = None if report.sampled_models is None else closed_loop_poles(
        report.sampled_models.realizations["loop_input"])
    tag = run_tag(report, label, ax is None)
    fig, ax = _axes(ax, 2 if z is None else 3, (12, 5) if z is None else (17, 5))
    shift = 2 * run_index(ax[0], RUN_GID) if tag else 0
    c_cont, c_samp = f"C{shift % 10}", f"C{(shift + 1) % 10}"
    # |z| < exp(-pi): faster than the Nyquist frequency, the computation delay's poles
    # near z = 0, which have no continuous counterpart
    fast = None if z is None else np.abs(z) < math.exp(-math.pi)
    s_z = None if z is None else np.log(z[~fast]) / report.sampled_models.dt
    for a, zoom in zip(ax[:2], (False, True), strict=True):
        a.plot(p.real, p.imag, "x", color=c_cont, label=f"continuous{tag} ({p.size})",
               gid=RUN_GID)
        if s_z is not None:
            a.plot(s_z.real, s_z.imag, "+", color=c_samp, ms=8,
                   label=f"sampled{tag}, log(z)/dt ({s_z.size}; {int(fast.sum())} near z = 0)")
        a.axvline(0, color="k", lw=0.6)
        a.set_xlabel("Re s [1/s]")
        a.set_ylabel("Im s [rad/s]")
        a.grid(True, alpha=0.3)
        redraw_legend(a, fontsize="small", loc="upper left")
        if zoom:
            a.set_xlim(-0.5, 0.05)
            a.set_ylim(-0.3, 0.3)
            a.set_title("zoom: the slow adaptive and translational poles")
        else:
            a.set_title(f"closed-loop poles ({p.size})")
    if z is not None:
        a = ax[2]
        t = np.linspace(0, 2 * np.pi, 400)
        a.plot(np.cos(t), np.sin(t), "k", lw=0.6, label="unit circle")
        a.plot(z.real, z.imag, "+", color=c_samp, ms=8, label=f"sampled{tag} ({z.size})",
               gid=RUN_GID)
        a.set_aspect("equal")
        a.set_xlabel("Re z")
        a.set_ylabel("Im z")
        a.set_title(f"sampled loop in the z-plane, max |z| = {_modulus(np.max(np.abs(z)))}")
        a.grid(True, alpha=0.3)
        redraw_legend(a, fontsize="small", loc="upper left")
    fig.tight_layout()
    return fig

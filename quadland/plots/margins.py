"""Figures of a margin review: Bode, Nyquist, Nichols, singular values, poles.

Each loop is drawn broken at its input with the others closed,
``l_i = 1 / [(I + L)^-1]_ii - 1`` (:func:`quadland.analysis.loop_at_a_time`);
a sampled-data loop (zero-order hold and computation delay) is drawn dashed
beside the continuous one, up to its Nyquist frequency, and the sampled loop
with the navigation filter in it, when the report has one, dotted. Every phase is drawn
in one convention (:func:`quadland.plots.frequency.phase_deg`): unwrapped,
and turned by whole turns so that the phase at the gain crossover lies in
[-360, 0) deg, where the phase margin is read against -180 deg.

Each function takes ``ax=``: axes to draw into (of the shape the figure
would have), so that two reports overlay on one figure; it then returns
the axes' figure. A report drawn into axes already drawn (or given
``label=``) has its lines' labels end with `` (label)``, the label by default
its scenario's name, its curves take the next colours, and each legend is
drawn again with one entry per label (:mod:`quadland.plots.overlay`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from quadland.plots.canvas import new_figure
from quadland.plots.frequency import (
    LoopCurves,
    crossing_phase,
    exclusion_circle,
    loop_curves,
    m_circle,
)
from quadland.plots.log_labels import plain_log_labels
from quadland.plots.log_minor import cheap_minor_ticks
from quadland.plots.overlay import redraw_legend, run_index, run_tag
from quadland.plots.sensitivity import RUN_GID, pole_plot, sigma_plot

if TYPE_CHECKING:       # a figure draws a report it is given; it never builds one
    from quadland.margins import MarginReport

__all__ = ["MARGIN_FIGURES", "M_CIRCLES_DB", "bode_plot", "nyquist_plot", "nichols_plot",
           "sigma_plot", "pole_plot", "margin_figures"]

#: File names of :func:`margin_figures`, in order.
MARGIN_FIGURES = ("bode.png", "nyquist.png", "nichols.png", "sigma.png", "poles.png")

#: dB, the closed-loop gains ``|l / (1 + l)|`` of the Nichols chart's M-circles.
M_CIRCLES_DB = (6.0, 3.0, 1.0, 0.5, -1.0, -3.0, -6.0, -12.0)


def _names(report: MarginReport) -> list[str]:
    return [m.name for m in report.continuous.loops]


def _axes(ax, shape: tuple[int, ...], make) -> tuple[Figure, np.ndarray]:
    """``ax`` as an array of ``shape`` and its figure, or a new figure from ``make()``."""
    if ax is None:
        fig, axes = make()
        return fig, np.asarray(axes).reshape(shape)
    axes = np.asarray(ax, dtype=object).reshape(shape)
    return axes.flat[0].figure, axes


def _for_run(report: MarginReport, curves: tuple[LoopCurves, ...], ax, label: str | None
             ) -> tuple[LoopCurves, ...]:
    """The curves as this report's run draws them: labels tagged and colours moved on
    past the reports the axes already show (:mod:`quadland.plots.overlay`)."""
    tag = run_tag(report, label, ax is None)
    if not tag:
        return curves
    first = None if ax is None else np.ravel(np.asarray(ax, dtype=object))[0]
    k = 0 if first is None else run_index(first, RUN_GID)
    return tuple(dataclasses.replace(c, label=c.label + tag, color=f"C{(3 * k + j) % 10}")
                 for j, c in enumerate(curves))


def _bode_markers(mag, phase, c: LoopCurves, i: int) -> None:
    """The phase margin at the gain crossover, the gain margins at the phase crossovers."""
    m = c.margins[i]
    if m.crossover_frequency is not None:
        wc = m.crossover_frequency
        mag.plot([wc], [0.0], "o", color=c.color, ms=5, gid=f"{c.label}-crossover")
        phase.plot([wc, wc], [-180.0, crossing_phase(c, i, wc)], "-o", color=c.color, lw=2,
                   ms=4, markevery=[1], gid=f"{c.label}-phase-margin",
                   label=f"{c.label}: PM {m.phase_margin_deg:.1f} deg at {wc:.3g} rad/s")
    for gm, w, side in ((m.gain_margin_up_db, m.gain_margin_up_frequency, "up"),
                        (m.gain_margin_down_db, m.gain_margin_down_frequency, "down")):
        if w is None:
            continue
        db = float(np.interp(np.log(w), np.log(c.omega), 20 * np.log10(np.abs(c.loops[:, i]))))
        mag.plot([w, w], [0.0, db], "-s", color=c.color, lw=2, ms=4, markevery=[1],
                 gid=f"{c.label}-gain-margin-{side}",
                 label=f"{c.label}: GM {gm:+.1f} dB at {w:.3g} rad/s")
        phase.plot([w], [crossing_phase(c, i, w)], "s", color=c.color, ms=4,
                   gid=f"{c.label}-phase-crossover-{side}")


def bode_plot(report: MarginReport, ax=None, label: str | None = None) -> Figure:
    """Bode diagram of each loop with the others closed, with its margins marked.

    Parameters
    ----------
    report : MarginReport
    ax : array of matplotlib Axes, shape (2, loops), optional
        Where to draw (magnitudes in the first row); a new figure if None.
    label : str, optional
        This report's name in the labels when overlaid (module docstring).

    Returns
    -------
    matplotlib.figure.Figure
        Two rows of one axis per loop: magnitude of ``l_i`` (dB, with the
        0 dB line) and its phase (deg, :func:`~quadland.plots.frequency.phase_deg`,
        with the -180 deg line) against frequency (rad/s); the sampled loop
        dashed. Margins are marked in each curve's colour: the phase margin
        as a bar from -180 deg up to the phase at the gain crossover (a dot
        at 0 dB above it), each gain margin as a bar from 0 dB to the
        magnitude at its phase crossover (a square at the phase there).
        Each marker's ``gid`` names it (``"sampled-phase-margin"``,
        ``"continuous-gain-margin-down"``, ...).
    """
    return _bode(report, _for_run(report, loop_curves(report), ax, label), ax)


def _bode(report: MarginReport, curves: tuple[LoopCurves, ...], ax) -> Figure:
    names = _names(report)
    fig, ax = _axes(ax, (2, len(names)), lambda: _new(2, len(names), (15, 7.5), sharex=True))
    for i, name in enumerate(names):
        mag, phase = ax[0, i], ax[1, i]
        for j, c in enumerate(curves):
            mag.semilogx(c.omega, 20 * np.log10(np.abs(c.loops[:, i])), c.style, color=c.color,
                         label=c.label, gid=RUN_GID if j == 0 else None)
            phase.semilogx(c.omega, c.phase(i), c.style, color=c.color)
            _bode_markers(mag, phase, c, i)
        mag.axhline(0, color="k", lw=0.6)
        phase.axhline(-180, color="k", lw=0.6)
        mag.set_title(f"{name} loop (others closed)")
        phase.set_xlabel("frequency [rad/s]")
        for a in (mag, phase):
            a.grid(True, which="both", alpha=0.3)
            cheap_minor_ticks(a)
            plain_log_labels(a)
            redraw_legend(a, fontsize="x-small", loc="best")
    ax[0, 0].set_ylabel("|l| [dB]")
    ax[1, 0].set_ylabel("arg l [deg], crossover in [-360, 0)")
    fig.tight_layout()
    return fig


def _new(rows: int, cols: int, size, **kw):
    fig = new_figure(size)
    return fig, fig.subplots(rows, cols, squeeze=False, **kw)


def _exclusion(a, c: LoopCurves, i: int) -> None:
    """The values of ``l_i`` that the loop's disk margin excludes, shaded."""
    alpha = c.margins[i].disk.disk_margin
    centre, radius, inside = exclusion_circle(alpha)
    if not np.isfinite(centre):
        a.axvspan(-1e3, 0, color=c.color, alpha=0.12, lw=0,
                  label=f"{c.label}: excluded by its disk margin (alpha {alpha:.3g})")
        return
    a.add_patch(Circle((centre, 0.0), radius, fill=inside, facecolor=c.color, alpha=0.15,
                       edgecolor=c.color, ls=":", gid=f"{c.label}-exclusion",
                       label=f"{c.label}: excluded by its disk margin (alpha {alpha:.3g})"
                       + ("" if inside else ", outside the circle")))


def nyquist_plot(report: MarginReport, ax=None, label: str | None = None) -> Figure:
    """Nyquist diagram of each loop with the others closed, zoomed on -1.

    Parameters
    ----------
    report : MarginReport
    ax : array of matplotlib Axes, one per loop, optional
        Where to draw; a new 2 x 2 figure if None.
    label : str, optional
        This report's name in the labels when overlaid (module docstring).

    Returns
    -------
    matplotlib.figure.Figure
        One axis per loop: ``l_i(j w)`` for ``w > 0`` and its mirror image
        (faint), the unit circle, the critical point -1 and the region its
        loop-at-a-time disk margin excludes (shaded, a
        :class:`matplotlib.patches.Circle` of
        :func:`~quadland.plots.frequency.exclusion_circle`, the curve
        touches it at the disk margin's frequency); the sampled loop dashed.
    """
    return _nyquist(report, _for_run(report, loop_curves(report), ax, label), ax)


def _nyquist(report: MarginReport, curves: tuple[LoopCurves, ...], ax) -> Figure:
    names = _names(report)
    fig, ax = _axes(ax, (len(names),), lambda: _new(2, (len(names) + 1) // 2, (11, 10)))
    t = np.linspace(0, 2 * np.pi, 200)
    for i, (name, a) in enumerate(zip(names, ax, strict=True)):
        for j, c in enumerate(curves):
            vals = c.loops[:, i]
            a.plot(vals.real, vals.imag, c.style, color=c.color, label=f"{c.label}, w > 0",
                   gid=RUN_GID if j == 0 else None)
            a.plot(vals.real, -vals.imag, c.style, color=c.color, alpha=0.35,
                   label=f"{c.label}, w < 0")
            _exclusion(a, c, i)
        a.plot(np.cos(t), np.sin(t), "k:", lw=0.6, label="unit circle")
        a.plot([-1], [0], "r+", ms=12, mew=2, label="-1")
        a.set_xlim(-3, 2)
        a.set_ylim(-2.5, 2.5)
        a.set_aspect("equal")
        a.set_xlabel("Re l")
        a.set_ylabel("Im l")
        a.set_title(f"{name} loop (others closed): Nyquist, zoom on -1")
        a.grid(True, alpha=0.3)
        redraw_legend(a, fontsize="x-small", loc="best")     # clear of the curves
    fig.tight_layout()
    return fig


def nichols_plot(report: MarginReport, ax=None, label: str | None = None) -> Figure:
    """Nichols chart of each loop with the others closed, with M-circles.

    Parameters
    ----------
    report : MarginReport
    ax : array of matplotlib Axes, one per loop, optional
        Where to draw; a new 2 x 2 figure if None.
    label : str, optional
        This report's name in the labels when overlaid (module docstring).

    Returns
    -------
    matplotlib.figure.Figure
        One axis per loop: gain (dB) against phase (deg, the figures' one
        convention) of ``l_i``, the sampled loop dashed; the critical point
        (-180 deg, 0 dB); the M-circles ``|l / (1 + l)| = M`` of
        :data:`M_CIRCLES_DB` (:func:`~quadland.plots.frequency.m_circle`,
        grey, ``gid`` ``"M 3 dB"`` ...); zoomed on [-360, 0] deg and
        [-30, 40] dB around the critical point.
    """
    return _nichols(report, _for_run(report, loop_curves(report), ax, label), ax)


def _nichols(report: MarginReport, curves: tuple[LoopCurves, ...], ax) -> Figure:
    names = _names(report)
    fig, ax = _axes(ax, (len(names),), lambda: _new(2, (len(names) + 1) // 2, (11, 10)))
    for i, (name, a) in enumerate(zip(names, ax, strict=True)):
        for m_db in M_CIRCLES_DB:
            ph, db = m_circle(m_db)
            a.plot(ph, db, color="0.6", lw=0.7, gid=f"M {m_db:g} dB")
            k = int(np.argmax(db)) if m_db > 0 else int(np.argmin(np.abs(ph + 90)))
            a.annotate(f"{m_db:g} dB", (ph[k], db[k]), fontsize="xx-small", color="0.4",
                       ha="center", va="bottom")
        for j, c in enumerate(curves):
            a.plot(c.phase(i), 20 * np.log10(np.abs(c.loops[:, i])), c.style, color=c.color,
                   label=c.label, gid=RUN_GID if j == 0 else None)
        a.plot([-180], [0], "r+", ms=12, mew=2, label="critical point")
        a.set_xlim(-360, 0)
        a.set_ylim(-30, 40)
        a.set_xticks(np.arange(-360, 1, 45))
        a.set_xlabel("arg l [deg]")
        a.set_ylabel("|l| [dB]")
        a.set_title(f"{name} loop (others closed): Nichols, M-circles of |l/(1+l)|")
        a.grid(True, alpha=0.3)
        redraw_legend(a, fontsize="x-small", loc="upper left")
    fig.tight_layout()
    return fig


def margin_figures(report: MarginReport) -> dict[str, Figure]:
    """Every figure of a margin review, by the file name it is saved under.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        Keys are :data:`MARGIN_FIGURES`: Bode, Nyquist, Nichols, singular
        values and poles. The frequency responses are evaluated once for all
        of them.
    """
    curves = loop_curves(report)
    figs = (_bode(report, curves, None), _nyquist(report, curves, None),
            _nichols(report, curves, None), sigma_plot(report), pole_plot(report))
    return dict(zip(MARGIN_FIGURES, figs, strict=True))

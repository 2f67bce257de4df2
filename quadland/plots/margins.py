"""Figures of a margin review: Bode, Nyquist, singular values, poles.

Each loop is drawn broken at its input with the other loops closed,
``l_i = 1 / [(I + L)^-1]_ii - 1`` (:func:`quadland.analysis.loop_at_a_time`);
a sampled-data loop is drawn dashed beside the continuous one, up to its
Nyquist frequency.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from quadland.analysis import frequency_grid, loop_at_a_time, response_of, sensitivity_sigma

if TYPE_CHECKING:       # a figure draws a report it is given; it never builds one
    from quadland.margins import MarginReport

__all__ = ["MARGIN_FIGURES", "bode_plot", "nyquist_plot", "sigma_plot", "pole_plot",
           "margin_figures"]

#: File names of :func:`margin_figures`, in order.
MARGIN_FIGURES = ("bode.png", "nyquist.png", "sigma.png", "poles.png")

#: Grid density of the figures, points per decade (the margins use a finer one).
_POINTS_PER_DECADE = 30


@dataclasses.dataclass(frozen=True)
class _LoopResponse:
    """Loop-at-a-time responses on the figures' grid, shared by Bode and Nyquist."""

    omega: np.ndarray                   # rad/s
    loops: np.ndarray                   # (len(omega), m), continuous
    sampled_omega: np.ndarray | None    # rad/s, below the Nyquist frequency
    sampled_loops: np.ndarray | None


def _loop_response(report: MarginReport) -> _LoopResponse:
    resp = response_of(report.models.loop_input)        # the margins' own, shared
    omega = frequency_grid(resp, points_per_decade=_POINTS_PER_DECADE,
                           extra_poles=report.poles)
    loops = loop_at_a_time(resp(omega))
    wd = ld = None
    if report.sampled_models is not None:
        discrete = response_of(report.sampled_models.loop_input)
        wd = omega[omega < math.pi / report.sampled_models.dt]
        ld = loop_at_a_time(discrete(wd))
    return _LoopResponse(omega, loops, wd, ld)


def _names(report: MarginReport) -> list[str]:
    return [m.name for m in report.continuous.loops]


def _bode(report: MarginReport, r: _LoopResponse) -> Figure:
    names = _names(report)
    fig = Figure(figsize=(15, 6.5))
    ax = fig.subplots(2, len(names), sharex=True, squeeze=False)
    for i, name in enumerate(names):
        ax[0, i].semilogx(r.omega, 20 * np.log10(np.abs(r.loops[:, i])), label="continuous")
        ax[1, i].semilogx(r.omega, np.degrees(np.unwrap(np.angle(r.loops[:, i]))))
        if r.sampled_loops is not None:
            ax[0, i].semilogx(r.sampled_omega, 20 * np.log10(np.abs(r.sampled_loops[:, i])),
                              "--", label="sampled")
            ax[1, i].semilogx(r.sampled_omega,
                              np.degrees(np.unwrap(np.angle(r.sampled_loops[:, i]))), "--")
        ax[0, i].axhline(0, color="k", lw=0.6)
        ax[0, i].set_title(f"{name} loop (others closed)")
        ax[1, i].set_xlabel("frequency [rad/s]")
        ax[0, i].grid(True, which="both", alpha=0.3)
        ax[1, i].grid(True, which="both", alpha=0.3)
    ax[0, 0].set_ylabel("|L| [dB]")
    ax[1, 0].set_ylabel("arg L [deg]")
    ax[0, 0].legend()
    fig.tight_layout()
    return fig


def _nyquist(report: MarginReport, r: _LoopResponse) -> Figure:
    names = _names(report)
    fig = Figure(figsize=(10, 9))
    ax = fig.subplots(2, 2)
    t = np.linspace(0, 2 * np.pi, 200)
    for i, (name, a) in enumerate(zip(names, ax.ravel(), strict=True)):
        curves = [(r.loops[:, i], "-", "C0")]
        if r.sampled_loops is not None:
            curves.append((r.sampled_loops[:, i], "--", "C1"))
        for vals, style, color in curves:
            a.plot(vals.real, vals.imag, style, color=color)
            a.plot(vals.real, -vals.imag, style, color=color, alpha=0.35)
        a.plot(np.cos(t), np.sin(t), "k:", lw=0.6)
        a.plot([-1], [0], "r+", ms=12)
        a.set_xlim(-3, 2)
        a.set_ylim(-2.5, 2.5)
        a.set_aspect("equal")
        a.set_title(f"{name} loop: Nyquist (zoom on -1)")
        a.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def _sigma(report: MarginReport, omega: np.ndarray) -> Figure:
    sS, sT = sensitivity_sigma(report.models.loop_input, omega)
    fig = Figure(figsize=(12, 4.5))
    ax = fig.subplots(1, 2, sharey=True)
    for a, sv, name in ((ax[0], sS, "S = (I + L)^-1"), (ax[1], sT, "T = I - S")):
        a.semilogx(omega, 20 * np.log10(sv))
        a.set_title(f"singular values of {name} at the plant input")
        a.set_xlabel("frequency [rad/s]")
        a.grid(True, which="both", alpha=0.3)
    ax[0].set_ylabel("sigma [dB]")
    fig.tight_layout()
    return fig


def bode_plot(report: MarginReport) -> Figure:
    """Bode diagram of each loop with the others closed.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    matplotlib.figure.Figure
        Two rows of one axis per loop: magnitude of ``l_i`` (dB, with the
        0 dB line) and its unwrapped phase (deg) against frequency (rad/s);
        the sampled loop dashed.
    """
    return _bode(report, _loop_response(report))


def nyquist_plot(report: MarginReport) -> Figure:
    """Nyquist diagram of each loop with the others closed, zoomed on -1.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    matplotlib.figure.Figure
        One axis per loop (2 x 2): ``l_i(j w)`` for ``w > 0`` and its mirror
        image (faint), the unit circle and the critical point -1; the
        sampled loop dashed.
    """
    return _nyquist(report, _loop_response(report))


def sigma_plot(report: MarginReport) -> Figure:
    """Singular values of S and T at the plant input.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: the singular values (dB) of ``S = (I + L)^-1`` and of
        ``T = I - S`` of the continuous loop against frequency (rad/s), one
        line per singular value, largest first.
    """
    return _sigma(report, _loop_response(report).omega)


def pole_plot(report: MarginReport) -> Figure:
    """Map of the continuous closed loop's poles.

    Parameters
    ----------
    report : MarginReport

    Returns
    -------
    matplotlib.figure.Figure
        Two axes: every pole, and a zoom on the slow adaptive and
        translational poles near the origin.
    """
    p = report.poles
    fig = Figure(figsize=(12, 5))
    ax = fig.subplots(1, 2)
    for a, zoom in zip(ax, (False, True), strict=True):
        a.plot(p.real, p.imag, "x")
        a.axvline(0, color="k", lw=0.6)
        a.set_xlabel("Re [1/s]")
        a.set_ylabel("Im [rad/s]")
        a.grid(True, alpha=0.3)
        if zoom:
            a.set_xlim(-0.5, 0.05)
            a.set_ylim(-0.3, 0.3)
            a.set_title("zoom: the slow adaptive and translational poles")
        else:
            a.set_title(f"closed-loop poles ({p.size})")
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
        Keys are :data:`MARGIN_FIGURES`: Bode, Nyquist, singular values and poles.
        The frequency responses are evaluated once for all of them.
    """
    r = _loop_response(report)
    return dict(zip(MARGIN_FIGURES, (_bode(report, r), _nyquist(report, r), _sigma(report, r.omega),
                              pole_plot(report)), strict=True))

"""Figures and an animation of a landing on a moving deck.

A landing result is anything with ``result[name]`` (a NumPy array per
column: ``t``, ``phase``, both bodies' poses ``x1 .. psi1`` and
``x2 .. psi2`` in E, the relative position ``x_e, y_e, z_e`` in the deck
frame, ``F_total``, ``M_x .. M_z``, ``F_1 .. F_4``, ``d_Fx .. d_Fz``) and
``result.scenario`` (:class:`LandingResult`). E has z up; attitudes are ZYX
Euler angles, ``R = Rz(psi) Ry(theta) Rx(phi)``; phases are
:data:`quadland_symbolic.landing.guidance.PHASES`.
"""

from __future__ import annotations

import types
from collections.abc import Mapping
from typing import Protocol

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from quadland.plots.finite import drawable
from quadland.plots.navigation import NAVIGATION_FIGURES, has_estimate, navigation_plot
from quadland.plots.overlay import redraw_legend, run_index, run_tag
from quadland.plots.style import finish
from quadland.scenario import Scenario
from quadland_symbolic.landing.guidance import PHASES, TOUCHDOWN
from quadland_symbolic.landing.relative import TOUCHDOWN_LIMITS

__all__ = ["LANDING_FIGURES", "LIMIT_NAMES", "PAD_SIZE", "LandingResult", "landing_limits",
           "pad_size_of", "body_rotation", "deck_rectangle", "touchdown_row",
           "trajectory_3d_plot", "relative_position_plot", "landing_ground_track_plot",
           "rotor_forces_plot", "landing_figures"]

#: File name and title of each figure, in the order of :func:`landing_figures`.
LANDING_FIGURES = types.MappingProxyType({
    "landing_3d.png": "Quadrotor relative to the pad centre, equal scales",
    "relative_position.png": "Relative position, speeds and tilt against the touchdown limits",
    "ground_tracks.png": "Ground tracks of the quadrotor and the pad centre",
    "rotor_forces.png": "Rotor forces against their limits",
})

#: The limits a landing's figures can draw: sink rate (m/s), horizontal offset (m),
#: tilt from the deck normal (deg), horizontal relative speed (m/s), and the
#: largest force of one rotor (N). The loop kind gives their values
#: (``quadland.kinds.landing.report.touchdown_limits``).
LIMIT_NAMES = (*TOUCHDOWN_LIMITS, "F_max")

#: m, side of the square pad drawn when the scenario gives no ``pad_size``.
PAD_SIZE = 1.0

#: Shading of each phase, by number (approach, align, descend, touchdown, landed).
_PHASE_COLORS = ("#9ecae1", "#fdd0a2", "#a1d99b", "#fc9272", "#bcbddc")


class LandingResult(Protocol):
    """What the landing figures read: columns by name and the scenario."""

    scenario: Scenario

    def __getitem__(self, name: str) -> np.ndarray: ...


def landing_limits(limits: Mapping | None = None) -> dict:
    """The limits a figure draws, each :data:`LIMIT_NAMES` entry or None (not drawn).

    Parameters
    ----------
    limits : mapping, optional
        Any of :data:`LIMIT_NAMES`, in their units; the landing loop kind
        passes the scenario's (``quadland.kinds.landing.report.touchdown_limits``).

    Raises
    ------
    ValueError
        ``limits`` has a key that is not a limit.
    """
    limits = dict(limits or {})
    unknown = sorted(set(limits) - set(LIMIT_NAMES))
    if unknown:
        raise ValueError(f"landing_limits: unknown limit(s) {', '.join(unknown)}; "
                         f"known: {', '.join(LIMIT_NAMES)}")
    return {k: None if limits.get(k) is None else float(limits[k]) for k in LIMIT_NAMES}


def touchdown_row(result: LandingResult) -> int | None:
    """Index of the first row at touchdown or later (phase >= 3), None if none."""
    rows = np.flatnonzero(np.asarray(result["phase"]) >= TOUCHDOWN)
    return int(rows[0]) if rows.size else None


def pad_size_of(result: LandingResult) -> float:
    """The landing pad's side, m: the scenario's ``pad_size``, else :data:`PAD_SIZE`."""
    data = result.scenario.data
    for section in ("landing", "deck"):
        if "pad_size" in data.get(section, {}):
            return float(data[section]["pad_size"])
    return PAD_SIZE


def body_rotation(phi, theta, psi) -> np.ndarray:
    """``Rz(psi) Ry(theta) Rx(phi)``, (..., 3, 3), body to E."""
    cf, sf, ct, st, cp, sp = (np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta),
                              np.cos(psi), np.sin(psi))
    return np.stack([
        np.stack([cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf], -1),
        np.stack([sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf], -1),
        np.stack([-st, ct * sf, ct * cf], -1),
    ], -2)


def deck_rectangle(result: LandingResult, row: int, length: float, width: float) -> np.ndarray:
    """Corners (4, 3) in E of a rectangle centred on the pad in the deck plane.

    ``length`` is along the deck's x axis (its heading), ``width`` along y.
    """
    R = body_rotation(*(result[n][row] for n in ("phi2", "theta2", "psi2")))
    p2 = np.array([result[n][row] for n in ("x2", "y2", "z2")])
    a, b = length / 2, width / 2
    corners = np.array([[a, b, 0.0], [-a, b, 0.0], [-a, -b, 0.0], [a, -b, 0.0]])
    return p2 + corners @ R.T


def _phase_runs(result: LandingResult) -> list[tuple[int, float, float]]:
    """``(phase, t_start, t_end)`` of each run of one phase; a run ends where the next starts."""
    t, phase = np.asarray(result["t"]), np.asarray(result["phase"]).astype(int)
    starts = np.r_[0, np.flatnonzero(np.diff(phase)) + 1]
    ends = np.r_[starts[1:], len(t) - 1]
    return [(int(phase[s]), float(t[s]), float(t[e])) for s, e in zip(starts, ends, strict=True)]


def _shade_phases(fig: Figure, axes, result: LandingResult) -> None:
    """An axvspan per phase run on every axis, and a figure legend of the phases shown."""
    runs = _phase_runs(result)
    for a in axes:
        for p, t0, t1 in runs:
            a.axvspan(t0, t1, color=_PHASE_COLORS[p], alpha=0.5, lw=0, zorder=0,
                      label="_phase")
    shown = sorted({p for p, _, _ in runs})
    fig.legend(handles=[Patch(color=_PHASE_COLORS[p], alpha=0.5, label=PHASES[p])
                        for p in shown],
               loc="upper center", bbox_to_anchor=(0.5, 1 - 0.4 / fig.get_figheight()),
               ncols=len(shown), fontsize="small", frameon=False)


def _time_grid(title: str, rows: int):
    fig = Figure(figsize=(7, 1.9 * rows + 0.9))
    axes = fig.subplots(rows, 1, sharex=True)
    fig.suptitle(title, y=1 - 0.1 / fig.get_figheight(), va="top")
    return fig, axes


def _limit_lines(ax, values, label: str, ls: str = ":") -> None:
    """Horizontal lines at ``values`` (a None limit is not drawn)."""
    for i, v in enumerate(x for x in values if x is not None):
        ax.axhline(v, color="k", ls=ls, lw=1, label=label if i == 0 else "_limit")


def _touchdown_lines(ax, result: LandingResult, values, label: str, ls: str = ":") -> None:
    """Segments at ``values`` from the touchdown to the end, where a touchdown limit
    applies (none without a touchdown; a None limit is not drawn). ``gid`` "limit"."""
    row = touchdown_row(result)
    if row is None:
        return
    t = np.asarray(result["t"])
    for i, v in enumerate(x for x in values if x is not None):
        ax.plot([t[row], t[-1]], [v, v], color="k", ls=ls, lw=1.5, gid="limit",
                label=label if i == 0 else "_limit")


def _finish_time(fig: Figure, result: LandingResult, axes, own: bool = True) -> Figure:
    """The legends (again, over every run in an overlay); a new figure's phases and frame."""
    for a in axes:
        redraw_legend(a, loc="best", fontsize="small")   # clear of the touchdown limits
    if not own:
        return fig
    _shade_phases(fig, axes, result)
    finish(fig, result, axes)
    fig.subplots_adjust(top=1 - 0.8 / fig.get_figheight())    # room for the phase legend
    return fig


def trajectory_3d_plot(result: LandingResult, pad_size: float | None = None,
                       ax=None, label: str | None = None) -> Figure:
    """The approach in 3D, seen from the pad centre, equal scales.

    Parameters
    ----------
    result : LandingResult
    pad_size : float, optional
        m, side of the square pad; by default the scenario's ``pad_size`` (in
        ``[landing]`` or ``[deck]``), else :data:`PAD_SIZE`.
    ax : matplotlib 3D Axes, optional
        Where to draw (``projection="3d"``), to overlay runs (each in its own
        colours, its lines labelled with ``label``); a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name in an
        overlay, none alone.

    Returns
    -------
    matplotlib.figure.Figure
        One 3D axis, m, along E's axes with the origin on the pad centre (the
        deck's travel, tens of metres against a few of height, is the ground
        track's): the quadrotor's ``(x1 - x2, y1 - y2, z1 - z2)`` and its
        start, the pad centre, and the pad as a closed square (5 vertices) in
        the deck plane at :func:`touchdown_row` (at the last row, labelled
        so, when there is no touchdown). Equal scales: a metre is as long on
        every axis (the box has the proportions of the flight, each side at
        least a pad).
    """
    size = pad_size_of(result) if pad_size is None else float(pad_size)
    own = ax is None
    if own:
        fig = Figure(figsize=(8, 6.5))
        ax = fig.add_subplot(projection="3d")
    fig, a = ax.figure, ax
    tag, run = run_tag(result, label, own), run_index(ax, "quadrotor")
    rel = [np.asarray(result[f"{n}1"], dtype=float) - np.asarray(result[f"{n}2"], dtype=float)
           for n in "xyz"]
    a.plot(*rel, color=f"C{2 * run % 10}", label=f"quadrotor{tag}", gid="quadrotor")
    a.plot(*[[r[0]] for r in rel], "o", color=f"C{2 * run % 10}",
           label=f"quadrotor start{tag}")
    a.plot([0.0], [0.0], [0.0], "o", color="C1", label="pad centre")
    row = touchdown_row(result)
    what = "pad at touchdown"
    if row is None:
        row, what = len(result["t"]) - 1, "pad at the end (no touchdown)"
    square = deck_rectangle(result, row, size, size)
    closed = np.vstack([square, square[:1]]) - [result[f"{n}2"][row] for n in "xyz"]
    a.plot(closed[:, 0], closed[:, 1], closed[:, 2], color=f"C{(2 * run + 3) % 10}",
           label=what + tag)
    drawn = [np.column_stack(ln.get_data_3d()) for ln in a.lines]    # an overlay's too
    _equal_scales(a, np.vstack(drawn), size)
    a.set_xlabel("x - x2 [m]")
    a.set_ylabel("y - y2 [m]")
    a.set_zlabel("z - z2 [m]")
    a.set_title(LANDING_FIGURES["landing_3d.png"])
    redraw_legend(a, loc="upper left", fontsize="small")
    return finish(fig, result) if own else fig


def _equal_scales(a, points: np.ndarray, least: float) -> None:
    """Limits around ``points`` and a box of the same proportions: one metre is as long
    on every axis (an axis spans at least ``least``, so a flat flight keeps a visible box)."""
    lo, hi = np.nanmin(points, axis=0), np.nanmax(points, axis=0)
    span = np.maximum(hi - lo, least) * 1.05
    mid = (lo + hi) / 2
    a.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
    a.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
    a.set_zlim(mid[2] - span[2] / 2, mid[2] + span[2] / 2)
    a.set_box_aspect(tuple(span), zoom=0.9)


def relative_position_plot(result: LandingResult, limits: Mapping | None = None,
                           ax=None, label: str | None = None) -> Figure:
    """Relative position, speeds and tilt over time against the limits.

    Parameters
    ----------
    result : LandingResult
    limits : mapping, optional
        See :func:`landing_limits`.
    ax : sequence of four matplotlib Axes, optional
        Where to draw, to overlay runs (no phase shading then; each run's
        lines labelled with ``label``, the legends drawn again); a new figure
        if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name in an
        overlay, none alone.

    Returns
    -------
    matplotlib.figure.Figure
        Four time axes, the guidance phases shaded (one ``axvspan`` per run
        of a phase, a figure legend of their names):

        0. ``x_e``, ``y_e`` and the offset ``hypot(x_e, y_e)``, m, with
           ``+-max_offset``;
        1. ``z_e``, m;
        2. the horizontal relative speed ``hypot(dx_e, dy_e)`` with
           ``max_relative_speed`` and the sink rate ``-dz_e`` with
           ``max_sink_rate``, m/s (the result's own ``dx_e``, ``dy_e``, ``dz_e``);
        3. the tilt of the thrust axis from the deck normal, deg, with
           ``max_tilt_deg``.

        The touchdown limits hold at touchdown: each is a black segment
        (dotted, the sink rate's dashed; ``gid`` "limit") from
        :func:`touchdown_row`'s time to the end, after the data lines, and
        is not drawn without a touchdown (the descent above the deck is not
        held to them).
    """
    lim = landing_limits(limits)
    t = np.asarray(result["t"])
    x_e, y_e, z_e = (np.asarray(result[n]) for n in ("x_e", "y_e", "z_e"))
    own = ax is None
    tag = run_tag(result, label, own)
    fig, ax = _time_grid(LANDING_FIGURES["relative_position.png"], 4) if own else \
        (ax[0].figure, list(ax))
    ax[0].plot(t, x_e, label=f"x_e{tag}")
    ax[0].plot(t, y_e, label=f"y_e{tag}")
    ax[0].plot(t, np.hypot(x_e, y_e), label=f"offset{tag}")
    offset = lim["max_offset"]
    _touchdown_lines(ax[0], result, () if offset is None else (offset, -offset), "max_offset")
    ax[0].set_ylabel("position [m]")
    ax[1].plot(t, z_e, label=f"z_e{tag}")
    ax[1].set_ylabel("z_e [m]")
    ax[2].plot(t, np.hypot(result["dx_e"], result["dy_e"]), label=f"horizontal speed{tag}")
    ax[2].plot(t, -np.asarray(result["dz_e"]), label=f"sink rate{tag}")
    _touchdown_lines(ax[2], result, (lim["max_relative_speed"],), "max_relative_speed")
    _touchdown_lines(ax[2], result, (lim["max_sink_rate"],), "max_sink_rate", ls="--")
    ax[2].set_ylabel("speed [m/s]")
    ax[3].plot(t, result["tilt_deg"], label=f"tilt from deck normal{tag}")
    _touchdown_lines(ax[3], result, (lim["max_tilt_deg"],), "max_tilt_deg")
    ax[3].set_ylabel("tilt [deg]")
    return _finish_time(fig, result, ax, own)


def landing_ground_track_plot(result: LandingResult, ax=None,
                              label: str | None = None) -> Figure:
    """Both tracks from above, the starts and the touchdown, with a true-scale inset.

    Parameters
    ----------
    result : LandingResult
    ax : matplotlib Axes, optional
        Where to draw the tracks, to overlay runs (each in its own colours,
        its lines labelled with ``label``); a new figure if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name in an
        overlay, none alone.

    Returns
    -------
    matplotlib.figure.Figure
        One axis, m, its scales free so that the approach shows whatever the
        deck's travel: ``(x2, y2)``, ``(x1, y1)`` (dashed), the two starts
        (circles) and, if there is a touchdown, both positions at
        :func:`touchdown_row` (crosses). With a touchdown (and a new
        figure), an inset with equal scales, four pads wide, around the pad
        at touchdown: both tracks and the pad square.
    """
    own = ax is None
    if own:
        fig = Figure(figsize=(8, 5))
        ax = fig.subplots()
    fig, a = ax.figure, ax
    _tracks(a, result, markers=True, tag=run_tag(result, label, own), n=run_index(a, "quadrotor"))
    row = touchdown_row(result)
    if own and row is not None:
        _touchdown_inset(a, result, row)
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_title(LANDING_FIGURES["ground_tracks.png"])
    redraw_legend(a, loc="best", fontsize="small")
    a.grid(True)
    return finish(fig, result) if own else fig


def _tracks(a, result: LandingResult, markers: bool, tag: str = "", n: int = 0) -> None:
    """The pad's and the quadrotor's tracks, the ``n``-th run's colours, labels + ``tag``."""
    pad, quad = f"C{(2 * n + 1) % 10}", f"C{2 * n % 10}"
    a.plot(result["x2"], result["y2"], color=pad, label=f"pad centre{tag}")
    a.plot(result["x1"], result["y1"], "--", color=quad, label=f"quadrotor{tag}",
           gid="quadrotor")
    if not markers:
        return
    a.plot(result["x2"][0], result["y2"][0], "o", color=pad, label=f"pad start{tag}")
    a.plot(result["x1"][0], result["y1"][0], "o", color=quad, label=f"quadrotor start{tag}")
    row = touchdown_row(result)
    if row is not None:
        a.plot(result["x2"][row], result["y2"][row], "x", color=pad, ms=10,
               label=f"pad at touchdown{tag}")
        a.plot(result["x1"][row], result["y1"][row], "+", color=quad, ms=12,
               label=f"quadrotor at touchdown{tag}")


def _touchdown_inset(a, result: LandingResult, row: int) -> None:
    """Equal scales, four pads wide, around the pad centre at touchdown."""
    size = pad_size_of(result)
    inset = a.inset_axes((0.4, 0.3, 0.3, 0.55))     # the middle: the tracks run low
    _tracks(inset, result, markers=False)
    square = deck_rectangle(result, row, size, size)
    closed = np.vstack([square, square[:1]])
    inset.plot(closed[:, 0], closed[:, 1], color="C3", label="pad at touchdown")
    cx, cy = result["x2"][row], result["y2"][row]
    inset.set_xlim(cx - 2 * size, cx + 2 * size)
    inset.set_ylim(cy - 2 * size, cy + 2 * size)
    inset.set_aspect("equal")
    inset.set_title("at touchdown, equal scales", fontsize="x-small")
    inset.tick_params(labelsize="x-small")
    inset.grid(True, alpha=0.3)


def rotor_forces_plot(result: LandingResult, limits: Mapping | None = None,
                      ax=None, label: str | None = None) -> Figure:
    """Rotor forces and their sum against ``[0, F_max]``.

    Parameters
    ----------
    result : LandingResult
    limits : mapping, optional
        See :func:`landing_limits`; only ``F_max`` is read.
    ax : sequence of two matplotlib Axes, optional
        Where to draw, to overlay runs (no phase shading then; each run's
        lines labelled with ``label``, the legends drawn again); a new figure
        if None.
    label : str, optional
        The run's name in the legend; by default its scenario's name in an
        overlay, none alone.

    Returns
    -------
    matplotlib.figure.Figure
        Two time axes, phases shaded: ``F_1 .. F_4`` with ``0`` and ``F_max``,
        and ``F_total`` with ``0`` and ``4 F_max``, N (without an upper line
        when ``F_max`` is unknown).
    """
    F_max = landing_limits(limits)["F_max"]
    t = result["t"]
    own = ax is None
    tag = run_tag(result, label, own)
    fig, ax = _time_grid(LANDING_FIGURES["rotor_forces.png"], 2) if own else \
        (ax[0].figure, list(ax))
    for k in range(1, 5):
        ax[0].plot(t, result[f"F_{k}"], label=f"F_{k}{tag}")
    ax[1].plot(t, result["F_total"], label=f"F_total{tag}")
    for a, n in ((ax[0], 1), (ax[1], 4)):
        _limit_lines(a, (0.0,) if F_max is None else (0.0, n * F_max),
                     "0" if F_max is None else f"[0, {'4 ' * (n == 4)}F_max]")
    ax[0].set_ylabel("rotor force [N]")
    ax[1].set_ylabel("F_total [N]")
    return _finish_time(fig, result, ax, own)


def landing_figures(result: LandingResult, limits: Mapping | None = None) -> dict[str, Figure]:
    """Every landing figure, by the file name it is saved under.

    Parameters
    ----------
    result : LandingResult
    limits : mapping, optional
        See :func:`landing_limits`.

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        Keys are those of :data:`LANDING_FIGURES`, in that order, then, for a landing
        flown on its sensors (:func:`quadland.plots.navigation.has_estimate`), those of
        :data:`quadland.plots.navigation.NAVIGATION_FIGURES`: the filter's estimate, the
        truth and its 3-sigma band (a landing on the true state has no estimate to draw).
    """
    result = drawable(result)                 # a failed flight's last rows may diverge
    figs = (trajectory_3d_plot(result), relative_position_plot(result, limits),
            landing_ground_track_plot(result), rotor_forces_plot(result, limits))
    out = dict(zip(LANDING_FIGURES, figs, strict=True))
    if has_estimate(result):
        out.update(zip(NAVIGATION_FIGURES, (navigation_plot(result),), strict=True))
    return out


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

import io
import math
import types
from collections.abc import Mapping
from pathlib import Path
from typing import Protocol

import numpy as np
from matplotlib.animation import PillowWriter
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from PIL import Image

from quadland.exceptions import QuadlandError
from quadland.plots.finite import drawable
from quadland.plots.style import finish
from quadland.scenario import Scenario
from quadland_symbolic.landing.guidance import PHASES, TOUCHDOWN

__all__ = ["LANDING_FIGURES", "LIMIT_NAMES", "PAD_SIZE", "LandingResult", "landing_limits",
           "touchdown_row", "trajectory_3d_plot", "relative_position_plot", "ground_track_plot",
           "rotor_forces_plot", "landing_figures", "landing_animation"]

#: File name and title of each figure, in the order of :func:`landing_figures`.
LANDING_FIGURES = types.MappingProxyType({
    "landing_3d.png": "Quadrotor and pad centre in E",
    "relative_position.png": "Relative position, speeds and tilt against the touchdown limits",
    "ground_tracks.png": "Ground tracks of the quadrotor and the pad centre",
    "rotor_forces.png": "Rotor forces against their limits",
})

#: The limits a landing's figures can draw: sink rate (m/s), horizontal offset (m),
#: tilt from the deck normal (deg), horizontal relative speed (m/s), and the
#: largest force of one rotor (N). The loop kind gives their values
#: (``quadland.kinds.landing.report.touchdown_limits``).
LIMIT_NAMES = ("max_sink_rate", "max_offset", "max_tilt_deg", "max_relative_speed", "F_max")

#: m, side of the square pad drawn when the scenario gives no ``pad_size``.
PAD_SIZE = 1.0

#: Shading of each phase, by number (approach, align, descend, touchdown, landed).
_PHASE_COLORS = ("#9ecae1", "#fdd0a2", "#a1d99b", "#fc9272", "#bcbddc")

#: s, the longest animation: a longer landing is played faster.
_MAX_PLAYBACK = 12.0
#: m, farthest from E's origin the animation follows a body: a failed flight that
#: leaves this box (or whose pose stops being finite) is animated up to the row before.
_SCENE_EXTENT = 1e6


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


def _pad_size(result: LandingResult) -> float:
    data = result.scenario.data
    for section in ("landing", "deck"):
        if "pad_size" in data.get(section, {}):
            return float(data[section]["pad_size"])
    return PAD_SIZE


def _rotation(phi, theta, psi) -> np.ndarray:
    """``Rz(psi) Ry(theta) Rx(phi)``, (..., 3, 3), body to E."""
    cf, sf, ct, st, cp, sp = (np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta),
                              np.cos(psi), np.sin(psi))
    return np.stack([
        np.stack([cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf], -1),
        np.stack([sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf], -1),
        np.stack([-st, ct * sf, ct * cf], -1),
    ], -2)


def _deck_rectangle(result: LandingResult, row: int, length: float, width: float) -> np.ndarray:
    """Corners (4, 3) in E of a rectangle centred on the pad in the deck plane.

    ``length`` is along the deck's x axis (its heading), ``width`` along y.
    """
    R = _rotation(*(result[n][row] for n in ("phi2", "theta2", "psi2")))
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


def _finish_time(fig: Figure, result: LandingResult, axes) -> Figure:
    for a in axes:
        a.legend(loc="upper right", fontsize="small")
    finish(fig, result, axes)
    fig.subplots_adjust(top=1 - 0.8 / fig.get_figheight())    # room for the phase legend
    return fig


def trajectory_3d_plot(result: LandingResult, pad_size: float | None = None) -> Figure:
    """Both trajectories in 3D, the pad at touchdown and the starts.

    Parameters
    ----------
    result : LandingResult
    pad_size : float, optional
        m, side of the square pad; by default the scenario's ``pad_size`` (in
        ``[landing]`` or ``[deck]``), else :data:`PAD_SIZE`.

    Returns
    -------
    matplotlib.figure.Figure
        One 3D axis, m: lines ``(x1, y1, z1)`` and ``(x2, y2, z2)``, each
        start as a marker, and the pad as a closed square (5 vertices) in the
        deck plane at :func:`touchdown_row` (at the last row, labelled so,
        when there is no touchdown).
    """
    size = _pad_size(result) if pad_size is None else float(pad_size)
    fig = Figure(figsize=(7, 6))
    a = fig.add_subplot(projection="3d")
    a.plot(result["x1"], result["y1"], result["z1"], color="C0", label="quadrotor")
    a.plot(result["x2"], result["y2"], result["z2"], color="C1", label="pad centre")
    a.plot([result["x1"][0]], [result["y1"][0]], [result["z1"][0]], "o", color="C0",
           label="quadrotor start")
    a.plot([result["x2"][0]], [result["y2"][0]], [result["z2"][0]], "o", color="C1",
           label="pad start")
    row = touchdown_row(result)
    label = "pad at touchdown"
    if row is None:
        row, label = len(result["t"]) - 1, "pad at the end (no touchdown)"
    square = _deck_rectangle(result, row, size, size)
    closed = np.vstack([square, square[:1]])
    a.plot(closed[:, 0], closed[:, 1], closed[:, 2], color="C3", label=label)
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_zlabel("z [m]")
    a.set_title(LANDING_FIGURES["landing_3d.png"])
    a.legend(loc="upper left", fontsize="small")
    return finish(fig, result)


def relative_position_plot(result: LandingResult, limits: Mapping | None = None) -> Figure:
    """Relative position, speeds and tilt over time against the limits.

    Parameters
    ----------
    result : LandingResult
    limits : mapping, optional
        See :func:`landing_limits`.

    Returns
    -------
    matplotlib.figure.Figure
        Four time axes, the guidance phases shaded (one ``axvspan`` per run
        of a phase, a figure legend of their names):

        0. ``x_e``, ``y_e`` and the offset ``hypot(x_e, y_e)``, m, with
           ``+-max_offset``;
        1. ``z_e``, m;
        2. the horizontal relative speed ``hypot(dx_e/dt, dy_e/dt)`` with
           ``max_relative_speed`` and the sink rate ``-dz_e/dt`` with
           ``max_sink_rate``, m/s (central differences of the columns);
        3. the tilt of the thrust axis from the deck normal, deg, with
           ``max_tilt_deg``.

        Limit lines are dotted black, after the data lines.
    """
    lim = landing_limits(limits)
    t = np.asarray(result["t"])
    x_e, y_e, z_e = (np.asarray(result[n]) for n in ("x_e", "y_e", "z_e"))
    fig, ax = _time_grid(LANDING_FIGURES["relative_position.png"], 4)
    ax[0].plot(t, x_e, label="x_e")
    ax[0].plot(t, y_e, label="y_e")
    ax[0].plot(t, np.hypot(x_e, y_e), label="offset")
    offset = lim["max_offset"]
    _limit_lines(ax[0], () if offset is None else (offset, -offset), "max_offset")
    ax[0].set_ylabel("position [m]")
    ax[1].plot(t, z_e, label="z_e")
    ax[1].set_ylabel("z_e [m]")
    ax[2].plot(t, np.hypot(result["dx_e"], result["dy_e"]), label="horizontal speed")
    ax[2].plot(t, -np.asarray(result["dz_e"]), label="sink rate")
    _limit_lines(ax[2], (lim["max_relative_speed"],), "max_relative_speed")
    _limit_lines(ax[2], (lim["max_sink_rate"],), "max_sink_rate", ls="--")
    ax[2].set_ylabel("speed [m/s]")
    ax[3].plot(t, result["tilt_deg"], label="tilt from deck normal")
    _limit_lines(ax[3], (lim["max_tilt_deg"],), "max_tilt_deg")
    ax[3].set_ylabel("tilt [deg]")
    _shade_phases(fig, ax, result)
    return _finish_time(fig, result, ax)


def ground_track_plot(result: LandingResult) -> Figure:
    """Both tracks from above, the starts and the touchdown.

    Parameters
    ----------
    result : LandingResult

    Returns
    -------
    matplotlib.figure.Figure
        One axis, equal scales, m: ``(x2, y2)``, ``(x1, y1)`` (dashed), the
        two starts (circles) and, if there is a touchdown, both positions at
        :func:`touchdown_row` (crosses).
    """
    fig = Figure(figsize=(6, 6))
    a = fig.subplots()
    a.plot(result["x2"], result["y2"], color="C1", label="pad centre")
    a.plot(result["x1"], result["y1"], "--", color="C0", label="quadrotor")
    a.plot(result["x2"][0], result["y2"][0], "o", color="C1", label="pad start")
    a.plot(result["x1"][0], result["y1"][0], "o", color="C0", label="quadrotor start")
    row = touchdown_row(result)
    if row is not None:
        a.plot(result["x2"][row], result["y2"][row], "x", color="C1", ms=10,
               label="pad at touchdown")
        a.plot(result["x1"][row], result["y1"][row], "+", color="C0", ms=12,
               label="quadrotor at touchdown")
    a.set_xlabel("x [m]")
    a.set_ylabel("y [m]")
    a.set_aspect("equal", adjustable="datalim")
    a.set_title(LANDING_FIGURES["ground_tracks.png"])
    a.legend(loc="best", fontsize="small")
    a.grid(True)
    return finish(fig, result)


def rotor_forces_plot(result: LandingResult, limits: Mapping | None = None) -> Figure:
    """Rotor forces and their sum against ``[0, F_max]``.

    Parameters
    ----------
    result : LandingResult
    limits : mapping, optional
        See :func:`landing_limits`; only ``F_max`` is read.

    Returns
    -------
    matplotlib.figure.Figure
        Two time axes, phases shaded: ``F_1 .. F_4`` with ``0`` and ``F_max``,
        and ``F_total`` with ``0`` and ``4 F_max``, N (without an upper line
        when ``F_max`` is unknown).
    """
    F_max = landing_limits(limits)["F_max"]
    t = result["t"]
    fig, ax = _time_grid(LANDING_FIGURES["rotor_forces.png"], 2)
    for k in range(1, 5):
        ax[0].plot(t, result[f"F_{k}"], label=f"F_{k}")
    ax[1].plot(t, result["F_total"], label="F_total")
    for a, n in ((ax[0], 1), (ax[1], 4)):
        _limit_lines(a, (0.0,) if F_max is None else (0.0, n * F_max),
                     "0" if F_max is None else f"[0, {'4 ' * (n == 4)}F_max]")
    ax[0].set_ylabel("rotor force [N]")
    ax[1].set_ylabel("F_total [N]")
    _shade_phases(fig, ax, result)
    return _finish_time(fig, result, ax)


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
        Keys are those of :data:`LANDING_FIGURES`, in that order.
    """
    result = drawable(result)                 # a failed flight's last rows may diverge
    figs = (trajectory_3d_plot(result), relative_position_plot(result, limits),
            ground_track_plot(result), rotor_forces_plot(result, limits))
    return dict(zip(LANDING_FIGURES, figs, strict=True))


def _frame_rows(t: np.ndarray, fps: float) -> np.ndarray:
    """Rows shown as frames: evenly spaced in time, at most ``_MAX_PLAYBACK * fps + 1``.

    A landing of ``T`` seconds plays in ``min(T, _MAX_PLAYBACK)`` seconds:
    ``round(min(T, _MAX_PLAYBACK) * fps) + 1`` frames (no more than the
    rows), each the row nearest its time (the earlier on a tie), so the
    first and the last rows are shown. A row nearest two times is shown once.
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return np.zeros(len(t), dtype=int)
    n = min(len(t), round(min(float(t[-1] - t[0]), _MAX_PLAYBACK) * fps) + 1)
    times = np.linspace(t[0], t[-1], max(n, 2))
    right = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    left = right - 1
    return np.unique(np.where(times - t[left] <= t[right] - times, left, right))


def _nice(x: float) -> float:
    """The smallest of 1, 2, 5 times a power of ten that is >= x."""
    p = 10.0 ** math.floor(math.log10(x))
    return next(m * p for m in (1, 2, 5, 10) if m * p >= x)


def _grid_lines(cx: float, cy: float, half: float, z: float) -> tuple[np.ndarray, float]:
    """A horizontal grid fixed in E, over ``[c - half, c + half]``, as one NaN-separated line."""
    step = _nice(half / 2)
    xs = np.arange(math.ceil((cx - half) / step), math.floor((cx + half) / step) + 1) * step
    ys = np.arange(math.ceil((cy - half) / step), math.floor((cy + half) / step) + 1) * step
    segments = [[(x, cy - half), (x, cy + half)] for x in xs]
    segments += [[(cx - half, y), (cx + half, y)] for y in ys]
    pts = np.array([p for seg in segments for p in (*seg, (np.nan, np.nan))]).reshape(-1, 2)
    return np.column_stack([pts, np.where(np.isnan(pts[:, 0]), np.nan, z)]), step


class _GifWriter(PillowWriter):
    """matplotlib's PillowWriter, each frame reduced to 256 colours as it comes.

    Pillow's fast octree quantizer takes a seventh of the time of the median
    cut that saving the GIF would otherwise run on every frame.
    """

    def setup(self, fig, outfile, dpi=None):
        super().setup(fig, outfile, dpi=dpi)
        self._paletted = []

    def grab_frame(self, **savefig_kwargs):
        buf = io.BytesIO()
        self.fig.savefig(buf, **{**savefig_kwargs, "format": "rgba", "dpi": self.dpi})
        im = Image.frombuffer("RGBA", self.frame_size, buf.getbuffer(), "raw", "RGBA", 0, 1)
        self._paletted.append(im.convert("RGB").quantize(256, Image.Quantize.FASTOCTREE))

    def finish(self):
        self._paletted[0].save(self.outfile, save_all=True, append_images=self._paletted[1:],
                               duration=int(1000 / self.fps), loop=0)


def landing_animation(result: LandingResult, path, fps: float = 20,
                      limits: Mapping | None = None) -> Path:
    """Write an animation of the landing: GIF, or MP4 through ffmpeg.

    Parameters
    ----------
    result : LandingResult
    path : str or os.PathLike
        Ends in ``.gif`` (matplotlib's PillowWriter) or ``.mp4`` (its
        FFMpegWriter: needs ffmpeg on the PATH).
    fps : float
        Frames per second of the animation.
    limits : mapping, optional
        See :func:`landing_limits`; the offset limit is shown in the text.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    QuadlandError
        ``path`` has another ending, or it ends in ``.mp4`` and ffmpeg is
        not found.

    Notes
    -----
    A 3D scene that follows the pair, equal scales on the three axes: the
    deck (a grey rectangle three pads long and two wide, in the deck plane
    at the pad, turned by ``psi2`` and tilted by ``phi2``, ``theta2``), the
    pad square, the quadrotor as the cross of its arms (rotor 1's arm red)
    turned by its attitude with a dotted line down to the pad's height,
    both trails, a grid on the ground (fixed in E at ``z = 0``, or lower if
    anything goes lower) that shows the deck's travel, and the time, phase,
    height and offset. The view is centred between the two bodies and is
    as wide as their distance needs, at least two pads each way; when it is
    wide the cross is drawn larger than life (at least a 25th of the view)
    so that it stays visible.

    Frames are rows evenly spaced in time: a landing of ``T`` seconds plays
    in ``min(T, 12)`` seconds, ``round(min(T, 12) * fps) + 1`` frames (at
    most one per row), a longer one sped up, as the text says. The same
    result gives the same file. A failed flight is animated up to its last
    row whose poses are finite and within 1e6 m of E's origin.

    Examples
    --------
    >>> from quadland.plots import landing_animation
    >>> landing_animation(result, "landing.gif")  # doctest: +SKIP
    """
    from matplotlib import animation
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".gif":
        writer = _GifWriter(fps=fps)
    elif suffix == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise QuadlandError(f"landing_animation: writing {path.name} needs ffmpeg, which "
                                "was not found on the PATH; install ffmpeg or write a .gif")
        writer = animation.FFMpegWriter(fps=fps)
    else:
        raise QuadlandError(f"landing_animation: cannot write {path.name!r}; "
                            "the animation is a .gif or an .mp4")

    result = drawable(result)
    lim = landing_limits(limits)
    pad = _pad_size(result)
    arm = float(result.scenario.data.get("quadrotor", {}).get("arm_length", 0.25))
    p1 = np.column_stack([result[n] for n in ("x1", "y1", "z1")]).astype(float)
    p2 = np.column_stack([result[n] for n in ("x2", "y2", "z2")]).astype(float)
    angles = np.column_stack([result[n] for n in ("phi1", "theta1", "psi1", "phi2", "theta2",
                                                  "psi2", "x_e", "y_e", "z_e")])
    sane = (np.all(np.abs(p1) <= _SCENE_EXTENT, axis=1)
            & np.all(np.abs(p2) <= _SCENE_EXTENT, axis=1) & np.all(np.isfinite(angles), axis=1))
    n = max(1, int(np.argmin(sane)) if not sane.all() else len(sane))   # the rows drawn
    t = np.asarray(result["t"], dtype=float)[:n]
    phase = np.asarray(result["phase"])[:n].astype(int)
    p1, p2 = p1[:n], p2[:n]
    R1 = _rotation(result["phi1"][:n], result["theta1"][:n], result["psi1"][:n])
    offset = np.hypot(result["x_e"][:n], result["y_e"][:n])
    z_ground = min(0.0, float(np.nanmin(p1[:, 2])), float(np.nanmin(p2[:, 2])))
    rows = _frame_rows(t, fps)
    speedup = (t[-1] - t[0]) / _MAX_PLAYBACK

    fig = Figure(figsize=(6.4, 5.2), dpi=80)
    FigureCanvasAgg(fig)
    # drawn in this order, not sorted by depth: the quadrotor is above the deck
    a = fig.add_axes((0.0, 0.0, 1.0, 0.9), projection="3d", computed_zorder=False)
    a.set_box_aspect((1, 1, 1), zoom=1.4)
    a.set_axis_off()
    ground, = a.plot([], [], [], color="0.8", lw=0.8, zorder=0)
    trail2, = a.plot([], [], [], color="C1", lw=1, alpha=0.6, zorder=1)
    deck = Poly3DCollection([np.zeros((4, 3))], facecolor="0.6", edgecolor="0.3", alpha=0.7,
                            zorder=2)
    a.add_collection3d(deck)
    pad_line, = a.plot([], [], [], color="C1", lw=2, zorder=3)
    trail1, = a.plot([], [], [], color="C0", lw=1, zorder=4)
    drop, = a.plot([], [], [], color="C0", lw=0.8, ls=":", zorder=4)
    arm_front, = a.plot([], [], [], color="C3", lw=3, zorder=5)
    arm_rest, = a.plot([], [], [], color="k", lw=3, zorder=5)
    text = fig.text(0.02, 0.97, "", va="top", family="monospace", fontsize="small")
    fig.text(0.98, 0.97, f"scenario {result.scenario.name}", ha="right", va="top",
             fontsize="x-small", color="0.4")

    def draw(k: int) -> None:
        half = max(2 * pad, 0.6 * float(np.linalg.norm(p1[k] - p2[k])) + pad)
        c = (p1[k] + p2[k]) / 2
        a.set_xlim(c[0] - half, c[0] + half)
        a.set_ylim(c[1] - half, c[1] + half)
        a.set_zlim(c[2] - half, c[2] + half)
        grid, step = _grid_lines(c[0], c[1], half, z_ground)
        ground.set_data_3d(*grid.T)
        deck.set_verts([_deck_rectangle(result, k, 3 * pad, 2 * pad)])
        sq = _deck_rectangle(result, k, pad, pad)
        pad_line.set_data_3d(*np.vstack([sq, sq[:1]]).T)
        trail1.set_data_3d(*p1[:k + 1].T)
        trail2.set_data_3d(*p2[:k + 1].T)
        drop.set_data_3d([p1[k, 0]] * 2, [p1[k, 1]] * 2, [p1[k, 2], p2[k, 2]])
        d = max(arm, 2 * half / 25)
        front = p1[k] + np.array([[0.0, 0, 0], [d, 0, 0]]) @ R1[k].T
        rest = p1[k] + np.array([[0.0, 0, 0], [-d, 0, 0], [np.nan] * 3, [0, d, 0],
                                 [0, -d, 0]]) @ R1[k].T
        arm_front.set_data_3d(*front.T)
        arm_rest.set_data_3d(*rest.T)
        fast = f" (played x{speedup:.1f})" if speedup > 1 else ""
        most = "" if lim["max_offset"] is None else f" (max {lim['max_offset']:g})"
        text.set_text(f"t = {t[k]:6.2f} s  {PHASES[phase[k]]}{fast}\n"
                      f"height {result['z_e'][k]:5.2f} m, offset {offset[k]:4.2f} m"
                      f"{most}; grid {step:g} m")

    with writer.saving(fig, str(path), dpi=fig.dpi):
        for k in rows:
            draw(int(k))
            writer.grab_frame()
    return path

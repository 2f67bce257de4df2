"""The landing animated: a 3D scene following the pair, as a GIF or an MP4.

Frames are rows of the result evenly spaced in time (:func:`frame_rows`); each
is drawn by a :class:`_Scene`, whose artists are made once and moved frame
by frame; a GIF's frames are quantized as they come (:class:`_GifWriter`).
"""

from __future__ import annotations

import io
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.animation import PillowWriter
from matplotlib.figure import Figure
from PIL import Image

from quadland.exceptions import QuadlandError
from quadland.plots.finite import drawable
from quadland.plots.landing import (
    LandingResult,
    body_rotation,
    deck_rectangle,
    landing_limits,
    pad_size_of,
)
from quadland_symbolic.landing.guidance import PHASES

__all__ = ["MAX_PLAYBACK", "FRAME_SIZE", "FRAME_DPI", "GIF_COLORS", "SCENE_EXTENT",
           "frame_rows", "landing_animation"]

#: s, the longest animation: a longer landing is played faster.
MAX_PLAYBACK = 12.0
#: inch and dots per inch of a frame: 800 x 650 pixels, lines and text as sharp as the
#: figures' (512 x 416 before: a blur on a review screen).
FRAME_SIZE, FRAME_DPI = (8.0, 6.5), 100
#: Colours of a GIF frame: the scene has a few flat colours, and 64 keep its antialiased
#: edges at 8 % fewer bytes than 256 (highway: 1.95 MB against 2.11 MB).
GIF_COLORS = 64
#: m, farthest from E's origin the animation follows a body: a failed flight that
#: leaves this box (or whose pose stops being finite) is animated up to the row before.
SCENE_EXTENT = 1e6


def frame_rows(t: np.ndarray, fps: float) -> np.ndarray:
    """Rows shown as frames: evenly spaced in time, at most ``MAX_PLAYBACK * fps + 1``.

    A landing of ``T`` seconds plays in ``min(T, MAX_PLAYBACK)`` seconds:
    ``round(min(T, MAX_PLAYBACK) * fps) + 1`` frames (no more than the
    rows), each the row nearest its time (the earlier on a tie), so the
    first and the last rows are shown. A row nearest two times is shown once.
    """
    t = np.asarray(t, dtype=float)
    if len(t) < 2:
        return np.zeros(len(t), dtype=int)
    n = min(len(t), round(min(float(t[-1] - t[0]), MAX_PLAYBACK) * fps) + 1)
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
    """matplotlib's PillowWriter, each frame reduced to :data:`GIF_COLORS` as it comes.

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
        self._paletted.append(im.convert("RGB").quantize(GIF_COLORS, Image.Quantize.FASTOCTREE))

    def finish(self):
        self._paletted[0].save(self.outfile, save_all=True, append_images=self._paletted[1:],
                               duration=int(1000 / self.fps), loop=0)


def _writer(path: Path, fps: float):
    """The matplotlib writer for ``path``'s ending, or one line saying why none."""
    from matplotlib import animation

    suffix = path.suffix.lower()
    if suffix == ".gif":
        return _GifWriter(fps=fps)
    if suffix == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise QuadlandError(f"landing_animation: writing {path.name} needs ffmpeg, which "
                                "was not found on the PATH; install ffmpeg or write a .gif")
        return animation.FFMpegWriter(fps=fps)
    raise QuadlandError(f"landing_animation: cannot write {path.name!r}; "
                        "the animation is a .gif or an .mp4")


class _Scene:
    """The animation's figure and artists, and the rows they are drawn from.

    Only rows whose poses are finite and within :data:`SCENE_EXTENT` of E's
    origin are kept (a failed flight's last rows may diverge).
    """

    def __init__(self, result: LandingResult, limits: Mapping | None):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        self.result, self.lim, self.pad = result, landing_limits(limits), pad_size_of(result)
        self.arm = float(result.scenario.data.get("quadrotor", {}).get("arm_length", 0.25))
        p1 = np.column_stack([result[n] for n in ("x1", "y1", "z1")]).astype(float)
        p2 = np.column_stack([result[n] for n in ("x2", "y2", "z2")]).astype(float)
        angles = np.column_stack([result[n] for n in ("phi1", "theta1", "psi1", "phi2",
                                                      "theta2", "psi2", "x_e", "y_e", "z_e")])
        sane = (np.all(np.abs(p1) <= SCENE_EXTENT, axis=1)
                & np.all(np.abs(p2) <= SCENE_EXTENT, axis=1)
                & np.all(np.isfinite(angles), axis=1))
        n = max(1, int(np.argmin(sane)) if not sane.all() else len(sane))  # the rows drawn
        self.t = np.asarray(result["t"], dtype=float)[:n]
        self.phase = np.asarray(result["phase"])[:n].astype(int)
        self.p1, self.p2 = p1[:n], p2[:n]
        self.R1 = body_rotation(result["phi1"][:n], result["theta1"][:n], result["psi1"][:n])
        self.offset = np.hypot(result["x_e"][:n], result["y_e"][:n])
        self.z_ground = min(0.0, float(np.nanmin(self.p1[:, 2])),
                            float(np.nanmin(self.p2[:, 2])))
        self.speedup = (self.t[-1] - self.t[0]) / MAX_PLAYBACK
        self.fig = fig = Figure(figsize=FRAME_SIZE, dpi=FRAME_DPI)
        FigureCanvasAgg(fig)
        self._artists()
        fig.text(0.98, 0.97, f"scenario {result.scenario.name}", ha="right", va="top",
                 fontsize="x-small", color="0.4")

    def _artists(self) -> None:
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        # drawn in this order, not sorted by depth: the quadrotor is above the deck
        a = self.fig.add_axes((0.0, 0.0, 1.0, 0.9), projection="3d", computed_zorder=False)
        a.set_box_aspect((1, 1, 1), zoom=1.4)
        a.set_axis_off()
        self.axes = a
        self.ground, = a.plot([], [], [], color="0.8", lw=0.8, zorder=0)
        self.trail2, = a.plot([], [], [], color="C1", lw=1, alpha=0.6, zorder=1)
        self.deck = Poly3DCollection([np.zeros((4, 3))], facecolor="0.6", edgecolor="0.3",
                                     alpha=0.7, zorder=2)
        a.add_collection3d(self.deck)
        self.pad_line, = a.plot([], [], [], color="C1", lw=2, zorder=3)
        self.trail1, = a.plot([], [], [], color="C0", lw=1, zorder=4)
        self.drop, = a.plot([], [], [], color="C0", lw=0.8, ls=":", zorder=4)
        self.arm_front, = a.plot([], [], [], color="C3", lw=3, zorder=5)
        self.arm_rest, = a.plot([], [], [], color="k", lw=3, zorder=5)
        self.text = self.fig.text(0.02, 0.97, "", va="top", family="monospace",
                                  fontsize="small")

    def draw(self, k: int) -> None:
        """Move every artist to row ``k``."""
        p1, p2, pad = self.p1, self.p2, self.pad
        half = max(2 * pad, 0.6 * float(np.linalg.norm(p1[k] - p2[k])) + pad)
        c = (p1[k] + p2[k]) / 2
        self.axes.set_xlim(c[0] - half, c[0] + half)
        self.axes.set_ylim(c[1] - half, c[1] + half)
        self.axes.set_zlim(c[2] - half, c[2] + half)
        grid, step = _grid_lines(c[0], c[1], half, self.z_ground)
        self.ground.set_data_3d(*grid.T)
        self.deck.set_verts([deck_rectangle(self.result, k, 3 * pad, 2 * pad)])
        sq = deck_rectangle(self.result, k, pad, pad)
        self.pad_line.set_data_3d(*np.vstack([sq, sq[:1]]).T)
        self.trail1.set_data_3d(*p1[:k + 1].T)
        self.trail2.set_data_3d(*p2[:k + 1].T)
        self.drop.set_data_3d([p1[k, 0]] * 2, [p1[k, 1]] * 2, [p1[k, 2], p2[k, 2]])
        d = max(self.arm, 2 * half / 25)
        front = p1[k] + np.array([[0.0, 0, 0], [d, 0, 0]]) @ self.R1[k].T
        rest = p1[k] + np.array([[0.0, 0, 0], [-d, 0, 0], [np.nan] * 3, [0, d, 0],
                                 [0, -d, 0]]) @ self.R1[k].T
        self.arm_front.set_data_3d(*front.T)
        self.arm_rest.set_data_3d(*rest.T)
        fast = f" (played x{self.speedup:.1f})" if self.speedup > 1 else ""
        most = "" if self.lim["max_offset"] is None else f" (max {self.lim['max_offset']:g})"
        self.text.set_text(f"t = {self.t[k]:6.2f} s  {PHASES[self.phase[k]]}{fast}\n"
                           f"height {self.result['z_e'][k]:5.2f} m, offset "
                           f"{self.offset[k]:4.2f} m{most}; grid {step:g} m")


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
    path = Path(path)
    writer = _writer(path, fps)
    scene = _Scene(drawable(result), limits)
    with writer.saving(scene.fig, str(path), dpi=scene.fig.dpi):
        for k in frame_rows(scene.t, fps):
            scene.draw(int(k))
            writer.grab_frame()
    return path

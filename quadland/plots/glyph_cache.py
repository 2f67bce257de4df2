"""A plain text's glyphs drawn on Agg, each bitmap rendered once per sub-pixel place
(:func:`draw_glyphs`).

matplotlib 3.11's Agg renderer draws a text glyph by glyph: for each, the font is sized,
its transform computed with NumPy (the text's rotation as a 16.16 matrix and the glyph's
place in 1/64 pixel) and set, the glyph loaded, hinted and rendered by FreeType, and the
bitmap blended into the canvas. The margin figures draw about 4,700 glyphs this way.

A glyph's bitmap depends on the font, its size and resolution, the hinting, the render
mode, the rotation matrix and the glyph's place within its pixel (the place's remainder
modulo 64 in FreeType's 1/64 pixel); the place's whole pixels only move the bitmap, whose
``left`` and ``top`` grow by them (FreeType translates the hinted outline by the place and
renders it in its own pixel box). :func:`draw_glyphs` keeps each bitmap, with ``left`` and
``top`` less the whole pixels, by these; a glyph drawn again at the same remainder (the
tick labels' digits, the legends' repeated words: about a third of the margin figures'
glyphs) is blended from the kept bitmap. A glyph not kept is rendered with the same calls
in the same order as matplotlib's, and the text's rotation matrix is computed once with
matplotlib's arithmetic: the same pixels (``tests/test_glyph_cache.py``).
"""

from __future__ import annotations

import math
import os
from typing import NamedTuple

import matplotlib as mpl
import numpy as np
from matplotlib import ft2font

from quadland.plots.font_memory import font_identity

__all__ = ["Glyph", "glyphs_of", "draw_glyphs", "available", "CACHE_SIZE"]

#: FreeType's render modes as matplotlib names them (3.10 on; None before, where
#: ``quadland.plots.text_cache`` draws as matplotlib does and this module is not called).
RenderMode = getattr(ft2font, "RenderMode", None)

#: Most bitmaps kept; the cache is emptied when full.
CACHE_SIZE = 16384

_BITMAPS: dict = {}


def kept_bitmaps() -> dict:
    """The bitmaps kept (by font identity, size, resolution, glyph, hinting, render mode,
    matrix and hinting factor, and remainder of the place): read and written by
    :mod:`quadland.plots.text_store`."""
    return _BITMAPS


def available() -> bool:
    """Whether this matplotlib has what :func:`draw_glyphs` calls (its render modes)."""
    return RenderMode is not None


def rotation(angle: float) -> tuple[np.ndarray, float, float]:
    """The 16.16 matrix FreeType is given for a plain text at ``angle`` deg, its cosine and
    sine: matplotlib's arithmetic (its ``extend`` 1 and ``slant`` 0)."""
    cos = math.cos(math.radians(angle))
    sin = math.sin(math.radians(angle))
    matrix = (0x10000 * np.array([[cos, -sin], [sin, cos]])
              @ [[1, 0], [0, 1]]).round().astype(int)
    return matrix, cos, sin


def _render(font, size, dpi, glyph_index, flags, mode, matrix, place, antialiased):
    """One glyph rendered as matplotlib's Agg renderer renders it: bitmap, left, top."""
    font.set_size(size, dpi)
    font._set_transform(matrix, list(place))
    bitmap = font._render_glyph(glyph_index, flags, mode)
    buffer = np.array(bitmap.buffer)
    if not antialiased:
        buffer *= 0xff
    return buffer, bitmap.left, bitmap.top


class Glyph(NamedTuple):
    """A laid-out glyph as :func:`draw_glyphs` draws it: its font (None for a layout read
    back from another process, :mod:`quadland.plots.text_store`), the font's identity
    (:func:`quadland.plots.font_memory.font_identity`, or the font where it has none),
    its index in the font and its place in the text (pixels)."""

    font: object
    identity: object
    glyph_index: int
    x: float
    y: float


def glyphs_of(items) -> tuple[Glyph, ...]:
    """``FT2Font._layout``'s items as :class:`Glyph` tuples."""
    ids: dict = {}
    out = []
    for item in items:
        font = item.ft_object
        identity = ids.get(font, ids)
        if identity is ids:
            identity = ids[font] = font_identity(font) or font
        out.append(Glyph(font, identity, item.glyph_index, item.x, item.y))
    return tuple(out)


def draw_glyphs(renderer, gc, x: float, y: float, angle: float, glyphs, size: float,
                flags) -> bool:
    """Draw a plain text's laid-out glyphs as ``RendererAgg._draw_text_glyphs_and_boxes``.

    Parameters
    ----------
    renderer : matplotlib.backends.backend_agg.RendererAgg
    gc : GraphicsContextBase
        The text's colour, alpha and antialiasing.
    x, y : float
        The text's anchor, pixels (``y`` downwards, as matplotlib passes it).
    angle : float
        deg.
    glyphs : sequence of Glyph
        The text's glyphs (:func:`glyphs_of`).
    size : float
        pt.
    flags : matplotlib.ft2font.LoadFlags
        FreeType's load flags (matplotlib's hinting).

    Returns
    -------
    bool
        False, with nothing drawn, where a glyph without its font has no kept bitmap.
    """
    matrix, cos, sin = rotation(angle)
    # the hinting factor: a font made by matplotlib's get_font before 3.11 holds the rc's
    key_matrix = (*matrix.ravel().tolist(), mpl.rcParams["text.hinting_factor"])
    antialiased = bool(gc.get_antialiased())
    mode = RenderMode.NORMAL if antialiased else RenderMode.MONO
    height, dpi = renderer.height, renderer.dpi
    placed = []
    for glyph in glyphs:
        dx, dy = glyph.x, glyph.y
        place = (round(0x40 * (x + dx * cos - dy * sin)),
                 round(0x40 * (height - y + dx * sin + dy * cos)))   # FreeType's y is upwards
        key = (glyph.identity, size, dpi, glyph.glyph_index, flags, mode.name, key_matrix,
               place[0] & 63, place[1] & 63)
        kept = _BITMAPS.get(key)
        if kept is None:
            if glyph.font is None:
                return False
            buffer, left, top = _render(glyph.font, size, dpi, glyph.glyph_index, flags,
                                        mode, matrix, place, antialiased)
            if len(_BITMAPS) >= CACHE_SIZE:
                _BITMAPS.clear()
            kept = _BITMAPS[key] = (buffer, left - (place[0] >> 6), top - (place[1] >> 6))
        placed.append((kept, place[0] >> 6, place[1] >> 6))
    draw = renderer._renderer.draw_text_image
    bottom = int(height)
    for (buffer, left, top), whole_x, whole_y in placed:
        # draw_text_image's y is downwards, at the bitmap's bottom side
        draw(buffer, left + whole_x, bottom - (top + whole_y) + buffer.shape[0], 0, gc)
    return True


if hasattr(os, "register_at_fork"):
    # a forked child makes its fonts anew (quadland.plots.font_memory, matplotlib's own):
    # the parent's, kept here as keys, would only hold memory
    os.register_at_fork(after_in_child=_BITMAPS.clear)

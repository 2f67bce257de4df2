"""An Agg renderer that lays each distinct text out once (:class:`TextCacheRenderer`).

matplotlib 3.11's Agg renderer lays a text out glyph by glyph on every draw
(``FT2Font._layout``: every glyph loaded and hinted, about 40 us a glyph here,
1 ms for a 25-letter title), and every text's size is measured against its
font's height metrics, read from the font's tables again for each
measurement (``Text._get_layout``). A margin review draws about 380 texts
(five figures), most of them tick labels that repeat (``10⁰``, ``-180``), and
measures them about 2,000 times.

:class:`TextCacheRenderer` keeps both, by what they are computed from: the
layout and the measurement (width, height, descent) of a string by its fonts' files
as found on disk (:func:`text_key`), size, resolution, hinting, features and
whether the last-resort font is a fallback (what :mod:`quadland.plots.text_store`
writes for the next process); the height metrics by the fonts' files,
size and resolution; a text's font files by its font properties and the rc parameters
(:func:`font_paths`). Its glyphs are drawn by
:func:`quadland.plots.glyph_cache.draw_glyphs`, each bitmap rendered once per sub-pixel
place. The pixels are the same (checked in ``tests/test_quick_figure.py``,
``tests/test_glyph_cache.py`` and ``tests/test_text_cache_rc.py``). Where matplotlib's
Agg renderer has not the methods this one relies on (another version), it draws as
matplotlib does.
"""

from __future__ import annotations

import os

import matplotlib as mpl
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg, get_hinting_flag
from matplotlib.font_manager import fontManager, get_font
from matplotlib.ft2font import FT2Font

from quadland.plots.font_memory import file_identity, memory_font
from quadland.plots.glyph_cache import available as glyphs_drawable
from quadland.plots.glyph_cache import draw_glyphs, glyphs_of

__all__ = ["TextCacheRenderer", "TextCacheCanvas", "CACHE_SIZE", "font_paths", "kept_texts"]

#: Most layouts (and height metrics) kept; the cache is emptied when full.
CACHE_SIZE = 4096

_LAYOUTS: dict = {}
_HEIGHTS: dict = {}
_PATHS: dict = {}
_MEASURES: dict = {}
#: The measurements' keys whose every character is in the text's first font.
_WHOLE: set = set()


def kept_texts() -> tuple[dict, dict, set]:
    """The layouts (:class:`~quadland.plots.glyph_cache.Glyph` tuples) and measurements
    (width, height, descent) kept, by their texts' :func:`text_key`, and the keys of the
    measurements whose every character is in the text's first font: read and written by
    :mod:`quadland.plots.text_store`."""
    return _LAYOUTS, _MEASURES, _WHOLE

#: Whether this matplotlib draws text as the renderer below expects (3.11's Agg).
_CACHEABLE = (hasattr(RendererAgg, "_draw_text_glyphs_and_boxes")
              and hasattr(FT2Font, "_layout") and glyphs_drawable())


#: The font properties' own values and the rc parameters matplotlib's ``findfont`` reads.
_RC_FONT_KEYS = tuple(f"font.{key}" for key in (
    "family", "style", "variant", "weight", "stretch", "size",
    "serif", "sans-serif", "cursive", "fantasy", "monospace"))


def font_paths(prop) -> tuple:
    """``fontManager._find_fonts_by_props(prop)`` as a tuple, found once per process for
    what it is found from: the properties' values, the rc parameters matplotlib's
    ``findfont`` reads, its ``MPL_IGNORE_SYSTEM_FONTS``, the font lists' lengths (a font
    added with ``addfont`` starts a new entry) and the default family (taken where none of
    the properties' families is found). matplotlib's own search copies the
    properties once per family and hashes them again for its cache on every call."""
    # rcParams._get: the stored value without the backend's resolution, which no font
    # parameter has (matplotlib keeps its name stable)
    read = getattr(mpl.rcParams, "_get", mpl.rcParams.__getitem__)
    try:
        key = (tuple(vars(prop).items()),
               tuple(tuple(v) if isinstance(v, list) else v for v in map(read, _RC_FONT_KEYS)),
               os.getenv("MPL_IGNORE_SYSTEM_FONTS"), len(fontManager.ttflist),
               len(fontManager.afmlist), fontManager.defaultFamily.get("ttf"))
        paths = _PATHS.get(key)
    except TypeError:                   # a property not hashable: found each time
        return tuple(fontManager._find_fonts_by_props(prop))
    if paths is None:
        paths = _remember(_PATHS, key, tuple(fontManager._find_fonts_by_props(prop)))
    return paths


def _font_key(prop, dpi) -> tuple:
    # font.enable_last_resort: whether a glyph no file has is the last-resort font's or
    # the first font's .notdef (a different glyph, advance and layout)
    paths = font_paths(prop)
    return (paths, prop.get_size_in_points(), dpi, mpl.rcParams["text.hinting_factor"],
            mpl.rcParams["text.kerning_factor"], mpl.rcParams["font.enable_last_resort"])


def text_key(prop, dpi) -> tuple:
    """What a text's layout and measurement depend on besides the string, the hinting and
    the features: its fonts' files as another process finds them
    (:func:`~quadland.plots.font_memory.file_identity`), size, resolution, hinting and
    kerning factors and whether the last-resort font is a fallback."""
    key = _font_key(prop, dpi)
    files = tuple(file_identity(os.fspath(getattr(p, "path", p)), getattr(p, "face_index", 0))
                  for p in key[0])
    return (files, *key[1:])


def _remember(cache: dict, key, value):
    if len(cache) >= CACHE_SIZE:
        cache.clear()
    cache[key] = value
    return value


class TextCacheRenderer(RendererAgg):
    """matplotlib's Agg renderer, each distinct text's layout and each font's height
    metrics computed once per process (module docstring)."""

    def _get_font_height_metrics(self, prop):
        """A font's ascent, descent and line gap in pixels, as ``Text._get_layout`` reads
        them from its ``OS/2`` or ``hhea`` table (None where it has neither)."""
        key = _font_key(prop, self.dpi)
        if key in _HEIGHTS:
            return _HEIGHTS[key]
        font = get_font(list(key[0]))
        value = (None, None, None)
        for table_name, linegap_key, ascent_key, descent_key in (
                ('OS/2', 'sTypoLineGap', 'sTypoAscender', 'sTypoDescender'),
                ('hhea', 'lineGap', 'ascent', 'descent')):
            table = font.get_sfnt_table(table_name)
            if table is None:
                continue
            # the same operations in the same order as matplotlib's Text._get_layout
            fontsize = prop.get_size_in_points()
            units_per_em = font.get_sfnt_table('head')['unitsPerEm']
            scale = 1 / units_per_em * fontsize * self.dpi / 72
            value = (table[ascent_key] * scale, -table[descent_key] * scale,
                     table[linegap_key] * scale)
            break
        return _remember(_HEIGHTS, key, value)

    def _prepare_font(self, font_prop):
        """The font of ``font_prop`` cleared and sized, as matplotlib's Agg renderer
        prepares it, read from memory (:func:`~quadland.plots.font_memory.memory_font`)
        where this matplotlib allows."""
        font = memory_font(font_paths(font_prop)) if _CACHEABLE else None
        if font is None:
            return super()._prepare_font(font_prop)
        font.clear()
        font.set_size(font_prop.get_size_in_points(), self.dpi)
        return font

    def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
        """Draw ``s`` as matplotlib's Agg renderer does, its glyphs' layout cached."""
        if ismath or not _CACHEABLE:
            return super().draw_text(gc, x, y, s, prop, angle, ismath=ismath, mtext=mtext)
        flags = get_hinting_flag()
        features = mtext.get_fontfeatures() if mtext is not None else None
        language = mtext.get_language() if mtext is not None else None
        key = (text_key(prop, self.dpi), s, flags,
               None if features is None else tuple(features),
               language if language is None or isinstance(language, str) else tuple(language))
        size = prop.get_size_in_points()
        glyphs = _LAYOUTS.get(key)
        # a layout read back from another process has no fonts: laid out again where one
        # of its glyphs has no kept bitmap
        if glyphs is None or not draw_glyphs(self, gc, x, y, angle, glyphs, size, flags):
            font = self._prepare_font(prop)
            glyphs = _remember(_LAYOUTS, key, glyphs_of(font._layout(
                s, flags=flags, features=features, language=language)))
            draw_glyphs(self, gc, x, y, angle, glyphs, size, flags)
        return None

    def get_text_width_height_descent(self, s, prop, ismath):
        """As matplotlib's Agg renderer measures ``s``, a plain text's measurement kept by
        its :func:`text_key`, string and hinting."""
        if ismath is not False or not _CACHEABLE:
            return super().get_text_width_height_descent(s, prop, ismath)
        key = (text_key(prop, self.dpi), s, get_hinting_flag())
        value = _MEASURES.get(key)
        if value is None:
            value = _remember(_MEASURES, key,
                              tuple(super().get_text_width_height_descent(s, prop, ismath)))
            font = self._prepare_font(prop)
            if all(font.get_char_index(ord(c)) for c in s):
                if len(_WHOLE) >= CACHE_SIZE:
                    _WHOLE.clear()
                _WHOLE.add(key)
        return value


class TextCacheCanvas(FigureCanvasAgg):
    """An Agg canvas drawing with :class:`TextCacheRenderer`."""

    def get_renderer(self):
        """The canvas's renderer, made again when the figure's size or dpi changed."""
        w, h = self.get_width_height(physical=True)
        key = w, h, self.figure.dpi
        if self._lastKey != key:
            self.renderer = TextCacheRenderer(w, h, self.figure.dpi)
            self._lastKey = key
        return self.renderer

"""Fonts read by FreeType from memory rather than through a file (:func:`memory_font`).

matplotlib 3.11 opens each font file as a Python file object and gives FreeType a
stream whose every read is a Python call: a seek and a read through the buffered file,
most of them a system call, since FreeType reads a glyph's outline and hinting program
from wherever they lie in the file. Loading one hinted glyph of DejaVu Sans so takes
about 80 us, of which about 60 us are these reads (the margin figures load about 12,000
glyphs: laying texts out, measuring them, rendering them). A font object made from the
file's bytes in memory (an ``io.BytesIO``, which ``FT2Font`` takes as any binary file)
reads the same bytes without the system calls: the same glyphs, outlines, metrics and
bitmaps, in a quarter of the time.

:func:`memory_font` makes such a font with matplotlib's own recipe for a list of font
files (``matplotlib.font_manager._get_font``: the first file's face, the others and
matplotlib's last-resort font as its fallbacks), each file given as bytes in memory
instead of its path. That recipe is private to matplotlib; where it is not the one this
module expects (another matplotlib version), :func:`memory_font` returns None and the
caller uses ``matplotlib.font_manager.get_font`` as matplotlib does. Like matplotlib's
own fonts, those made here are kept per thread and forgotten in a forked child (a font
object must not be used across ``fork``).
"""

from __future__ import annotations

import inspect
import io
import os
import threading

import matplotlib as mpl
from matplotlib import font_manager

__all__ = ["memory_font", "available", "font_identity", "file_identity"]

#: The fonts made, by their files and the rc parameters matplotlib's recipe reads.
_FONTS: dict = {}
#: Each font file's bytes, by its real path.
_BYTES: dict = {}
#: Each font file's real path, by the path matplotlib gives.
_REAL_PATHS: dict = {}

_RECIPE_PARAMETERS = ("font_filepaths", "_kerning_factor", "thread_id", "enable_last_resort")

#: matplotlib's last-resort font, which its recipe treats apart when it is in the list.
_LAST_RESORT = os.path.realpath(os.path.join(mpl.get_data_path(), "fonts", "ttf",
                                             "LastResortHE-Regular.ttf"))


def _recipe():
    """matplotlib's uncached ``_get_font`` if it takes what this module gives, else None."""
    cached = getattr(font_manager, "_get_font", None)
    recipe = getattr(cached, "__wrapped__", None)
    if recipe is None:
        return None
    try:
        parameters = tuple(inspect.signature(recipe).parameters)
    except (TypeError, ValueError):
        return None
    return recipe if parameters == _RECIPE_PARAMETERS else None


_RECIPE = _recipe()


def available() -> bool:
    """Whether this matplotlib's font recipe is the one :func:`memory_font` uses."""
    return _RECIPE is not None


def _file_entry(font_path) -> tuple[str, int]:
    """A ``FontPath`` (matplotlib 3.11) or a path: its real path and face index.

    The real path is resolved once per path and process (a font's text is drawn many
    times; its bytes are read once anyway, :func:`_in_memory`)."""
    path = os.fspath(getattr(font_path, "path", font_path))
    real = _REAL_PATHS.get(path)
    if real is None:
        real = _REAL_PATHS[path] = os.path.realpath(path)
    return real, int(getattr(font_path, "face_index", 0))


class _FontBytes(io.BytesIO):
    """A font file's bytes, with what names them across processes (:func:`font_identity`)."""

    identity: tuple = ()


#: Each font file's (real path, size, modification time in ns), by its real path.
_STATS: dict = {}


def file_identity(path: str, face_index: int = 0) -> tuple:
    """A font file's face as another process finds it: its real path, face index, size and
    modification time (ns), the file read once per process (a file changed while a
    process runs is that process's font still)."""
    real = _REAL_PATHS.get(path)
    if real is None:
        real = _REAL_PATHS[path] = os.path.realpath(path)
    stat = _STATS.get(real)
    if stat is None:
        info = os.stat(real)
        stat = _STATS[real] = (real, info.st_size, info.st_mtime_ns)
    return (stat[0], int(face_index), *stat[1:])


def font_identity(font):
    """The identity (:func:`file_identity`) of the face an ``FT2Font`` was made from, by
    :func:`memory_font` or from a path (matplotlib's last-resort fallback); None for a
    font made from another file object."""
    name = font.fname
    if isinstance(name, _FontBytes):
        return name.identity
    if isinstance(name, str):
        return file_identity(name, font.face_index)
    return None


def _in_memory(path: str, index: int) -> io.BytesIO:
    data = _BYTES.get(path)
    identity = file_identity(path, index)      # stat before the read: a later change shows
    if data is None:
        with open(path, "rb") as f:
            data = _BYTES[path] = f.read()
    stream = _FontBytes(data)
    stream.identity = identity
    return stream


def memory_font(font_paths):
    """The font matplotlib's ``get_font(font_paths)`` gives, FreeType reading it from memory.

    Parameters
    ----------
    font_paths : list of str or matplotlib.font_manager.FontPath
        As ``matplotlib.font_manager.FontManager._find_fonts_by_props`` returns them: the
        font and its fallbacks, in order.

    Returns
    -------
    matplotlib.ft2font.FT2Font or None
        Made once per files, rc parameters and thread; its transform reset to the
        identity at each call, as ``get_font`` does. None where matplotlib's recipe is not
        the expected one (module docstring), or where the files include matplotlib's
        last-resort font (which its recipe recognizes by its path).
    """
    if _RECIPE is None:
        return None
    entries = tuple(_file_entry(p) for p in font_paths)
    if any(path == _LAST_RESORT for path, _ in entries):
        return None
    kerning = mpl.rcParams["text.kerning_factor"]
    last_resort = mpl.rcParams["font.enable_last_resort"]
    key = (entries, kerning, last_resort, threading.get_ident())
    font = _FONTS.get(key)
    try:
        if font is None:
            font = _RECIPE(tuple((_in_memory(path, index), index) for path, index in entries),
                           _kerning_factor=kerning, thread_id=key[-1],
                           enable_last_resort=last_resort)
            _FONTS[key] = font
        font._set_transform([[0x10000, 0], [0, 0x10000]], [0, 0])
    except (TypeError, AttributeError, ValueError):
        # a recipe of the expected signature that takes no file object (another
        # matplotlib): matplotlib's own get_font, as where the signature differs
        return None
    return font


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_FONTS.clear)

"""The figures' text layouts, measurements and glyph bitmaps kept on disk (:func:`texts_kept`).

A figure's texts cost FreeType's work in every process: each distinct string measured
and laid out (every glyph loaded and hinted) and each glyph rendered at its sub-pixel
place (:mod:`quadland.plots.text_cache`, :mod:`quadland.plots.glyph_cache` keep them
within a process). ``quadland margins`` draws the same labels, tick labels and legend
entries in every run of a scenario: highway's five figures measure about 200 strings, lay
out about 170 and render about 3,400 glyph bitmaps, a fifth of the figures' CPU.

Within :func:`texts_kept`, those kept by the process are read from the cache folder
(:func:`quadland.engine.build.cache_dir`, ``texts/``) on entry and written back on exit
when it drew new ones. Each entry is keyed by what FreeType computes it from: the font
files as found on disk (real path, face index, size and modification time,
:func:`quadland.plots.font_memory.file_identity`), size, resolution, hinting, factors,
render mode, rotation and place within its pixel; the file by the versions of
matplotlib, FreeType, NumPy and Python and this format. A layout read back carries no
font object: where one of its glyphs has no kept bitmap, the text is laid out again
(:meth:`quadland.plots.text_cache.TextCacheRenderer.draw_text`). The same pixels as
FreeType's (``tests/test_text_store.py``).

Texts drawn with matplotlib's last-resort font or a missing glyph (FreeType's
``.notdef``, index 0) are not written, so that matplotlib's warning about the missing
glyph is given again in the next process. The file starts with the SHA-256 of the rest,
checked before it is read; one that cannot be read (absent, cut, damaged, another format)
is ignored and rewritten; a folder that cannot be written only costs the next process the
work. The file is a pickle: it is read only from the user's own cache folder, which others
cannot write (:func:`~quadland.engine.build.cache_dir`), as are the libraries loaded from it.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import platform
from pathlib import Path

import matplotlib as mpl
import numpy as np
from matplotlib import ft2font

from quadland.plots import glyph_cache, text_cache

__all__ = ["texts_kept", "store_path", "FORMAT"]

#: The stored file's format; a new one starts a new file.
FORMAT = 1
#: Folder of the cache that holds the stored texts.
TEXTS = "texts"

_DIGEST = hashlib.sha256().digest_size


def store_path() -> Path:
    """The file of this matplotlib, FreeType, NumPy and Python in the cache folder."""
    from quadland.engine.build import cache_dir

    versions = (f"texts-{FORMAT}\0{mpl.__version__}\0{ft2font.__freetype_version__}\0"
                f"{np.__version__}\0{platform.python_version()}")
    name = hashlib.sha256(versions.encode()).hexdigest()[:24]
    return cache_dir() / TEXTS / f"{name}.pickle"


def _last_resort(identity) -> bool:
    return isinstance(identity, tuple) and os.path.basename(str(identity[0])).startswith(
        "LastResort")


def _storable(glyphs) -> bool:
    """Whether a layout is read back: every glyph of a font file and none missing."""
    return all(isinstance(g.identity, tuple) and g.glyph_index != 0
               and not _last_resort(g.identity) for g in glyphs)


def _contents() -> dict:
    """What this process keeps that another can read: plain values, no font objects."""
    layouts, measures, whole = text_cache.kept_texts()
    stored = {key: tuple(g._replace(font=None) for g in glyphs)
              for key, glyphs in layouts.items() if _storable(glyphs)}
    texts = {key[:3] for key in stored}             # font key, string, hinting
    bitmaps, pixels, offset = {}, [], 0
    for key, (buffer, left, top) in glyph_cache.kept_bitmaps().items():
        if isinstance(key[0], tuple) and key[3] != 0 and not _last_resort(key[0]):
            bitmaps[key] = (offset, buffer.shape, left, top)
            pixels.append(buffer.tobytes())
            offset += buffer.size
    return {"layouts": stored, "bitmaps": bitmaps, "pixels": b"".join(pixels),
            "measures": {key: value for key, value in measures.items()
                         if key in texts or key in whole}}


def _read(path: Path) -> dict | None:
    try:
        data = path.read_bytes()
    except OSError:
        return None
    body = data[_DIGEST:]
    if len(data) <= _DIGEST or hashlib.sha256(body).digest() != data[:_DIGEST]:
        return None
    try:
        contents = pickle.loads(body)
    except Exception:       # noqa: BLE001 - a file of another making: ignored, rewritten
        return None
    if not (isinstance(contents, dict) and contents.get("format") == FORMAT
            and isinstance(contents.get("pixels"), bytes)
            and all(isinstance(contents.get(k), dict)
                    for k in ("layouts", "bitmaps", "measures"))):
        return None         # another making under this format's number: ignored, rewritten
    return contents


def _load(contents: dict) -> int:
    """Put the stored entries in the process's caches; how many there are."""
    layouts, measures, whole = text_cache.kept_texts()
    bitmaps = glyph_cache.kept_bitmaps()
    # one writable buffer (Agg's blending takes no read-only array), an array on it each
    pixels = bytearray(contents["pixels"])
    for key, (offset, shape, left, top) in contents["bitmaps"].items():
        if key not in bitmaps:
            bitmaps[key] = (np.ndarray(shape, np.uint8, pixels, offset), left, top)
    for key, glyphs in contents["layouts"].items():
        layouts.setdefault(key, tuple(glyph_cache.Glyph(*g) for g in glyphs))
    for key, value in contents["measures"].items():
        measures.setdefault(key, value)
        whole.add(key)                  # stored so: written again by this process
    return sum(len(contents[k]) for k in ("bitmaps", "layouts", "measures"))


def _write(path: Path, contents: dict) -> None:
    from quadland.output import write_bytes_atomic

    body = pickle.dumps({"format": FORMAT, **contents}, protocol=pickle.HIGHEST_PROTOCOL)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_bytes_atomic(path, hashlib.sha256(body).digest() + body)
    except OSError:
        pass            # a folder that cannot be written: the next process does the work


@contextlib.contextmanager
def texts_kept(path: Path | None = None):
    """Within the block, figures draw their texts from and into the stored file.

    Parameters
    ----------
    path : Path, optional
        The file; :func:`store_path` by default.

    Yields
    ------
    Path
        The file read and written.
    """
    path = store_path() if path is None else Path(path)
    stored = _read(path)
    before = _load(stored) if stored is not None else 0
    loaded = _kept()
    yield path
    if _kept() == loaded:           # nothing drawn that was not read (nor emptied)
        return
    contents = _contents()
    # fewer than read too: a cache filled up and emptied (glyph_cache.CACHE_SIZE), the
    # entries kept since written, so that a file full of ones no longer drawn (fonts
    # changed since) gives way to those drawn now
    if sum(len(contents[k]) for k in ("bitmaps", "layouts", "measures")) != before:
        _write(path, contents)


def _kept() -> int:
    layouts, measures, _ = text_cache.kept_texts()
    return len(layouts) + len(measures) + len(glyph_cache.kept_bitmaps())

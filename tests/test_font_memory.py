"""quadland.plots.font_memory: a font read by FreeType from memory gives what matplotlib's
own font (read through its file) gives: the same layouts, measurements and glyph bitmaps.

The reference is ``matplotlib.font_manager.get_font`` on the same files; the font from
memory is checked to need no file once made (its file deleted), and to be made again per
thread and after a fork, as matplotlib's own fonts are.
"""

from __future__ import annotations

import os
import shutil
import threading

import matplotlib as mpl
import numpy as np
import pytest
from figure_pixels import drawn_alike
from matplotlib.backends.backend_agg import get_hinting_flag
from matplotlib.font_manager import FontProperties, fontManager, get_font
from matplotlib.ft2font import RenderMode

from quadland.plots import font_memory, text_cache

pytestmark = pytest.mark.skipif(not font_memory.available(),
                                reason="this matplotlib's font recipe is not the expected one")

TEXTS = ("continuous: PM 45.3 deg at 2.34 rad/s", "10⁻²", "−180", "Wg|ÿ", "x", "ア")


def _paths(**kw):
    return fontManager._find_fonts_by_props(FontProperties(**kw))


def _glyphs(font, text: str, size: float, dpi: float, angle: float, offset) -> list:
    """Each glyph of ``text`` rendered as matplotlib's Agg renderer renders it, at
    ``angle`` deg and ``offset`` (1/64 pixel)."""
    flags = get_hinting_flag()
    font.clear()
    font.set_size(size, dpi)
    out = []
    c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
    matrix = (0x10000 * np.array([[c, -s], [s, c]])).round().astype(int)
    for item in font._layout(text, flags=flags, features=None, language=None):
        item.ft_object.set_size(size, dpi)
        item.ft_object._set_transform(matrix, [offset[0] + round(64 * item.x),
                                               offset[1] + round(64 * item.y)])
        bitmap = item.ft_object._render_glyph(item.glyph_index, flags, RenderMode.NORMAL)
        out.append((item.glyph_index, item.x, item.y, bitmap.left, bitmap.top,
                    np.array(bitmap.buffer)))
    return out


def _measure(font, text: str, size: float, dpi: float) -> tuple:
    font.clear()
    font.set_size(size, dpi)
    font.set_text(text, 0.0, flags=get_hinting_flag())
    return font.get_width_height(), font.get_descent(), font.get_bitmap_offset()


def _same_glyphs(a: list, b: list) -> bool:
    return len(a) == len(b) and all(
        x[:5] == y[:5] and np.array_equal(x[5], y[5]) for x, y in zip(a, b, strict=True))


@pytest.mark.filterwarnings("ignore:Glyph .* missing from font")
@pytest.mark.parametrize("kw", [{}, {"weight": "bold"}, {"family": "serif", "style": "italic"}])
def test_a_font_from_memory_lays_out_measures_and_renders_as_matplotlibs(kw):
    paths = _paths(**kw)
    theirs, mine = get_font(paths), font_memory.memory_font(paths)
    assert mine is not None and mine is not theirs
    assert mine.family_name == theirs.family_name and mine.style_name == theirs.style_name
    for text in TEXTS:                      # "ア": a fallback font's glyph (or a missing one)
        for size, dpi in ((10.0, 200.0), (6.94, 200.0), (12.0, 72.0)):
            assert _measure(mine, text, size, dpi) == _measure(theirs, text, size, dpi)
            for angle, offset in ((0.0, (0, 0)), (0.0, (13, 50)), (90.0, (37, 5)),
                                  (30.0, (64 * 7 + 3, 64 * 11 + 60))):
                assert _same_glyphs(_glyphs(mine, text, size, dpi, angle, offset),
                                    _glyphs(theirs, text, size, dpi, angle, offset))


def test_a_font_from_memory_needs_no_file_once_made(tmp_path):
    source = _paths()[0]
    copy = tmp_path / "copy.ttf"
    shutil.copy(getattr(source, "path", source), copy)
    mine = font_memory.memory_font([str(copy)])
    os.remove(copy)
    reference = _glyphs(get_font(_paths()), "Memory 42", 10.0, 200.0, 0.0, (5, 9))
    assert _same_glyphs(_glyphs(mine, "Memory 42", 10.0, 200.0, 0.0, (5, 9)), reference)
    assert font_memory.memory_font([str(copy)]) is mine       # kept: the file is not read


def test_fonts_are_kept_per_thread_and_forgotten_in_a_forked_child():
    paths = _paths()
    here = font_memory.memory_font(paths)
    assert font_memory.memory_font(paths) is here
    there = []
    worker = threading.Thread(target=lambda: there.append(font_memory.memory_font(paths)))
    worker.start()
    worker.join()
    assert there[0] is not None and there[0] is not here
    if not hasattr(os, "fork"):
        return
    pid = os.fork()
    if pid == 0:                    # the child: nothing kept from the parent
        os._exit(0 if not font_memory._FONTS else 1)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0


def test_the_transform_is_reset_as_get_font_resets_it():
    paths = _paths()
    font = font_memory.memory_font(paths)
    font._set_transform([[0, -0x10000], [0x10000, 0]], [640, 640])
    font = font_memory.memory_font(paths)
    reference = _measure(get_font(paths), "reset", 10.0, 200.0)
    assert _measure(font, "reset", 10.0, 200.0) == reference
    assert _same_glyphs(_glyphs(font, "T", 10.0, 200.0, 0.0, (0, 0)),
                        _glyphs(get_font(paths), "T", 10.0, 200.0, 0.0, (0, 0)))


def test_the_last_resort_font_and_another_recipe_leave_it_to_matplotlib(monkeypatch):
    last_resort = os.path.join(mpl.get_data_path(), "fonts", "ttf", "LastResortHE-Regular.ttf")
    assert font_memory.memory_font([last_resort]) is None
    monkeypatch.setattr(font_memory, "_RECIPE", None)
    assert font_memory.memory_font(_paths()) is None

    def content(fig):                    # the renderer then uses matplotlib's fonts
        ax = fig.subplots()
        ax.plot([0, 1], [0, 1], label="a line")
        ax.legend()
        ax.set_title("matplotlib's own fonts")
        fig.tight_layout()

    text_cache._LAYOUTS.clear()
    drawn_alike(content, (4, 3))


def test_a_recipe_of_the_same_signature_that_takes_no_file_object_leaves_it_to_matplotlib(
        monkeypatch):
    """A matplotlib whose ``_get_font`` has the expected parameters but opens each entry as
    a path: matplotlib's fonts, the figure drawn as matplotlib draws it."""
    recipe = font_memory._RECIPE

    def paths_only(font_filepaths, *, _kerning_factor, thread_id, enable_last_resort):
        return recipe(tuple((os.fspath(p), i) for p, i in font_filepaths),
                      _kerning_factor=_kerning_factor, thread_id=thread_id,
                      enable_last_resort=enable_last_resort)

    monkeypatch.setattr(font_memory, "_RECIPE", paths_only)
    monkeypatch.setattr(font_memory, "_FONTS", {})
    assert font_memory.memory_font(_paths(family="serif")) is None

    def content(fig):
        ax = fig.subplots()
        ax.set_title("a recipe for paths only")

    text_cache._LAYOUTS.clear()
    drawn_alike(content, (4, 3))

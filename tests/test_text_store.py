"""quadland.plots.text_store: texts laid out, measured and rendered by one process and read
back by the next draw matplotlib's own pixels, without FreeType's work.

The reference is matplotlib's own ``Figure`` on its own Agg canvas (whole figures, pixel
for pixel). A "new process" here is one whose caches are empty and whose font objects are
made anew (:func:`_new_process`); what is counted is what FreeType would be asked for:
glyphs rendered (``glyph_cache._render``), strings laid out (``text_cache.glyphs_of`` of
``FT2Font._layout``) and strings measured (matplotlib's
``RendererAgg.get_text_width_height_descent``).
"""

from __future__ import annotations

import hashlib
import pickle
import warnings

import numpy as np
import pytest
from figure_pixels import pixels
from matplotlib.backends.backend_agg import FigureCanvasAgg, RendererAgg
from matplotlib.figure import Figure

from quadland.plots import font_memory, glyph_cache, text_cache
from quadland.plots.canvas import new_figure
from quadland.plots.text_store import FORMAT, texts_kept
from quadland.png import PNG_DPI

pytestmark = pytest.mark.skipif(not (text_cache._CACHEABLE and font_memory.available()),
                                reason="this matplotlib's Agg renderer draws text otherwise")

SIZE = (5.0, 3.5)


def _content(shift: float = 0.0):
    """Titles, labels, tick labels, a legend, rotated and bold texts, ``shift`` figure
    pixels to the right (a fraction moves every glyph within its pixel)."""
    def draw(fig):
        ax = fig.add_subplot()
        ax.semilogx([1, 10, 100], [0, -90, -180], label="continuous: PM 45.3 deg at 2.1 rad/s")
        ax.plot([1, 100], [-30, -150], "--", label="sampled (250 Hz)")
        ax.set_title("roll loop (others closed)")
        ax.set_xlabel("frequency [rad/s]")
        ax.set_ylabel("arg l [deg]")
        ax.legend(fontsize="x-small", loc="lower left")
        for k, angle in enumerate((0, 90, 33)):
            fig.text(0.15 + 0.2 * k + shift / fig.dpi / SIZE[0], 0.5, "Wg|ÿ 0.5",
                     rotation=angle, weight=("normal", "bold")[k % 2])
    return draw


def _theirs(content) -> np.ndarray:
    fig = Figure(figsize=SIZE, dpi=PNG_DPI)
    FigureCanvasAgg(fig)
    content(fig)
    return pixels(fig)


def _new_process(monkeypatch) -> None:
    """The caches of a process that has drawn nothing, its fonts made anew."""
    glyph_cache.kept_bitmaps().clear()
    for kept in text_cache.kept_texts():
        kept.clear()
    text_cache._HEIGHTS.clear()
    monkeypatch.setattr(font_memory, "_FONTS", {})


def _counted(monkeypatch) -> dict:
    """FreeType's work from now on: glyphs rendered, plain strings laid out and measured."""
    work = {"rendered": 0, "laid out": 0, "measured": 0}

    def counter(name, function):
        def counted(*args, **kwargs):
            work[name] += 1
            return function(*args, **kwargs)
        return counted

    monkeypatch.setattr(glyph_cache, "_render", counter("rendered", glyph_cache._render))
    monkeypatch.setattr(text_cache, "glyphs_of", counter("laid out", text_cache.glyphs_of))
    measure = RendererAgg.get_text_width_height_descent

    def measured(renderer, s, prop, ismath):
        work["measured"] += ismath is False     # mathtext (the log axis's 10^k) is not kept
        return measure(renderer, s, prop, ismath)

    monkeypatch.setattr(RendererAgg, "get_text_width_height_descent", measured)
    return work


def _mine(content, store) -> np.ndarray:
    with texts_kept(store):
        fig = new_figure(SIZE)
        content(fig)
        return pixels(fig)


def test_texts_read_back_draw_matplotlibs_pixels_without_freetype(tmp_path, monkeypatch):
    store = tmp_path / "texts.pickle"
    theirs = _theirs(_content())
    _new_process(monkeypatch)
    first = _mine(_content(), store)
    assert store.exists()
    _new_process(monkeypatch)
    work = _counted(monkeypatch)
    again = _mine(_content(), store)
    assert work == {"rendered": 0, "laid out": 0, "measured": 0}
    assert np.array_equal(first, theirs)
    assert np.array_equal(again, theirs)


def test_a_layout_read_back_whose_glyphs_lie_elsewhere_is_laid_out_again(tmp_path,
                                                                          monkeypatch):
    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    _new_process(monkeypatch)
    work = _counted(monkeypatch)
    moved = _mine(_content(0.37), store)        # the figure texts' glyphs at new remainders
    assert work["rendered"] > 0 and work["laid out"] > 0
    assert np.array_equal(moved, _theirs(_content(0.37)))


def _damaged(data: bytes, how: str) -> bytes:
    body = data[32:]
    if how == "a byte changed":
        return data[:100] + bytes([data[100] ^ 1]) + data[101:]
    if how == "cut":
        return data[: len(data) // 2]
    if how == "empty":
        return b""
    if how == "another layout":         # this format's number, other contents
        other = pickle.dumps({"format": FORMAT, "layouts": [], "bitmaps": None})
    else:
        other = pickle.dumps({**pickle.loads(body), "format": FORMAT + 1})   # a later format
    return hashlib.sha256(other).digest() + other


@pytest.mark.parametrize("how", ["a byte changed", "cut", "empty", "another format",
                                 "another layout"])
def test_a_damaged_or_foreign_file_is_ignored_and_written_again(tmp_path, monkeypatch, how):
    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    store.write_bytes(_damaged(store.read_bytes(), how))
    _new_process(monkeypatch)
    work = _counted(monkeypatch)
    drawn = _mine(_content(), store)
    assert work["rendered"] > 0                 # nothing read from it
    assert np.array_equal(drawn, _theirs(_content()))
    _new_process(monkeypatch)
    work = _counted(monkeypatch)
    _mine(_content(), store)                    # written again, whole
    assert work == {"rendered": 0, "laid out": 0, "measured": 0}


def test_a_changed_font_file_is_not_read_back(tmp_path, monkeypatch):
    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    _new_process(monkeypatch)
    # the font files as a later process finds them after they changed: other times
    stats = {path: (real, size, mtime + 1) for path, (real, size, mtime)
             in font_memory._STATS.items()}
    monkeypatch.setattr(font_memory, "_STATS", stats)
    work = _counted(monkeypatch)
    drawn = _mine(_content(), store)
    assert work["rendered"] > 0 and work["laid out"] > 0 and work["measured"] > 0
    assert np.array_equal(drawn, _theirs(_content()))


def test_a_text_with_a_missing_glyph_is_not_kept_so_its_warning_is_given_again(
        tmp_path, monkeypatch):
    store = tmp_path / "texts.pickle"

    def missing(fig):
        fig.text(0.1, 0.5, "roll \u6587")       # not in DejaVu Sans

    for _ in range(2):
        _new_process(monkeypatch)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _mine(missing, store)
        assert any("missing from font" in str(w.message) for w in caught)
    layouts = pickle.loads(store.read_bytes()[32:])["layouts"] if store.exists() else {}
    assert not any("\u6587" in key[1] for key in layouts)


def test_a_folder_that_cannot_be_written_only_costs_the_work(tmp_path, monkeypatch):
    (tmp_path / "a file").write_text("")
    store = tmp_path / "a file" / "texts.pickle"      # its folder is a file
    _new_process(monkeypatch)
    drawn = _mine(_content(), store)
    assert not store.exists()
    assert np.array_equal(drawn, _theirs(_content()))


def test_a_full_file_of_entries_no_longer_drawn_gives_way_to_the_current_ones(tmp_path,
                                                                              monkeypatch):
    store = tmp_path / "texts.pickle"
    theirs = _theirs(_content())
    _new_process(monkeypatch)
    _mine(_content(), store)
    drawn = len(glyph_cache.kept_bitmaps())
    # room for the figure's bitmaps and a half of them: the file's and the figure's do not
    # both fit, the cache is emptied once while the figure is drawn
    monkeypatch.setattr(glyph_cache, "CACHE_SIZE", drawn * 3 // 2)
    # the font files changed after the file was written: none of its entries is drawn
    stats = {path: (real, size, mtime + 1) for path, (real, size, mtime)
             in font_memory._STATS.items()}
    rendered = []
    for _ in range(4):
        _new_process(monkeypatch)
        monkeypatch.setattr(font_memory, "_STATS", dict(stats))
        work = _counted(monkeypatch)
        assert np.array_equal(_mine(_content(), store), theirs)
        rendered.append(work["rendered"])
    assert rendered[0] == drawn
    assert rendered[-1] == 0, rendered


def test_a_file_whose_pixels_changed_is_not_read(tmp_path, monkeypatch):
    """A byte of a glyph bitmap changed: the file still unpickles, its digest does not hold."""
    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    data = bytearray(store.read_bytes())
    blob = pickle.loads(bytes(data[32:]))["pixels"]
    at = bytes(data).find(blob) + len(blob) // 2
    data[at] ^= 0xFF
    store.write_bytes(bytes(data))
    _new_process(monkeypatch)
    assert np.array_equal(_mine(_content(), store), _theirs(_content()))


@pytest.mark.parametrize("rc", [{"text.hinting": "no_hinting"}, {"text.hinting": "auto"},
                                {"text.antialiased": False}, {"font.family": "serif"}])
def test_a_file_written_under_other_rc_parameters_draws_matplotlibs_pixels(
        tmp_path, monkeypatch, rc):
    import matplotlib as mpl

    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    with mpl.rc_context(rc):
        theirs = _theirs(_content())
        _new_process(monkeypatch)
        assert np.array_equal(_mine(_content(), store), theirs)
        _new_process(monkeypatch)       # and the file as that process wrote it
        assert np.array_equal(_mine(_content(), store), theirs)


def _unicode_and_math(fig):
    """Non-ASCII labels, a glyph from the second family (cmr10 has no Greek capitals) and
    mathtext beside plain text."""
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1], label="Δφ → 45°, ±3 dB")
    ax.set_title("marge de phase: ü é ß")
    ax.set_xlabel(r"$\omega$ [rad/s] and $10^{2}$")
    ax.legend()
    fig.text(0.2, 0.5, "Ωmega ΔV", family=["cmr10", "DejaVu Sans"], rotation=15)


def test_unicode_fallback_fonts_and_mathtext_read_back_draw_matplotlibs_pixels(
        tmp_path, monkeypatch):
    store = tmp_path / "texts.pickle"
    theirs = _theirs(_unicode_and_math)
    _new_process(monkeypatch)
    assert np.array_equal(_mine(_unicode_and_math, store), theirs)
    _new_process(monkeypatch)
    work = _counted(monkeypatch)
    assert np.array_equal(_mine(_unicode_and_math, store), theirs)
    assert work["rendered"] == 0 and work["laid out"] == 0


def test_a_font_file_touched_since_is_not_read_back(tmp_path, monkeypatch):
    """The file's modification time as ``os.stat`` gives it to a later process (one ns on),
    its size the same: nothing read back (what the stat of ``file_identity`` is for)."""
    import os
    import types

    store = tmp_path / "texts.pickle"
    _new_process(monkeypatch)
    _mine(_content(), store)
    _new_process(monkeypatch)
    monkeypatch.setattr(font_memory, "_STATS", {})

    def touched(path):
        info = os.stat(path)
        return types.SimpleNamespace(st_size=info.st_size, st_mtime_ns=info.st_mtime_ns + 1)

    monkeypatch.setattr(font_memory, "os", types.SimpleNamespace(
        stat=touched, path=os.path, fspath=os.fspath))
    work = _counted(monkeypatch)
    assert np.array_equal(_mine(_content(), store), _theirs(_content()))
    assert work["rendered"] > 0 and work["laid out"] > 0 and work["measured"] > 0

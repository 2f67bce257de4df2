"""quadland.plots.glyph_cache: a text's glyphs blended from bitmaps kept per sub-pixel place
give matplotlib's own pixels.

The references are matplotlib's own ``Figure`` on its own Agg canvas (whole figures, pixel
for pixel) and FreeType rendering a glyph at places a whole number of pixels apart (the
property the cache rests on: the bitmap moves, its bytes do not).
"""

from __future__ import annotations

import matplotlib as mpl
import numpy as np
import pytest
from figure_pixels import drawn_alike, pixels
from matplotlib.backends.backend_agg import get_hinting_flag
from matplotlib.font_manager import FontProperties, fontManager, get_font
from matplotlib.ft2font import RenderMode

from quadland.plots import glyph_cache, text_cache

pytestmark = pytest.mark.skipif(not text_cache._CACHEABLE,
                                reason="this matplotlib's Agg renderer draws text otherwise")

WORDS = ("continuous: PM 45.3 deg", "10⁻²", "−180", "Wg|ÿ", "x", "0.5", "0.5")


def _texts(fig):
    """Repeated words at places that share and that do not share a sub-pixel remainder,
    rotated, coloured, translucent, bold, and not antialiased."""
    ax = fig.add_subplot()
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    for k, word in enumerate(WORDS):
        for j, x in enumerate((0.05, 0.05 + 1 / 7.0, 0.3, 0.3 + 0.5 / fig.dpi, 0.61)):
            ax.text(x, 0.05 + 0.11 * k + 0.013 * j, word, fontsize=7 + j,
                    rotation=(0, 90, 30, 0, -45)[j], color=f"C{j}", alpha=(1, 0.5)[j % 2],
                    weight=("normal", "bold")[k % 2], antialiased=(j != 3))
    ax.set_title("titles 0.5 0.5", family="serif")
    ax.set_xlabel("frequency [rad/s]")


def test_glyphs_from_kept_bitmaps_draw_matplotlibs_pixels():
    glyph_cache._BITMAPS.clear()
    mine = drawn_alike(_texts, (6.0, 5.0))
    assert glyph_cache._BITMAPS            # the quick figure's texts went through the cache
    first = pixels(mine)
    again = pixels(mine)                   # every glyph from a kept bitmap now
    assert np.array_equal(first, again)


def test_a_glyph_drawn_again_at_the_same_remainder_is_not_rendered_again(monkeypatch):
    glyph_cache._BITMAPS.clear()
    rendered = []
    render = glyph_cache._render

    def counted(*args):
        rendered.append(args[3])           # the glyph index
        return render(*args)

    monkeypatch.setattr(glyph_cache, "_render", counted)
    from quadland.plots.canvas import new_figure

    fig = new_figure((3.0, 2.0))
    fig.text(0.1, 0.5, "aaaa")             # glyphs at remainders of their own
    fig.text(0.1 + 2 / fig.dpi, 0.5 + 3 / fig.dpi, "aaaa")    # whole pixels from the first
    pixels(fig)
    n_first = len(rendered)
    assert 1 <= n_first <= 4
    pixels(fig)
    assert len(rendered) == n_first        # drawn again: nothing rendered


@pytest.mark.parametrize("angle", [0.0, 90.0, 33.0])
def test_freetype_moves_a_glyph_by_whole_pixels_without_changing_its_bitmap(angle):
    flags = get_hinting_flag()
    font = get_font(fontManager._find_fonts_by_props(FontProperties(family="DejaVu Sans")))
    matrix, _, _ = glyph_cache.rotation(angle)
    for char in "g8Wé":
        glyph = font.get_char_index(ord(char))
        for remainder in ((0, 0), (17, 45), (63, 1)):
            seen = []
            for whole in ((0, 0), (3, -2), (-5, 7), (120, 88)):
                place = [remainder[i] + 64 * whole[i] for i in range(2)]
                font.set_size(11.0, 110.0)
                font._set_transform(matrix, place)
                bitmap = font._render_glyph(glyph, flags, RenderMode.NORMAL)
                seen.append((np.array(bitmap.buffer), bitmap.left - whole[0],
                             bitmap.top - whole[1]))
            for buffer, left, top in seen[1:]:
                assert np.array_equal(buffer, seen[0][0])
                assert (left, top) == seen[0][1:]


def test_the_rotation_is_matplotlibs():
    for angle in (0.0, 90.0, 33.0, -45.0, 180.0):
        c, s = np.cos(np.radians(angle)), np.sin(np.radians(angle))
        theirs = (0x10000 * np.array([[c, -s], [s, c]]) @ [[1, 1 * 0], [0, 1]]).round().astype(int)
        assert np.array_equal(glyph_cache.rotation(angle)[0], theirs)


def test_a_full_cache_is_emptied(monkeypatch):
    monkeypatch.setattr(glyph_cache, "CACHE_SIZE", 3)
    glyph_cache._BITMAPS.clear()
    from quadland.plots.canvas import new_figure

    fig = new_figure((3.0, 2.0))
    fig.text(0.1, 0.5, "abcdefgh")
    pixels(fig)
    assert len(glyph_cache._BITMAPS) <= 3
    with mpl.rc_context({"text.antialiased": False}):
        drawn_alike(_texts, (6.0, 5.0))


#: What a glyph's bitmap depends on besides its place, one varied per text (the others as
#: the first text's), each at the same place within its pixel as the first.
VARIED = ({}, {"rotation": 90}, {"rotation": 33}, {"antialiased": False}, {"weight": "bold"},
          {"family": "DejaVu Serif"}, {"fontsize": 13})


def _one_glyph_each(fig):
    """A "g" per entry of VARIED, anchored at its baseline's left end, places whole pixels
    apart (figure pixels): its first glyph at the first's sub-pixel remainder."""
    from matplotlib.transforms import IdentityTransform

    for k, varied in enumerate(VARIED):
        kw = {"fontsize": 11, "rotation": 0, "antialiased": True, **varied}
        fig.text(20.3 + 40 * k, 60.6 + 3 * k, "g", transform=IdentityTransform(),
                 ha="left", va="baseline", rotation_mode="anchor", **kw)


@pytest.mark.parametrize("rc", [{}, {"text.hinting": "no_hinting"}, {"text.hinting": "auto"}])
@pytest.mark.parametrize("dpi", [110.0, 72.0, 137.5])
def test_a_glyph_varied_in_one_thing_at_one_remainder_is_rendered_for_it(rc, dpi):
    """The cache kept from the cases before (other resolutions and hinting, not emptied):
    each text's pixels are matplotlib's all the same."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    with mpl.rc_context(rc):
        drawn = []
        for canvas in (text_cache.TextCacheCanvas, FigureCanvasAgg):
            fig = Figure(figsize=(3.0, 1.0), dpi=dpi)
            canvas(fig)
            _one_glyph_each(fig)
            drawn.append(pixels(fig))
    assert np.array_equal(*drawn)


def test_a_matplotlib_without_render_modes_imports_the_module(monkeypatch):
    """matplotlib before 3.10 has no ``ft2font.RenderMode`` (pyproject allows 3.8): the
    module imports, says it cannot draw, and text_cache then draws as matplotlib does
    (checked by hand on 3.8.4: a quick figure drawn, ``_CACHEABLE`` False)."""
    import importlib

    from matplotlib import ft2font

    monkeypatch.delattr(ft2font, "RenderMode")
    try:
        importlib.reload(glyph_cache)
        assert not glyph_cache.available()
    finally:
        monkeypatch.undo()
        importlib.reload(glyph_cache)
    assert glyph_cache.available()

"""What the margin figures' cost cuts keep: plain log labels, one resolution, the PNG.

- :mod:`quadland.plots.log_labels`: a log axis's powers of ten as plain text
  (``10⁻²``) that read as matplotlib's mathtext labels; the margin figures'
  frequency axes so labelled, every label still there.
- :mod:`quadland.plots.canvas`: the figures made at the PNG's resolution, their
  layout the one the PNG is drawn with.
- :func:`quadland.png.encode_png`: what Pillow decodes is the pixels given.
- :mod:`quadland.plots` loads a figure module only when one of its names is used.
"""

import io
import subprocess
import sys

import numpy as np
import pytest
from matplotlib.ticker import LogFormatterSciNotation
from PIL import Image
from threadpoolctl import threadpool_limits

import quadland
from quadland.margins import margin_report
from quadland.plots import margin_figures
from quadland.plots.canvas import new_figure
from quadland.plots.log_labels import PlainLogFormatter, plain_math
from quadland.png import PNG_DPI, encode_png, figure_png

SUPERSCRIPT = dict(zip("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹", strict=True))


@pytest.mark.parametrize(("mathtext", "plain"), [
    (r"$\mathdefault{10^{-2}}$", "10⁻²"),
    (r"$\mathdefault{10^{0}}$", "10⁰"),
    (r"$\mathdefault{10^{13}}$", "10¹³"),
    (r"$\mathdefault{-10^{3}}$", "\u221210³"),
    (r"$\mathdefault{2\times10^{-1}}$", "2×10⁻¹"),
    (r"$\mathdefault{10^{2.50}}$", r"$\mathdefault{10^{2.50}}$"),     # kept as mathtext
    ("", ""),
    ("5", "5"),
])
def test_plain_math(mathtext, plain):
    assert plain_math(mathtext) == plain


def test_the_plain_formatter_labels_the_decades_matplotlib_labels():
    fig = new_figure((4, 3))
    ax = fig.subplots()
    ax.semilogx([1e-3, 1e4], [0, 1])
    mine, theirs = PlainLogFormatter(), LogFormatterSciNotation()
    for f in (mine, theirs):
        f.set_axis(ax.xaxis)
    decades = 10.0 ** np.arange(-3, 5)
    mine.set_locs(decades)
    theirs.set_locs(decades)
    for k, x in zip(range(-3, 5), decades, strict=True):
        assert theirs(x) == rf"$\mathdefault{{10^{{{k}}}}}$"
        assert mine(x) == "10" + "".join(SUPERSCRIPT[c] for c in str(k))


@pytest.fixture(scope="module")
def figures():
    with threadpool_limits(1):
        report = margin_report(quadland.load_scenario("paper", ["rbf.nodes=5",
                                                                "controller.rate_hz=50"]))
    return margin_figures(report)


def _drawn(fig):
    fig.canvas.draw()
    return fig


def test_the_frequency_axes_keep_every_label_in_plain_text(figures):
    for name in ("bode.png", "sigma.png"):
        fig = _drawn(figures[name])
        for ax in fig.axes:
            assert ax.get_xscale() == "log"
            assert isinstance(ax.xaxis.get_major_formatter(), PlainLogFormatter)
            lo, hi = ax.get_xlim()
            locs = ax.xaxis.get_majorticklocs()
            labels = ax.get_xticklabels()
            if ax.xaxis.get_label_text():       # the bottom row of a shared axis labels it
                assert ax.get_xlabel() == "frequency [rad/s]"
                assert sum(lo <= t <= hi for t in locs) >= 3
                # each label is the decade its tick stands at, no mathtext left
                for t, label in zip(locs, labels, strict=True):
                    k = round(np.log10(t))
                    assert label.get_text() == "10" + "".join(SUPERSCRIPT[c] for c in str(k))
                    assert label.get_visible()
        assert all(ax.get_legend() is not None for ax in fig.axes)
    bode = figures["bode.png"].axes
    loops = len(bode) // 2
    assert all(ax.get_title().endswith("loop (others closed)") for ax in bode[:loops])
    assert bode[0].get_ylabel() == "|l| [dB]"
    assert bode[loops].get_ylabel().startswith("arg l [deg]")
    assert [ax.get_title()[:22] for ax in figures["sigma.png"].axes] == [
        "singular values of S =", "singular values of T ="]


def test_figures_are_made_at_the_pngs_resolution(figures):
    for name, fig in figures.items():
        assert fig.dpi == PNG_DPI, name
        png = Image.open(io.BytesIO(figure_png(fig)))
        width, height = fig.get_size_inches()
        assert png.size == (int(width * PNG_DPI + 1e-8), int(height * PNG_DPI + 1e-8))
        # nothing moved since the layout: the titles stay inside the figure
        renderer = fig.canvas.get_renderer()
        box = fig.bbox
        for ax in fig.axes:
            title = ax.title.get_window_extent(renderer)
            assert box.x0 <= title.x0 and title.x1 <= box.x1 and title.y1 <= box.y1


@pytest.mark.parametrize("channels", [3, 4])
def test_encode_png_is_decoded_to_the_same_pixels(channels):
    rng = np.random.default_rng(20)
    pixels = rng.integers(0, 256, size=(37, 53, channels), dtype=np.uint8)
    pixels[10:20] = 255                         # repeated rows, as a figure has
    image = Image.open(io.BytesIO(encode_png(pixels, dpi=110)))
    assert image.mode == ("RGB" if channels == 3 else "RGBA")
    assert np.array_equal(np.asarray(image), pixels)
    assert image.info["dpi"] == pytest.approx((110, 110), abs=0.01)


def test_the_figures_package_loads_a_module_on_first_use():
    code = ("import sys, quadland.plots as p; "
            "print(sorted(m for m in sys.modules if m.startswith('quadland.plots.'))); "
            "p.margin_figures; "
            "print('quadland.plots.margins' in sys.modules, "
            "'quadland.plots.landing' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.splitlines()
    assert out == ["[]", "True False"]

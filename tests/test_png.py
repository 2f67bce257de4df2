"""A figure's PNG (quadland.png): the pixels matplotlib's own ``savefig`` writes."""

import io

import numpy as np
from matplotlib.figure import Figure
from PIL import Image

from quadland.png import PNG_DPI, figure_png


def _pixels(png: bytes) -> tuple[str, np.ndarray]:
    image = Image.open(io.BytesIO(png))
    return image.mode, np.asarray(image.convert("RGBA"))


def _savefig(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=PNG_DPI)
    return buf.getvalue()


def _laid_out_figure(**kw) -> Figure:
    """Two log axes with titles and legends, laid out by tight_layout (which leaves the
    placeholder layout engine figure_png sets aside while it draws)."""
    fig = Figure(figsize=(4.1, 2.3), **kw)
    w = np.logspace(-2, 3, 200)
    for k, a in enumerate(fig.subplots(1, 2)):
        a.semilogx(w, 20 * np.log10(np.abs(1 / (1j * w * (1 + 1j * w / (k + 2))))), label="l")
        a.set_title(f"loop {k}")
        a.grid(True, which="both", alpha=0.3)
        a.legend(loc="best")
    fig.tight_layout()
    return fig


def test_an_opaque_figure_is_savefigs_pixels_in_rgb():
    fig = _laid_out_figure()
    expected = _savefig(fig)           # matplotlib's PNG, every pixel opaque
    mode, got = _pixels(figure_png(fig))
    assert mode == "RGB"
    assert np.array_equal(got, _pixels(expected)[1])
    # 4.1 x 2.3 in at 110 dpi, each side truncated as matplotlib's canvas is
    assert got.shape == (253, 451, 4)
    # the layout engine tight_layout left is back, for a later draw
    assert fig.get_layout_engine() is not None


def test_a_transparent_figure_keeps_its_alpha():
    fig = _laid_out_figure(facecolor=(1.0, 1.0, 1.0, 0.0))
    mode, got = _pixels(figure_png(fig))
    assert mode == "RGBA"
    assert got[..., 3].min() == 0
    assert np.array_equal(got, _pixels(_savefig(fig))[1])


def test_an_alpha_of_254_is_not_opaque():
    """Every pixel's alpha 254 (one short of opaque): written RGBA, as savefig's pixels."""
    fig = _laid_out_figure(facecolor=(1.0, 1.0, 1.0, 254 / 255))
    mode, got = _pixels(figure_png(fig))
    assert mode == "RGBA"
    assert got[..., 3].min() == 254
    assert np.array_equal(got, _pixels(_savefig(fig))[1])

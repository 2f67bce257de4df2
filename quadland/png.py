"""A figure's PNG bytes, as every command writes them (:func:`figure_png`)."""

from __future__ import annotations

import contextlib
import io

import numpy as np

__all__ = ["PNG_DPI", "PNG_COMPRESS_LEVEL", "figure_png"]

#: Resolution of the figures written, dots per inch.
PNG_DPI = 110
#: zlib level of the figures' PNGs: 1 encodes in about half the time of Pillow's
#: default 6 and, as RGB, in files about as large as before (RGBA at 6).
PNG_COMPRESS_LEVEL = 1


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure, the same for the same figure.

    Drawn at :data:`PNG_DPI` (matplotlib's Agg, as ``savefig`` draws a PNG)
    and encoded by Pillow without matplotlib's "Software" entry (which
    carries its version): an opaque figure (every pixel's alpha 255, as a
    figure with a coloured background is) as RGB, the alpha channel
    dropped, else RGBA; at zlib level :data:`PNG_COMPRESS_LEVEL`. The
    pixels are those ``savefig`` writes. A figure that pyplot manages is
    closed afterwards, so that a batch of figures does not accumulate.

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    bytes
    """
    from PIL import Image

    raw = io.BytesIO()
    with _layout_done(fig):
        fig.savefig(raw, format="rgba", dpi=PNG_DPI)
    # the canvas savefig draws: figure size x dpi, each truncated after adding 1e-8
    # (matplotlib's FigureCanvasBase.get_width_height)
    width, height = (int(v * PNG_DPI + 1e-8) for v in fig.get_size_inches())
    pixels = np.frombuffer(raw.getbuffer(), dtype=np.uint8)
    if pixels.size != width * height * 4:       # not expected: let matplotlib encode
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=PNG_DPI, metadata={"Software": None})
    else:
        pixels = pixels.reshape(height, width, 4)
        image = (Image.fromarray(pixels[..., :3]) if bool((pixels[..., 3] == 255).all())
                 else Image.fromarray(pixels))
        buf = io.BytesIO()
        image.save(buf, format="png", compress_level=PNG_COMPRESS_LEVEL,
                   dpi=(PNG_DPI, PNG_DPI))
    if getattr(fig.canvas, "manager", None) is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return buf.getvalue()


@contextlib.contextmanager
def _layout_done(fig):
    """The figure without the placeholder layout engine ``tight_layout`` leaves.

    With any layout engine set, ``savefig`` draws the whole figure once
    (rendering nothing) before drawing it: for the placeholder of a layout
    already done that pass only recomputes every tick and text the real draw
    computes again, a third of a figure's cost. Its pixels are the same
    without it.
    """
    from matplotlib import rcParams
    from matplotlib.layout_engine import PlaceHolderLayoutEngine

    engine = fig.get_layout_engine()
    if (not isinstance(engine, PlaceHolderLayoutEngine) or rcParams["figure.autolayout"]
            or rcParams["figure.constrained_layout.use"]):
        yield
        return
    fig.set_layout_engine(None)       # None: no engine (the rcParams above are off)
    try:
        yield
    finally:
        fig.set_layout_engine(engine)

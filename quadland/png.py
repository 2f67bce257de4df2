"""A figure's PNG bytes, as every command writes them (:func:`figure_png`)."""

from __future__ import annotations

import contextlib
import io
import struct
import zlib

import numpy as np

__all__ = ["PNG_DPI", "PNG_COMPRESS_LEVEL", "figure_png", "encode_png"]

#: Resolution of the figures written, dots per inch.
PNG_DPI = 110
#: zlib level of the figures' PNGs: 1 encodes in about half the time of Pillow's
#: default 6 and, as RGB, in files about as large as before (RGBA at 6).
PNG_COMPRESS_LEVEL = 1

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: PNG's filter type "Up": each byte minus the byte above it.
_UP = 2


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(
        ">I", zlib.crc32(data, zlib.crc32(kind)))


def encode_png(pixels: np.ndarray, dpi: float = PNG_DPI,
               level: int = PNG_COMPRESS_LEVEL) -> bytes:
    """PNG bytes of 8-bit RGB or RGBA pixels, every row filtered "Up".

    A figure's rows mostly repeat the row above (white space, grid lines,
    axes), so "Up" leaves mostly zeros for zlib: files as small as Pillow's
    adaptive filtering makes them, in half its time, with no encoder to load.

    Parameters
    ----------
    pixels : ndarray of uint8, shape (height, width, 3 or 4)
        RGB or RGBA, top row first.
    dpi : float
        Written as the image's physical resolution (``pHYs``, dots per metre).
    level : int
        zlib level.

    Returns
    -------
    bytes
    """
    height, width, channels = pixels.shape
    rows = np.ascontiguousarray(pixels, dtype=np.uint8).reshape(height, width * channels)
    filtered = np.empty((height, width * channels + 1), dtype=np.uint8)
    filtered[:, 0] = _UP
    filtered[0, 1:] = rows[0]                   # the row above the first is zeros
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])     # modulo 256
    per_metre = int(dpi / 0.0254 + 0.5)
    header = struct.pack(">IIBBBBB", width, height, 8, {3: 2, 4: 6}[channels], 0, 0, 0)
    return b"".join((_SIGNATURE, _chunk(b"IHDR", header),
                     _chunk(b"pHYs", struct.pack(">IIB", per_metre, per_metre, 1)),
                     _chunk(b"IDAT", zlib.compress(filtered.data, level)),
                     _chunk(b"IEND", b"")))


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure, the same for the same figure.

    Drawn at :data:`PNG_DPI` (matplotlib's Agg, as ``savefig`` draws a PNG)
    and encoded by :func:`encode_png`, without matplotlib's "Software" entry
    (which carries its version): an opaque figure (every pixel's alpha 255, as a
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
        png = buf.getvalue()
    else:
        opaque = bool((pixels.view("<u4") >= 0xFF000000).all())    # each alpha byte 255
        pixels = pixels.reshape(height, width, 4)
        png = encode_png(_without_alpha(pixels) if opaque else pixels)
    if getattr(fig.canvas, "manager", None) is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return png


def _without_alpha(pixels: np.ndarray) -> np.ndarray:
    """The RGB bytes of contiguous RGBA pixels, by Pillow (which matplotlib requires and
    imports with its figures) in about half numpy's time for a strided copy."""
    try:
        from PIL import Image
    except ImportError:         # pragma: no cover - matplotlib requires Pillow
        return np.ascontiguousarray(pixels[..., :3])
    height, width, _ = pixels.shape
    rgb = Image.frombuffer("RGBA", (width, height), pixels, "raw", "RGBA", 0, 1).convert("RGB")
    return np.frombuffer(rgb.tobytes(), dtype=np.uint8).reshape(height, width, 3)


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

"""A log axis's minor ticks drawn as two artists (quadland.plots.log_minor): the same
places and the same pixels as matplotlib's own minor ticks."""

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import NullLocator

from quadland.plots.log_minor import MinorTicks, cheap_minor_ticks


def _bode_like(cheap: bool, xlim=None) -> Figure:
    """A 2 x 2 figure of semilogx axes sharing x, minor grid on, as the Bode figure is."""
    fig = Figure(figsize=(10, 5), dpi=100)
    axes = fig.subplots(2, 2, sharex=True)
    w = np.logspace(-2.3, 3.1, 300)
    for k, a in enumerate(axes.flat):
        a.semilogx(w, 20 * np.log10(np.abs(1 / (1j * w * (1 + 1j * w / (k + 1))))))
        a.axhline(0, color="k", lw=0.6)
        a.set_title(f"loop {k}")
        a.grid(True, which="both", alpha=0.3)
        if cheap:
            cheap_minor_ticks(a)
    if xlim is not None:
        axes[0, 0].set_xlim(*xlim)
    fig.tight_layout()
    return fig


def _rgba(fig) -> np.ndarray:
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba()).copy()


@pytest.mark.parametrize("xlim", [None, (0.3, 40.0)])
def test_the_same_pixels_as_matplotlibs_minor_ticks(xlim):
    # matplotlib's own Tick per minor tick against the two artists: whole figure, exact
    assert np.array_equal(_rgba(_bode_like(False, xlim)), _rgba(_bode_like(True, xlim)))


def test_the_places_are_matplotlibs():
    plain, cheap = _bode_like(False), _bode_like(True)
    _rgba(plain)
    _rgba(cheap)
    for a, b in zip(plain.axes, cheap.axes, strict=True):
        lo, hi = a.get_xlim()
        # matplotlib's minor ticks in the view (its _update_ticks keeps those within it)
        expected = [t for t in a.xaxis.get_minorticklocs() if lo <= t <= hi]
        (artist,) = [m for m in b.artists if isinstance(m, MinorTicks)]
        assert np.array_equal(artist.locations(), expected)
        assert len(expected) > 30                  # 2 to 9 in every decade of about 5
        assert isinstance(b.xaxis.get_minor_locator(), NullLocator)


def test_once_per_axes_and_only_on_log_axes():
    fig = _bode_like(True)
    a = fig.axes[0]
    cheap_minor_ticks(a)                           # an overlay's second call: nothing added
    assert sum(isinstance(m, MinorTicks) for m in a.artists) == 1
    linear = Figure().subplots()
    linear.plot([0, 1], [0, 1])
    cheap_minor_ticks(linear)
    assert not linear.artists

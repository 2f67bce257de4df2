"""quadland.plots.text_cache in a long process: figures drawn one after another with the rc
parameters changed between them give the pixels matplotlib's own canvas gives for each.

The reference is matplotlib's own ``Figure`` on its own Agg canvas, drawn in the same
process right after quadland's, for each figure of the sequence.
"""

from __future__ import annotations

import logging

import matplotlib as mpl
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from quadland.plots import text_cache
from quadland.plots.text_cache import TextCacheCanvas

pytestmark = pytest.mark.skipif(not text_cache._CACHEABLE,
                                reason="this matplotlib's Agg renderer draws text otherwise")

#: Characters no font here has (matplotlib's last-resort font draws them, or .notdef does).
MISSING = "中文 ⟦x⟧ 0.5"


def _pixels(canvas_class, dpi, content) -> np.ndarray:
    fig = Figure(figsize=(3.0, 1.5), dpi=dpi)
    canvas_class(fig)
    content(fig)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba()).copy()


def _words(fig):
    fig.text(0.05, 0.6, MISSING, fontsize=14)
    fig.text(0.05, 0.2, MISSING, fontsize=14, rotation=10)


@pytest.mark.parametrize("order", [(True, False, True), (False, True, False)])
def test_the_last_resort_switch_between_figures(order, caplog):
    caplog.set_level(logging.ERROR)
    for last_resort in order:
        with mpl.rc_context({"font.enable_last_resort": last_resort}):
            mine = _pixels(TextCacheCanvas, 110, _words)
            theirs = _pixels(FigureCanvasAgg, 110, _words)
        assert np.array_equal(mine, theirs), f"font.enable_last_resort={last_resort}"

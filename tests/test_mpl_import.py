"""quadland.mpl_import: the command line's process imports matplotlib's figure module
without the artists' generated ``set`` docstrings, and draws the same figures; any other
process imports it as matplotlib does."""

from __future__ import annotations

import subprocess
import sys

_PROBE = """
import sys
import quadland.mpl_import as mi
if sys.argv[1] == "cli":
    mi.for_the_command_line()
import quadland.plots
from matplotlib.lines import Line2D

class Later(Line2D):            # defined after the import: as matplotlib makes it
    pass

line = Line2D([0, 1], [0, 1])
line.set(color="r", linewidth=3, label="x")      # set takes every property still
print(bool(Line2D.set.__doc__), "linewidth" in str(getattr(Line2D.set, "__signature__", "")),
      "linewidth" in (Later.set.__doc__ or ""), line.get_color(), line.get_linewidth())
"""


def _probe(mode: str) -> str:
    proc = subprocess.run([sys.executable, "-c", _PROBE, mode], capture_output=True,
                          text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.strip()


def test_the_command_line_skips_the_set_docstrings_and_others_do_not():
    assert _probe("cli") == "False False True r 3.0"
    assert _probe("plain") == "True True True r 3.0"


_TABLES = """
import sys
import quadland.mpl_import as mi
if sys.argv[1] == "cli":
    mi.for_the_command_line()
import quadland.plots
from matplotlib import _docstring
from matplotlib.axes import Axes

@_docstring.interpd
def later():
    '''Properties: %(Line2D:kwdoc)s'''

print("markerfacecoloralt" in Axes.plot.__doc__, "markerfacecoloralt" in later.__doc__)
"""


def test_the_property_tables_are_matplotlibs_in_every_process():
    """The artists' property tables (``%(Line2D:kwdoc)s``) are written into matplotlib's
    docstrings as matplotlib writes them, in the command line's process as in any other:
    ``Axes.plot``'s docstring (defined while the figure module is imported) and one
    defined afterwards both list a property of ``Line2D`` (the eighteenth session's
    review left matplotlib's private docstring loader unpatched, docs/performance.md)."""
    for mode in ("cli", "plain"):
        proc = subprocess.run([sys.executable, "-c", _TABLES, mode], capture_output=True,
                              text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr
        assert proc.stdout.strip() == "True True"


def test_the_command_lines_figures_are_matplotlibs(tmp_path):
    """A margin figure written by the command line's process (the docstrings skipped)
    and by a plain one: the same bytes."""
    code = """
import sys
import quadland.mpl_import as mi
if sys.argv[1] == "cli":
    mi.for_the_command_line()
import quadland
from quadland.margins import margin_report
from quadland.output import figure_png
from quadland.plots import margin_figures
figs = margin_figures(margin_report(quadland.load_scenario("paper", ["rbf.nodes=5"])))
sys.stdout.buffer.write(b"".join(figure_png(f) for f in figs.values()))
"""
    out = [subprocess.run([sys.executable, "-c", code, mode], capture_output=True,
                          timeout=300).stdout for mode in ("cli", "plain")]
    assert out[0][:8] == b"\x89PNG\r\n\x1a\n"
    assert out[0] == out[1]

"""Figures of quadland's results, as matplotlib Figures.

:mod:`quadland.plots.simulation` draws a simulation (the paper's Figures
2-5 and the ground track), :mod:`quadland.plots.margins` a margin review
(Bode, Nyquist, Nichols, singular values, poles), :mod:`quadland.plots.navigation` the
navigation filter's estimate and consistency. Every function returns a
:class:`matplotlib.figure.Figure` made without pyplot: nothing is shown or
kept behind the caller's back and no backend is chosen, so a figure
displays in a notebook as it is, and ``quadland.output.figure_png`` turns
it into the PNG the command line writes.

In IPython (a Jupyter notebook), importing this package lets a Figure made
without pyplot display inline as a PNG: matplotlib's inline backend registers
its display formatter only once pyplot is imported, so without it a notebook
shows ``<Figure size 700x820 with 4 Axes>``. Nothing happens outside IPython,
and the backend is never changed.

The margin figures import python-control; they are loaded on first use so
that drawing a simulation does not pay for it.
"""

import io
import sys

from matplotlib.figure import Figure

from quadland.plots.animation import landing_animation
from quadland.plots.landing import (
    LANDING_FIGURES,
    landing_figures,
    landing_ground_track_plot,
    landing_limits,
    relative_position_plot,
    rotor_forces_plot,
    trajectory_3d_plot,
)
from quadland.plots.navigation import (
    NAVIGATION_FIGURES,
    consistency_plot,
    navigation_plot,
)
from quadland.plots.simulation import (
    SIMULATION_FIGURES,
    control_inputs_plot,
    ground_track_plot,
    relative_errors_plot,
    simulation_figures,
    uncertainty_plot,
    velocity_errors_plot,
)

__all__ = ["SIMULATION_FIGURES", "simulation_figures", "relative_errors_plot",
           "velocity_errors_plot", "control_inputs_plot", "uncertainty_plot",
           "ground_track_plot", "MARGIN_FIGURES", "margin_figures", "bode_plot",
           "nyquist_plot", "nichols_plot", "sigma_plot", "pole_plot",
           "LANDING_FIGURES", "landing_figures", "landing_limits", "trajectory_3d_plot",
           "relative_position_plot", "landing_ground_track_plot", "rotor_forces_plot",
           "landing_animation", "NAVIGATION_FIGURES", "navigation_plot", "consistency_plot"]

_LAZY = {"MARGIN_FIGURES": "MARGIN_FIGURES", "margin_figures": "margin_figures",
         "bode_plot": "bode_plot", "nyquist_plot": "nyquist_plot",
         "nichols_plot": "nichols_plot", "sigma_plot": "sigma_plot", "pole_plot": "pole_plot"}


def __getattr__(name):
    if name in _LAZY:
        from quadland.plots import margins

        return getattr(margins, _LAZY[name])
    raise AttributeError(f"module 'quadland.plots' has no attribute {name!r}")


def _figure_png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", bbox_inches="tight")
    return buf.getvalue()


def _show_figures_in_ipython() -> None:
    """Register a PNG display formatter for Figure in a running IPython, unless one is."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None
    formatters = getattr(getattr(shell, "display_formatter", None), "formatters", {})
    png = formatters.get("image/png")
    if png is not None and Figure not in png.type_printers:
        png.for_type(Figure, _figure_png)


_show_figures_in_ipython()

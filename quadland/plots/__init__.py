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

Each figure's module is loaded on first use of one of its names, so that a
command pays only for the figures it draws.
"""

import importlib
import io
import sys

from quadland.mpl_import import figure_class

Figure = figure_class()     # the command line's process imports it without set's docs

__all__ = ["SIMULATION_FIGURES", "simulation_figures", "relative_errors_plot",
           "velocity_errors_plot", "control_inputs_plot", "uncertainty_plot",
           "ground_track_plot", "MARGIN_FIGURES", "margin_figures", "bode_plot",
           "nyquist_plot", "nichols_plot", "sigma_plot", "pole_plot",
           "LANDING_FIGURES", "landing_figures", "landing_limits", "trajectory_3d_plot",
           "relative_position_plot", "landing_ground_track_plot", "rotor_forces_plot",
           "landing_animation", "NAVIGATION_FIGURES", "navigation_plot", "consistency_plot"]

#: Each name's module, loaded on first use: a command imports only the figures it
#: draws (the margin figures do not pay for the landing's, its 3D axes and its
#: navigation filter's symbolic modules).
_LAZY = {
    **dict.fromkeys(("SIMULATION_FIGURES", "simulation_figures", "relative_errors_plot",
                     "velocity_errors_plot", "control_inputs_plot", "uncertainty_plot",
                     "ground_track_plot"), "quadland.plots.simulation"),
    **dict.fromkeys(("MARGIN_FIGURES", "margin_figures", "bode_plot", "nyquist_plot",
                     "nichols_plot", "sigma_plot", "pole_plot"), "quadland.plots.margins"),
    **dict.fromkeys(("LANDING_FIGURES", "landing_figures", "landing_limits",
                     "trajectory_3d_plot", "relative_position_plot",
                     "landing_ground_track_plot", "rotor_forces_plot"),
                    "quadland.plots.landing"),
    "landing_animation": "quadland.plots.animation",
    **dict.fromkeys(("NAVIGATION_FIGURES", "navigation_plot", "consistency_plot"),
                    "quadland.plots.navigation"),
}


def __getattr__(name):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'quadland.plots' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(__all__))


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

"""quadland: adaptive RBFNN backstepping landing of a quadrotor on a moving vehicle.

The model and the controller live once, symbolically, in ``symbolic``;
this package loads scenarios, simulates, analyses and plots.
"""

from importlib.metadata import PackageNotFoundError, version

from quadland.exceptions import QuadlandError, ScenarioError, SimulationError
from quadland.scenario import Scenario, load_scenario
from quadland.simulate import SimulationResult, simulate

try:
    __version__ = version("quadland")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__", "QuadlandError", "ScenarioError", "SimulationError", "Scenario",
           "load_scenario",
           "SimulationResult", "simulate", "allmargin", "diskmargin", "equilibrium",
           "frozen_point", "linear_models", "Requirement", "MarginReport", "margin_report",
           "format_report", "simulation_figures", "margin_figures", "run_campaign"]

# The analysis API imports python-control and the figures matplotlib; load
# them on first use so that `import quadland` stays light for simulation.
_LAZY = {"allmargin": "quadland.analysis", "diskmargin": "quadland.analysis",
         "equilibrium": "quadland.linearize", "frozen_point": "quadland.linearize",
         "linear_models": "quadland.linearize", "Requirement": "quadland.margins",
         "MarginReport": "quadland.margins", "margin_report": "quadland.margins",
         "format_report": "quadland.margins", "simulation_figures": "quadland.plots",
         "margin_figures": "quadland.plots", "run_campaign": "quadland.campaign.execute"}


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'quadland' has no attribute {name!r}")

"""quadland: adaptive RBFNN backstepping landing of a quadrotor on a moving vehicle.

The model and the controller live once, symbolically, in ``symbolic``;
this package loads scenarios, simulates, analyses and plots.
"""

from importlib.metadata import PackageNotFoundError, version

from quadland.exceptions import QuadlandError, ScenarioError
from quadland.scenario import Scenario, load_scenario
from quadland.simulate import SimulationResult, simulate

try:
    __version__ = version("quadland")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"

__all__ = ["__version__", "QuadlandError", "ScenarioError", "Scenario", "load_scenario",
           "SimulationResult", "simulate"]

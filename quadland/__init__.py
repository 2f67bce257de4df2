"""quadland: adaptive RBFNN backstepping landing of a quadrotor on a moving vehicle.

The model and the controller live once, symbolically, in ``quadland_symbolic``;
this package loads scenarios, simulates, analyses and plots. Every name below
(``__version__`` too) is loaded on first use, so that ``import quadland`` (and
``python -m quadland``, whose Ctrl-C must be one line from its first instant)
imports nothing.
"""

__all__ = ["__version__", "QuadlandError", "ScenarioError", "SimulationError", "Scenario",
           "load_scenario", "SimulationResult", "simulate", "kind_of", "KINDS", "allmargin",
           "diskmargin", "equilibrium", "frozen_point", "linear_models", "sampled_models",
           "Requirement", "MarginReport", "margin_report", "format_report",
           "simulation_figures", "margin_figures", "run_campaign", "run_envelope", "nlsys"]

#: When this package was first imported (``time.time_ns``): a source file written after it
#: may differ from the code this process runs (``quadland.engine.recall.remember``).
IMPORTED_NS = __import__("time").time_ns()

_LAZY = {"QuadlandError": "quadland.exceptions", "ScenarioError": "quadland.exceptions",
         "SimulationError": "quadland.exceptions", "Scenario": "quadland.scenario",
         "load_scenario": "quadland.scenario", "SimulationResult": "quadland.engine.result",
         "simulate": "quadland.simulation", "kind_of": "quadland.kinds", "KINDS": "quadland.kinds",
         "allmargin": "quadland.analysis", "diskmargin": "quadland.analysis",
         "equilibrium": "quadland.linearization", "frozen_point": "quadland.linearization",
         "linear_models": "quadland.linearization",
         "sampled_models": "quadland.linearization", "Requirement": "quadland.margins",
         "MarginReport": "quadland.margins", "margin_report": "quadland.margins",
         "format_report": "quadland.margins", "simulation_figures": "quadland.plots",
         "margin_figures": "quadland.plots", "run_campaign": "quadland.campaign.execute",
         "run_envelope": "quadland.campaign.grid", "nlsys": "quadland.nonlinear"}


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("quadland")
    except PackageNotFoundError:  # running from a source tree that is not installed
        return "0+unknown"


def __getattr__(name):
    if name == "__version__":
        value = globals()["__version__"] = _version()
        return value
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'quadland' has no attribute {name!r}")


def __dir__():
    return sorted(__all__)

"""A simulation run: validate, simulate, then write every output whole."""

from __future__ import annotations

import json
import platform
from pathlib import Path

import casadi as ca
import numpy as np

from quadland.metrics import summarize
from quadland.output import figure_png, output_folder, write_files
from quadland.scenario import Scenario, load_scenario
from quadland.simulate import SimulationResult, simulate

__all__ = ["run_simulation", "provenance"]


def provenance(scenario: Scenario) -> dict:
    """What made an output: scenario, overrides, seed and software versions."""
    from quadland import __version__

    return {
        "scenario_name": scenario.name,
        "scenario_source": scenario.source,
        "overrides": list(scenario.overrides),
        "seed": scenario.data["simulation"]["seed"],
        "versions": {"quadland": __version__, "casadi": ca.__version__,
                     "numpy": np.__version__, "python": platform.python_version()},
        "scenario": scenario.to_dict(),
    }


def run_simulation(scenario: str | Path | Scenario = "paper", overrides=None,
                   out: Path | None = None, plots: bool = True) -> Path:
    """Simulate a scenario and write its outputs into a folder.

    Writes ``trajectory.csv``, ``summary.json`` and, with ``plots``, the
    figures of :data:`quadland.plots.SIMULATION_FIGURES`. The scenario and
    ``out`` are checked before the simulation, and the folder is created
    only after it has finished; each file is written through a temporary
    file and a rename (:func:`quadland.output.write_files`).

    Parameters
    ----------
    scenario : str, Path or Scenario
        A shipped scenario's name, a TOML file, or a loaded scenario.
    overrides : list of str or dict, optional
        Scenario overrides (ignored for a loaded ``scenario``).
    out : Path, optional
        Output folder; default a new ``<scenario>-<YYYYmmdd-HHMMSS>``
        (:func:`quadland.output.output_folder`).
    plots : bool
        Also write the figures.

    Returns
    -------
    Path
        The output folder.
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    folder = output_folder(out, sc.name)
    result = simulate(sc)
    return write_files(folder, _render(result, plots))


def _render(result: SimulationResult, plots: bool) -> dict[str, bytes]:
    summary = {**summarize(result), **provenance(result.scenario)}
    files = {"trajectory.csv": result.to_csv().encode("utf-8"),
             "summary.json": (json.dumps(summary, indent=2) + "\n").encode("utf-8")}
    if plots:
        from quadland.plots import simulation_figures

        files.update({name: figure_png(fig) for name, fig in simulation_figures(result).items()})
    return files

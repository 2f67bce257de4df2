"""A simulation run: validate, simulate, then write every output whole."""

from __future__ import annotations

import datetime
import json
import platform
from pathlib import Path

import casadi as ca
import numpy as np

from quadland.exceptions import QuadlandError
from quadland.metrics import summarize
from quadland.output import write_bytes_atomic
from quadland.scenario import Scenario, load_scenario
from quadland.simulate import SimulationResult, simulate

__all__ = ["run_simulation", "provenance", "default_out_dir", "prepare_out_dir"]


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


def default_out_dir(scenario: Scenario, kind: str = "") -> Path:
    """``<name>[-kind]-<YYYYmmdd-HHMMSS>`` in the current folder, made unique."""
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    stem = "-".join(s for s in (scenario.name, kind, stamp) if s)
    path, n = Path.cwd() / stem, 1
    while path.exists():
        n += 1
        path = Path.cwd() / f"{stem}-{n}"
    return path


def prepare_out_dir(out: Path) -> Path:
    """Create the output folder (after every input has been validated)."""
    if out.exists() and not out.is_dir():
        raise QuadlandError(f"{out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise QuadlandError(f"{out}: cannot create the output folder: {exc.strerror}") from None
    return out


def _check_out_arg(out: Path | None) -> None:
    if out is not None and out.exists() and not out.is_dir():
        raise QuadlandError(f"--out {out}: exists and is not a folder")


def run_simulation(scenario: str | Path | Scenario = "paper", overrides=None,
                   out: Path | None = None, plots: bool = True) -> Path:
    """Simulate a scenario and write its outputs into a folder.

    Writes ``trajectory.csv``, ``summary.json`` and, with ``plots``, the
    figures of :data:`quadland.plots.FIGURES`. The scenario is validated
    and the simulation finished before the folder is created; each file is
    written through a temporary file and a rename.

    Returns
    -------
    Path
        The output folder.
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    _check_out_arg(out)
    result = simulate(sc)
    files = _render(result, plots)
    folder = prepare_out_dir(out if out is not None else default_out_dir(sc))
    for name, data in files.items():
        write_bytes_atomic(folder / name, data)
    return folder


def _render(result: SimulationResult, plots: bool) -> dict[str, bytes]:
    summary = {**summarize(result), **provenance(result.scenario)}
    files = {"trajectory.csv": result.to_csv().encode("utf-8"),
             "summary.json": (json.dumps(summary, indent=2) + "\n").encode("utf-8")}
    if plots:
        from quadland.plots import render_figures
        files.update(render_figures(result))
    return files

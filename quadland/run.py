"""A simulation run: validate, simulate, then write every output whole."""

from __future__ import annotations

import platform
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from quadland.engine.result import SimulationResult, columns_sidecar
from quadland.exceptions import ScenarioError, SimulationError
from quadland.kinds import KINDS, kind_of
from quadland.output import figure_png, output_folder, strict_json
from quadland.scenario import Scenario, load_scenario

__all__ = ["run_simulation", "provenance", "versions", "result_lines", "DEPENDENCIES"]


#: Distributions whose versions shape a result, recorded in every output.
DEPENDENCIES = ("quadland", "casadi", "numpy", "scipy", "control", "slycot", "matplotlib",
                "Jinja2", "threadpoolctl")


def versions() -> dict:
    """Versions of Python, the C compiler and every distribution in :data:`DEPENDENCIES`."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version(), "platform": platform.platform()}
    for name in DEPENDENCIES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = None
    out["casadi"] = ca.__version__
    from quadland.engine.build import compiler_version

    out["c_compiler"] = compiler_version()
    return out


def provenance(scenario: Scenario) -> dict:
    """What made an output: scenario, overrides, seed and software versions."""
    return {
        "scenario_name": scenario.name,
        "scenario_source": scenario.source,
        "overrides": list(scenario.overrides),
        "seed": scenario.data["simulation"]["seed"],
        "versions": versions(),
        "scenario": scenario.to_dict(),
    }


def run_simulation(scenario: str | Path | Scenario = "paper", overrides=None,
                   out: Path | None = None, plots: bool = True, animate: bool = False) -> Path:
    """Simulate a scenario and write its outputs into a folder, whole.

    Writes ``trajectory.csv``, ``columns.json`` (each column's unit),
    ``summary.json``, ``scenario.toml`` (the resolved scenario: ``quadland
    simulate --scenario OUT/scenario.toml`` repeats the run bit for bit)
    and, with ``plots``, the figures of
    :data:`quadland.plots.SIMULATION_FIGURES`. The scenario, its resource
    plan and ``out`` are checked, and ``out`` is claimed, before the
    simulation; the files appear together after it
    (:class:`quadland.output.OutputFolder`).

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
    animate : bool
        Also write ``landing.gif``, an animation of the landing
        (``quadland.plots.animation.landing_animation``); landing scenarios only.

    Returns
    -------
    Path
        The output folder.

    Raises
    ------
    SimulationError
        The flight failed. The trajectory up to the failure is written
        first, with ``"status": "failed"`` in ``summary.json``.
    ScenarioError
        ``animate`` for a scenario that is not a landing's, or without
        ``quadland.plots.landing``; before any work.
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario, overrides)
    kind = kind_of(sc)
    kind.check(sc)
    if animate and not kind.can_animate:
        animated = ", ".join(k.name for k in KINDS.values() if k.can_animate)
        raise ScenarioError(f"animate: scenario.model \"{sc.model}\" has no animation "
                            f"(the loops that have one: {animated})")
    with output_folder(out, sc.name) as folder:
        try:
            result = kind.simulate(sc)
        except SimulationError as exc:
            if exc.partial is not None:
                folder.write(_render(exc.partial, plots, animate, failure=str(exc)))
            raise
        return folder.write(_render(result, plots, animate))


def _render(result: SimulationResult, plots: bool, animate: bool = False,
            failure: str | None = None) -> dict:
    kind = kind_of(result.scenario)
    status = {"status": "failed", "failure": failure} if failure else {"status": "ok"}
    summary = {**status, **kind.summary(result), **provenance(result.scenario)}
    files = {"trajectory.csv": result.to_csv().encode("utf-8"),
             "columns.json": strict_json(columns_sidecar(result.layout)),
             "summary.json": strict_json(summary),
             "scenario.toml": result.scenario.to_toml().encode("utf-8")}
    if plots and len(result["t"]) > 1:
        with np.errstate(all="ignore"):            # a failed flight's diverged rows
            files.update({name: figure_png(fig) for name, fig in kind.figures(result).items()})
    if animate and len(result["t"]) > 1:
        with tempfile.TemporaryDirectory() as tmp, np.errstate(all="ignore"):
            files["landing.gif"] = kind.animation(result, Path(tmp) / "landing.gif").read_bytes()
    return files


def result_lines(out) -> list[str]:
    """The verdict and figures of the run written to ``out``, from its summary.json (the
    lines ``quadland simulate`` prints; none if the file is absent or unreadable)."""
    import json

    from quadland.kinds import KINDS
    from quadland.scenario import DEFAULT_MODEL

    try:
        summary = json.loads((Path(out) / "summary.json").read_text())
        model = summary["scenario"]["scenario"].get("model", DEFAULT_MODEL)
        return KINDS[model].result_lines(summary)
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return []

"""Regenerate, or check, the committed C code under ``generated/``.

``generated/`` holds the double-precision build at its top, the
single-precision build in ``float/`` and the pure-C example in
``example/``; every file comes from :func:`symbolic.codegen.generate` with
the paper scenario's values as defaults.
"""

from __future__ import annotations

import difflib
import sys
import tempfile
from pathlib import Path

import numpy as np

from quadland.model import model_values
from quadland.scenario import load_scenario
from symbolic.codegen import CodegenConfig, Defaults, generate, generate_example

__all__ = ["GENERATED_DIR", "EXAMPLE_CONTROL_RATE_HZ", "TILT_MIN", "default_values",
           "generated_files", "write", "diff", "main"]

#: The project's committed ``generated/`` folder.
GENERATED_DIR = Path(__file__).resolve().parents[1] / "generated"

#: Control rate of the pure-C example flight, Hz (a flight stack's typical rate).
EXAMPLE_CONTROL_RATE_HZ = 500.0

#: Default smallest accepted |cos(theta1) cos(phi1)|, as the simulator's.
TILT_MIN = 1e-3

_GITIGNORE = ("# Build outputs of the example (quadland codegen writes this file).\n"
              "example/build/\n*.o\n*.so\n*.csv\n")


def default_values(scenario_name: str = "paper") -> Defaults:
    """The C defaults: the values of a shipped scenario (the paper's)."""
    sc = load_scenario(scenario_name)
    mv = model_values(sc)
    d, sim = sc.data["disturbance"], sc.data["simulation"]
    return Defaults(
        l=mv.l, p_quad=mv.p_quad, p_veh=mv.p_veh, p_ctrl=mv.p_ctrl, ref=mv.ref,
        rotor_limits=tuple(float(v) for v in mv.rotor_limits), tilt_min=TILT_MIN,
        hold=mv.hold, x0=mv.x0,
        duration=float(sim["duration"]), output_rate_hz=float(sim["output_rate_hz"]),
        control_rate_hz=EXAMPLE_CONTROL_RATE_HZ,
        disturbance_rate_hz=float(d["sample_rate_hz"]),
        force_bias=tuple(np.asarray(d["force_bias"], dtype=float)),
        force_amplitude=float(d["force_amplitude"]),
        force_frequency=float(d["force_frequency"]),
        moment_bias=tuple(np.asarray(d["moment_bias"], dtype=float)),
        moment_amplitude=float(d["moment_amplitude"]),
        moment_frequency=float(d["moment_frequency"]))


def generated_files(defaults: Defaults | None = None) -> dict[str, str]:
    """Every file of ``generated/`` by relative path (POSIX separators)."""
    defaults = defaults or default_values()
    files = dict(generate(defaults, CodegenConfig("double")))
    files.update({f"float/{k}": v for k, v in generate(defaults, CodegenConfig("float")).items()})
    files.update(generate_example(defaults))
    files[".gitignore"] = _GITIGNORE
    return files


def write(out: Path, files: dict[str, str]) -> list[str]:
    """Write ``files`` under ``out``; return the paths that changed."""
    changed = []
    for rel, text in sorted(files.items()):
        path = out / rel
        data = text.encode("utf-8")
        if path.exists() and path.read_bytes() == data:
            continue
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        changed.append(rel)
    return changed


def diff(out: Path, files: dict[str, str]) -> str:
    """Unified diff from the files in ``out`` to ``files`` (empty when equal)."""
    chunks = []
    for rel, text in sorted(files.items()):
        path = out / rel
        old = path.read_text(encoding="utf-8") if path.exists() else ""
        if old != text:
            chunks.extend(difflib.unified_diff(
                old.splitlines(keepends=True), text.splitlines(keepends=True),
                fromfile=f"a/{rel}" if path.exists() else "/dev/null", tofile=f"b/{rel}"))
    return "".join(chunks)


def main(out: Path | None = None, check: bool = False) -> int:
    """The ``quadland codegen`` command.

    Parameters
    ----------
    out : Path, optional
        Target folder; the project's ``generated/`` by default.
    check : bool
        Regenerate into a temporary folder and compare instead of writing:
        print a unified diff and return 1 where ``out`` differs.

    Returns
    -------
    int
        Exit status: 0, or 1 when ``check`` found differences.
    """
    out = Path(out) if out is not None else GENERATED_DIR
    files = generated_files()
    if check:
        with tempfile.TemporaryDirectory() as tmp:
            write(Path(tmp), files)
            fresh = {rel: (Path(tmp) / rel).read_text(encoding="utf-8") for rel in files}
        text = diff(out, fresh)
        if text:
            sys.stdout.write(text)
            print(f"quadland: {out} is out of date; run `quadland codegen --out {out}`",
                  file=sys.stderr)
            return 1
        print(f"quadland: {out} is up to date ({len(files)} files)")
        return 0
    changed = write(out, files)
    print(f"quadland: wrote {len(changed)} of {len(files)} files in {out}")
    return 0

"""A non-editable install works from outside the checkout and writes nothing into itself.

The package is built from a copy of its sources (no build isolation, so no
download) and installed with ``pip --target`` into a folder; the commands
then run with that folder first on the path, from a folder outside the
checkout, with an empty compiler cache.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _tree(folder: Path) -> dict[str, int]:
    return {str(p.relative_to(folder)): p.stat().st_size for p in folder.rglob("*")
            if p.is_file() and "__pycache__" not in p.parts}


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    base = tmp_path_factory.mktemp("install")
    src = base / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("quadland", "symbolic"):
        shutil.copytree(ROOT / name, src / name,
                        ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    target = base / "site"
    proc = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                           "--no-build-isolation", "--target", str(target), str(src)],
                          capture_output=True, text=True, timeout=600)
    if proc.returncode != 0:
        pytest.fail(f"pip install failed: {proc.stderr[-2000:]}")
    work = base / "elsewhere"
    work.mkdir()
    env = dict(os.environ, PYTHONPATH=str(target), XDG_CACHE_HOME=str(base / "cache"))
    return target, work, env


def _quadland(installed, *args):
    target, work, env = installed
    return subprocess.run([sys.executable, "-m", "quadland", *args], cwd=work, env=env,
                          capture_output=True, text=True, timeout=600)


@pytest.mark.slow
def test_it_runs_the_installed_copy(installed):
    target, work, env = installed
    proc = subprocess.run([sys.executable, "-c", "import quadland, quadland_symbolic; "
                           "print(quadland.__file__); print(quadland_symbolic.__file__)"],
                          cwd=work, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert all(line.startswith(str(target)) for line in proc.stdout.split())
    # the symbolic layer is installed under its own name only
    assert (target / "quadland_symbolic").is_dir() and not (target / "symbolic").exists()


def test_pyproject_lists_every_package():
    """setuptools ships only the packages pyproject.toml lists: every folder of Python
    or templates under quadland/ and symbolic/ (installed as quadland_symbolic) is one."""
    import tomllib

    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = set()
    for top, name in (("quadland", "quadland"), ("symbolic", "quadland_symbolic")):
        for folder in [ROOT / top, *(p for p in (ROOT / top).rglob("*") if p.is_dir())]:
            if "__pycache__" in folder.parts:
                continue
            if any(folder.glob("*.py")) or any(folder.glob("*.jinja")) or any(
                    folder.glob("*.toml")):
                rel = folder.relative_to(ROOT / top).parts
                found.add(".".join((name, *rel)))
    assert found == listed


@pytest.mark.slow
def test_commands_work_and_write_nothing_into_the_package(installed):
    target, work, _ = installed
    before = _tree(target)
    proc = _quadland(installed, "simulate", "--set", "simulation.duration=0.2", "--no-plots",
                     "--out", "sim")
    assert proc.returncode == 0, proc.stderr
    proc = _quadland(installed, "simulate", "--set", "simulation.duration=0.1", "--set",
                     "controller.rate_hz=500", "--set", "controller.backend=c", "--set",
                     "rbf.nodes=5", "--no-plots", "--out", "sim_c")
    assert proc.returncode == 0, proc.stderr
    proc = _quadland(installed, "margins", "--set", "rbf.nodes=5", "--no-plots", "--out", "mg")
    assert proc.returncode == 0, proc.stderr
    proc = _quadland(installed, "codegen", "--out", "gen")
    assert proc.returncode == 0, proc.stderr
    generated = ROOT / "generated"
    for rel in ("quadland.h", "control_step.c", "float/quadland.h", "example/fly.c"):
        assert (work / "gen" / rel).read_text() == (generated / rel).read_text(), rel
    assert (work / "sim" / "trajectory.csv").exists() and (work / "mg" / "margins.json").exists()
    assert _tree(target) == before


@pytest.mark.slow
def test_codegen_without_out_outside_a_checkout_is_one_line(installed):
    target, work, _ = installed
    before = _tree(target)
    for args in (["codegen"], ["codegen", "--check"]):
        proc = _quadland(installed, *args)
        assert proc.returncode == 2
        (line,) = proc.stderr.strip().splitlines()
        assert line.startswith("quadland: error: ") and "--out" in line
    assert _tree(target) == before

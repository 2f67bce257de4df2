"""Cold and warm ``simulate`` of the paper scenario against the SciPy baseline, paired.

Issue 20's targets for ``simulate`` measured side by side in one run, every
measurement of one round taken in turn (CPU time, medians (min to max)):

* the SciPy baseline of ``bench_simulate.py`` (``solve_ivp`` RK45 on the NumPy
  right-hand side), in this process;
* ``simulate`` warm in this process, right after the baseline (the two
  interleaved: each warm run follows other work);
* ``simulate`` cold: a fresh interpreter flying the same 60 s, the compiled
  simulator cached (whole process, children included), twice: with Python's
  bytecode of ``quadland`` and ``quadland_symbolic`` cached (``__pycache__``,
  as any installed package has it) and compiled from source (their
  ``__pycache__`` removed and ``PYTHONDONTWRITEBYTECODE=1``, as in a checkout
  whose environment forbids writing it: every module compiled in every process);
* ``simulate`` cold with an empty cache (a fresh ``XDG_CACHE_HOME``: the
  simulator's C generated and compiled in the process; no bytecode cached either),
  every ``--empty-every`` rounds.

With ``--against TREE`` the three cold measurements are taken of another source
tree too (a ``git archive`` of an older commit: its ``quadland/`` and ``symbolic/``
put first on ``PYTHONPATH``, run from a folder outside this checkout), each right
after this tree's, so that before and after are paired run by run.

Run from the repository root::

    nice -n 10 python benchmarks/bench_cold.py --rounds 5
    nice -n 10 python benchmarks/bench_cold.py --rounds 5 --against /tmp/old
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_simulate as bs  # noqa: E402

import quadland  # noqa: E402


def _stats(xs, scale=1e3, digits=1):
    return (f"{statistics.median(xs) * scale:,.{digits}f} ({min(xs) * scale:,.{digits}f} to "
            f"{max(xs) * scale:,.{digits}f})")


ROOT = Path(__file__).resolve().parent.parent


def _drop_bytecode(root: Path = ROOT) -> None:
    """Remove the ``__pycache__`` folders of both packages' sources under ``root``."""
    for package in ("quadland", "symbolic"):
        for folder in (root / package).rglob("__pycache__"):
            shutil.rmtree(folder, ignore_errors=True)


class Tree:
    """A source tree the cold runs import ``quadland`` from, and how to run it.

    This checkout runs from its root (its packages installed in editable mode);
    another tree through ``PYTHONPATH`` (links named as the packages), from a
    folder outside this checkout, so that ``python -c`` does not find this
    checkout's ``quadland`` first.
    """

    def __init__(self, root: Path, tmp: Path | None = None):
        self.root, self.env, self.cwd = root, {}, ROOT
        if tmp is not None:
            path = tmp / "against"
            path.mkdir()
            (path / "quadland").symlink_to(root / "quadland")
            (path / "quadland_symbolic").symlink_to(root / "symbolic")
            self.env, self.cwd = {"PYTHONPATH": str(path)}, tmp

    def cpu(self, code: str, extra: dict | None = None, write: bool = False) -> float:
        """Whole-process CPU s (children included) of ``python -c code``; bytecode
        written only with ``write``."""
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env.update(self.env, **(extra or {}))
        if not write:
            env["PYTHONDONTWRITEBYTECODE"] = "1"
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-c", code], check=True, cwd=self.cwd, env=env,
                       stdout=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime

    def cold(self, code: str, empty: bool) -> dict[str, float]:
        """The cold runs of one round: modules compiled from source, bytecode cached, and
        (``empty``) an empty cache with no bytecode either."""
        out = {}
        _drop_bytecode(self.root)
        out["cold, cache filled, modules compiled from source"] = self.cpu(code)
        self.cpu(code, write=True)                 # untimed: the bytecode written
        out["cold, cache filled, bytecode cached"] = self.cpu(code)
        if empty:
            _drop_bytecode(self.root)               # nothing cached at all
            cache = tempfile.mkdtemp(prefix="quadland-bench-cache-")
            try:
                out["cold, empty cache"] = self.cpu(code, {"XDG_CACHE_HOME": cache})
            finally:
                shutil.rmtree(cache, ignore_errors=True)
        return out


def rounds(n: int, empty_every: int, against: Path | None = None) -> dict[str, list[float]]:
    """CPU s of each measurement, by name (`` (against)`` for the other tree), ``n``
    rounds interleaved."""
    sc = bs.scenario(bs.FULL)
    quadland.simulate(sc)                       # built or loaded: the cache is filled
    bs.baseline(sc)
    code = bs.cold_code(bs.FULL)
    out: dict[str, list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"": Tree(ROOT)}
        if against is not None:
            trees[" (against)"] = Tree(against.resolve(), Path(tmp))
            trees[" (against)"].cpu(code)        # its simulator built: the cache filled
        for k in range(n):
            c = time.process_time()
            bs.baseline(sc)
            out.setdefault("baseline", []).append(time.process_time() - c)
            c = time.process_time()
            quadland.simulate(sc)
            out.setdefault("warm, after the baseline", []).append(time.process_time() - c)
            for tag, tree in trees.items():
                cold = tree.cold(code, bool(empty_every) and k % empty_every == 0)
                for name, cpu in cold.items():
                    out.setdefault(name + tag, []).append(cpu)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--empty-every", type=int, default=2,
                    help="an empty-cache run every this many rounds (0: none)")
    ap.add_argument("--against", type=Path, help="another source tree, paired run by run")
    args = ap.parse_args(argv)
    out = rounds(args.rounds, args.empty_every, args.against)
    base = statistics.median(out["baseline"])
    print("## paper scenario, 60 s: CPU ms, median (min to max); baseline / this")
    for name, xs in out.items():
        print(f"- {name} ({len(xs)} runs): {_stats(xs)}; {base / statistics.median(xs):.2f}x")


if __name__ == "__main__":
    main()

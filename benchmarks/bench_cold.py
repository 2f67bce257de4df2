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

Run from the repository root::

    nice -n 10 python benchmarks/bench_cold.py --rounds 5
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_simulate as bs  # noqa: E402

import quadland  # noqa: E402


def _stats(xs, scale=1e3, digits=1):
    return (f"{statistics.median(xs) * scale:,.{digits}f} ({min(xs) * scale:,.{digits}f} to "
            f"{max(xs) * scale:,.{digits}f})")


ROOT = Path(__file__).resolve().parent.parent


def _drop_bytecode() -> None:
    """Remove the ``__pycache__`` folders of both packages' sources."""
    for package in ("quadland", "symbolic"):
        for folder in (ROOT / package).rglob("__pycache__"):
            shutil.rmtree(folder, ignore_errors=True)


def _write_bytecode(code: str) -> None:
    """Run ``code`` once with bytecode writing allowed (untimed)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, env=env,
                   stdout=subprocess.DEVNULL)


def _no_write():
    """The cold runs' environment: bytecode read where cached, never written."""
    return {"PYTHONDONTWRITEBYTECODE": "1"}, lambda: None


def rounds(n: int, empty_every: int) -> dict[str, list[float]]:
    """CPU s of each measurement, by name, ``n`` rounds interleaved."""
    sc = bs.scenario(bs.FULL)
    quadland.simulate(sc)                       # built or loaded: the cache is filled
    bs.baseline(sc)
    code = bs.cold_code(bs.FULL)
    out: dict[str, list[float]] = {}
    for k in range(n):
        c = time.process_time()
        bs.baseline(sc)
        out.setdefault("baseline", []).append(time.process_time() - c)
        c = time.process_time()
        quadland.simulate(sc)
        out.setdefault("warm, after the baseline", []).append(time.process_time() - c)
        _drop_bytecode()
        out.setdefault("cold, cache filled, modules compiled from source", []).append(
            bs.time_process(code, 1, _no_write).median)
        _write_bytecode(code)
        out.setdefault("cold, cache filled, bytecode cached", []).append(
            bs.time_process(code, 1, _no_write).median)
        if empty_every and k % empty_every == 0:
            _drop_bytecode()                    # nothing cached at all
            out.setdefault("cold, empty cache", []).append(
                bs.time_process(code, 1, bs.empty_cache).median)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--empty-every", type=int, default=2,
                    help="an empty-cache run every this many rounds (0: none)")
    args = ap.parse_args(argv)
    out = rounds(args.rounds, args.empty_every)
    base = statistics.median(out["baseline"])
    print("## paper scenario, 60 s: CPU ms, median (min to max); baseline / this")
    for name, xs in out.items():
        print(f"- {name} ({len(xs)} runs): {_stats(xs)}; {base / statistics.median(xs):.2f}x")


if __name__ == "__main__":
    main()

"""The test suite's wall and CPU time from an empty compiled-code cache: one process, and workers.

CI (``.ci/run``) runs ``pytest`` after a fresh install, so every simulator the
tests fly compiles on first use. This runs the suite (or the files given) the
way CI does, each time with a new, empty ``XDG_CACHE_HOME``: once with
``-n 0`` (one process, as before pytest-xdist) and once with ``-n WORKERS``
(the ``-n auto --dist loadfile`` of ``pyproject.toml``), alternating
``--repeats`` times, and prints for each the wall time, the CPU time of the
whole process tree (user + system, ``getrusage`` of the children: the
workers, the compilers and the tests' own subprocesses) and pytest's last
line (the counts). The machine's load average is printed before and after
each run: on a shared machine compare the CPU times and the paired ratio of
wall times, not the wall times across sessions.

Run from the repository root::

    python benchmarks/bench_suite.py                        # the whole suite, twice
    python benchmarks/bench_suite.py tests/test_landing.py  # some files
    python benchmarks/bench_suite.py --repeats 2 --workers 2
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time


def _load() -> str:
    with open("/proc/loadavg") as fh:
        return " ".join(fh.read().split()[:3])


def run_suite(workers: int, paths: list[str]) -> dict:
    """One run of ``pytest -n workers`` on a new empty cache: wall s, CPU s, last line."""
    with tempfile.TemporaryDirectory(prefix="bench-suite-") as cache:
        env = dict(os.environ, XDG_CACHE_HOME=cache)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load = _load()
        start = time.perf_counter()
        proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                               "-n", str(workers), *paths], env=env, capture_output=True,
                              text=True)
        wall = time.perf_counter() - start
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    lines = proc.stdout.strip().splitlines()
    return {"workers": workers, "wall": wall, "cpu": cpu, "load": f"{load} -> {_load()}",
            "result": lines[-1] if lines else proc.stderr[-300:]}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("paths", nargs="*", help="test files or folders (default: the suite)")
    ap.add_argument("--workers", type=int, default=2, help="pytest-xdist workers (default 2)")
    ap.add_argument("--repeats", type=int, default=1, help="pairs of runs (default 1)")
    args = ap.parse_args(argv)
    rows = []
    for _ in range(args.repeats):
        for workers in (0, args.workers):
            row = run_suite(workers, args.paths)
            rows.append(row)
            print(f"-n {row['workers']}: wall {row['wall']:7.1f} s  CPU {row['cpu']:7.1f} s  "
                  f"load {row['load']}  {row['result']}", flush=True)
    for one, many in zip(rows[::2], rows[1::2], strict=True):
        print(f"pair: wall -n {args.workers} / -n 0 = {many['wall'] / one['wall']:.2f}, "
              f"CPU {many['cpu'] / one['cpu']:.2f}")


if __name__ == "__main__":
    main()

"""Fixed costs and margins: the warm paper run against SciPy interleaved, BLAS threads, the
cache key, ``quadland margins``.

Measured in one run, CPU time (``time.process_time`` in this process; user +
system of the whole child process, from ``getrusage``, for commands), medians
(min to max), each pair side by side:

* the warm paper run (``bench_simulate.py``'s scenario, 60 s) alternating
  with the SciPy baseline in this process, and alone; and with every result
  kept, so that each run's rows land in fresh memory, once as quadland
  allocates them (small pages) and once with NumPy's huge-page advice (as
  before);
* ``quadland margins`` (paper and highway, ``--no-plots`` and with the
  figures) as the command line runs it (one BLAS thread), and with
  ``OPENBLAS_NUM_THREADS=2`` given (the machine's default);
* loading a cached compiled simulator: by its recipe key, and by generating
  its C to hash it (as before).

Run from the repository root::

    python benchmarks/bench_fixed_costs.py            # about 3 minutes
    python benchmarks/bench_fixed_costs.py --quick    # fewer repeats
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_simulate as bs  # noqa: E402

import quadland  # noqa: E402
from quadland.engine import runs  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def _cpu(fn):
    c = time.process_time()
    out = fn()
    return time.process_time() - c, out


def _stats(xs, scale=1e3):
    return (f"{statistics.median(xs) * scale:,.1f} ({min(xs) * scale:,.1f} to "
            f"{max(xs) * scale:,.1f})")


def warm_ratio(pairs: int, alone: int):
    """Baseline and warm ``simulate`` interleaved; warm alone; CPU s lists."""
    sc = bs.scenario(bs.FULL)
    quadland.simulate(sc)
    bs.baseline(sc)
    base, inter = [], []
    for _ in range(pairs):
        base.append(_cpu(lambda: bs.baseline(sc))[0])
        inter.append(_cpu(lambda: quadland.simulate(sc))[0])
    solo = [_cpu(lambda: quadland.simulate(sc))[0] for _ in range(alone)]
    return base, inter, solo


def fresh_memory(runs_: int):
    """Warm runs whose results are all kept (fresh memory each), in small pages and with
    NumPy's huge-page advice; CPU s lists."""
    sc = bs.scenario(bs.FULL)
    out = {}
    for label, switch in (("small pages (row_buffer)", runs._HUGEPAGE_SWITCH),
                          ("NumPy's huge-page advice", None)):
        saved, runs._HUGEPAGE_SWITCH = runs._HUGEPAGE_SWITCH, switch
        try:
            kept, times = [], []
            for _ in range(runs_):
                t, res = _cpu(lambda: quadland.simulate(sc))
                kept.append(res)
                times.append(t)
            out[label] = times
        finally:
            runs._HUGEPAGE_SWITCH = saved
        del kept
    return out


def process_cpu(args, env=None, repeat=3):
    """Whole-process CPU s (user + system, children included) of ``args``, each run."""
    out = []
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(args, cwd=ROOT, env=dict(os.environ, **(env or {})), check=False,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        out.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return out


def margins(repeat: int):
    """``quadland margins`` per scenario and figures, one BLAS thread and two, CPU s."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("paper", "highway"):
            for plots in ((), ("--no-plots",)):
                for threads in (None, "2"):
                    env = {} if threads is None else {"OPENBLAS_NUM_THREADS": threads}
                    args = [sys.executable, "-m", "quadland", "margins", "--scenario", name,
                            *plots, "--out", str(Path(tmp, f"{name}{len(out)}"))]
                    out[(name, bool(plots), threads)] = process_cpu(args, env, repeat)
    return out


def cache_key(repeat: int):
    """Loading the cached highway and paper simulators: by recipe, and generating the C."""
    from quadland.engine import compiled
    from quadland.engine.compiled import CompiledLoop
    from quadland.kinds.landing.simulate import landing_loop
    from quadland_symbolic.paper_loop import paper_loop

    out = {}
    for label, model, part in (("paper (l = 100), continuous", paper_loop(100), "continuous"),
                               ("highway (l = 10), sampled", landing_loop(10), "sampled")):
        CompiledLoop(model, part)                      # built and remembered
        by_recipe = [_cpu(lambda m=model, p=part: CompiledLoop(m, p))[0] for _ in range(repeat)]
        saved, compiled.recalled = compiled.recalled, lambda key: None   # as before
        try:
            generated = [_cpu(lambda m=model, p=part: CompiledLoop(m, p))[0]
                         for _ in range(repeat)]
        finally:
            compiled.recalled = saved
        out[label] = (by_recipe, generated)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats")
    args = ap.parse_args(argv)
    n = 3 if args.quick else 5

    base, inter, solo = warm_ratio(pairs=n, alone=n)
    print("## warm paper run (60 s) against the SciPy baseline, CPU ms, median (min to max)")
    print(f"- SciPy baseline, interleaved: {_stats(base)}")
    print(f"- `simulate` warm, interleaved with it: {_stats(inter)}: ratio "
          f"{statistics.median(base) / statistics.median(inter):.1f}x")
    print(f"- `simulate` warm, alone: {_stats(solo)}: ratio "
          f"{statistics.median(base) / statistics.median(solo):.1f}x")
    for label, times in fresh_memory(n + 2).items():
        print(f"- every result kept (fresh memory), {label}: {_stats(times)}: ratio "
              f"{statistics.median(base) / statistics.median(times):.1f}x")

    print("\n## loading a cached compiled simulator, CPU ms")
    for label, (rec, gen) in cache_key(n).items():
        print(f"- {label}: by recipe key {_stats(rec)}; generating the C for the key "
              f"{_stats(gen)}")

    print("\n## quadland margins, whole process, CPU s")
    for (name, no_plots, threads), cpu in margins(3).items():
        how = "one BLAS thread (the command line)" if threads is None else \
            "OPENBLAS_NUM_THREADS=2"
        print(f"- {name}{' --no-plots' if no_plots else ''}, {how}: {_stats(cpu, 1)}")


if __name__ == "__main__":
    main()

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
  figures), whole process; and ``margin_report`` in this process as the
  command line runs it, with SciPy's OpenBLAS on two threads (as before its
  limit was fixed) and with the modal form off (triangular solves on every
  grid, as before);
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


def _stats(xs, scale=1e3, digits=1):
    return (f"{statistics.median(xs) * scale:,.{digits}f} ({min(xs) * scale:,.{digits}f} to "
            f"{max(xs) * scale:,.{digits}f})")


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


def margins_commands(repeat: int):
    """``quadland margins`` per scenario, with and without the figures: whole process, CPU s."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("paper", "highway"):
            for figures in (False, True):
                args = [sys.executable, "-m", "quadland", "margins", "--scenario", name,
                        *(() if figures else ("--no-plots",)),
                        "--out", str(Path(tmp, f"{name}{len(out)}"))]
                out[(name, figures)] = process_cpu(args, repeat=repeat)
    return out


def margins_in_process(repeat: int):
    """``margin_report`` (the linearized loop given) in this process, CPU s: as the
    command line runs it (every BLAS one thread, the modal form on grids); with SciPy's
    OpenBLAS left at two threads (as when threadpoolctl ran before it loaded); with the
    triangular solves on grids too (the modal form off)."""
    import scipy.linalg  # noqa: F401
    from threadpoolctl import ThreadpoolController

    from quadland.analysis import modal, response
    from quadland.margins import margin_report

    blas = ThreadpoolController().select(user_api="blas")
    scipy_blas = [lib for lib in blas.lib_controllers if "scipy.libs" in lib.filepath]
    out = {}
    for name in ("paper", "highway"):
        sc = quadland.load_scenario(name)
        margin_report(sc)                                   # linearization's caches, imports
        for label, two, cond in (
                ("as the command line runs it", False, modal.MODAL_COND),
                ("SciPy's OpenBLAS on two threads (before)", True, None),
                ("triangular solves on grids (no modal form)", False, 0.0),
                ("both, as before", True, 0.0)):
            saved = modal.MODAL_COND
            times = []
            try:
                modal.MODAL_COND = saved if cond is None else cond
                with blas.limit(limits=1):
                    for lib in scipy_blas if two else ():
                        lib.set_num_threads(2)
                    for _ in range(repeat):
                        response._RECENT.clear()            # each report factors its loops
                        times.append(_cpu(lambda sc=sc: margin_report(sc))[0])
            finally:
                modal.MODAL_COND = saved
            out[(name, label)] = times
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
    for (name, figures), cpu in margins_commands(3).items():
        print(f"- {name}{' (with the figures)' if figures else ' --no-plots'}: {_stats(cpu, 1, 2)}")
    print("\n## margin_report in this process (linearization included), CPU s")
    for (name, label), cpu in margins_in_process(3).items():
        print(f"- {name}, {label}: {_stats(cpu, 1, 2)}")

if __name__ == "__main__":
    main()

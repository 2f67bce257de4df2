"""The margin figures alone: CPU of drawing and encoding them in a fresh process, paired.

Each scenario's review is computed once here and pickled; then, run by run and tree by
tree (alternating which goes first), a fresh process unpickles it, imports the figures as
the command line does (:func:`quadland.mpl_import.for_the_command_line`) and draws and
encodes the five figures (``margin_figures``, ``figure_png``, the collector paused as
``quadland margins`` pauses it), less the same process without the figures. Without the
review in the measured processes (1.3 to 2.5 s each), the load's scatter is smaller than
in ``bench_margins.py``'s whole commands. CPU time of the children (``getrusage``),
medians (min to max), and the run-by-run ratio of ``this`` to ``against``.

With ``--glyph-cache``, in this process instead: the five figures of highway drawn and
encoded with the kept glyph bitmaps (``quadland.plots.glyph_cache``, emptied before each
draw) and with matplotlib's own glyph loop, the two alternating pair by pair; CPU s
(``time.process_time``), medians (min to max) and the pair by pair ratio.

Run from the repository root::

    python benchmarks/bench_margin_figures.py --runs 9 --against /tmp/old
    python benchmarks/bench_margin_figures.py --glyph-cache --runs 15
    python benchmarks/bench_margin_figures.py --callgrind --runs 9 --against /tmp/old

With ``--property-tables``: importing the figures' modules as the command line does
(:func:`quadland.mpl_import.for_the_command_line`, after NumPy, SciPy and Pillow), in a
fresh process each time, with the artists' property tables left out of matplotlib's
docstrings (matplotlib's private loader of them, ``_docstring._ArtistKwdocLoader``,
patched in the measured process only: the eighteenth session's review kept that patch out
of quadland, docs/performance.md) and with them written, alternating; CPU s of the import
(``time.process_time``).

With ``--callgrind``: each tree's figures' instructions (callgrind's count of the
process with the figures less the one without, the stored texts read back), and the
instructions per second of the figures' process on this host (its count over its CPU
time in ``--runs`` runs without valgrind: the fastest run, the least disturbed by the
load, and the median), by which the instructions are converted to seconds.
"""

from __future__ import annotations

import argparse
import os
import pickle
import resource
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_margins import _stats, _tree_env

#: What each measured process runs: argv[1] the pickled review, argv[2] "figures" or not,
#: argv[3] the stored texts' file (``quadland.plots.text_store``; a tree without it draws
#: its texts as it does).
CHILD = """
import contextlib, os, pickle, sys
from quadland import mpl_import
mpl_import.for_the_command_line()
import scipy.linalg
import quadland.engine.build    # as the command's review has imported it (and CasADi)
from threadpoolctl import threadpool_limits
with open(sys.argv[1], "rb") as f:
    report = pickle.load(f)
if sys.argv[2] == "figures":
    with threadpool_limits(1):
        from quadland.output import figure_png
        from quadland.plots import margin_figures
        from quadland.plots.gc_pause import collection_paused
        try:
            from quadland.plots.text_store import texts_kept
        except ImportError:
            texts_kept = lambda path: contextlib.nullcontext()
        with collection_paused(), texts_kept(sys.argv[3]):
            pngs = {k: figure_png(v) for k, v in margin_figures(report).items()}
os._exit(0)
"""


#: What each ``--property-tables`` process runs: argv[1] "skipped" or "written".
IMPORT_CHILD = """
import sys, time
import numpy, scipy.linalg, PIL.Image
from matplotlib import _docstring
from quadland import mpl_import
mpl_import.for_the_command_line()
loader = _docstring._ArtistKwdocLoader
missing = loader.__missing__
if sys.argv[1] == "skipped":      # each ':kwdoc' table an empty text, not remembered
    loader.__missing__ = lambda self, key: "" if key.endswith(":kwdoc") else missing(self, key)
start = time.process_time()
import quadland.plots
from quadland.plots import margin_figures
print(time.process_time() - start)
loader.__missing__ = missing
"""


def property_tables(runs: int) -> dict:
    """CPU s of importing the figures' modules in fresh processes, the property tables
    skipped and written, by which (alternating which goes first)."""
    out: dict = {"skipped": [], "written": []}
    order = list(out)
    for k in range(runs):
        for which in order if k % 2 == 0 else order[::-1]:
            proc = subprocess.run([sys.executable, "-c", IMPORT_CHILD, which], check=True,
                                  capture_output=True, text=True)
            out[which].append(float(proc.stdout.split()[-1]))
    return out


def _review(name: str, path: Path) -> None:
    import scipy.linalg  # noqa: F401  (threadpoolctl limits the BLAS loaded)
    from threadpoolctl import threadpool_limits

    from quadland import load_scenario
    from quadland.margins import margin_report

    with threadpool_limits(1):
        report = margin_report(load_scenario(name))
    path.write_bytes(pickle.dumps(report))


def _cpu(args, env) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, env=env, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def _setup(tmp: Path, against: Path | None, scenarios) -> tuple[Path, dict]:
    """In ``tmp``: the child script, each scenario's review pickled, and the trees' env
    (this one's, and ``against``'s exported tree when given)."""
    child = Path(tmp, "child.py")
    child.write_text(CHILD)
    trees = {"this": dict(os.environ)}
    if against is not None:
        trees["against"] = _tree_env(against.resolve(), tmp)
    for name in scenarios:
        _review(name, Path(tmp, f"{name}.pkl"))
    return child, trees


def figures(runs: int, against: Path | None, scenarios, texts: str = "stored") -> dict:
    """CPU s of the five figures in each run, by (scenario, tree); ``texts`` "stored": the
    stored texts' file written by the first run (not counted) and read by the others,
    "cold": none (each run lays out and renders every text, and writes the file)."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        child, trees = _setup(Path(tmp), against, scenarios)
        for k in range(runs + (texts == "stored")):
            for name in scenarios:
                order = list(trees.items())
                for tree, env in order if k % 2 == 0 else order[::-1]:
                    store = Path(tmp, f"{name}-{tree}.texts")
                    if texts == "cold":
                        store.unlink(missing_ok=True)
                    args = [sys.executable, str(child), str(Path(tmp, f"{name}.pkl"))]
                    base = _cpu([*args, "none", str(store)], env)
                    cpu = _cpu([*args, "figures", str(store)], env) - base
                    if k or texts == "cold":
                        out.setdefault((name, tree), []).append(cpu)
    return out


def _instructions(args, env, out: Path) -> int:
    """Instructions the process ``args`` executes (callgrind's ``Ir``, children not traced)."""
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *args],
                   env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for line in out.read_text().splitlines():
        if line.startswith(("summary:", "totals:")):
            return int(line.split()[1])
    raise RuntimeError(f"no instruction count in {out}")


def instructions(against: Path | None, scenarios, native_runs: int) -> dict:
    """Per scenario and tree: the figures' instructions (the figures' process less the one
    without, under callgrind, the stored texts written by a run before), the figures'
    process's own instructions and its CPU s in ``native_runs`` runs without valgrind
    (alternating the trees), for instructions per second on this host."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        child, trees = _setup(Path(tmp), against, scenarios)
        for name in scenarios:
            for tree, env in trees.items():
                args = [sys.executable, str(child), str(Path(tmp, f"{name}.pkl"))]
                store = str(Path(tmp, f"{name}-{tree}.texts"))
                _cpu([*args, "figures", store], env)            # the stored texts written
                counts = {mode: _instructions([*args, mode, store], env,
                                              Path(tmp, f"{name}-{tree}-{mode}.out"))
                          for mode in ("none", "figures")}
                out[name, tree] = {"figures": counts["figures"] - counts["none"],
                                   "process": counts["figures"], "cpu": []}
            for _ in range(native_runs):
                for tree, env in trees.items():
                    args = [sys.executable, str(child), str(Path(tmp, f"{name}.pkl"))]
                    out[name, tree]["cpu"].append(
                        _cpu([*args, "figures", str(Path(tmp, f"{name}-{tree}.texts"))], env))
    return out


def _print_instructions(measured: dict) -> None:
    print("## the five margin figures' instructions (callgrind), stored texts read back")
    print("| scenario | tree | figures, G instr. | figures' process, G instr. | its CPU s, "
          "min (median) | G instr./s at the min (median) | figures' s at that rate |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for (name, tree), m in measured.items():
        cpu_min, cpu_med = min(m["cpu"]), sorted(m["cpu"])[len(m["cpu"]) // 2]
        ips, ips_med = m["process"] / cpu_min, m["process"] / cpu_med
        print(f"| {name} | {tree} | {m['figures'] / 1e9:.3f} | {m['process'] / 1e9:.3f} | "
              f"{cpu_min:.2f} ({cpu_med:.2f}) | {ips / 1e9:.2f} ({ips_med / 1e9:.2f}) | "
              f"{m['figures'] / ips:.3f} ({m['figures'] / ips_med:.3f}) |")


def _matplotlibs_glyphs(renderer, gc, x, y, angle, items, size, flags):
    """A text's glyphs (``glyph_cache.Glyph``, with their fonts) drawn by matplotlib's Agg
    loop (what ``draw_glyphs`` replaces)."""
    renderer._draw_text_glyphs_and_boxes(
        gc, x, y, angle,
        ((item.font, size, item.glyph_index, 0, 1, item.x, item.y) for item in items), [])
    return True


def glyph_cache_pairs(runs: int, name: str = "highway") -> dict:
    """CPU s of drawing and encoding ``name``'s five figures in this process, with the kept
    glyph bitmaps (emptied before each draw) and with matplotlib's glyph loop, by which."""
    import time

    from threadpoolctl import threadpool_limits

    from quadland import load_scenario
    from quadland.margins import margin_report
    from quadland.output import figure_png
    from quadland.plots import glyph_cache, margin_figures, text_cache
    from quadland.plots.gc_pause import collection_paused

    with threadpool_limits(1):
        report = margin_report(load_scenario(name))
    kept = text_cache.draw_glyphs
    out: dict = {"kept": [], "matplotlib": []}
    order = [("kept", kept), ("matplotlib", _matplotlibs_glyphs)]
    try:
        for k in range(runs + 1):                       # the first pair warms both up
            for which, draw in order if k % 2 == 0 else order[::-1]:
                text_cache.draw_glyphs = draw
                glyph_cache._BITMAPS.clear()
                start = time.process_time()
                with threadpool_limits(1), collection_paused():
                    pngs = {key: figure_png(fig) for key, fig in margin_figures(report).items()}
                if k:
                    out[which].append(time.process_time() - start)
                del pngs
    finally:
        text_cache.draw_glyphs = kept
    return out


def _report_pairs(heading: str, what: str, measured: dict, ratio: tuple[str, str]) -> None:
    """Each arm's CPU seconds, then the ratio of the two arms named in ``ratio``, pair by pair."""
    print(f"## {heading}, CPU s, median (min to max)")
    for which, cpu in measured.items():
        print(f"- {what} {which}: {_stats(cpu)}")
    num, den = ratio
    ratios = [a / b for a, b in zip(measured[num], measured[den], strict=True)]
    print(f"- {num} / {den}, pair by pair: {_stats(ratios)}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="runs of each")
    ap.add_argument("--against", type=Path, help="another source tree, paired run by run")
    ap.add_argument("--scenarios", nargs="+", default=("paper", "highway"))
    ap.add_argument("--texts", choices=("stored", "cold"), default="stored",
                    help="the stored texts read back (a first run writes them) or none")
    ap.add_argument("--glyph-cache", action="store_true",
                    help="in this process: highway's figures with and without the kept glyphs")
    ap.add_argument("--callgrind", action="store_true",
                    help="instructions under callgrind, converted by this host's rate")
    ap.add_argument("--property-tables", action="store_true",
                    help="the figures' import with and without matplotlib's property tables")
    args = ap.parse_args(argv)
    if args.property_tables:
        _report_pairs("importing the figures' modules in a fresh process", "property tables",
                      property_tables(args.runs), ("skipped", "written"))
        return
    if args.callgrind:
        _print_instructions(instructions(args.against, args.scenarios, args.runs))
        return
    if args.glyph_cache:
        _report_pairs("highway's five figures in this process", "glyphs",
                      glyph_cache_pairs(args.runs), ("kept", "matplotlib"))
        return
    measured = figures(args.runs, args.against, args.scenarios, args.texts)
    print(f"## the five margin figures in a fresh process, CPU s, median (min to max), "
          f"texts {args.texts}")
    for (name, tree), cpu in measured.items():
        print(f"- {name}, {tree}: {_stats(cpu)}")
    if args.against is not None:
        for name in args.scenarios:
            ratios = [a / b for a, b in zip(measured[name, "this"], measured[name, "against"],
                                            strict=True)]
            print(f"- {name}, this / against, run by run: {_stats(ratios)}")


if __name__ == "__main__":
    main()

"""``quadland margins``: whole-process CPU per scenario, and where a review's time goes.

Measured in one run, CPU time (user + system of each child process from
``getrusage``; ``time.process_time`` in this process), medians (min to max):

* ``quadland margins --scenario S --no-plots`` and with the figures, for
  ``paper``, ``highway`` and ``ship``, the runs of every command interleaved;
  with ``--against TREE`` each run paired with the same command of another
  source tree (a ``git archive`` of an older commit: its ``quadland/`` and
  ``symbolic/`` are put first on ``PYTHONPATH``);
* in this process, one ``margin_report`` of ``highway`` cut into its stages:
  the operating point, each section's linearization and analysis, the filter
  in the loop's models (builders included: a process builds them once).

With ``--callgrind``, instead: each command's instructions (valgrind's callgrind, the
whole process; a first run of each, not counted, writes what the command keeps between
runs), this tree's and ``--against``'s: a count the machine's load does not change, to
carry a quiet host's CPU seconds measured on one tree over to another (the figures'
instructions less ``--no-plots``'s, in the ratio of the two trees').

Run from the repository root::

    python benchmarks/bench_margins.py                       # about 2 minutes
    python benchmarks/bench_margins.py --runs 5 --against /tmp/old
    python benchmarks/bench_margins.py --scenarios paper highway --no-stages
    python benchmarks/bench_margins.py --callgrind --against /tmp/old --scenarios highway
    python benchmarks/bench_margins.py --bytecode --runs 5 --scenarios highway --no-stages

With ``--bytecode``: this tree as above (where ``PYTHONDONTWRITEBYTECODE`` is set, as on
the project's machines, each process compiles quadland's modules from their source) against
the same tree reading its modules' compiled bytecode, as an installed package does.
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

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("paper", "highway", "ship")


def _stats(v) -> str:
    return f"{statistics.median(v):.2f} ({min(v):.2f} to {max(v):.2f})"


def _tree_env(tree: Path, tmp: Path) -> dict:
    """An environment that imports ``quadland`` and ``quadland_symbolic`` from ``tree``."""
    path = tmp / "against"
    path.mkdir()
    (path / "quadland").symlink_to(tree / "quadland")
    (path / "quadland_symbolic").symlink_to(tree / "symbolic")
    return dict(os.environ, PYTHONPATH=str(path))


def _cpu(args, env, cwd) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(args, cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime


def _bytecode_env(env: dict, folder: Path) -> dict:
    """``env`` reading (and writing) the modules' compiled bytecode under ``folder``, as an
    installed package's ``__pycache__`` holds it, whatever ``PYTHONDONTWRITEBYTECODE``."""
    env = dict(env, PYTHONPYCACHEPREFIX=str(folder))
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def commands(runs: int, against: Path | None, scenarios=SCENARIOS,
             bytecode: bool = False) -> dict:
    """Whole-process CPU s of each command, by (scenario, figures, tree); ``bytecode``:
    the trees ``"this"`` (its modules compiled from source in each process where Python
    writes no bytecode, ``PYTHONDONTWRITEBYTECODE``) and ``"bytecode"`` (the same tree, its
    compiled modules read from a folder a first round, not counted, wrote)."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this": dict(os.environ)}
        if bytecode:
            trees["bytecode"] = _bytecode_env(os.environ, Path(tmp, "pycache"))
        elif against is not None:
            trees["against"] = _tree_env(against.resolve(), Path(tmp))
        for k in range(runs + bytecode):
            for name in scenarios:
                for figures in (False, True):
                    for tree, env in trees.items():
                        folder = Path(tmp, f"{name}-{figures}-{tree}-{k}")
                        args = [sys.executable, "-m", "quadland", "margins", "--scenario", name,
                                "--out", str(folder), *(() if figures else ("--no-plots",))]
                        cpu = _cpu(args, env, tmp)
                        if k or not bytecode:
                            out.setdefault((name, figures, tree), []).append(cpu)
    return out


def _instructions(args, env, cwd, out: Path) -> int:
    """Instructions the process ``args`` executes (callgrind's total, children not traced)."""
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", *args],
                   cwd=cwd, env=env, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    for line in out.read_text().splitlines():
        if line.startswith(("summary:", "totals:")):
            return int(line.split()[1])
    raise RuntimeError(f"no instruction count in {out}")


def instructions(against: Path | None, scenarios=SCENARIOS) -> dict:
    """Instructions of each command, by (scenario, figures, tree), each after a first run
    of it (not counted)."""
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this": dict(os.environ)}
        if against is not None:
            trees["against"] = _tree_env(against.resolve(), Path(tmp))
        for name in scenarios:
            for figures in (False, True):
                for tree, env in trees.items():
                    args = [sys.executable, "-m", "quadland", "margins", "--scenario", name,
                            *(() if figures else ("--no-plots",))]
                    _cpu([*args, "--out", str(Path(tmp, f"{name}-{figures}-{tree}-w"))],
                         env, tmp)
                    folder = str(Path(tmp, f"{name}-{figures}-{tree}"))
                    out[name, figures, tree] = _instructions(
                        [*args, "--out", folder], env, tmp,
                        Path(tmp, f"{name}-{figures}-{tree}.callgrind"))
    return out


def _print_instructions(measured: dict) -> None:
    print("## quadland margins, whole process, instructions (callgrind), G")
    print("| scenario | tree | `--no-plots` | figures | the figures' instructions |")
    print("|---|---|---:|---:|---:|")
    for name, tree in dict.fromkeys((n, t) for n, _, t in measured):
        bare, full = measured[name, False, tree], measured[name, True, tree]
        print(f"| {name} | {tree} | {bare / 1e9:.3f} | {full / 1e9:.3f} | "
              f"{(full - bare) / 1e9:.3f} |")
    for name in dict.fromkeys(n for n, _, _ in measured):
        if (name, True, "against") in measured:
            fig = [measured[name, True, t] - measured[name, False, t]
                   for t in ("this", "against")]
            bare = [measured[name, False, t] for t in ("this", "against")]
            print(f"- {name}, this / against: --no-plots {bare[0] / bare[1]:.3f}, "
                  f"the figures {fig[0] / fig[1]:.3f}")


def stages(name: str = "highway") -> dict:
    """CPU s of each stage of one ``margin_report`` in a fresh process's first call."""
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits

    import quadland
    from quadland.kinds import kind_of
    from quadland.margins.report import Requirement
    from quadland.margins.review import _filtered_section, _loop_report, _with_extras

    out = {}

    def timed(label, f, *args):
        t = time.process_time()
        value = f(*args)
        out[label] = time.process_time() - t
        return value

    with threadpool_limits(1):
        sc, req = quadland.load_scenario(name), Requirement()
        kind = kind_of(sc)
        delay, rate = kind.computation_delay(sc), float(sc.data["controller"]["rate_hz"])
        point = timed("operating point", kind.operating_point, sc, None)
        for label, make in (("continuous", lambda: kind.linear_models(sc, point)),
                            ("sampled", lambda: kind.sampled_models(sc, point, rate, delay))):
            models = timed(f"{label}: models", make)
            loop = models.realizations["loop_input"]
            section, _ = timed(f"{label}: margins, disk margins, poles", _loop_report, loop,
                               models.loop_names, req, rate, delay)
            timed(f"{label}: sensitivity peaks, sensor delay margins", _with_extras, section,
                  models, sc, req)
        timed("filter in the loop: models and analysis", _filtered_section, kind, sc, point,
              rate, delay, req)
    return out


def _costs(measured: dict, name: str, tree: str) -> list[float]:
    """The figures' CPU s in each run: the command with them less without them."""
    return [a - b for a, b in zip(measured[name, True, tree], measured[name, False, tree],
                                  strict=True)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3, help="runs of each command")
    ap.add_argument("--against", type=Path, help="another source tree, paired run by run")
    ap.add_argument("--scenarios", nargs="+", default=SCENARIOS, help="scenarios measured")
    ap.add_argument("--no-stages", action="store_true", help="skip the stages of highway's review")
    ap.add_argument("--bytecode", action="store_true",
                    help="this tree with its compiled bytecode read back against without")
    ap.add_argument("--callgrind", action="store_true",
                    help="each command's instructions under callgrind instead of CPU time")
    args = ap.parse_args(argv)
    if args.callgrind:
        _print_instructions(instructions(args.against, args.scenarios))
        return
    print("## quadland margins, whole process, CPU s, median (min to max)")
    measured = commands(args.runs, args.against, args.scenarios, args.bytecode)
    for (name, figures, tree), cpu in measured.items():
        print(f"- {name}{' (figures)' if figures else ' --no-plots'}, {tree}: {_stats(cpu)}")
    print("\n## the figures' cost, run by run (figures less --no-plots of the same run), CPU s")
    for name, tree in dict.fromkeys((n, t) for n, _, t in measured):
        print(f"- {name}, {tree}: {_stats(_costs(measured, name, tree))}")
    other = "bytecode" if args.bytecode else "against" if args.against is not None else None
    if other is not None:
        for name in args.scenarios:
            ratios = [a / b for a, b in zip(_costs(measured, name, "this"),
                                            _costs(measured, name, other), strict=True)]
            print(f"- {name}, this / {other}, run by run: {_stats(ratios)}")
            bare = [a / b for a, b in zip(measured[name, False, "this"],
                                          measured[name, False, other], strict=True)]
            print(f"- {name} --no-plots, this / {other}, run by run: {_stats(bare)}")
    if args.no_stages:
        return
    print("\n## margin_report of highway in this process, first call, CPU s")
    for label, cpu in stages().items():
        print(f"- {label}: {cpu:.3f}")


if __name__ == "__main__":
    main()

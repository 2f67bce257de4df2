"""Speed, accuracy and memory of ``quadland.simulate`` against SciPy.

The comparison is with what a user would write instead: SciPy
``solve_ivp(method="RK45", rtol=1e-6, atol=1e-8, max_step=0.01)`` on a
plain NumPy right-hand side of the same closed loop, with the disturbance
looked up per time (held piecewise constant over its 10 ms samples). The
right-hand side is ``numpy_rhs`` of ``tests/numpy_closed_loop.py``, derived
again from the paper independently of ``symbolic/`` (and checked against
``closed_loop_function`` here and by ``tests/test_numpy_closed_loop.py``).

Scenario: the paper's, 60 s, noise off, nominal model on. Measured in one
run, CPU time (``time.process_time``, or the whole process's from
``getrusage`` for fresh interpreters), medians over several runs:

* the baseline; ``simulate`` warm; cold in a fresh interpreter with the
  compiled simulator already cached, and with an empty cache (a fresh
  ``XDG_CACHE_HOME``: the build is included); the sampled-data loop at
  500 Hz with ``controller.backend="casadi"`` and ``"c"``;
* accuracy of the baseline and of ``simulate`` against a reference,
  ``solve_ivp`` DOP853 at rtol = atol = 1e-12 restarted at every switch of
  the held disturbance (itself checked against ``simulate`` with 8 RK4
  steps per hold interval, and against quadland's cvodes at 1e-12);
* memory in a fresh interpreter: tracemalloc peak of a long run per
  simulated second, the growth of the peak resident set, and what stays
  allocated once the result is dropped;
* where a warm call's time goes (the compiled integration, the outputs).

Run from the repository root::

    python benchmarks/bench_simulate.py            # full run, about 2 minutes
    python benchmarks/bench_simulate.py --quick    # smoke run, shorter, fewer repeats
    python benchmarks/bench_simulate.py --write    # full run, rewrite the doc's section

``--write`` rewrites the ``## Simulation`` section of ``docs/performance.md``
up to its ``### Earlier figures`` subsection, which is kept as it is.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import importlib.util
import itertools
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np
import scipy
from scipy.integrate import solve_ivp

import quadland
from quadland.engine.build import find_compiler
from quadland.engine.disturbance import disturbance_samples
from quadland.kinds.paper.simulate import (
    paper_envelope,
    paper_loop_part,
    run_clocks,
    time_grid,
)
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import (
    closed_loop_function,
    closed_loop_params,
    closed_loop_state,
)

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "performance.md"
SECTION = "## Simulation"
KEPT = "### Earlier figures"

SCENARIO = ["disturbance.noise=false", "controller.nominal_model=true"]
BASELINE = dict(method="RK45", rtol=1e-6, atol=1e-8, max_step=0.01)
REFERENCE = dict(method="DOP853", rtol=1e-12, atol=1e-12)
CHECKS = {"`simulate` with 8 RK4 steps per hold interval": ["simulation.rk_steps_per_interval=8"],
          "quadland's cvodes, reltol = abstol = 1e-12": [
              'simulation.integrator="cvodes"', "simulation.reltol=1e-12",
              "simulation.abstol=1e-12"]}
SAMPLED = ["controller.rate_hz=500"]
BACKENDS = ("casadi", "c")

#: Targets: baseline / quadland at least this (warm, cold cached, cold empty
#: cache: strictly more), sampled / continuous at most this, peak memory per
#: simulated second at most this (MiB/s).
TARGET_WARM, AIM_WARM, TARGET_COLD, TARGET_EMPTY = 50.0, 100.0, 10.0, 1.0
TARGET_SAMPLED, TARGET_MEMORY = 3.0, 1.0
MIB = 2.0**20


@dataclasses.dataclass(frozen=True)
class Plan:
    """Durations (s of flight) and repeats of one run of the benchmark."""

    duration: float
    memory_duration: float
    leak_duration: float
    baseline_runs: int
    warm_runs: int
    cold_runs: int
    empty_runs: int
    sampled_runs: int
    c_backend_runs: int


FULL = Plan(60.0, 600.0, 120.0, 5, 15, 7, 3, 7, 3)
QUICK = Plan(10.0, 60.0, 20.0, 1, 5, 2, 1, 3, 1)


def _load_oracle():
    """``tests/numpy_closed_loop.py``, loaded by file path."""
    path = ROOT / "tests" / "numpy_closed_loop.py"
    spec = importlib.util.spec_from_file_location("numpy_closed_loop", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


oracle = _load_oracle()


def scenario(plan, *extra):
    """The benchmark's paper scenario with ``extra`` overrides."""
    return quadland.load_scenario(
        "paper", [f"simulation.duration={plan.duration:g}", *SCENARIO, *extra])


# --- the baseline -------------------------------------------------------------

def baseline_rhs(sc):
    """``f(t, x)``: the NumPy right-hand side with the disturbance held at time t."""
    mv = model_values(sc)
    _, t_dist, _ = time_grid(sc)
    w_dist = disturbance_samples(sc, t_dist)
    rhs = oracle.numpy_rhs(mv.p, mv.l)
    last = w_dist.shape[1] - 1

    def f(t, x):
        k = np.searchsorted(t_dist, t + 1e-12, side="right") - 1   # held sample at t
        return rhs(t, x, w_dist[:, min(max(k, 0), last)])

    return f


def baseline(sc):
    """What a user would write: one ``solve_ivp`` call, disturbance looked up per time.

    Returns the ``solve_ivp`` solution at ``simulate``'s output times.
    """
    t_out = time_grid(sc)[0]
    sol = solve_ivp(baseline_rhs(sc), (t_out[0], t_out[-1]), model_values(sc).x0, t_eval=t_out,
                    **BASELINE)
    if not sol.success:
        raise SystemExit(f"baseline solve_ivp failed: {sol.message}")
    return sol


def reference(sc):
    """States at the output times, ``(n, nx)``: ``solve_ivp`` with ``REFERENCE``
    restarted at every point of the merged grid, so that no step straddles a
    switch of the held disturbance."""
    mv = model_values(sc)
    t_out, t_dist, t_all = time_grid(sc)
    w = _held(t_dist, disturbance_samples(sc, t_dist), t_all[:-1])
    rhs = oracle.numpy_rhs(mv.p, mv.l)
    X = [mv.x0]
    for k, (t0, t1) in enumerate(itertools.pairwise(t_all)):
        X.append(solve_ivp(rhs, (t0, t1), X[-1], args=(w[k],), **REFERENCE).y[:, -1])
    keep = np.isin(np.round(t_all, 12), np.round(t_out, 12))
    return np.array(X)[keep]


def rhs_mismatch(mv, n=20, seed=0):
    """Largest ``|f_numpy - f_casadi| / (1 + |f_casadi|)`` over random states."""
    f_ca = closed_loop_function(mv.l)
    rhs = oracle.numpy_rhs(mv.p, mv.l)
    X, W = oracle.random_states(mv, n, seed)
    worst = 0.0
    for k in range(n):
        ref = np.asarray(f_ca(X[:, k], W[:, k], mv.p)).ravel()
        worst = max(worst, float(np.max(np.abs(rhs(0.0, X[:, k], W[:, k]) - ref)
                                        / (1.0 + np.abs(ref)))))
    return worst


# --- accuracy -----------------------------------------------------------------

def error_signals(X, mv):
    """``z_e`` (m) and the attitude errors ``phi_e, theta_e, psi_e`` (rad, eq. 5)
    from closed-loop states ``X`` of shape ``(n, nx)``."""
    S, P = closed_loop_state(mv.l), closed_loop_params(mv.l)
    z2 = mv.p[P.slice("p_veh.z2")][0]
    return {"z_e": X[:, S.index("z1")] - z2, "phi_e": X[:, S.index("phi1")],
            "theta_e": X[:, S.index("theta1")],
            "psi_e": X[:, S.index("psi1")] - X[:, S.index("psi2")]}


def max_errors(X, X_ref, mv):
    """``(max |z_e error|, max |attitude error| over the three angles)``."""
    e, r = error_signals(X, mv), error_signals(X_ref, mv)
    return (float(np.max(np.abs(e["z_e"] - r["z_e"]))),
            max(float(np.max(np.abs(e[n] - r[n]))) for n in ("phi_e", "theta_e", "psi_e")))


# --- timing -------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Timing:
    """Median, min and max of several runs, s; ``wall`` is the median wall time."""

    median: float
    low: float
    high: float
    runs: int
    wall: float

    @classmethod
    def of(cls, cpu, wall):
        return cls(statistics.median(cpu), min(cpu), max(cpu), len(cpu),
                   statistics.median(wall))


def time_call(fn, runs):
    """CPU time (``process_time``) of ``fn()`` over ``runs`` calls."""
    cpu, wall = [], []
    for _ in range(runs):
        c, w = time.process_time(), time.perf_counter()
        fn()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    return Timing.of(cpu, wall)


def time_process(code, runs, env_for_run=lambda: None):
    """Whole-process CPU time (user + sys, children included) of ``python -c code``.

    ``env_for_run()`` gives each run's extra environment and a clean-up, or None.
    """
    cpu, wall = [], []
    for _ in range(runs):
        extra = env_for_run()
        env = dict(os.environ, **(extra[0] if extra else {}))
        try:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            w = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT, env=env,
                           stdout=subprocess.DEVNULL)
            wall.append(time.perf_counter() - w)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
        finally:
            if extra:
                extra[1]()
        cpu.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return Timing.of(cpu, wall)


def empty_cache():
    """A fresh ``XDG_CACHE_HOME`` for one run, and its removal."""
    path = tempfile.mkdtemp(prefix="quadland-bench-cache-")
    return {"XDG_CACHE_HOME": path}, lambda: shutil.rmtree(path, ignore_errors=True)


def cold_code(plan):
    overrides = [f"simulation.duration={plan.duration:g}", *SCENARIO]
    return ("import quadland; "
            f"quadland.simulate(quadland.load_scenario('paper', {overrides!r}))")


def _held(t_switch, values, times):
    idx = np.searchsorted(t_switch, np.asarray(times) + 1e-12, side="right") - 1
    return np.ascontiguousarray(values[:, np.clip(idx, 0, values.shape[1] - 1)].T)


def breakdown(sc, runs):
    """Time of the compiled integration and of the outputs alone, as ``simulate``
    calls them; and the number of right-hand side evaluations."""
    mv = model_values(sc)
    clocks = run_clocks(sc)
    w_dist = disturbance_samples(sc, clocks[1].times())
    substeps = sc.data["simulation"]["rk_steps_per_interval"]
    loop = paper_loop_part(mv.l, "continuous")
    bounds = paper_envelope(sc, mv).bounds
    run = loop.integrate(mv.x0, clocks, w_dist.T, substeps, mv.p, bounds)
    assert run.status == 0 and np.array_equal(run.X, quadland.simulate(sc).states)
    W_out = np.ascontiguousarray(w_dist[:, run.w_index].T)
    return dict(integrate=time_call(lambda: loop.integrate(mv.x0, clocks, w_dist.T, substeps,
                                                           mv.p, bounds), runs),
                outputs=time_call(lambda: loop.outputs(run.X, W_out, run.times, mv.p), runs),
                evaluations=4 * substeps * (len(time_grid(sc)[2]) - 1))


# --- memory (in a fresh interpreter) --------------------------------------------

_MEMORY = """
import gc, json, resource, sys, tracemalloc
import numpy as np
import quadland

def scenario(T):
    return quadland.load_scenario("paper", [f"simulation.duration={T:g}", *OVERRIDES])

def rss():
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) * 1024

def maxrss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024

def owned(res):
    roots = {}
    for a in (res.states, *res.columns.values()):
        while isinstance(a.base, np.ndarray):
            a = a.base
        roots[id(a)] = a.nbytes
    return sum(roots.values())

T_LONG, T_LEAK = float(sys.argv[1]), float(sys.argv[2])
long, leak = scenario(T_LONG), scenario(T_LEAK)
quadland.simulate(scenario(1.0))                       # library loaded, caches filled
gc.collect()
out = dict(rss0=rss(), maxrss0=maxrss())
res = quadland.simulate(long)
out.update(maxrss1=maxrss(), rss_with=rss(), result_long=owned(res))
del res
gc.collect()
out["rss_after"] = rss()

tracemalloc.start()
res = quadland.simulate(long)
out["peak_long"] = tracemalloc.get_traced_memory()[1]
del res
gc.collect()
tracemalloc.reset_peak()
before = tracemalloc.get_traced_memory()[0]
res = quadland.simulate(leak)
out.update(with_result=tracemalloc.get_traced_memory()[0] - before, result_leak=owned(res))
del res
gc.collect()
out["after_drop"] = tracemalloc.get_traced_memory()[0] - before
print(json.dumps(out))
"""


def memory(plan):
    """Memory figures of ``simulate`` from a fresh interpreter, bytes."""
    code = _MEMORY.replace("OVERRIDES", repr(SCENARIO))
    out = subprocess.run([sys.executable, "-c", code, str(plan.memory_duration),
                          str(plan.leak_duration)], check=True, cwd=ROOT, capture_output=True,
                         text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


# --- report -------------------------------------------------------------------

def machine():
    """CPU model, core count, compiler and library versions, date."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cc = find_compiler()
    cc_version = subprocess.run([cc, "--version"], capture_output=True, text=True,
                                check=True).stdout.splitlines()[0]
    git = subprocess.run(["git", "describe", "--always", "--dirty=, with uncommitted changes"],
                         capture_output=True, text=True, cwd=ROOT).stdout.strip() or "unknown"
    return {"code": f"commit {git}",
            "CPU": f"{cpu}, {os.cpu_count()} logical cores", "C compiler": cc_version,
            "Python": platform.python_version(), "NumPy": np.__version__,
            "SciPy": scipy.__version__, "CasADi": ca.__version__,
            "date": datetime.date.today().isoformat()}


def _ms(t):
    return f"{t.median * 1e3:,.1f} ({t.low * 1e3:,.1f} to {t.high * 1e3:,.1f})"


def _verdict(ok):
    return "**met**" if ok else "**missed**"


def _narrow(ratios, margin=1.25):
    """A note on the cold targets met by less than ``margin`` (noise can flip them)."""
    close = [f"{label} {ratios[k]:.1f}x against {target:g}x" for k, label, target in
             (("cold", "cold cached", TARGET_COLD), ("empty", "cold empty cache", TARGET_EMPTY))
             if target <= ratios[k] < margin * target]
    if not close:
        return []
    return ["- Met narrowly (" + "; ".join(close) + "): single runs of a loaded machine can "
            "fall on either side."]


def render(m):
    """The report as Markdown: the ``## Simulation`` section up to its earlier figures."""
    plan, base = m["plan"], m["baseline"].median
    r = {k: base / m[k].median for k in ("warm", "cold", "empty")}
    sampled = {b: m["sampled"][b].median / m["warm"].median for b in BACKENDS}
    acc, mem, bd = m["accuracy"], m["memory"], m["breakdown"]
    per_s = mem["peak_long"] / MIB / plan.memory_duration
    eval_us = bd["integrate"].median / bd["evaluations"] * 1e6
    rest = m["warm"].median - bd["integrate"].median - bd["outputs"].median
    T = f"{plan.duration:g} s"
    rows = [
        ("SciPy baseline: `solve_ivp` RK45, rtol 1e-6, atol 1e-8, max_step 0.01",
         m["baseline"], "1", "", ""),
        ("`simulate`, warm", m["warm"], f"{r['warm']:.0f}x",
         f">= {TARGET_WARM:.0f}x (aim {AIM_WARM:.0f}x)", _verdict(r["warm"] >= TARGET_WARM)
         + ("" if r["warm"] >= AIM_WARM else ", aim not reached")),
        ("`simulate`, cold: fresh interpreter, compiled simulator cached (whole process)",
         m["cold"], f"{r['cold']:.1f}x", f">= {TARGET_COLD:.0f}x",
         _verdict(r["cold"] >= TARGET_COLD)),
        ("`simulate`, cold, empty cache: the build included (whole process)",
         m["empty"], f"{r['empty']:.1f}x", f"> {TARGET_EMPTY:.0f}x",
         _verdict(r["empty"] > TARGET_EMPTY)),
        ("of the cold runs: `import quadland` alone (whole process)", m["import"], "", "", ""),
    ]
    lines = [
        SECTION, "",
        f"The paper scenario, {T} of flight (noise off, nominal model on; l = 100, "
        f"{m['nx']} states, disturbance held over {m['intervals']:,} intervals of 10 ms), "
        "against what a user would write instead: SciPy `solve_ivp(method=\"RK45\", "
        "rtol=1e-6, atol=1e-8, max_step=0.01)` on a plain NumPy right-hand side of the "
        "same closed loop, whose disturbance is looked up at each time (held piecewise "
        "constant). The right-hand side is `tests/numpy_closed_loop.py`, derived again from "
        "the paper independently of `symbolic/`; it agrees with `closed_loop_function` to "
        f"{m['mismatch']:.1e} (relative) at random states. Measured in one run by "
        "`python benchmarks/bench_simulate.py`; CPU time (user + system; for fresh "
        "interpreters the whole process's, children included), median (min to max).", "",
        "| | runs | CPU time (ms) | baseline / this | target | verdict |",
        "|---|---:|---:|---:|---|---|",
    ]
    lines += [f"| {label} | {t.runs} | {_ms(t)} | {ratio} | {target} | {ok} |"
              for label, t, ratio, target, ok in rows]
    lines += [
        "", "| sampled-data loop, 500 Hz | runs | CPU time (ms) | / continuous warm | target "
        "| verdict |",
        "|---|---:|---:|---:|---|---|",
    ]
    lines += [f"| `controller.backend=\"{b}\"` | {m['sampled'][b].runs} | "
              f"{_ms(m['sampled'][b])} | {sampled[b]:.1f}x | <= {TARGET_SAMPLED:.0f}x | "
              f"{_verdict(sampled[b] <= TARGET_SAMPLED)} |" for b in BACKENDS]
    lines += [
        "",
        f"- The baseline is timed inside the benchmark's process, without its interpreter "
        "start-up and imports, which favours it against the cold figures. It evaluated "
        f"the right-hand side {m['nfev']:,} times.",
        *_narrow(r),
        f"- Building the simulator (generating its C and compiling it) adds "
        f"{m['empty'].median - m['cold'].median:.2f} s CPU to a cold run; the empty-cache "
        f"run's wall time is {m['empty'].wall:.2f} s (the translation units compile in "
        f"parallel on {os.cpu_count()} cores), the cached one's {m['cold'].wall:.2f} s.",
        "",
        "Accuracy, largest deviation over the run from a reference: `solve_ivp` DOP853 at "
        "rtol = atol = 1e-12 on the same NumPy right-hand side, restarted at every "
        "disturbance switch so that no step straddles one:", "",
        "| | z_e (m) | attitude, max of phi_e, theta_e, psi_e (rad) |",
        "|---|---:|---:|",
    ]
    lines += ["| {} | {:.1e} | {:.1e} |".format(k, *v) for k, v in acc.items()]
    lines += ["| reference check: {} | {:.1e} | {:.1e} |".format(k, *v)
              for k, v in m["checks"].items()]
    (zb, ab), (zq, aq) = acc.values()
    lines += [
        "",
        f"`simulate` is {zb / zq:.0f}x closer than the baseline in z_e, the baseline "
        f"{aq / ab:.0f}x closer in attitude. The baseline's first step is "
        f"{m['first_step'] * 1e3:.2f} ms, every later one the 10 ms of `max_step`; so each "
        "step straddles a switch of the held disturbance, whose force jumps perturb the "
        "altitude (its error estimate does not see them at rtol 1e-6). Otherwise its "
        "fifth-order formula is more accurate than one RK4 step per interval, which shows "
        "in attitude, where the held moment barely changes from sample to sample.",
        "",
        "The first check (another method on the CasADi right-hand side, compiled) bounds "
        "the reference's own error; the second shows why the reference is not cvodes: its "
        "Adams method at 1e-12 is off by more in z_e than the fine RK4.",
        "",
        "Memory, in a fresh interpreter (after one short warm-up run):", "",
        f"- tracemalloc peak of a {plan.memory_duration:g} s run: "
        f"{mem['peak_long'] / MIB:.0f} MiB, **{per_s:.2f} MiB per simulated second** "
        f"(target <= {TARGET_MEMORY:g}: {_verdict(per_s <= TARGET_MEMORY)}); the result "
        f"itself holds {mem['result_long'] / MIB:.0f} MiB "
        f"({mem['result_long'] / MIB / plan.memory_duration:.2f} MiB/s: "
        f"{m['nx']} states and {m['ncols']} output columns per row at 100 Hz).",
        f"- Peak resident set of the process: {mem['maxrss0'] / MIB:.0f} MiB before that "
        f"run, {mem['maxrss1'] / MIB:.0f} MiB after it "
        f"(+{(mem['maxrss1'] - mem['maxrss0']) / MIB:.0f} MiB); the resident set was "
        f"{mem['rss0'] / MIB:.0f} MiB before the run, {mem['rss_with'] / MIB:.0f} MiB "
        f"with the result alive and {mem['rss_after'] / MIB:.0f} MiB after dropping it.",
        f"- Nothing large is kept: after a {plan.leak_duration:g} s run, traced memory "
        f"grew by {mem['with_result'] / MIB:.2f} MiB with the result alive, of which the "
        f"result's own arrays are {mem['result_leak'] / MIB:.2f} MiB; after dropping it "
        f"and `gc.collect()`, {mem['after_drop'] / 1024:.1f} KiB remain.",
        "",
        "Where a warm call's time goes (medians, same run):", "",
        f"- the compiled integration {bd['integrate'].median * 1e3:.1f} ms: "
        f"{bd['evaluations']:,} evaluations of the compiled right-hand side (one RK4 step "
        f"per interval), {eval_us:.1f} us each including the RK4 update at -O2;",
        f"- the compiled output signals at {m['rows']:,} rows "
        f"{bd['outputs'].median * 1e3:.1f} ms;",
        f"- the rest (disturbance samples, grids, assembling the result's columns) "
        f"{rest * 1e3:.1f} ms.",
        "- The right-hand side itself is the cost, not the compiler's options: built at "
        "-O3, and with `-march=native`, the 60 s integration measured no faster (49.3 and "
        "47.0 ms against 48.6 ms at -O2; measured separately, not by this script).",
        "",
        "- Machine: " + "; ".join(f"{k} {v}" for k, v in m["machine"].items()) + ".",
    ]
    return "\n".join(lines) + "\n"


def write_section(text, path=DOC):
    """Replace the ``## Simulation`` section of ``path`` up to its ``### Earlier
    figures`` subsection (kept), or add the section."""
    old = path.read_text() if path.exists() else "# Performance\n"
    lines = old.splitlines(keepends=True)
    start = next((i for i, s in enumerate(lines) if s.rstrip() == SECTION), None)
    if start is None:
        path.write_text(old.rstrip("\n") + "\n\n" + text)
        return
    stop = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")),
                len(lines))
    kept = next((i for i in range(start + 1, stop) if lines[i].startswith(KEPT)), stop)
    earlier = "".join(lines[kept:stop]).rstrip("\n")
    tail = "".join(lines[stop:])
    body = text + ("\n" + earlier + "\n" if earlier else "")
    path.write_text("".join(lines[:start]) + body + ("\n" + tail if tail else ""))


def summary(m):
    """A plain-text table for the terminal."""
    base = m["baseline"].median
    rows = [("baseline solve_ivp RK45", m["baseline"], ""),
            ("simulate warm", m["warm"], f"{base / m['warm'].median:.0f}x  (>= 50x, aim 100x)"),
            ("cold, cached (process)", m["cold"], f"{base / m['cold'].median:.1f}x  (>= 10x)"),
            ("cold, empty cache (process)", m["empty"], f"{base / m['empty'].median:.1f}x  (> 1x)"),
            ("import quadland (process)", m["import"], "")]
    rows += [(f"sampled 500 Hz, {b}", m["sampled"][b],
              f"{m['sampled'][b].median / m['warm'].median:.1f}x continuous  (<= 3x)")
             for b in BACKENDS]
    out = [f"{'':30s} {'CPU ms (median)':>16s} {'min':>9s} {'max':>9s}  baseline/this"]
    out += [f"{label:30s} {t.median * 1e3:16.1f} {t.low * 1e3:9.1f} {t.high * 1e3:9.1f}  {note}"
            for label, t, note in rows]
    acc, mem = m["accuracy"], m["memory"]
    out += ["", f"{'max error vs DOP853 1e-12':52s} z_e (m)    attitude (rad)"]
    out += [f"{k:52s} {v[0]:.1e}    {v[1]:.1e}" for k, v in (*acc.items(),
                                                           *m["checks"].items())]
    out += ["", f"memory: {mem['peak_long'] / MIB / m['plan'].memory_duration:.2f} MiB per "
            f"simulated second (tracemalloc peak {mem['peak_long'] / MIB:.0f} MiB over "
            f"{m['plan'].memory_duration:g} s); peak RSS +"
            f"{(mem['maxrss1'] - mem['maxrss0']) / MIB:.0f} MiB; kept after drop "
            f"{mem['after_drop'] / 1024:.1f} KiB"]
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: shorter flights, fewer repeats")
    ap.add_argument("--write", action="store_true",
                    help="rewrite the Simulation section of docs/performance.md")
    args = ap.parse_args(argv)
    if args.quick and args.write:
        ap.error("--write takes the full run's figures; drop --quick")
    plan = QUICK if args.quick else FULL

    sc = scenario(plan)
    mv = model_values(sc)
    mismatch = rhs_mismatch(mv)
    print(f"NumPy rhs vs closed_loop_function: {mismatch:.1e}")
    if mismatch > 1e-9:
        raise SystemExit("the NumPy right-hand side disagrees with CasADi's")

    res = quadland.simulate(sc)                         # builds or loads the simulator
    m = dict(plan=plan, mismatch=mismatch, nx=mv.x0.size, rows=len(res["t"]), ncols=len(res),
             intervals=len(time_grid(sc)[2]) - 1, machine=machine())

    # fresh interpreters first, while this process is still small
    code = cold_code(plan)
    m["cold"] = time_process(code, plan.cold_runs)
    print(f"cold, cached: {m['cold'].median:.3f} s")
    m["import"] = time_process("import quadland", plan.cold_runs)
    m["empty"] = time_process(code, plan.empty_runs, empty_cache)
    print(f"cold, empty cache: {m['empty'].median:.3f} s")
    m["memory"] = memory(plan)

    m["warm"] = time_call(lambda: quadland.simulate(sc), plan.warm_runs)
    print(f"warm: {m['warm'].median * 1e3:.1f} ms")
    m["breakdown"] = breakdown(sc, plan.warm_runs)
    m["sampled"] = {}
    for b in BACKENDS:
        ss = scenario(plan, *SAMPLED, f'controller.backend="{b}"')
        quadland.simulate(ss)
        m["sampled"][b] = time_call(lambda ss=ss: quadland.simulate(ss),
                                    plan.c_backend_runs if b == "c" else plan.sampled_runs)
        print(f"sampled 500 Hz, {b}: {m['sampled'][b].median * 1e3:.1f} ms")

    sol = baseline(sc)
    m["nfev"] = sol.nfev
    m["first_step"] = solve_ivp(baseline_rhs(sc), (0.0, 0.05), mv.x0, **BASELINE).t[1]
    m["baseline"] = time_call(lambda: baseline(sc), plan.baseline_runs)
    print(f"baseline: {m['baseline'].median:.3f} s")

    X_ref = reference(sc)
    m["accuracy"] = {
        "SciPy baseline": max_errors(sol.y.T, X_ref, mv),
        "`simulate` (one RK4 step per 10 ms hold interval)": max_errors(res.states, X_ref, mv),
    }
    m["checks"] = {label: max_errors(quadland.simulate(scenario(plan, *extra)).states, X_ref, mv)
                   for label, extra in CHECKS.items()}

    print()
    print(summary(m))
    if args.write:
        write_section(render(m))
        print(f"\nupdated {DOC}")


if __name__ == "__main__":
    main()

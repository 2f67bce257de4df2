"""The sensed landing loop's cost: flying on sensors and the filter against the true state.

Measured in one run, for ``highway`` and ``ship``, side by side: the landing flown on
its sensors and the navigation filter (``sensors.enabled = true``, every shipped
landing's default) and on the true state (``sensors.enabled = false``, perfect
sensing):

* one warm ``quadland.simulate`` of the landing (the compiled simulator built
  beforehand): CPU time (``time.process_time``), median of :data:`WARM_RUNS`, and the
  ratio of the two;
* where the sensed call's extra time goes: the sensors' random draws of every
  control tick of the run (``quadland.kinds.landing.sensed.tick_table``, NumPy,
  before the flight), and the navigation filter's share, estimated as the control
  ticks flown times one ``estimator_step`` call at the flight sizes, timed alone in
  CasADi's C of it compiled as the simulator's (``cc -std=c99 -O2``; the step is
  branch-free, so every call costs the same): the filter is inlined in the sensed
  loop's compiled controller and cannot be timed inside it;
* the build, cold: a fresh interpreter flying the landing with an empty cache (a
  fresh ``XDG_CACHE_HOME``: the simulator's C generated and compiled, then the first
  call) and with the simulator cached (loaded); CPU time (user + system, the
  compilers included) and wall time, medians, of the whole process and, timed inside
  it, of the simulator's build (or load) and of the first call;
* the simulator's size: the C of its sampled part and the CasADi operations of its
  controller, the filter's among them;
* a 100-run campaign of the scenario's shipped ``[campaign]`` table on 2 local
  processes: wall time (``CampaignResult.elapsed``: from the first run submitted to
  the last recorded, the pool's start included), median of ``--repeats``.

Run from the repository root::

    python benchmarks/bench_sensed.py            # about six minutes
    python benchmarks/bench_sensed.py --write    # and rewrite docs/performance.md's part

``--write`` replaces the text between ``<!-- bench_sensed: begin -->`` and
``<!-- bench_sensed: end -->`` of ``docs/performance.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np
from bench_simulate import Timing, empty_cache, machine, time_call

import quadland
from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.constants import TILT_MIN
from quadland.engine.build import RUNTIME_CFLAGS, find_compiler
from quadland.engine.compiled import SIM_EVENT
from quadland.kinds.landing.report import touchdown_report
from quadland.kinds.landing.sensed import sensed_vectors, tick_table
from quadland.kinds.landing.simulate import landing_envelope, landing_loop_part
from quadland.kinds.landing.values import landing_clocks, landing_disturbance, landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.codegen import simulator_sources
from quadland_symbolic.kalman import operation_counts
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_init_function,
    estimator_step_function,
)
from quadland_symbolic.landing.loop import landing_loop
from quadland_symbolic.landing.navigation import (
    ESTIMATOR_DEFAULTS,
    IMU,
    NAV,
    NAV_PACKETS,
    estimator_params,
)
from quadland_symbolic.landing.plant import LANDING_PLANT_STATE
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.sensed_loop import landing_sensed_loop

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "performance.md"
BEGIN, END = "<!-- bench_sensed: begin -->", "<!-- bench_sensed: end -->"
SCENARIOS = ("highway", "ship")
#: The two loops: on the sensors and the filter, and on the true state.
MODES = {"sensed": [], "perfect": ["sensors.enabled=false"]}
WARM_RUNS = 15
COLD_EMPTY_RUNS = 2
COLD_CACHED_RUNS = 5
CAMPAIGN_RUNS = 100
WORKERS = 2
FILTER_CALLS = 20000


def scenario(name: str, mode: str) -> quadland.Scenario:
    return load_scenario(name, MODES[mode])


# --- warm ---------------------------------------------------------------------

def warm(name: str, mode: str) -> Timing:
    """CPU time of one warm ``simulate`` of the landing."""
    sc = scenario(name, mode)
    quadland.simulate(sc)                                      # build or load once
    return time_call(lambda: quadland.simulate(sc), WARM_RUNS)


def draws(name: str) -> tuple[int, Timing]:
    """The sensors' draws of a sensed run: its control ticks and their CPU time."""
    sc = scenario(name, "sensed")
    n = len(landing_clocks(sc)[2].times())
    return n, time_call(lambda: tick_table(sc, n), WARM_RUNS)


def flight(name: str, mode: str) -> Timing:
    """CPU time of the compiled flight alone: ``sampled`` up to touchdown, as
    ``quadland.kinds.landing.simulate.simulate_landing`` calls it (its inputs formed
    beforehand, the sensors' draws among them)."""
    sc = scenario(name, mode)
    lv, clocks = landing_values(sc), landing_clocks(sc)
    w = landing_disturbance(sc, clocks[1].times())
    sensed = mode == "sensed"
    loop = landing_loop_part(lv.l, "sampled", sensed)
    pc, xc0, N = lv.pc, lv.xc0, None
    if sensed:
        pc, xc0 = sensed_vectors(sc, lv)
        N = tick_table(sc, len(clocks[2].times()))
    hover = QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(lv.xp0)["x1q"])["F"]
    bounds = landing_envelope(sc).bounds
    d = sc.data

    def fly():
        run = loop.sampled(lv.xp0, xc0, clocks, w.T, d["simulation"]["rk_steps_per_interval"],
                           lv.pp, pc, TILT_MIN, bounds,
                           delay=d["controller"]["delay_periods"], uh0=hover, N=N)
        assert run.status == SIM_EVENT                      # touchdown
    fly()
    return time_call(fly, WARM_RUNS)


def ticks_flown(name: str) -> int:
    """Control ticks the sensed landing flies before its touchdown (the compiled part)."""
    sc = scenario(name, "sensed")
    t_td = touchdown_report(quadland.simulate(sc)).time
    return int(np.floor(t_td * sc["controller.rate_hz"] + 1e-9)) + 1


# --- the filter alone -----------------------------------------------------------

def _c_array(name: str, v) -> str:
    values = ", ".join(repr(float(x)) for x in np.ravel(v))
    return f"static const casadi_real {name}[{max(np.size(v), 1)}] = {{{values or '0'}}};"


def _filter_inputs() -> list[np.ndarray]:
    """A running filter at the flight sizes, a packet of every sensor due."""
    x0 = np.zeros(NAV.size)
    x0[NAV.slice("p_r")] = [0.3, -0.2, 3.0]
    mem = np.array(estimator_init_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)(
        x0, np.full(NAV.size, 0.5), np.zeros(9), 0.0)).ravel()
    imu = IMU.pack(dict(eta_hat=[0.02, -0.01, 0.5], f_b=[0.1, 0.2, 9.7], omega=[0.01] * 3))
    values = dict(fresh=1.0, tau=0.0, r_E=[-0.3, 0.2, -3.0], rel=[-0.2, 0.3, -3.1],
                  v1=[0.1] * 3, vt=[0.1] * 3, s=3.0, b3_E=[0.0, 0.0, 1.0],
                  eta2=[0.01, 0.0, 0.5], v2E=[0.1] * 3, a2E=[0.0] * 3, w2E=[0.0] * 3,
                  w2E_dot=[0.0] * 3)
    pkts = [p.pack({f.name: values[f.name] for f in p.fields}) for p in NAV_PACKETS]
    p_est = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    return [mem, imu, *pkts, p_est, np.array([0.004]), np.array([0.0])]


def filter_step_seconds(repeats: int = 5) -> float:
    """CPU seconds of one ``estimator_step`` call, CasADi's C at -O2, median of runs."""
    f = estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cg = ca.CodeGenerator("step.c", {"with_header": True})
        cg.add(f)
        cg.generate(f"{work}/")
        ins = _filter_inputs()
        arrays = "\n".join(_c_array(f"in{i}", v) for i, v in enumerate(ins))
        outs = "\n".join(f"static casadi_real out{i}[{f.nnz_out(i)}];" for i in range(f.n_out()))
        (work / "main.c").write_text(f"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "step.h"
{arrays}
{outs}
static casadi_real w[{f.sz_w()}];
static casadi_int iw[{f.sz_iw() + 1}];
int main(int argc, char **argv) {{
    const casadi_real *arg[{f.sz_arg()}] = {{{", ".join(f"in{i}" for i in range(f.n_in()))}}};
    casadi_real *res[{f.sz_res()}] = {{{", ".join(f"out{i}" for i in range(f.n_out()))}}};
    long i, n = atol(argv[1]);
    struct timespec a, b;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
    for (i = 0; i < n; ++i) estimator_step(arg, res, iw, w, 0);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
    printf("%.9g\\n", ((b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec)) / n);
    return 0;
}}
""")
        subprocess.run([find_compiler(), *RUNTIME_CFLAGS, "-O2", "-o", "bench", "main.c",
                        "step.c", "-lm"], cwd=work, check=True)
        return statistics.median(
            float(subprocess.run(["./bench", str(FILTER_CALLS)], cwd=work, check=True,
                                 capture_output=True, text=True).stdout)
            for _ in range(repeats))


# --- size -----------------------------------------------------------------------

def _controller_ops(model) -> int:
    """Arithmetic operations of a tick of ``model``'s controller; of a staged one (the
    sensed loop's), its SX stages' and the branch-free filter step's: the most a tick
    computes (every sensor due; the reads of the delay's slot are copies)."""
    if model.controller_stages is None:
        return operation_counts(model.controller)["arithmetic"]
    return sum(operation_counts(f)["arithmetic"] for f in model.controller_stages.stages
               if f.is_a("SXFunction")) + operation_counts(
        estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING))["arithmetic"]


def sizes() -> dict:
    """C of the sampled part and controller operations, of both landing loops (l = 10)."""
    out = {}
    for mode, model in (("sensed", landing_sensed_loop(10)), ("perfect", landing_loop(10))):
        files = simulator_sources(model, "sampled")
        out[mode] = dict(c_bytes=sum(len(t) for t in files.values()),
                         controller_bytes=sum(len(t) for n, t in files.items() if n.startswith(
                             f"qlsim_{model.name}_controller") and n.endswith(".c")),
                         controller_ops=_controller_ops(model))
    out["filter_ops"] = operation_counts(
        estimator_step_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING))["arithmetic"]
    return out


# --- cold -----------------------------------------------------------------------

#: A fresh interpreter flying one landing, timing its phases: the imports and the
#: scenario, the simulator (generated and compiled, or loaded from the cache), the first
#: call. CPU times count the compilers (children) too.
COLD_CODE = """
import json, resource, time
def cpu():
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime
def now():
    return cpu(), time.perf_counter()
a = now()
import quadland
from quadland.kinds.landing.simulate import landing_loop_part
from quadland.kinds.landing.values import landing_values
sc = quadland.load_scenario({name!r}, {overrides!r})
b = now()
landing_loop_part(landing_values(sc).l, "sampled", {sensed!r})
c = now()
quadland.simulate(sc)
d = now()
print(json.dumps(dict(build=[c[0] - b[0], c[1] - b[1]], first=[d[0] - c[0], d[1] - c[1]])))
"""


def _phases(code: str, env: dict | None) -> dict:
    """One fresh interpreter: its phases, and the whole process's CPU and wall time."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    w = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT,
                         env=dict(os.environ, **(env or {})), capture_output=True,
                         text=True).stdout
    wall = time.perf_counter() - w
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    phases = json.loads(out.strip().splitlines()[-1])
    phases["whole"] = [after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime,
                       wall]
    return phases


def cold(name: str, mode: str) -> dict:
    """Fresh interpreters: with an empty cache (the build included) and a cached one.

    Per case and phase (``whole``, ``build``, ``first``), the medians of CPU and wall s.
    """
    code = COLD_CODE.format(name=name, overrides=MODES[mode], sensed=mode == "sensed")
    runs = {"empty": [], "cached": []}
    for _ in range(COLD_EMPTY_RUNS):
        env, clean = empty_cache()
        try:
            runs["empty"].append(_phases(code, env))
        finally:
            clean()
    _phases(code, None)                                        # the default cache built
    runs["cached"] = [_phases(code, None) for _ in range(COLD_CACHED_RUNS)]
    return {case: {k: [statistics.median(r[k][i] for r in rs) for i in (0, 1)]
                   for k in ("whole", "build", "first")} for case, rs in runs.items()}


# --- campaign -------------------------------------------------------------------

def campaign(name: str, mode: str, repeats: int) -> list[float]:
    """Wall seconds of a 100-run campaign on 2 local processes, per repeat."""
    warm_up(scenario(name, mode))
    walls = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            result = run_campaign(name, MODES[mode], runs=CAMPAIGN_RUNS, out=Path(tmp) / "c",
                                  workers=WORKERS, plots=False)
            assert result.complete and result.flown == CAMPAIGN_RUNS
            walls.append(result.elapsed)
    return walls


def measure(repeats: int) -> dict:
    start = time.perf_counter()
    m = {"machine": machine(), "load": [os.getloadavg()[0]], "sizes": sizes(),
         "filter_step": filter_step_seconds()}
    for name in SCENARIOS:
        m[name] = {"warm": {mode: warm(name, mode) for mode in MODES},
                   "draws": draws(name), "ticks_flown": ticks_flown(name),
                   "flight": {mode: flight(name, mode) for mode in MODES},
                   "cold": {mode: cold(name, mode) for mode in MODES},
                   "campaign": {mode: campaign(name, mode, repeats) for mode in MODES}}
    m["elapsed"] = time.perf_counter() - start
    m["load"].append(os.getloadavg()[0])
    return m


# --- report ---------------------------------------------------------------------

def _ms(t: Timing) -> str:
    return f"{t.median * 1e3:,.1f} ({t.low * 1e3:,.1f} to {t.high * 1e3:,.1f})"


def render(m: dict) -> str:
    step = m["filter_step"]
    out = [BEGIN, "",
           "Measured in one run by `python benchmarks/bench_sensed.py`: each landing flown on "
           "its sensors and the navigation filter (`sensors.enabled = true`, the shipped "
           "default) and on the true state (`sensors.enabled = false`, perfect sensing); "
           "medians (min to max).", "",
           f"**One warm landing** (`quadland.simulate`, the simulator built beforehand, CPU "
           f"time, {WARM_RUNS} runs):", "",
           "| scenario | on sensors (ms) | perfect sensing (ms) | sensors / perfect |",
           "| --- | ---: | ---: | ---: |"]
    for name in SCENARIOS:
        w = m[name]["warm"]
        out.append(f"| `{name}` | {_ms(w['sensed'])} | {_ms(w['perfect'])} | "
                   f"{w['sensed'].median / w['perfect'].median:.1f}x |")
    out += ["", "**Where the sensed call's time goes** (medians, ms, and their share of the "
            "sensed call): the sensors' draws, made for every control tick of "
            "`simulation.duration` before the flight; the compiled flight up to touchdown "
            "(`sampled`, timed alone; perfect sensing's beside it); in it the navigation "
            "filter, which is inlined in the compiled controller and so estimated: the ticks "
            f"flown times one `estimator_step` call timed alone ({step * 1e6:.2f} us: "
            "CasADi's C of it at the flight sizes, `cc -std=c99 -O2`, median of 5 runs of "
            f"{FILTER_CALLS:,} calls; branch-free, every call costs the same); the rest "
            "(the output signals, the ride on the deck, the result's columns, the values):",
            "", "| scenario | sensed call | sensors' draws (ticks) | compiled flight (perfect "
            "sensing's) | the filter in it (ticks flown) | the rest |",
            "| --- | ---: | ---: | ---: | ---: | ---: |"]
    for name in SCENARIOS:
        r = m[name]
        total = r["warm"]["sensed"].median
        n, draws_t = r["draws"]
        fl, fp = r["flight"]["sensed"].median, r["flight"]["perfect"].median
        f_est = r["ticks_flown"] * step
        rest = total - draws_t.median - fl

        def pct(v, total=total):
            return f"{v * 1e3:.1f} ({100 * v / total:.0f} %)"
        out.append(f"| `{name}` | {total * 1e3:.1f} | {pct(draws_t.median)}, {n:,} ticks | "
                   f"{pct(fl)}; perfect {fp * 1e3:.1f} | {pct(f_est)}, "
                   f"{r['ticks_flown']:,} ticks | {pct(rest)} |")
    out += ["", "**Cold**: a fresh interpreter flying the landing, with an empty cache "
            "(a fresh `XDG_CACHE_HOME`: the simulator's C generated and compiled, "
            f"{COLD_EMPTY_RUNS} runs) and with the simulator cached (loaded, "
            f"{COLD_CACHED_RUNS} runs); CPU s (wall s), medians; the whole process, and in "
            "it the simulator's build or load and the first call (ms):", "",
            "| scenario, loop | empty cache: whole | the build | its first call (ms) | "
            "cached: whole | the load | its first call (ms) |",
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for name in SCENARIOS:
        for mode in MODES:
            e, k = m[name]["cold"][mode]["empty"], m[name]["cold"][mode]["cached"]
            cells = []
            for case in (e, k):
                cells += [f"{case['whole'][0]:,.2f} ({case['whole'][1]:,.2f})",
                          f"{case['build'][0]:,.2f} ({case['build'][1]:,.2f})",
                          f"{case['first'][0] * 1e3:,.0f} ({case['first'][1] * 1e3:,.0f})"]
            out.append(f"| `{name}`, {'on sensors' if mode == 'sensed' else 'perfect'} | "
                       + " | ".join(cells) + " |")
    out += ["", f"**A {CAMPAIGN_RUNS}-run campaign** (the shipped `[campaign]` table, "
            f"{WORKERS} local processes, wall time from the first run submitted to the last "
            f"recorded, median (min to max) of {len(m[SCENARIOS[0]]['campaign']['sensed'])}):",
            "", "| scenario | on sensors (s) | perfect sensing (s) | sensors / perfect |",
            "| --- | ---: | ---: | ---: |"]
    for name in SCENARIOS:
        v = m[name]["campaign"]
        c = {mode: statistics.median(w) for mode, w in v.items()}
        cells = [f"{c[k]:.2f} ({min(v[k]):.2f} to {max(v[k]):.2f}; "
                 f"{CAMPAIGN_RUNS / c[k]:.1f} runs/s)" for k in ("sensed", "perfect")]
        out.append(f"| `{name}` | {cells[0]} | {cells[1]} | "
                   f"{c['sensed'] / c['perfect']:.1f}x |")
    z = m["sizes"]
    s, p = z["sensed"], z["perfect"]
    out += ["",
            f"- The simulator's sampled part (l = 10, both scenarios: one build serves both) "
            f"is {s['c_bytes'] / 1e6:.2f} MB of C on sensors, of which the controller "
            f"{s['controller_bytes'] / 1e6:.2f} MB, against {p['c_bytes'] / 1e6:.2f} MB "
            f"({p['controller_bytes'] / 1e6:.2f} MB) with perfect sensing. Its controller "
            f"computes at most {s['controller_ops']:,} CasADi operations per tick (every "
            "sensor's update due; the filter evaluates only the due ones) against "
            f"{p['controller_ops']:,}; the filter's step is {z['filter_ops']:,} of them "
            f"({100 * z['filter_ops'] / s['controller_ops']:.0f} %), the sensors' models and "
            "delivery lines most of the rest.",
            f"- The machine is shared: its load average (1 min) was {m['load'][0]:.1f} when "
            f"the run began and {m['load'][1]:.1f} when it ended, on 2 cores; the wall times "
            "of the campaigns suffer most from other jobs, the CPU times least.",
            "- Machine: " + "; ".join(f"{k} {v}" for k, v in m["machine"].items()) + ".",
            "", END]
    return "\n".join(out)


def write(text: str, path: Path = DOC) -> None:
    doc = path.read_text()
    head, sep, rest = doc.partition(BEGIN)
    _, sep2, tail = rest.partition(END)
    if not (sep and sep2):
        raise SystemExit(f"{path}: no {BEGIN} ... {END} markers")
    path.write_text(head + text + tail)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="campaigns per scenario and loop")
    ap.add_argument("--write", action="store_true", help="rewrite docs/performance.md's part")
    args = ap.parse_args(argv)
    m = measure(args.repeats)
    text = render(m)
    print(text)
    print(f"(measured in {m['elapsed']:.0f} s)")
    if args.write:
        write(text)


if __name__ == "__main__":
    main()

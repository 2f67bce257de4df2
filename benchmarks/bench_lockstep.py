"""The navigation filter's step, one instance at a time against W in lockstep (issue 20).

Run with ``nice -n 10 python benchmarks/bench_lockstep.py [--function F] [--rounds N]
[--widths W ...]
[--opts O2 O3] [--isas base avx2 avx512]``. For each build (an optimization level and
an instruction set: ``base`` is x86-64's baseline, SSE2; ``avx2`` adds ``-mavx2``;
``avx512`` ``-mavx512f -mavx512dq``) and each W, one program holds CasADi's scalar C
of the step as ``generated/estimator_step.c`` has it and the lockstep C of the same
Function (:func:`quadland_symbolic.codegen.lockstep.lockstep_c`), both compiled with
the same flags (``-std=c99 -ffp-contract=off``, no ``-ffast-math``), and flies a table of
64 calls of 8 filters (tests/lockstep_c.py's ``filter_flight``: packets due, late,
stale, from the future, not finite and outliers) in four modes. ``--function
landing_loop_plant`` measures the landing's plant with the contact instead (its C in
``generated/landing_loop_plant.c``, the plant ``land -q`` spends most in), at the states
of ``generated/example/land_scenario.h``'s start perturbed, its parameters, hover
commands and a light wind, at times 4 ms apart; ``--function landing_loop_plant_flat``
the same plant on a flat deck as the runtime flies a car's landing
(:func:`quadland_symbolic.landing.flat_deck.flat_function`: the deck's sinusoids folded
away), its scalar C written by CasADi here, without the NULL tests as ``generated/``
has them. The modes:

* ``check``: every lane of every lockstep call against the scalar call, bit for bit
  (the program exits 1 on a difference; the benchmark stops);
* ``scalar``: W calls of the scalar step per table row;
* ``lockstep``: one call on inputs already in the lockstep layout (a campaign keeping
  its runs' filter memories interleaved);
* ``packed``: the inputs interleaved from W separate instances before the call and the
  outputs separated after it (a campaign keeping each run's memory apart).

Reported per instance and call: the CPU time (``CLOCK_PROCESS_CPUTIME_ID`` inside the
program; medians over the rounds, every build's modes run side by side in each round)
and, where valgrind runs the build (not AVX-512), the instructions (callgrind,
``--toggle-collect`` on the mode's step function, libm's calls included).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from statistics import median

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from lockstep_c import filter_flight, filter_step  # noqa: E402

from quadland_symbolic.codegen.lockstep import lockstep_c  # noqa: E402
from quadland_symbolic.codegen.registry import BY_NAME  # noqa: E402
from quadland_symbolic.landing.flat_deck import amplitude_indices, flat_function  # noqa: E402
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS  # noqa: E402

STEPS, LANES = 64, 8
ISAS = {"base": (), "avx2": ("-mavx2",), "avx512": ("-mavx512f", "-mavx512dq")}
#: The widths built by default for each instruction set: its register's doubles (2, 4, 8),
#: W = 1 (the lockstep writer's own scalar C, against CasADi's) and one over the width.
PLAN = {"base": (1, 2, 4), "avx2": (4, 8), "avx512": (8,)}
FLAGS = ("-std=c99", "-Wall", "-ffp-contract=off")

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "FUNC.h"
void LOCK(const double* const* arg, double* const* res);
static const int nin[NI] = {NIN_}, nout[NO] = {NOUT_};
static int oin[NI], oout[NO];
static double table[S][LANES][TIN], lanes_in[S][TIN * W], buf[TIN * W];
static double out_s[W][TOUT], out_l[TOUT * W], work[SZW];

__attribute__((noinline)) static void scalar_step(int s) {
  const double* arg[NI]; double* res[NO];
  for (int j = 0; j < W; ++j) {
    for (int i = 0; i < NI; ++i) arg[i] = table[s][j] + oin[i];
    for (int i = 0; i < NO; ++i) res[i] = out_s[j] + oout[i];
    ql_casadi_FUNC(arg, res, 0, work, 0);
  }
}
__attribute__((noinline)) static void lockstep_step(int s) {
  const double* arg[NI]; double* res[NO];
  for (int i = 0; i < NI; ++i) arg[i] = lanes_in[s] + W * oin[i];
  for (int i = 0; i < NO; ++i) res[i] = out_l + W * oout[i];
  LOCK(arg, res);
}
__attribute__((noinline)) static void packed_step(int s) {
  const double* arg[NI]; double* res[NO];
  for (int k = 0; k < TIN; ++k) for (int j = 0; j < W; ++j) buf[W * k + j] = table[s][j][k];
  for (int i = 0; i < NI; ++i) arg[i] = buf + W * oin[i];
  for (int i = 0; i < NO; ++i) res[i] = out_l + W * oout[i];
  LOCK(arg, res);
  for (int k = 0; k < TOUT; ++k) for (int j = 0; j < W; ++j) out_s[j][k] = out_l[W * k + j];
}
static double cpu(void) {
  struct timespec t; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}
int main(int argc, char** argv) {
  FILE* f = fopen(argv[1], "rb");
  if (!f || fread(table, sizeof table, 1, f) != 1) return 2;
  fclose(f);
  for (int i = 1; i < NI; ++i) oin[i] = oin[i - 1] + nin[i - 1];
  for (int i = 1; i < NO; ++i) oout[i] = oout[i - 1] + nout[i - 1];
  for (int s = 0; s < S; ++s)
    for (int k = 0; k < TIN; ++k)
      for (int j = 0; j < W; ++j) lanes_in[s][W * k + j] = table[s][j][k];
  const char* mode = argv[2];
  long reps = atol(argv[3]);
  if (!strcmp(mode, "check")) {
    long bad = 0;
    for (int s = 0; s < S; ++s) {
      scalar_step(s); lockstep_step(s);
      for (int j = 0; j < W; ++j) for (int k = 0; k < TOUT; ++k)
        bad += memcmp(&out_s[j][k], &out_l[W * k + j], sizeof(double)) != 0;
    }
    printf("check %ld\n", bad);
    return bad != 0;
  }
  void (*step)(int) = !strcmp(mode, "scalar") ? scalar_step
                      : !strcmp(mode, "lockstep") ? lockstep_step : packed_step;
  double t0 = cpu();
  for (long r = 0; r < reps; ++r) for (int s = 0; s < S; ++s) step(s);
  double t1 = cpu();
  printf("%s %.1f ns %.17g\n", mode, 1e9 * (t1 - t0) / ((double)reps * S * W),
         out_l[0] + out_s[0][0]);
  return 0;
}
"""


def _header_array(name: str) -> np.ndarray:
    text = (ROOT / "generated" / "example" / "land_scenario.h").read_text()
    body = re.search(rf"{name}\[\d+\] = \{{([^}}]*)\}}", text).group(1)
    return np.array([float(v) for v in body.replace(",", " ").split()])


def _plant_flight(seed: int, steps: int) -> list[list[np.ndarray]]:
    rng = np.random.default_rng(seed)
    xp0, pp = _header_array("ql_land_xp0"), _header_array("ql_land_pp")
    return [[xp0 + rng.normal(size=xp0.size) * 0.05, 4.9 + rng.normal(size=4) * 0.1,
             rng.normal(size=9) * 0.5, np.array([7.0 + 0.004 * k]), pp]
            for k in range(steps)]


def _function(function: str):
    if function == "estimator_step":
        return filter_step()
    if function == "landing_loop_plant_flat":
        plant = BY_NAME["landing_loop_plant"].function(0)
        flat = flat_function(plant, {"pp": amplitude_indices(LANDING_PLANT_PARAMS)})
        return ca.Function(function, [flat.sx_in(i) for i in range(flat.n_in())],
                           flat.call([flat.sx_in(i) for i in range(flat.n_in())]),
                           flat.name_in(), flat.name_out())
    return BY_NAME[function].function(0)


def _scalar_c(fn, function: str, folder: Path) -> None:
    """The scalar C as ``generated/`` has it, or written by CasADi (the flat plant)."""
    if function != "landing_loop_plant_flat":
        for ext in ("c", "h"):
            shutil.copy(ROOT / "generated" / f"{function}.{ext}", folder)
        return
    named = ca.Function(f"ql_casadi_{function}", [fn.sx_in(i) for i in range(fn.n_in())],
                        fn.call([fn.sx_in(i) for i in range(fn.n_in())]))
    cg = ca.CodeGenerator(f"{function}.c", {"with_header": True})
    cg.add(named)
    cg.generate(str(folder) + os.sep)
    c = (folder / f"{function}.c").read_text()
    c = re.sub(r"arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0", r"arg[\1][\2]", c)
    c = re.sub(r"if \(res\[(\d+)\]!=0\) res\[\1\]", r"res[\1]", c)
    (folder / f"{function}.c").write_text(c)


def _table(path: Path, function: str):
    fn = _function(function)
    fly = filter_flight if function == "estimator_step" else _plant_flight
    flights = [fly(seed, STEPS) for seed in range(LANES)]
    rows = [np.concatenate(flights[j][s]) for s in range(STEPS) for j in range(LANES)]
    np.asarray(rows, dtype=np.float64).tofile(path)
    return fn


def _build(fn, folder: Path, width: int, opt: str, isa: str, function: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    name = f"lock{width}"
    (folder / "lock.c").write_text(lockstep_c(fn, width, name=name))
    _scalar_c(fn, function, folder)
    defs = dict(LOCK=name, NI=fn.n_in(), NO=fn.n_out(), S=STEPS, LANES=LANES, W=width,
                TIN=sum(fn.nnz_in(i) for i in range(fn.n_in())),
                TOUT=sum(fn.nnz_out(i) for i in range(fn.n_out())), SZW=max(fn.sz_w(), 1),
                NIN=", ".join(str(fn.nnz_in(i)) for i in range(fn.n_in())),
                NOUT=", ".join(str(fn.nnz_out(i)) for i in range(fn.n_out())))
    text = HARNESS.replace("NIN_", defs.pop("NIN")).replace("NOUT_", defs.pop("NOUT"))
    text = text.replace("FUNC", function)
    (folder / "main.c").write_text(text)
    exe = folder / "bench"
    subprocess.run(["cc", *FLAGS, "-" + opt, *ISAS[isa], *(f"-D{k}={v}" for k, v in defs.items()),
                    "-I", str(folder), "-o", str(exe), str(folder / "main.c"),
                    str(folder / "lock.c"), str(folder / f"{function}.c"), "-lm"],
                   check=True)
    return exe


def _run(exe: Path, table: Path, mode: str, reps: int) -> float:
    out = subprocess.run([str(exe), str(table), mode, str(reps)], capture_output=True,
                         text=True, check=True).stdout
    return float(out.split()[1])


def _instructions(exe: Path, table: Path, mode: str, width: int) -> float | None:
    """Callgrind's instructions per instance and call of the mode's step function."""
    if not shutil.which("valgrind"):
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp, "cg.out")
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                              f"--toggle-collect={mode}_step", str(exe), str(table), mode, "1"],
                             capture_output=True, text=True)
        if run.returncode != 0:
            return None
        m = re.search(r"summary:\s+(\d+)", out.read_text())
    return int(m.group(1)) / (STEPS * width) if m else None


def _avx512_runs() -> bool:
    flags = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    return " avx512f" in flags and " avx512dq" in flags


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--function", default="estimator_step",
                    choices=("estimator_step", "landing_loop_plant",
                             "landing_loop_plant_flat"))
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--widths", type=int, nargs="+", help="W of every build (default: PLAN)")
    ap.add_argument("--opts", nargs="+", default=["O2", "O3"])
    ap.add_argument("--isas", nargs="+", default=["base", "avx2", "avx512"])
    ap.add_argument("--reps", type=int, default=20, help="passes over the table per timing")
    args = ap.parse_args()
    isas = [i for i in args.isas if i != "avx512" or _avx512_runs()]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        table = tmp / "table.bin"
        fn = _table(table, args.function)
        builds = {}
        for opt in args.opts:
            for isa in isas:
                for w in args.widths or PLAN[isa]:
                    key = (opt, isa, w)
                    t0 = os.times()
                    exe = builds[key] = _build(fn, tmp / f"{opt}{isa}{w}", w, opt, isa,
                                               args.function)
                    t1 = os.times()
                    subprocess.run([str(exe), str(table), "check", "1"], check=True,
                                   capture_output=True)
                    print(f"built and checked {opt} {isa} W={w} bit for bit "
                          f"(compile {t1.children_user - t0.children_user:.1f} s CPU)",
                          flush=True)
        modes = ("scalar", "lockstep", "packed")
        times = {(k, m): [] for k in builds for m in modes}
        for _ in range(args.rounds):
            for key, exe in builds.items():
                for m in modes:
                    times[key, m].append(_run(exe, table, m, args.reps))
        print(f"\nper instance and call; CPU ns: median of {args.rounds} rounds (min to max); "
              "instructions: callgrind")
        print(f"{'build':<14}{'W':>3} {'scalar ns':>18} {'lockstep ns':>18} {'packed ns':>18}"
              f" {'speed-up':>9} {'scalar Ir':>10} {'lockstep Ir':>12} {'packed Ir':>10}")
        for (opt, isa, w), exe in builds.items():
            med = {m: median(times[(opt, isa, w), m]) for m in modes}
            cells = [f"{med[m]:7.0f} ({min(times[(opt, isa, w), m]):.0f}-"
                     f"{max(times[(opt, isa, w), m]):.0f})" for m in modes]
            ir = [None if isa == "avx512" else _instructions(exe, table, m, w) for m in modes]
            irs = [f"{v:,.0f}" if v else "-" for v in ir]
            print(f"{opt + ' ' + isa:<14}{w:>3} {cells[0]:>18} {cells[1]:>18} {cells[2]:>18} "
                  f"{med['scalar'] / med['lockstep']:>8.2f}x {irs[0]:>10} {irs[1]:>12} "
                  f"{irs[2]:>10}", flush=True)


if __name__ == "__main__":
    main()

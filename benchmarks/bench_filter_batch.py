"""The runtime's filter, run by run, against W runs in one batch call in lockstep (issue 20).

Run with ``nice -n 10 python benchmarks/bench_filter_batch.py [--rounds N] [--isas base
avx2 avx512]`` from the repository root. The scalar side is the runtime's own compiled
filter: the ``sensed_filter`` and ``sensed_finish`` stages (the conditional step, each
sensor's updates only when due) of ``highway``'s simulator, loaded from the disk cache
(``dlopen``, the library ``quadland.simulate`` flies). The batch side is
:func:`quadland_symbolic.codegen.lockstep_batch.lockstep_batch_c` of the branch-free step
(the Function of ``generated/estimator_step.c``, at the flight's sizes), compiled here
with the simulators' flags plus the instruction set. One program holds both and flies a
table of 64 calls of 8 filters (``tests/lockstep_c.py``'s ``filter_flight``) in modes:

* ``check``: every run of every batch call against the runtime's two stages, bit for bit,
  once with every run active and once with runs 1 and 3 finished (exit 1 on a
  difference);
* ``runtime``: the two stages once per run (what a driver flying W runs calls now);
* ``batch``: one call of the batch entry per table row, the W runs' pointers in (their
  memories kept apart), every run active;
* ``tail``: the same with one run active (the campaign's last runs), per active run;
* ``lockstep``: the lockstep kernel alone on inputs already interleaved (a driver keeping
  its runs' memories interleaved).

Reported per run and call: the CPU time (``CLOCK_PROCESS_CPUTIME_ID`` in the program,
medians over the rounds, the modes side by side in each round) and the instructions
(callgrind, ``--toggle-collect`` on the mode's step function, libm's calls included; not
for AVX-512, which valgrind does not run).
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

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_delivery_ring import captured  # noqa: E402
from lockstep_c import filter_flight, filter_step  # noqa: E402

from quadland_symbolic.codegen.lockstep import lockstep_c  # noqa: E402
from quadland_symbolic.codegen.lockstep_batch import lockstep_batch_c  # noqa: E402
from quadland_symbolic.landing.estimator import (  # noqa: E402
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
)
from quadland_symbolic.landing.estimator_switch import conditional_step_stages  # noqa: E402

STEPS, LANES = 64, 8
ISAS = {"base": ((), 2), "avx2": (("-mavx2",), 4), "avx512": (("-mavx512f", "-mavx512dq"), 8)}
FLAGS = ("-std=c99", "-O2", "-Wall", "-ffp-contract=off", "-fno-math-errno")

HARNESS = r"""
#define _POSIX_C_SOURCE 199309L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
typedef int (*stage_f)(const double**, double**, int*, double*, int);
typedef int (*work_f)(int*, int*, int*, int*);
void filter_batch(const double* const* arg, double* const* res, const int* active);
void filter_lanes(const double* const* arg, double* const* res);
static const int nin[NI] = {NIN_}, nout[NO] = {NOUT_}, nbet[NB] = {NBET_};
/* the finish's inputs: >= 0 an input of the filter's, < 0 its output -1 - k */
static const int fin_src[NF] = {FIN_};
static int oin[NI], oout[NO];
static double table[S][LANES][TIN], lanes_in[S][TIN * W];
static double out_r[W][TOUT], out_b[W][TOUT], out_l[TOUT * W], bet[TBET], *iw_w;
static int *iw;
/* the stages' arg and res arrays: CasADi's sz_arg and sz_res (its calls' scratch after the
   function's own pointers) */
static const double** s_arg;
static double** s_res;
static stage_f filt, fin;

__attribute__((noinline)) static void runtime_step(int s) {
  const double** arg = s_arg; double** res = s_res;
  for (int j = 0; j < W; ++j) {
    for (int i = 0; i < NI; ++i) arg[i] = table[s][j] + oin[i];
    double* b = bet;
    for (int i = 0; i < NB; ++i) { res[i] = b; b += nbet[i]; }
    filt(arg, res, iw, iw_w, 0);
    const double* bo[NB]; b = bet;
    for (int i = 0; i < NB; ++i) { bo[i] = b; b += nbet[i]; }
    for (int i = 0; i < NF; ++i)
      arg[i] = fin_src[i] >= 0 ? table[s][j] + oin[fin_src[i]] : bo[-1 - fin_src[i]];
    for (int i = 0; i < NO; ++i) res[i] = out_r[j] + oout[i];
    fin(arg, res, iw, iw_w, 0);
  }
}
static void batch_call(int s, const int* active) {
  const double* arg[NI * W]; double* res[NO * W];
  for (int j = 0; j < W; ++j) {
    for (int i = 0; i < NI; ++i) arg[NI * j + i] = table[s][j] + oin[i];
    for (int i = 0; i < NO; ++i) res[NO * j + i] = out_b[j] + oout[i];
  }
  filter_batch(arg, res, active);
}
static const int all_on[W] = {ALL_ON}, one_on[W] = {1};
__attribute__((noinline)) static void batch_step(int s) { batch_call(s, all_on); }
__attribute__((noinline)) static void tail_step(int s) { batch_call(s, one_on); }
__attribute__((noinline)) static void lockstep_step(int s) {
  const double* arg[NI]; double* res[NO];
  for (int i = 0; i < NI; ++i) arg[i] = lanes_in[s] + W * oin[i];
  for (int i = 0; i < NO; ++i) res[i] = out_l + W * oout[i];
  filter_lanes(arg, res);
}
static double cpu(void) {
  struct timespec t; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}
static long compare(int s, const int* active) {
  long bad = 0;
  memset(out_b, 0xff, sizeof out_b);
  runtime_step(s); batch_call(s, active);
  for (int j = 0; j < W; ++j) {
    if (!active[j]) { for (int k = 0; k < TOUT; ++k) bad += out_b[j][k] == out_b[j][k]; continue; }
    bad += memcmp(out_r[j], out_b[j], sizeof out_r[j]) != 0;
  }
  lockstep_step(s);
  for (int j = 0; j < W; ++j) for (int k = 0; k < TOUT; ++k)
    bad += memcmp(&out_r[j][k], &out_l[W * k + j], sizeof(double)) != 0;
  return bad;
}
int main(int argc, char** argv) {
  void* h = dlopen(argv[1], RTLD_NOW);
  if (!h) { fprintf(stderr, "%s\n", dlerror()); return 2; }
  filt = (stage_f)dlsym(h, PREFIX "sensed_filter");
  fin = (stage_f)dlsym(h, PREFIX "sensed_finish");
  work_f wf = (work_f)dlsym(h, PREFIX "sensed_filter_work"),
         wn = (work_f)dlsym(h, PREFIX "sensed_finish_work");
  if (!filt || !fin || !wf || !wn) return 2;
  int a1, r1, i1, w1, a2, r2, i2, w2;
  wf(&a1, &r1, &i1, &w1); wn(&a2, &r2, &i2, &w2);
  s_arg = calloc((a1 > a2 ? a1 : a2) + NI + NF, sizeof *s_arg);
  s_res = calloc((r1 > r2 ? r1 : r2) + NO + NB, sizeof *s_res);
  iw = calloc((i1 > i2 ? i1 : i2) + 1, sizeof *iw);
  iw_w = calloc((w1 > w2 ? w1 : w2) + 1, sizeof *iw_w);
  FILE* f = fopen(argv[2], "rb");
  if (!f || fread(table, sizeof table, 1, f) != 1) return 2;
  fclose(f);
  for (int i = 1; i < NI; ++i) oin[i] = oin[i - 1] + nin[i - 1];
  for (int i = 1; i < NO; ++i) oout[i] = oout[i - 1] + nout[i - 1];
  for (int s = 0; s < S; ++s)
    for (int k = 0; k < TIN; ++k)
      for (int j = 0; j < W; ++j) lanes_in[s][W * k + j] = table[s][j][k];
  const char* mode = argv[3];
  long reps = atol(argv[4]);
  if (!strcmp(mode, "check")) {
    int some[W];
    for (int j = 0; j < W; ++j) some[j] = j != 1 && j != 3;
    long bad = 0;
    for (int s = 0; s < S; ++s) bad += compare(s, all_on) + (W > 3 ? compare(s, some) : 0);
    printf("check %ld\n", bad);
    return bad != 0;
  }
  void (*step)(int) = !strcmp(mode, "runtime") ? runtime_step : !strcmp(mode, "batch")
                      ? batch_step : !strcmp(mode, "tail") ? tail_step : lockstep_step;
  double t0 = cpu();
  for (long q = 0; q < reps; ++q) for (int s = 0; s < S; ++s) step(s);
  double t1 = cpu();
  int per = !strcmp(mode, "tail") ? 1 : W;
  printf("%s %.1f ns %.17g\n", mode, 1e9 * (t1 - t0) / ((double)reps * S * per),
         out_l[0] + out_r[0][0] + out_b[0][0]);
  return 0;
}
"""


def _stages_layout(fn) -> dict:
    """The defines that wire the two stages (their order of inputs and outputs)."""
    fused, finish = conditional_step_stages(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    assert [fused.nnz_in(i) for i in range(fused.n_in())] == \
        [fn.nnz_in(i) for i in range(fn.n_in())]
    assert [finish.nnz_out(i) for i in range(finish.n_out())] == \
        [fn.nnz_out(i) for i in range(fn.n_out())]
    src = [fused.name_in().index(n) if n in fused.name_in()
           else -1 - fused.name_out().index(n) for n in finish.name_in()]
    nbet = [fused.nnz_out(i) for i in range(fused.n_out())]
    return dict(NB=len(nbet), NF=finish.n_in(), TBET=sum(nbet),
                NBET_=", ".join(map(str, nbet)), FIN_=", ".join(map(str, src)))


def _build(fn, folder: Path, isa: str, prefix: str) -> Path:
    flags, width = ISAS[isa]
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "batch.c").write_text(lockstep_batch_c(fn, width, name="filter_batch"))
    (folder / "lanes.c").write_text(lockstep_c(fn, width, name="filter_lanes"))
    d = dict(NI=fn.n_in(), NO=fn.n_out(), S=STEPS, LANES=LANES, W=width,
             TIN=sum(fn.nnz_in(i) for i in range(fn.n_in())),
             TOUT=sum(fn.nnz_out(i) for i in range(fn.n_out())),
             NIN_=", ".join(str(fn.nnz_in(i)) for i in range(fn.n_in())),
             NOUT_=", ".join(str(fn.nnz_out(i)) for i in range(fn.n_out())),
             ALL_ON=", ".join(["1"] * width), PREFIX=f'"{prefix}"', **_stages_layout(fn))
    text = HARNESS
    for k in ("NIN_", "NOUT_", "NBET_", "FIN_", "ALL_ON", "PREFIX"):
        text = text.replace(k, str(d.pop(k)))
    (folder / "main.c").write_text(text)
    exe = folder / "bench"
    subprocess.run(["cc", *FLAGS, *flags, *(f"-D{k}={v}" for k, v in d.items()), "-o",
                    str(exe), str(folder / "main.c"), str(folder / "batch.c"),
                    str(folder / "lanes.c"), "-lm", "-ldl"], check=True)
    return exe


def _run(exe: Path, lib: str, table: Path, mode: str, reps: int) -> float:
    out = subprocess.run([str(exe), lib, str(table), mode, str(reps)], capture_output=True,
                         text=True, check=True).stdout
    return float(out.split()[1])


def _instructions(exe: Path, lib: str, table: Path, mode: str, per: int) -> float | None:
    """Callgrind's instructions per run and call of the mode's step function."""
    if not shutil.which("valgrind"):
        return None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp, "cg.out")
        run = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                              f"--toggle-collect={mode}_step", str(exe), lib, str(table),
                              mode, "1"], capture_output=True, text=True)
        if run.returncode != 0:
            return None
        m = re.search(r"summary:\s+(\d+)", out.read_text())
    return int(m.group(1)) / (STEPS * per) if m else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--reps", type=int, default=20, help="passes over the table per timing")
    ap.add_argument("--isas", nargs="+", default=["base", "avx2", "avx512"])
    args = ap.parse_args()
    cpuinfo = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() else ""
    runs = {"base": True, "avx2": " avx2" in cpuinfo,
            "avx512": " avx512f" in cpuinfo and " avx512dq" in cpuinfo}
    isas = [i for i in args.isas if runs[i]]
    loop = captured("highway")[0]
    lib, prefix = str(loop.library), f"qlsim_{loop.model.name}_controller_"
    print(f"load average {os.getloadavg()}; the runtime's filter from {lib}")
    fn = filter_step()
    modes = ("runtime", "batch", "tail", "lockstep")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        table = tmp / "table.bin"
        flights = [filter_flight(seed, STEPS) for seed in range(LANES)]
        np.asarray([np.concatenate(flights[j][s]) for s in range(STEPS) for j in range(LANES)],
                   dtype=np.float64).tofile(table)
        builds = {}
        for isa in isas:
            exe = builds[isa] = _build(fn, tmp / isa, isa, prefix)
            subprocess.run([str(exe), lib, str(table), "check", "1"], check=True,
                           capture_output=True)
            print(f"built {isa} (W = {ISAS[isa][1]}); every run of every call the runtime's "
                  "bits (check)", flush=True)
        times = {(k, m): [] for k in builds for m in modes}
        for _ in range(args.rounds):
            for isa, exe in builds.items():
                for m in modes:
                    times[isa, m].append(_run(exe, lib, table, m, args.reps))
        print(f"\nper run and call; CPU ns: median of {args.rounds} rounds; instructions: "
              "callgrind")
        for isa, exe in builds.items():
            w = ISAS[isa][1]
            med = {m: median(times[isa, m]) for m in modes}
            ir = {m: None if isa == "avx512" else
                  _instructions(exe, lib, table, m, 1 if m == "tail" else w) for m in modes}
            cells = "; ".join(
                f"{m} {med[m]:.0f} ns ({med['runtime'] / med[m]:.2f}x)"
                + (f", {ir[m]:,.0f} instr." if ir[m] else "") for m in modes)
            print(f"- {isa}, W = {w}: {cells}", flush=True)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

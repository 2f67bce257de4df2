"""The compiled flight's libm calls: ``-fno-math-errno`` and a table of its sines and
cosines (issue 20, eleventh session; the table a trial, not shipped).

``--count``: flies the default landing of each of ``--flights`` (the runtime's own
simulator and arguments, as ``bench_delivery_ring.py`` captures them) in a child
process with a small ``LD_PRELOAD`` library in front of glibc's ``sin``, ``cos``,
``sincos``, ``exp``, ``tan``, ``tanh``, ``expm1``, ``log1p``, ``sinh`` and ``cosh``:
per function, its calls during one flight (a process that only captures the arguments
subtracted), how many took an argument (by its 64 bits) one of the 64 before it took
(sines and cosines share one history, each other function its own) and how many took
zero.

``-fno-math-errno`` (shipped, :data:`quadland.engine.machine.ERRNO_FLAGS`): the shipped
build against one ``with errno`` (the machine's flags without it, as before).

The trial (``--flights``, the default): the simulator's C with CasADi's ``sin(x)`` and
``cos(x)`` rewritten into a look-up in a per-thread, direct-mapped table of 64
arguments and their ``sincos`` (one table for all of a simulator's functions, a hit
returns what ``sincos`` gave for the same bits, which is glibc's ``sin`` and ``cos``),
built two ways beside the shipped build: in every function (``memo, all``), in the
controller's stages only (``memo, controller``); the model renamed for each (a build
of its own). Each build's flight is checked the same bits as the shipped one's first
(every recorded row, state and the end state), then all are flown alternately in one
process (CPU ms, median of ``--rounds``).
``--callgrind NAME`` flies one build's flight once, for::

    valgrind --tool=callgrind --toggle-collect=qlsim_<model>_plant \\
        --toggle-collect=qlsim_<model>_controller ... python benchmarks/bench_trig_memo.py \\
        --flights highway --callgrind "memo, all"

Run from the repository root: ``nice -n 10 python benchmarks/bench_trig_memo.py
[--count]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import report_flights, timed_flights  # noqa: E402
from bench_delivery_ring import captured  # noqa: E402

from quadland.engine import build  # noqa: E402
from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland.engine.machine import ERRNO_FLAGS  # noqa: E402
from quadland_symbolic.codegen import simulator  # noqa: E402

SLOTS = 64
HEADER = "quadland_trig.h"
_CALL = re.compile(r"(?<![\w.])(sin|cos)\(")
_BODY = re.compile(r"^static int casadi_f\d+\([^)]*\) \{\n", re.MULTILINE)

#: ``qll_sin``/``qll_cos``: the thread's table (its address taken once a function body,
#: ``__tls_get_addr`` in a shared library), ``sincos`` on a miss.
TRIG_H = f"""#ifndef QUADLAND_TRIG_H
#define QUADLAND_TRIG_H
#include <math.h>
#include <string.h>
typedef struct {{ unsigned long long x; double s, c; }} qll_trig_slot;
extern __thread qll_trig_slot qll_trig_memo[{SLOTS}] __attribute__((visibility("hidden")));
void sincos(double x, double *s, double *c);
static inline qll_trig_slot *qll_trig(qll_trig_slot *t, double x)
{{
    unsigned long long b;
    qll_trig_slot *e;
    memcpy(&b, &x, sizeof b);
    e = &t[(b * 0x9E3779B97F4A7C15ULL) >> {64 - SLOTS.bit_length() + 1}];
    if (e->x != b) {{
        sincos(x, &e->s, &e->c);
        e->x = b;
    }}
    return e;
}}
#define qll_sin(x) (qll_trig(qll_tab, (x))->s)
#define qll_cos(x) (qll_trig(qll_tab, (x))->c)
#endif
"""
#: The table's one definition: every slot +0.0 with its sine +0.0 and cosine 1.0.
TRIG_C = (f'#include "{HEADER}"\n__thread qll_trig_slot qll_trig_memo[{SLOTS}] = '
          f'{{{", ".join(["{0ULL, 0.0, 1.0}"] * SLOTS)}}};\n')


def memo_sin_cos(c: str) -> str:
    """CasADi's C with its ``sin(`` and ``cos(`` calls through the table."""
    if not _CALL.search(c):
        return c
    c = _BODY.sub(lambda m: m.group(0) + "  qll_trig_slot *const qll_tab = qll_trig_memo;\n",
                  _CALL.sub(r"qll_\1(", c))
    return c.replace("#include <math.h>\n", f'#include <math.h>\n#include "{HEADER}"\n', 1)


def memo_build(model, suffix: str, where) -> CompiledLoop:
    """The sampled simulator of ``model`` (renamed) with the table in the functions whose
    name ``where`` accepts."""
    emit, sources = simulator._emit, simulator.simulator_sources

    def emit_memo(name, f):
        text, fn = emit(name, f)
        if where(name):
            text[f"{name}.c"] = memo_sin_cos(text[f"{name}.c"])
        return text, fn

    def sources_memo(m, part):
        files = sources(m, part)
        return {**files, HEADER: TRIG_H, f"qlsim_{m.name}_trig.c": TRIG_C}

    simulator._emit, simulator.simulator_sources = emit_memo, sources_memo
    try:
        return CompiledLoop(dataclasses.replace(model, name=model.name + suffix), "sampled")
    finally:
        simulator._emit, simulator.simulator_sources = emit, sources


def errno_build(model) -> CompiledLoop:
    """The sampled simulator of ``model`` (renamed) built with libm's ``errno``: the
    machine's flags without :data:`quadland.engine.machine.ERRNO_FLAGS` (before)."""
    real = build.machine_flags
    build.machine_flags = lambda cc: tuple(f for f in real(cc) if f not in ERRNO_FLAGS)
    try:
        return CompiledLoop(dataclasses.replace(model, name=model.name + "_errno"), "sampled")
    finally:
        build.machine_flags = real


def builds(scenario: str):
    loop, args, kwargs = captured(scenario)
    model = built_model(loop.model)
    return {"baseline, libm": loop,
            "with errno": errno_build(model),
            "memo, all": memo_build(model, "_memo", lambda n: True),
            "memo, controller": memo_build(model, "_memoc", lambda n: "_controller_" in n)
            }, args, kwargs


#: The counting library: each function's calls, repeats of one of the last 64
#: arguments, zeros; printed at exit.
SHIM = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>
#define K 64
enum { SIN, COS, SINCOS, EXP, TAN, TANH, EXPM1, LOG1P, SINH, COSH, NF };
static const char *names[NF] = {"sin", "cos", "sincos", "exp", "tan", "tanh", "expm1",
                                "log1p", "sinh", "cosh"};
static unsigned long long hist[NF][K];
static int head[NF];
static long calls[NF], again[NF], zero[NF];
static void note(int f, double x)
{
    unsigned long long b;
    int h = f <= SINCOS ? SIN : f, i;
    memcpy(&b, &x, 8);
    calls[f]++;
    zero[f] += x == 0.0;
    for (i = 0; i < K; i++)
        if (hist[h][i] == b) { again[f]++; return; }
    hist[h][head[h]] = b;
    head[h] = (head[h] + 1) % K;
}
#define ONE(F, f) double f(double x) { static double (*r)(double); \
    if (!r) r = (double (*)(double))dlsym(RTLD_NEXT, #f); note(F, x); return r(x); }
ONE(SIN, sin) ONE(COS, cos) ONE(EXP, exp) ONE(TAN, tan) ONE(TANH, tanh) ONE(EXPM1, expm1)
ONE(LOG1P, log1p) ONE(SINH, sinh) ONE(COSH, cosh)
void sincos(double x, double *s, double *c)
{
    static void (*r)(double, double *, double *);
    if (!r) r = (void (*)(double, double *, double *))dlsym(RTLD_NEXT, "sincos");
    note(SINCOS, x);
    r(x, s, c);
}
__attribute__((destructor)) static void report(void)
{
    int f;
    for (f = 0; f < NF; f++)
        fprintf(stderr, "libm %s %ld %ld %ld\n", names[f], calls[f], again[f], zero[f]);
}
"""

FLY = r"""
import sys
sys.path.insert(0, sys.argv[1])
from bench_delivery_ring import captured
loop, args, kwargs = captured(sys.argv[2])
for _ in range(int(sys.argv[3])):
    loop.sampled(*args, **kwargs)
"""


def counts(scenario: str) -> dict:
    """Per libm function: (calls, repeats of the last 64 arguments, zeros) in one flight."""
    tmp = Path(tempfile.mkdtemp(prefix="quadland-libm-"))
    (tmp / "shim.c").write_text(SHIM)
    subprocess.run([build.find_compiler(), "-O2", "-shared", "-fPIC", str(tmp / "shim.c"),
                    "-o", str(tmp / "shim.so"), "-ldl"], check=True)
    env = {**os.environ, "LD_PRELOAD": str(tmp / "shim.so")}
    got = []
    for n in (0, 1):
        err = subprocess.run([sys.executable, "-c", FLY, str(Path(__file__).parent), scenario,
                              str(n)], env=env, capture_output=True, text=True,
                             check=True).stderr
        got.append({w[1]: tuple(map(int, w[2:])) for w in
                    (line.split() for line in err.splitlines() if line.startswith("libm "))})
    return {f: tuple(b - a for a, b in zip(got[0][f], got[1][f], strict=True)) for f in got[1]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--count", action="store_true")
    parser.add_argument("--callgrind")
    a = parser.parse_args()
    print(f"load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        if a.count:
            for f, (n, again, zero) in counts(s).items():
                print(f"- {s}, {f}: {n} calls a flight, {again} of them an argument of the "
                      f"last 64, {zero} of zero")
            continue
        loops, args, kwargs = builds(s)
        if a.callgrind:
            loops[a.callgrind].sampled(*args, **kwargs)
            continue
        report_flights(s, timed_flights(loops, args, kwargs, a.rounds), a.rounds,
                       "of the shipped C's")
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

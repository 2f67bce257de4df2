"""Lockstep C (``quadland_symbolic.codegen.lockstep``) compiled and called, for the tests
and ``benchmarks/bench_lockstep.py``.

:func:`filter_flight` flies the navigation filter's branch-free step (the function of
``generated/estimator_step.c``) through CasADi on packets due, late, stale, from the
future, not finite and outliers (as ``tests/test_estimator_switch.py`` does), and
returns each call's arguments; :func:`interleave` and :func:`deinterleave` convert
between one array per instance and the lockstep layout (nonzero ``k`` of instance ``j``
at ``W * k + j``).
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
from filter_packets import packet

from quadland_symbolic.codegen.registry import BY_NAME, ESTIMATOR_SIZES
from quadland_symbolic.landing.estimator import estimator_init_function, estimator_memory
from quadland_symbolic.landing.navigation import ESTIMATOR_DEFAULTS, NAV_PACKETS, estimator_params

ROOT = Path(__file__).resolve().parent.parent
DT = 0.004
#: Flags of every build: C99 (no fused multiply-add contraction) and said so; a library.
BASE_FLAGS = ("-std=c99", "-ffp-contract=off", "-fPIC", "-shared")
#: The warnings the lockstep C compiles without.
STRICT = ("-pedantic", "-Wall", "-Wextra", "-Werror")
PD = ctypes.POINTER(ctypes.c_double)


def filter_step():
    """The filter's step at its flight sizes, the Function ``generated/estimator_step.c`` is."""
    return BY_NAME["estimator_step"].function(0)


def filter_flight(seed: int, steps: int) -> list[list[np.ndarray]]:
    """``steps`` calls' arguments of the filter's step, flown from a random start."""
    rng = np.random.default_rng(seed)
    step = filter_step()
    sizes = dict(ESTIMATOR_SIZES)
    p = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    x0 = np.r_[0.3, -0.2, 3.0, 0.2, -0.1, -0.3, 0.5, 0.1, 0.0, np.zeros(12)]
    x0[:18] += rng.normal(size=18) * 0.05
    P0 = np.r_[[0.5] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.04] * 3, [0.01] * 3]
    mem = np.asarray(estimator_init_function(**sizes)(
        x0, P0, [0, 0, 0.3, 0, 0, 0.05, 0, 0, 0], 7.0)).ravel()
    h = estimator_memory(**sizes).slice("t_h")
    calls, t = [], 7.0
    for _ in range(steps):
        t += DT
        pkts = [packet(layout, rng, t, mem[h][0]) for layout in NAV_PACKETS]
        imu = np.r_[0.02, -0.01, 0.5, 0.0, 0.0, 9.8, rng.normal(size=3) * 0.01]
        args = [mem, imu, *pkts, p, np.array([DT]), np.array([t])]
        calls.append([np.ascontiguousarray(a, dtype=np.float64) for a in args])
        mem = np.asarray(step(*args)[0]).ravel()
    return calls


def interleave(per_instance: list[np.ndarray]) -> np.ndarray:
    """One input of W instances in the lockstep layout (``W * k + j``)."""
    return np.ascontiguousarray(np.stack(per_instance, axis=1).ravel())


def deinterleave(lanes: np.ndarray, width: int) -> list[np.ndarray]:
    """The W instances' arrays of one lockstep output."""
    return [lanes.reshape(-1, width)[:, j].copy() for j in range(width)]


def compile_shared(files: dict[str, str], out: Path, flags=("-O2",)) -> ctypes.CDLL:
    """The ``.c`` files of ``files`` compiled and linked into ``out`` with ``flags``."""
    cc = shutil.which("cc") or shutil.which("gcc")
    out.parent.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        (out.parent / name).write_text(text)
    units = [str(out.parent / n) for n in files if n.endswith(".c")]
    subprocess.run([cc, *BASE_FLAGS, *flags, "-I", str(out.parent), "-o", str(out), *units,
                    "-lm"], check=True)
    return ctypes.CDLL(str(out))


def call_lockstep(fn_c, fn, width: int, lane_args: list[list[np.ndarray]]) -> list[list]:
    """The lockstep C ``fn_c`` on W instances' arguments; each instance's outputs."""
    ins = [interleave([a[i] for a in lane_args]) for i in range(fn.n_in())]
    outs = [np.full(fn.nnz_out(i) * width, np.nan) for i in range(fn.n_out())]
    arg = (PD * len(ins))(*[a.ctypes.data_as(PD) for a in ins])
    res = (PD * len(outs))(*[r.ctypes.data_as(PD) for r in outs])
    fn_c(arg, res)
    per = [deinterleave(r, width) for r in outs]
    return [[per[i][j] for i in range(fn.n_out())] for j in range(width)]


def call_casadi_c(fn_c, fn, args: list[np.ndarray]) -> list[np.ndarray]:
    """CasADi's scalar C (``int f(arg, res, iw, w, mem)``) on one instance."""
    outs = [np.full(fn.nnz_out(i), np.nan) for i in range(fn.n_out())]
    arg = (PD * fn.n_in())(*[np.ascontiguousarray(a).ctypes.data_as(PD) for a in args])
    res = (PD * fn.n_out())(*[r.ctypes.data_as(PD) for r in outs])
    w = np.zeros(max(fn.sz_w(), 1))
    iw = np.zeros(max(fn.sz_iw(), 1), dtype=np.int32)      # casadi_int is int
    assert fn_c(arg, res, iw.ctypes.data_as(ctypes.c_void_p), w.ctypes.data_as(PD), 0) == 0
    return outs


def bits(v) -> np.ndarray:
    """The bits of a float64 array (equal bits: the same value, zero's sign and NaN)."""
    return np.asarray(v, dtype=np.float64).ravel().view(np.uint64)

"""The batch entry over the lockstep C (``quadland_symbolic.codegen.lockstep_batch``).

Each active run's outputs against two independent evaluations of one call: CasADi's
scalar C of the same Function, and, for the navigation filter, CasADi's own evaluation
of the runtime's filter (the sensed loop's ``sensed_filter`` and ``sensed_finish``
stages: the conditional step, an MX Function of ``Switch``es, whose bits are the
branch-free step's, ``tests/test_estimator_switch.py``); bit for bit. An inactive run's
arguments are not read and its outputs not written; NULL arguments are zeros and NULL
results not wanted, as in CasADi's calling convention.
"""

from __future__ import annotations

import ctypes
import subprocess
import sys
import textwrap

import casadi as ca
import numpy as np
import pytest
from lockstep_c import (
    PD,
    ROOT,
    STRICT,
    bits,
    call_casadi_c,
    compile_shared,
    filter_flight,
    filter_step,
)

from quadland_symbolic.codegen.lockstep_batch import lockstep_batch_c
from quadland_symbolic.landing.estimator import FLIGHT_COUPLING, FLIGHT_DEPTH, N_HIST
from quadland_symbolic.landing.estimator_switch import conditional_step_stages

NAN = float("nan")


def _call_batch(fn_c, fn, per_run: list, active: list[int]) -> list[list[np.ndarray]]:
    """The batch entry on each run's arguments (None: a NULL pointer); each run's outputs
    (NaN where not written)."""
    width = len(per_run)
    keep = []

    def ptr(a):
        if a is None:
            return None
        keep.append(a := np.ascontiguousarray(a, dtype=np.float64))
        return a.ctypes.data_as(PD)

    outs = [[np.full(fn.nnz_out(i), NAN) for i in range(fn.n_out())] for _ in range(width)]
    arg = (PD * (fn.n_in() * width))(*[ptr(a) for args in per_run for a in args])
    res = (PD * (fn.n_out() * width))(*[o.ctypes.data_as(PD) for run in outs for o in run])
    fn_c(arg, res, (ctypes.c_int * width)(*active))
    return outs


def _runtime_filter():
    """The runtime's filter, its two stages composed (CasADi's evaluation, MX)."""
    fused, finish = conditional_step_stages(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    ins = [fused.mx_in(i) for i in range(fused.n_in())]
    between = dict(zip(fused.name_out(), fused.call(ins), strict=True))
    named = dict(zip(fused.name_in(), ins, strict=True))
    return ca.Function("runtime_filter", ins, finish.call(
        [named.get(n, between.get(n)) for n in finish.name_in()]))


@pytest.fixture(scope="module")
def filter_batch(tmp_path_factory):
    """The flight's filter's batch entry at W = 4 with CasADi's scalar C, one library."""
    tmp = tmp_path_factory.mktemp("batch")
    files = {"batch.c": lockstep_batch_c(filter_step(), 4, name="filter_batch"),
             **{f"estimator_step.{ext}": (ROOT / "generated" / f"estimator_step.{ext}")
                .read_text() for ext in ("c", "h")}}
    return compile_shared(files, tmp / "libbatch.so", ("-O2", *STRICT))


@pytest.mark.slow
def test_the_filter_run_by_run_bit_for_bit_with_runs_finished(filter_batch):
    """Four flights of the filter, the third finished after 8 calls and the first after
    16: every active run's outputs are the scalar C's and the runtime filter's bits, a
    finished run's are not written."""
    fn, runtime = filter_step(), _runtime_filter()
    flights = [filter_flight(seed, 24) for seed in (11, 12, 13, 14)]
    for k in range(24):
        active = [int(k < 16), 1, int(k < 8), 1]
        got = _call_batch(filter_batch.filter_batch, fn, [f[k] for f in flights], active)
        for j, on in enumerate(active):
            if not on:
                assert all(np.isnan(o).all() for o in got[j])
                continue
            want_c = call_casadi_c(filter_batch.ql_casadi_estimator_step, fn, flights[j][k])
            want_rt = [np.asarray(v).ravel() for v in runtime(*flights[j][k])]
            for g, c, r in zip(got[j], want_c, want_rt, strict=True):
                assert np.array_equal(bits(g), bits(c)) and np.array_equal(bits(g), bits(r))
        assert not np.array_equal(got[1][0], got[3][0])     # the lanes are their own


@pytest.mark.parametrize("width", [1, 2, 4, 8])
def test_pointers_masks_and_nulls_worked_by_hand(tmp_path, width):
    """``f(a, b) = (a[1] b, a[0] - b, 2 a)`` (``a`` of 11 values: whole blocks of W values
    and a remainder moved) for runs j with a = (j + 1) (1, 10, 3, 4, ..., 11) and b = 3,
    run 0's b NULL (zero), the last run inactive (its pointers NULL: never read), run
    1's second result NULL (not wanted)."""
    a, b = ca.SX.sym("a", 11), ca.SX.sym("b")
    fn = ca.Function("f", [a, b], [a[1] * b, a[0] - b, 2 * a])
    lib = compile_shared({"f.c": lockstep_batch_c(fn, width)}, tmp_path / "libf.so",
                         ("-O2", *STRICT))
    base = np.r_[1.0, 10.0, 3.0:12.0]
    runs = [[(j + 1) * base, None if j == 0 else np.array([3.0])] for j in range(width)]
    active = [1] * width
    if width > 1:
        runs[-1], active[-1] = [None, None], 0
    outs = [[np.full(1, NAN), np.full(1, NAN), np.full(11, NAN)] for _ in range(width)]
    res = [o.ctypes.data_as(PD) for run in outs for o in run]
    if width > 1:
        res[4] = None
    arg = [None if x is None else x.ctypes.data_as(PD) for r in runs for x in r]
    getattr(lib, f"f_batch{width}")((PD * len(arg))(*arg), (PD * len(res))(*res),
                                    (ctypes.c_int * width)(*active))
    for j in range(width):
        bj = 0.0 if j == 0 else 3.0
        want = [[10.0 * (j + 1) * bj], [j + 1.0 - bj], 2 * (j + 1) * base]
        if width > 1 and j == 1:
            want[1] = [NAN]
        if width > 1 and j == width - 1:
            want = [[NAN], [NAN], np.full(11, NAN)]
        assert np.array_equal(np.concatenate(outs[j]), np.concatenate(want), equal_nan=True)


def test_no_run_active_writes_nothing(tmp_path):
    x = ca.SX.sym("x")
    lib = compile_shared({"g.c": lockstep_batch_c(ca.Function("g", [x], [2 * x]), 2)},
                         tmp_path / "libg.so", ("-O2", *STRICT))
    out = np.full(2, NAN)
    lib.g_batch2((PD * 2)(None, None), (PD * 2)(*[out[i:].ctypes.data_as(PD)
                                                   for i in range(2)]),
                 (ctypes.c_int * 2)(0, 0))
    assert np.isnan(out).all()



def _mixing(n: int = 37) -> ca.Function:
    """``y[k] = a[k] b - (k + 1) a[k + 1 mod n]`` and ``z = b c`` (``c`` lower triangular,
    3 nonzeros): every output value mixes two of ``a``'s, so a permutation of a block
    made when gathering and undone when scattering still shows."""
    a, b, c = ca.SX.sym("a", n), ca.SX.sym("b"), ca.SX.sym("c", ca.Sparsity.lower(2))
    y = ca.vertcat(*[a[k] * b - (k + 1) * a[(k + 1) % n] for k in range(n)])
    return ca.Function("mix", [a, b, c], [y, b * c])


@pytest.mark.parametrize("width", [1, 2, 4, 8, 16])
def test_every_width_against_casadi_with_non_finite_lanes_shared_and_in_place(tmp_path, width):
    """W runs of :func:`_mixing` (37 values: whole blocks and a remainder at every W)
    against CasADi's own evaluation, bit for bit: run 1 with a NaN, infinities and
    ``b = -0.0`` (the other lanes' bits untouched), every run's ``c`` one shared buffer,
    run 0's ``y`` written over its own ``a`` (every input is read before any output is
    written), the last of four or more inactive (its buffers neither read into a result
    nor written)."""
    fn, rng = _mixing(), np.random.default_rng(width)
    lib = compile_shared({"m.c": lockstep_batch_c(fn, width)}, tmp_path / "libm.so",
                         ("-O2", *STRICT))
    c = np.array([0.5, -1.25, 3.0])
    runs = [[rng.normal(size=37), rng.normal(size=1), c] for _ in range(width)]
    if width > 1:
        runs[1][0][[5, 20, 30]], runs[1][1][0] = [NAN, np.inf, -np.inf], -0.0
    active = [int(not (width >= 4 and j == width - 1)) for j in range(width)]
    want = [[np.asarray(v.nonzeros()) for v in fn.call([ca.DM(a), ca.DM(b),
                                                         ca.DM(ca.Sparsity.lower(2), cc)])]
            for a, b, cc in runs]
    before = [[x.copy() for x in r] for r in runs]
    outs = [[np.full(37, NAN), np.full(3, NAN)] for _ in range(width)]
    outs[0][0] = runs[0][0]                                  # y over run 0's a
    arg = [x.ctypes.data_as(PD) for r in runs for x in r]
    res = [o.ctypes.data_as(PD) for r in outs for o in r]
    getattr(lib, f"mix_batch{width}")((PD * len(arg))(*arg), (PD * len(res))(*res),
                                      (ctypes.c_int * width)(*active))
    for j in range(width):
        if not active[j]:
            assert all(np.isnan(o).all() for o in outs[j])
            assert all(np.array_equal(bits(x), bits(y))
                       for x, y in zip(runs[j], before[j], strict=True))
            continue
        for g, w in zip(outs[j], want[j], strict=True):
            assert np.array_equal(bits(g), bits(w)), (j, g, w)
    assert np.array_equal(bits(c), bits(before[0][2]))       # the shared input kept


def test_an_inactive_runs_pointers_are_never_dereferenced(tmp_path):
    """Run 1 of 4 inactive with every pointer invalid (address 8): the call, in a child
    process, neither reads nor writes through them (it would fault) and the active runs'
    results are CasADi's."""
    fn = _mixing()
    compile_shared({"m.c": lockstep_batch_c(fn, 4)}, tmp_path / "libm.so", ("-O2", *STRICT))
    child = textwrap.dedent(f"""
        import ctypes, numpy as np
        PD = ctypes.POINTER(ctypes.c_double)
        lib, bad = ctypes.CDLL({str(tmp_path / "libm.so")!r}), ctypes.cast(8, PD)
        runs = [[np.arange(37.0) + j, np.array([2.0]), np.ones(3)] for j in range(4)]
        outs = [[np.zeros(37), np.zeros(3)] for j in range(4)]
        arg = [bad if j == 1 else x.ctypes.data_as(PD) for j, r in enumerate(runs) for x in r]
        res = [bad if j == 1 else o.ctypes.data_as(PD) for j, r in enumerate(outs) for o in r]
        lib.mix_batch4((PD * 12)(*arg), (PD * 8)(*res), (ctypes.c_int * 4)(1, 0, 1, 1))
        np.save({str(tmp_path / "y.npy")!r}, np.array([outs[j][0] for j in (0, 2, 3)]))
        """)
    subprocess.run([sys.executable, "-c", child], check=True, timeout=60)
    for y, j in zip(np.load(tmp_path / "y.npy"), (0, 2, 3), strict=True):
        want = fn(np.arange(37.0) + j, 2.0, ca.DM(ca.Sparsity.lower(2), np.ones(3)))[0]
        assert np.array_equal(bits(y), bits(np.asarray(want).ravel()))


@pytest.mark.parametrize("case", ["no input", "empty inputs and outputs"])
def test_functions_without_values_compile_as_iso_c(tmp_path, case):
    """A Function without inputs, and one whose inputs and outputs are all empty: the
    entry compiles with ``-pedantic-errors`` (no zero-length arrays) and gives CasADi's
    values."""
    e = ca.SX.sym("e", 0)
    fn = (ca.Function("k", [], [ca.SX(3.0)]) if case == "no input"
          else ca.Function("k", [e, e[:0]], [ca.SX(0, 1)]))
    lib = compile_shared({"k.c": lockstep_batch_c(fn, 2)}, tmp_path / "libk.so",
                         ("-O2", "-pedantic-errors"))
    args = [[np.zeros(0)] * fn.n_in() for _ in range(2)]
    got = _call_batch(lib.k_batch2, fn, args, [1, 1])
    for j in range(2):
        want = fn.call([ca.DM(a) for a in args[j]])
        for g, w in zip(got[j], want, strict=True):
            assert np.array_equal(bits(g), bits(np.asarray(w.nonzeros())))

"""W instances of an SX Function in lockstep (``quadland_symbolic.codegen.lockstep``).

Each lane of the lockstep C against two references it does not share code with:
CasADi's C of the Function (for the filter, the committed ``generated/estimator_step.c``),
bit for bit, and CasADi's own evaluation of it (its virtual machine; the same bits but
for the NaNs it makes itself, whose sign differs from libm's), for
W = 1, 4 and 8: every operation the writer knows on values that include signed zeros,
infinities and NaNs, and the navigation filter's step over flights of packets due,
late, stale, from the future, not finite and outliers.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from lockstep_c import (
    PD,
    ROOT,
    STRICT,
    bits,
    call_casadi_c,
    call_lockstep,
    compile_shared,
    filter_flight,
    filter_step,
)

from quadland_symbolic.codegen.lockstep import (
    LANE_OPS,
    MINMAX_OPS,
    VECTOR_OPS,
    lockstep_c,
    lockstep_supported,
)

WIDTHS = (1, 4, 8)
SPECIAL = (0.0, -0.0, 1.0, -1.0, 0.5, -2.5, 3.0, math.inf, -math.inf, math.nan, 1e-310, 1e300)


def _every_op() -> ca.Function:
    """A Function using every operation the writer knows, on two inputs."""
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    xy = x * y
    e = [x + y, x - y, x * y, x / y, -x, x ** 2, 2 * x, 1 / x, x < y, x <= y, x == y,
         x != y, ca.logic_not(x), ca.logic_and(x, y), ca.logic_or(x, y),
         ca.if_else(x, y, 0), ca.if_else(x < y, ca.sin(x), ca.cos(y)), ca.fabs(x),
         ca.sign(x), ca.sqrt(x), ca.exp(x), ca.log(x), ca.tan(x), ca.asin(x), ca.acos(x),
         ca.atan(x), ca.sinh(x), ca.cosh(x), ca.tanh(x), ca.floor(x), ca.ceil(x), ca.erf(x),
         ca.expm1(x), ca.log1p(x), ca.atan2(x, y), x ** y, x ** 3.5, ca.fmin(x, y),
         ca.fmax(x, y), ca.fmod(x, y), ca.copysign(x, y), ca.hypot(x, y),
         -0.0 * x + ca.DM(-0.0), ca.inf + x, 0.1 * x - 1e-300,
         ca.sin(xy) - ca.cos(xy)]                 # a sine and cosine paired in one loop
    assert str(e[FMIN_FMAX[0]]) == "fmin(x,y)" and str(e[FMIN_FMAX[1]]) == "fmax(x,y)"
    return ca.Function("every_op", [x, y], [ca.vertcat(*e)], ["x", "y"], ["r"])


#: The outputs fmin(x, y) and fmax(x, y) of :func:`_every_op`. Of +0.0 and -0.0, C leaves
#: unspecified which they return, and GCC takes the two as commutative (it may swap the
#: operands of the call): on that tie neither CasADi's C nor the lockstep C is
#: reproducible from one compilation to the next, and the sign of their zero is not
#: compared (glibc returns its first operand on a tie, and GCC swapped the scalar C's).
FMIN_FMAX = (37, 38)


def _tie(a: float, b: float) -> bool:
    return a == 0.0 and b == 0.0 and math.copysign(1, a) != math.copysign(1, b)


@pytest.fixture(scope="module")
def every_op_libs(tmp_path_factory):
    fn = _every_op()
    tmp = tmp_path_factory.mktemp("lockstep_ops")
    lock = compile_shared({"lock.c": "\n".join(lockstep_c(fn, w) for w in WIDTHS)},
                          tmp / "lock" / "liblock.so", ("-O2", *STRICT))
    cwd = os.getcwd()
    try:
        os.chdir(tmp)
        fn.generate("every_op.c")
    finally:
        os.chdir(cwd)
    scalar = compile_shared({"every_op.c": (tmp / "every_op.c").read_text()},
                            tmp / "scalar" / "libscalar.so", ("-O2", "-w"))
    return fn, lock, scalar


def test_the_test_function_uses_every_operation_the_writer_knows():
    fn = _every_op()
    used = {fn.instruction_id(k) for k in range(fn.n_instructions())}
    # CasADi's SX algorithms copy a value by OP_INPUT/OP_OUTPUT, never by OP_ASSIGN
    assert (set(VECTOR_OPS) | set(MINMAX_OPS) | set(LANE_OPS)) - used == {ca.OP_ASSIGN}
    assert lockstep_supported(fn) == []
    assert lockstep_c(fn, 4).count("= cos(x_); }") == 1


@pytest.mark.parametrize("width", WIDTHS)
def test_every_operation_lane_by_lane_bit_for_bit(every_op_libs, width):
    fn, lock, scalar = every_op_libs
    rng = np.random.default_rng(width)
    pairs = [(a, b) for a in SPECIAL for b in SPECIAL]
    pairs += [tuple(v) for v in rng.normal(size=(64, 2)) * rng.choice((1e-3, 1, 30), (64, 2))]
    pairs += [(0.0, 0.0)] * (-len(pairs) % width)
    lock_c = getattr(lock, f"every_op_lockstep{width}")
    for start in range(0, len(pairs), width):
        lanes = [[np.array([a]), np.array([b])] for a, b in pairs[start:start + width]]
        got = call_lockstep(lock_c, fn, width, lanes)
        for j, args in enumerate(lanes):
            want_vm = np.asarray(fn(*args)).ravel()
            want_c = call_casadi_c(scalar.every_op, fn, args)[0]
            g = got[j][0]
            if _tie(*pairs[start + j]):
                assert set(g[list(FMIN_FMAX)]) == set(want_c[list(FMIN_FMAX)]) == {0.0}
                g, want_c, want_vm = (np.delete(v, FMIN_FMAX) for v in (g, want_c, want_vm))
            assert np.array_equal(bits(g), bits(want_c)), (pairs[start + j], g, want_c)
            # CasADi's machine makes some NaNs of its own (log(-1): +NaN, libm's -NaN)
            assert np.all((bits(want_vm) == bits(want_c)) | (np.isnan(want_vm) &
                                                             np.isnan(want_c)))


def _filter_lib(tmp: Path, width: int, flags) -> object:
    files = {"lock.c": lockstep_c(filter_step(), width, name="filter_lockstep"),
             **{f"estimator_step.{ext}": (ROOT / "generated" / f"estimator_step.{ext}")
                .read_text() for ext in ("c", "h")}}
    return compile_shared(files, tmp / "libfilter.so", (*flags, *STRICT))


def _avx2() -> bool:
    return " avx2" in Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").exists() \
        else False


@pytest.mark.slow
@pytest.mark.parametrize("width, flags", [(1, ("-O2",)), (4, ("-O2",)), (8, ("-O2",)),
                                          (4, ("-O3", "-mavx2"))])
def test_the_filter_step_lane_by_lane_bit_for_bit(tmp_path, width, flags):
    """The navigation filter's step, W flights at once, against the committed scalar C."""
    if "-mavx2" in flags and not _avx2():
        pytest.skip("the CPU has no AVX2")
    fn = filter_step()
    lib = _filter_lib(tmp_path, width, flags)
    flights = [filter_flight(seed, 25) for seed in range(width)]
    moved = 0
    for k in range(25):
        lanes = [flights[j][k] for j in range(width)]
        got = call_lockstep(lib.filter_lockstep, fn, width, lanes)
        for j, args in enumerate(lanes):
            want_c = call_casadi_c(lib.ql_casadi_estimator_step, fn, args)
            want_vm = [np.asarray(v).ravel() for v in fn(*args)]
            for g, c, v in zip(got[j], want_c, want_vm, strict=True):
                assert np.array_equal(bits(g), bits(c)) and np.array_equal(bits(c), bits(v))
        if width > 1:       # the lanes are different flights: a lane mixed up would show
            assert not np.array_equal(got[0][0], got[1][0])
        moved += int(np.any(got[0][0] != lanes[0][0]))
    assert moved == 25      # the memory moved in every step


def test_what_it_refuses():
    x = ca.SX.sym("x")
    with pytest.raises(ValueError, match="not an SX Function"):
        m = ca.MX.sym("m")
        lockstep_c(ca.Function("m", [m], [2 * m]), 4)
    with pytest.raises(ValueError, match="width must be 1, 2, 4, 8 or 16, got 3"):
        lockstep_c(ca.Function("f", [x], [2 * x]), 3)
    odd = ca.Function("odd", [x], [ca.erfinv(x)])
    assert lockstep_supported(odd) == ["OP_ERFINV"]
    with pytest.raises(ValueError, match="odd uses OP_ERFINV"):
        lockstep_c(odd, 4)
    with pytest.raises(ValueError, match="NaN constant"):
        lockstep_c(ca.Function("n", [x], [x * ca.DM(math.nan)]), 2)


def test_the_layout_is_value_by_value(tmp_path):
    """Nonzero k of instance j at W * k + j, in and out (worked by hand for W = 2)."""
    a, b = ca.SX.sym("a", 2), ca.SX.sym("b")
    fn = ca.Function("swap", [a, b], [ca.vertcat(a[1] * b, a[0])])
    lib = compile_shared({"swap.c": lockstep_c(fn, 2)}, tmp_path / "libswap.so",
                         ("-O2", *STRICT))
    a_in = np.array([1.0, 10.0, 2.0, 20.0])          # a = (1, 2) and (10, 20)
    b_in = np.array([3.0, 5.0])                      # b = 3 and 5
    out = np.zeros(4)
    lib.swap_lockstep2((PD * 2)(a_in.ctypes.data_as(PD), b_in.ctypes.data_as(PD)),
                       (PD * 1)(out.ctypes.data_as(PD)))
    assert out.tolist() == [6.0, 100.0, 1.0, 10.0]   # (2 * 3, 20 * 5), then (1, 10)

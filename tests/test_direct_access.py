"""The simulators' SX bodies read and write through pointers taken once a call (issue 20).

``quadland_symbolic.codegen.simulator.direct_access`` rewrites CasADi's ``a=arg[i]?
arg[i][j] : 0;`` and ``if (res[i]!=0) res[i][j]=a;`` as reads of ``ql_a<i>[j]`` and writes
of ``ql_r<i>[j]``, the pointers taken once a call (zeros for a null argument, a sink for a
null result). The reference is CasADi's own C, compiled beside it: both forms of the same
Function are called on the same values, special ones included, with every combination of
null arguments and results, and compared bit for bit where a result is a number; a NaN is
a NaN in both, its payload and sign left to the compiler (GCC commutes a product's operands
and folds ``x * 1.0`` to ``x``, which keeps a signalling NaN's payload, in any compilation;
the flights stop at the first value that is not finite). And CasADi's own evaluation where
every pointer is given.
"""

from __future__ import annotations

import ctypes
import itertools
import struct

import casadi as ca
import numpy as np
import pytest

from quadland.engine import build
from quadland_symbolic.codegen import simulator

pytestmark = pytest.mark.skipif(not build.have_compiler(), reason="needs a C compiler")


def _double(bits: int) -> float:
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


#: Signed zeros, infinities, NaNs (a payload, a signalling one), subnormals, extremes.
SPECIAL = [0.0, -0.0, 1.0, -1.5, np.inf, -np.inf, np.nan, _double(0x7FF8000000000123),
           _double(0x7FF0000000000001), 5e-324, -5e-324, 1.7976931348623157e308, 0.1, 3.0]

#: Each form's entry: ``n`` calls, each with its own null pattern of the three arguments
#: (bit i of ``mask_in`` set: ``arg[i]`` null) and two results.
WRAP = """\
#include "{name}.h"
void call_{name}(const double* x, const double* y, const double* z, const long* mask_in,
                 const long* mask_out, double* r0, double* r1, long n)
{{
    for (long k = 0; k < n; ++k) {{
        const casadi_real* arg[3] = {{mask_in[k] & 1 ? 0 : x + 3 * k,
                                      mask_in[k] & 2 ? 0 : y + 2 * k,
                                      mask_in[k] & 4 ? 0 : z + k}};
        casadi_real* res[2] = {{mask_out[k] & 1 ? 0 : r0 + 4 * k,
                               mask_out[k] & 2 ? 0 : r1 + 2 * k}};
        {name}(arg, res, 0, 0, 0);
    }}
}}
"""


def _function() -> ca.Function:
    """Three arguments (3, 2, 1), two results (4, 2), with libm, products, zeros, a
    comparison and a branch: zeros in place of a null argument change every result."""
    x, y, z = ca.SX.sym("x", 3), ca.SX.sym("y", 2), ca.SX.sym("z")
    r0 = ca.vertcat(x[0] * y[1] + ca.sin(x[2]), ca.if_else(z > x[1], y[0], -x[0]),
                    ca.fmax(x[0], z) - 0.0, x[1] / (y[0] + 1.5))
    r1 = ca.vertcat(ca.exp(-z) * x[2], ca.sqrt(ca.fabs(y[1])) + z)
    return ca.Function("da", [x, y, z], [r0, r1], ["x", "y", "z"], ["r0", "r1"])


def _library(monkeypatch, direct: bool, name: str):
    monkeypatch.setattr(simulator, "DIRECT_ACCESS", direct)
    files, _ = simulator._emit(name, _function())
    files = {**files, "wrap.c": WRAP.format(name=name)}
    lib = ctypes.CDLL(str(build.build_library(files, (f"{name}.c", "wrap.c"),
                                              name=f"lib{name}", strict=False)))
    return files[f"{name}.c"], getattr(lib, f"call_{name}")


def _cases(seed: int = 7):
    """Every null pattern of the arguments and results, each on special and random
    values: the inputs, the masks and the results' arrays filled with a marker."""
    rng = np.random.default_rng(seed)
    masks = list(itertools.product(range(8), range(4)))
    per = 40
    n = len(masks) * per
    pool = np.array(SPECIAL + list(rng.normal(0, 3, 50)))
    x, y, z = (rng.choice(pool, size=n * k) for k in (3, 2, 1))
    mask_in = np.repeat([m[0] for m in masks], per).astype(np.int64)
    mask_out = np.repeat([m[1] for m in masks], per).astype(np.int64)
    return n, x, y, z, mask_in, mask_out


def _call(fn, n, x, y, z, mask_in, mask_out):
    marker = _double(0x7FF4DEADBEEF0001)
    r0, r1 = np.full(4 * n, marker), np.full(2 * n, marker)
    real, long_ = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_long)
    fn(*(a.ctypes.data_as(real) for a in (x, y, z)),
       *(m.ctypes.data_as(long_) for m in (mask_in, mask_out)),
       r0.ctypes.data_as(real), r1.ctypes.data_as(real), ctypes.c_long(n))
    return r0.view(np.uint64), r1.view(np.uint64)


def test_the_direct_form_gives_casadi_s_bits_null_pointers_included(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    plain_c, plain = _library(monkeypatch, False, "t_da_plain")
    direct_c, direct = _library(monkeypatch, True, "t_da_direct")
    assert "arg[0]? arg[0][0] : 0;" in plain_c and "if (res[1]!=0) res[1][1]=" in plain_c
    assert "]? arg[" not in direct_c and "if (res[" not in direct_c
    assert "const casadi_real* const ql_a2 = arg[2] ? arg[2] : ql_z;" in direct_c
    assert "casadi_real* const ql_r1 = res[1] ? res[1] : ql_s;" in direct_c
    case = _cases()
    got, want = _call(direct, *case), _call(plain, *case)
    for g, w in zip(got, want, strict=True):
        nan = np.isnan(w.view(np.float64))
        assert np.array_equal(np.isnan(g.view(np.float64)), nan)
        assert np.array_equal(g[~nan], w[~nan]) and (~nan).sum() > 0.3 * nan.size
    # the nulls matter: a null argument is zeros, a null result is left untouched
    n, x, y, z, mask_in, mask_out = case
    marker = np.float64(_double(0x7FF4DEADBEEF0001)).view(np.uint64)
    untouched = np.repeat(mask_out & 1 != 0, 4)
    assert untouched.any() and (got[0][untouched] == marker).all()
    assert (got[0][~untouched] != marker).all()
    # where every pointer is given, CasADi's own evaluation, bit for bit
    f = _function()
    compared = 0
    for k in np.flatnonzero((mask_in == 0) & (mask_out == 0))[:80]:
        r0, r1 = f(x[3 * k:3 * k + 3], y[2 * k:2 * k + 2], z[k])
        for want_k, got_k in ((r0, got[0][4 * k:4 * k + 4]), (r1, got[1][2 * k:2 * k + 2])):
            want_k = np.asarray(want_k, dtype=float).ravel()
            number = ~np.isnan(want_k)
            assert np.array_equal(np.isnan(got_k.view(np.float64)), ~number)
            assert np.array_equal(want_k[number].view(np.uint64), got_k[number])
            compared += int(number.sum())
    assert compared > 200


def test_mx_bodies_and_large_results_are_left_as_they_are(monkeypatch):
    """An MX body's reads (``w = arg[i] ? arg[i][j] : 0;``) and a body whose result is over
    the sink's limit keep CasADi's form; the text is otherwise unchanged."""
    x = ca.MX.sym("x", 2)
    u = ca.SX.sym("u", 2)
    inner = ca.Function("inner", [u], [u * 2])
    files, _ = simulator._emit("t_da_mx", ca.Function("outer", [x], [inner(x) + x[0]]))
    c = files["t_da_mx.c"]
    assert "ql_" not in c.split("static int casadi_f0(")[1]       # the MX body
    v = ca.SX.sym("v")
    big = ca.Function("big", [v], [v * ca.DM.ones(9)])
    monkeypatch.setattr(simulator, "DIRECT_SINK_MAX", 8)
    text = simulator._emit("t_da_big", big)[0]["t_da_big.c"]
    assert "ql_a0" in text and "ql_r0" not in text and "if (res[0]!=0) res[0][8]=" in text
    plain = "int f(void) { return 0; }\n"
    assert simulator.direct_access(plain) == plain

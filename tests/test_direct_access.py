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


# --- The review's cases (rev-flightcost, twentieth): aliasing, call nodes, sparsity, levels.

def _aliasing_function() -> ca.Function:
    """CasADi's SX body of this writes ``a`` (all of it) before it reads ``x[2]`` and
    ``x[1]``, reads a sparse argument's third nonzero, writes a constant, a copy of ``x``, a
    result of no elements and a sparse one: called with ``res[0] == arg[0]`` the later reads
    see the written values."""
    x, y = ca.SX.sym("x", 3), ca.SX.sym("y", ca.Sparsity.lower(2))
    return ca.Function("alias", [x, y], [
        ca.vertcat(2 * x[0], x[0] + 1, 3.0), ca.vertcat(x[2] * x[1], y.nz[2]),
        ca.DM.zeros(0, 1), x, ca.sparsify(ca.vertcat(0, x[1], 0))],
        ["x", "y"], ["a", "b", "e", "p", "s"])


def _call_node_function() -> ca.Function:
    """An SX function calling another through CasADi's call node (``never_inline``): its
    body sets ``arg[n_in]`` and ``res[n_out]`` for the callee and reads the callee's
    results from ``w``."""
    u = ca.SX.sym("u", 2)
    g = ca.Function("g", [u], [ca.sin(u) * 2 - u[::-1]], {"never_inline": True})
    x = ca.SX.sym("x", 3)
    return ca.Function("callnode", [x], [g(x[:2]) + x[2], g(x[1:]) * x[0]], ["x"], ["o", "q"])


def _direct_library(monkeypatch, f: ca.Function, direct: bool, name: str, opt: str = "-O2"):
    """``f``'s C, rewritten or not, built at ``opt``; its entry with CasADi's signature."""
    monkeypatch.setattr(simulator, "DIRECT_ACCESS", direct)
    files, fn = simulator._emit(name, f)
    lib = ctypes.CDLL(str(build.build_library(files, (f"{name}.c",), opt=opt,
                                              name=f"lib{name}{opt[1:]}", strict=False)))
    entry = getattr(lib, name)
    entry.restype = ctypes.c_int
    return files[f"{name}.c"], entry, fn


def _raw_call(entry, fn: ca.Function, args: list, res: list) -> None:
    """``entry(arg, res, iw, w, 0)`` with CasADi's work sizes; ``None`` is a null pointer,
    an array its data (several may share one buffer)."""
    real_p = ctypes.POINTER(ctypes.c_double)
    arg = (real_p * max(fn.sz_arg(), 1))(*(
        ctypes.cast(a.ctypes.data, real_p) if a is not None else real_p() for a in args))
    out = (real_p * max(fn.sz_res(), 1))(*(
        ctypes.cast(r.ctypes.data, real_p) if r is not None else real_p() for r in res))
    iw = (ctypes.c_longlong * max(fn.sz_iw(), 1))()
    w = (ctypes.c_double * max(fn.sz_w(), 1))()
    assert entry(arg, out, iw, w, 0) == 0


def test_an_output_aliasing_an_input_reads_what_was_written_in_both_forms(monkeypatch,
                                                                            tmp_path):
    """``res[0] == arg[0]``: CasADi's body writes ``a`` over ``x`` and then reads ``x[1]``,
    ``x[2]``; the pointers taken once a call are the same memory, so the direct form reads
    the written values as CasADi's does. Against the hand derivation (``b[0] = 3 (x0 + 1)``,
    ``p = (x0, x0 + 1, 3)``), CasADi's compiled C and, unaliased, CasADi's own evaluation."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    f = _aliasing_function()
    plain_c, plain, fn = _direct_library(monkeypatch, f, False, "t_da_alias_plain")
    direct_c, direct, _ = _direct_library(monkeypatch, f, True, "t_da_alias_direct")
    body = plain_c.split("static int casadi_f0(")[1]
    assert body.index("if (res[0]!=0) res[0][2]=") < body.index("arg[0]? arg[0][2] : 0")
    assert "if (res[" not in direct_c and "]? arg[" not in direct_c
    rng = np.random.default_rng(11)
    for x0 in [*SPECIAL, *rng.normal(0, 3, 20)]:
        x_in = np.array([x0, rng.normal(), rng.normal()])
        y_in = rng.normal(size=3)
        got = {}
        for form, entry in (("plain", plain), ("direct", direct)):
            x = x_in.copy()
            b, p, s = np.full(2, 7.0), np.full(3, 7.0), np.full(1, 7.0)
            _raw_call(entry, fn, [x, y_in], [x, b, None, p, s])       # a written over x
            got[form] = np.concatenate([x, b, p, s])
        nan = np.isnan(got["plain"])
        assert np.array_equal(np.isnan(got["direct"]), nan)
        assert got["plain"][~nan].view(np.uint64).tolist() == \
            got["direct"][~nan].view(np.uint64).tolist()
        x, b, p, s = np.split(got["direct"], [3, 5, 8])
        assert b[1] == y_in[2]                          # the sparse argument's third nonzero
        if np.isfinite(x0):                             # the hand derivation
            want = np.array([2 * x0, x0 + 1, 3.0, 3.0 * (x0 + 1), y_in[2], x0, x0 + 1, 3.0,
                             x0 + 1])
            assert got["direct"].view(np.uint64).tolist() == want.view(np.uint64).tolist()
            assert (p[1], p[2]) != (x_in[1], x_in[2])   # the aliasing was exercised
        # not aliased: CasADi's own evaluation, bit for bit where a number
        x = x_in.copy()
        a, b, p, s = np.full(3, 7.0), np.full(2, 7.0), np.full(3, 7.0), np.full(1, 7.0)
        _raw_call(direct, fn, [x, y_in], [a, b, None, p, s])
        want = f(x_in, ca.DM(ca.Sparsity.lower(2), y_in))
        for g, w_ in zip((a, b, p, s), (want[0], want[1], want[3], want[4]), strict=True):
            w_ = np.asarray(ca.DM(w_).nonzeros(), dtype=float)
            assert np.array_equal(np.isnan(g), np.isnan(w_))
            assert g[~np.isnan(g)].view(np.uint64).tolist() == \
                w_[~np.isnan(w_)].view(np.uint64).tolist()


@pytest.mark.parametrize("opt", ["-O2", "-Os", "-O0"])
def test_call_nodes_and_every_build_level_give_casadi_s_bits(monkeypatch, tmp_path, opt):
    """A body with CasADi's call node (it sets ``arg[1]``/``res[2]`` itself) and its callee,
    each rewritten, built at each level the runtime may fall back to
    (``build.OPT_LEVELS``): the bits of CasADi's own C at that level, a null argument and
    each null result included, and CasADi's evaluation where every pointer is given."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    f = _call_node_function()
    plain_c, plain, fn = _direct_library(monkeypatch, f, False, "t_da_call_plain", opt)
    direct_c, direct, _ = _direct_library(monkeypatch, f, True, "t_da_call_direct", opt)
    assert "if (casadi_f1(arg+1, res+2, iw, w+4, 0)) return 1;" in direct_c
    assert direct_c.count("ql_a0 = arg[0] ? arg[0] : ql_z;") == 2
    rng = np.random.default_rng(13)
    pool = np.array(SPECIAL + list(rng.normal(0, 3, 30)))
    compared = 0
    for k in range(120):
        x_in = rng.choice(pool, size=3)
        null_x, null_o, null_q = k % 4 == 3, k % 3 == 1, k % 5 == 2
        got = []
        for entry in (plain, direct):
            o, q = np.full(2, 7.0), np.full(2, 7.0)
            _raw_call(entry, fn, [None if null_x else x_in.copy()],
                      [None if null_o else o, None if null_q else q])
            got.append(np.concatenate([o, q]))
        nan = np.isnan(got[0])
        assert np.array_equal(np.isnan(got[1]), nan)
        assert got[0][~nan].view(np.uint64).tolist() == got[1][~nan].view(np.uint64).tolist()
        assert (got[1][:2] == 7.0).all() == null_o and (got[1][2:] == 7.0).all() == null_q
        if not (null_x or null_o or null_q):
            want = np.concatenate([np.asarray(w_, dtype=float).ravel() for w_ in f(x_in)])
            assert np.array_equal(np.isnan(want), nan)
            assert want[~nan].view(np.uint64).tolist() == got[1][~nan].view(
                np.uint64).tolist()
            compared += int((~nan).sum())
    assert compared > 100

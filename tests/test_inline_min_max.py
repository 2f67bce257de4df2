"""The simulators' ``casadi_fmax``/``casadi_fmin`` computed inline (issue 20): the bits of
glibc's ``fmax``/``fmin`` for every pair of special and ordinary values.

``quadland_symbolic.codegen.simulator.inline_min_max`` replaces CasADi's calls of libm's
``fmax(x, y)`` and ``fmin(x, y)`` by ``x > y ? x : y`` and ``x < y ? x : y`` where neither
operand is a NaN, on x86-64 with glibc (whose ``fmax`` is ``maxsd``, giving ``y`` for
equal operands, ``+0.0`` and ``-0.0`` included), and by libm's call otherwise. Each pair is
compared, bit for bit, with glibc's own ``fmax``/``fmin`` called through ctypes, in the
order CasADi's C passes them.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import platform
import struct

import casadi as ca
import numpy as np
import pytest

from quadland.engine import build
from quadland_symbolic.codegen import simulator

GLIBC_X86 = (platform.machine().lower() in ("x86_64", "amd64")
             and platform.libc_ver()[0] == "glibc")
pytestmark = [pytest.mark.skipif(not build.have_compiler(), reason="needs a C compiler"),
              pytest.mark.skipif(not GLIBC_X86, reason="the inline form is glibc's on x86-64")]


def _double(bits: int) -> float:
    return struct.unpack("<d", struct.pack("<Q", bits))[0]


#: Signed zeros, infinities, quiet NaNs of both signs and a payload, a signalling NaN,
#: subnormals, the extremes, ordinary values and equal pairs.
VALUES = [0.0, -0.0, 1.0, -1.0, 0.5, 3.0, -3.0, np.inf, -np.inf, np.nan, -np.nan,
          _double(0x7FF8000000000123), _double(0x7FF0000000000001), 5e-324, -5e-324,
          2.2250738585072014e-308, -2.2250738585072014e-308, 1.7976931348623157e308,
          -1.7976931348623157e308, 1.0000000000000002, 0.9999999999999999]

WRAP = """\
#include "t_mm.h"
void mm_both(const double* x, const double* y, double* out, long n)
{
    for (long i = 0; i < n; ++i) {
        const casadi_real* arg[2] = {x + i, y + i};
        casadi_real* res[2] = {out + 2 * i, out + 2 * i + 1};
        t_mm(arg, res, 0, 0, 0);
    }
}
"""


def _sources() -> dict[str, str]:
    x, y = ca.SX.sym("x"), ca.SX.sym("y")
    files, _ = simulator._emit("t_mm", ca.Function("mm", [x, y], [ca.fmax(x, y),
                                                                 ca.fmin(x, y)]))
    return {**files, "wrap.c": WRAP}


def _bits(a) -> np.ndarray:
    return np.asarray(a, dtype=np.float64).view(np.uint64)


@pytest.mark.parametrize("machine", [True, False], ids=["machine flags", "baseline"])
def test_fmax_and_fmin_are_glibcs_bits(monkeypatch, tmp_path, machine):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    if not machine:
        monkeypatch.setattr(build, "machine_flags", lambda cc: ())
    files = _sources()
    assert "if (!isnan(x) && !isnan(y)) return x > y ? x : y;" in files["t_mm.c"]
    assert "a2=casadi_fmax(a0,a1);" in files["t_mm.c"]       # x, then y
    lib = ctypes.CDLL(str(build.build_library(files, ("t_mm.c", "wrap.c"), name="libmm",
                                              strict=False)))
    x, y = (np.ascontiguousarray(v) for v in np.meshgrid(VALUES, VALUES, indexing="ij"))
    x, y = x.ravel(), y.ravel()
    out = np.empty(2 * x.size)
    real = ctypes.POINTER(ctypes.c_double)
    lib.mm_both(x.ctypes.data_as(real), y.ctypes.data_as(real), out.ctypes.data_as(real),
                ctypes.c_long(x.size))
    libm = ctypes.CDLL(ctypes.util.find_library("m"))
    for name in ("fmax", "fmin"):
        getattr(libm, name).restype = ctypes.c_double
        getattr(libm, name).argtypes = [ctypes.c_double, ctypes.c_double]
    want_max = [libm.fmax(a, b) for a, b in zip(x, y, strict=True)]
    want_min = [libm.fmin(a, b) for a, b in zip(x, y, strict=True)]
    assert np.array_equal(_bits(out[0::2]), _bits(want_max))
    assert np.array_equal(_bits(out[1::2]), _bits(want_min))
    # the ties that make the order matter: glibc gives the second operand
    pairs = {(a, b): k for k, (a, b) in enumerate(zip(_bits(x), _bits(y), strict=True))}
    k = pairs[(_bits([0.0])[0], _bits([-0.0])[0])]
    assert _bits([out[2 * k], out[2 * k + 1]]).tolist() == _bits([-0.0, -0.0]).tolist()


def test_elsewhere_the_call_is_kept():
    """The inline form is compiled only on x86-64 with glibc; libm's call stays after it."""
    text = simulator.inline_min_max("  return fmax(x, y);\n  return fmin(x, y);\n")
    assert text.count("#if defined(__x86_64__) && defined(__GLIBC__)") == 2
    assert text.endswith("#endif\n  return fmin(x, y);\n")
    assert "#endif\n  return fmax(x, y);\n" in text

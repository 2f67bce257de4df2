"""The first-order recursion of the noise processes, compiled.

``x_(k+1) = a_k x_k + b_k n_(k+1)`` down each column: the Gauss-Markov processes of
the sensors (:func:`quadland.engine.noise.gauss_markov`), 10,000 steps a column for a
40 s landing at 250 Hz. Sequential, so NumPy cannot vectorize it without changing its
rounding; over Python floats it costs about 0.1 us a step, in C a few nanoseconds.
The C computes the same two products and one sum per step in double precision
(``-std=c99``: no contraction into fused multiply-adds), so both give the same bits.

The library is built once into the disk cache
(:func:`quadland.engine.build.build_library`); without a C compiler, or when the
build fails, :func:`compiled_recursion` is None and the caller keeps Python's loop.
"""

from __future__ import annotations

import ctypes
import functools

import numpy as np

from quadland.engine.build import build_library
from quadland.exceptions import CompileError, CompilerNotFoundError

__all__ = ["SOURCE", "compiled_recursion", "recursion"]

#: The C of the recursion: ``x`` holds row 0 on entry; every array row-major.
SOURCE = """\
/* x[k+1][j] = a[k][j] x[k][j] + b[k][j] n[k+1][j], k = 0 .. n_rows - 2 */
void ql_first_order(long n_rows, long n_cols, const double *a, const double *b,
                    const double *normals, double *x)
{
    long k, j;
    for (k = 0; k + 1 < n_rows; ++k) {
        const double *ak = a + k * n_cols, *bk = b + k * n_cols;
        const double *nk = normals + (k + 1) * n_cols;
        const double *xk = x + k * n_cols;
        double *xn = x + (k + 1) * n_cols;
        for (j = 0; j < n_cols; ++j) {
            double u = ak[j] * xk[j];
            double v = bk[j] * nk[j];
            xn[j] = u + v;
        }
    }
}
"""

_REAL = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")


@functools.cache
def compiled_recursion():
    """The compiled ``ql_first_order``, or None without a working C compiler."""
    try:
        library = build_library({"ql_first_order.c": SOURCE}, ("ql_first_order.c",),
                                "-O2", "libquadland_recursion", strict=True)
        fn = ctypes.CDLL(str(library)).ql_first_order
    except (CompileError, CompilerNotFoundError, OSError, AttributeError):
        return None
    fn.restype = None
    fn.argtypes = [ctypes.c_long, ctypes.c_long, _REAL, _REAL, _REAL, _REAL]
    return fn


def recursion(x0, a, b, normals) -> np.ndarray | None:
    """``x`` of shape ``(n, m)`` with ``x[0] = x0`` and ``x[k+1] = a[k] x[k] + b[k]
    normals[k+1]`` (``a``, ``b`` of shape ``(n - 1, m)``), in C; None without it."""
    fn = compiled_recursion()
    if fn is None:
        return None
    normals = np.ascontiguousarray(normals, dtype=float)
    n, m = normals.shape
    x = np.empty((n, m))
    x[0] = x0
    fn(n, m, np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float),
       normals, x)
    return x

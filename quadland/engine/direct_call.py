"""A CasADi function called on NumPy arrays through its buffer, without CasADi's matrices.

Calling a ``casadi.Function`` from Python converts each argument to a ``casadi.DM`` and
each result back (SWIG's checks, a copy each way): 60 to 70 microseconds for a call of a
few small vectors, about as much again per matrix of a few thousand numbers. A run of a
campaign makes a handful of such calls on numbers (the deck's pose at the handover, the
touchdown's figures, the gear's signals at its contact rows). :class:`DirectCall`
evaluates the same function on the caller's arrays through CasADi's function buffer
(``Function.buffer``): the arguments' memory is read and the results' written in place,
by the same evaluation (``eval`` of the function: its virtual machine's instructions,
on the same doubles), so the numbers are the same bits as the ``DM`` call's
(``tests/test_direct_call.py``); issue 20, docs/performance.md.
"""

from __future__ import annotations

import threading

import numpy as np

__all__ = ["DirectCall"]


class DirectCall:
    """``f(*args)`` on NumPy arrays: each result a new array of ``f``'s output's shape.

    Parameters
    ----------
    f : casadi.Function
        Every input and output dense (a function with a sparse one is refused: its
        buffer holds the nonzeros only).

    Notes
    -----
    An argument is anything ``numpy.asarray`` takes, with as many numbers as the input
    has entries: a vector's (a flat array, a list, a column or a row), a scalar's, or a
    matrix of the input's shape (read in column order, as ``casadi.DM`` of it would be).
    A result is a ``(rows, columns)`` array, as ``numpy.asarray`` of the ``DM`` result.
    The function's buffer is this object's: its calls take turns under a lock (a Dask
    worker flies runs in threads of one process).
    """

    def __init__(self, f):
        for i in range(f.n_in()):
            if not f.sparsity_in(i).is_dense():
                raise ValueError(f"{f.name()}: input {f.name_in(i)} is sparse")
        for i in range(f.n_out()):
            if not f.sparsity_out(i).is_dense():
                raise ValueError(f"{f.name()}: output {f.name_out(i)} is sparse")
        self.function = f
        self._in = tuple((f.size1_in(i), f.size2_in(i)) for i in range(f.n_in()))
        self._out = tuple((f.size1_out(i), f.size2_out(i)) for i in range(f.n_out()))
        self._buffer, self._eval = f.buffer()
        self._lock = threading.Lock()

    def __call__(self, *args) -> tuple[np.ndarray, ...]:
        if len(args) != len(self._in):
            raise TypeError(f"{self.function.name()} takes {len(self._in)} arguments, "
                            f"got {len(args)}")
        keep = []                                   # alive until the evaluation is done
        for i, (a, shape) in enumerate(zip(args, self._in, strict=True)):
            a = np.asarray(a, dtype=np.float64)
            flat = a.ravel(order="F") if a.ndim == 2 and a.shape == shape else a.ravel()
            if flat.size != shape[0] * shape[1]:
                raise ValueError(f"{self.function.name()}: input {self.function.name_in(i)} "
                                 f"has {shape[0]}x{shape[1]} entries, got an array of "
                                 f"shape {a.shape}")
            keep.append(np.ascontiguousarray(flat))
        out = tuple(np.empty(s2 * s1) for s1, s2 in self._out)
        with self._lock:
            for i, a in enumerate(keep):
                self._buffer.set_arg(i, memoryview(a))
            for i, o in enumerate(out):
                self._buffer.set_res(i, memoryview(o))
            self._eval()
            failed = self._buffer.ret()
        if failed:                                  # as the DM call's "Evaluation failed"
            raise RuntimeError(f"{self.function.name()}: evaluation failed")
        return tuple(o.reshape(s2, s1).T for o, (s1, s2) in zip(out, self._out, strict=True))

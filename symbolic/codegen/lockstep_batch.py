"""A batch entry over :func:`~quadland_symbolic.codegen.lockstep.lockstep_c`: W runs'
calls of one Function in one call, each run's arguments where the run keeps them.

A campaign's driver that flies W runs period by period holds each run's memory apart,
and calls the scalar Function once per run with that run's ``arg`` and ``res`` pointers
(CasADi's calling convention). :func:`lockstep_batch_c` writes the entry such a driver
calls instead: the W runs' pointers in, each run's inputs gathered into the lockstep
layout (nonzero ``k`` of run ``j`` at ``W k + j``), the lockstep C evaluated once, and
each active run's outputs scattered back where its scalar call would have written them;
a run that has finished (``active[j] == 0``) is neither read nor written (its lane
computes a copy of the first active run's, whose result is dropped). Every active
run's outputs are the scalar Function's bit for bit (the lanes are independent:
:mod:`quadland_symbolic.codegen.lockstep`).

A piece of issue 20's item 2 ("vectorizing across runs"), measured against the
runtime's compiled filter in ``benchmarks/bench_filter_batch.py`` (docs/performance.md,
"The filter's batch entry in lockstep"); the simulators do not call it yet.

Gathering and scattering: each run's inputs and outputs (the filter's 884 and 938 values)
are moved once each way, W values of W runs at a time as a W x W block transposed in
vector registers (log2 W rounds of shuffles swapping blocks: moves only, so the bits are
the values'). A driver that keeps its runs' memories interleaved calls the kernel
directly (:func:`lockstep_c`) and pays none of it.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.codegen.lockstep import lockstep_c
from quadland_symbolic.codegen.render import common_context, render

__all__ = ["lockstep_batch_c"]


def lockstep_batch_c(fn: ca.Function, width: int, name: str | None = None) -> str:
    """C of a batch entry: ``fn`` for up to ``width`` runs at once.

    Parameters
    ----------
    fn : casadi.Function
        An SX Function (as :func:`~quadland_symbolic.codegen.lockstep.lockstep_c`).
    width : int
        Runs per call, W (1, 2, 4, 8 or 16).
    name : str, optional
        The entry's C name; ``<fn.name()>_batch<W>`` by default. The lockstep kernel it
        calls is ``<name>_lanes`` (static, in the same translation unit).

    Returns
    -------
    str
        One translation unit defining ``void name(const double* const* arg,
        double* const* res, const int* active)``: ``arg[n_in * j + i]`` is run ``j``'s
        input ``i`` as its scalar call takes it (NULL: zeros), ``res[n_out * j + i]`` its
        output ``i`` (NULL: not wanted), ``active[j]`` nonzero for a run to evaluate.
        Inactive runs' pointers are not dereferenced. Every input is read before any
        output is written, so an output may overwrite any run's input. Compile as the lockstep C (no
        ``-ffast-math``, ``-ffp-contract=off``).

    Raises
    ------
    ValueError
        As :func:`~quadland_symbolic.codegen.lockstep.lockstep_c`.

    Examples
    --------
    >>> x = ca.SX.sym("x", 2)
    >>> text = lockstep_batch_c(ca.Function("f", [x], [x[0] * x[1]]), 4)
    >>> "void f_batch4(const double* const* arg, double* const* res, const int* active)" in text
    True
    """
    name = name or f"{fn.name()}_batch{width}"
    kernel = lockstep_c(fn, width, name=f"{name}_lanes")
    kernel = kernel.replace(f"\nvoid {name}_lanes(", f"\nstatic void {name}_lanes(", 1)
    n_in = [fn.nnz_in(i) for i in range(fn.n_in())]
    n_out = [fn.nnz_out(i) for i in range(fn.n_out())]
    return kernel + render("lockstep_batch.c.jinja", name=name, width=width, n_in=n_in,
                           n_out=n_out, off_in=_offsets(n_in), off_out=_offsets(n_out),
                           vec=f"{name}_lanes_v", transpose=_transpose(width),
                           swaps=_swaps(width), **common_context(None))


def _swaps(width: int) -> list[tuple[int, str, str]]:
    """Each round of the block transpose: ``(d, low, high)``, the lanes of the two
    shuffles of rows ``a`` and ``b`` ``d`` apart (``b``'s lanes numbered from ``width``):
    ``low`` keeps ``a``'s blocks of ``d`` at even block places and takes ``b``'s before
    them at the odd; ``high`` the rest (each one instruction with SSE2, AVX2, AVX-512)."""
    out, d = [], 1
    while d < width:
        low = [m if not m & d else width + m - d for m in range(width)]
        high = [m + d if not m & d else width + m for m in range(width)]
        out.append((d, ", ".join(map(str, low)), ", ".join(map(str, high))))
        d *= 2
    return out


def _transpose(width: int) -> list[str]:
    """Statements turning the vectors ``r0 .. r<W-1>`` (lane ``j``'s W values in a row)
    into ``r0 .. r<W-1>`` transposed (value ``m`` of every lane): in rounds ``d = 1, 2,
    ...``, rows ``i`` and ``i + d`` swap their off-diagonal blocks of ``d``; moves only."""
    lines = []
    for d, _, _ in _swaps(width):
        pairs = [(i, i + d) for i in range(width) if not i & d]
        lines += [f"t{i} = LO{d}_(r{i}, r{k}); t{k} = HI{d}_(r{i}, r{k});" for i, k in pairs]
        lines.append(" ".join(f"r{i} = t{i};" for i in range(width)))
    return lines


def _offsets(sizes: list[int]) -> list[int]:
    """Where each of ``sizes``' pieces starts when they lie end to end."""
    out, at = [], 0
    for n in sizes:
        out.append(at)
        at += n
    return out

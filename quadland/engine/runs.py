"""What a simulator's driver returns, and the checks of what it is given.

The status codes of the drivers (``symbolic/templates/simulator.c.jinja``), one run's
rows (:class:`Run`) and a ride's (:class:`Ride`), shared by the compiled simulators
(:mod:`quadland.engine.compiled`) and their mirror on CasADi's virtual machine
(:mod:`quadland.engine.vm`).
"""

from __future__ import annotations

import dataclasses
import importlib
import threading

import numpy as np

from quadland_symbolic.loop import LoopModel

__all__ = ["SIM_OK", "SIM_NONFINITE", "SIM_GUARD", "SIM_CONTROLLER", "SIM_EVENT",
           "SIM_ENVELOPE", "SIM_ROWS", "Run", "Ride", "as_f64", "make_run", "tick_rows",
           "tick_source",
           "envelope_bounds", "row_buffer"]

#: Status codes of the drivers (``symbolic/templates/simulator.c.jinja``).
SIM_OK, SIM_NONFINITE, SIM_GUARD, SIM_CONTROLLER, SIM_EVENT, SIM_ENVELOPE, SIM_ROWS = range(7)


def _hugepage_switch():
    """NumPy's switch of its huge-page advice (``_set_madvise_hugepage``), or None."""
    for module in ("numpy._core.multiarray", "numpy.core.multiarray"):
        try:
            return importlib.import_module(module)._set_madvise_hugepage
        except (ImportError, AttributeError):
            continue
    return None


_HUGEPAGE_SWITCH = _hugepage_switch()
_HUGEPAGE_LOCK = threading.Lock()


def row_buffer(rows: int, width: int, zeroed: bool = True) -> np.ndarray:
    """A ``(rows, width)`` array of doubles for a driver to fill, in small pages: zeroed,
    or (``zeroed=False``) as the allocator gives it, for a driver that writes each row it
    returns whole (the sampled driver's rows of states and recorded signals: the rows past
    those it returns are never read).

    NumPy advises the kernel to back arrays of 4 MiB and more with 2 MiB pages
    (``madvise(MADV_HUGEPAGE)``). A run's rows are written once, front to back;
    where the memory is fresh (the allocator could not reuse freed pages, as
    after other work in the process), faulting in huge pages cost 20 to 40 ms
    of system time per 20 MiB on the measuring machine (a virtual machine:
    the host backs each fresh huge page), against 7 ms in 4 KiB pages. The
    paper's 60 s run writes 20 MiB of states, so this alone took a warm run
    from 53 to 93 ms. NumPy's switch is process-wide: it is turned off only
    while this array is allocated, under a lock. Where a process keeps the memory its
    runs free (:func:`quadland.engine.heap.keep_freed_memory`), zeroing is the buffer's
    whole cost: a 40 s landing's 10 MB of rows written over by the C library's
    ``memset`` before the driver writes the rows it needs (issue 20).
    """
    make = np.zeros if zeroed else np.empty
    if _HUGEPAGE_SWITCH is None:
        return make((rows, width))
    with _HUGEPAGE_LOCK:
        before = _HUGEPAGE_SWITCH(False)
        try:
            return make((rows, width))
        finally:
            _HUGEPAGE_SWITCH(before)



def as_f64(a) -> np.ndarray:
    """``a`` as a C-contiguous array of doubles (a view when it already is one)."""
    return np.ascontiguousarray(a, dtype=np.float64)


@dataclasses.dataclass(frozen=True)
class Run:
    """What one call of a driver gave.

    Attributes
    ----------
    status : int
        :data:`SIM_OK`, or the ``SIM_*`` code that stopped the run.
    X : ndarray, (rows, nx)
        The loop's state at each output row recorded.
    R : ndarray, (rows, nrec) or None
        The sampled loop's recorded signals at each row (None: continuous).
    times : ndarray, (rows,)
        Each row's time, s.
    w_index : ndarray of int, (rows,)
        Each row's disturbance sample (the row of ``W`` in force).
    x_end : ndarray
        The state where the run ended (the sampled loop's ``[xp, xc]``).
    t_stop : float
        s, where a run that did not reach its end stopped (an event's instant);
        NaN otherwise.
    envelope : ndarray or None
        For :data:`SIM_ENVELOPE`: the envelope magnitudes that left their bounds.
    t_event : float
        s, the first crossing of a continuing event (NaN: none).
    x_event : ndarray or None
        The loop's state at that instant.
    """

    status: int
    X: np.ndarray
    R: np.ndarray | None
    times: np.ndarray
    w_index: np.ndarray
    x_end: np.ndarray
    t_stop: float = float("nan")
    envelope: np.ndarray | None = None
    t_event: float = float("nan")
    x_event: np.ndarray | None = None

    @property
    def rows(self) -> int:
        """Rows recorded."""
        return len(self.times)


@dataclasses.dataclass(frozen=True)
class Ride:
    """The rows of a ride after an event (:meth:`CompiledLoop.ride`).

    ``status`` is :data:`SIM_OK` or the ``SIM_*`` code that stopped it; ``times``,
    ``X`` (the loop's state), ``Y`` (its output signals) and ``R`` (its recorded
    signals) hold the rows before that.
    """

    status: int
    times: np.ndarray
    X: np.ndarray
    Y: np.ndarray
    R: np.ndarray


def make_run(m: LoopModel, status, X, R, times, w_index, x_end, t_stop, env,
             t_event=float("nan"), x_event=None) -> Run:
    X = np.array(X, dtype=float).reshape(-1, m.state.size)
    R = None if R is None else np.array(R, dtype=float).reshape(-1, m.recorded.size)
    return Run(status, X, R, np.array(times, dtype=float), np.array(w_index, dtype=np.int_),
               np.asarray(x_end, dtype=float), t_stop, env if status == SIM_ENVELOPE else None,
               float(t_event), None if x_event is None else np.asarray(x_event, dtype=float))


def tick_rows(model: LoopModel, N) -> np.ndarray:
    """The per-tick table of a model with tick inputs (rows of its width), else empty."""
    width = 0 if model.tick_inputs is None else model.tick_inputs.size
    N = np.zeros((0, width)) if N is None else as_f64(N)
    if N.ndim != 2 or N.shape[1] != width:
        raise ValueError(f"N must have {width} columns, got shape {N.shape}")
    return np.ascontiguousarray(N)


def tick_source(model: LoopModel, N) -> tuple[np.ndarray, int, object]:
    """A per-tick table as the drivers take it: ``(rows, filled, more)``.

    ``N`` is an array (every row filled; ``more`` None) or a table drawn as the
    flight goes: an object with ``rows``, the whole ``(ticks, width)`` array (the
    rows not yet drawn are never read), ``filled``, the rows drawn, and
    ``more(tick)``, which fills rows of the same array at least past ``tick`` (when
    the table reaches it) and returns how many are filled now.
    """
    if N is None or not hasattr(N, "more"):
        rows = tick_rows(model, N)
        return rows, rows.shape[0], None
    rows = tick_rows(model, N.rows)
    if rows is not N.rows:
        raise ValueError("a drawn table's rows must be C-contiguous doubles")
    return rows, int(N.filled), N.more


def envelope_bounds(model: LoopModel, bound) -> np.ndarray:
    """The envelope's bounds as the drivers take them (none without an envelope)."""
    if model.envelope_layout is None:            # (a recipe's: without building it)
        return np.zeros(0)
    bound = as_f64(bound)
    if bound.shape != (model.envelope_layout.size,):
        raise ValueError(f"bound: expected {model.envelope_layout.size} envelope bounds, "
                         f"got shape {bound.shape}")
    return bound

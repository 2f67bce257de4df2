"""Simulators of the loops of ``symbolic.simulation``: compiled, or on CasADi's VM.

:func:`compiled_loop` generates the C of one part of a simulator
(``symbolic.simulation.simulator_sources``), builds it once into the disk
cache (:mod:`quadland.build`) and loads it with ``ctypes``
(:class:`CompiledLoop`). A call runs a whole simulation in C: RK4 over the
exact time grid, the parameters passed once, states and outputs written
straight into NumPy arrays. Where no C compiler is found it returns, after
one warning, a :class:`VMLoop`: the same drivers, step for step, on CasADi's
virtual machine, several times slower.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import warnings

import numpy as np

from quadland.build import build_library, have_compiler
from quadland.exceptions import CompileError, CompilerNotFoundError
from symbolic.landing.loop import landing_loop
from symbolic.simulation import SIMULATOR_PARTS, LoopModel, paper_loop, rk4_step, simulator_sources

__all__ = ["QuadlandWarning", "CompiledLoop", "VMLoop", "compiled_loop", "LOOPS", "SIM_OK",
           "SIM_NONFINITE", "SIM_GUARD", "SIM_CONTROLLER", "SIM_EVENT", "Failure"]

#: The loops a scenario's ``scenario.model`` names: builders ``l -> LoopModel``.
LOOPS = {"paper": paper_loop, "landing": landing_loop}

#: Status codes of the drivers (``symbolic/templates/simulator.c.jinja``).
SIM_OK, SIM_NONFINITE, SIM_GUARD, SIM_CONTROLLER, SIM_EVENT = 0, 1, 2, 3, 4

_REAL = ctypes.POINTER(ctypes.c_double)
_LONG = ctypes.POINTER(ctypes.c_long)


class QuadlandWarning(UserWarning):
    """Something quadland worked around (e.g. no C compiler: a slower path)."""


def _ptr(a: np.ndarray, kind=_REAL):
    return a.ctypes.data_as(kind)


def _f64(a) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


@dataclasses.dataclass(frozen=True)
class Failure:
    """Where a run stopped early: its status, grid index and, for an event, the time."""

    status: int
    index: int
    time: float = float("nan")


class CompiledLoop:
    """One compiled part (``"continuous"`` or ``"sampled"``) of a loop's simulator.

    Parameters
    ----------
    model : LoopModel
    part : {"continuous", "sampled"}
    opt : str
        Optimization flag of the build.
    """

    def __init__(self, model: LoopModel, part: str, opt: str = "-O2",
                 flight: dict[str, str] | None = None, flight_sources: tuple[str, ...] = ()):
        self.model, self.part = model, part
        files = simulator_sources(model, part)
        sources = tuple(sorted(n for n in files if n.endswith(".c")))
        if flight is not None:                       # the flight code's own sources
            files = {**flight, **files}
            sources += flight_sources
        self.library = build_library(files, sources, opt, f"qlsim_{model.name}_{part}",
                                     strict=False)
        lib = ctypes.CDLL(str(self.library))
        prefix = f"qlsim_{model.name}_"
        self._outputs = getattr(lib, f"{prefix}{part}_outputs")
        self._outputs.argtypes = [_REAL, _REAL, _REAL, ctypes.c_long, _REAL, _REAL]
        if part == "continuous":
            self._integrate = getattr(lib, f"{prefix}integrate")
            self._integrate.argtypes = [_REAL, _REAL, _REAL, _LONG, ctypes.c_long,
                                        ctypes.c_long, _REAL, _REAL, _REAL, _LONG]
        else:
            self._sampled = getattr(lib, f"{prefix}sampled")
            self._sampled.argtypes = [_REAL, _REAL, _REAL, _REAL, ctypes.c_char_p, _LONG,
                                      ctypes.c_long, ctypes.c_long, _REAL, _REAL,
                                      ctypes.c_double, _REAL, _REAL, _REAL, _REAL, _LONG,
                                      _REAL]

    def integrate(self, x0, W, G, rec, substeps: int, p, n_rows: int):
        """The continuous loop over the ``len(G) - 1`` intervals of the grid ``G``.

        Parameters
        ----------
        x0 : array_like, (nx,)
        W : array_like, (n, nw)
            Disturbance held over each interval.
        G : array_like, (n + 1,)
            Grid times, s.
        rec : array_like of int, (n,)
            Row of the returned states for the state at each interval's end, or -1.
        substeps : int
            RK4 steps per interval.
        p : array_like, (np,)
        n_rows : int
            Rows of the returned states; row 0 is ``x0``.

        Returns
        -------
        X : ndarray, (n_rows, nx)
        x_end : ndarray, (nx,)
        failure : Failure or None
        """
        m = self.model
        x0, W, G, p = _f64(x0), _f64(W), _f64(G), _f64(p)
        rec = np.ascontiguousarray(rec, dtype=np.int_)
        n = len(G) - 1
        assert W.shape == (n, m.disturbance.size) and rec.shape == (n,)
        X = np.zeros((n_rows, m.state.size))
        X[0] = x0
        x_end = np.empty(m.state.size)
        fail = ctypes.c_long(-1)
        status = self._integrate(_ptr(x0), _ptr(W), _ptr(G), _ptr(rec, _LONG), n, int(substeps),
                                 _ptr(p), _ptr(X), _ptr(x_end), ctypes.byref(fail))
        return X, x_end, (Failure(status, fail.value) if status else None)

    def sampled(self, xp0, xc0, W, G, ctrl, rec, substeps: int, pp, pc, guard_min: float,
                n_rows: int):
        """The sampled-data loop over the ``len(G) - 1`` intervals of the grid ``G``.

        ``ctrl`` (n,) and ``rec`` (n + 1,) flag, per grid point, a control
        step and the row it is recorded to (or -1). A model with an event
        stops where it happens: the failure then has status
        :data:`SIM_EVENT`, its ``time`` and, in ``xp_end``, the state then.

        Returns
        -------
        X : ndarray, (n_rows, nx)
            The loop's state at the recorded points.
        R : ndarray, (n_rows, nrec)
            The recorded signals (held from the last control step).
        xp_end, xc_end : ndarray
        failure : Failure or None
        """
        m = self.model
        xp0, xc0, W, G, pp, pc = (_f64(a) for a in (xp0, xc0, W, G, pp, pc))
        ctrl = np.ascontiguousarray(ctrl, dtype=np.uint8)
        rec = np.ascontiguousarray(rec, dtype=np.int_)
        n = len(G) - 1
        assert W.shape == (n, m.disturbance.size) and ctrl.shape == (n,)
        assert rec.shape == (n + 1,)
        X = np.zeros((n_rows, m.state.size))
        R = np.zeros((n_rows, m.recorded.size))
        xp_end, xc_end = np.empty(m.plant_state.size), np.empty(m.controller_state.size)
        fail, t_event = ctypes.c_long(-1), ctypes.c_double(np.nan)
        status = self._sampled(_ptr(xp0), _ptr(xc0), _ptr(W), _ptr(G), ctrl.ctypes.data_as(
            ctypes.c_char_p), _ptr(rec, _LONG), n, int(substeps), _ptr(pp), _ptr(pc),
            float(guard_min), _ptr(X), _ptr(R), _ptr(xp_end), _ptr(xc_end), ctypes.byref(fail),
            ctypes.byref(t_event))
        return X, R, xp_end, xc_end, (Failure(status, fail.value, t_event.value) if status
                                      else None)

    def outputs(self, X, W, T, p) -> np.ndarray:
        """Output signals at each row of ``X`` (with ``W``'s rows, at times ``T``), ``(n, ny)``."""
        m = self.model
        X, W, T, p = _f64(X), _f64(W), _f64(T), _f64(p)
        n = X.shape[0]
        assert X.shape == (n, m.state.size) and W.shape == (n, m.disturbance.size)
        assert T.shape == (n,)
        Y = np.empty((n, m.outputs.size))
        self._outputs(_ptr(X), _ptr(W), _ptr(T), n, _ptr(p), _ptr(Y))
        return Y


class VMLoop:
    """The drivers of :class:`CompiledLoop` on CasADi's virtual machine.

    The same algorithm, step for step (``symbolic/templates/simulator.c.jinja``):
    used where no C compiler is found.
    """

    #: Samples per call of the mapped output function.
    CHUNK = 256

    def __init__(self, model: LoopModel, part: str):
        self.model, self.part = model, part
        self._rhs = rk4_step(model.rhs) if model.rhs is not None else None
        self._plant = rk4_step(model.plant)
        self._outputs = model.output_fn.map("outputs_map", "serial", self.CHUNK, [3], [])

    def integrate(self, x0, W, G, rec, substeps: int, p, n_rows: int):
        """As :meth:`CompiledLoop.integrate`."""
        X = np.zeros((n_rows, self.model.state.size))
        X[0] = x = np.asarray(x0, dtype=float)
        for j in range(len(G) - 1):
            h = (G[j + 1] - G[j]) / substeps
            for s in range(int(substeps)):
                x = self._rhs(x, W[j], G[j] + s * h, p, h)
            x = np.asarray(x, dtype=float).ravel()
            if not np.all(np.isfinite(x)):
                return X, x, Failure(SIM_NONFINITE, j)
            if rec[j] >= 0:
                X[rec[j]] = x
        return X, x, None

    def _span(self, xp, uh, w, pp, t_start, span, substeps):
        h = span / substeps
        for s in range(int(substeps)):
            xp = self._plant(xp, uh, w, t_start + s * h, pp, h)
        return np.asarray(xp, dtype=float).ravel()

    def _event(self, xp, t, pp) -> float:
        return float(self.model.event(xp, t, pp))

    def sampled(self, xp0, xc0, W, G, ctrl, rec, substeps: int, pp, pc, guard_min: float,
                n_rows: int):
        """As :meth:`CompiledLoop.sampled`."""
        m = self.model
        X = np.zeros((n_rows, m.state.size))
        R = np.zeros((n_rows, m.recorded.size))
        xp, xc = np.asarray(xp0, dtype=float), np.asarray(xc0, dtype=float)
        uh, rv, first = np.zeros(m.held.size), np.zeros(m.recorded.size), 1.0
        n = len(G) - 1
        g_start = self._event(xp, G[0], pp) if m.event is not None else None
        for j in range(n + 1):
            if j < n and ctrl[j]:
                xc_n, uh_n, rv_n, guard = (np.asarray(v, dtype=float).ravel() for v in
                                           m.controller(xp, xc, pc, first, G[j]))
                if not abs(guard[0]) >= guard_min:
                    return X, R, xp, xc, Failure(SIM_GUARD, j)
                if not (np.all(np.isfinite(xc_n)) and np.all(np.isfinite(uh_n))
                        and np.all(np.isfinite(rv_n))):
                    return X, R, xp, xc, Failure(SIM_NONFINITE, j)
                xc, uh, rv, first = xc_n, uh_n, rv_n, 0.0
            if rec[j] >= 0:
                X[rec[j]] = np.asarray(m.assemble(xp, xc), dtype=float).ravel()
                R[rec[j]] = rv
            if j == n:
                break
            start, span = xp, G[j + 1] - G[j]
            xp = self._span(start, uh, W[j], pp, G[j], span, substeps)
            if not np.all(np.isfinite(xp)):
                return X, R, xp, xc, Failure(SIM_NONFINITE, j)
            if g_start is not None:
                g_end = self._event(xp, G[j + 1], pp)
                if g_start > 0 and not g_end > 0:
                    lo, hi = 0.0, span
                    while hi - lo > 1e-12 * span:
                        mid = (lo + hi) / 2
                        trial = self._span(start, uh, W[j], pp, G[j], mid, substeps)
                        if self._event(trial, G[j] + mid, pp) > 0:
                            lo = mid
                        else:
                            hi, xp = mid, trial
                    return X, R, xp, xc, Failure(SIM_EVENT, j, G[j] + hi)
                g_start = g_end
        return X, R, xp, xc, None

    def outputs(self, X, W, T, p) -> np.ndarray:
        """As :meth:`CompiledLoop.outputs`, in chunks with ``p`` shared, not repeated."""
        n, k = X.shape[0], self.CHUNK
        Y = np.empty((n, self.model.outputs.size))
        for a in range(0, n, k):
            b = min(a + k, n)
            Xc = np.zeros((k, X.shape[1]))
            Wc = np.zeros((k, W.shape[1]))
            Tc = np.zeros((1, k))
            Xc[: b - a], Wc[: b - a], Tc[0, : b - a] = X[a:b], W[a:b], T[a:b]
            Y[a:b] = np.asarray(self._outputs(Xc.T, Wc.T, Tc, p), dtype=float).T[: b - a]
        return Y


@functools.lru_cache(maxsize=16)
def compiled_loop(l: int, part: str, model: str = "paper") -> CompiledLoop | VMLoop:
    """The ``part`` of a loop's simulator for ``l`` nodes: compiled, or on the VM.

    ``part`` is a key of ``symbolic.simulation.SIMULATOR_PARTS``; ``model`` a
    key of :data:`LOOPS` (the paper's loop, the landing loop). One simulator
    is kept per model, ``l`` and part. Without a C compiler: a
    :class:`VMLoop` after one :class:`QuadlandWarning`; the flight code
    (part ``"sampled_flight"``: the paper's control step, or the landing's
    guidance and step) exists only compiled.

    A compiler that fails, a cache that cannot be written (a full disk), a
    library that does not load or C over the build's budgets
    (``quadland.build.plan_build``) also give the VM after one warning; the
    flight code has no VM fallback and raises.

    Raises
    ------
    CompilerNotFoundError
        For ``"sampled_flight"`` without a C compiler.
    CompileError
        For ``"sampled_flight"`` when its build fails (one line; a budget
        refusal names ``rbf.nodes``).
    """
    if part not in SIMULATOR_PARTS:
        raise ValueError(f"part must be one of {', '.join(SIMULATOR_PARTS)}, got {part!r}")
    if model not in LOOPS:
        raise ValueError(f"model must be one of {', '.join(LOOPS)}, got {model!r}")
    loop = LOOPS[model](l)
    if not have_compiler():
        if part == "sampled_flight":
            raise CompilerNotFoundError(
                "controller.backend = \"c\" flies the compiled flight code, and no C compiler "
                "was found (set CC or install gcc; or use controller.backend = \"casadi\")")
        _warn_no_compiler()
        return VMLoop(loop, part)
    flight, flight_sources = None, ()
    if part == "sampled_flight":
        from quadland.cbackend import sources
        from symbolic.codegen import c_sources

        flight = sources(l, "double", model)
        flight_sources = c_sources(({"paper": "control_step", "landing": "landing_step"}[model],))
    try:
        return CompiledLoop(loop, part, flight=flight, flight_sources=flight_sources)
    except (CompileError, OSError, AttributeError) as exc:
        # A broken compiler or cache (the build checks the library loads; a library
        # without the driver's symbols is the last resort): CasADi's VM still works.
        text = (str(exc) or repr(exc)).splitlines()[0]
        why = text if isinstance(exc, CompileError) else \
            f"the compiled simulator does not load: {text}"
        if part == "sampled_flight":
            raise CompileError(why) from None
        _warn_compile_failed(why)
        return VMLoop(loop, part)


@functools.cache
def _warn_compile_failed(why: str) -> None:
    warnings.warn(f"{why}; simulating on CasADi's virtual machine, several times slower",
                  QuadlandWarning, stacklevel=4)


@functools.cache
def _warn_no_compiler() -> None:
    warnings.warn("no C compiler found (set CC or install gcc): simulating on CasADi's "
                  "virtual machine, several times slower", QuadlandWarning, stacklevel=4)

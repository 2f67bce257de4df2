"""Simulators of the loops of ``quadland_symbolic.loop.LoopModel``: compiled, or on CasADi's VM.

:func:`compiled_loop` generates the C of one part of a simulator
(``quadland_symbolic.codegen.simulator_sources``), builds it once into the disk
cache (:mod:`quadland.engine.build`) and loads it with ``ctypes``
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

from quadland.engine.build import build_library, compiler_problem, have_compiler
from quadland.engine.loop import Clock, locate_event, merged_grid, ride_grid, rk4_span
from quadland.exceptions import CompileError, CompilerNotFoundError
from quadland_symbolic.codegen import SIMULATOR_PARTS, simulator_sources
from quadland_symbolic.loop import LoopModel, rk4_step

__all__ = ["QuadlandWarning", "CompiledLoop", "VMLoop", "compiled_loop", "SIM_OK",
           "SIM_NONFINITE", "SIM_GUARD", "SIM_CONTROLLER", "SIM_EVENT", "SIM_ENVELOPE",
           "SIM_ROWS", "Run", "Ride", "FlightCode"]


#: Status codes of the drivers (``symbolic/templates/simulator.c.jinja``).
SIM_OK, SIM_NONFINITE, SIM_GUARD, SIM_CONTROLLER, SIM_EVENT, SIM_ENVELOPE, SIM_ROWS = range(7)

_REAL = ctypes.POINTER(ctypes.c_double)
_LONG = ctypes.POINTER(ctypes.c_long)


class QuadlandWarning(UserWarning):
    """Something quadland worked around (e.g. no C compiler: a slower path)."""


def _ptr(a: np.ndarray, kind=_REAL):
    return a.ctypes.data_as(kind)


def _f64(a) -> np.ndarray:
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
    """

    status: int
    X: np.ndarray
    R: np.ndarray | None
    times: np.ndarray
    w_index: np.ndarray
    x_end: np.ndarray
    t_stop: float = float("nan")
    envelope: np.ndarray | None = None

    @property
    def rows(self) -> int:
        """Rows recorded."""
        return len(self.times)


def _clock_table(clocks) -> np.ndarray:
    return np.ascontiguousarray([c.table() for c in clocks], dtype=np.float64).ravel()


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


class CompiledLoop:
    """One compiled part (``"continuous"`` or ``"sampled"``) of a loop's simulator.

    Parameters
    ----------
    model : LoopModel
    part : {"continuous", "sampled", "sampled_flight"}
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
        D, L = ctypes.c_double, ctypes.c_long
        if part == "continuous":
            self._integrate = getattr(lib, f"{prefix}integrate")
            self._integrate.argtypes = [_REAL, _REAL, D, _REAL, L, _REAL, _REAL, _REAL, _REAL,
                                        _LONG, L, _LONG, _REAL, ctypes.POINTER(D), _REAL]
        else:
            self._sampled = getattr(lib, f"{prefix}sampled")
            self._sampled.argtypes = [_REAL, _REAL, _REAL, D, _REAL, L, L, _REAL, _REAL, _REAL,
                                      D, _REAL, _REAL, _REAL, _REAL, _LONG, L, _LONG, _REAL,
                                      _REAL, ctypes.POINTER(D), _REAL]
            if model.ride_rhs is not None:
                self._ride = getattr(lib, f"{prefix}ride")
                self._ride.argtypes = [_REAL, _REAL, _REAL, D, D, D, D, _REAL, _REAL, _REAL,
                                       _REAL, _REAL, L, _LONG]

    def integrate(self, x0, clocks, W, substeps: int, p, bound=None) -> Run:
        """The continuous loop over the merged grid of its output and disturbance clocks.

        Parameters
        ----------
        x0 : array_like, (nx,)
        clocks : sequence of quadland.engine.loop.Clock
            The output clock, then the disturbance clock (both closing).
        W : array_like, (samples, nw)
            The disturbance at each tick of the disturbance clock, held until the next.
        substeps : int
            RK4 steps per grid interval.
        p : array_like, (np,)
        bound : array_like, (nenv,), optional
            The envelope's bounds (:attr:`LoopModel.envelope`); none for a
            model without an envelope.

        Returns
        -------
        Run
        """
        m = self.model
        out, dist = clocks
        x0, W, p, bound = _f64(x0), _f64(W), _f64(p), _bounds(m, bound)
        rows = len(out.times())
        assert W.shape == (len(dist.times()), m.disturbance.size)
        X = np.zeros((rows, m.state.size))
        times, w_index = np.zeros(rows), np.zeros(rows, dtype=np.int_)
        x_end, env = np.empty(m.state.size), np.full(max(bound.size, 1), np.nan)
        n_rows, t_stop = ctypes.c_long(0), ctypes.c_double(np.nan)
        status = self._integrate(
            _ptr(x0), _ptr(_clock_table(clocks)), float(out.T), _ptr(W), int(substeps), _ptr(p),
            _ptr(bound), _ptr(X), _ptr(times), _ptr(w_index, _LONG), rows,
            ctypes.byref(n_rows), _ptr(x_end), ctypes.byref(t_stop), _ptr(env))
        n = n_rows.value
        return Run(status, X[:n], None, times[:n], w_index[:n], x_end, t_stop.value,
                   env if status == SIM_ENVELOPE else None)

    def sampled(self, xp0, xc0, clocks, W, substeps: int, pp, pc, guard_min: float,
                bound=None, delay: int = 0, uh0=None) -> Run:
        """The sampled-data loop over the merged grid of its output, disturbance and
        control clocks.

        ``delay`` control periods pass between computing a command and applying
        it (``uh0`` is held before the first arrives; zero by default). A model
        with an event stops where it happens: the run's status is
        :data:`SIM_EVENT`, ``t_stop`` its instant and ``x_end`` the state then.
        ``bound`` (nenv,) are the envelope's bounds: the run stops at the first
        grid point outside them (:data:`SIM_ENVELOPE`).
        """
        m = self.model
        out, dist, _ = clocks
        xp0, xc0, W, pp, pc = (_f64(a) for a in (xp0, xc0, W, pp, pc))
        bound = _bounds(m, bound)
        uh0 = np.zeros(m.held.size) if uh0 is None else _f64(uh0)
        rows = len(out.times())
        assert W.shape == (len(dist.times()), m.disturbance.size)
        X = np.zeros((rows, m.state.size))
        R = np.zeros((rows, m.recorded.size))
        times, w_index = np.zeros(rows), np.zeros(rows, dtype=np.int_)
        xp_end, xc_end = np.empty(m.plant_state.size), np.empty(m.controller_state.size)
        env = np.full(max(bound.size, 1), np.nan)
        n_rows, t_stop = ctypes.c_long(0), ctypes.c_double(np.nan)
        status = self._sampled(
            _ptr(xp0), _ptr(xc0), _ptr(_clock_table(clocks)), float(out.T), _ptr(W),
            int(substeps), int(delay), _ptr(uh0), _ptr(pp), _ptr(pc), float(guard_min),
            _ptr(bound), _ptr(X), _ptr(R), _ptr(times), _ptr(w_index, _LONG), rows,
            ctypes.byref(n_rows), _ptr(xp_end), _ptr(xc_end), ctypes.byref(t_stop), _ptr(env))
        n = n_rows.value
        return Run(status, X[:n], R[:n], times[:n], w_index[:n], np.concatenate([xp_end, xc_end]),
                   t_stop.value, env if status == SIM_ENVELOPE else None)

    def ride(self, z0, a, rows: Clock, t_ev: float, t_end: float, h_max: float, pp) -> Ride:
        """The ride after the event at ``t_ev`` (a model with ``ride_rhs``, ``ride_row``):
        ``z0`` carried to ``t_end``, a row at each tick of ``rows`` after ``t_ev`` and at
        ``t_end`` (``quadland_loop.h``'s ``qll_ride``)."""
        m = self.model
        n = len(rows.times()) + 1
        X, Y = np.zeros((n, m.state.size)), np.zeros((n, m.outputs.size))
        R, times, n_rows = np.zeros((n, m.recorded.size)), np.zeros(n), ctypes.c_long(0)
        status = self._ride(_ptr(_f64(z0)), _ptr(_f64(a)), _ptr(_clock_table([rows])),
                            float(rows.T), float(t_ev), float(t_end), float(h_max),
                            _ptr(_f64(pp)), _ptr(X), _ptr(Y), _ptr(R), _ptr(times), n,
                            ctypes.byref(n_rows))
        k = n_rows.value
        return Ride(status, times[:k], X[:k], Y[:k], R[:k])

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

    The same algorithm, step for step (``quadland_loop.h``, mirrored by
    :mod:`quadland.engine.loop`): used where no C compiler is found.
    """

    #: Samples per call of the mapped output function.
    CHUNK = 256

    def __init__(self, model: LoopModel, part: str):
        self.model, self.part = model, part
        self._rhs = rk4_step(model.rhs) if model.rhs is not None else None
        self._plant = rk4_step(model.plant)
        self._ride_step = rk4_step(model.ride_rhs) if model.ride_rhs is not None else None
        self._outputs = model.output_fn.map("outputs_map", "serial", self.CHUNK, [3], [])
        self._no_input = np.zeros(model.held.size)

    def _outside(self, x, uh, bound) -> np.ndarray | None:
        """The envelope's magnitudes when one is beyond its bound (or NaN), else None."""
        if self.model.envelope is None:
            return None
        s = np.asarray(self.model.envelope(x, uh), dtype=float).ravel()
        return None if np.all(s <= bound) else s

    def integrate(self, x0, clocks, W, substeps: int, p, bound=None) -> Run:
        """As :meth:`CompiledLoop.integrate`."""
        m = self.model
        bound = _bounds(m, bound)
        grid, (out, dist) = merged_grid(clocks)
        x = np.asarray(x0, dtype=float)
        X, times, w_index = [], [], []
        i_w, status, t_stop, env = 0, SIM_OK, np.nan, None
        for j, t in enumerate(grid):
            if dist[j] >= 0:
                i_w = dist[j]
            env = self._outside(x, self._no_input, bound)
            if env is not None:
                status, t_stop = SIM_ENVELOPE, t
                break
            if out[j] >= 0:
                X.append(x)
                times.append(clocks[0].times()[out[j]])
                w_index.append(i_w)
            if j + 1 == len(grid):
                break
            w = W[i_w]
            x = rk4_span(lambda xx, tt, h, w=w: self._rhs(xx, w, tt, p, h), x, t,
                         grid[j + 1] - t, substeps)
            if not np.all(np.isfinite(x)):
                status, t_stop = SIM_NONFINITE, grid[j + 1]
                break
        return _run(m, status, X, None, times, w_index, x, t_stop, env)

    def sampled(self, xp0, xc0, clocks, W, substeps: int, pp, pc, guard_min: float,
                bound=None, delay: int = 0, uh0=None) -> Run:
        """As :meth:`CompiledLoop.sampled`."""
        m = self.model
        bound = _bounds(m, bound)
        grid, (out, dist, ctrl) = merged_grid(clocks)
        xp, xc = np.asarray(xp0, dtype=float), np.asarray(xc0, dtype=float)
        uh = np.zeros(m.held.size) if uh0 is None else np.asarray(uh0, dtype=float)
        rv, first, queue = np.zeros(m.recorded.size), 1.0, []
        X, R, times, w_index = [], [], [], []
        i_w, status, t_stop, env = 0, SIM_OK, np.nan, None
        event = None if m.event is None else (lambda x, t: float(m.event(x, t, pp)))
        g_start = event(xp, grid[0]) if event is not None else None
        for j, t in enumerate(grid):
            if dist[j] >= 0:
                i_w = dist[j]
            if ctrl[j] >= 0:
                xc_n, uh_n, rv_n, guard = (np.asarray(v, dtype=float).ravel() for v in
                                           m.controller(xp, xc, pc, first, t))
                if not abs(guard[0]) >= guard_min:
                    status, t_stop = SIM_GUARD, t
                    break
                if not (np.all(np.isfinite(xc_n)) and np.all(np.isfinite(uh_n))
                        and np.all(np.isfinite(rv_n))):
                    status, t_stop = SIM_NONFINITE, t
                    break
                xc, rv, first = xc_n, rv_n, 0.0
                queue.append(uh_n)
                if len(queue) > delay:
                    uh = queue.pop(0)
            x = np.asarray(m.assemble(xp, xc), dtype=float).ravel()
            env = self._outside(x, uh, bound)
            if env is not None:
                status, t_stop = SIM_ENVELOPE, t
                break
            if out[j] >= 0:
                X.append(x)
                R.append(rv)
                times.append(clocks[0].times()[out[j]])
                w_index.append(i_w)
            if j + 1 == len(grid):
                break
            w, span = W[i_w], grid[j + 1] - t

            def step(xx, tt, h, uh=uh, w=w):
                return self._plant(xx, uh, w, tt, pp, h)

            start = xp
            xp = rk4_span(step, start, t, span, substeps)
            if not np.all(np.isfinite(xp)):
                status, t_stop = SIM_NONFINITE, grid[j + 1]
                break
            if event is not None:
                g_end = event(xp, grid[j + 1])
                if g_start > 0 and not g_end > 0:
                    offset, xp = locate_event(step, event, start, xp, t, span, substeps)
                    status, t_stop = SIM_EVENT, t + offset
                    break
                g_start = g_end
        return _run(m, status, X, R, times, w_index, np.concatenate([xp, xc]), t_stop, env)

    def ride(self, z0, a, rows: Clock, t_ev: float, t_end: float, h_max: float, pp) -> Ride:
        """As :meth:`CompiledLoop.ride` (:func:`quadland.engine.loop.ride_grid`)."""
        m = self.model
        step, z, t_prev = self._ride_step, np.asarray(z0, dtype=float), t_ev
        out = {"X": [], "Y": [], "R": []}
        times, steps = ride_grid(rows, t_ev, t_end, h_max)
        status = SIM_OK
        for t, s in zip(times, steps, strict=True):
            z = rk4_span(lambda zz, tt, h: step(zz, tt, pp, h), z, t_prev, t - t_prev, s)
            t_prev = t
            x, y, r = (np.asarray(v, dtype=float).ravel() for v in m.ride_row(z, a, t, pp))
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                status = SIM_NONFINITE
                break
            for name, v in zip("XYR", (x, y, r), strict=True):
                out[name].append(v)
        k = len(out["X"])
        sizes = {"X": m.state.size, "Y": m.outputs.size, "R": m.recorded.size}
        X, Y, R = (np.array(out[n], dtype=float).reshape(-1, sizes[n]) for n in "XYR")
        return Ride(status, times[:k], X, Y, R)

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


def _run(m: LoopModel, status, X, R, times, w_index, x_end, t_stop, env) -> Run:
    X = np.array(X, dtype=float).reshape(-1, m.state.size)
    R = None if R is None else np.array(R, dtype=float).reshape(-1, m.recorded.size)
    return Run(status, X, R, np.array(times, dtype=float), np.array(w_index, dtype=np.int_),
               np.asarray(x_end, dtype=float), t_stop, env if status == SIM_ENVELOPE else None)


def _bounds(model: LoopModel, bound) -> np.ndarray:
    """The envelope's bounds as the drivers take them (none without an envelope)."""
    if model.envelope is None:
        return np.zeros(0)
    bound = _f64(bound)
    if bound.shape != (model.envelope_layout.size,):
        raise ValueError(f"bound: expected {model.envelope_layout.size} envelope bounds, "
                         f"got shape {bound.shape}")
    return bound


@dataclasses.dataclass(frozen=True)
class FlightCode:
    """Flight C a simulator flies in place of the symbolic controller (part
    ``"sampled_flight"``): every file of its build by name, and the sources to compile."""

    files: tuple[tuple[str, str], ...]
    sources: tuple[str, ...]


@functools.cache
def compiled_loop(loop: LoopModel, part: str,
                  flight: FlightCode | None = None) -> CompiledLoop | VMLoop:
    """The ``part`` of a loop's simulator: compiled, or on the VM.

    ``part`` is a key of ``quadland_symbolic.codegen.SIMULATOR_PARTS``;
    ``"sampled_flight"`` needs ``flight``, the flight code behind the loop's
    adapter (:attr:`LoopModel.flight`). Without a C compiler: a
    :class:`VMLoop` after one :class:`QuadlandWarning`; the flight code exists
    only compiled. One simulator is kept per loop, part and flight code (a
    build is cached on disk, but loading it is not free);
    ``compiled_loop.cache_clear()`` forgets them.

    A compiler that fails or runs over its time (``--version`` too), a
    ``$CC`` that names no program, a cache that cannot be written (a full
    disk), a library that does not load or C over the build's budgets
    (``quadland.engine.build.plan_build``) also give the VM after one warning; the
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
    if (part == "sampled_flight") != (flight is not None):
        raise ValueError("flight code goes with part 'sampled_flight', and only with it")
    if not have_compiler():
        why = compiler_problem()
        given = why is not None and why.startswith("CC=")   # a $CC that names no program
        if part == "sampled_flight":
            raise CompilerNotFoundError(
                "controller.backend = \"c\" flies the compiled flight code, and "
                + (f"{why} (or use" if given else
                   "no C compiler was found (set CC or install gcc; or use")
                + " controller.backend = \"casadi\")")
        _warn_no_compiler(why if given else "no C compiler found (set CC or install gcc)")
        return VMLoop(loop, part)
    try:
        return CompiledLoop(loop, part, flight=None if flight is None else dict(flight.files),
                            flight_sources=() if flight is None else flight.sources)
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
def _warn_no_compiler(why: str) -> None:
    warnings.warn(f"{why}: simulating on CasADi's virtual machine, several times slower",
                  QuadlandWarning, stacklevel=4)

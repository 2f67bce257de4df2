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
from collections.abc import Callable

import numpy as np

from quadland import interrupt
from quadland.engine.build import build_library, compiler_problem, have_compiler, plan_build
from quadland.engine.loop import Clock
from quadland.engine.recall import recall_key, recalled, remember
from quadland.engine.runs import (
    SIM_CONTROLLER,
    SIM_ENVELOPE,
    SIM_EVENT,
    SIM_GUARD,
    SIM_NONFINITE,
    SIM_OK,
    SIM_ROWS,
    Ride,
    Run,
    as_f64,
    envelope_bounds,
    row_buffer,
    tick_source,
)
from quadland.engine.vm import VMLoop
from quadland.exceptions import CompileError, CompilerNotFoundError
from quadland_symbolic.codegen.simulator import SIMULATOR_PARTS
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.loop_recipe import LoopRecipe

__all__ = ["QuadlandWarning", "CompiledLoop", "VMLoop", "compiled_loop", "SIM_OK",
           "SIM_NONFINITE", "SIM_GUARD", "SIM_CONTROLLER", "SIM_EVENT", "SIM_ENVELOPE",
           "SIM_ROWS", "Run", "Ride", "FlightCode"]



_REAL = ctypes.POINTER(ctypes.c_double)
_LONG = ctypes.POINTER(ctypes.c_long)
#: The driver's ``more(tick)``: rows of the per-tick table filled past ``tick``.
_MORE = ctypes.CFUNCTYPE(ctypes.c_long, ctypes.c_long)


class QuadlandWarning(UserWarning):
    """Something quadland worked around (e.g. no C compiler: a slower path)."""


def simulator_sources(model: LoopModel, part: str) -> dict[str, str]:
    """:func:`quadland_symbolic.codegen.simulator_sources`, its module (Jinja2 and the C
    writers) loaded on the first call: a cached simulator needs none of it."""
    from quadland_symbolic.codegen.simulator import simulator_sources as sources

    return sources(model, part)


def _ptr(a: np.ndarray, kind=_REAL):
    return a.ctypes.data_as(kind)






def _more_callback(more) -> tuple[object, list]:
    """``more`` as the driver's C callback (NULL for None), and the list that receives
    what it raised (the driver then stops: no rows past the tick)."""
    failed: list[BaseException] = []
    if more is None:
        return ctypes.cast(None, _MORE), failed

    def call(tick: int) -> int:
        try:
            return int(more(int(tick)))
        except BaseException as exc:            # noqa: BLE001 - re-raised after the call
            failed.append(exc)
            return -1
    return _MORE(call), failed


def _clock_table(clocks) -> np.ndarray:
    return np.ascontiguousarray([c.table() for c in clocks], dtype=np.float64).ravel()




class CompiledLoop:
    """One compiled part (``"continuous"`` or ``"sampled"``) of a loop's simulator.

    Parameters
    ----------
    model : LoopModel or LoopRecipe
        A recipe's CasADi functions are built only when the library is not in the
        cache (its key is the recipe's: :func:`quadland.engine.recall.recall_key`).
    part : {"continuous", "sampled", "sampled_flight"}
    opt : str
        Optimization flag of the build.
    """

    def __init__(self, model: LoopModel | LoopRecipe, part: str, opt: str = "-O2",
                 flight: FlightCode | None = None):
        self.model, self.part = model, part
        name = f"qlsim_{model.name}_{part}"
        key = recall_key(model, part, None if flight is None else flight.recipe,
                         () if flight is None else flight.sources, name, opt, strict=False)
        self.library = recalled(key)                 # without generating the C
        if self.library is None:
            files = simulator_sources(built_model(model), part)   # (the C writers load here)
            sources = tuple(sorted(n for n in files if n.endswith(".c")))
            if flight is not None:                   # the flight code's own sources
                files = {**dict(flight.files), **files}
                sources += flight.sources
            self.library = build_library(files, sources, opt, name, strict=False)
            if not plan_build(files, sources, opt).lowered:   # a lowered build warns each time
                remember(key, self.library)
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
            self._sampled.argtypes = [_REAL, _REAL, _REAL, D, _REAL, _REAL, L, _MORE, L, L,
                                      _REAL,
                                      _REAL, _REAL,
                                      D, _REAL, _REAL, _REAL, _REAL, _LONG, L, _LONG, _REAL,
                                      _REAL, ctypes.POINTER(D), _REAL, D, D,
                                      ctypes.POINTER(D), _REAL, D]
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
        x0, W, p, bound = as_f64(x0), as_f64(W), as_f64(p), envelope_bounds(m, bound)
        rows = out.count()
        assert W.shape == (dist.count(), m.disturbance.size)
        X = row_buffer(rows, m.state.size)
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
                bound=None, delay: int = 0, uh0=None, N=None, h_after: float = np.inf,
                after: float = np.inf, near: float = np.inf) -> Run:
        """The sampled-data loop over the merged grid of its output, disturbance and
        control clocks.

        ``N`` (one row per control tick) are the controller's per-tick inputs of a
        model with :attr:`~quadland_symbolic.loop.LoopModel.tick_inputs`.

        ``delay`` control periods pass between computing a command and applying
        it (``uh0`` is held before the first arrives; zero by default). A model
        with an event stops where it happens: the run's status is
        :data:`SIM_EVENT`, ``t_stop`` its instant and ``x_end`` the state then; a
        model whose event continues (:attr:`LoopModel.event_continues`) records its
        first crossing (the run's ``t_event``, ``x_event``) and goes on in RK4 steps
        of at most ``h_after`` until ``after`` seconds past it.
        ``bound`` (nenv,) are the envelope's bounds: the run stops at the first
        grid point outside them (:data:`SIM_ENVELOPE`). A model with a
        :attr:`~quadland_symbolic.loop.LoopModel.free_plant` integrates it, before
        the first crossing, over each grid interval whose event function is above
        ``near`` at both ends (infinity, the default: never).
        """
        m = self.model
        out, dist, _ = clocks
        xp0, xc0, W, pp, pc = (as_f64(a) for a in (xp0, xc0, W, pp, pc))
        bound = envelope_bounds(m, bound)
        uh0 = np.zeros(m.held.size) if uh0 is None else as_f64(uh0)
        rows = out.count()
        assert W.shape == (dist.count(), m.disturbance.size)
        # each row the driver returns is written whole (simulator.c.jinja's memcpy of x, rv)
        X = row_buffer(rows, m.state.size, zeroed=False)
        R = row_buffer(rows, m.recorded.size, zeroed=False)
        times, w_index = np.zeros(rows), np.zeros(rows, dtype=np.int_)
        xp_end, xc_end = np.empty(m.plant_state.size), np.empty(m.controller_state.size)
        env = np.full(max(bound.size, 1), np.nan)
        n_rows, t_stop = ctypes.c_long(0), ctypes.c_double(np.nan)
        t_event, x_event = ctypes.c_double(np.nan), np.full(m.state.size, np.nan)
        N, filled, more = tick_source(m, N)
        more_c, failed = _more_callback(more)
        status = self._sampled(
            _ptr(xp0), _ptr(xc0), _ptr(_clock_table(clocks)), float(out.T), _ptr(W),
            _ptr(N), filled, more_c, int(substeps), int(delay), _ptr(uh0), _ptr(pp),
            _ptr(pc),
            float(guard_min),
            _ptr(bound), _ptr(X), _ptr(R), _ptr(times), _ptr(w_index, _LONG), rows,
            ctypes.byref(n_rows), _ptr(xp_end), _ptr(xc_end), ctypes.byref(t_stop), _ptr(env),
            float(h_after), float(after), ctypes.byref(t_event), _ptr(x_event), float(near))
        if failed:                                  # raised in more(): raised here
            raise failed[0]
        n = n_rows.value
        hit = not np.isnan(t_event.value)
        return Run(status, X[:n], R[:n], times[:n], w_index[:n], np.concatenate([xp_end, xc_end]),
                   t_stop.value, env if status == SIM_ENVELOPE else None, t_event.value,
                   x_event if hit else None)

    def ride(self, z0, a, rows: Clock, t_ev: float, t_end: float, h_max: float, pp) -> Ride:
        """The ride after the event at ``t_ev`` (a model with ``ride_rhs``, ``ride_row``):
        ``z0`` carried to ``t_end``, a row at each tick of ``rows`` after ``t_ev`` and at
        ``t_end`` (``quadland_loop.h``'s ``qll_ride``)."""
        m = self.model
        n = len(rows.times()) + 1
        X, Y = np.zeros((n, m.state.size)), np.zeros((n, m.outputs.size))
        R, times, n_rows = np.zeros((n, m.recorded.size)), np.zeros(n), ctypes.c_long(0)
        status = self._ride(_ptr(as_f64(z0)), _ptr(as_f64(a)), _ptr(_clock_table([rows])),
                            float(rows.T), float(t_ev), float(t_end), float(h_max),
                            _ptr(as_f64(pp)), _ptr(X), _ptr(Y), _ptr(R), _ptr(times), n,
                            ctypes.byref(n_rows))
        k = n_rows.value
        return Ride(status, times[:k], X[:k], Y[:k], R[:k])

    def outputs(self, X, W, T, p) -> np.ndarray:
        """Output signals at each row of ``X`` (with ``W``'s rows, at times ``T``), ``(n, ny)``."""
        m = self.model
        X, W, T, p = as_f64(X), as_f64(W), as_f64(T), as_f64(p)
        n = X.shape[0]
        assert X.shape == (n, m.state.size) and W.shape == (n, m.disturbance.size)
        assert T.shape == (n,)
        Y = np.empty((n, m.outputs.size))
        self._outputs(_ptr(X), _ptr(W), _ptr(T), n, _ptr(p), _ptr(Y))
        return Y










@dataclasses.dataclass(frozen=True)
class FlightCode:
    """Flight C a simulator flies in place of the symbolic controller (part
    ``"sampled_flight"``): the sources to compile, a recipe key of what its files are
    generated from (:func:`quadland.engine.recall.code_recipe`: equal keys, equal files),
    and ``make()``, which generates them (every file of the build by name), called only
    when the simulator is not in the cache."""

    sources: tuple[str, ...]
    recipe: str
    make: Callable[[], tuple[tuple[str, str], ...]] = dataclasses.field(
        compare=False, repr=False)

    @property
    def files(self) -> tuple[tuple[str, str], ...]:
        """Every file of the build by name (generated on each call)."""
        return self.make()


def built_model(loop: LoopModel | LoopRecipe) -> LoopModel:
    """The model of ``loop``: a recipe's built (once) and checked against the layouts,
    name and absent functions the recipe gave without building it.

    Raises
    ------
    ValueError
        When the recipe's description differs from the model it builds.
    """
    if not isinstance(loop, LoopRecipe):
        return loop
    model = loop.model
    wrong = [n for n, v in loop.known().items() if getattr(model, n) != v]
    if wrong or model.name != loop.name:
        raise ValueError(f"{loop!r} describes its model wrongly: {', '.join(wrong) or 'name'}")
    return model


@functools.cache
def compiled_loop(loop: LoopModel | LoopRecipe, part: str, flight: FlightCode | None = None,
                  opt: str = "-O2") -> CompiledLoop | VMLoop:
    """The ``part`` of a loop's simulator: compiled (at ``opt``), or on the VM.

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
    interrupt.check()                           # one a library swallowed while the loop was built
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
        return VMLoop(built_model(loop), part)
    try:
        return CompiledLoop(loop, part, opt, flight=flight)
    except (CompileError, OSError, AttributeError) as exc:
        # A broken compiler or cache (the build checks the library loads; a library
        # without the driver's symbols is the last resort): CasADi's VM still works.
        text = (str(exc) or repr(exc)).splitlines()[0]
        why = text if isinstance(exc, CompileError) else \
            f"the compiled simulator does not load: {text}"
        if part == "sampled_flight":
            raise CompileError(why) from None
        _warn_compile_failed(why)
        return VMLoop(built_model(loop), part)


@functools.cache
def _warn_compile_failed(why: str) -> None:
    warnings.warn(f"{why}; simulating on CasADi's virtual machine, several times slower",
                  QuadlandWarning, stacklevel=4)


@functools.cache
def _warn_no_compiler(why: str) -> None:
    warnings.warn(f"{why}: simulating on CasADi's virtual machine, several times slower",
                  QuadlandWarning, stacklevel=4)

"""Compiled simulators: the loops of ``symbolic.simulation`` as native code.

:func:`compiled_loop` generates the C of one part of a simulator
(``symbolic.simulation.simulator_sources``), builds it once into the disk
cache (:mod:`quadland.build`) and loads it with ``ctypes``. A call runs a
whole simulation in C: RK4 over the exact time grid, the parameters passed
once, states and outputs written straight into NumPy arrays. Where no C
compiler is found, :func:`compiled_loop` returns None after one warning, and
the simulator falls back to CasADi's virtual machine.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import warnings

import numpy as np

from quadland.build import build_library, have_compiler
from symbolic.simulation import SIMULATOR_PARTS, LoopModel, paper_loop, simulator_sources

__all__ = ["QuadlandWarning", "CompiledLoop", "compiled_loop", "SIM_OK", "SIM_NONFINITE",
           "SIM_GUARD", "SIM_CONTROLLER"]

#: Status codes of the drivers (``symbolic/templates/simulator.c.jinja``).
SIM_OK, SIM_NONFINITE, SIM_GUARD, SIM_CONTROLLER = 0, 1, 2, 3

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
    """Where a compiled run stopped: its status and grid index."""

    status: int
    index: int


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
                 flight: dict[str, str] | None = None):
        self.model, self.part = model, part
        files = simulator_sources(model, part)
        sources = tuple(sorted(n for n in files if n.endswith(".c")))
        if flight is not None:                       # the flight step's own sources
            files = {**flight, **files}
            sources += ("control_step.c", "quadland.c")
        self.library = build_library(files, sources, opt, f"qlsim_{model.name}_{part}",
                                     strict=False)
        lib = ctypes.CDLL(str(self.library))
        prefix = f"qlsim_{model.name}_"
        self._outputs = getattr(lib, f"{prefix}{part}_outputs")
        self._outputs.argtypes = [_REAL, _REAL, ctypes.c_long, _REAL, _REAL]
        if part == "continuous":
            self._integrate = getattr(lib, f"{prefix}integrate")
            self._integrate.argtypes = [_REAL, _REAL, _REAL, _LONG, ctypes.c_long,
                                        ctypes.c_long, _REAL, _REAL, _REAL, _LONG]
        else:
            self._sampled = getattr(lib, f"{prefix}sampled")
            self._sampled.argtypes = [_REAL, _REAL, _REAL, _REAL, ctypes.c_char_p, _LONG,
                                      ctypes.c_long, ctypes.c_long, _REAL, _REAL,
                                      ctypes.c_double, _REAL, _REAL, _REAL, _REAL, _LONG]

    def integrate(self, x0, W, H, rec, substeps: int, p, n_rows: int):
        """The continuous loop over ``len(H)`` intervals (see the driver's docs).

        Parameters
        ----------
        x0 : array_like, (nx,)
        W : array_like, (n, nw)
            Disturbance held over each interval.
        H : array_like, (n,)
            Interval lengths, s.
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
        x0, W, H, p = _f64(x0), _f64(W), _f64(H), _f64(p)
        rec = np.ascontiguousarray(rec, dtype=np.int_)
        n = len(H)
        assert W.shape == (n, m.disturbance.size) and rec.shape == (n,)
        X = np.zeros((n_rows, m.state.size))
        X[0] = x0
        x_end = np.empty(m.state.size)
        fail = ctypes.c_long(-1)
        status = self._integrate(_ptr(x0), _ptr(W), _ptr(H), _ptr(rec, _LONG), n, int(substeps),
                                 _ptr(p), _ptr(X), _ptr(x_end), ctypes.byref(fail))
        return X, x_end, (Failure(status, fail.value) if status else None)

    def sampled(self, xp0, xc0, W, H, ctrl, rec, substeps: int, pp, pc, guard_min: float,
                n_rows: int):
        """The sampled-data loop over ``len(H)`` intervals (see the driver's docs).

        ``ctrl`` (n,) and ``rec`` (n + 1,) flag, per grid point, a control
        step and the row it is recorded to (or -1).

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
        xp0, xc0, W, H, pp, pc = (_f64(a) for a in (xp0, xc0, W, H, pp, pc))
        ctrl = np.ascontiguousarray(ctrl, dtype=np.uint8)
        rec = np.ascontiguousarray(rec, dtype=np.int_)
        n = len(H)
        assert W.shape == (n, m.disturbance.size) and ctrl.shape == (n,)
        assert rec.shape == (n + 1,)
        X = np.zeros((n_rows, m.state.size))
        R = np.zeros((n_rows, m.recorded.size))
        xp_end, xc_end = np.empty(m.plant_state.size), np.empty(m.controller_state.size)
        fail = ctypes.c_long(-1)
        status = self._sampled(_ptr(xp0), _ptr(xc0), _ptr(W), _ptr(H), ctrl.ctypes.data_as(
            ctypes.c_char_p), _ptr(rec, _LONG), n, int(substeps), _ptr(pp), _ptr(pc),
            float(guard_min), _ptr(X), _ptr(R), _ptr(xp_end), _ptr(xc_end), ctypes.byref(fail))
        return X, R, xp_end, xc_end, (Failure(status, fail.value) if status else None)

    def outputs(self, X, W, p) -> np.ndarray:
        """Output signals at each row of ``X`` (with ``W``'s rows), ``(n, ny)``."""
        m = self.model
        X, W, p = _f64(X), _f64(W), _f64(p)
        n = X.shape[0]
        assert X.shape == (n, m.state.size) and W.shape == (n, m.disturbance.size)
        Y = np.empty((n, m.outputs.size))
        self._outputs(_ptr(X), _ptr(W), n, _ptr(p), _ptr(Y))
        return Y


@functools.lru_cache(maxsize=16)
def compiled_loop(l: int, part: str) -> CompiledLoop | None:
    """The compiled ``part`` of the paper loop's simulator for ``l`` nodes, or None.

    ``part`` is a key of ``symbolic.simulation.SIMULATOR_PARTS``.

    None (after one :class:`QuadlandWarning`) when no C compiler is found.
    """
    if part not in SIMULATOR_PARTS:
        raise ValueError(f"part must be one of {', '.join(SIMULATOR_PARTS)}, got {part!r}")
    if not have_compiler():
        _warn_no_compiler()
        return None
    flight = None
    if part == "sampled_flight":
        from quadland.cbackend import sources

        flight = sources(l, "double")
    return CompiledLoop(paper_loop(l), part, flight=flight)


@functools.cache
def _warn_no_compiler() -> None:
    warnings.warn("no C compiler found (set CC or install gcc): simulating in CasADi's "
                  "virtual machine, several times slower", QuadlandWarning, stacklevel=3)

"""The generated C, compiled on demand and called from Python.

The sources of ``generated/`` (or, for another node count ``l``, sources
generated for it) are compiled with the system's C compiler into a shared
library, cached under ``$XDG_CACHE_HOME/quadland`` (``~/.cache/quadland``)
by a hash of the sources, compiler and flags, and loaded with ``ctypes``.

:func:`load_control_step` returns a callable with the calling convention and
outputs of ``symbolic.control_step.control_step_function`` (NumPy arrays of
the same shapes), used by the sampled-data simulation with
``controller.backend = "c"``; :func:`load_api` gives the readable ``ql_``
API with ``ctypes`` mirrors of its structs.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
from pathlib import Path

import numpy as np

from quadland.build import build_library
from symbolic.control_step import step_inputs, step_outputs
from symbolic.layout import Layout
from symbolic.parameters import QUADROTOR, VEHICLE, controller_layout

__all__ = ["sources", "CControlStep", "load_control_step", "CApi", "load_api"]

_STEP_SOURCES = ("control_step.c", "quadland.c")
_ALL_SOURCES = _STEP_SOURCES + ("closed_loop.c", "plant.c", "quadland_model.c",
                                "closed_loop_jacobian.c", "quadland_jacobian.c")


@functools.lru_cache(maxsize=8)
def _generated_sources(l: int, precision: str) -> tuple[tuple[str, str], ...]:
    from quadland.codegen import GENERATED_DIR, default_values
    from symbolic.codegen import CodegenConfig, generate

    folder = GENERATED_DIR if precision == "double" else GENERATED_DIR / "float"
    header = folder / "quadland.h"
    if header.exists() and f"#define QL_RBF_NODES {l} " in header.read_text():
        files = {p.name: p.read_text() for p in folder.iterdir() if p.suffix in (".c", ".h")}
    else:
        files = generate(_defaults_for(l, default_values()), CodegenConfig(precision))
    return tuple(sorted(files.items()))


def _defaults_for(l, defaults):
    if l == defaults.l:
        return defaults
    from quadland.model import model_values
    from quadland.scenario import load_scenario

    mv = model_values(load_scenario("paper", [f"rbf.nodes={l}"]))
    return dataclasses.replace(defaults, l=l, p_ctrl=mv.p_ctrl, x0=mv.x0)


def sources(l: int, precision: str = "double") -> dict[str, str]:
    """The C files for ``l`` nodes: ``generated/`` when it matches, else fresh ones."""
    if precision not in ("double", "float"):
        raise ValueError(f"precision must be 'double' or 'float', got {precision!r}")
    return dict(_generated_sources(l, precision))


def _pointer_array(arrays, ctype):
    return (ctypes.POINTER(ctype) * len(arrays))(
        *[a.ctypes.data_as(ctypes.POINTER(ctype)) for a in arrays])


class CControlStep:
    """The compiled ``control_step``, called like the CasADi function.

    ``step(xq, yv, ref, W_hat, zeta_hat, u_prev, p_quad, p_ctrl,
    rotor_limits, hold, dt) -> (u, wrench, rotor, W_next, zeta_next, u_law,
    n_clipped, tilt)``, each a
    float64 array shaped as the CasADi function's output (``(4, 1)``,
    ``(l, 4)``, ``(1, 1)``, ...). With ``precision = "float"`` the inputs
    are rounded to float32 and the single-precision build runs. The object
    reuses its buffers between calls: use one per thread.
    """

    def __init__(self, l: int, precision: str = "double", opt: str = "-O2"):
        self.l, self.precision = l, precision
        files = sources(l, precision)
        self.library = build_library(files, _STEP_SOURCES, opt)
        self._lib = ctypes.CDLL(str(self.library))
        self._real = ctypes.c_double if precision == "double" else ctypes.c_float
        self._dtype = np.float64 if precision == "double" else np.float32
        fn = self._lib.control_step
        ptr = ctypes.POINTER(self._real)
        fn.argtypes = [ctypes.POINTER(ptr), ctypes.POINTER(ptr), ctypes.POINTER(ctypes.c_int),
                       ptr, ctypes.c_int]
        fn.restype = ctypes.c_int
        self._fn = fn
        self._in_names = step_inputs(l).names()
        in_sizes = tuple(f.size for f in step_inputs(l).fields)
        self._out_names = step_outputs(l).names()
        self._out_shapes = tuple(f.shape or (f.size, 1) for f in step_outputs(l).fields)
        # Buffers and pointer arrays live as long as the object: a call only copies.
        self._ins = [np.zeros(n, dtype=self._dtype) for n in in_sizes]
        self._outs = [np.zeros(int(np.prod(s)), dtype=self._dtype) for s in self._out_shapes]
        self._arg = _pointer_array(self._ins, self._real)
        self._res = _pointer_array(self._outs, self._real)
        self._iw = (ctypes.c_int * 1)()
        self._w = (self._real * 1)()

    def __call__(self, *args):
        if len(args) != len(self._in_names):
            raise TypeError(f"control_step takes {len(self._in_names)} inputs {self._in_names}")
        for name, a, buf in zip(self._in_names, args, self._ins):
            v = np.asarray(a, dtype=float)
            if v.ndim > 1:
                v = v.reshape(-1, order="F")
            if v.size != buf.size:
                raise ValueError(f"control_step: {name} has {v.size} values, "
                                 f"expected {buf.size}")
            buf[:] = v.ravel()
        self._fn(self._arg, self._res, self._iw, self._w, 0)
        return tuple(o.astype(np.float64).reshape(s, order="F")
                     for o, s in zip(self._outs, self._out_shapes))

    def __repr__(self) -> str:
        return (f"CControlStep(l={self.l}, precision={self.precision!r}): "
                f"{', '.join(self._in_names)} -> {', '.join(self._out_names)}")


@functools.lru_cache(maxsize=8)
def load_control_step(l: int, precision: str = "double") -> CControlStep:
    """The compiled control step for ``l`` RBF nodes (built on first use).

    Raises
    ------
    CompilerNotFoundError
        When no C compiler is found.
    CompileError
        When the compiler rejects the sources.
    """
    return CControlStep(l, precision)


def _struct(name: str, fields, real):
    return type(name, (ctypes.Structure,), {"_fields_": list(fields)})


def _layout_struct(name: str, layout: Layout, real):
    fields = []
    for f in layout.fields:
        if f.shape is not None:
            fields.append((f.name, (real * f.shape[0]) * f.shape[1]))
        else:
            fields.append((f.name, real if f.size == 1 else real * f.size))
    return _struct(name, fields, real)


@dataclasses.dataclass(frozen=True)
class CApi:
    """The readable C API (``quadland.h``) loaded with ``ctypes``.

    Attributes
    ----------
    lib : ctypes.CDLL
        With ``ql_params_init``, ``ql_control_step``, ``ql_closed_loop``, ...
    QuadrotorState, VehicleState, Reference, AdaptiveState, Params, Output,
    VehicleParams : type
        ``ctypes.Structure`` mirrors of the header's structs.
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """

    lib: ctypes.CDLL
    QuadrotorState: type
    VehicleState: type
    Reference: type
    AdaptiveState: type
    Params: type
    Output: type
    VehicleParams: type
    real: type


@functools.lru_cache(maxsize=8)
def load_api(l: int, precision: str = "double", opt: str = "-O2", model: bool = True) -> CApi:
    """The generated library: the step's API and, with ``model``, the closed
    loop, its Jacobian and the plant (whose compilation takes most of the time)."""
    files = sources(l, precision)
    lib = ctypes.CDLL(str(build_library(files, _ALL_SOURCES if model else _STEP_SOURCES, opt)))
    real = ctypes.c_double if precision == "double" else ctypes.c_float
    S = _struct
    api = CApi(
        lib=lib,
        QuadrotorState=S("QuadrotorState", [("z1", real), ("eta1", real * 3), ("V1", real * 3),
                                            ("Omega1", real * 3)], real),
        VehicleState=S("VehicleState", [("z2", real), ("psi2", real), ("r2", real)], real),
        Reference=S("Reference", [("e1d", real * 4), ("e1d_dot", real * 4),
                                  ("e1d_ddot", real * 4)], real),
        AdaptiveState=S("AdaptiveState", [("W_hat", (real * l) * 4), ("zeta_hat", real * 4),
                                          ("u_prev", real * 4), ("has_prev", ctypes.c_int)],
                        real),
        Params=S("Params", [("quad", _layout_struct("QuadrotorParams", QUADROTOR, real)),
                            ("ctrl", _layout_struct("ControllerParams", controller_layout(l),
                                                    real)),
                            ("rotor_force_min", real), ("rotor_force_max", real),
                            ("tilt_min", real), ("hold_compensation", real)], real),
        Output=S("Output", [("u", real * 4), ("u_law", real * 4), ("wrench", real * 4),
                            ("rotor", real * 4), ("n_clipped", ctypes.c_int), ("tilt", real)],
                 real),
        VehicleParams=_layout_struct("VehicleParams", VEHICLE, real),
        real=real)
    P = ctypes.POINTER
    lib.ql_control_step.argtypes = [P(api.QuadrotorState), P(api.VehicleState),
                                    P(api.Reference), P(api.Params), real,
                                    P(api.AdaptiveState), P(api.Output)]
    lib.ql_control_step.restype = ctypes.c_int
    lib.ql_status_string.argtypes = [ctypes.c_int]
    lib.ql_status_string.restype = ctypes.c_char_p
    lib.ql_pack_closed_loop_params.argtypes = [P(api.Params), P(api.VehicleParams),
                                               P(api.Reference), P(real)]
    if not model:
        return api
    for name in ("ql_closed_loop", "ql_closed_loop_jacobian"):
        getattr(lib, name).argtypes = [P(real)] * 4
    lib.ql_plant.argtypes = [P(real)] * 6
    lib.ql_closed_loop_jacobian_sparsity.restype = P(ctypes.c_int)
    return api

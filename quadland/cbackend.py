"""The generated C, compiled on demand and called from Python.

Data flows one way: the C for the requested node count ``l`` and precision
is generated from ``symbolic`` (:func:`quadland_symbolic.codegen.generate`, with the
paper scenario's defaults and ``rbf.nodes = l``) and compiled with the
system's C compiler by :func:`quadland.build.build_library` into a shared
library, cached under ``$XDG_CACHE_HOME/quadland`` (``~/.cache/quadland``)
by a hash of the sources, compiler and flags, and loaded with ``ctypes``.
The source tree's ``generated/`` is never read, so an installed quadland
works the same as a checkout.

:func:`load_control_step` returns a callable with the calling convention and
outputs of ``quadland_symbolic.control_step.control_step_function`` (NumPy arrays of
the same shapes), used by the sampled-data simulation with
``controller.backend = "c"``; :func:`load_api` gives the readable API with
``ctypes`` mirrors of its structs, derived from the same layouts as the C
(:func:`ctypes_struct`).
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools

import numpy as np

from quadland.build import build_library
from quadland_symbolic.codegen import (
    FUNCTIONS,
    CodegenConfig,
    c_sources,
    generate,
    generate_landing,
)
from quadland_symbolic.codegen.structs import api_structs, landing_api_structs
from quadland_symbolic.control_step import step_inputs, step_outputs
from quadland_symbolic.layout import Layout

__all__ = ["sources", "ctypes_struct", "CControlStep", "load_control_step", "CApi", "load_api",
           "LandingApi", "load_landing_api"]

_MODEL = tuple(f.name for f in FUNCTIONS if f.part == "paper")


@functools.lru_cache(maxsize=8)
def _sources(l: int, precision: str, model: str) -> tuple[tuple[str, str], ...]:
    from quadland.codegen import (
        LANDING_SCENARIO,
        PAPER_SCENARIO,
        default_values,
        landing_default_values,
    )

    config = CodegenConfig(precision)
    paper = default_values(PAPER_SCENARIO)
    if model == "paper" and paper.l != l:
        paper = default_values(PAPER_SCENARIO, [f"rbf.nodes={l}"])
    files = generate(paper, config)
    if model == "landing":
        landing = landing_default_values(LANDING_SCENARIO)
        if landing.l != l:
            landing = landing_default_values(LANDING_SCENARIO, [f"rbf.nodes={l}"])
        files.update(generate_landing(landing, config))
    return tuple(sorted(files.items()))


def sources(l: int, precision: str = "double", model: str = "paper") -> dict[str, str]:
    """The C files of one build for ``l`` nodes, generated from ``symbolic``.

    ``model = "paper"``: the paper's control step (``quadland.h``), with the
    paper scenario's defaults and ``rbf.nodes = l``; ``"landing"``: also the
    landing step and guidance (``quadland_landing.h``) with the highway
    scenario's and ``rbf.nodes = l`` (the paper's with its own ``l``). For
    the scenarios' own ``l`` the files equal ``generated/`` (or
    ``generated/float/``).
    """
    if precision not in ("double", "float"):
        raise ValueError(f"precision must be 'double' or 'float', got {precision!r}")
    if model not in ("paper", "landing"):
        raise ValueError(f"model must be 'paper' or 'landing', got {model!r}")
    return dict(_sources(l, precision, model))


def _real(precision: str):
    return ctypes.c_double if precision == "double" else ctypes.c_float


@functools.cache
def ctypes_struct(layout: Layout, real) -> type:
    """The ``ctypes.Structure`` of a layout, as ``quadland_symbolic.codegen`` declares it in C.

    Real fields in order (a matrix ``shape = (rows, cols)`` as
    ``real[cols][rows]``), nested layouts as nested structures, ``int``
    fields as ``c_int``.

    Parameters
    ----------
    layout : Layout
        The struct's layout (``quadland_symbolic.codegen.structs``).
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """
    fields = []
    for f in layout.fields:
        if f.ctype == "int":
            fields.append((f.name, ctypes.c_int))
        elif f.layout is not None:
            fields.append((f.name, ctypes_struct(f.layout, real)))
        elif f.shape is not None:
            fields.append((f.name, (real * f.shape[0]) * f.shape[1]))
        else:
            fields.append((f.name, real if f.size == 1 else real * f.size))
    return type(layout.name, (ctypes.Structure,), {"_fields_": fields})


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
        self.library = build_library(files, c_sources(), opt)
        self._lib = ctypes.CDLL(str(self.library))
        self._real = _real(precision)
        self._dtype = np.float64 if precision == "double" else np.float32
        entry = next(f for f in FUNCTIONS if f.name == "control_step")
        fn = getattr(self._lib, entry.c_name(CodegenConfig(precision)))
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
        for name, a, buf in zip(self._in_names, args, self._ins, strict=True):
            v = np.asarray(a, dtype=float)
            if v.ndim > 1:
                v = v.reshape(-1, order="F")
            if v.size != buf.size:
                raise ValueError(f"control_step: {name} has {v.size} values, "
                                 f"expected {buf.size}")
            buf[:] = v.ravel()
        self._fn(self._arg, self._res, self._iw, self._w, 0)
        return tuple(o.astype(np.float64).reshape(s, order="F")
                     for o, s in zip(self._outs, self._out_shapes, strict=True))

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


class _Library:
    """A build's library, its API spelled ``ql_`` whatever the build's prefix.

    ``lib.ql_control_step`` is ``qlf_control_step`` in the float build;
    every other name is looked up as it is.
    """

    def __init__(self, cdll: ctypes.CDLL, prefix: str):
        self._cdll, self.prefix = cdll, prefix

    def __getattr__(self, name: str):
        if name.startswith("ql_"):
            name = self.prefix + name[3:]
        return getattr(self._cdll, name)


@dataclasses.dataclass(frozen=True)
class CApi:
    """The readable C API (``quadland.h``) loaded with ``ctypes``.

    Attributes
    ----------
    lib : object
        The library, with ``ql_params_init``, ``ql_check_params``,
        ``ql_control_step``, ``ql_closed_loop``, ... spelled ``ql_`` in
        either precision (the float build's symbols are ``qlf_...``).
    QuadrotorState, VehicleState, Reference, AdaptiveState, QuadrotorParams,
    ControllerParams, VehicleParams, Params, Output : type
        ``ctypes.Structure`` mirrors of the header's structs, from the same
        layouts (:func:`ctypes_struct`).
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """

    lib: object
    QuadrotorState: type
    VehicleState: type
    Reference: type
    AdaptiveState: type
    QuadrotorParams: type
    ControllerParams: type
    VehicleParams: type
    Params: type
    Output: type
    real: type


@functools.lru_cache(maxsize=8)
def load_api(l: int, precision: str = "double", opt: str = "-O2", model: bool = True) -> CApi:
    """The generated library: the step's API and, with ``model``, the closed
    loop, its Jacobian and the plant (whose compilation takes most of the time)."""
    files = sources(l, precision)
    config = CodegenConfig(precision)
    compiled = c_sources(_MODEL if model else ())
    lib = _Library(ctypes.CDLL(str(build_library(files, compiled, opt))), config.prefix)
    real = _real(precision)
    api = CApi(lib=lib, real=real,
               **{s.mirror: ctypes_struct(s.layout, real) for s in api_structs(l)})
    P = ctypes.POINTER
    lib.ql_control_step.argtypes = [P(api.QuadrotorState), P(api.VehicleState),
                                    P(api.Reference), P(api.Params), real,
                                    P(api.AdaptiveState), P(api.Output)]
    lib.ql_control_step.restype = ctypes.c_int
    lib.ql_check_params.argtypes = [P(api.Params), P(ctypes.c_char_p)]
    lib.ql_check_params.restype = ctypes.c_int
    lib.ql_status_string.argtypes = [ctypes.c_int]
    lib.ql_status_string.restype = ctypes.c_char_p
    lib.ql_pack_closed_loop_params.argtypes = [P(api.Params), P(api.VehicleParams),
                                               P(api.Reference), P(real)]
    if not model:
        return api
    for entry in FUNCTIONS:
        if entry.wrapper is None or entry.part != "paper":
            continue
        ins, outs = entry.arguments(l)
        getattr(lib, f"ql_{entry.name}").argtypes = [P(real)] * (len(ins) + len(outs))
    lib.ql_closed_loop_jacobian_sparsity.restype = P(ctypes.c_int)
    return api


@dataclasses.dataclass(frozen=True)
class LandingApi:
    """The landing API (``quadland_landing.h``) loaded with ``ctypes``.

    Attributes
    ----------
    lib : object
        The library, its names spelled ``ql_`` in either precision
        (``ql_landing_step``, ``ql_guidance_step``, ``ql_check_landing_params``,
        ...).
    LandingMeasurement, PositionReference, LandingState, LandingControllerParams,
    ActuatorParams, LandingParams, LandingOutput, GuidanceState, GuidanceParams : type
        ``ctypes.Structure`` mirrors of the header's structs (:func:`ctypes_struct`).
    real : type
        ``ctypes.c_double`` or ``ctypes.c_float``.
    """

    lib: object
    LandingMeasurement: type
    PositionReference: type
    LandingState: type
    LandingControllerParams: type
    ActuatorParams: type
    LandingParams: type
    LandingOutput: type
    GuidanceState: type
    GuidanceParams: type
    real: type


@functools.lru_cache(maxsize=8)
def load_landing_api(l: int, precision: str = "double", opt: str = "-O2") -> LandingApi:
    """The landing step and guidance for ``l`` nodes, compiled (the highway scenario's
    defaults, ``rbf.nodes = l``)."""
    files = sources(l, precision, "landing")
    config = CodegenConfig(precision)
    lib = _Library(ctypes.CDLL(str(build_library(files, c_sources(("landing_step",)), opt))),
                   config.prefix)
    real = _real(precision)
    api = LandingApi(lib=lib, real=real, **{s.mirror: ctypes_struct(s.layout, real)
                                            for s in landing_api_structs(l)})
    P = ctypes.POINTER
    lib.ql_landing_step.argtypes = [P(api.LandingMeasurement), P(api.PositionReference),
                                    P(api.LandingParams), real, P(api.LandingState),
                                    P(api.LandingOutput)]
    lib.ql_guidance_step.argtypes = [P(api.LandingMeasurement), P(api.GuidanceParams), real,
                                     P(api.GuidanceState), P(api.PositionReference)]
    for name, struct in (("landing", api.LandingParams), ("guidance", api.GuidanceParams)):
        check = getattr(lib, f"ql_check_{name}_params")
        check.argtypes = [P(struct), P(ctypes.c_char_p)]
        check.restype = ctypes.c_int
    lib.ql_landing_step.restype = lib.ql_guidance_step.restype = ctypes.c_int
    lib.ql_landing_state_init.argtypes = [P(api.LandingState), P(api.LandingMeasurement)]
    lib.ql_guidance_state_init.argtypes = [P(api.GuidanceState), P(api.GuidanceParams)]
    lib.ql_phase_name.restype = ctypes.c_char_p
    return api

"""The paper's flight code: its C defaults, its build, and the step called from Python.

The control step of ``quadland_symbolic.control_step`` generated as C
(``quadland.h``), with a scenario's values as its C defaults
(:func:`paper_defaults`; ``generated/`` carries the paper scenario's), built on
first use and loaded with ``ctypes``: :func:`load_control_step` (called like
the CasADi function, what ``controller.backend = "c"`` flies) and
:func:`load_api` (the readable API with ``ctypes`` mirrors of its structs).
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools

import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.build import build_library
from quadland.engine.compiled import FlightCode
from quadland.engine.flightcode import Library, ctypes_struct, label, pointer_array, real_type
from quadland.engine.recall import code_recipe
from quadland.kinds.paper import PAPER_SCENARIO
from quadland.kinds.paper.values import model_values
from quadland.scenario import Scenario, load_scenario
from quadland_symbolic import codegen
from quadland_symbolic.codegen import CodegenConfig, Defaults
from quadland_symbolic.control_step import step_inputs, step_outputs

__all__ = ["PAPER_SCENARIO", "EXAMPLE_CONTROL_RATE_HZ", "paper_defaults", "default_paper",
           "flight_files", "flight_code", "CControlStep", "load_control_step", "CApi",
           "load_api"]


#: Control rate of the pure-C example flight for a continuous-time scenario,
#: Hz (a flight stack's typical rate); a sampled scenario's own rate otherwise.
EXAMPLE_CONTROL_RATE_HZ = 500.0



def _model_functions() -> tuple[str, ...]:
    """The paper model's registered functions (the registry is loaded when first needed:
    it imports every kind's symbolic modules, which a cached simulator does not need)."""
    return tuple(f.name for f in codegen.FUNCTIONS if f.part == "paper")


def paper_defaults(sc: Scenario) -> Defaults:
    """The C defaults of the paper's control step and the example ``fly``: a scenario's values."""
    mv = model_values(sc)
    d, sim = sc.data["disturbance"], sc.data["simulation"]
    rate = float(sc.data["controller"]["rate_hz"]) or EXAMPLE_CONTROL_RATE_HZ
    return Defaults(
        scenario=label(sc), l=mv.l, p_quad=mv.p_quad, p_veh=mv.p_veh, p_ctrl=mv.p_ctrl, ref=mv.ref,
        rotor_limits=tuple(float(v) for v in mv.rotor_limits), tilt_min=TILT_MIN,
        hold=mv.hold, x0=mv.x0,
        duration=float(sim["duration"]), output_rate_hz=float(sim["output_rate_hz"]),
        control_rate_hz=rate,
        disturbance_rate_hz=float(d["sample_rate_hz"]),
        force_bias=tuple(float(v) for v in np.asarray(d["force_bias"], dtype=float)),
        force_amplitude=float(d["force_amplitude"]),
        force_frequency=float(d["force_frequency"]),
        moment_bias=tuple(float(v) for v in np.asarray(d["moment_bias"], dtype=float)),
        moment_amplitude=float(d["moment_amplitude"]),
        moment_frequency=float(d["moment_frequency"]))




@functools.cache
def default_paper(l: int) -> Defaults:
    """:func:`paper_defaults` of :data:`PAPER_SCENARIO` with ``rbf.nodes = l``."""
    sc = load_scenario(PAPER_SCENARIO)
    if sc["rbf.nodes"] != l:
        sc = load_scenario(PAPER_SCENARIO, [f"rbf.nodes={l}"])
    return paper_defaults(sc)


@functools.lru_cache(maxsize=8)
def _flight_files(l: int, precision: str) -> tuple[tuple[str, str], ...]:
    from quadland_symbolic.codegen import generate  # the C writers: on use

    return tuple(sorted(generate(default_paper(l), CodegenConfig(precision)).items()))


def flight_files(l: int, precision: str = "double") -> dict[str, str]:
    """The C files of one build of the paper's flight code for ``l`` nodes.

    With :data:`PAPER_SCENARIO`'s defaults and ``rbf.nodes = l``: for its own
    ``l`` the files equal ``generated/`` (or ``generated/float/``).
    """
    if precision not in ("double", "float"):
        raise ValueError(f"precision must be 'double' or 'float', got {precision!r}")
    return dict(_flight_files(l, precision))


def flight_code(l: int) -> FlightCode:
    """The control step the sampled simulator flies with ``controller.backend = "c"``."""
    return FlightCode(codegen.c_sources(("control_step",)), code_recipe("paper flight", f"l={l}"),
                      functools.partial(_flight_files, l, "double"))


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
        files = flight_files(l, precision)
        self.library = build_library(files, codegen.c_sources(), opt)
        self._lib = ctypes.CDLL(str(self.library))
        self._real = real_type(precision)
        self._dtype = np.float64 if precision == "double" else np.float32
        entry = next(f for f in codegen.FUNCTIONS if f.name == "control_step")
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
        self._arg = pointer_array(self._ins, self._real)
        self._res = pointer_array(self._outs, self._real)
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
    from quadland_symbolic.codegen.structs import api_structs  # the landing's too: on use

    files = flight_files(l, precision)
    config = CodegenConfig(precision)
    compiled = codegen.c_sources(_model_functions() if model else ())
    lib = Library(ctypes.CDLL(str(build_library(files, compiled, opt))), config.prefix)
    real = real_type(precision)
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
    for entry in codegen.FUNCTIONS:
        if entry.wrapper is None or entry.part != "paper":
            continue
        ins, outs = entry.arguments(l)
        getattr(lib, f"ql_{entry.name}").argtypes = [P(real)] * (len(ins) + len(outs))
    lib.ql_closed_loop_jacobian_sparsity.restype = P(ctypes.c_int)
    return api



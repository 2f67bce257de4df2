"""C code of the control step and the closed loop, with a readable API.

One entry point per tree, :func:`generate` (one precision) and
:func:`generate_tree` (everything under ``generated/``), turns the symbolic
functions into C text:

* one CasADi-generated file per function of the registry
  :data:`FUNCTIONS`, its symbols prefixed for the build, post-processed so
  that each compiles alone with ``-std=c99 -pedantic -Wall -Wextra
  -Werror`` (unused arguments are voided) and, for the single-precision
  build, uses float constants and float math;
* ``quadland.h`` / ``quadland.c`` (named structs, defaults and a checked
  ``ql_control_step`` over CasADi's arg/res arrays) and the named-pointer
  wrappers of the other functions, rendered from the Jinja2 templates in
  ``symbolic/templates/``. Python only builds the templates' context: the
  structs come from the layouts of :mod:`symbolic.c_api`, offsets and
  sizes from the layouts of the model, defaults as C literals;
* ``example/``: a pure-C flight of the scenario, a benchmark and their
  Makefile.

Every global C symbol carries the build's prefix (:attr:`CodegenConfig.prefix`:
``ql_`` for double, ``qlf_`` for float), CasADi's functions and helpers
included, so that both builds link into one program.

Numeric defaults (a scenario's values) are passed in as :class:`Defaults`;
this module imports nothing from ``quadland``. The output depends only on
its inputs and on the CasADi version, never on time or paths, so
regeneration is byte for byte reproducible.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import re
import tempfile
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import jinja2
import numpy as np

from symbolic.c_api import (
    MAX_ABORTS,
    CStruct,
    adaptive_state_layout,
    api_structs,
    guidance_param_ranges,
    guidance_state_layout,
    landing_api_structs,
    landing_output_layout,
    landing_param_ranges,
    landing_params_layout,
    output_layout,
    param_ranges,
    params_layout,
)
from symbolic.closed_loop import (
    PAPER_PLANT_STATE,
    closed_loop_function,
    closed_loop_jacobian_function,
    closed_loop_params,
    closed_loop_state,
    plant_function,
)
from symbolic.control_step import control_step_function, step_inputs, step_outputs
from symbolic.landing.contact import ANCHOR, anchor_function, landed_outputs_function
from symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    N_CHANNELS,
    NETWORK_INPUT_DIM,
    landing_guidance_function,
    landing_memory,
    landing_step_function,
    landing_step_outputs,
)
from symbolic.landing.guidance import (
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    PHASE_DOCS,
    PHASES,
    POSITION_REFERENCE,
)
from symbolic.landing.loop import gear_gap_function
from symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from symbolic.landing.relative import TOUCHDOWN_FIGURES, touchdown_figures_function
from symbolic.landing.sensors import measurement_function
from symbolic.landing.signals import LANDING_SIGNALS, LANDING_TRAJECTORY, landing_signals_function
from symbolic.layout import Field, Layout
from symbolic.parameters import QUADROTOR, RBF_INPUT_DIM, VEHICLE, controller_layout
from symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE
from symbolic.relative import E1
from symbolic.simulation import loop_header
from symbolic.vehicle import VEHICLE_MEASUREMENT, VEHICLE_STATE, vehicle_function

__all__ = ["CodegenConfig", "Defaults", "LandingDefaults", "GeneratedFunction", "FUNCTIONS",
           "STATUS_CODES", "TEMPLATE_DIR", "c_sources", "example_columns", "land_columns",
           "generate", "generate_landing", "generate_example", "generate_tree"]

#: Folder of the Jinja2 templates (installed with the package).
TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"

#: Status codes of ``ql_control_step`` and ``ql_check_params`` (name in the
#: double build, value, meaning).
STATUS_CODES = (
    ("QL_OK", 0, "success; outputs and adaptive state updated"),
    ("QL_ERR_NULL", 1, "a NULL pointer argument"),
    ("QL_ERR_INVALID", 2, "dt <= 0, or a guidance state out of range"),
    ("QL_ERR_NONFINITE_INPUT", 3, "an input, a parameter or the state is NaN or infinite"),
    ("QL_ERR_TILT", 4, "|cos(theta1) cos(phi1)| < tilt_min: thrust map not invertible"),
    ("QL_ERR_NONFINITE_OUTPUT", 5,
     "the law overflowed: a NaN or infinite value from finite inputs"),
    ("QL_ERR_PARAM", 6, "a parameter outside its range (ql_check_params names it)"),
)

_MATH = ("exp", "expm1", "log", "log1p", "sqrt", "cos", "sin", "tan", "acos", "asin", "atan",
         "atan2", "tanh", "sinh", "cosh", "fmin", "fmax", "fabs", "floor", "ceil", "pow", "erf",
         "hypot")
_MATH_RE = re.compile(r"\b(" + "|".join(_MATH) + r")\(")
_LITERAL_RE = re.compile(r"(?<![\w.])(\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")


@dataclasses.dataclass(frozen=True)
class CodegenConfig:
    """Emitter settings of the generated C.

    Attributes
    ----------
    precision : {"double", "float"}
        Type of every real; ``"float"`` also writes float constants
        (``1.5f``) and calls float math (``expf``).
    prefix : str, optional
        Prefix of every global C name of the build (functions, types and,
        upper-cased, macros and enumerators); ``"ql_"`` for double and
        ``"qlf_"`` for float by default.
    casadi_int : str
        C type of CasADi's integers (sparsity patterns).
    null_checks : bool
        Keep CasADi's convention that a NULL ``arg[i]`` reads as zeros and
        a NULL ``res[i]`` is skipped. Off by default: the tests cost two
        instructions per scalar read or written (a fifth of the control
        step), and every caller in the generated API passes all pointers.
    builder : str
        Name of the command that regenerates, written into each header.
    """

    precision: str = "double"
    prefix: str | None = None
    casadi_int: str = "int"
    null_checks: bool = False
    builder: str = "quadland codegen (symbolic/codegen.py)"

    def __post_init__(self):
        if self.precision not in ("double", "float"):
            raise ValueError(f"precision must be 'double' or 'float', got {self.precision!r}")
        if self.prefix is None:
            object.__setattr__(self, "prefix", "ql_" if self.precision == "double" else "qlf_")
        if not re.fullmatch(r"[a-z][a-z0-9]*_", self.prefix):
            raise ValueError(f"prefix must be lower-case letters and digits ending in '_', "
                             f"got {self.prefix!r}")

    @property
    def is_float(self) -> bool:
        """True for the single-precision build."""
        return self.precision == "float"

    @property
    def macro_prefix(self) -> str:
        """Prefix of the build's macros and enumerators (``QL_``)."""
        return self.prefix.upper()

    def literal(self, value: float) -> str:
        """A C literal of ``value`` in this precision (shortest round trip)."""
        text = repr(float(value))
        if not np.isfinite(value):
            raise ValueError(f"non-finite default {value}")
        if "." not in text and "e" not in text:
            text += ".0"
        return text + ("f" if self.is_float else "")

    def math(self, name: str) -> str:
        """Name of the C math function ``name`` in this precision."""
        return name + ("f" if self.is_float else "")


@dataclasses.dataclass(frozen=True)
class Defaults:
    """Numeric defaults written into the C (one scenario's values).

    Attributes
    ----------
    scenario : str
        Which scenario they are, for the comments: its name and overrides
        (never a path, so that the output does not depend on the machine).
    l : int
        RBF node count.
    p_quad, p_veh, p_ctrl : ndarray
        Parameter vectors in the layouts of ``symbolic.parameters``.
    ref : ndarray, (12,)
        ``[e1d, e1d_dot, e1d_ddot]``.
    rotor_limits : tuple of float
        ``(F_min, F_max)``, N.
    tilt_min : float
        Smallest accepted ``|cos(theta1) cos(phi1)|``.
    hold : float
        Hold compensation of the control step, periods.
    x0 : ndarray
        Initial closed-loop state.
    duration, output_rate_hz, control_rate_hz, disturbance_rate_hz : float
        Example flight: s, Hz, Hz (0 = continuous), Hz.
    force_bias, moment_bias : tuple of float
        N, N m, per axis.
    force_amplitude, force_frequency, moment_amplitude, moment_frequency : float
        N, rad/s, N m, rad/s.
    """

    scenario: str
    l: int
    p_quad: np.ndarray
    p_veh: np.ndarray
    p_ctrl: np.ndarray
    ref: np.ndarray
    rotor_limits: tuple[float, float]
    tilt_min: float
    hold: float
    x0: np.ndarray
    duration: float
    output_rate_hz: float
    control_rate_hz: float
    disturbance_rate_hz: float
    force_bias: tuple[float, float, float]
    force_amplitude: float
    force_frequency: float
    moment_bias: tuple[float, float, float]
    moment_amplitude: float
    moment_frequency: float


@dataclasses.dataclass(frozen=True)
class LandingDefaults:
    """Numeric defaults of the landing API and its example (one landing scenario's values).

    Attributes
    ----------
    scenario : str
        Its name and overrides, for the comments.
    l : int
        RBF node count of the landing step.
    p_quad, p_ctrl, p_act, p_guid : ndarray
        ``symbolic.parameters.QUADROTOR``, ``landing_controller_params(l)``,
        ``symbolic.landing.quadrotor.ACTUATOR``, ``symbolic.landing.guidance.GUIDANCE_PARAMS``.
    tilt_min : float
        Smallest accepted ``|cos(theta1) cos(phi1)|``.
    pp, xp0 : ndarray
        The example's plant parameters (``symbolic.landing.plant.LANDING_PLANT_PARAMS``)
        and initial plant state.
    duration, output_rate_hz, control_rate_hz, disturbance_rate_hz : float
        s, Hz, Hz, Hz.
    rk_steps : int
        RK4 steps per interval of the merged time grid.
    force_bias, moment_bias : tuple of float
    force_amplitude, force_frequency, moment_amplitude, moment_frequency : float
        The disturbance's deterministic part: N, rad/s, N m, rad/s.
    wind_mean : tuple of float
        m/s, E.
    gust_start, gust_half_length, gust_amplitude : float
        The 1-cosine gust: s, s, m/s (0: none).
    gust_direction : tuple of float
        Unit vector in E.
    settle_time : float
        s from touchdown to the end of the run.
    limits : tuple of (str, float)
        The touchdown limits by name (``max_sink_rate``, ...), in report order.
    """

    scenario: str
    l: int
    p_quad: np.ndarray
    p_ctrl: np.ndarray
    p_act: np.ndarray
    p_guid: np.ndarray
    tilt_min: float
    pp: np.ndarray
    xp0: np.ndarray
    duration: float
    output_rate_hz: float
    control_rate_hz: float
    disturbance_rate_hz: float
    rk_steps: int
    force_bias: tuple[float, float, float]
    force_amplitude: float
    force_frequency: float
    moment_bias: tuple[float, float, float]
    moment_amplitude: float
    moment_frequency: float
    wind_mean: tuple[float, float, float]
    gust_start: float
    gust_half_length: float
    gust_amplitude: float
    gust_direction: tuple[float, float, float]
    settle_time: float
    limits: tuple[tuple[str, float], ...]


@dataclasses.dataclass(frozen=True)
class GeneratedFunction:
    """One CasADi function written as C.

    Attributes
    ----------
    name : str
        The ``casadi.Function``'s name and the stem of its ``.c``/``.h``.
    builder : callable
        ``builder(l)`` (or ``builder()`` without ``per_node_count``)
        returns the function.
    per_node_count : bool
        Whether the function depends on the RBF node count ``l``.
    wrapper : str, optional
        File of its named-pointer wrapper ``ql_<name>(...)``, whose
        arguments are the function's ``name_in``/``name_out``; None when
        ``quadland.c`` wraps it.
    doc : str
        Comment of the wrapper in its header (``{ql}``/``{QL}`` stand for
        the build's prefixes).
    part : {"paper", "landing"}
        Which API it belongs to: ``quadland.h`` (the paper's control step,
        ``l`` of the paper's scenario) or ``quadland_landing.h`` (the landing
        step and guidance, ``l`` of the landing scenario).
    """

    name: str
    builder: Callable[..., ca.Function]
    per_node_count: bool = True
    wrapper: str | None = None
    doc: str = ""
    part: str = "paper"

    @property
    def source(self) -> str:
        """Dotted path of the builder, for the banner."""
        return f"{self.builder.__module__}.{self.builder.__qualname__}"

    def function(self, l: int) -> ca.Function:
        """The ``casadi.Function`` for ``l`` RBF nodes."""
        fn = self.builder(l) if self.per_node_count else self.builder()
        if fn.name() != self.name:
            raise ValueError(f"{self.source} builds {fn.name()!r}, registered as {self.name!r}")
        return fn

    def origin(self, l: int) -> str:
        """The builder's call, as the banner names it."""
        return f"{self.source}(l={l})" if self.per_node_count else f"{self.source}()"

    def c_name(self, config: CodegenConfig) -> str:
        """Its C symbol in a build: ``ql_casadi_control_step``."""
        return f"{config.prefix}casadi_{self.name}"

    def arguments(self, l: int) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Names of its inputs and outputs: the wrapper's arguments."""
        fn = self.function(l)
        return tuple(fn.name_in()), tuple(fn.name_out())


#: The CasADi functions written as C, in file order: the one registry.
FUNCTIONS = (
    GeneratedFunction("control_step", control_step_function),
    GeneratedFunction("closed_loop", closed_loop_function, wrapper="quadland_model.c",
                      doc="x_dot of the continuous-time closed loop (symbolic.closed_loop)."),
    GeneratedFunction("closed_loop_jacobian", closed_loop_jacobian_function,
                      wrapper="quadland_jacobian.c",
                      doc="d x_dot / d x: the {QL}CLOSED_LOOP_JACOBIAN_NNZ nonzeros in "
                          "compressed\n * column storage; {ql}closed_loop_jacobian_sparsity "
                          "gives the pattern\n * (CasADi format: nrow, ncol, colind[ncol + 1], "
                          "row[nnz])."),
    GeneratedFunction("plant", plant_function, per_node_count=False, wrapper="quadland_model.c",
                      doc="xp_dot of the plant alone (quadrotor, vehicle, planar position) "
                          "under a\n * held wrench and disturbance w."),
    GeneratedFunction("landing_step", landing_step_function, part="landing"),
    GeneratedFunction("landing_guidance", landing_guidance_function, per_node_count=False,
                      part="landing"),
    *(GeneratedFunction(name, builder, per_node_count=False, wrapper="quadland_landing_model.c",
                        doc=doc, part="landing") for name, builder, doc in (
        ("landing_loop_plant", loop_plant_function,
         "xp_dot of the landing plant (quadrotor with motor lag, vehicle; the deck's\n"
         " * motion is prescribed) under held rotor commands and w = [v_wind (E), d_F,\n"
         " * d_M (body)]."),
        ("landing_sensors", measurement_function,
         "The landing step's measurements y from the plant's state: perfect sensors."),
        ("landing_signals", landing_signals_function,
         "The landing trajectory's signals y ({QL}LANDING_NY): both bodies, the\n"
         " * relative state, the rotors, the external forces, phase and aborts."),
        ("landing_gear_gap", gear_gap_function,
         "The landing gear's height above the deck plane, m: touchdown is its zero\n"
         " * crossing."),
        ("landing_anchor", anchor_function,
         "The pose at touchdown (p_e, R_deck^T R1) from the signals y there."),
        ("landed_outputs", landed_outputs_function,
         "After touchdown: the signals y and the state x1q of the quadrotor pinned to\n"
         " * the deck at anchor, its rotor forces F winding down."),
        ("vehicle", vehicle_function, "xv_dot of the vehicle alone (eq. 3-4)."),
        ("touchdown_figures", touchdown_figures_function,
         "Sink rate (m/s), offset (m), relative speed (m/s) and tilt (deg) of a\n"
         " * contact."),
    )),
)

_BY_NAME = {f.name: f for f in FUNCTIONS}

#: The readable API's source of each part, which calls its functions without a wrapper.
_API_FILE = {"paper": "quadland.c", "landing": "quadland_landing.c"}


def c_sources(functions=("control_step",)) -> tuple[str, ...]:
    """The ``.c`` files that link the API of ``functions`` (names in :data:`FUNCTIONS`).

    For each part (``quadland.h``, ``quadland_landing.h``) a function belongs
    to (the paper's without any): its API file and the functions it calls
    (the paper's control step; the landing step and guidance); each other
    function with its wrapper's file; ``quadland_status.c`` always.
    """
    unknown = set(functions) - set(_BY_NAME)
    if unknown:
        raise ValueError(f"unknown generated functions {sorted(unknown)}")
    parts = [p for p in _API_FILE if any(_BY_NAME[f].part == p for f in functions)] or ["paper"]
    chosen = [f for f in FUNCTIONS
              if f.name in functions or (f.part in parts and f.wrapper is None)]
    files = [f"{f.name}.c" for f in chosen] + [_API_FILE[p] for p in parts]
    for f in chosen:
        if f.wrapper and f.wrapper not in files:
            files.append(f.wrapper)
    return (*files, "quadland_status.c")


# --- templates -------------------------------------------------------------

def _pad(text: str, width: int) -> str:
    return text.ljust(width)


def _signature(params, head: str, width: int = 96) -> str:
    """``head(p1, p2, ...)`` wrapped before ``width``, continuation under the ``(``."""
    indent = " " * (len(head) + 1)
    lines, line = [], head + "("
    for i, p in enumerate(params):
        piece = p + (", " if i < len(params) - 1 else ")")
        if len(line) + len(piece.rstrip()) > width and line.strip() != head + "(":
            lines.append(line.rstrip())
            line = indent
        line += piece
    lines.append(line)
    return "\n".join(lines)


@functools.cache
def _declared(text: str, ql: str, QL: str) -> list[str]:
    """The names a rendered header declares with the build's prefixes, sorted."""
    return sorted(set(re.findall(rf"\b(?:{ql}|{QL})\w+", text)))


@functools.cache
def _environment() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATE_DIR)),
                             keep_trailing_newline=True, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, autoescape=False)
    env.filters.update(pad=_pad, signature=_signature, declared=_declared,
                       prefix=lambda text, head: head + text)
    return env


def _render(template: str, **context) -> str:
    return _environment().get_template(template).render(**context)


def _common(config: CodegenConfig | None) -> dict:
    """Context every template shares: the banner's facts and the prefixes."""
    ctx = dict(builder=(config or CodegenConfig()).builder, casadi_version=ca.__version__,
               precision=config.precision if config else None)
    if config is not None:
        ql, QL = config.prefix, config.macro_prefix
        ctx.update(ql=ql, QL=QL, real=ql + "real", lit=config.literal, math=config.math,
                   api=lambda text: text.replace("{ql}", ql).replace("{QL}", QL))
    return ctx


# --- the CasADi files ------------------------------------------------------

def _emit_casadi(entry: GeneratedFunction, l: int, config: CodegenConfig) -> dict[str, str]:
    """CasADi's C for one function, prefixed and post-processed; ``{file name: text}``."""
    fn = entry.function(l)
    c_name = entry.c_name(config)
    # The same expression graph under the build's symbol (CasADi names the C
    # function after the Function); "prefix" names its helpers c_name__*.
    renamed = ca.Function(c_name, fn.sx_in(), fn.call(fn.sx_in()), fn.name_in(), fn.name_out())
    opts = {"with_header": True, "casadi_real": config.precision, "casadi_int": config.casadi_int,
            "prefix": f"{c_name}_", "verbose": False, "with_export": False}
    cg = ca.CodeGenerator(f"{entry.name}.c", opts)
    cg.add(renamed)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        texts = {ext: Path(tmp, f"{entry.name}.{ext}").read_text() for ext in ("c", "h")}
    c = texts["c"]
    # Arguments CasADi's SX code leaves unused (-Wunused-parameter).
    c = re.sub(r"(static int \w+\(const casadi_real\*\* arg, casadi_real\*\* res, "
               r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n)",
               r"\1  (void)arg; (void)res; (void)iw; (void)w; (void)mem;\n", c)
    c = re.sub(r"(void \w+_release\(int mem\) \{\n)", r"\1  (void)mem;\n", c)
    c = re.sub(r"(casadi_real \w+_default_in\(casadi_int i\) \{\n)", r"\1  (void)i;\n", c)
    h = texts["h"]
    if not config.null_checks:
        c = re.sub(r"arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0", r"arg[\1][\2]", c)
        c = re.sub(r"if \(res\[(\d+)\]!=0\) res\[\1\]", r"res[\1]", c)
        c = c.replace(f"int {c_name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory: NULL is not\n"
                      " * accepted (symbolic.codegen.CodegenConfig.null_checks). */\n"
                      f"int {c_name}(const casadi_real** arg,", 1)
        h = h.replace(f"int {c_name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory. */\n"
                      f"int {c_name}(const casadi_real** arg,", 1)
    if config.is_float:
        head, sep, body = c.partition("#include <math.h>")
        body = _MATH_RE.sub(lambda m: config.math(m.group(1)) + "(", body)
        body = _LITERAL_RE.sub(lambda m: m.group(1) + "f", body)
        c = head + sep + body
    what = re.sub(r"\s+", " ", str(fn)).removesuffix(" SXFunction")
    ctx = dict(_common(config), what=f"{c_name}: {what}", source=entry.origin(l))
    return {f"{entry.name}.{ext}": _render("casadi.jinja", code=text, **ctx)
            for ext, text in (("c", c), ("h", h))}


# --- the readable API ------------------------------------------------------

def _unit_text(f: Field) -> str:
    if isinstance(f.unit, tuple):
        return f.unit[0] if len(set(f.unit)) == 1 else ", ".join(f.unit)
    return f.unit


def _member(f: Field, structs: tuple[CStruct, ...], ql: str) -> dict:
    """A struct member: C type, array dimensions and comment."""
    if f.ctype == "int":
        ctype, dims = "int", []
    elif f.layout is not None:
        owner = [s for s in structs if s.layout == f.layout]
        if not owner:
            raise ValueError(f"{f.name}: no C struct has layout {f.layout.name!r}")
        ctype, dims = ql + owner[0].name, []
    else:
        ctype = ql + "real"
        dims = [f.shape[1], f.shape[0]] if f.shape is not None else (
            [] if f.size == 1 else [f.size])
    unit = _unit_text(f)
    comment = f"{unit}: {f.doc}" if unit else f.doc
    generic = tuple(f"{f.name}_{i + 1}" for i in range(f.size))
    if (f.elements is not None and f.elements != generic and 1 < f.size <= 6
            and not any(e in f.doc for e in f.elements)):
        comment += f" ({', '.join(f.elements)})"
    return dict(name=f.name, type=ctype, dims=dims, comment=comment)


def _struct_context(s: CStruct, structs, ql: str) -> dict:
    offsets = s.layout.offsets()
    reals = [dict(name=f.name, offset=offsets[f.name][0]) for f in s.layout.fields
             if f.ctype == "real"]
    ints = [dict(name=f.name, index=i) for i, f in
            enumerate(f for f in s.layout.fields if f.ctype == "int")]
    return dict(name=s.name, doc=s.doc, size=s.layout.size, reals=reals, ints=ints,
                members=[_member(f, structs, ql) for f in s.layout.fields])


def _sizes(l: int, jac_nnz: int) -> list[dict]:
    """The size macros (name without prefix, value, comment), from the layouts."""
    def fields(layout):
        return ", ".join(f"{f.name} ({f.size})" for f in layout.fields)

    return [
        dict(name="RBF_NODES", value=l, doc="l, RBF nodes (eq. 8)"),
        dict(name="RBF_INPUT_DIM", value=RBF_INPUT_DIM, doc="dimension of vartheta (Section 3.2)"),
        dict(name="P_QUAD_SIZE", value=QUADROTOR.size, doc="reals in p_quad"),
        dict(name="P_VEH_SIZE", value=VEHICLE.size, doc="reals in p_veh"),
        dict(name="P_CTRL_SIZE", value=controller_layout(l).size, doc="reals in p_ctrl"),
        dict(name="PARAMS_SIZE", value=params_layout(l).size, doc="reals in {ql}params"),
        dict(name="CLOSED_LOOP_NX", value=closed_loop_state(l).size,
             doc=f"x = [{fields(closed_loop_state(l))}]"),
        dict(name="CLOSED_LOOP_NW", value=BODY_DISTURBANCE.size,
             doc=f"w = [{fields(BODY_DISTURBANCE)}]"),
        dict(name="CLOSED_LOOP_NP", value=closed_loop_params(l).size,
             doc=f"p = [{fields(closed_loop_params(l))}]"),
        dict(name="CLOSED_LOOP_JACOBIAN_NNZ", value=jac_nnz, doc="nonzeros of d x_dot / d x"),
        dict(name="PLANT_NX", value=PAPER_PLANT_STATE.size,
             doc=f"xp = [{fields(PAPER_PLANT_STATE)}]"),
    ]


def _vector_structs(d: Defaults, config: CodegenConfig) -> list[dict]:
    """Structs that are vectors of the model: defaults, pack and unpack."""
    structs = {s.name: s.layout for s in api_structs(d.l)}
    out = []
    for name, values, public in (("quadrotor_params", d.p_quad, True),
                                 ("controller_params", d.p_ctrl, True),
                                 ("vehicle_params", d.p_veh, True),
                                 ("reference", d.ref, False)):
        layout = structs[name]
        values = [config.literal(v) for v in np.asarray(values, dtype=float).ravel()]
        if len(values) != layout.size:
            raise ValueError(f"{name}: {len(values)} defaults for {layout.size} entries")
        offsets = layout.offsets()
        out.append(dict(name=name, vector=layout.name, public=public,
                        rows=[values[i:i + 6] for i in range(0, len(values), 6)],
                        size=len(values),
                        fields=[dict(name=f.name, offset=offsets[f.name][0], size=f.size)
                                for f in layout.fields]))
    return out


def _step_context(l: int, config: CodegenConfig) -> dict:
    """Where ``ql_control_step`` puts each argument and result of CasADi's function."""
    ins, outs = step_inputs(l), step_outputs(l)
    # The caller's measurements and dt, staged in one buffer and checked in one pass.
    staged_in = Layout("in", tuple(ins[n] for n in ("xq", "yv", "ref", "dt")))
    # Every result but the two scalars read first (n_clipped, tilt), likewise.
    staged_res = Layout("res_v", tuple(f for f in outs.fields
                                       if f.name not in ("n_clipped", "tilt")))
    res_offsets = staged_res.offsets()
    return dict(
        c_name=_BY_NAME["control_step"].c_name(config),
        arg={n: i for i, n in enumerate(ins.names())},
        res={n: i for i, n in enumerate(outs.names())},
        in_size=staged_in.size, in_offset={n: a for n, (a, _) in staged_in.offsets().items()},
        res_size=staged_res.size, res_offset={n: a for n, (a, _) in res_offsets.items()},
        staged_res=[dict(name=n, index=outs.names().index(n), offset=a)
                    for n, (a, _) in res_offsets.items()],
        adaptive=adaptive_state_layout(l).offsets())


def _wrapped(l: int, config: CodegenConfig, part: str = "paper") -> list[dict]:
    out = []
    for entry in FUNCTIONS:
        if entry.wrapper is None or entry.part != part:
            continue
        fn = entry.function(l)
        ins, outs = entry.arguments(l)
        sparse = any(not fn.sparsity_out(i).is_dense() for i in range(fn.n_out()))
        out.append(dict(name=entry.name, c_name=entry.c_name(config), file=entry.wrapper,
                        ins=ins, outs=outs, doc=entry.doc, sparse=sparse))
    return out


def _param_ranges(l: int, config: CodegenConfig, ranges=param_ranges) -> list[dict]:
    """The range of each member of ``ql_params`` (``symbolic.c_api.param_ranges``, or
    another table's ``ranges(l)``), bounds as C literals.

    ``bounded`` is False where only finiteness is asked; ``in_step`` marks
    the bounded members whose size does not grow with ``l``: the control
    step tests those on every call (a few dozen comparisons), the per-node
    arrays only ``ql_check_params``.
    """
    out = []
    for r, other in zip(ranges(l), ranges(l + 1), strict=True):
        g = r.range
        bounded = (g.lo is not None or g.hi is not None or g.choices is not None
                   or r.at_least is not None)
        out.append(dict(
            name=r.name, offset=r.offset, size=r.size, text=g.text(),
            lo=None if g.lo is None else config.literal(g.lo), lo_open=g.lo_open,
            hi=None if g.hi is None else config.literal(g.hi), hi_open=g.hi_open,
            choices=None if g.choices is None else [config.literal(v) for v in g.choices],
            at_least=r.at_least, bounded=bounded, in_step=bounded and other.size == r.size))
    return out


def _api_context(config: CodegenConfig, d: Defaults) -> dict:
    l = d.l
    structs = api_structs(l)
    jac = closed_loop_jacobian_function(l).sparsity_out(0)
    lo, hi = d.rotor_limits
    scalars = {"rotor_force_min": lo, "rotor_force_max": hi, "tilt_min": d.tilt_min,
               "hold_compensation": d.hold}
    params = params_layout(l)
    return dict(
        _common(config),
        scenario=d.scenario,
        aliases=config.prefix != "ql_",
        sizes=_sizes(l, jac.nnz()),
        status_codes=[dict(name=n.removeprefix("QL_"), value=v, doc=doc)
                      for n, v, doc in STATUS_CODES],
        structs=[_struct_context(s, structs, config.prefix) for s in structs],
        vectors=_vector_structs(d, config),
        params_scalars=[dict(name=f.name, value=config.literal(scalars[f.name]))
                        for f in params.fields if f.layout is None],
        p_offset={n: a for n, (a, _) in closed_loop_params(l).offsets().items()},
        step=_step_context(l, config),
        param_ranges=_param_ranges(l, config),
        wrapped=_wrapped(l, config),
    )


def generate(defaults: Defaults, config: CodegenConfig = CodegenConfig()) -> dict[str, str]:
    """Text of every generated C file of one precision.

    Parameters
    ----------
    defaults : Defaults
        Numeric defaults of the parameter structs.
    config : CodegenConfig
        Emitter settings.

    Returns
    -------
    dict of str to str
        File name (relative to the build's folder) to its text.
    """
    if config.casadi_int != "int":
        raise ValueError("the readable API exposes sparsity patterns as int: "
                         "keep casadi_int = int")
    return _emit_part("paper", defaults.l, config, _api_context(config, defaults),
                      ("quadland.h", "quadland.c", "quadland_status.c"))


def _emit_part(part: str, l: int, config: CodegenConfig, ctx: dict,
               sources: tuple[str, ...]) -> dict[str, str]:
    """The files of one API: its CasADi functions, its templates, its wrappers.

    ``sources`` are rendered from ``<name>.jinja``; the first is the API's
    header, which the wrappers include.
    """
    files = {}
    for entry in FUNCTIONS:
        if entry.part == part:
            files.update(_emit_casadi(entry, l, config))
    for name in sources:
        files[name] = _render(f"{name}.jinja", **ctx)
    for file in dict.fromkeys(w["file"] for w in ctx["wrapped"]):
        files[file] = _render("wrappers.c.jinja", file=file, header=sources[0],
                              functions=[w for w in ctx["wrapped"] if w["file"] == file], **ctx)
    return files


# --- the landing API -------------------------------------------------------

def _landing_sizes(l: int) -> list[dict]:
    """The landing API's size macros (name without prefix, value, comment)."""
    def fields(layout):
        return ", ".join(f"{f.name} ({f.size})" for f in layout.fields)

    return [
        dict(name="LANDING_RBF_NODES", value=l, doc="l, RBF nodes of the landing step"),
        dict(name="LANDING_NETWORK_INPUT_DIM", value=NETWORK_INPUT_DIM,
             doc="dimension of the network's input [v_e, Omega_e]"),
        dict(name="LANDING_CHANNELS", value=N_CHANNELS,
             doc="channels: deck-frame x, y, z; roll, pitch, yaw"),
        dict(name="LANDING_PARAMS_SIZE", value=landing_params_layout(l).size,
             doc="reals in {ql}landing_params"),
        dict(name="LANDING_STATE_SIZE", value=landing_memory(l).size,
             doc="reals in {ql}landing_state"),
        dict(name="GUIDANCE_PARAMS_SIZE", value=GUIDANCE_PARAMS.size,
             doc="reals in {ql}guidance_params"),
        dict(name="GUIDANCE_MAX_ABORTS", value=MAX_ABORTS,
             doc="largest abort count {ql}guidance_step accepts"),
        dict(name="LANDING_PLANT_NX", value=LANDING_PLANT_STATE.size,
             doc=f"xp = [{fields(LANDING_PLANT_STATE)}]"),
        dict(name="LANDING_PLANT_NP", value=LANDING_PLANT_PARAMS.size,
             doc=f"pp = [{fields(LANDING_PLANT_PARAMS)}]"),
        dict(name="LANDING_NW", value=LANDING_DISTURBANCE.size,
             doc=f"w = [{fields(LANDING_DISTURBANCE)}]"),
        dict(name="LANDING_NY", value=LANDING_SIGNALS.size, doc="signals y of a landing"),
        dict(name="LANDING_ANCHOR_SIZE", value=ANCHOR.size,
             doc=f"anchor = [{fields(ANCHOR)}]"),
        dict(name="LANDING_VEHICLE_NX", value=VEHICLE_STATE.size,
             doc=f"xv = [{', '.join(VEHICLE_STATE.element_names())}]"),
        dict(name="TOUCHDOWN_FIGURES", value=TOUCHDOWN_FIGURES.size,
             doc=f"[{', '.join(TOUCHDOWN_FIGURES.names())}]"),
    ]


def _vector(name: str, values, config: CodegenConfig) -> dict:
    values = [config.literal(v) for v in np.asarray(values, dtype=float).ravel()]
    return dict(name=name, size=len(values), rows=[values[i:i + 6]
                                                   for i in range(0, len(values), 6)])


def _landing_step_context(l: int, config: CodegenConfig) -> dict:
    """Where ``ql_landing_step`` and ``ql_guidance_step`` put each argument and result."""
    step, guide = landing_step_function(l), landing_guidance_function()
    outs = landing_step_outputs(l)
    # every real result but tilt and the flags, staged and checked in one pass
    staged = Layout("res_v", tuple(f for f in outs.fields if f.name not in ("tilt", "limits")))
    offsets = {n: a for n, (a, _) in staged.offsets().items()}
    out_lay = landing_output_layout(l)
    copies = [dict(name=f.name, offset=offsets[f.name]) for f in out_lay.fields
              if f.ctype == "real" and f.name in offsets]
    # the guidance's results, staged likewise: [xg_next, ref]
    g_offset = dict(zip(guide.name_out(), np.cumsum([0] + [guide.nnz_out(i) for i in range(
        guide.n_out())]).tolist(), strict=False))
    return dict(
        c_name=_BY_NAME["landing_step"].c_name(config),
        arg={n: i for i, n in enumerate(step.name_in())},
        res={n: i for i, n in enumerate(step.name_out())},
        res_size=staged.size, res_offset=offsets,
        staged_res=[dict(name=n, index=step.name_out().index(n), offset=a)
                    for n, a in offsets.items()],
        copies=copies,
        flags=[dict(name=n, index=i) for i, n in enumerate(outs["limits"].elements)],
        y_size=LANDING_MEASUREMENT.size, ref_size=POSITION_REFERENCE.size,
        state_size=landing_memory(l).size,
        mem_next=offsets["mem_next"],
        eta_f=landing_memory(l)["eta_f"].size,
        guidance=dict(
            c_name=_BY_NAME["landing_guidance"].c_name(config),
            arg={n: i for i, n in enumerate(guide.name_in())},
            res={n: i for i, n in enumerate(guide.name_out())},
            res_size=sum(guide.nnz_out(i) for i in range(guide.n_out())), res_offset=g_offset,
            xg=[dict(name=n, index=i, int=guidance_state_layout()[n].ctype == "int")
                for i, n in enumerate(GUIDANCE_STATE.names())],
            xg_size=GUIDANCE_STATE.size, params_size=GUIDANCE_PARAMS.size),
    )


def _landing_api_context(config: CodegenConfig, d: LandingDefaults) -> dict:
    l = d.l
    paper = api_structs(1)
    structs = landing_api_structs(l)
    lookup = (*paper, *structs)
    return dict(
        _common(config),
        scenario=d.scenario,
        aliases=config.prefix != "ql_",
        sizes=_landing_sizes(l),
        phases=[dict(name=n.upper(), value=i, doc=doc, text=n)
                for i, (n, doc) in enumerate(zip(PHASES, PHASE_DOCS, strict=True))],
        structs=[_struct_context(s, lookup, config.prefix) for s in structs],
        defaults=dict(p_quad=_vector("p_quad", d.p_quad, config),
                      p_land=_vector("p_land", d.p_ctrl, config),
                      p_act=_vector("p_act", d.p_act, config),
                      p_guid=_vector("p_guid", d.p_guid, config)),
        tilt_min=config.literal(d.tilt_min),
        max_aborts=MAX_ABORTS,
        n_phases=len(PHASES),
        landing_ranges=_param_ranges(l, config, landing_param_ranges),
        guidance_ranges=_param_ranges(l, config, lambda _: guidance_param_ranges()),
        step=_landing_step_context(l, config),
        wrapped=_wrapped(l, config, "landing"),
    )


def generate_landing(defaults: LandingDefaults,
                     config: CodegenConfig = CodegenConfig()) -> dict[str, str]:
    """Text of the landing API's C files of one precision (``quadland_landing.h``, ...).

    They include the same build's ``quadland.h`` (:func:`generate`) for
    ``ql_real``, ``ql_status`` and ``ql_quadrotor_params``.
    """
    return _emit_part("landing", defaults.l, config, _landing_api_context(config, defaults),
                      ("quadland_landing.h", "quadland_landing.c"))


# --- the pure-C example ----------------------------------------------------

def example_columns(l: int) -> list[tuple[str, str]]:
    """Columns of the example's CSV: ``(name, C expression)``, names from the layouts.

    The names are the layouts' element names, the same as
    ``quadland.simulate.TRAJECTORY``'s for the same signals; ``n_clipped``
    and ``status`` are the example's own (ints, last). The expressions read
    the closed-loop state ``x``, the step's output ``out`` and the vehicle's
    parameters ``vehicle``.
    """
    x = closed_loop_state(l)
    names = x.element_names()

    def at(name):
        return f"(double)x[{names.index(name)}]"

    xq, xv, pos1, zeta = (x.slice(n) for n in ("xq", "xv", "pos1", "zeta_hat"))
    # e1 = [z1 - z2, phi1 - phi2, theta1 - theta2, psi1 - psi2] with phi2 = theta2 = 0 (eq. 5, 7)
    e1 = {"z_e": f"{at('z1')} - (double)vehicle->z2", "phi_e": at("phi1"), "theta_e": at("theta1"),
          "psi_e": f"{at('psi1')} - {at('psi2')}"}
    cols = [("t", "t")]
    cols += [(n, e1[n]) for n in E1.element_names()]
    cols += [(names[i], at(names[i])) for s in (xq, xv, pos1) for i in range(s.start, s.stop)]
    for fname in ("u", "wrench", "rotor"):
        f = output_layout(l)[fname]
        cols += [(n, f"(double)out->{fname}[{i}]") for i, n in enumerate(f.element_names())]
    cols += [(names[i], at(names[i])) for i in range(zeta.start, zeta.stop)]
    cols += [("norm_W_hat", "sqrt(norm_W_hat)"), ("n_clipped", "out->n_clipped"),
             ("status", "status")]
    return cols


def _example_context(d: Defaults) -> dict:
    l = d.l
    x = closed_loop_state(l)
    cols = example_columns(l)
    n_real = len(cols) - 2
    xq0 = x.slice("xq").start
    xv_names = VEHICLE_STATE.element_names()
    vehicle = []
    for f in VEHICLE_MEASUREMENT.fields:
        if f.name in xv_names:
            i = x.slice("xv").start + xv_names.index(f.name)
            vehicle.append(dict(name=f.name, expr=f"x[{i}]"))
        else:
            vehicle.append(dict(name=f.name, expr=f"vehicle->{f.name}"))
    offsets = QUAD_STATE.offsets()
    return dict(
        _common(None),
        scenario=d.scenario,
        columns=[n for n, _ in cols],
        real_columns=[dict(name=n, expr=e) for n, e in cols[:n_real]],
        int_columns=[dict(name=n, expr=e) for n, e in cols[n_real:]],
        quad=[dict(name=f.name, offset=xq0 + offsets[f.name][0], size=f.size)
              for f in QUAD_STATE.fields],
        z1=xq0 + offsets["z1"][0],
        vehicle=vehicle,
        plant=[dict(name=f.name, xp=PAPER_PLANT_STATE.slice(f.name).start, x=x.slice(f.name).start,
                    size=f.size) for f in PAPER_PLANT_STATE.fields],
        W_hat=x.slice("W_hat").start, zeta_hat=x.slice("zeta_hat").start,
        d=d,
        bias=[repr(float(v)) for v in (*d.force_bias, *d.moment_bias)],
        x0_rows=[[repr(float(v)) for v in d.x0[i:i + 6]] for i in range(0, len(d.x0), 6)],
        x0_size=len(d.x0),
        step_sources=c_sources(),
        model_sources=c_sources(("closed_loop", "plant")),
    )


def land_columns() -> list[tuple[str, str]]:
    """Columns of the example ``land``'s CSV: ``(name, C expression)``, from the layouts.

    The names are ``symbolic.landing.loop.LANDING_TRAJECTORY``'s (``quadland
    simulate``'s trajectory.csv of a landing); the expressions read the time
    ``t`` and the signals ``y`` (``symbolic.landing.loop.LANDING_SIGNALS``).
    """
    cols = []
    for f in LANDING_TRAJECTORY.fields:
        if f.name == "t":
            cols.append(("t", "t"))
            continue
        at = LANDING_SIGNALS.slice(f.name).start
        cols += [(n, f"(double)y[{at + i}]") for i, n in enumerate(f.element_names())]
    return cols


def _land_context(d: LandingDefaults) -> dict:
    """The example ``land``'s context: its scenario's values and the layouts' offsets."""
    def rows(values):
        values = [repr(float(v)) for v in np.asarray(values, dtype=float).ravel()]
        return [values[i:i + 6] for i in range(0, len(values), 6)]

    def fields(layout):
        return ", ".join(f"{f.name} ({f.size})" for f in layout.fields)

    x1q = LANDING_PLANT_STATE.slice("x1q").start
    return dict(
        d=d,
        columns=[dict(name=n, expr=e) for n, e in land_columns()],
        xg=[dict(name=n, index=i) for i, n in enumerate(GUIDANCE_STATE.names())],
        w={n: a for n, (a, _) in LANDING_DISTURBANCE.offsets().items()},
        y={n: LANDING_SIGNALS.slice(n).start for n in ("p_e", "v_e", "eta1", "eta2")}
        | {"psi1": LANDING_SIGNALS.index("psi1")},
        figures=[dict(name=n, index=i, limit="max_" + n)
                 for i, n in enumerate(TOUCHDOWN_FIGURES.names())],
        limits=[(name, repr(float(v))) for name, v in d.limits],
        bias=[repr(float(v)) for v in (*d.force_bias, *d.moment_bias)],
        wind_mean=[repr(float(v)) for v in d.wind_mean],
        gust_direction=[repr(float(v)) for v in d.gust_direction],
        pp_rows=rows(d.pp), pp_size=len(d.pp), pp_fields=fields(LANDING_PLANT_PARAMS),
        xp_rows=rows(d.xp0), xp_size=len(d.xp0), xp_fields=fields(LANDING_PLANT_STATE),
        xv=LANDING_PLANT_STATE.slice("xv").start, x1q_size=QUAD6_STATE.size,
        rotors=x1q + QUAD6_STATE.slice("F").start,
        p_veh=LANDING_PLANT_PARAMS.slice("p_veh").start,
        tau_m=LANDING_PLANT_PARAMS.slice("p_act").start + ACTUATOR.index("motor_time_constant"),
    )


#: The landing model's functions the example ``land`` calls.
_LAND_MODEL = tuple(f.name for f in FUNCTIONS if f.part == "landing" and f.wrapper is not None)


def generate_example(defaults: Defaults, landing: LandingDefaults) -> dict[str, str]:
    """Text of the pure-C example: flights, benchmark, scenario headers and Makefile.

    ``fly.c`` flies the paper's scenario (``defaults``, ``scenario.h``),
    ``land.c`` the landing scenario (``landing``, ``land_scenario.h``),
    ``bench.c`` times either step. The sources are precision-independent
    (``ql_real``; the float header spells its names ``ql_`` too when it is
    the only build included); the Makefile builds them against both the
    double (``../``) and the float (``../float/``) files.
    """
    status = "quadland_status.c"
    paper = _example_context(defaults)
    paper.update(land_scenario=landing.scenario, common_sources=[status],
                 step_sources=[f for f in paper["step_sources"] if f != status],
                 land_sources=[f for f in c_sources(_LAND_MODEL) if f != status])
    land = dict(_common(None), scenario=landing.scenario, **_land_context(landing))
    files = {f"example/{name}": _render(f"example/{name}.jinja", **paper)
             for name in ("scenario.h", "fly.c", "bench.c", "Makefile")}
    files.update({f"example/{name}": _render(f"example/{name}.jinja", **land)
                  for name in ("land_scenario.h", "land.c")})
    files["example/quadland_loop.h"] = loop_header()
    return files


def generate_tree(defaults: Defaults, landing: LandingDefaults) -> dict[str, str]:
    """Every file of ``generated/`` by relative path (POSIX separators).

    The paper's step (``defaults``) and the landing step (``landing``), the
    double build at the top, the float build in ``float/``, the example in
    ``example/`` and a ``.gitignore`` of the example's build outputs.
    """
    files = {}
    for config, folder in ((CodegenConfig("double"), ""), (CodegenConfig("float"), "float/")):
        built = {**generate(defaults, config), **generate_landing(landing, config)}
        files.update({folder + k: v for k, v in built.items()})
    files.update(generate_example(defaults, landing))
    files[".gitignore"] = _render("gitignore.jinja", **_common(None))
    return files

"""C code of the control step and the closed loop, with a readable API.

One entry point, :func:`generate`, turns the symbolic functions into the
text of every file under ``generated/``:

* one CasADi-generated file per function (``control_step``,
  ``closed_loop``, ``closed_loop_jacobian``, ``plant``), with its symbol
  prefix set so that the files link together, and post-processed so that
  each compiles alone with ``-std=c99 -pedantic -Wall -Wextra -Werror``
  (unused arguments are voided) and, for the single-precision build, uses
  float constants and float math;
* ``quadland.h`` / ``quadland.c``: named structs, defaults and a checked
  ``ql_control_step`` over CasADi's arg/res arrays, written from the
  parameter layouts of ``symbolic.parameters`` so that they cannot drift;
* ``example/``: a pure-C flight of the paper's scenario, a benchmark and
  their Makefile.

Numeric defaults (the paper scenario) are passed in as :class:`Defaults`;
this module imports nothing from ``quadland``. The emitter settings are the
frozen :class:`CodegenConfig`. The output depends only on its inputs and on
the CasADi version, never on time or paths, so regeneration is byte for
byte reproducible.
"""

from __future__ import annotations

import dataclasses
import os
import re
import tempfile

import casadi as ca
import numpy as np

from symbolic.closed_loop import (PLANT_STATE, closed_loop_function, closed_loop_params,
                                  closed_loop_state, plant_function)
from symbolic.quadrotor import DISTURBANCE
from symbolic.control_step import control_step_function
from symbolic.parameters import QUADROTOR, RBF_INPUT_DIM, VEHICLE, controller_layout

__all__ = ["CodegenConfig", "Defaults", "STATUS_CODES", "CASADI_FUNCTIONS", "generate_example",
           "closed_loop_jacobian_function", "generate"]

#: Status codes of ``ql_control_step`` (name, value, meaning).
STATUS_CODES = (
    ("QL_OK", 0, "success; outputs and adaptive state updated"),
    ("QL_ERR_NULL", 1, "a NULL pointer argument"),
    ("QL_ERR_INVALID", 2,
     "dt <= 0, rotor_force_min > rotor_force_max or hold_compensation outside [0, 1]"),
    ("QL_ERR_NONFINITE_INPUT", 3, "an input, parameter or the adaptive state is NaN or infinite"),
    ("QL_ERR_TILT", 4, "|cos(theta1) cos(phi1)| < tilt_min: thrust map not invertible"),
    ("QL_ERR_NONFINITE_OUTPUT", 5,
     "the law overflowed: a NaN or infinite value from finite inputs"),
)

#: The CasADi functions written as C, in file order.
CASADI_FUNCTIONS = ("control_step", "closed_loop", "closed_loop_jacobian", "plant")

_MATH = ("exp", "expm1", "log", "log1p", "sqrt", "cos", "sin", "tan", "acos", "asin", "atan",
         "atan2", "tanh", "sinh", "cosh", "fmin", "fmax", "fabs", "floor", "ceil", "pow", "erf")
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
    casadi_int: str = "int"
    null_checks: bool = False
    builder: str = "quadland codegen (symbolic/codegen.py)"

    def __post_init__(self):
        if self.precision not in ("double", "float"):
            raise ValueError(f"precision must be 'double' or 'float', got {self.precision!r}")

    @property
    def is_float(self) -> bool:
        """True for the single-precision build."""
        return self.precision == "float"

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
    """Numeric defaults written into the C (the paper scenario).

    Attributes
    ----------
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


def closed_loop_jacobian_function(l: int) -> ca.Function:
    """``closed_loop_jacobian(x, w, p) -> jac_x``: d x_dot / d x, sparse.

    The Jacobian of ``symbolic.closed_loop.closed_loop_function`` with
    respect to the state, formed by CasADi's algorithmic differentiation.
    """
    f = closed_loop_function(l)
    x, w, p = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("w", f.size1_in(1)), \
        ca.SX.sym("p", f.size1_in(2))
    return ca.Function("closed_loop_jacobian", [x, w, p], [ca.jacobian(f(x, w, p), x)],
                       ["x", "w", "p"], ["jac_x"])


def _casadi_function(name: str, l: int) -> ca.Function:
    return {"control_step": lambda: control_step_function(l),
            "closed_loop": lambda: closed_loop_function(l),
            "closed_loop_jacobian": lambda: closed_loop_jacobian_function(l),
            "plant": plant_function}[name]()


def _banner(config: CodegenConfig, what: str, source: str) -> str:
    return (f"/* {what}\n"
            f" *\n"
            f" * Generated by {config.builder} from {source}\n"
            f" * with CasADi {ca.__version__}, precision: {config.precision}.\n"
            f" * Do not edit: regenerate with `quadland codegen`.\n"
            f" */\n")


def _emit_casadi(name: str, l: int, config: CodegenConfig) -> dict[str, str]:
    """CasADi's C for one function, post-processed; ``{file name: text}``."""
    fn = _casadi_function(name, l)
    opts = {"with_header": True, "casadi_real": config.precision, "casadi_int": config.casadi_int,
            "prefix": f"{name}_", "verbose": False, "with_export": False}
    cg = ca.CodeGenerator(f"{name}.c", opts)
    cg.add(fn)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        texts = {ext: open(os.path.join(tmp, f"{name}.{ext}")).read() for ext in ("c", "h")}
    source = {"control_step": "symbolic.control_step.control_step_function",
              "closed_loop": "symbolic.closed_loop.closed_loop_function",
              "closed_loop_jacobian": "symbolic.codegen.closed_loop_jacobian_function",
              "plant": "symbolic.closed_loop.plant_function"}[name]
    signature = re.sub(r"\s+", " ", str(fn)).removesuffix(" SXFunction")
    banner = _banner(config, signature, f"{source}(l={l})"
                     if name != "plant" else f"{source}()")
    c = texts["c"]
    # Arguments CasADi's SX code leaves unused (-Wunused-parameter).
    c = re.sub(r"(static int \w+\(const casadi_real\*\* arg, casadi_real\*\* res, "
               r"casadi_int\* iw, casadi_real\* w, int mem\) \{\n)",
               r"\1  (void)arg; (void)res; (void)iw; (void)w; (void)mem;\n", c)
    c = re.sub(r"(void \w+_release\(int mem\) \{\n)", r"\1  (void)mem;\n", c)
    c = re.sub(r"(casadi_real \w+_default_in\(casadi_int i\) \{\n)", r"\1  (void)i;\n", c)
    if not config.null_checks:
        c = re.sub(r"arg\[(\d+)\]\? arg\[\1\]\[(\d+)\] : 0", r"arg[\1][\2]", c)
        c = re.sub(r"if \(res\[(\d+)\]!=0\) res\[\1\]", r"res[\1]", c)
        c = c.replace(f"int {name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory: NULL is not\n"
                      " * accepted (symbolic.codegen.CodegenConfig.null_checks). */\n"
                      f"int {name}(const casadi_real** arg,", 1)
    if config.is_float:
        head, sep, body = c.partition("#include <math.h>")
        body = _MATH_RE.sub(lambda m: config.math(m.group(1)) + "(", body)
        body = _LITERAL_RE.sub(lambda m: m.group(1) + "f", body)
        c = head + sep + body
    h = texts["h"]
    if not config.null_checks:
        h = h.replace(f"int {name}(const casadi_real** arg,",
                      "/* Every arg[i] and res[i] must point to valid memory. */\n"
                      f"int {name}(const casadi_real** arg,", 1)
    return {f"{name}.c": banner + c, f"{name}.h": banner + h}


def _c_field(f, config) -> str:
    if f.shape is not None:
        rows, cols = f.shape
        decl = f"ql_real {f.name}[{cols}][{rows}];"
    elif f.size == 1:
        decl = f"ql_real {f.name};"
    else:
        decl = f"ql_real {f.name}[{f.size}];"
    return f"    {decl:<32} /* {f.unit}: {f.doc} */"


def _param_structs(l: int):
    """(struct name, layout, comment) of the parameter structs."""
    return (("ql_quadrotor_params", QUADROTOR,
             "Physical constants of the quadrotor (Table 1, eq. 2): layout p_quad."),
            ("ql_controller_params", controller_layout(l),
             "Gains, adaptation constants and RBF network (eq. 14, 20, 22): layout p_ctrl."),
            ("ql_vehicle_params", VEHICLE,
             "Constants and inputs of the ground vehicle (Table 1, eq. 4): layout p_veh."))


def _array(config, name, values) -> str:
    vals = [config.literal(v) for v in np.asarray(values, dtype=float).ravel()]
    lines = []
    for i in range(0, len(vals), 6):
        lines.append("    " + ", ".join(vals[i:i + 6]) + ",")
    return f"static const ql_real {name}[{len(vals)}] = {{\n" + "\n".join(lines) + "\n};\n"


def _header(config: CodegenConfig, d: Defaults) -> str:
    l = d.l
    jac = closed_loop_jacobian_function(l).sparsity_out(0)
    out = [_banner(config, "quadland.h: readable C API of the adaptive backstepping control step.",
                   "the layouts of symbolic.parameters"),
           "#ifndef QUADLAND_H\n#define QUADLAND_H\n"]
    out.append(f"""
#ifdef __cplusplus
extern "C" {{
#endif

/* Every real is a ql_real: {config.precision} in this build. */
typedef {config.precision} ql_real;

#define QL_RBF_NODES {l}          /* l, RBF nodes (eq. 8) */
#define QL_RBF_INPUT_DIM {RBF_INPUT_DIM}       /* dimension of vartheta (Section 3.2) */
#define QL_P_QUAD_SIZE {QUADROTOR.size}
#define QL_P_VEH_SIZE {VEHICLE.size}
#define QL_P_CTRL_SIZE {controller_layout(l).size}
#define QL_PARAMS_SIZE (QL_P_QUAD_SIZE + QL_P_CTRL_SIZE + 4)   /* ql_params, scalars */
#define QL_CLOSED_LOOP_NX {closed_loop_state(l).size}   /* [xq (10), xv (6), vec(W_hat) (4 l), zeta_hat (4), x1, y1] */
#define QL_CLOSED_LOOP_NW {DISTURBANCE.size}     /* [d_F (3), d_M (3)] */
#define QL_CLOSED_LOOP_NP {closed_loop_params(l).size}  /* [p_quad, p_veh, p_ctrl, ref (12)] */
#define QL_CLOSED_LOOP_JACOBIAN_NNZ {jac.nnz()}
#define QL_PLANT_NX {PLANT_STATE.size}         /* [xq (10), xv (6), x1, y1] */

/* Status of ql_control_step. */
typedef enum {{
""")
    for name, value, doc in STATUS_CODES:
        out.append(f"    {name + ' = ' + str(value) + ',':<30} /* {doc} */\n")
    out.append("} ql_status;\n")
    out.append("""
/* Measured quadrotor state (eq. 1-2): Earth frame z up, ZYX Euler angles. */
typedef struct {
    ql_real z1;                      /* m: altitude */
    ql_real eta1[3];                 /* rad: roll phi1, pitch theta1, yaw psi1 */
    ql_real V1[3];                   /* m/s: body velocity u1, v1, w1 */
    ql_real Omega1[3];               /* rad/s: body rates p1, q1, r1 */
} ql_quadrotor_state;

/* Measured vehicle state (eq. 4); heave, roll and pitch are neglected. */
typedef struct {
    ql_real z2;                      /* m: deck altitude */
    ql_real psi2;                    /* rad: heading */
    ql_real r2;                      /* rad/s: yaw rate */
} ql_vehicle_state;

/* Reference of the relative states e1 = [z_e, phi_e, theta_e, psi_e]. */
typedef struct {
    ql_real e1d[4];                  /* m, rad, rad, rad */
    ql_real e1d_dot[4];              /* first time derivative */
    ql_real e1d_ddot[4];             /* second time derivative */
} ql_reference;

/* The step's memory: the adaptive state (eq. 22) and the law's previous
 * output for the hold compensation. Start with ql_adaptive_state_init. */
typedef struct {
    ql_real W_hat[4][QL_RBF_NODES];  /* W_hat (l x 4) column-major: W_hat[j][i] = W(i, j) */
    ql_real zeta_hat[4];             /* zeta_hat */
    ql_real u_prev[4];               /* u_law of the last successful step */
    int has_prev;                    /* 0: do not extrapolate (initially, after a gap) */
} ql_adaptive_state;
""")
    for sname, layout, doc in _param_structs(l):
        out.append(f"\n/* {doc} */\ntypedef struct {{\n")
        out.extend(_c_field(f, config) + "\n" for f in layout.fields)
        out.append(f"}} {sname};\n")
    out.append("""
/* Everything ql_control_step is tuned with; ql_params_init fills the defaults. */
typedef struct {
    ql_quadrotor_params quad;        /* physical constants */
    ql_controller_params ctrl;       /* gains, adaptation, RBF network */
    ql_real rotor_force_min;         /* N: lower rotor force limit (clipping) */
    ql_real rotor_force_max;         /* N: upper rotor force limit (clipping) */
    ql_real tilt_min;                /* -: smallest accepted |cos(theta1) cos(phi1)| */
    ql_real hold_compensation;       /* periods, 0..1: extrapolation of the held command */
} ql_params;

/* Outputs of one control step. */
typedef struct {
    ql_real u[4];                    /* commanded virtual inputs, before clipping */
    ql_real u_law[4];                /* the law of eq. (20) at the measurements */
    ql_real wrench[4];               /* N, N m: F_total, M_x, M_y, M_z of the clipped rotors */
    ql_real rotor[4];                /* N: rotor forces F1..F4, clipped to the limits */
    int n_clipped;                   /* number of rotors clipped this step (0..4) */
    ql_real tilt;                    /* cos(theta1) cos(phi1) */
} ql_output;

/* Fill the defaults (the paper scenario, quadland/scenarios/paper.toml). */
void ql_params_init(ql_params *params);
void ql_vehicle_params_init(ql_vehicle_params *params);
/* W_hat(0) = 0 and zeta_hat(0) = 0 (Section 4), no previous command. */
void ql_adaptive_state_init(ql_adaptive_state *state);
/* The paper's reference e1d = 0. */
void ql_reference_init(ql_reference *ref);

/* One control step of period dt (s).
 *
 * Evaluates the law of eq. (20) at the measurements (u_law), extrapolates
 * it against the hold's delay, u = u_law + hold_compensation (u_law -
 * u_prev) (from the second step on), clips the rotor forces of u to
 * [rotor_force_min, rotor_force_max] and integrates the adaptive laws of
 * eq. (22) exactly over dt with the measurements held. The rotor forces
 * are meant to be held until the next step. On QL_OK the outputs are
 * written and the state advanced; on any error the state is left
 * untouched and the outputs are set to zero (never NaN): the caller
 * applies its failsafe, and clears state->has_prev before the next call
 * (as after any period whose output was not applied). No heap, no global
 * state: reentrant. */
ql_status ql_control_step(const ql_quadrotor_state *xq, const ql_vehicle_state *yv,
                          const ql_reference *ref, const ql_params *params, ql_real dt,
                          ql_adaptive_state *state, ql_output *out);

/* A short English description of a status code. */
const char *ql_status_string(ql_status status);

/* Pack the named parameters into the layouts of symbolic.parameters. */
void ql_pack_quadrotor_params(const ql_quadrotor_params *s, ql_real *p_quad);
void ql_pack_controller_params(const ql_controller_params *s, ql_real *p_ctrl);
void ql_pack_vehicle_params(const ql_vehicle_params *s, ql_real *p_veh);
/* The closed loop's parameter vector p = [p_quad, p_veh, p_ctrl, ref]. */
void ql_pack_closed_loop_params(const ql_params *params, const ql_vehicle_params *vehicle,
                                const ql_reference *ref, ql_real *p);

/* x_dot of the continuous-time closed loop (symbolic.closed_loop). */
void ql_closed_loop(const ql_real *x, const ql_real *w, const ql_real *p, ql_real *x_dot);
/* d x_dot / d x: the QL_CLOSED_LOOP_JACOBIAN_NNZ nonzeros in compressed
 * column storage; ql_closed_loop_jacobian_sparsity gives the pattern
 * (CasADi format: nrow, ncol, colind[ncol + 1], row[nnz]). */
void ql_closed_loop_jacobian(const ql_real *x, const ql_real *w, const ql_real *p,
                             ql_real *jac_nz);
const int *ql_closed_loop_jacobian_sparsity(void);
/* xp_dot of the plant alone (quadrotor, vehicle, planar position) under a
 * held wrench and disturbance w. */
void ql_plant(const ql_real *xp, const ql_real *wrench, const ql_real *w,
              const ql_real *p_quad, const ql_real *p_veh, ql_real *xp_dot);

#ifdef __cplusplus
} /* extern "C" */
#endif

#endif /* QUADLAND_H */
""")
    return "".join(out)


def _source(config: CodegenConfig, d: Defaults) -> str:
    l = d.l
    m = config.math
    out = [_banner(config, "quadland.c: readable C API of the adaptive backstepping control step.",
                   "the layouts of symbolic.parameters"),
           '#include "quadland.h"\n\n'
           '#include <math.h>\n#include <stddef.h>\n#include <string.h>\n\n'
           '#include "control_step.h"\n\n']
    out.append("/* The parameter structs hold ql_real fields only and no padding, so that\n"
               " * they are the vectors of symbolic.parameters that CasADi reads. */\n")
    for sname, size in (("ql_quadrotor_params", "QL_P_QUAD_SIZE"),
                        ("ql_controller_params", "QL_P_CTRL_SIZE"),
                        ("ql_vehicle_params", "QL_P_VEH_SIZE")):
        out.append(f"typedef char {sname}_is_packed"
                   f"[sizeof({sname}) == {size} * sizeof(ql_real) ? 1 : -1];\n")
    out.append("typedef char ql_params_is_packed"
               "[sizeof(ql_params) == QL_PARAMS_SIZE * sizeof(ql_real) ? 1 : -1];\n")
    out.append("typedef char ql_adaptive_state_is_packed[offsetof(ql_adaptive_state, has_prev)"
               " == (4 * QL_RBF_NODES + 8) * sizeof(ql_real) ? 1 : -1];\n")
    out.append("\n/* Defaults: quadland/scenarios/paper.toml. */\n")
    out.append(_array(config, "ql_default_p_quad", d.p_quad))
    out.append(_array(config, "ql_default_p_ctrl", d.p_ctrl))
    out.append(_array(config, "ql_default_p_veh", d.p_veh))
    out.append(_array(config, "ql_default_ref", d.ref))
    for (sname, layout, _), short in zip(_param_structs(l), ("quadrotor", "controller", "vehicle")):
        pack = [f"\nvoid ql_pack_{short}_params(const {sname} *s, ql_real *p)\n{{\n"]
        unpack = [f"\nstatic void ql_unpack_{short}_params(const ql_real *p, {sname} *s)\n{{\n"]
        for f in layout.fields:
            a, _ = layout.offsets()[f.name]
            pack.append(f"    memcpy(p + {a}, &s->{f.name}, {f.size} * sizeof(ql_real));\n")
            unpack.append(f"    memcpy(&s->{f.name}, p + {a}, {f.size} * sizeof(ql_real));\n")
        out.extend(pack + ["}\n"] + unpack + ["}\n"])
    lo, hi = d.rotor_limits
    out.append(f"""
void ql_params_init(ql_params *params)
{{
    ql_unpack_quadrotor_params(ql_default_p_quad, &params->quad);
    ql_unpack_controller_params(ql_default_p_ctrl, &params->ctrl);
    params->rotor_force_min = {config.literal(lo)};
    params->rotor_force_max = {config.literal(hi)};
    params->tilt_min = {config.literal(d.tilt_min)};
    params->hold_compensation = {config.literal(d.hold)};
}}

void ql_vehicle_params_init(ql_vehicle_params *params)
{{
    ql_unpack_vehicle_params(ql_default_p_veh, params);
}}

void ql_adaptive_state_init(ql_adaptive_state *state)
{{
    memset(state, 0, sizeof *state);
}}

void ql_reference_init(ql_reference *ref)
{{
    memcpy(ref->e1d, ql_default_ref, 4 * sizeof(ql_real));
    memcpy(ref->e1d_dot, ql_default_ref + 4, 4 * sizeof(ql_real));
    memcpy(ref->e1d_ddot, ql_default_ref + 8, 4 * sizeof(ql_real));
}}

void ql_pack_closed_loop_params(const ql_params *params, const ql_vehicle_params *vehicle,
                                const ql_reference *ref, ql_real *p)
{{
    ql_pack_quadrotor_params(&params->quad, p);
    ql_pack_vehicle_params(vehicle, p + QL_P_QUAD_SIZE);
    ql_pack_controller_params(&params->ctrl, p + QL_P_QUAD_SIZE + QL_P_VEH_SIZE);
    memcpy(p + QL_P_QUAD_SIZE + QL_P_VEH_SIZE + QL_P_CTRL_SIZE, ref, 12 * sizeof(ql_real));
}}

const char *ql_status_string(ql_status status)
{{
    switch (status) {{
""")
    for name, _, doc in STATUS_CODES:
        out.append(f'    case {name}: return "{doc}";\n')
    out.append(f"""    }}
    return "unknown status";
}}

/* 1 when all n values are finite. A sum of values is finite when all of
 * them are (a NaN or an infinity survives every addition, inf - inf is
 * NaN), so one addition per value decides the common case; only a sum that
 * overflowed from finite values needs the value-by-value test. Sixteen
 * independent sums keep the loop branch-free and let the compiler pair
 * them in vector instructions. */
static int ql_all_finite(const ql_real *v, int n)
{{
    ql_real acc[16] = {{0}};
    int i = 0;
    for (; i + 16 <= n; i += 16) {{
""" + "".join(f"        acc[{k}] += v[i + {k}];\n" for k in range(16)) + f"""    }}
    for (; i < n; ++i) {{
        acc[0] += v[i];
    }}
    for (i = 1; i < 16; ++i) {{
        acc[0] += acc[i];
    }}
    if (isfinite(acc[0])) {{
        return 1;
    }}
    for (i = 0; i < n; ++i) {{
        if (!isfinite(v[i])) {{
            return 0;
        }}
    }}
    return 1;
}}

static void ql_output_zero(ql_output *out, ql_real tilt)
{{
    memset(out, 0, sizeof *out);
    out->tilt = isfinite(tilt) ? tilt : 0;
}}

ql_status ql_control_step(const ql_quadrotor_state *xq, const ql_vehicle_state *yv,
                          const ql_reference *ref, const ql_params *params, ql_real dt,
                          ql_adaptive_state *state, ql_output *out)
{{
    /* in = [xq (10), yv (3), ref (12), dt]; res_v = [u, wrench, rotor,
     * zeta_next, u_law, W_next (4 l)], so that each is checked in one pass. */
    ql_real in[26], res_v[20 + 4 * QL_RBF_NODES], limits[2], hold, n_clipped, tilt;
    ql_real no_prev[4] = {{0, 0, 0, 0}};
    const ql_real *arg[control_step_SZ_ARG];
    ql_real *res[control_step_SZ_RES];
    casadi_int work_int[control_step_SZ_IW + 1];
    ql_real work_real[control_step_SZ_W + 1];

    if (!xq || !yv || !ref || !params || !state || !out) {{
        if (out) ql_output_zero(out, 0);
        return QL_ERR_NULL;
    }}
    in[0] = xq->z1;
    memcpy(in + 1, xq->eta1, 3 * sizeof(ql_real));
    memcpy(in + 4, xq->V1, 3 * sizeof(ql_real));
    memcpy(in + 7, xq->Omega1, 3 * sizeof(ql_real));
    in[10] = yv->z2;
    in[11] = yv->psi2;
    in[12] = yv->r2;
    memcpy(in + 13, ref->e1d, 4 * sizeof(ql_real));
    memcpy(in + 17, ref->e1d_dot, 4 * sizeof(ql_real));
    memcpy(in + 21, ref->e1d_ddot, 4 * sizeof(ql_real));
    in[25] = dt;
    /* The parameters, limits and tilt_min in one pass over ql_params. The
     * state is checked through the outputs: a NaN or an infinity in W_hat or
     * zeta_hat reaches u through W_hat^T Psi (0 * inf is NaN) and W_next,
     * zeta_next; one in u_prev reaches u when has_prev is set (u_prev is not
     * read otherwise). */
    if (!(ql_all_finite(in, 26) & ql_all_finite((const ql_real *)params, QL_PARAMS_SIZE))) {{
        ql_output_zero(out, 0);
        return QL_ERR_NONFINITE_INPUT;
    }}
    if (!(dt > 0) || !(params->rotor_force_min <= params->rotor_force_max)
        || !(params->hold_compensation >= 0 && params->hold_compensation <= 1)) {{
        ql_output_zero(out, 0);
        return QL_ERR_INVALID;
    }}
    limits[0] = params->rotor_force_min;
    limits[1] = params->rotor_force_max;
    hold = state->has_prev ? params->hold_compensation : 0;

    arg[0] = in;
    arg[1] = in + 10;
    arg[2] = in + 13;
    arg[3] = &state->W_hat[0][0];
    arg[4] = state->zeta_hat;
    arg[5] = state->has_prev ? state->u_prev : no_prev;
    arg[6] = (const ql_real *)&params->quad;
    arg[7] = (const ql_real *)&params->ctrl;
    arg[8] = limits;
    arg[9] = &hold;
    arg[10] = in + 25;
    res[0] = res_v;
    res[1] = res_v + 4;
    res[2] = res_v + 8;
    res[3] = res_v + 20;
    res[4] = res_v + 12;
    res[5] = res_v + 16;
    res[6] = &n_clipped;
    res[7] = &tilt;
    control_step(arg, res, work_int, work_real, 0);

    if (!({m("fabs")}(tilt) >= params->tilt_min)) {{
        ql_output_zero(out, tilt);
        return QL_ERR_TILT;
    }}
    if (!ql_all_finite(res_v, 20 + 4 * QL_RBF_NODES)) {{
        ql_output_zero(out, tilt);
        return ql_all_finite(&state->W_hat[0][0], 4 * QL_RBF_NODES + (state->has_prev ? 8 : 4))
            ? QL_ERR_NONFINITE_OUTPUT : QL_ERR_NONFINITE_INPUT;
    }}
    memcpy(out->u, res_v, 4 * sizeof(ql_real));
    memcpy(out->wrench, res_v + 4, 4 * sizeof(ql_real));
    memcpy(out->rotor, res_v + 8, 4 * sizeof(ql_real));
    memcpy(out->u_law, res_v + 16, 4 * sizeof(ql_real));
    out->n_clipped = (int)n_clipped;
    out->tilt = tilt;
    memcpy(state->zeta_hat, res_v + 12, 4 * sizeof(ql_real));
    memcpy(state->u_prev, res_v + 16, 4 * sizeof(ql_real));
    memcpy(&state->W_hat[0][0], res_v + 20, 4 * QL_RBF_NODES * sizeof(ql_real));
    state->has_prev = 1;
    return QL_OK;
}}
""")
    return "".join(out)


_WRAPPED = {
    "closed_loop": (("x", "w", "p"), ("x_dot",)),
    "closed_loop_jacobian": (("x", "w", "p"), ("jac_nz",)),
    "plant": (("xp", "wrench", "w", "p_quad", "p_veh"), ("xp_dot",)),
}


def _wrapper_source(config: CodegenConfig, file: str, names: tuple[str, ...]) -> str:
    """Named-pointer wrappers of CasADi functions, one file per link unit."""
    out = [_banner(config, f"{file}: C API of {', '.join(names)}.", "symbolic.codegen"),
           '#include "quadland.h"\n\n']
    out.extend(f'#include "{name}.h"\n' for name in names)
    for name in names:
        ins, outs = _WRAPPED[name]
        params = (",\n" + " " * (len(name) + 9)).join(
            [f"const ql_real *{a}" for a in ins] + [f"ql_real *{r}" for r in outs])
        out.append(f"\nvoid ql_{name}({params})\n{{\n"
                   f"    const ql_real *arg[{name}_SZ_ARG];\n"
                   f"    ql_real *res[{name}_SZ_RES];\n"
                   f"    casadi_int work_int[{name}_SZ_IW + 1];\n"
                   f"    ql_real work_real[{name}_SZ_W + 1];\n")
        out.extend(f"    arg[{i}] = {a};\n" for i, a in enumerate(ins))
        out.extend(f"    res[{i}] = {r};\n" for i, r in enumerate(outs))
        out.append(f"    {name}(arg, res, work_int, work_real, 0);\n}}\n")
        if name == "closed_loop_jacobian":
            out.append("\nconst int *ql_closed_loop_jacobian_sparsity(void)\n{\n"
                       "    return closed_loop_jacobian_sparsity_out(0);\n}\n")
    return "".join(out)


def generate(defaults: Defaults, config: CodegenConfig = CodegenConfig()) -> dict[str, str]:
    """Text of every generated C file of one precision.

    Parameters
    ----------
    defaults : Defaults
        Numeric defaults of the parameter structs and of the example.
    config : CodegenConfig
        Emitter settings.

    Returns
    -------
    dict of str to str
        File name (relative to the build's folder) to its text.
    """
    if config.casadi_int != "int":
        raise ValueError("the readable API exposes sparsity patterns as int: keep casadi_int = int")
    files = {}
    for name in CASADI_FUNCTIONS:
        files.update(_emit_casadi(name, defaults.l, config))
    files["quadland.h"] = _header(config, defaults)
    files["quadland.c"] = _source(config, defaults)
    files["quadland_model.c"] = _wrapper_source(config, "quadland_model.c",
                                                ("closed_loop", "plant"))
    files["quadland_jacobian.c"] = _wrapper_source(config, "quadland_jacobian.c",
                                                   ("closed_loop_jacobian",))
    return files


def _double_array(name: str, values) -> str:
    vals = [repr(float(v)) for v in np.asarray(values, dtype=float).ravel()]
    lines = ["    " + ", ".join(vals[i:i + 6]) + "," for i in range(0, len(vals), 6)]
    return f"static const double {name}[{len(vals)}] = {{\n" + "\n".join(lines) + "\n};\n"


def _example_scenario(d: Defaults) -> str:
    banner = _banner(CodegenConfig(), "paper_scenario.h: the paper's scenario for the examples.",
                     "quadland/scenarios/paper.toml")
    return (banner + "#ifndef QL_PAPER_SCENARIO_H\n#define QL_PAPER_SCENARIO_H\n\n"
            f"#define QL_EXAMPLE_DURATION {d.duration!r}              /* s */\n"
            f"#define QL_EXAMPLE_OUTPUT_RATE_HZ {d.output_rate_hz!r}      /* Hz, CSV rows */\n"
            f"#define QL_EXAMPLE_CONTROL_RATE_HZ {d.control_rate_hz!r}"
            "     /* Hz, 0 = continuous */\n"
            f"#define QL_EXAMPLE_DISTURBANCE_RATE_HZ {d.disturbance_rate_hz!r} /* Hz, hold */\n"
            f"#define QL_EXAMPLE_FORCE_AMPLITUDE {d.force_amplitude!r}     /* N */\n"
            f"#define QL_EXAMPLE_FORCE_FREQUENCY {d.force_frequency!r}     /* rad/s */\n"
            f"#define QL_EXAMPLE_MOMENT_AMPLITUDE {d.moment_amplitude!r}   /* N m */\n"
            f"#define QL_EXAMPLE_MOMENT_FREQUENCY {d.moment_frequency!r}   /* rad/s */\n\n"
            "/* Disturbance bias [d_F (N), d_M (N m)]; the random part is left out. */\n"
            + _double_array("ql_example_bias", [*d.force_bias, *d.moment_bias])
            + "\n/* Initial closed-loop state (layout of QL_CLOSED_LOOP_NX). */\n"
            + _double_array("ql_example_x0", d.x0)
            + "\n/* Vehicle deck altitude z2 (m). */\n"
            f"#define QL_EXAMPLE_Z2 {float(d.p_veh[-1])!r}\n\n#endif /* QL_PAPER_SCENARIO_H */\n")


_FLY_C = r"""#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "paper_scenario.h"
#include "quadland.h"

/* Usage: fly [RATE_HZ [DURATION_S]] > trajectory.csv
 *
 * RATE_HZ > 0: sampled data. ql_control_step runs every 1/RATE_HZ s and its
 * wrench is held on the plant (ql_plant), integrated by one classical RK4
 * step per control period. RATE_HZ = 0: the continuous-time closed loop
 * (ql_closed_loop), one RK4 step per output interval. The disturbance is
 * bias + amplitude sin(frequency t), held over each disturbance sample;
 * the paper's random part is left out so that runs are reproducible
 * everywhere. The rates must divide each other (see paper_scenario.h). */

#define NX QL_CLOSED_LOOP_NX
#define NL (4 * QL_RBF_NODES)

static void disturbance(double t, ql_real *w)
{
    int i;
    for (i = 0; i < 3; ++i) {
        w[i] = (ql_real)(ql_example_bias[i]
                         + QL_EXAMPLE_FORCE_AMPLITUDE * sin(QL_EXAMPLE_FORCE_FREQUENCY * t));
        w[3 + i] = (ql_real)(ql_example_bias[3 + i]
                             + QL_EXAMPLE_MOMENT_AMPLITUDE * sin(QL_EXAMPLE_MOMENT_FREQUENCY * t));
    }
}

/* Plant state xp = [xq (10), xv (6), x1, y1] from the closed-loop state. */
static void plant_from_closed_loop(const ql_real *x, ql_real *xp)
{
    memcpy(xp, x, 16 * sizeof(ql_real));
    xp[16] = x[NX - 2];
    xp[17] = x[NX - 1];
}

static void measure(const ql_real *x, ql_quadrotor_state *xq, ql_vehicle_state *yv)
{
    xq->z1 = x[0];
    memcpy(xq->eta1, x + 1, 3 * sizeof(ql_real));
    memcpy(xq->V1, x + 4, 3 * sizeof(ql_real));
    memcpy(xq->Omega1, x + 7, 3 * sizeof(ql_real));
    yv->z2 = (ql_real)QL_EXAMPLE_Z2;
    yv->psi2 = x[12];
    yv->r2 = x[15];
}

static void rk4_plant(ql_real *xp, const ql_real *wrench, const ql_real *w, const ql_real *pq,
                      const ql_real *pv, ql_real h)
{
    ql_real k1[QL_PLANT_NX], k2[QL_PLANT_NX], k3[QL_PLANT_NX], k4[QL_PLANT_NX], y[QL_PLANT_NX];
    int i;
    ql_plant(xp, wrench, w, pq, pv, k1);
    for (i = 0; i < QL_PLANT_NX; ++i) y[i] = xp[i] + h / 2 * k1[i];
    ql_plant(y, wrench, w, pq, pv, k2);
    for (i = 0; i < QL_PLANT_NX; ++i) y[i] = xp[i] + h / 2 * k2[i];
    ql_plant(y, wrench, w, pq, pv, k3);
    for (i = 0; i < QL_PLANT_NX; ++i) y[i] = xp[i] + h * k3[i];
    ql_plant(y, wrench, w, pq, pv, k4);
    for (i = 0; i < QL_PLANT_NX; ++i) xp[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
}

static void rk4_closed_loop(ql_real *x, const ql_real *w, const ql_real *p, ql_real h)
{
    static ql_real k1[NX], k2[NX], k3[NX], k4[NX], y[NX];
    int i;
    ql_closed_loop(x, w, p, k1);
    for (i = 0; i < NX; ++i) y[i] = x[i] + h / 2 * k1[i];
    ql_closed_loop(y, w, p, k2);
    for (i = 0; i < NX; ++i) y[i] = x[i] + h / 2 * k2[i];
    ql_closed_loop(y, w, p, k3);
    for (i = 0; i < NX; ++i) y[i] = x[i] + h * k3[i];
    ql_closed_loop(y, w, p, k4);
    for (i = 0; i < NX; ++i) x[i] += h / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
}

static void write_header(void)
{
    int i;
    printf("t,z_e,phi_e,theta_e,psi_e,z1,phi1,theta1,psi1,u1,v1,w1,p1,q1,r1,"
           "x2,y2,psi2,u2,v2,r2,x1,y1");
    for (i = 1; i <= 4; ++i) printf(",u_%d", i);
    printf(",F_total,M_x,M_y,M_z");
    for (i = 1; i <= 4; ++i) printf(",F_%d", i);
    for (i = 1; i <= 4; ++i) printf(",zeta_hat_%d", i);
    printf(",norm_W_hat,n_clipped,status\n");
}

static void write_row(double t, const ql_real *x, const ql_output *out, int status)
{
    double norm = 0;
    int i;
    for (i = 16; i < 16 + NL; ++i) norm += (double)x[i] * (double)x[i];
    printf("%.17g,%.17g,%.17g,%.17g,%.17g", t, (double)x[0] - QL_EXAMPLE_Z2, (double)x[1],
           (double)x[2], (double)x[3] - (double)x[12]);
    for (i = 0; i < 16; ++i) printf(",%.17g", (double)x[i]);
    printf(",%.17g,%.17g", (double)x[NX - 2], (double)x[NX - 1]);
    for (i = 0; i < 4; ++i) printf(",%.17g", (double)out->u[i]);
    for (i = 0; i < 4; ++i) printf(",%.17g", (double)out->wrench[i]);
    for (i = 0; i < 4; ++i) printf(",%.17g", (double)out->rotor[i]);
    for (i = 0; i < 4; ++i) printf(",%.17g", (double)x[16 + NL + i]);
    printf(",%.17g,%d,%d\n", sqrt(norm), out->n_clipped, status);
}

/* Steps of the grid per period of a rate; 0 when it does not divide. */
static long steps_per(double grid_hz, double rate_hz)
{
    long n = lround(grid_hz / rate_hz);
    return (n > 0 && fabs((double)n * rate_hz - grid_hz) < 1e-9 * grid_hz) ? n : 0;
}

int main(int argc, char **argv)
{
    static ql_real x[NX], p[QL_CLOSED_LOOP_NP];
    ql_real xp[QL_PLANT_NX], pq[QL_P_QUAD_SIZE], pv[QL_P_VEH_SIZE], w[6];
    ql_real wrench[4] = {0, 0, 0, 0};
    static ql_params params;
    static ql_adaptive_state state, probe;
    ql_vehicle_params vehicle;
    ql_reference ref;
    ql_quadrotor_state xq;
    ql_vehicle_state yv;
    ql_output out;
    double rate = argc > 1 ? atof(argv[1]) : QL_EXAMPLE_CONTROL_RATE_HZ;
    double duration = argc > 2 ? atof(argv[2]) : QL_EXAMPLE_DURATION;
    double grid_hz = rate > 0 ? rate : fmax(QL_EXAMPLE_OUTPUT_RATE_HZ,
                                            QL_EXAMPLE_DISTURBANCE_RATE_HZ);
    long n_out = steps_per(grid_hz, QL_EXAMPLE_OUTPUT_RATE_HZ);
    long n_dist = steps_per(grid_hz, QL_EXAMPLE_DISTURBANCE_RATE_HZ);
    long k, n_steps = lround(duration * grid_hz);
    ql_real h = (ql_real)(1.0 / grid_hz);
    int i, status = QL_OK;

    if (rate < 0 || duration < 0 || n_out == 0 || n_dist == 0) {
        fprintf(stderr, "fly: RATE_HZ must be 0 or a multiple of %g Hz and %g Hz\n",
                QL_EXAMPLE_OUTPUT_RATE_HZ, QL_EXAMPLE_DISTURBANCE_RATE_HZ);
        return 2;
    }
    ql_params_init(&params);
    ql_vehicle_params_init(&vehicle);
    ql_reference_init(&ref);
    ql_adaptive_state_init(&state);
    ql_pack_quadrotor_params(&params.quad, pq);
    ql_pack_vehicle_params(&vehicle, pv);
    ql_pack_closed_loop_params(&params, &vehicle, &ref, p);
    for (i = 0; i < NX; ++i) x[i] = (ql_real)ql_example_x0[i];
    plant_from_closed_loop(x, xp);
    memset(&out, 0, sizeof out);
    write_header();
    for (k = 0; k <= n_steps; ++k) {
        double t = (double)k / grid_hz;
        if (k % n_dist == 0) disturbance((double)(k / n_dist) / QL_EXAMPLE_DISTURBANCE_RATE_HZ, w);
        if (rate > 0) {
            if (k < n_steps) {
                measure(x, &xq, &yv);
                status = ql_control_step(&xq, &yv, &ref, &params, h, &state, &out);
                if (status != QL_OK) {
                    fprintf(stderr, "fly: t = %g s: %s\n", t, ql_status_string(status));
                    return 1;
                }
                memcpy(wrench, out.wrench, sizeof wrench);
            }
            memcpy(x + 16, &state.W_hat[0][0], NL * sizeof(ql_real));
            memcpy(x + 16 + NL, state.zeta_hat, 4 * sizeof(ql_real));
        } else {
            /* The law's outputs at this state, for the CSV only. */
            memcpy(&probe.W_hat[0][0], x + 16, NL * sizeof(ql_real));
            memcpy(probe.zeta_hat, x + 16 + NL, 4 * sizeof(ql_real));
            probe.has_prev = 0;
            measure(x, &xq, &yv);
            status = ql_control_step(&xq, &yv, &ref, &params, h, &probe, &out);
        }
        if (k % n_out == 0) write_row(t, x, &out, status);
        if (k == n_steps) break;
        if (rate > 0) {
            rk4_plant(xp, wrench, w, pq, pv, h);
            memcpy(x, xp, 16 * sizeof(ql_real));
            x[NX - 2] = xp[16];
            x[NX - 1] = xp[17];
        } else {
            rk4_closed_loop(x, w, p, h);
        }
    }
    return 0;
}
"""

_BENCH_C = r"""#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "paper_scenario.h"
#include "quadland.h"

/* Usage: bench N
 *
 * Runs N control steps (l = QL_RBF_NODES) from the paper's initial state,
 * each on slightly different measurements, and prints the time per step. */

int main(int argc, char **argv)
{
    static ql_params params;
    static ql_adaptive_state state;
    ql_reference ref;
    ql_quadrotor_state xq;
    ql_vehicle_state yv;
    ql_output out;
    struct timespec t0, t1;
    long i, n = argc > 1 ? strtol(argv[1], NULL, 10) : 100000;
    double seconds, check = 0;
    int bad = 0;

    if (n < 0) {
        fprintf(stderr, "usage: bench N\n");
        return 2;
    }
    ql_params_init(&params);
    ql_reference_init(&ref);
    ql_adaptive_state_init(&state);
    xq.z1 = (ql_real)ql_example_x0[0];
    for (i = 0; i < 3; ++i) {
        xq.eta1[i] = (ql_real)ql_example_x0[1 + i];
        xq.V1[i] = (ql_real)ql_example_x0[4 + i];
        xq.Omega1[i] = (ql_real)ql_example_x0[7 + i];
    }
    yv.z2 = (ql_real)QL_EXAMPLE_Z2;
    yv.psi2 = (ql_real)ql_example_x0[12];
    yv.r2 = (ql_real)ql_example_x0[15];
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (i = 0; i < n; ++i) {
        xq.z1 = (ql_real)(ql_example_x0[0] + 1e-6 * (double)(i & 1023));
        bad += ql_control_step(&xq, &yv, &ref, &params, (ql_real)0.002, &state, &out) != QL_OK;
        check += (double)out.wrench[0];
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    printf("control_step (%s, l = %d): %ld steps, %.1f ns/step (checksum %.6g, %d errors)\n",
           sizeof(ql_real) == sizeof(double) ? "double" : "float", QL_RBF_NODES, n,
           n > 0 ? 1e9 * seconds / (double)n : 0.0, check, bad);
    return bad != 0;
}
"""

_MAKEFILE = """\
CC ?= cc
CFLAGS ?= -std=c99 -pedantic -Wall -Wextra -Werror -O2
LDLIBS = -lm
BUILD = build
STEP = control_step.c quadland.c
MODEL = closed_loop.c plant.c quadland_model.c

.PHONY: all clean run
all: $(BUILD)/fly $(BUILD)/bench $(BUILD)/fly_float $(BUILD)/bench_float

$(BUILD):
\tmkdir -p $(BUILD)

# Double precision: sources in ../, single precision: ../float/.
$(BUILD)/fly: fly.c paper_scenario.h $(addprefix ../,$(STEP) $(MODEL)) | $(BUILD)
\t$(CC) $(CFLAGS) -I.. -o $@ fly.c $(addprefix ../,$(STEP) $(MODEL)) $(LDLIBS)

$(BUILD)/bench: bench.c paper_scenario.h $(addprefix ../,$(STEP)) | $(BUILD)
\t$(CC) $(CFLAGS) -I.. -o $@ bench.c $(addprefix ../,$(STEP)) $(LDLIBS)

$(BUILD)/fly_float: fly.c paper_scenario.h $(addprefix ../float/,$(STEP) $(MODEL)) | $(BUILD)
\t$(CC) $(CFLAGS) -I../float -o $@ fly.c $(addprefix ../float/,$(STEP) $(MODEL)) $(LDLIBS)

$(BUILD)/bench_float: bench.c paper_scenario.h $(addprefix ../float/,$(STEP)) | $(BUILD)
\t$(CC) $(CFLAGS) -I../float -o $@ bench.c $(addprefix ../float/,$(STEP)) $(LDLIBS)

run: $(BUILD)/fly $(BUILD)/bench
\t$(BUILD)/fly > $(BUILD)/trajectory.csv
\t$(BUILD)/bench 100000

clean:
\trm -rf $(BUILD)
"""


def generate_example(defaults: Defaults) -> dict[str, str]:
    """Text of the pure-C example: flight, benchmark and Makefile.

    The sources are precision-independent (``ql_real``); the Makefile builds
    them against both the double (``../``) and the float (``../float/``)
    files.
    """
    config = CodegenConfig()
    mk_banner = "".join("# " + line.lstrip(" /*").rstrip() + "\n"
                        for line in _banner(config, "Makefile of the pure-C example.",
                                            "symbolic.codegen").splitlines()
                        if line.strip(" /*"))
    return {
        "example/paper_scenario.h": _example_scenario(defaults),
        "example/fly.c": _banner(config, "fly.c: the paper's scenario flown in pure C.",
                                 "symbolic.codegen") + _FLY_C,
        "example/bench.c": _banner(config, "bench.c: time per control step.",
                                   "symbolic.codegen") + _BENCH_C,
        "example/Makefile": mk_banner + _MAKEFILE,
    }

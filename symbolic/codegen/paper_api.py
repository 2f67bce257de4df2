"""The readable API of the paper's control step: quadland.h and quadland.c."""

from __future__ import annotations

import numpy as np

from quadland_symbolic.closed_loop import (
    PAPER_PLANT_STATE,
    closed_loop_jacobian_function,
    closed_loop_params,
    closed_loop_state,
)
from quadland_symbolic.codegen.casadi_files import emit_casadi
from quadland_symbolic.codegen.config import DEFAULT_CONFIG, STATUS_CODES, CodegenConfig, Defaults
from quadland_symbolic.codegen.registry import BY_NAME, FUNCTIONS
from quadland_symbolic.codegen.render import common_context, render
from quadland_symbolic.codegen.structs import (
    CStruct,
    adaptive_state_layout,
    api_structs,
    param_ranges,
    params_layout,
)
from quadland_symbolic.control_step import step_inputs, step_outputs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, RBF_INPUT_DIM, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE

__all__ = ["unit_text", "member_context", "struct_context", "paper_sizes", "vector_structs",
           "step_context", "wrapped_functions", "param_range_context", "api_context", "generate",
           "emit_part"]


def unit_text(f: Field) -> str:
    """The unit of a member's comment: one unit, each entry's, or the distinct ones.

    A long array of mixed units (a FIFO of records, a stored covariance) names
    its distinct units in order, or says they are per entry when they are many.
    """
    if isinstance(f.unit, tuple):
        if len(set(f.unit)) == 1:
            return f.unit[0]
        if len(f.unit) <= 6:
            return ", ".join(f.unit)
        distinct = list(dict.fromkeys(f.unit))
        return ", ".join(distinct) if len(distinct) <= 4 else "per entry (see its layout)"
    return f.unit


def member_context(f: Field, structs: tuple[CStruct, ...], ql: str) -> dict:
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
    unit = unit_text(f)
    comment = f"{unit}: {f.doc}" if unit else f.doc
    generic = tuple(f"{f.name}_{i + 1}" for i in range(f.size))
    if (f.elements is not None and f.elements != generic and 1 < f.size <= 6
            and not any(e in f.doc for e in f.elements)):
        comment += f" ({', '.join(f.elements)})"
    return dict(name=f.name, type=ctype, dims=dims, comment=comment)


def struct_context(s: CStruct, structs, ql: str) -> dict:
    offsets = s.layout.offsets()
    reals = [dict(name=f.name, offset=offsets[f.name][0]) for f in s.layout.fields
             if f.ctype == "real"]
    ints = [dict(name=f.name, index=i) for i, f in
            enumerate(f for f in s.layout.fields if f.ctype == "int")]
    return dict(name=s.name, doc=s.doc, size=s.layout.size, reals=reals, ints=ints,
                members=[member_context(f, structs, ql) for f in s.layout.fields])


def paper_sizes(l: int, jac_nnz: int) -> list[dict]:
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


def vector_structs(d: Defaults, config: CodegenConfig) -> list[dict]:
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


def step_context(l: int, config: CodegenConfig) -> dict:
    """Where ``ql_control_step`` puts each argument and result of CasADi's function."""
    ins, outs = step_inputs(l), step_outputs(l)
    # The caller's measurements and dt, staged in one buffer and checked in one pass.
    staged_in = Layout("in", tuple(ins[n] for n in ("xq", "yv", "ref", "dt")))
    # Every result but the two scalars read first (n_clipped, tilt), likewise.
    staged_res = Layout("res_v", tuple(f for f in outs.fields
                                       if f.name not in ("n_clipped", "tilt")))
    res_offsets = staged_res.offsets()
    return dict(
        c_name=BY_NAME["control_step"].c_name(config),
        arg={n: i for i, n in enumerate(ins.names())},
        res={n: i for i, n in enumerate(outs.names())},
        in_size=staged_in.size, in_offset={n: a for n, (a, _) in staged_in.offsets().items()},
        res_size=staged_res.size, res_offset={n: a for n, (a, _) in res_offsets.items()},
        staged_res=[dict(name=n, index=outs.names().index(n), offset=a)
                    for n, (a, _) in res_offsets.items()],
        adaptive=adaptive_state_layout(l).offsets())


def wrapped_functions(l: int, config: CodegenConfig, part: str = "paper") -> list[dict]:
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


def param_range_context(l: int, config: CodegenConfig, ranges=param_ranges) -> list[dict]:
    """The range of each member of ``ql_params``, bounds as C literals.

    From ``quadland_symbolic.codegen.structs.param_ranges``, or another table's
    ``ranges(l)``.

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


def api_context(config: CodegenConfig, d: Defaults) -> dict:
    l = d.l
    structs = api_structs(l)
    jac = closed_loop_jacobian_function(l).sparsity_out(0)
    lo, hi = d.rotor_limits
    scalars = {"rotor_force_min": lo, "rotor_force_max": hi, "tilt_min": d.tilt_min,
               "hold_compensation": d.hold}
    params = params_layout(l)
    return dict(
        common_context(config),
        scenario=d.scenario,
        aliases=config.prefix != "ql_",
        sizes=paper_sizes(l, jac.nnz()),
        status_codes=[dict(name=n.removeprefix("QL_"), value=v, doc=doc)
                      for n, v, doc in STATUS_CODES],
        structs=[struct_context(s, structs, config.prefix) for s in structs],
        vectors=vector_structs(d, config),
        params_scalars=[dict(name=f.name, value=config.literal(scalars[f.name]))
                        for f in params.fields if f.layout is None],
        p_offset={n: a for n, (a, _) in closed_loop_params(l).offsets().items()},
        step=step_context(l, config),
        param_ranges=param_range_context(l, config),
        wrapped=wrapped_functions(l, config),
    )


def generate(defaults: Defaults, config: CodegenConfig = DEFAULT_CONFIG) -> dict[str, str]:
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
    return emit_part("paper", defaults.l, config, api_context(config, defaults),
                      ("quadland.h", "quadland.c", "quadland_status.c"))


def emit_part(part: str, l: int, config: CodegenConfig, ctx: dict,
               sources: tuple[str, ...]) -> dict[str, str]:
    """The files of one API: its CasADi functions, its templates, its wrappers.

    ``sources`` are rendered from ``<name>.jinja``; the first is the API's
    header, which the wrappers include.
    """
    files = {}
    for entry in FUNCTIONS:
        if entry.part == part:
            files.update(emit_casadi(entry, l, config))
    for name in sources:
        files[name] = render(f"{name}.jinja", **ctx)
    for file in dict.fromkeys(w["file"] for w in ctx["wrapped"]):
        files[file] = render("wrappers.c.jinja", file=file, header=sources[0],
                              functions=[w for w in ctx["wrapped"] if w["file"] == file], **ctx)
    return files


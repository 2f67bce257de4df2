"""The readable API of the landing step and guidance: quadland_landing.h and .c."""

from __future__ import annotations

import numpy as np

from quadland_symbolic.codegen.config import DEFAULT_CONFIG, CodegenConfig, LandingDefaults
from quadland_symbolic.codegen.paper_api import (
    emit_part,
    param_range_context,
    struct_context,
    wrapped_functions,
)
from quadland_symbolic.codegen.registry import BY_NAME
from quadland_symbolic.codegen.render import common_context
from quadland_symbolic.codegen.structs import (
    MAX_ABORTS,
    api_structs,
    guidance_param_ranges,
    guidance_state_layout,
    landing_api_structs,
    landing_output_layout,
    landing_param_ranges,
    landing_params_layout,
)
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    N_CHANNELS,
    NETWORK_INPUT_DIM,
    landing_guidance_function,
    landing_memory,
    landing_step_function,
    landing_step_outputs,
)
from quadland_symbolic.landing.guidance import (
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    PHASE_DOCS,
    PHASES,
    POSITION_REFERENCE,
)
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.relative import TOUCHDOWN_FIGURES
from quadland_symbolic.landing.ride import ANCHOR
from quadland_symbolic.landing.signals import LANDING_SIGNALS
from quadland_symbolic.layout import Layout
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["landing_sizes", "vector_context", "landing_step_context", "landing_api_context",
           "generate_landing"]


def landing_sizes(l: int) -> list[dict]:
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


def vector_context(name: str, values, config: CodegenConfig) -> dict:
    values = [config.literal(v) for v in np.asarray(values, dtype=float).ravel()]
    return dict(name=name, size=len(values), rows=[values[i:i + 6]
                                                   for i in range(0, len(values), 6)])


def landing_step_context(l: int, config: CodegenConfig) -> dict:
    """Where ``ql_landing_step`` and ``ql_guidance_step`` put each argument and result."""
    step, guide = landing_step_function(l), landing_guidance_function()
    outs = landing_step_outputs(l)
    # every real result but tilt and the flags, staged and checked in one pass
    staged = Layout("res_land", tuple(f for f in outs.fields if f.name not in ("tilt", "limits")))
    offsets = {n: a for n, (a, _) in staged.offsets().items()}
    out_lay = landing_output_layout(l)
    copies = [dict(name=f.name, offset=offsets[f.name]) for f in out_lay.fields
              if f.ctype == "real" and f.name in offsets]
    # the guidance's results, staged likewise: [xg_next, ref]
    g_offset = dict(zip(guide.name_out(), np.cumsum([0] + [guide.nnz_out(i) for i in range(
        guide.n_out())]).tolist(), strict=False))
    return dict(
        c_name=BY_NAME["landing_step"].c_name(config),
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
            c_name=BY_NAME["landing_guidance"].c_name(config),
            arg={n: i for i, n in enumerate(guide.name_in())},
            res={n: i for i, n in enumerate(guide.name_out())},
            res_size=sum(guide.nnz_out(i) for i in range(guide.n_out())), res_offset=g_offset,
            xg=[dict(name=n, index=i, int=guidance_state_layout()[n].ctype == "int")
                for i, n in enumerate(GUIDANCE_STATE.names())],
            xg_size=GUIDANCE_STATE.size, params_size=GUIDANCE_PARAMS.size,
            cues_size=GUIDANCE_CUES.size),
    )


def landing_api_context(config: CodegenConfig, d: LandingDefaults) -> dict:
    l = d.l
    paper = api_structs(1)
    structs = landing_api_structs(l)
    lookup = (*paper, *structs)
    return dict(
        common_context(config),
        scenario=d.scenario,
        aliases=config.prefix != "ql_",
        sizes=landing_sizes(l),
        phases=[dict(name=n.upper(), value=i, doc=doc, text=n)
                for i, (n, doc) in enumerate(zip(PHASES, PHASE_DOCS, strict=True))],
        structs=[struct_context(s, lookup, config.prefix) for s in structs],
        defaults=dict(p_quad=vector_context("p_quad", d.p_quad, config),
                      p_land=vector_context("p_land", d.p_ctrl, config),
                      p_act=vector_context("p_act", d.p_act, config),
                      p_guid=vector_context("p_guid", d.p_guid, config)),
        tilt_min=config.literal(d.tilt_min),
        max_aborts=MAX_ABORTS,
        n_phases=len(PHASES),
        landing_ranges=param_range_context(l, config, landing_param_ranges),
        guidance_ranges=param_range_context(l, config, lambda _: guidance_param_ranges()),
        step=landing_step_context(l, config),
        wrapped=wrapped_functions(l, config, "landing"),
    )


def generate_landing(defaults: LandingDefaults,
                     config: CodegenConfig = DEFAULT_CONFIG) -> dict[str, str]:
    """Text of the landing API's C files of one precision (``quadland_landing.h``, ...).

    They include the same build's ``quadland.h`` (:func:`generate`) for
    ``ql_real``, ``ql_status`` and ``ql_quadrotor_params``.
    """
    return emit_part("landing", defaults.l, config, landing_api_context(config, defaults),
                      ("quadland_landing.h", "quadland_landing.c"))


"""The structs of the readable C API (``quadland.h``, ``quadland_landing.h``), as layouts.

Each struct of ``quadland.h`` (the paper's control step) and of
``quadland_landing.h`` (the landing step and guidance) is one
:class:`CStruct`: a name and a
:class:`quadland_symbolic.layout.Layout`. The C declarations (``quadland_symbolic.codegen``)
and the ``ctypes`` mirrors (``quadland.engine.flightcode.ctypes_struct``) are both
derived from these layouts, so that they cannot drift apart:

* the real members are the layout's real fields, in order and without
  padding, so that a member's byte offset is its layout offset times
  ``sizeof(real)`` (``quadland.c`` checks this at compile time);
* ``int`` members (``ctype="int"``) follow every real one;
* a nested layout is a member of the struct type that has that layout;
* a matrix field ``shape = (rows, cols)`` (column-major, as CasADi stores
  it) is the C array ``name[cols][rows]``.

Structs that are vectors of the model take the model's layouts directly
(``quadland_symbolic.quadrotor.QUAD_STATE``, ``quadland_symbolic.parameters.QUADROTOR``, ...);
the three that only C has (``params``, ``adaptive_state``, ``output``)
are defined here from the fields of the control step's signature.

The valid values of every member of ``ql_params`` are one table,
:data:`PARAM_RANGES`, keyed by member path; :func:`param_ranges` walks
``params_layout(l)`` in order and pairs each real member with its range, so
that a new parameter without a range fails generation. ``ql_check_params``
and the step's own range test are generated from it. The landing API's
``ql_landing_params`` and ``ql_guidance_params`` have theirs,
:data:`LANDING_PARAM_RANGES` and :data:`GUIDANCE_PARAM_RANGES`
(:func:`landing_param_ranges`, :func:`guidance_param_ranges`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from types import MappingProxyType

from quadland_symbolic.backstepping import PAPER_REFERENCE
from quadland_symbolic.control_step import step_inputs, step_outputs
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    landing_controller_params,
    landing_memory,
    landing_step_outputs,
)
from quadland_symbolic.landing.guidance import (
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import QUAD_STATE
from quadland_symbolic.vehicle import VEHICLE_MEASUREMENT

__all__ = ["CStruct", "Range", "PARAM_RANGES", "ParamRange", "params_layout", "param_ranges",
           "adaptive_state_layout", "output_layout", "api_structs", "LANDING_PARAM_RANGES",
           "GUIDANCE_PARAM_RANGES", "MAX_ABORTS", "landing_params_layout",
           "landing_output_layout", "guidance_state_layout", "landing_param_ranges",
           "guidance_param_ranges", "landing_api_structs", "member_ranges"]


@dataclasses.dataclass(frozen=True)
class CStruct:
    """One struct of ``quadland.h``.

    Attributes
    ----------
    name : str
        C name without the build's prefix (``"quadrotor_state"`` is
        ``ql_quadrotor_state`` in the double build).
    layout : Layout
        Its members.
    doc : str
        The comment above the struct.
    """

    name: str
    layout: Layout
    doc: str

    def __post_init__(self):
        seen_int = False
        for f in self.layout.fields:
            if f.ctype == "int":
                if f.size != 1 or f.layout is not None or f.shape is not None:
                    raise ValueError(f"{self.name}.{f.name}: an int member is one scalar")
                seen_int = True
            elif seen_int:
                raise ValueError(f"{self.name}.{f.name}: real members come before int ones")

    @property
    def mirror(self) -> str:
        """Name of its ``ctypes`` mirror (``QuadrotorState``)."""
        return "".join(w.capitalize() for w in self.name.split("_"))


def _flat(field: Field, doc: str | None = None) -> Field:
    """A nested field as a plain array, keeping its entries' names and units."""
    if field.layout is None:
        return field if doc is None else dataclasses.replace(field, doc=doc)
    return Field(field.name, field.size, field.layout.element_units(), doc or field.doc,
                 elements=field.layout.element_names())


@functools.cache
def params_layout(l: int) -> Layout:
    """``ql_params``: everything the step is tuned with."""
    return Layout("params", (
        Field.nested("quad", QUADROTOR, "physical constants"),
        Field.nested("ctrl", controller_layout(l), "gains, adaptation, RBF network"),
        Field("rotor_force_min", 1, "N", "lower rotor force limit (clipping)"),
        Field("rotor_force_max", 1, "N", "upper rotor force limit (clipping)"),
        Field("tilt_min", 1, "-", "smallest accepted |cos(theta1) cos(phi1)|"),
        Field("hold_compensation", 1, "periods",
              "extrapolation of the held command, 0..1"),
    ), "tuning of the control step")


@dataclasses.dataclass(frozen=True)
class Range:
    """Valid values of one parameter member, every value finite.

    Attributes
    ----------
    lo, hi : float, optional
        Bounds (None: none).
    lo_open, hi_open : bool
        Whether the bound itself is excluded.
    choices : tuple of float, optional
        The only valid values (then no bounds).
    at_least : str, optional
        Path of a scalar member that bounds this one from below
        (``rotor_force_max >= rotor_force_min``); it comes earlier in the
        layout.
    """

    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    choices: tuple[float, ...] | None = None
    at_least: str | None = None

    def __post_init__(self):
        if self.choices is not None and (self.lo is not None or self.hi is not None):
            raise ValueError("a range has either choices or bounds")

    def text(self) -> str:
        """The range as the documentation writes it (``> 0``, ``in [0, 1)``)."""
        def num(v):
            return f"{v:g}"

        if self.choices is not None:
            return " or ".join(num(v) for v in self.choices)
        if self.at_least is not None:
            return f">= {self.at_least}"
        if self.lo is not None and self.hi is not None:
            return (f"in {'(' if self.lo_open else '['}{num(self.lo)}, "
                    f"{num(self.hi)}{')' if self.hi_open else ']'}")
        if self.lo is not None:
            return f"{'>' if self.lo_open else '>='} {num(self.lo)}"
        if self.hi is not None:
            return f"{'<' if self.hi_open else '<='} {num(self.hi)}"
        return "finite"


_FINITE = Range()
_POSITIVE = Range(lo=0.0, lo_open=True)
_NONNEGATIVE = Range(lo=0.0)

#: Valid values of every member of ``ql_params`` by member path (NaN and
#: infinities are invalid everywhere). Divisors and physical magnitudes are
#: positive (masses, inertias, arm, c, rho, widths), gains, adaptation
#: rates and leakages are positive (eq. 14, 20, 22: Lyapunov stability),
#: drag is not negative. The scenario schema (``quadland.scenario``) keeps
#: its values inside these ranges.
PARAM_RANGES = MappingProxyType({
    "quad.m1": _POSITIVE,
    "quad.I": _POSITIVE,
    "quad.Kt": _NONNEGATIVE,
    "quad.Kr": _NONNEGATIVE,
    "quad.g": _POSITIVE,
    "quad.arm": _POSITIVE,
    "quad.c": _POSITIVE,
    "ctrl.k1": _POSITIVE,
    "ctrl.k2": _POSITIVE,
    "ctrl.gamma1": _POSITIVE,
    "ctrl.gamma2": _POSITIVE,
    "ctrl.k_w": _POSITIVE,
    "ctrl.k_zeta": _POSITIVE,
    "ctrl.rho": _POSITIVE,
    "ctrl.nominal_model": Range(choices=(0.0, 1.0)),
    "ctrl.centers": _FINITE,
    "ctrl.widths": _POSITIVE,
    "rotor_force_min": _FINITE,
    "rotor_force_max": Range(at_least="rotor_force_min"),
    "tilt_min": Range(lo=0.0, hi=1.0, hi_open=True),
    "hold_compensation": Range(lo=0.0, hi=1.0),
})


@dataclasses.dataclass(frozen=True)
class ParamRange:
    """One member of ``ql_params`` with its range.

    Attributes
    ----------
    name : str
        Member path (``"quad.m1"``), as ``ql_check_params`` reports it.
    offset, size : int
        Position in the params vector (reals).
    range : Range
    at_least : int, optional
        Offset of the member named by ``range.at_least``.
    """

    name: str
    offset: int
    size: int
    range: Range
    at_least: int | None = None


def member_ranges(layout: Layout, table) -> tuple[ParamRange, ...]:
    """Every real member of ``layout`` in order, with its range in ``table``."""
    rows, offsets = [], {}

    def walk(lay: Layout, base: int, path: str):
        for f in lay.fields:
            if f.ctype != "real":
                continue
            start = base + lay.offsets()[f.name][0]
            name = path + f.name
            if f.layout is not None:
                walk(f.layout, start, name + ".")
                continue
            if name not in table:
                raise ValueError(f"{layout.name} member {name!r} has no range")
            rng = table[name]
            bound = None
            if rng.at_least is not None:
                if rng.at_least not in offsets:
                    raise ValueError(f"{name}: {rng.at_least!r} is not an earlier member")
                bound = offsets[rng.at_least]
            offsets[name] = start
            rows.append(ParamRange(name, start, f.size, rng, bound))

    walk(layout, 0, "")
    unused = set(table) - {r.name for r in rows}
    if unused:
        raise ValueError(f"the ranges of {layout.name} name no member: {sorted(unused)}")
    return tuple(rows)


@functools.cache
def param_ranges(l: int) -> tuple[ParamRange, ...]:
    """Every real member of ``ql_params`` in layout order, with its range.

    Raises
    ------
    ValueError
        When a member has no entry in :data:`PARAM_RANGES` or an entry
        names no member.
    """
    return member_ranges(params_layout(l), PARAM_RANGES)


@functools.cache
def adaptive_state_layout(l: int) -> Layout:
    """``ql_adaptive_state``: the step's memory, from its arguments."""
    ins = step_inputs(l)
    return Layout("adaptive_state", (
        _flat(ins["W_hat"], "W_hat (l x 4) column-major: W_hat[j][i] = W(i, j)"),
        _flat(ins["zeta_hat"], "zeta_hat (eq. 22)"),
        _flat(ins["u_prev"], "u_law of the last successful step"),
        Field("has_prev", 1, "-", "0: do not extrapolate (initially, after a gap)",
              ctype="int"),
    ), "adaptive state and previous command")


@functools.cache
def output_layout(l: int) -> Layout:
    """``ql_output``: the step's results for the flight stack."""
    outs = step_outputs(l)
    return Layout("output", (
        _flat(outs["u"], "commanded virtual inputs, before clipping"),
        _flat(outs["u_law"], "the law of eq. (20) at the measurements"),
        _flat(outs["wrench"], "F_total, M_x, M_y, M_z of the clipped rotors"),
        _flat(outs["rotor"], "rotor forces F1..F4, clipped to the limits"),
        _flat(outs["tilt"], "cos(theta1) cos(phi1)"),
        dataclasses.replace(outs["n_clipped"], doc="number of rotors clipped this step (0..4)",
                            ctype="int"),
    ), "outputs of one control step")


@functools.cache
def api_structs(l: int) -> tuple[CStruct, ...]:
    """Every struct of ``quadland.h`` for ``l`` RBF nodes, in declaration order."""
    return (
        CStruct("quadrotor_state", QUAD_STATE,
                "Measured quadrotor state (eq. 1-2): Earth frame z up, ZYX Euler angles."),
        CStruct("vehicle_state", VEHICLE_MEASUREMENT,
                "Measured vehicle state (eq. 4); heave, roll and pitch are neglected."),
        CStruct("reference", PAPER_REFERENCE,
                "Reference of the relative states e1 = [z_e, phi_e, theta_e, psi_e]."),
        CStruct("adaptive_state", adaptive_state_layout(l),
                "The step's memory: the adaptive state (eq. 22) and the law's previous\n"
                " * output for the hold compensation. Start with {ql}adaptive_state_init."),
        CStruct("quadrotor_params", QUADROTOR,
                "Physical constants of the quadrotor (Table 1, eq. 2): layout p_quad."),
        CStruct("controller_params", controller_layout(l),
                "Gains, adaptation constants and RBF network (eq. 14, 20, 22): layout p_ctrl."),
        CStruct("vehicle_params", VEHICLE,
                "Constants and inputs of the ground vehicle (Table 1, eq. 4): layout p_veh."),
        CStruct("params", params_layout(l),
                "Everything {ql}control_step is tuned with; {ql}params_init fills the defaults."),
        CStruct("output", output_layout(l), "Outputs of one control step."),
    )


# --- the landing API (quadland_landing.h) -------------------------------------

_QUAD_RANGES = {k: v for k, v in PARAM_RANGES.items() if k.startswith("quad.")}

#: Valid values of every member of ``ql_landing_params`` by member path: the
#: quadrotor's as in :data:`PARAM_RANGES`; gains, adaptation rates, leakages,
#: the filter's frequency and damping positive (eq. 14, 20, 22 and a stable
#: filter); the tilt limit inside (0, pi/2) (the thrust must point up); the
#: bias estimates' gains and bounds not negative (0: no integral action); the
#: rotor limit and the motors' lag positive; the gear not above the centre; the
#: quadratic drag and the rotor radius not negative, the air's density positive; the
#: rotors' efficiencies not negative, the centre of gravity's offset finite.
LANDING_PARAM_RANGES = MappingProxyType({
    **_QUAD_RANGES,
    **{f"ctrl.{k}": _POSITIVE for k in ("k1p", "k2p", "k1", "k2", "gamma1", "gamma2", "k_w",
                                        "k_zeta", "rho")},
    "ctrl.nominal_model": Range(choices=(0.0, 1.0)),
    "ctrl.w_f": _POSITIVE,
    "ctrl.zeta_f": _POSITIVE,
    "ctrl.tilt_max": Range(lo=0.0, hi=math.pi / 2, lo_open=True, hi_open=True),
    "ctrl.centers": _FINITE,
    "ctrl.widths": _POSITIVE,
    **{f"ctrl.{k}": _NONNEGATIVE for k in ("ki_p", "ki", "d_max_p", "d_max", "r_learn",
                                                      "w_o")},
    "act.motor_time_constant": _POSITIVE,
    "act.F_max": _POSITIVE,
    "act.gear_height": _NONNEGATIVE,
    "act.drag_quadratic": _NONNEGATIVE,
    "act.rotor_radius": _NONNEGATIVE,
    "act.air_density": _POSITIVE,
    "act.rotor_efficiency": _NONNEGATIVE,
    "act.cg_offset": _FINITE,
    "tilt_min": Range(lo=0.0, hi=1.0, hi_open=True),
})

#: Valid values of every member of ``ql_guidance_params``: heights, radii,
#: speeds and times positive (a zero dwell or settling time is allowed), the
#: gear's height not negative.
GUIDANCE_PARAM_RANGES = MappingProxyType({
    "hover_height": _POSITIVE,
    "align_radius": _POSITIVE,
    "dwell_time": _NONNEGATIVE,
    "descent_speed": _POSITIVE,
    "descent_time": _POSITIVE,
    "touchdown_speed": _POSITIVE,
    "touchdown_height": _NONNEGATIVE,
    "max_offset": _POSITIVE,
    "max_relative_speed": _POSITIVE,
    "max_deck_rise": _POSITIVE,
    "settle_time": _NONNEGATIVE,
    "marker_timeout": _NONNEGATIVE,
    "search_height": _POSITIVE,
    "fly_on": Range(choices=(0.0, 1.0)),
    "flare_height": _NONNEGATIVE,
    "flare_tilt": Range(lo=0.0, hi=math.pi / 2, lo_open=True, hi_open=True),
    "hold_time": _NONNEGATIVE,
    "level_time": _POSITIVE,
    "cut_time": _NONNEGATIVE,
    "aim_height": _NONNEGATIVE,
    "pivot_x": _NONNEGATIVE,
    "pivot_y": _NONNEGATIVE,
    "pivot_h": _NONNEGATIVE,
    "commit_height": _POSITIVE,
    "commit_horizon": _POSITIVE,
    "calm_speed": _POSITIVE,
    "motion_time": _POSITIVE,
    "descent_leash": _NONNEGATIVE,
    "leash_height": _NONNEGATIVE,
    "withdraw_height": _FINITE,
    "calm_tilt": _NONNEGATIVE,
    "calm_lean": _NONNEGATIVE,
    "lean_time": _POSITIVE,
    "lean_withdraw": Range(choices=(0.0, 1.0)),
    "contact_drop": _NONNEGATIVE,
    "crawl_pause": Range(choices=(0.0, 1.0)),
    "swerve_accel": _NONNEGATIVE,
    "crawl_gate": _NONNEGATIVE,
    "crawl_gate_time": _NONNEGATIVE,
    "crawl_gate_floor": _NONNEGATIVE,
    "crawl_gate_wait": _NONNEGATIVE,
    "abort_floor": _FINITE,
    "crawl_gate_rise": _NONNEGATIVE,
    "crawl_gate_wait_height": _NONNEGATIVE,
    "ground_airmode": Range(choices=(0.0, 1.0)),
    "flare_deck_tilt": Range(lo=0.0, hi=math.pi / 2, lo_open=True),
    "flare_deck_height": _NONNEGATIVE,
    "crawl_abort_offset": _POSITIVE,
    "crawl_gate_count_height": _NONNEGATIVE,
    "crawl_abort_budget": _NONNEGATIVE, "withdraw_budget": _NONNEGATIVE,
})

#: Largest abort count ``ql_guidance_step`` accepts in its state (2^24 - 1:
#: exact in float, and one more still fits an int).
MAX_ABORTS = 2 ** 24 - 1


@functools.cache
def landing_params_layout(l: int) -> Layout:
    """``ql_landing_params``: everything the landing step is tuned with."""
    return Layout("landing_params", (
        Field.nested("quad", QUADROTOR, "physical constants"),
        Field.nested("ctrl", landing_controller_params(l),
                     "gains, command filter, tilt limit, RBF network"),
        Field.nested("act", ACTUATOR, "rotor limit (and the motors' lag, the gear)"),
        Field("tilt_min", 1, "-", "smallest accepted |cos(theta1) cos(phi1)|"),
    ), "tuning of the landing step")


@functools.cache
def landing_output_layout(l: int) -> Layout:
    """``ql_landing_output``: the landing step's results but its memory, flags as ints."""
    outs = landing_step_outputs(l)
    flags = outs["limits"].elements
    docs = {"thrust_limited": "1 when the thrust was limited to [0, 4 F_max]",
            "tilt_limited": "1 when the thrust axis was limited to tilt_max",
            "n_clipped": "number of rotor commands clipped to [0, F_max] (0..4)"}
    return Layout("landing_output", (
        *(_flat(outs[n]) for n in outs.names() if n not in ("mem_next", "limits")),
        *(Field(name, 1, "-", docs[name], ctype="int") for name in flags),
    ), "outputs of one landing step")


@functools.cache
def guidance_state_layout() -> Layout:
    """``ql_guidance_state``: the guidance's memory, phase and abort count as ints."""
    return Layout("guidance_state", (
        *(f for f in GUIDANCE_STATE.fields if f.name not in ("phase", "aborts")),
        Field("phase", 1, "-", "phase: QL_PHASE_APPROACH .. QL_PHASE_LANDED", ctype="int"),
        Field("aborts", 1, "-", "aborted descents so far", ctype="int"),
    ), "guidance state")


@functools.cache
def landing_param_ranges(l: int) -> tuple[ParamRange, ...]:
    """Every real member of ``ql_landing_params`` in order, with its range."""
    return member_ranges(landing_params_layout(l), LANDING_PARAM_RANGES)


@functools.cache
def guidance_param_ranges() -> tuple[ParamRange, ...]:
    """Every member of ``ql_guidance_params`` in order, with its range."""
    return member_ranges(GUIDANCE_PARAMS, GUIDANCE_PARAM_RANGES)


@functools.cache
def landing_api_structs(l: int) -> tuple[CStruct, ...]:
    """Every struct of ``quadland_landing.h`` for ``l`` RBF nodes, in declaration order.

    ``ql_landing_params.quad`` is ``quadland.h``'s ``ql_quadrotor_params``.
    """
    return (
        CStruct("landing_measurement", LANDING_MEASUREMENT,
                "What the landing step and the guidance measure: the landing sensor (deck\n"
                " * frame), the IMU and the vehicle's broadcast of its deck's motion (E)."),
        CStruct("guidance_cues", GUIDANCE_CUES,
                "What the rest of the flight stack tells the guidance: the touchdown\n"
                " * verdict (on sensors the land detector's) and the marker's age."),
        CStruct("position_reference", POSITION_REFERENCE,
                "The guidance's reference of the relative position, deck frame."),
        CStruct("landing_state", landing_memory(l),
                "The landing step's memory: network, robust terms, command filter and\n"
                " * saturation compensator. Start with {ql}landing_state_init."),
        CStruct("landing_controller_params", landing_controller_params(l),
                "Gains, adaptation, command filter, tilt limit and RBF network: layout\n"
                " * p_land."),
        CStruct("actuator_params", ACTUATOR, "Rotors and landing gear: layout p_act."),
        CStruct("landing_params", landing_params_layout(l),
                "Everything {ql}landing_step is tuned with; {ql}landing_params_init fills\n"
                " * the defaults."),
        CStruct("landing_output", landing_output_layout(l), "Outputs of one landing step."),
        CStruct("guidance_state", guidance_state_layout(),
                "The guidance's memory. Start with {ql}guidance_state_init."),
        CStruct("guidance_params", GUIDANCE_PARAMS,
                "The guidance's parameters; {ql}guidance_params_init fills the defaults."),
    )

"""The structs of the readable C API (``quadland.h``), as layouts.

Each struct of ``quadland.h`` is one :class:`CStruct`: a name and a
:class:`symbolic.layout.Layout`. The C declarations (``symbolic.codegen``)
and the ``ctypes`` mirrors (``quadland.cbackend.ctypes_struct``) are both
derived from these layouts, so that they cannot drift apart:

* the real members are the layout's real fields, in order and without
  padding, so that a member's byte offset is its layout offset times
  ``sizeof(real)`` (``quadland.c`` checks this at compile time);
* ``int`` members (``ctype="int"``) follow every real one;
* a nested layout is a member of the struct type that has that layout;
* a matrix field ``shape = (rows, cols)`` (column-major, as CasADi stores
  it) is the C array ``name[cols][rows]``.

Structs that are vectors of the model take the model's layouts directly
(``symbolic.quadrotor.STATE``, ``symbolic.parameters.QUADROTOR``, ...);
the three that only C has (``params``, ``adaptive_state``, ``output``)
are defined here from the fields of the control step's signature.

The valid values of every member of ``ql_params`` are one table,
:data:`PARAM_RANGES`, keyed by member path; :func:`param_ranges` walks
``params_layout(l)`` in order and pairs each real member with its range, so
that a new parameter without a range fails generation. ``ql_check_params``
and the step's own range test are generated from it.
"""

from __future__ import annotations

import dataclasses
import functools
from types import MappingProxyType

from symbolic.backstepping import REFERENCE
from symbolic.control_step import step_inputs, step_outputs
from symbolic.layout import Field, Layout
from symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from symbolic.quadrotor import STATE as QUAD_STATE
from symbolic.vehicle import MEASUREMENT

__all__ = ["CStruct", "Range", "PARAM_RANGES", "ParamRange", "params_layout", "param_ranges",
           "adaptive_state_layout", "output_layout", "api_structs"]


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


@functools.cache
def param_ranges(l: int) -> tuple[ParamRange, ...]:
    """Every real member of ``ql_params`` in layout order, with its range.

    Raises
    ------
    ValueError
        When a member has no entry in :data:`PARAM_RANGES` or an entry
        names no member.
    """
    rows, offsets = [], {}

    def walk(layout: Layout, base: int, path: str):
        for f in layout.fields:
            start = base + layout.offsets()[f.name][0]
            name = path + f.name
            if f.layout is not None:
                walk(f.layout, start, name + ".")
                continue
            if name not in PARAM_RANGES:
                raise ValueError(f"params member {name!r} has no range in PARAM_RANGES")
            rng = PARAM_RANGES[name]
            bound = None
            if rng.at_least is not None:
                if rng.at_least not in offsets:
                    raise ValueError(f"{name}: {rng.at_least!r} is not an earlier member")
                bound = offsets[rng.at_least]
            offsets[name] = start
            rows.append(ParamRange(name, start, f.size, rng, bound))

    walk(params_layout(l), 0, "")
    unused = set(PARAM_RANGES) - {r.name for r in rows}
    if unused:
        raise ValueError(f"PARAM_RANGES names no member: {sorted(unused)}")
    return tuple(rows)


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
        CStruct("vehicle_state", MEASUREMENT,
                "Measured vehicle state (eq. 4); heave, roll and pitch are neglected."),
        CStruct("reference", REFERENCE,
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

"""The functions a compiled simulator needs, in a model-independent shape.

A simulator integrates one of two kinds of loop, and knows nothing of a
model but the sizes of these functions' flat vector arguments:

* continuous: ``rhs(x, w, t, p) -> x_dot`` and ``outputs(x, w, t, p) -> y``
  (the output signals stacked in one vector);
* sampled-data: a plant ``plant(xp, uh, w, t, pp) -> xp_dot`` driven by the
  held input ``uh``, a controller ``controller(xp, xc, pc, first, t) ->
  (xc_next, uh, rec, guard)`` run at its own rate (``rec``: the signals to
  record at the output times, ``guard``: a scalar that must stay away from
  zero, ``first``: 1 on the first step), and ``assemble(xp, xc) -> x``, the
  continuous loop's state, so that ``outputs`` serves both loops; and,
  optionally, an event ``event(xp, t, pp) -> g`` whose crossing from
  positive to zero or below ends the run at the instant it happens (a
  touchdown), located within the step;

and an envelope ``envelope(x, uh) -> s``: magnitudes (altitude, speed, rate,
network weights, ...) that must stay at or below bounds given per run, so
that a diverging flight stops as soon as it leaves the physical envelope
instead of when a value overflows.

``t`` is the time, s: models that do not depend on it ignore it.

:class:`LoopModel` bundles them with their layouts; :func:`paper_loop`
builds it for the paper's 4-DOF loop. A new model supplies its own
``LoopModel`` and goes through the same code generation, build and driver.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import tempfile
from pathlib import Path

import casadi as ca
import jinja2

from symbolic.backstepping import PAPER_REFERENCE
from symbolic.closed_loop import (
    PAPER_ENVELOPE,
    PAPER_OUTPUTS,
    PAPER_PLANT_STATE,
    closed_loop_function,
    closed_loop_outputs,
    closed_loop_params,
    closed_loop_state,
    paper_envelope_function,
    plant_function,
    vehicle_measurement,
)
from symbolic.control_step import control_step_function, step_inputs, step_outputs
from symbolic.layout import Field, Layout
from symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from symbolic.quadrotor import BODY_DISTURBANCE, WRENCH

__all__ = ["rk4_step", "LoopModel", "paper_loop", "paper_controller_state",
           "paper_controller_params",
           "PAPER_PLANT_PARAMS", "PAPER_RECORDED", "SIMULATOR_PARTS", "simulator_sources",
           "loop_header"]


def rk4_step(f: ca.Function) -> ca.Function:
    """One classical RK4 step of ``x' = f(x, *u)``, the inputs after ``x`` held.

    ``rk4(x, *u, h) -> x_next``: the step the compiled drivers take, for
    CasADi's virtual machine (the fallback without a C compiler). An input
    named ``t`` is the time: it advances through the stages (``t``,
    ``t + h/2``, ``t + h``) instead of being held.
    """
    args = [ca.MX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(f.n_in())]
    h = ca.MX.sym("h")
    x, u = args[0], args[1:]
    names = f.name_in()[1:]

    def at(c):
        return [ui + c * h if name == "t" else ui for name, ui in zip(names, u, strict=True)]

    k1 = f(x, *at(0))
    k2 = f(x + h / 2 * k1, *at(0.5))
    k3 = f(x + h / 2 * k2, *at(0.5))
    k4 = f(x + h * k3, *at(1))
    return ca.Function(f"{f.name()}_rk4", [*args, h], [x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)],
                       [*f.name_in(), "h"], [f"{f.name_out(0)}_next"])


@dataclasses.dataclass(frozen=True)
class LoopModel:
    """The symbolic functions and layouts of one simulated loop.

    Attributes
    ----------
    name : str
        Identifier, used in generated C symbols.
    state, disturbance, params, outputs : Layout
        Layouts of ``x``, ``w``, ``p`` and ``y`` of the continuous loop.
    rhs, output_fn : casadi.Function
        ``rhs(x, w, t, p) -> x_dot`` (None for a loop that is sampled-data
        only); ``outputs(x, w, t, p) -> y`` (one vector).
    plant_state, held, controller_state, plant_params, controller_params, recorded : Layout
        Layouts of the sampled-data loop's ``xp``, ``uh``, ``xc``, ``pp``,
        ``pc`` and ``rec``.
    plant, controller, assemble : casadi.Function
        The sampled-data loop's functions (see the module docstring).
    step_args : casadi.Function or None
        ``step_args(xp, xc, pc, first, t) -> (...)``: the flight code's
        arguments as the controller forms them (the paper's: the control
        step's, ``symbolic.control_step.step_inputs``). The flight code behind
        the controller's flat signature (part ``"sampled_flight"``) starts
        from it.
    event : casadi.Function or None
        ``event(xp, t, pp) -> g``: the run ends where ``g`` falls from
        positive to zero or below (see the module docstring).
    envelope : casadi.Function or None
        ``envelope(x, uh) -> s``: magnitudes of the loop state ``x`` and the
        held input ``uh`` (zero in the continuous loop) that a flight must
        keep below bounds given at run time: the run stops where one does
        not (a diverging flight), see the module docstring.
    envelope_layout : Layout or None
        Names, units and meanings of ``s``.
    flight : str or None
        The template (in ``symbolic/templates/``) of the adapter that puts
        the flight code behind the controller's signature.
    """

    name: str
    state: Layout
    disturbance: Layout
    params: Layout
    outputs: Layout
    rhs: ca.Function | None
    output_fn: ca.Function
    plant_state: Layout
    held: Layout
    controller_state: Layout
    plant_params: Layout
    controller_params: Layout
    recorded: Layout
    plant: ca.Function
    controller: ca.Function
    assemble: ca.Function
    step_args: ca.Function | None = None
    event: ca.Function | None = None
    envelope: ca.Function | None = None
    envelope_layout: Layout | None = None
    flight: str | None = None

    def functions(self) -> tuple[ca.Function, ...]:
        """Every function a simulator calls, named ``rhs``, ``outputs``, ... ."""
        return tuple(f for f in (self.rhs, self.output_fn, self.plant, self.controller,
                                 self.assemble, self.step_args, self.event, self.envelope)
                     if f is not None)


#: What the sampled loop records of each control step: the held signals.
PAPER_RECORDED = Layout("rec", tuple(step_outputs(1)[n] for n in ("u", "wrench", "rotor")),
                  "signals of the control step held until the next")


@functools.cache
def paper_controller_state(l: int) -> Layout:
    """The sampled controller's memory: adaptive states and the law's last output."""
    so = step_outputs(l)
    return Layout("xc", (
        dataclasses.replace(so["W_next"], name="W_hat"),
        dataclasses.replace(so["zeta_next"], name="zeta_hat"),
        dataclasses.replace(so["u_law"], name="u_prev"),
    ), "sampled controller state")


#: Parameters of the plant alone.
PAPER_PLANT_PARAMS = Layout("pp", (Field.nested("p_quad", QUADROTOR, "quadrotor constants"),
                             Field.nested("p_veh", VEHICLE, "vehicle constants and inputs")),
                      "plant parameters")


@functools.cache
def paper_controller_params(l: int) -> Layout:
    """Parameters of the sampled controller: the loop's, limits, hold and period."""
    return Layout("pc", (
        Field.nested("p_quad", QUADROTOR, "quadrotor constants"),
        Field.nested("p_veh", VEHICLE, "vehicle constants and inputs"),
        Field.nested("p_ctrl", controller_layout(l), "controller"),
        Field.nested("ref", PAPER_REFERENCE, "reference"),
        Field("rotor_limits", 2, "N", "rotor force limits", elements=("F_min", "F_max")),
        Field("hold", 1, "periods", "hold compensation"),
        Field("dt", 1, "s", "control period"),
    ), "sampled controller parameters")


def _named(name, ins, outs, in_names, out_names):
    return ca.Function(name, ins, outs, in_names, out_names)


@functools.cache
def paper_loop(l: int) -> LoopModel:
    """The paper's 4-DOF loop (``symbolic.closed_loop``) for ``l`` RBF nodes."""
    state, params = closed_loop_state(l), closed_loop_params(l)
    x, w, p, t = state.sym(), BODY_DISTURBANCE.sym(), params.sym(), ca.SX.sym("t")
    rhs = _named("rhs", [x, w, t, p], [closed_loop_function(l)(x, w, p)],
                 ["x", "w", "t", "p"], ["x_dot"])
    output_fn = _named("outputs", [x, w, t, p],
                       [ca.vertcat(*closed_loop_outputs(l)(x, w, p))],
                       ["x", "w", "t", "p"], ["y"])

    xc_lay, pc_lay = paper_controller_state(l), paper_controller_params(l)
    xp, uh, pp = PAPER_PLANT_STATE.sym(), WRENCH.sym(), PAPER_PLANT_PARAMS.sym()
    pps = PAPER_PLANT_PARAMS.unpack(pp)
    plant = _named("plant", [xp, uh, w, t, pp],
                   [plant_function()(xp, uh, w, pps["p_quad"], pps["p_veh"])],
                   ["xp", "uh", "w", "t", "pp"], ["xp_dot"])

    xc, pc, first = xc_lay.sym(), pc_lay.sym(), ca.SX.sym("first")
    xs, cs, ps = PAPER_PLANT_STATE.unpack(xp), xc_lay.unpack(xc), pc_lay.unpack(pc)
    yv = vehicle_measurement(xs["xv"], ps["p_veh"])
    hold = (1 - first) * ps["hold"]                  # no previous command on the first step
    args = [xs["xq"], yv, ps["ref"], cs["W_hat"], cs["zeta_hat"], cs["u_prev"], ps["p_quad"],
            ps["p_ctrl"], ps["rotor_limits"], hold, ps["dt"]]
    step_args = _named("step_args", [xp, xc, pc, first, t], [ca.vec(a) for a in args],
                       ["xp", "xc", "pc", "first", "t"], list(step_inputs(l).names()))
    res = dict(zip(step_outputs(l).names(), control_step_function(l)(*args), strict=True))
    controller = _named(
        "controller", [xp, xc, pc, first, t],
        [ca.vertcat(ca.vec(res["W_next"]), res["zeta_next"], res["u_law"]), res["wrench"],
         ca.vertcat(*(res[n] for n in PAPER_RECORDED.names())), res["tilt"]],
        ["xp", "xc", "pc", "first", "t"], ["xc_next", "uh", "rec", "guard"])

    x_of = ca.vertcat(*[xs[n] if n in xs else ca.vec(cs[n]) for n in state.names()])
    assemble = _named("assemble", [xp, xc], [x_of], ["xp", "xc"], ["x"])
    envelope = _named("envelope", [x, uh], [paper_envelope_function(l)(x, uh)], ["x", "uh"], ["s"])
    return LoopModel("paper", state, BODY_DISTURBANCE, params, PAPER_OUTPUTS, rhs, output_fn,
                     PAPER_PLANT_STATE, WRENCH, xc_lay, PAPER_PLANT_PARAMS, pc_lay,
                     PAPER_RECORDED, plant,
                     controller, assemble, step_args=step_args, envelope=envelope,
                     envelope_layout=PAPER_ENVELOPE, flight="flight_controller.c.jinja")


_TEMPLATES = jinja2.Environment(
    loader=jinja2.FileSystemLoader(Path(__file__).parent / "templates"),
    undefined=jinja2.StrictUndefined, keep_trailing_newline=True, trim_blocks=True,
    lstrip_blocks=True)


#: The parts of a compiled simulator: each one's driver and the functions it calls.
#: ``"sampled_flight"`` flies the flight code (``quadland.h``'s
#: ``ql_control_step``; ``quadland_landing.h``'s ``ql_guidance_step`` and
#: ``ql_landing_step``) in place of the symbolic controller, through the
#: model's adapter (:attr:`LoopModel.flight`); its build adds the flight
#: sources.
SIMULATOR_PARTS = {"continuous": ("continuous", ("rhs", "outputs", "envelope")),
                   "sampled": ("sampled", ("plant", "controller", "assemble", "outputs",
                                           "envelope")),
                   "sampled_flight": ("sampled", ("plant", "step_args", "assemble", "outputs",
                                                  "envelope"))}


def loop_header(precision: str | None = None) -> str:
    """``quadland_loop.h``: the loop algorithm the simulators and the pure-C examples share.

    Clocks and their merged grid, RK4 over a span, the event's bisection
    (``symbolic/templates/quadland_loop.h.jinja``); ``quadland.engine.loop``
    mirrors it in Python.
    """
    return _TEMPLATES.get_template("quadland_loop.h.jinja").render(
        builder="quadland codegen (symbolic/codegen.py)", casadi_version=ca.__version__,
        precision=precision)


def simulator_sources(model: LoopModel, part: str) -> dict[str, str]:
    """C sources of one part of a compiled simulator of ``model``, by file name.

    Parameters
    ----------
    model : LoopModel
    part : {"continuous", "sampled"}
        Which loop; see :data:`SIMULATOR_PARTS`.

    Returns
    -------
    dict of str to str
        ``<prefix><function>.c/.h``: each function the part calls, as
        CasADi writes it, named ``<prefix><function>`` (one translation unit
        each, so that a build compiles them in parallel); ``<prefix><part>.c``:
        the driver (``symbolic/templates/simulator.c.jinja``): RK4 over an
        exact grid, one call per run, parameters passed once and shared,
        outputs written straight into the caller's arrays. ``prefix`` is
        ``qlsim_<model name>_``. The text depends only on the model and the
        CasADi version.
    """
    if part not in SIMULATOR_PARTS:
        raise ValueError(f"part must be one of {', '.join(SIMULATOR_PARTS)}, got {part!r}")
    prefix = f"qlsim_{model.name}_"
    by_name = {f.name(): f for f in model.functions()}
    driver, names = SIMULATOR_PARTS[part]
    if driver == "sampled" and model.event is not None:
        names = (*names, "event")
    if model.envelope is None:
        names = tuple(n for n in names if n != "envelope")
    files, fns = {}, []
    for name in names:
        f = by_name[name]
        args = f.sx_in()
        fn = ca.Function(prefix + name, args, f.call(args), f.name_in(), f.name_out())
        fns.append(fn)
        cg = ca.CodeGenerator(f"{prefix}{name}.c", {
            "with_header": True, "with_export": False, "prefix": f"{prefix}{name}_",
            "verbose": False})
        cg.add(fn)
        with tempfile.TemporaryDirectory() as tmp:
            cg.generate(tmp + os.sep)
            for ext in ("c", "h"):
                files[f"{prefix}{name}.{ext}"] = Path(tmp, f"{prefix}{name}.{ext}").read_text()
    sizes = dict(NX=model.state.size, NW=model.disturbance.size, NP=model.params.size,
                 NY=model.outputs.size, NXP=model.plant_state.size, NUH=model.held.size,
                 NXC=model.controller_state.size, NPP=model.plant_params.size,
                 NPC=model.controller_params.size, NREC=model.recorded.size,
                 NENV=model.envelope_layout.size if model.envelope is not None else 0)
    headers = [n for n in names if n != "step_args"] + (
        ["controller"] if part == "sampled_flight" else [])
    files["quadland_loop.h"] = loop_header()
    files[f"{prefix}{part}.c"] = _TEMPLATES.get_template("simulator.c.jinja").render(
        prefix=prefix, model=model.name, part=driver, name=part, functions=headers,
        has_event=driver == "sampled" and model.event is not None,
        has_envelope=model.envelope is not None,
        casadi_version=ca.__version__, sizes=sizes,
        sz_arg=max(f.sz_arg() for f in fns), sz_res=max(f.sz_res() for f in fns),
        sz_iw=max(f.sz_iw() for f in fns), sz_w=max(f.sz_w() for f in fns))
    if part == "sampled_flight":
        if model.flight is None:
            raise ValueError(f"the loop {model.name!r} has no flight code")
        args = by_name["step_args"]
        offsets = {lay.name: lay.offsets() for lay in (model.controller_state, model.recorded)}
        nested = {f.name: {g.name: a for g, (a, _) in zip(
            f.layout.fields, f.layout.offsets().values(), strict=True)}
            for f in model.controller_state.fields if f.layout is not None}
        files[f"{prefix}controller.h"] = (
            f"/* {prefix}controller: the flight step behind the controller's signature. */\n"
            f"#include \"{prefix}step_args.h\"\n"
            f"int {prefix}controller(const casadi_real** arg, casadi_real** res, "
            "casadi_int* iw, casadi_real* w, int mem);\n")
        files[f"{prefix}controller.c"] = _TEMPLATES.get_template(model.flight).render(
            prefix=prefix, model=model.name, casadi_version=ca.__version__,
            args=[(n, args.nnz_out(i)) for i, n in enumerate(args.name_out())],
            sz_iw=args.sz_iw(), sz_w=args.sz_w(),
            xc=[(f.name, offsets[model.controller_state.name][f.name][0])
                for f in model.controller_state.fields],
            rec=[(f.name, offsets[model.recorded.name][f.name][0])
                 for f in model.recorded.fields],
            nested=nested)
    return files

"""The paper's 4-DOF loop as the simulators see it (continuous and sampled-data).

:func:`paper_loop` bundles the closed loop of :mod:`quadland_symbolic.closed_loop`
(the continuous loop: ``rhs`` and ``outputs``) and its sampled-data form
(the plant under a held wrench, the control step of
:mod:`quadland_symbolic.control_step` as the controller) in the shape of
:class:`quadland_symbolic.loop.LoopModel`, with the layouts of the sampled loop's
memory, parameters and recorded signals.
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from quadland_symbolic.backstepping import PAPER_REFERENCE
from quadland_symbolic.closed_loop import (
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
from quadland_symbolic.control_step import control_step_function, step_inputs, step_outputs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.loop_recipe import LoopRecipe
from quadland_symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, WRENCH

__all__ = ["PAPER_RECORDED", "paper_controller_state", "PAPER_PLANT_PARAMS",
           "paper_controller_params", "paper_loop", "paper_loop_recipe"]

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
    """The paper's 4-DOF loop (``quadland_symbolic.closed_loop``) for ``l`` RBF nodes."""
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


@functools.cache
def paper_loop_recipe(l: int) -> LoopRecipe:
    """:func:`paper_loop` for ``l`` nodes, built when a function is first asked for: its
    layouts, name and absent functions given here (a test checks them against the
    built model's)."""
    layouts = dict(state=closed_loop_state(l), disturbance=BODY_DISTURBANCE,
                   params=closed_loop_params(l), outputs=PAPER_OUTPUTS,
                   plant_state=PAPER_PLANT_STATE, held=WRENCH,
                   controller_state=paper_controller_state(l), plant_params=PAPER_PLANT_PARAMS,
                   controller_params=paper_controller_params(l), recorded=PAPER_RECORDED,
                   envelope_layout=PAPER_ENVELOPE, tick_inputs=None)
    absent = frozenset(("event", "ride_rhs", "ride_row", "free_plant", "controller_stages"))
    return LoopRecipe(paper_loop, (l,), "paper", layouts, absent,
                      dict(flight="flight_controller.c.jinja", event_continues=False))

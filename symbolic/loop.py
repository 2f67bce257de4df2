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
  touchdown), located within the step; or, for a model whose event
  *continues* (:attr:`LoopModel.event_continues`), is located the same way,
  its instant and state recorded, and the integration goes on from that
  state, in steps no longer than a bound the run gives (a stiffer phase,
  the gear on the deck), to a given time after it;

optionally, the per-tick inputs ``n`` of the controller (:attr:`LoopModel.tick_inputs`:
one row of a table per control tick, drawn before the run, such as the sensors'
noise and sample flags): the controller is then ``controller(xp, xc, pc, first,
t, uh, w, pp, n)``, also given the held input and disturbance in force and the
plant's parameters (the world a sensor measures), ``n`` the row of this tick;

optionally, after the event, a *ride*: a reduced state ``z`` that goes on by
``ride_rhs(z, t, pp) -> z_dot`` (the ride's constants ``a``, formed once at
the event, are not needed there) and gives each row by ``ride_row(z, a, t, pp)
-> (x, y, rec)``: the loop's state, its output signals and its recorded
signals, at the output times after the event up to its end (a landed
quadrotor riding on the deck);

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

import casadi as ca

from quadland_symbolic.layout import Layout
from quadland_symbolic.stages import Staged

__all__ = ["MAX_DELAY_PERIODS", "RIDE_TOL", "rk4_step", "LoopModel"]

#: The longest computation delay a simulator holds, in control periods: the
#: sampled drivers keep the commands computed but not yet applied in a queue of
#: this length (``delay`` of the compiled and the VM simulators).
MAX_DELAY_PERIODS = 16

#: s: an output tick this close to an event, or to the ride's end, is that
#: instant's row; a ride's phase changes this close to its threshold.
RIDE_TOL = 1e-12


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
        step's, ``quadland_symbolic.control_step.step_inputs``). The flight code behind
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
    ride_rhs, ride_row : casadi.Function or None
        The ride after the event (see the module docstring): both or neither.
    tick_inputs : Layout or None
        The layout of ``n``, the controller's per-tick row (see the module
        docstring); None: ``controller(xp, xc, pc, first, t)``.
    event_continues : bool
        The event does not end the run: its first crossing is located and
        recorded, and the integration goes on (see the module docstring).
    controller_stages : quadland_symbolic.stages.Staged or None
        The stages ``controller`` is composed of (its ``function()``), for a
        controller that is an MX Function of SX stages and branching ones; None:
        ``controller`` is one Function.
    free_plant : casadi.Function or None
        ``free_plant(xp, uh, w, t, pp) -> xp_dot``: the plant without what
        happens only near the event (the gear's contact, exactly zero while
        ``g`` is large), for a model whose event continues: the sampled
        driver integrates it over a grid interval whose ``g`` is above a
        switch gap the run gives (``near``) at both ends, ``plant`` otherwise
        and from the first crossing on.
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
    ride_rhs: ca.Function | None = None
    ride_row: ca.Function | None = None
    tick_inputs: Layout | None = None
    event_continues: bool = False
    free_plant: ca.Function | None = None
    controller_stages: Staged | None = None

    def functions(self) -> tuple[ca.Function, ...]:
        """Every function a simulator calls, named ``rhs``, ``outputs``, ... ."""
        return tuple(f for f in (self.rhs, self.output_fn, self.plant, self.controller,
                                 self.assemble, self.step_args, self.event, self.envelope,
                                 self.ride_rhs, self.ride_row, self.free_plant)
                     if f is not None)



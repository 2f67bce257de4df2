"""A scenario's loop as a python-control nonlinear system (:func:`nlsys`).

quadland's loops are CasADi functions (``quadland_symbolic.loop.LoopModel``).
:func:`nlsys` wraps them, with the scenario's numbers, in a
``control.NonlinearIOSystem`` whose states, inputs and outputs carry the
layouts' names, so that python-control's own tools apply:
``control.input_output_response``, ``control.find_eqpt``,
``control.linearize``. It calls the symbolic functions on CasADi's virtual
machine, a few microseconds each: for exploring and cross-checking, not for
campaigns (``quadland.simulate`` flies the compiled loop).

**A landing's closed loop** is the loop ``quadland.simulate`` flies with
``sensors.enabled = false``, one control period per step, discrete time with
``dt`` the period (:class:`quadland.engine.period.SampledPeriod`). Its state
is the plant's (quadrotor, vehicle, gear), the controller's memory (guidance,
network, robust terms, command filter, compensator, bias estimates) and the
``controller.delay_periods`` rotor commands computed but not applied yet
(``F_1_cmd_delay1``, ...). The update is the guidance and landing step at
``t_k`` (CasADi's functions on the virtual machine, whatever
``controller.backend`` says), then the plant by the simulator's RK4 steps on
its grid under the oldest command held. The outputs at ``t_k`` are the row
the simulator records there: the landing's signals of the plant's state and
the memory after the step, then the step's commands, references and limit
flags. What it holds fixed:

* the sensors are perfect: the controller reads the true state at once (the
  loop ``quadland margins`` linearizes); a scenario's ``[sensors]`` and
  ``[estimator]`` are not used, and :func:`nlsys` warns when the scenario
  flies on them;
* the input ``w`` is held over each control period (the simulator holds it
  from each ``disturbance.sample_rate_hz`` sample): the two agree for a
  constant disturbance;
* the envelope and the singular-attitude guard are not checked, and the
  first contact is neither located nor followed by the gear's shorter steps:
  the system follows the flight up to the first contact only.

``timepts`` should be control instants (``k dt``): a period's grid is the
simulator's from them.
"""

from __future__ import annotations

import os
import warnings

import control
import numpy as np

from quadland.engine.period import SampledPeriod
from quadland.exceptions import ScenarioError
from quadland.kinds import kind_of
from quadland.scenario import Scenario, load_scenario

__all__ = ["nlsys", "SYSTEMS"]

#: What :func:`nlsys` can give: the continuous closed loop, or the open-loop plant.
SYSTEMS = ("closed_loop", "plant")


def _vector(value) -> np.ndarray:
    return np.asarray(value, dtype=float).ravel()


def nlsys(scenario: Scenario | str | os.PathLike,
          which: str = "closed_loop") -> control.NonlinearIOSystem:
    """The scenario's closed loop or plant as a ``control.NonlinearIOSystem``.

    Parameters
    ----------
    scenario : Scenario, str or path
        A scenario, or what :func:`quadland.load_scenario` loads.
    which : {"closed_loop", "plant"}
        ``"closed_loop"``: the continuous-time closed loop of the paper's
        model, ``x_dot = f(x, w, t)``: its inputs are the disturbance ``w``
        (its layout's names: ``d_Fz``, ...), its outputs the loop's signals
        (``z_e``, ``u_1``, ...), its states the loop's state (the plant's,
        then the network's weights). A landing's: the discrete-time sampled
        loop, ``x[k+1] = f(t_k, x[k], w[k])`` with ``dt`` the control period
        (see Notes). ``"plant"``: the open-loop plant,
        ``xp_dot = f(xp, u, w, t)``: its inputs are the held command ``u``
        (the paper's wrench ``F_total, M_x, ...``, a landing's rotor
        commands ``F_cmd_1, ...``) then ``w``; its outputs are its states.

    Returns
    -------
    control.NonlinearIOSystem
        Continuous time, but a landing's closed loop; ``params`` is unused
        (the scenario's numbers are bound in). ``sys.x0`` (an attribute
        added here) is the scenario's initial state.

    Raises
    ------
    ScenarioError
        ``which`` is not one of :data:`SYSTEMS`.

    Warns
    -----
    UserWarning
        A landing's closed loop for a scenario that flies on its sensors
        (``sensors.enabled = true``): the system reads the true state.

    Notes
    -----
    A landing's closed loop, and what it holds fixed: see the module
    docstring.

    Examples
    --------
    >>> import control, quadland
    >>> sys = quadland.nlsys("paper")
    >>> sys.ninputs, sys.input_labels[:2]
    (6, ['d_Fx', 'd_Fy'])
    """
    if which not in SYSTEMS:
        raise ScenarioError(f"which: must be one of {', '.join(SYSTEMS)}, got {which!r}")
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    kind = kind_of(scenario)
    loop = kind.loop_model(scenario["rbf.nodes"])
    values = kind.io_values(scenario)
    if which == "closed_loop" and loop.rhs is None:
        if values.get("sampled") is None:
            raise ScenarioError(f"{scenario.name}: the {kind.name} loop is sampled-data, with "
                                "no closed loop for nlsys; nlsys(scenario, 'plant') gives its "
                                "plant, quadland.simulate flies the loop")
        return _sampled_closed_loop(scenario, loop, values)
    if which == "closed_loop":
        return _continuous_closed_loop(scenario, loop, values)
    return _plant(scenario, loop, values)


def _continuous_closed_loop(scenario: Scenario, loop, values) -> control.NonlinearIOSystem:
    rhs, out, p = loop.rhs, loop.output_fn, values["p"]

    def update(t, x, u, params):
        return _vector(rhs(x, u, t, p))

    def output(t, x, u, params):
        return _vector(out(x, u, t, p))

    sys = control.nlsys(update, output, inputs=list(loop.disturbance.element_names()),
                        outputs=list(loop.outputs.element_names()),
                        states=list(loop.state.element_names()),
                        name=f"{scenario.name}_closed_loop")
    sys.x0 = _vector(values["x0"])
    return sys


def _plant(scenario: Scenario, loop, values) -> control.NonlinearIOSystem:
    plant, pp, n_u = loop.plant, values["pp"], loop.held.size

    def plant_update(t, x, u, params):
        return _vector(plant(x, u[:n_u], u[n_u:], t, pp))

    states = list(loop.plant_state.element_names())
    sys = control.nlsys(plant_update, None,
                        inputs=[*loop.held.element_names(), *loop.disturbance.element_names()],
                        outputs=states, states=states, name=f"{scenario.name}_plant")
    sys.x0 = _vector(values["xp0"])
    return sys


def _sampled_closed_loop(scenario: Scenario, loop, values) -> control.NonlinearIOSystem:
    """A sampled-data loop, one control period per step (see the module docstring)."""
    v = values["sampled"]
    if v["sensed"]:
        warnings.warn(f"nlsys: {scenario.name} flies on its sensors (sensors.enabled = true); "
                      "its closed loop here reads the true state (perfect sensors, the loop "
                      "quadland margins linearizes)", UserWarning, stacklevel=3)
    period = SampledPeriod(loop, _vector(v["pc"]), _vector(values["pp"]), float(v["dt"]),
                           int(v["delay"]), int(v["substeps"]),
                           tuple(float(r) for r in v["break_rates"]))

    def update(t, x, u, params):
        return period.update(t, x, u)

    def output(t, x, u, params):
        return period.output(t, x, u)

    sys = control.nlsys(update, output, inputs=list(loop.disturbance.element_names()),
                        outputs=period.output_names(), states=period.state_names(),
                        dt=period.dt, name=f"{scenario.name}_closed_loop")
    sys.x0 = period.initial_state(values["xp0"], v["xc0"], v["uh0"])
    return sys

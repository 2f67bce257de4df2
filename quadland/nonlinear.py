"""A scenario's loop as a python-control nonlinear system (:func:`nlsys`).

quadland's loops are CasADi functions (``quadland_symbolic.loop.LoopModel``).
:func:`nlsys` wraps them, with the scenario's numbers, in a
``control.NonlinearIOSystem`` whose states, inputs and outputs carry the
layouts' names, so that python-control's own tools apply:
``control.input_output_response``, ``control.find_eqpt``,
``control.linearize``. It calls the symbolic functions on CasADi's virtual
machine, a few microseconds each: for exploring and cross-checking, not for
campaigns (``quadland.simulate`` flies the compiled loop).
"""

from __future__ import annotations

import os

import control
import numpy as np

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
        then the network's weights). ``"plant"``: the open-loop plant,
        ``xp_dot = f(xp, u, w, t)``: its inputs are the held command ``u``
        (the paper's wrench ``F_total, M_x, ...``, a landing's rotor
        commands ``F_cmd_1, ...``) then ``w``; its outputs are its states.

    Returns
    -------
    control.NonlinearIOSystem
        Continuous time; ``params`` is unused (the scenario's numbers are
        bound in). ``sys.x0`` (an attribute added here) is the scenario's
        initial state.

    Raises
    ------
    ScenarioError
        ``which`` is not one of :data:`SYSTEMS`, or the loop has no
        continuous closed loop (a landing's controller is sampled-data: its
        plant is available, ``quadland.simulate`` flies the loop).

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
    w_names = list(loop.disturbance.element_names())
    if which == "closed_loop":
        if loop.rhs is None:
            raise ScenarioError(f"{scenario.name}: the {kind.name} loop is sampled-data, with "
                                "no continuous closed loop; nlsys(scenario, 'plant') gives its "
                                "plant, quadland.simulate flies the loop")
        rhs, out, p = loop.rhs, loop.output_fn, values["p"]

        def update(t, x, u, params):
            return _vector(rhs(x, u, t, p))

        def output(t, x, u, params):
            return _vector(out(x, u, t, p))

        sys = control.nlsys(update, output, inputs=w_names,
                            outputs=list(loop.outputs.element_names()),
                            states=list(loop.state.element_names()),
                            name=f"{scenario.name}_closed_loop")
        sys.x0 = _vector(values["x0"])
        return sys
    plant, pp, n_u = loop.plant, values["pp"], loop.held.size

    def plant_update(t, x, u, params):
        return _vector(plant(x, u[:n_u], u[n_u:], t, pp))

    states = list(loop.plant_state.element_names())
    sys = control.nlsys(plant_update, None, inputs=[*loop.held.element_names(), *w_names],
                        outputs=states, states=states, name=f"{scenario.name}_plant")
    sys.x0 = _vector(values["xp0"])
    return sys

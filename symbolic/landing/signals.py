"""The landing's signals: both bodies, the relative state, rotors and external forces.

:data:`LANDING_SIGNALS` is the vector the simulator records at every output
row of a landing (its ``y``), :data:`LANDING_TRAJECTORY` the columns of its
``trajectory.csv``; :func:`landing_signals` forms the vector from a
quadrotor state, the vehicle's and the external forces (in flight, from the
plant and its disturbance: :func:`landing_signals_function`; on the deck,
from the contact model: :mod:`quadland_symbolic.landing.contact`).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.landing.deck import DECK_POSE, deck_pose
from quadland_symbolic.landing.gear import gear_terms
from quadland_symbolic.landing.guidance import GUIDANCE_STATE
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    body_disturbance,
)
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.relative import (
    RELATIVE6,
    TOUCHDOWN_FIGURES,
    relative6,
    touchdown_figures,
)
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, wrench_from_rotors

__all__ = ["LANDING_SIGNALS", "LANDING_TRAJECTORY", "landing_signals",
           "landing_signals_function"]


#: The landing trajectory's signals (one vector, the simulator's ``y``).
LANDING_SIGNALS = Layout("y_land", (
    Field("phase", 1, "-", "guidance phase (quadland_symbolic.landing.guidance.PHASES)"),
    QUAD6_STATE["p1"],
    QUAD6_STATE["eta1"],
    DECK_POSE["p2"],
    DECK_POSE["eta2"],
    *RELATIVE6.fields,
    TOUCHDOWN_FIGURES["tilt_deg"],
    Field("F_total", 1, "N", "thrust acting (the rotor states, after motor lag and limits)"),
    Field("M", 3, "N m", "body moments of the rotor states", elements=("M_x", "M_y", "M_z")),
    QUAD6_STATE["F"],
    Field("d_F", 3, "N", "every external force but thrust, gravity and eq. 2's drag "
          "(wind, disturbance, contact), body frame", elements=("d_Fx", "d_Fy", "d_Fz")),
    Field("d_M", 3, "N m", "every external moment but the rotors' and eq. 2's drag, body "
          "frame", elements=("d_Mx", "d_My", "d_Mz")),
    Field("aborts", 1, "-", "aborted descents so far"),
), "landing signals: both bodies in E, the relative state, rotors, external forces")


#: The columns of a landing's trajectory.csv (``quadland simulate`` and the
#: generated C example ``land``): the time, then these :data:`LANDING_SIGNALS`.
LANDING_TRAJECTORY = Layout("landing_trajectory", (
    Field("t", 1, "s", "time"),
    *(LANDING_SIGNALS[n] for n in ("phase", "p1", "eta1", "p2", "eta2", "p_e", "F_total", "M", "F",
                           "d_F")),
), "one row per output time of a landing, and one at touchdown")


def landing_signals(x1q, xv, t, pp, d_F, d_M, phase, aborts):
    """The :data:`LANDING_SIGNALS` vector of a quadrotor state with its external forces."""
    p = LANDING_PLANT_PARAMS.unpack(pp)
    q = QUAD6_STATE.unpack(x1q)
    deck = deck_pose(xv, t, p["p_veh"], p["p_deck"])
    rel = relative6(x1q, xv, t, p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])
    tilt = touchdown_figures(rel[0], rel[1], q["eta1"], deck.eta2)[3]
    return ca.vertcat(phase, q["p1"], q["eta1"], deck.p2, deck.eta2, *rel, tilt,
                      wrench_from_rotors(q["F"], p["p_quad"]), q["F"], d_F, d_M, aborts)


@functools.cache
def landing_signals_function() -> ca.Function:
    """``landing_signals(xp, xg, w, t, pp) -> y``: :data:`LANDING_SIGNALS` in flight.

    The plant's state ``xp``, the guidance's state ``xg`` (its phase and
    abort count) and the disturbance ``w`` (:data:`LANDING_DISTURBANCE`); ``d_F``,
    ``d_M`` add the gear's contact and the lock-down's pull
    (:func:`quadland_symbolic.landing.gear.gear_terms`) to the wind and the disturbance.
    """
    xp, xg, w = LANDING_PLANT_STATE.sym(), GUIDANCE_STATE.sym(), LANDING_DISTURBANCE.sym()
    t, pp = ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    ps, gs = LANDING_PLANT_STATE.unpack(xp), GUIDANCE_STATE.unpack(xg)
    d = BODY_DISTURBANCE.unpack(body_disturbance(xp, w, pp, t))
    p = LANDING_PLANT_PARAMS.unpack(pp)
    F_c, M_c, _, _ = gear_terms(ps["x1q"], ps["xv"], ps["gear"], ca.SX.zeros(4), t, p["p_quad"],
                                p["p_veh"], p["p_deck"], p["p_gear"], p["p_lock"], p["p_td"])
    y = landing_signals(ps["x1q"], ps["xv"], t, pp, d["d_F"] + F_c, d["d_M"] + M_c,
                        gs["phase"], gs["aborts"])
    return ca.Function("landing_signals", [xp, xg, w, t, pp], [y],
                       ["xp", "xg", "w", "t", "pp"], ["y"])

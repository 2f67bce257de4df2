"""Closed loop: quadrotor + vehicle + controller + adaptive states as one ODE.

State ``x`` (:func:`closed_loop_state`): the quadrotor ``xq``, the vehicle
``xv``, ``vec(W_hat)`` (column-major), ``zeta_hat`` and the quadrotor's
planar position ``pos1 = [x1, y1]``, integrated from ``R(eta1) V1`` for the
ground track only (the 4-DOF model ignores it). Input ``w``
(``quadland_symbolic.quadrotor.BODY_DISTURBANCE``), the disturbance, held piecewise
constant by the simulator. Parameter ``p`` (:func:`closed_loop_params`):
``[p_quad, p_veh, p_ctrl, ref]``. The controller and the plant share one set
of physical parameters. :func:`closed_loop_outputs` gives the signals of
:data:`PAPER_OUTPUTS`.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.backstepping import ADAPTIVE_UNITS, PAPER_REFERENCE, control_law
from quadland_symbolic.kinematics import rotation, tilt_angle
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE, ROTORS, WRENCH, quadrotor_rhs
from quadland_symbolic.relative import (
    E1,
    E2,
    VIRTUAL_INPUT,
    disturbance_input,
    nominal_drift,
    relative_drift,
)
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

__all__ = ["POSITION1", "PAPER_PLANT_STATE", "PAPER_OUTPUTS", "PAPER_ENVELOPE", "closed_loop_state",
           "closed_loop_params", "closed_loop_rhs", "closed_loop_function",
           "closed_loop_jacobian_function", "plant_function", "closed_loop_outputs",
           "vehicle_measurement", "paper_envelope_function"]

#: The quadrotor's planar position in E, integrated for the ground track.
POSITION1 = Layout("pos1", (Field("x1", 1, "m", "quadrotor x in E"),
                            Field("y1", 1, "m", "quadrotor y in E")))

#: State of the plant alone (sampled-data loops): the closed loop without the
#: adaptive states.
PAPER_PLANT_STATE = Layout("xp", (
    Field.nested("xq", QUAD_STATE, "quadrotor"),
    Field.nested("xv", VEHICLE_STATE, "vehicle"),
    Field.nested("pos1", POSITION1, "quadrotor planar position"),
), "plant state: quadrotor, vehicle, planar position")

#: Signals of :func:`closed_loop_outputs`, in order.
PAPER_OUTPUTS = Layout("y", (
    Field.nested("e1", E1, "relative position (eq. 7)"),
    Field.nested("e2", E2, "relative rates (eq. 7)"),
    Field.nested("u", VIRTUAL_INPUT, "virtual input (eq. 20)"),
    Field.nested("wrench", WRENCH, "thrust and moments"),
    Field.nested("rotor", ROTORS, "rotor forces"),
    Field("Delta", 4, ADAPTIVE_UNITS, "true uncertainty f + d (eq. 16)",
          elements=tuple(f"Delta_{i}" for i in range(1, 5))),
    Field("Delta_target", 4, ADAPTIVE_UNITS, "what the network is asked to learn",
          elements=tuple(f"Delta_target_{i}" for i in range(1, 5))),
    Field("Delta_hat", 4, ADAPTIVE_UNITS, "network estimate W_hat^T Psi (eq. 16)",
          elements=tuple(f"Delta_hat_{i}" for i in range(1, 5))),
    Field("bs_z1", 4, E1["e1"].unit, "backstepping error z1 = e1 - e1d (eq. 9)"),
    Field("bs_z2", 4, E2["e2"].unit, "backstepping error z2 = e2 - alpha (eq. 9)"),
    Field("lyapunov_V1", 1, "-", "Lyapunov function V1 = z1^T z1 / 2 (eq. 12)"),
), "closed-loop output signals")


#: The magnitudes a flight must keep within its envelope (``paper_envelope_function``):
#: each is compared with a bound the runtime derives from the scenario.
PAPER_ENVELOPE = Layout("env", (
    Field("altitude", 1, "m", "|z1|, the quadrotor's altitude"),
    Field("speed", 1, "m/s", "largest body velocity component |V1|"),
    Field("rate", 1, "rad/s", "largest body rate |Omega1|"),
    Field("thrust", 1, "N", "largest held thrust or moment command |wrench| (sampled loop)"),
    Field("weight", 1, "-", "largest network weight |W_hat| (eq. 22)"),
    Field("robust", 1, "-", "largest robust term estimate |zeta_hat| (eq. 22)"),
    Field("tilt", 1, "rad", "tilt of the thrust axis from the vertical, acos(cos phi cos theta)"),
    Field("vehicle_speed", 1, "m/s", "largest vehicle velocity component |u2|, |v2|"),
), "magnitudes checked against the flight envelope")


def _inf_norm(v):
    return ca.mmax(ca.fabs(v))


@functools.cache
def closed_loop_state(l: int) -> Layout:
    """Layout of the closed-loop state for ``l`` RBF nodes."""
    return Layout("x", (
        Field.nested("xq", QUAD_STATE, "quadrotor"),
        Field.nested("xv", VEHICLE_STATE, "vehicle"),
        Field("W_hat", 4 * l, tuple(u for u in ADAPTIVE_UNITS for _ in range(l)),
              "network weights (eq. 22), column-major", shape=(l, 4)),
        Field("zeta_hat", 4, ADAPTIVE_UNITS, "robust term estimate (eq. 22)"),
        Field.nested("pos1", POSITION1, "quadrotor planar position"),
    ), "closed-loop state")


@functools.cache
def closed_loop_params(l: int) -> Layout:
    """Layout of the closed loop's parameter vector for ``l`` RBF nodes."""
    return Layout("p", (
        Field.nested("p_quad", QUADROTOR, "quadrotor constants"),
        Field.nested("p_veh", VEHICLE, "vehicle constants and inputs"),
        Field.nested("p_ctrl", controller_layout(l), "controller"),
        Field.nested("ref", PAPER_REFERENCE, "reference"),
    ), "closed-loop parameters")


def vehicle_measurement(xv, p_veh):
    """What the controller measures of the vehicle, ``yv = [z2, psi2, r2]``."""
    v = VEHICLE_STATE.unpack(xv)
    return ca.vertcat(VEHICLE.unpack(p_veh)["z2"], v["psi2"], v["r2"])


def _planar_velocity(xq):
    q = QUAD_STATE.unpack(xq)
    return (rotation(q["eta1"]) @ q["V1"])[0:2]


def _symbols(l: int):
    return (closed_loop_state(l).sym(), BODY_DISTURBANCE.sym(), closed_loop_params(l).sym())


def _signals(x, w, p, l):
    xs, ps, ws = closed_loop_state(l).unpack(x), closed_loop_params(l).unpack(p), \
        BODY_DISTURBANCE.unpack(w)
    xq, xv = xs["xq"], xs["xv"]
    p_quad, p_veh, p_ctrl = ps["p_quad"], ps["p_veh"], ps["p_ctrl"]
    yv = vehicle_measurement(xv, p_veh)
    law = control_law(xq, yv, ps["ref"], xs["W_hat"], xs["zeta_hat"], p_quad, p_ctrl)
    return xq, xv, p_quad, p_veh, p_ctrl, ws["d_F"], ws["d_M"], law


def closed_loop_rhs(x, w, p, l: int):
    """Time derivative of the closed-loop state (eq. 1-4, 20, 22)."""
    xq, xv, p_quad, p_veh, _, d_F, d_M, law = _signals(x, w, p, l)
    return ca.vertcat(
        quadrotor_rhs(xq, law["wrench"], d_F, d_M, p_quad),
        vehicle_rhs(xv, p_veh),
        ca.vec(law["W_hat_dot"]),
        law["zeta_hat_dot"],
        _planar_velocity(xq),
    )


@functools.cache
def closed_loop_function(l: int) -> ca.Function:
    """``closed_loop(x, w, p) -> x_dot`` for ``l`` RBF nodes."""
    x, w, p = _symbols(l)
    return ca.Function("closed_loop", [x, w, p], [closed_loop_rhs(x, w, p, l)],
                       ["x", "w", "p"], ["x_dot"])


@functools.cache
def closed_loop_jacobian_function(l: int) -> ca.Function:
    """``closed_loop_jacobian(x, w, p) -> jac_x``: d x_dot / d x, sparse.

    The Jacobian of :func:`closed_loop_function` with respect to the state,
    formed by CasADi's algorithmic differentiation.
    """
    x, w, p = _symbols(l)
    return ca.Function("closed_loop_jacobian", [x, w, p],
                       [ca.jacobian(closed_loop_function(l)(x, w, p), x)],
                       ["x", "w", "p"], ["jac_x"])


@functools.cache
def closed_loop_outputs(l: int) -> ca.Function:
    """``closed_loop_outputs(x, w, p) -> (e1, e2, u, ...)``: the fields of :data:`PAPER_OUTPUTS`.

    ``Delta = f + d`` is the true uncertainty of eq. (16); ``Delta_target``
    is what the network is asked to learn: Delta itself for the printed law,
    Delta minus the fed-forward nominal drift with ``nominal_model = 1``.
    """
    x, w, p = _symbols(l)
    xq, xv, p_quad, p_veh, p_ctrl, d_F, d_M, law = _signals(x, w, p, l)
    Delta = relative_drift(xq, xv, p_quad, p_veh) + disturbance_input(xq, d_F, d_M, p_quad)
    nominal = controller_layout(l).unpack(p_ctrl)["nominal_model"]
    signals = dict(law)
    signals["Delta"] = Delta
    signals["Delta_target"] = Delta - nominal * nominal_drift(xq, p_quad)
    signals["lyapunov_V1"] = 0.5 * ca.dot(law["bs_z1"], law["bs_z1"])            # eq. 12
    names = list(PAPER_OUTPUTS.names())
    return ca.Function("closed_loop_outputs", [x, w, p], [signals[n] for n in names],
                       ["x", "w", "p"], names)


@functools.cache
def paper_envelope_function(l: int) -> ca.Function:
    """``envelope(x, uh) -> s``: the :data:`PAPER_ENVELOPE` magnitudes of a loop state.

    ``x`` is :func:`closed_loop_state`, ``uh`` the held wrench
    (:data:`~quadland_symbolic.quadrotor.WRENCH`; zero in the continuous loop).
    """
    x, uh = closed_loop_state(l).sym(), WRENCH.sym()
    xs = closed_loop_state(l).unpack(x)
    q = QUAD_STATE.unpack(xs["xq"])
    v = VEHICLE_STATE.unpack(xs["xv"])
    s = ca.vertcat(ca.fabs(q["z1"]), _inf_norm(q["V1"]), _inf_norm(q["Omega1"]),
                   _inf_norm(uh), _inf_norm(xs["W_hat"]), _inf_norm(xs["zeta_hat"]),
                   tilt_angle(q["eta1"]), _inf_norm(ca.vertcat(v["u2"], v["v2"])))
    return ca.Function("envelope", [x, uh], [s], ["x", "uh"], ["s"])



@functools.cache
def plant_function() -> ca.Function:
    """``plant(xp, wrench, w, p_quad, p_veh) -> xp_dot`` for sampled-data loops.

    ``xp`` (:data:`PAPER_PLANT_STATE`): the closed-loop state without the adaptive
    states, driven by a held wrench and disturbance ``w``.
    """
    xp, wrench, w = PAPER_PLANT_STATE.sym(), WRENCH.sym(), BODY_DISTURBANCE.sym()
    p_quad, p_veh = QUADROTOR.sym(), VEHICLE.sym()
    xs, ws = PAPER_PLANT_STATE.unpack(xp), BODY_DISTURBANCE.unpack(w)
    xq, xv = xs["xq"], xs["xv"]
    rhs = ca.vertcat(quadrotor_rhs(xq, wrench, ws["d_F"], ws["d_M"], p_quad),
                     vehicle_rhs(xv, p_veh), _planar_velocity(xq))
    return ca.Function("plant", [xp, wrench, w, p_quad, p_veh], [rhs],
                       ["xp", "wrench", "w", "p_quad", "p_veh"], ["xp_dot"])

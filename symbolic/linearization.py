"""Exact Jacobians of the loop broken at the virtual input u (eq. 1-2, 6, 20, 22).

The loop is written in relative yaw: the plant state is

    xr = [z1, phi1, theta1, psi_e, u1, v1, w1, p1, q1, r1]     (10)

with ``psi_e = psi1 - psi2``. The quadrotor's dynamics (eq. 1-2) do not
depend on psi1, and the law of eq. (20) sees yaw only through psi_e, so
evaluating both with ``psi1 = psi_e`` and ``psi2 = 0`` is exact; the only
change is ``psi_e_dot = psi1_dot - r2``. In these coordinates a vehicle in a
steady turn (r2 constant) leaves an equilibrium, while psi1 and psi2 both
grow. The vehicle is exogenous to the loop (u does not reach it): its
measured yaw rate r2 and deck altitude z2 enter as frozen parameters.
The planar positions x1, y1, x2, y2 are pure integrators that feed back
nowhere and are left out.

The controller state is ``xc = [vec(W_hat) (4 l, column-major), zeta_hat
(4)]``, its input the measured plant state ``y = xr`` and its output u.
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from quadland_symbolic.backstepping import ADAPTIVE_UNITS, PAPER_REFERENCE, control_law
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE, quadrotor_rhs
from quadland_symbolic.relative import VIRTUAL_INPUT, wrench_from_virtual
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

__all__ = ["RELATIVE_PLANT", "FROZEN_VEHICLE", "VEHICLE_SPEEDS", "controller_states",
           "relative_plant_rhs", "loop_signals", "linearization_function",
           "equilibrium_residual_function"]

#: The relative plant state xr (= the measurement y): the quadrotor's state with
#: the relative yaw psi_e = psi1 - psi2 in place of psi1.
RELATIVE_PLANT = Layout("xr", tuple(
    dataclasses.replace(f, elements=("phi1", "theta1", "psi_e")) if f.name == "eta1" else f
    for f in QUAD_STATE.fields), "relative plant state")

#: The vehicle as the frozen loop sees it.
FROZEN_VEHICLE = Layout("vehicle", (Field("z2", 1, "m", "deck altitude"),
                                    Field("r2", 1, "rad/s", "yaw rate")))

#: The vehicle's speeds, unknowns of its steady motion.
VEHICLE_SPEEDS = Layout("v2", tuple(f for f in VEHICLE_STATE.fields
                                    if f.name in ("u2", "v2", "r2")))


@functools.cache
def controller_states(l: int) -> Layout:
    """The controller's state xc: the adaptive states of eq. (22)."""
    return Layout("xc_lin", (
        Field("W_hat", 4 * l, "-", "network weights, column-major", shape=(l, 4)),
        Field("zeta_hat", 4, ADAPTIVE_UNITS, "robust term estimate"),
    ), "controller state")


def relative_plant_rhs(xr, u, w, r2, p_quad):
    """xr_dot for a virtual input u (eq. 1-2 composed with eq. 6).

    The plant takes the wrench ``wrench_from_virtual(xr, u)``; the yaw row
    is ``psi_e_dot = psi1_dot - r2``.
    """
    wrench = wrench_from_virtual(xr, u, p_quad)
    ws = BODY_DISTURBANCE.unpack(w)
    xq_dot = quadrotor_rhs(xr, wrench, ws["d_F"], ws["d_M"], p_quad)
    psi_dot = ca.DM.zeros(RELATIVE_PLANT.size)
    psi_dot[RELATIVE_PLANT.index("psi_e")] = 1
    return xq_dot - psi_dot * r2


def loop_signals(xr, xc, vehicle, p_quad, p_ctrl, ref, l: int):
    """Controller output u and adaptive rhs xc_dot (eq. 20, 22) at ``psi2 = 0``.

    ``vehicle = [z2, r2]``.
    """
    c, v = controller_states(l).unpack(xc), FROZEN_VEHICLE.unpack(vehicle)
    yv = ca.vertcat(v["z2"], 0, v["r2"])                  # MEASUREMENT at psi2 = 0
    law = control_law(xr, yv, ref, c["W_hat"], c["zeta_hat"], p_quad, p_ctrl)
    return law["u"], ca.vertcat(ca.vec(law["W_hat_dot"]), law["zeta_hat_dot"])


def _symbols(l: int):
    return (RELATIVE_PLANT.sym(), controller_states(l).sym(), FROZEN_VEHICLE.sym(),
            BODY_DISTURBANCE.sym(), QUADROTOR.sym(), controller_layout(l).sym(),
            PAPER_REFERENCE.sym())


@functools.cache
def linearization_function(l: int) -> ca.Function:
    """Plant and controller Jacobians at an operating point.

    ``linearization(xr, xc, vehicle, w, p_quad, p_ctrl, ref) -> (u, xr_dot,
    xc_dot, A_p, B_p, A_c, B_c, C_c, D_c)`` with, about the point,

        d xr_dot = A_p d xr + B_p d u          (plant, eq. 1-2, 6)
        d xc_dot = A_c d xc + B_c d y          (adaptive laws, eq. 22)
        d u      = C_c d xc + D_c d y          (control law, eq. 20)

    and ``y = xr``; ``vehicle = [z2, r2]``.

    Parameters
    ----------
    l : int
        Number of RBF nodes.
    """
    xr, xc, vehicle, w, p_quad, p_ctrl, ref = _symbols(l)
    u_in = VIRTUAL_INPUT.sym()
    u, xc_dot = loop_signals(xr, xc, vehicle, p_quad, p_ctrl, ref, l)
    xr_dot_in = relative_plant_rhs(xr, u_in, w, vehicle[1], p_quad)
    A_p, B_p = ca.jacobian(xr_dot_in, xr), ca.jacobian(xr_dot_in, u_in)
    xr_dot = ca.substitute(xr_dot_in, u_in, u)
    A_p, B_p = ca.substitute(A_p, u_in, u), ca.substitute(B_p, u_in, u)
    outs = [u, xr_dot, xc_dot, A_p, B_p, ca.jacobian(xc_dot, xc), ca.jacobian(xc_dot, xr),
            ca.jacobian(u, xc), ca.jacobian(u, xr)]
    names = ["u", "xr_dot", "xc_dot", "A_p", "B_p", "A_c", "B_c", "C_c", "D_c"]
    return ca.Function("linearization", [xr, xc, vehicle, w, p_quad, p_ctrl, ref], outs,
                       ["xr", "xc", "vehicle", "w", "p_quad", "p_ctrl", "ref"], names)


@functools.cache
def equilibrium_residual_function(l: int) -> ca.Function:
    """Residual and exact Jacobian of the closed loop's steady motion.

    ``equilibrium_residual(xi, w, p_quad, p_veh, p_ctrl, ref) -> (F, dF)``
    with unknowns ``xi = [xr (10), xc (4 l + 4), u2, v2, r2]`` and residual
    ``F = [xr_dot, xc_dot, (u2, v2, r2)_dot]`` (eq. 1-2, 4, 20, 22): the
    vehicle in its steady motion, the loop at rest in relative coordinates.
    """
    xr, xc, _, w, p_quad, p_ctrl, ref = _symbols(l)
    v2 = VEHICLE_SPEEDS.sym()
    speeds = VEHICLE_SPEEDS.unpack(v2)
    p_veh = VEHICLE.sym()
    z2 = VEHICLE.unpack(p_veh)["z2"]
    u, xc_dot = loop_signals(xr, xc, ca.vertcat(z2, speeds["r2"]), p_quad, p_ctrl, ref, l)
    xv = ca.vertcat(*[speeds[n] if n in speeds else 0 for n in VEHICLE_STATE.names()])
    xv_dot = VEHICLE_STATE.unpack(vehicle_rhs(xv, p_veh))
    F = ca.vertcat(relative_plant_rhs(xr, u, w, speeds["r2"], p_quad), xc_dot,
                   *[xv_dot[n] for n in VEHICLE_SPEEDS.names()])
    xi = ca.vertcat(xr, xc, v2)
    return ca.Function("equilibrium_residual", [xi, w, p_quad, p_veh, p_ctrl, ref],
                       [F, ca.jacobian(F, xi)],
                       ["xi", "w", "p_quad", "p_veh", "p_ctrl", "ref"], ["F", "dF"])

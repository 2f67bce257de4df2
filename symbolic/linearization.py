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

import functools

import casadi as ca

from symbolic.backstepping import control_law
from symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from symbolic.quadrotor import quadrotor_rhs
from symbolic.relative import wrench_from_virtual
from symbolic.vehicle import vehicle_rhs

__all__ = ["PLANT_STATES", "relative_plant_rhs", "loop_signals", "linearization_function",
           "equilibrium_residual_function"]

#: Names of the relative plant state xr (= the measurement y).
PLANT_STATES = ("z1", "phi1", "theta1", "psi_e", "u1", "v1", "w1", "p1", "q1", "r1")


def relative_plant_rhs(xr, u, w, r2, p_quad):
    """xr_dot for a virtual input u (eq. 1-2 composed with eq. 6).

    The plant takes the wrench ``wrench_from_virtual(xr, u)``; the yaw row
    is ``psi_e_dot = psi1_dot - r2``.
    """
    wrench = wrench_from_virtual(xr, u, p_quad)
    xq_dot = quadrotor_rhs(xr, wrench, w[0:3], w[3:6], p_quad)
    return xq_dot - ca.vertcat(0, 0, 0, r2, ca.DM.zeros(6))


def loop_signals(xr, xc, vehicle, p_quad, p_ctrl, ref, l: int):
    """Controller output u and adaptive rhs xc_dot (eq. 20, 22) at ``psi2 = 0``.

    ``vehicle = [z2, r2]``.
    """
    W_hat = ca.reshape(xc[0:4 * l], l, 4)
    zeta_hat = xc[4 * l:4 * l + 4]
    yv = ca.vertcat(vehicle[0], 0, vehicle[1])
    law = control_law(xr, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl)
    return law["u"], ca.vertcat(ca.vec(law["W_hat_dot"]), law["zeta_hat_dot"])


def _symbols(l: int):
    return (ca.SX.sym("xr", 10), ca.SX.sym("xc", 4 * l + 4), ca.SX.sym("vehicle", 2),
            ca.SX.sym("w", 6), QUADROTOR.sym(), controller_layout(l).sym(), ca.SX.sym("ref", 12))


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
    u_in = ca.SX.sym("u", 4)
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
    v2 = ca.SX.sym("v2", 3)
    p_veh = VEHICLE.sym()
    z2 = VEHICLE.unpack(p_veh)["z2"]
    u, xc_dot = loop_signals(xr, xc, ca.vertcat(z2, v2[2]), p_quad, p_ctrl, ref, l)
    xv = ca.vertcat(0, 0, 0, v2)
    F = ca.vertcat(relative_plant_rhs(xr, u, w, v2[2], p_quad), xc_dot,
                   vehicle_rhs(xv, p_veh)[3:6])
    xi = ca.vertcat(xr, xc, v2)
    return ca.Function("equilibrium_residual", [xi, w, p_quad, p_veh, p_ctrl, ref],
                       [F, ca.jacobian(F, xi)],
                       ["xi", "w", "p_quad", "p_veh", "p_ctrl", "ref"], ["F", "dF"])

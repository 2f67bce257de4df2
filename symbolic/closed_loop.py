"""Closed loop: quadrotor + vehicle + controller + adaptive states as one ODE.

State ``x = [xq (10), xv (6), vec(W_hat) (4 l, column-major), zeta_hat (4),
x1, y1]``; the last two are the quadrotor's planar position in E, integrated
from ``R(eta1) V1`` for the ground track only (the 4-DOF model ignores it);
input ``w = [d_F (3), d_M (3)]``, the disturbance, held piecewise constant by
the simulator; parameter ``p = [p_quad, p_veh, p_ctrl, ref (12)]``.
The controller and the plant share one set of physical parameters.
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from symbolic.backstepping import control_law
from symbolic.kinematics import rotation
from symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from symbolic.quadrotor import quadrotor_rhs
from symbolic.relative import disturbance_input, nominal_drift, relative_drift
from symbolic.vehicle import vehicle_rhs

__all__ = ["ClosedLoopLayout", "closed_loop_layout", "closed_loop_rhs", "closed_loop_function",
           "plant_function",
           "closed_loop_outputs", "OUTPUTS"]

#: Outputs of ``closed_loop_outputs`` (name, size).
OUTPUTS = (("e1", 4), ("e2", 4), ("u", 4), ("wrench", 4), ("rotor", 4), ("Delta", 4),
           ("Delta_target", 4), ("Delta_hat", 4), ("z1", 4), ("z2", 4), ("V1", 1))


@dataclasses.dataclass(frozen=True)
class ClosedLoopLayout:
    """Sizes and offsets of the closed-loop state and parameter vectors."""

    l: int

    @property
    def nx(self) -> int:
        return 10 + 6 + 4 * self.l + 4 + 2

    @property
    def nw(self) -> int:
        return 6

    @property
    def np(self) -> int:
        return QUADROTOR.size + VEHICLE.size + controller_layout(self.l).size + 12

    def split_state(self, x):
        """``(xq, xv, W_hat (l x 4), zeta_hat, pos1)`` from a state vector."""
        l = self.l
        W = x[16:16 + 4 * l]
        W = ca.reshape(W, l, 4) if isinstance(x, ca.SX | ca.MX | ca.DM) else W.reshape(
            (l, 4), order="F")
        return x[0:10], x[10:16], W, x[16 + 4 * l:20 + 4 * l], x[20 + 4 * l:22 + 4 * l]

    def split_params(self, p):
        """``(p_quad, p_veh, p_ctrl, ref)`` from a parameter vector."""
        a = QUADROTOR.size
        b = a + VEHICLE.size
        c = b + controller_layout(self.l).size
        return p[0:a], p[a:b], p[b:c], p[c:c + 12]


@functools.cache
def closed_loop_layout(l: int) -> ClosedLoopLayout:
    """Layout of the closed-loop vectors for ``l`` RBF nodes."""
    return ClosedLoopLayout(l)


def _symbols(l: int):
    lay = closed_loop_layout(l)
    return ca.SX.sym("x", lay.nx), ca.SX.sym("w", lay.nw), ca.SX.sym("p", lay.np)


def _signals(x, w, p, l):
    lay = closed_loop_layout(l)
    xq, xv, W_hat, zeta_hat, _ = lay.split_state(x)
    p_quad, p_veh, p_ctrl, ref = lay.split_params(p)
    d_F, d_M = w[0:3], w[3:6]
    yv = ca.vertcat(VEHICLE.unpack(p_veh)["z2"], xv[2], xv[5])
    law = control_law(xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl)
    return xq, xv, p_quad, p_veh, p_ctrl, d_F, d_M, law


def closed_loop_rhs(x, w, p, l: int):
    """Time derivative of the closed-loop state (eq. 1-4, 20, 22)."""
    xq, xv, p_quad, p_veh, _, d_F, d_M, law = _signals(x, w, p, l)
    return ca.vertcat(
        quadrotor_rhs(xq, law["wrench"], d_F, d_M, p_quad),
        vehicle_rhs(xv, p_veh),
        ca.vec(law["W_hat_dot"]),
        law["zeta_hat_dot"],
        (rotation(xq[1:4]) @ xq[4:7])[0:2],
    )


@functools.cache
def closed_loop_function(l: int) -> ca.Function:
    """``closed_loop(x, w, p) -> x_dot`` for ``l`` RBF nodes."""
    x, w, p = _symbols(l)
    return ca.Function("closed_loop", [x, w, p], [closed_loop_rhs(x, w, p, l)],
                       ["x", "w", "p"], ["x_dot"])


@functools.cache
def closed_loop_outputs(l: int) -> ca.Function:
    """``closed_loop_outputs(x, w, p) -> (e1, e2, u, ...)``: the signals of ``OUTPUTS``.

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
    signals["V1"] = 0.5 * ca.dot(law["z1"], law["z1"])                          # eq. 12
    names = [n for n, _ in OUTPUTS]
    return ca.Function("closed_loop_outputs", [x, w, p], [signals[n] for n in names],
                       ["x", "w", "p"], names)


@functools.cache
def plant_function() -> ca.Function:
    """``plant(xp, wrench, w, p_quad, p_veh) -> xp_dot`` for sampled-data loops.

    ``xp = [xq (10), xv (6), x1, y1]``: the closed-loop state without the
    adaptive states, driven by a held wrench and disturbance ``w``.
    """
    xp, wrench, w = ca.SX.sym("xp", 18), ca.SX.sym("wrench", 4), ca.SX.sym("w", 6)
    p_quad, p_veh = QUADROTOR.sym(), VEHICLE.sym()
    xq, xv = xp[0:10], xp[10:16]
    rhs = ca.vertcat(quadrotor_rhs(xq, wrench, w[0:3], w[3:6], p_quad), vehicle_rhs(xv, p_veh),
                     (rotation(xq[1:4]) @ xq[4:7])[0:2])
    return ca.Function("plant", [xp, wrench, w, p_quad, p_veh], [rhs],
                       ["xp", "wrench", "w", "p_quad", "p_veh"], ["xp_dot"])

"""Adaptive RBFNN backstepping law (eq. 9-22) and its Lyapunov function (eq. 25).

Naming follows the paper inside the expressions: ``z1 = e1 - e1d`` and
``z2 = e2 - alpha`` are the backstepping errors of eq. (9), ``W_hat``
(l x 4) and ``zeta_hat`` (4) the adaptive states. Where they leave this
module (function outputs, CSV columns) the errors are named ``bs_z1`` and
``bs_z2`` and the Lyapunov functions ``lyapunov_V1``, ``lyapunov_V2``, so
that they cannot be mistaken for the altitude z1 or the body velocity V1.
The reference is ``ref = [e1d, e1d_dot, e1d_ddot]`` (:data:`PAPER_REFERENCE`).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kinematics import euler_rate_matrix_inv
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, controller_layout
from quadland_symbolic.quadrotor import QUAD_STATE, ROTORS, WRENCH, rotors_from_wrench
from quadland_symbolic.rbf import rbf, rbf_input
from quadland_symbolic.relative import (
    E1,
    E2,
    VIRTUAL_INPUT,
    error_rate_matrix,
    nominal_drift,
    relative_states,
    wrench_from_virtual,
)
from quadland_symbolic.vehicle import VEHICLE_MEASUREMENT

__all__ = ["PAPER_REFERENCE", "ADAPTIVE_UNITS", "controller_outputs", "virtual_control",
           "control_law", "controller_function", "lyapunov_function"]

_E1_UNITS = E1["e1"].unit
#: Units of the network's outputs, one per channel (those of Delta = f + d, eq. 16).
ADAPTIVE_UNITS = VIRTUAL_INPUT["u"].unit

#: The reference of the relative position e1 and its derivatives (eq. 9, 14, 18).
PAPER_REFERENCE = Layout("ref", (
    Field("e1d", 4, _E1_UNITS, "desired e1 = [z_e, phi_e, theta_e, psi_e]"),
    Field("e1d_dot", 4, tuple(f"{u}/s" for u in _E1_UNITS), "its first time derivative"),
    Field("e1d_ddot", 4, tuple(f"{u}/s^2" for u in _E1_UNITS), "its second time derivative"),
), "reference of the relative states")


@functools.cache
def controller_outputs(l: int) -> Layout:
    """Outputs of :func:`control_law` and :func:`controller_function`, in order."""
    return Layout("controller", (
        Field.nested("u", VIRTUAL_INPUT, "virtual input of eq. (20)"),
        Field.nested("wrench", WRENCH, "wrench that realises u"),
        Field.nested("rotor", ROTORS, "rotor forces of the wrench"),
        Field("W_hat_dot", 4 * l, "-", "W_hat rate (eq. 22)", shape=(l, 4)),
        Field("zeta_hat_dot", 4, ADAPTIVE_UNITS, "zeta_hat rate (eq. 22)"),
        Field.nested("e1", E1, "relative position (eq. 7)"),
        Field.nested("e2", E2, "relative rates (eq. 7)"),
        Field("bs_z1", 4, _E1_UNITS, "backstepping error z1 = e1 - e1d (eq. 9)"),
        Field("bs_z2", 4, E2["e2"].unit, "backstepping error z2 = e2 - alpha (eq. 9)"),
        Field("alpha", 4, E2["e2"].unit, "virtual control (eq. 14)"),
        Field("alpha_dot", 4, ADAPTIVE_UNITS, "its time derivative (eq. 18)"),
        Field("Psi", l, "-", "RBF basis vector (eq. 16)"),
        Field("Delta_hat", 4, ADAPTIVE_UNITS, "network estimate W_hat^T Psi (eq. 16)"),
    ), "signals of the continuous-time control law")


def virtual_control(e1, e1_dot, ref, k1):
    """alpha (eq. 14) and its exact time derivative alpha_dot (eq. 18).

    ``alpha = R^-1 (-k1 z1 + e1d_dot)`` depends on the relative attitude
    through R (phi1 = phi_e and theta1 = theta_e since the vehicle neither
    rolls nor pitches). alpha_dot is the directional derivative of alpha
    along ``(e1_dot, e1d_dot, e1d_ddot)``, formed by symbolic
    differentiation; ``e1_dot = R e2`` is measured, so no unknown dynamics
    enter the law.

    Returns
    -------
    alpha, alpha_dot : casadi.SX, (4, 1)
    """
    e1s, refs, k1s = E1.sym(), PAPER_REFERENCE.sym(), ca.SX.sym("k1", 4)
    e1_dots = ca.SX.sym("e1_dot", 4)
    r = PAPER_REFERENCE.unpack(refs)
    e1d, e1d_dot, e1d_ddot = r["e1d"], r["e1d_dot"], r["e1d_ddot"]
    z1 = e1s - e1d                                                   # eq. 9
    R_inv = ca.diagcat(1, euler_rate_matrix_inv(ca.vertcat(e1s[1], e1s[2], 0)))
    alpha = R_inv @ (-k1s * z1 + e1d_dot)                            # eq. 14
    alpha_dot = ca.jtimes(alpha, ca.vertcat(e1s, e1d, e1d_dot),      # eq. 18
                          ca.vertcat(e1_dots, e1d_dot, e1d_ddot))
    fn = ca.Function("virtual_control", [e1s, e1_dots, refs, k1s], [alpha, alpha_dot])
    return fn(e1, e1_dot, ref, k1)


def control_law(xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl):
    """The backstepping control and adaptive laws as expressions.

    Returns a dict with ``u`` (eq. 20), ``W_hat_dot`` and ``zeta_hat_dot``
    (eq. 22), the physical ``wrench`` and ``rotor`` forces, and the
    intermediate signals ``e1, e2, bs_z1, bs_z2, alpha, alpha_dot, Psi,
    Delta_hat`` (the fields of :func:`controller_outputs`). With
    ``nominal_model = 1`` the quadrotor's own known drift (gravity, drag,
    gyroscopic terms) is fed forward, so that the network
    estimates only the remainder of ``Delta = f + d``.
    """
    l = W_hat.shape[0]
    c = controller_layout(l).unpack(p_ctrl)
    k1, k2, rho = c["k1"], c["k2"], c["rho"]
    q, v = QUAD_STATE.unpack(xq), VEHICLE_MEASUREMENT.unpack(yv)
    e1, e2 = relative_states(xq, yv)
    R = error_rate_matrix(q["eta1"])
    z1 = e1 - PAPER_REFERENCE.unpack(ref)["e1d"]                           # eq. 9
    alpha, alpha_dot = virtual_control(e1, R @ e2, ref, k1)
    z2 = e2 - alpha                                                  # eq. 9
    w_e = q["V1"][2]                                                 # w2 = 0
    p_e, q_e = q["Omega1"][0], q["Omega1"][1]
    r_e = q["Omega1"][2] - v["r2"]
    Psi = rbf(rbf_input(w_e, p_e, q_e, r_e), c["centers"], c["widths"])       # eq. 16
    Delta_hat = W_hat.T @ Psi                                        # eq. 16
    squash = ca.tanh(z2 / rho)
    u = (-k2 * z2 - R.T @ z1 - Delta_hat - squash * zeta_hat + alpha_dot   # eq. 20
         - c["nominal_model"] * nominal_drift(xq, p_quad))
    W_hat_dot = c["gamma1"] * (Psi @ z2.T - c["k_w"] * W_hat)               # eq. 22
    zeta_hat_dot = c["gamma2"] * (squash * z2 - c["k_zeta"] * zeta_hat)     # eq. 22
    wrench = wrench_from_virtual(xq, u, p_quad)
    return dict(u=u, wrench=wrench, rotor=rotors_from_wrench(wrench, p_quad),
                W_hat_dot=W_hat_dot, zeta_hat_dot=zeta_hat_dot, e1=e1, e2=e2, bs_z1=z1, bs_z2=z2,
                alpha=alpha, alpha_dot=alpha_dot, Psi=Psi, Delta_hat=Delta_hat)


def controller_function(l: int) -> ca.Function:
    """The continuous-time controller as one Function.

    ``controller(xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl) -> (u, wrench,
    rotor, W_hat_dot, zeta_hat_dot, e1, e2, bs_z1, bs_z2, alpha, alpha_dot,
    Psi, Delta_hat)`` (:func:`controller_outputs`).

    Parameters
    ----------
    l : int
        Number of RBF nodes.
    """
    xq, yv, ref = QUAD_STATE.sym(), VEHICLE_MEASUREMENT.sym(), PAPER_REFERENCE.sym()
    W_hat, zeta_hat = ca.SX.sym("W_hat", l, 4), ca.SX.sym("zeta_hat", 4)
    p_quad, p_ctrl = QUADROTOR.sym(), controller_layout(l).sym()
    out = control_law(xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl)
    names = list(controller_outputs(l).names())
    return ca.Function("controller", [xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl],
                       [out[k] for k in names],
                       ["xq", "yv", "ref", "W_hat", "zeta_hat", "p_quad", "p_ctrl"], names)


def lyapunov_function(l: int) -> ca.Function:
    """Lyapunov function Y = V1 + V2 of eq. (12), (17) and (25).

    Needs the estimation errors ``W_tilde = W_hat - W*`` and
    ``zeta_tilde = zeta_hat - zeta``; W* and zeta are unknown, so callers
    pass a comparison value of their choice (zero gives the function's
    value about the origin of the weights).

    ``lyapunov(bs_z1, bs_z2, W_tilde, zeta_tilde, gamma1, gamma2) ->
    (lyapunov_V1, lyapunov_V2, lyapunov_Y)``.
    """
    z1, z2 = ca.SX.sym("z1", 4), ca.SX.sym("z2", 4)
    W_tilde, zeta_tilde = ca.SX.sym("W_tilde", l, 4), ca.SX.sym("zeta_tilde", 4)
    gamma1, gamma2 = ca.SX.sym("gamma1"), ca.SX.sym("gamma2")
    V1 = 0.5 * ca.dot(z1, z1)                                                   # eq. 12
    V2 = (0.5 * ca.dot(z2, z2) + 0.5 * ca.sum1(ca.sum2(W_tilde * W_tilde)) / gamma1
          + 0.5 * ca.dot(zeta_tilde, zeta_tilde) / gamma2)                      # eq. 17
    return ca.Function("lyapunov", [z1, z2, W_tilde, zeta_tilde, gamma1, gamma2],
                       [V1, V2, V1 + V2],
                       ["bs_z1", "bs_z2", "W_tilde", "zeta_tilde", "gamma1", "gamma2"],
                       ["lyapunov_V1", "lyapunov_V2", "lyapunov_Y"])

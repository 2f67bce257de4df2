"""Frames and kinematics (eq. 1, 3).

Earth frame E has z up; eta = [phi, theta, psi] are ZYX Euler angles and
``rotation(eta) = Rz(psi) Ry(theta) Rx(phi)`` maps body vectors to E.
"""

from __future__ import annotations

import casadi as ca

__all__ = [
    "rotation",
    "euler_rate_matrix",
    "euler_rate_matrix_inv",
    "vertical_row",
    "skew",
    "kinematics_function",
    "tilt_angle",
]


def rotation(eta):
    """Body-to-Earth rotation Rz(psi) Ry(theta) Rx(phi)."""
    phi, theta, psi = eta[0], eta[1], eta[2]
    cf, sf = ca.cos(phi), ca.sin(phi)
    ct, st = ca.cos(theta), ca.sin(theta)
    cp, sp = ca.cos(psi), ca.sin(psi)
    Rx = ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, cf, -sf), ca.horzcat(0, sf, cf))
    Ry = ca.vertcat(ca.horzcat(ct, 0, st), ca.horzcat(0, 1, 0), ca.horzcat(-st, 0, ct))
    Rz = ca.vertcat(ca.horzcat(cp, -sp, 0), ca.horzcat(sp, cp, 0), ca.horzcat(0, 0, 1))
    return Rz @ Ry @ Rx


def euler_rate_matrix(eta):
    """Rr(eta): body rates to Euler-angle rates, eta_dot = Rr Omega (eq. 1)."""
    phi, theta = eta[0], eta[1]
    cf, sf = ca.cos(phi), ca.sin(phi)
    tt, sec = ca.tan(theta), 1 / ca.cos(theta)
    return ca.vertcat(
        ca.horzcat(1, tt * sf, tt * cf),
        ca.horzcat(0, cf, -sf),
        ca.horzcat(0, sec * sf, sec * cf),
    )


def euler_rate_matrix_inv(eta):
    """Rr(eta)^-1 in closed form: Euler-angle rates to body rates."""
    phi, theta = eta[0], eta[1]
    cf, sf = ca.cos(phi), ca.sin(phi)
    ct, st = ca.cos(theta), ca.sin(theta)
    return ca.vertcat(
        ca.horzcat(1, 0, -st),
        ca.horzcat(0, cf, sf * ct),
        ca.horzcat(0, -sf, cf * ct),
    )


def vertical_row(eta):
    """J(eta): the last row of the body-to-Earth rotation (eq. 1)."""
    phi, theta = eta[0], eta[1]
    return ca.horzcat(-ca.sin(theta), ca.cos(theta) * ca.sin(phi), ca.cos(theta) * ca.cos(phi))


def skew(w):
    """S(w), the cross-product matrix: S(w) v = w x v."""
    return ca.vertcat(
        ca.horzcat(0, -w[2], w[1]),
        ca.horzcat(w[2], 0, -w[0]),
        ca.horzcat(-w[1], w[0], 0),
    )


def kinematics_function() -> ca.Function:
    """The frame quantities of eq. (1) as one named Function.

    Returns
    -------
    casadi.Function
        ``kinematics(eta, Omega) -> (R, Rr, Rr_inv, J, S)``.
    """
    eta = ca.SX.sym("eta", 3)
    Omega = ca.SX.sym("Omega", 3)
    return ca.Function(
        "kinematics",
        [eta, Omega],
        [rotation(eta), euler_rate_matrix(eta), euler_rate_matrix_inv(eta),
         vertical_row(eta), skew(Omega)],
        ["eta", "Omega"],
        ["R", "Rr", "Rr_inv", "J", "S"],
    )


def tilt_angle(eta):
    """The thrust axis' angle from the vertical, ``acos(cos phi cos theta)``, in [0, pi].

    Continuous in the Euler angles and blind to whole turns: a flight whose
    thrust map's singularity ``cos phi cos theta = 0`` is crossed between two
    checks is past ``pi / 2`` at the next one.

    Examples
    --------
    >>> import numpy as np
    >>> float(tilt_angle(ca.DM([np.pi / 3, 0, 5]))), float(tilt_angle(ca.DM([2 * np.pi, 0, 0])))
    (1.0471975511965976, 0.0)
    """
    c = ca.cos(eta[0]) * ca.cos(eta[1])
    return ca.acos(ca.fmin(1, ca.fmax(-1, c)))

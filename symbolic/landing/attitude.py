"""From a desired thrust vector to a collective thrust and an attitude.

The outer loop asks for a thrust vector ``t_E`` in E (N, z up). Its direction
becomes the desired body z axis, its size the collective thrust, with two
limits:

* **tilt**: the body z axis stays within ``tilt_max`` of E's z. A direction
  outside the cone is moved onto it in its own vertical plane (PX4's
  ``ControlMath::limitTilt``); ``t_E = 0`` or a straight-down ``t_E`` give
  the level attitude.
* **thrust**: ``T = t_z / b3_z``, the thrust whose vertical part is the one
  asked for (PX4's vertical priority: a limited tilt costs horizontal
  acceleration, never height), clipped to ``[0, T_max]``. Within the cone
  ``T = |t_E|``.

The attitude is PX4's ``ControlMath::bodyzToAttitude`` written for z up:
``b1 = y_C x b3`` with ``y_C = [-sin psi, cos psi, 0]``, ``b2 = b3 x b1``,
``R = [b1 b2 b3]``, and its ZYX angles. Taking ``b1`` normal to ``y_C`` puts
the body x axis in the vertical plane of the heading, so the ZYX yaw of the
result is exactly ``psi``. ``tilt_max`` must be below pi/2, which keeps
``b3_z > 0`` and away from PX4's inverted and horizontal special cases.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["limit_tilt", "body_z_to_attitude", "thrust_attitude", "thrust_attitude_function"]

_EPS = 1e-9


def _normalize(v):
    return v / ca.fmax(ca.norm_2(v), _EPS)


def limit_tilt(t_E, tilt_max):
    """Unit body z axis along ``t_E``, moved onto the cone ``tilt_max`` if outside.

    Returns
    -------
    b3 : casadi.SX, (3, 1)
    limited : casadi.SX
        1 where the tilt was limited (``t_E = 0`` counts as limited), else 0.
    """
    b = t_E / ca.fmax(ca.norm_2(t_E), _EPS)
    limited = b[2] < ca.cos(tilt_max)
    # the horizontal direction of b; for b straight down (or zero) it is zero
    # and the normalization below gives e_z
    h = b[0:2] / ca.fmax(ca.norm_2(b[0:2]), _EPS)
    on_cone = _normalize(ca.vertcat(ca.sin(tilt_max) * h, ca.cos(tilt_max)))
    return ca.if_else(limited, on_cone, b), limited


def body_z_to_attitude(b3, psi):
    """Roll and pitch ``(phi, theta)`` whose body z is ``b3`` at ZYX yaw ``psi``.

    PX4's ``bodyzToAttitude`` for z up and ``b3_z > 0``; the ZYX angles of
    ``R = [b1 b2 b3]`` are ``phi = atan2(R32, R33)`` and
    ``theta = atan2(-R31, hypot(R32, R33))``.
    """
    y_C = ca.vertcat(-ca.sin(psi), ca.cos(psi), 0)
    b1 = _normalize(ca.cross(y_C, b3))
    b2 = ca.cross(b3, b1)
    phi = ca.atan2(b2[2], b3[2])
    theta = ca.atan2(-b1[2], ca.sqrt(b2[2] ** 2 + b3[2] ** 2))
    return phi, theta


def thrust_attitude(t_E, psi, tilt_max, T_max, deck=None):
    """Collective thrust and attitude of a desired thrust vector.

    Parameters
    ----------
    t_E : casadi.SX, (3, 1)
        Desired thrust vector in E, N (z up).
    psi : casadi.SX
        Desired ZYX yaw, rad.
    tilt_max : casadi.SX
        Largest angle between the body z axis and E's z, rad, in (0, pi/2).
    T_max : casadi.SX
        Largest collective thrust, N.
    deck : tuple, optional
        ``(deck_tilt_max, R_deck)``: ``b3``, once within ``tilt_max`` of E's z, is also
        held within ``deck_tilt_max`` (rad, in (0, pi/2]) of the deck's normal ``R_deck
        e_z``: where it lies farther it is moved toward the normal onto that cone (along
        the great circle through both, so still within ``tilt_max`` of E's z when the
        normal is); where it lies within (always at ``pi/2`` for a body within 90 deg of
        the normal) it passes unchanged, bit for bit. None: E's z alone.

    Returns
    -------
    dict
        ``T`` (N, in ``[0, T_max]``), ``b3`` (unit body z axis), ``phi``,
        ``theta`` (rad), ``tilt_limited`` and ``thrust_limited`` (0 or 1).
    """
    b3, tilt_limited = limit_tilt(t_E, tilt_max)
    if deck is not None:
        deck_tilt_max, R_deck = deck
        outside = R_deck[:, 2].T @ b3 < ca.cos(deck_tilt_max)
        b3 = ca.if_else(outside, R_deck @ limit_tilt(R_deck.T @ b3, deck_tilt_max)[0], b3)
        tilt_limited = ca.logic_or(tilt_limited, outside)
    T_raw = t_E[2] / b3[2]                                   # vertical priority
    T = ca.fmin(ca.fmax(T_raw, 0), T_max)
    phi, theta = body_z_to_attitude(b3, psi)
    return dict(T=T, b3=b3, phi=phi, theta=theta, tilt_limited=tilt_limited,
                thrust_limited=ca.logic_or(T_raw < 0, T_raw > T_max))


def thrust_attitude_function() -> ca.Function:
    """``thrust_attitude(t_E, psi, tilt_max, T_max) -> (T, b3, phi, theta,
    tilt_limited, thrust_limited)`` (:func:`thrust_attitude`)."""
    t_E, psi = ca.SX.sym("t_E", 3), ca.SX.sym("psi")
    tilt_max, T_max = ca.SX.sym("tilt_max"), ca.SX.sym("T_max")
    out = thrust_attitude(t_E, psi, tilt_max, T_max)
    names = ["T", "b3", "phi", "theta", "tilt_limited", "thrust_limited"]
    return ca.Function("thrust_attitude", [t_E, psi, tilt_max, T_max],
                       [out[n] for n in names], ["t_E", "psi", "tilt_max", "T_max"], names)

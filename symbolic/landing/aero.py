"""The landing plant's aerodynamics beyond eq. (2): quadratic drag and ground effect.

Eq. (2)'s drag is linear, ``-Kt V1`` (the rotors' momentum drag, PX4's
``EKF2_MCOEF`` model); a real airframe also has a bluff body, whose drag
grows with the square of the airspeed (PX4's ``EKF2_BCOEF_X``/``_Y``). Near the
deck the rotors push on the air cushion under them and make more thrust for
the same power (the ground effect). Both are body forces, added to eq. (2)'s
``d_F`` (:func:`aero_force`); their constants are :data:`~quadland_symbolic.landing.
quadrotor.ACTUATOR`'s ``drag_quadratic``, ``rotor_radius`` and ``air_density``.

* **Quadratic drag**, per body axis, on the velocity relative to the air
  ``V_air = V1 - R(eta1)^T v_wind``: ``-Kq (V_air |V_air|)``.
* **Ground effect** (Cheeseman and Bennett 1955, the image-rotor model with
  the forward-flight correction): the thrust is ``F_total k_ge`` with
  ``k_ge = 1 / (1 - (R / (4 z))^2 / (1 + (V_h / v_i)^2))``, ``z`` the rotor
  plane's height above the deck plane (the centre's, along the deck normal),
  ``V_h`` the horizontal airspeed and ``v_i = sqrt(F_total / (8 rho pi R^2))``
  the hover induced velocity of one of four rotors. ``z`` is held at ``R / 2``
  or more, where the formula is still valid (it grows without bound at ``R / 4``):
  ``k_ge`` is at most 4/3. ``R = 0`` turns it off. The same ratio for every
  rotor (a total-thrust model: the deck's tilt makes no moment); the deck is
  taken as an unbounded plane.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.deck import deck_pose
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE

__all__ = ["ground_effect_ratio", "quadratic_drag", "aero_force"]


def ground_effect_ratio(z, v_h, F_total, p_act):
    """``k_ge``, the thrust in ground effect over the thrust out of it (module docstring).

    ``z``: the rotor plane's height above the deck (m); ``v_h``: the horizontal
    airspeed (m/s); ``F_total``: the rotors' thrust (N).
    """
    a = ACTUATOR.unpack(p_act)
    R, rho = a["rotor_radius"], a["air_density"]
    z_held = ca.fmax(z, ca.fmax(R / 2, 1e-6))
    v_i2 = ca.fmax(F_total, 0) / (8 * rho * ca.pi * ca.fmax(R, 1e-6) ** 2)
    image = (R / (4 * z_held)) ** 2 / (1 + v_h ** 2 / ca.fmax(v_i2, 1e-12))
    return 1 / (1 - image)


def quadratic_drag(V_air, p_act):
    """``-Kq (V_air |V_air|)``, body axes, N."""
    return -ACTUATOR.unpack(p_act)["drag_quadratic"] * V_air * ca.fabs(V_air)


def aero_force(x1q, xv, v_wind, t, p_act, p_veh, p_deck):
    """The body force of quadratic drag and ground effect, N (module docstring)."""
    q = QUAD6_STATE.unpack(x1q)
    R1 = rotation(q["eta1"])
    V_air = q["V1"] - R1.T @ v_wind
    deck = deck_pose(xv, t, p_veh, p_deck)
    z = (deck.R_deck[:, 2]).T @ (q["p1"] - deck.p2)
    air_E = R1 @ V_air
    v_h = ca.sqrt(air_E[0] ** 2 + air_E[1] ** 2 + 1e-12)
    F_total = ca.sum1(q["F"])
    lift = (ground_effect_ratio(z, v_h, F_total, p_act) - 1) * F_total
    return quadratic_drag(V_air, p_act) + ca.vertcat(0, 0, lift)

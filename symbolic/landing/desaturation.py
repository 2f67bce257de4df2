"""Attitude priority at the rotors: the collective thrust gives way to the moments.

Rotor ``i`` makes ``T / 4 + m_i`` (eq. 2's mixer), ``m_i`` its share of the moments
``M``. A rotor clipped at 0 or ``F_max`` loses its share, and the attitude with it;
the thrust is the one quantity the moments do not need. PX4's mixer desaturates the
same way (docs/landing.md, "Limits").
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.quadrotor import rotors_from_wrench

__all__ = ["thrust_within_moments", "clip_forces", "clipped_count"]


def thrust_within_moments(T, M, p_quad, F_max, airmode=1):
    """``T`` moved into the band where every rotor can make its share of ``M``.

    The band is ``[4 max(-m_i), 4 (F_max - max m_i)]``; where it is empty (moments
    beyond the rotors) its upper end is taken, and the result is never below 0.
    ``airmode`` 0 (a 0/1 flag, symbolic or not) never raises ``T`` to the band's lower
    end: the collective only comes down to its upper end, and the rotors the moments
    would take below 0 are clipped there by the caller. The clip gives up part of the
    moments, adds the clipped rotors' deficit to the thrust made (less than air mode's
    rise) and their share of the yaw; PX4 without air mode (``MC_AIRMODE`` 0) instead
    scales roll and pitch back and holds the thrust (docs/landing.md, "highway_100: the
    level-out without air mode"). 1, the default, is the band as above.

    Parameters
    ----------
    T : casadi.SX
        Collective thrust asked for, N.
    M : casadi.SX, (3, 1)
        Moments, N m.
    p_quad : casadi.SX
        :data:`~quadland_symbolic.parameters.QUADROTOR` (the mixer's arm and drag factor).
    F_max : casadi.SX
        Largest force of one rotor, N.
    airmode : casadi.SX or float
        1: the collective rises for the moments (air mode); 0: it does not.
    """
    m = rotors_from_wrench(ca.vertcat(0, M), p_quad)
    lo, hi = 4 * ca.mmax(-m), 4 * (F_max - ca.mmax(m))
    within = ca.fmax(ca.fmin(ca.fmax(T, lo), hi), 0)
    if isinstance(airmode, (int, float)) and airmode == 1:
        return within
    return ca.if_else(airmode > 0.5, within, ca.fmax(ca.fmin(T, hi), 0))


def clipped_count(F, F_max):
    """Rotor commands beyond ``[0, F_max]`` by more than ``1e-5 F_max``: one the thrust's
    band puts at a limit is not clipped, whatever its roundoff (float flight code)."""
    tol = 1e-5 * F_max
    return ca.sum1(F < -tol) + ca.sum1(F > F_max + tol)


def clip_forces(F, F_min, F_max):
    """Clip finite forces; a NaN or an infinity passes through, never hidden by a limit."""
    return ca.if_else(ca.logic_and(F < F_min, F > -ca.inf), F_min,
                      ca.if_else(ca.logic_and(F > F_max, F < ca.inf), F_max, F))

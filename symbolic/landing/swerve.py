"""The pad swerving: the guidance's hold of the final descent while the vehicle manoeuvres.

A car changing lane carries its roof sideways with an acceleration of ``2 pi L / T^2`` at
its peak (3.5 m in 4 s: 1.37 m/s^2, docs/landing.md, "Cars that drive"); a quadrotor
meeting the roof then meets it leaning sideways and pulled across it. The guidance can
wait: it does not commit to the final descent while the pad swerves, and withdraws a
committed one (the reference glides back up to the wait height, as for a deck rising
past ``max_deck_rise``), then commits again once the swerve is over
(:mod:`quadland_symbolic.landing.guidance`, ``swerve_accel``).

**What the aircraft knows of the swerve.** Two measures of the pad's horizontal
acceleration, from what the flight stack holds, never the truth: the pad's acceleration
``a2E`` (the broadcast on perfect sensing, the navigation filter's ``a_t`` on sensors)
and the acceleration of the pad's velocity turned by the vehicle's rotation,
``w2E x v2E`` (the datalink's angular velocity, and the pad's velocity): for a vehicle
at a constant speed ``u`` turning at the yaw rate ``r`` it is ``u r``, the lateral
acceleration again, from another source (the broadcast's yaw rate, fused by no filter).
The swerve is the larger of their horizontal magnitudes, m/s^2.

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["pad_swerve", "swerving"]


def pad_swerve(v2E, a2E, w2E):
    """The pad's horizontal acceleration as the aircraft knows it, m/s^2: the larger of
    ``|a2E_h|`` and ``|(w2E x v2E)_h|`` (the subscript: x and y in E).

    Parameters
    ----------
    v2E, a2E, w2E : casadi.SX, (3,)
        The pad's velocity (m/s) and acceleration (m/s^2), the vehicle's angular velocity
        (rad/s), in E.
    """
    turn = ca.cross(w2E, v2E)
    return ca.fmax(ca.norm_2(a2E[0:2]), ca.norm_2(turn[0:2]))


def swerving(swerve, swerve_accel):
    """1 (CasADi) when the swerve exceeds ``swerve_accel`` > 0; never at 0 (no hold)."""
    return ca.logic_and(swerve_accel > 0, swerve > swerve_accel)

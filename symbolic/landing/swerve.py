"""The pad swerving: the guidance's hold of the final descent while the vehicle manoeuvres.

A car changing lane carries its roof sideways with an acceleration of ``2 pi L / T^2`` at
its peak (3.5 m in 4 s: 1.37 m/s^2, docs/landing.md, "Cars that drive"); a quadrotor
meeting the roof then meets it leaning sideways and pulled across it. The guidance can
wait: it does not commit to the final descent while the pad swerves, and withdraws a
committed one (the reference glides back up to the wait height, as for a deck rising
past ``max_deck_rise``), then commits again once the swerve is over
(:mod:`quadland_symbolic.landing.guidance`, ``swerve_accel``).

**What the aircraft knows of the swerve.** The pad's horizontal acceleration ``a2E``
as the flight stack holds it, never the truth: the vehicle's broadcast on perfect sensing,
the navigation filter's estimate ``a_t`` on sensors (fed by the datalink's reported
acceleration; its noise on a straight road, ``estimator.q_at`` 0.1, is a 0.045 m/s^2
standard deviation). The swerve is its horizontal magnitude, m/s^2. (The acceleration
of the pad's velocity turned by the datalink's yaw rate, ``w2E x v2E``, is the same
lateral acceleration from the broadcast alone, but extrapolated over the link's age with
its yaw acceleration (0.03 rad/s^2 of noise) it read past 0.3 m/s^2 on a straight road
at 100 km/h: docs/landing.md, "highway_100: the guidance holds through the lane change".)

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["pad_swerve", "swerving"]


def pad_swerve(a2E):
    """The pad's horizontal acceleration as the aircraft knows it, m/s^2: ``|a2E_h|``
    (x and y of ``a2E``, the pad's acceleration in E, m/s^2)."""
    return ca.norm_2(a2E[0:2])


def swerving(swerve, swerve_accel):
    """1 (CasADi) when the swerve exceeds ``swerve_accel`` > 0; never at 0 (no hold)."""
    return ca.logic_and(swerve_accel > 0, swerve > swerve_accel)

"""How the vehicle is driven: a time table of speed changes, turns and lane changes.

A car on a road does not hold eq. (4)'s constant inputs: it brakes, accelerates
and changes lanes. The drive profile is :data:`N_LEGS` legs (parameters
:data:`DRIVE_PARAMS`), each starting at ``start`` and lasting ``duration`` (s),
with ``tau = (t - start) / duration`` clipped to ``[0, 1]``; the legs add up:

* a **speed change** ``dv`` (m/s) with a raised-cosine acceleration
  ``du/dt = dv / T (1 - cos 2 pi tau)``, so ``du = dv (tau - sin(2 pi tau) / (2 pi))``:
  jerk-free at both ends, its peak ``2 dv / T`` at mid-leg;
* a **heading change** ``dpsi`` (rad) with the yaw rate ``dr = dpsi / T (1 - cos 2 pi tau)``;
* a **lane change**: the sinusoidal yaw rate ``dr = A sin(2 pi tau)``, one full period,
  which returns to the heading it started from, displaced sideways by
  ``u A T^2 / (2 pi)`` at the speed ``u`` (to second order in the heading,
  docs/landing.md "Cars that drive").

The profile is a driver: it does not prescribe the state, it adds to eq. (4)'s
inputs ``tau`` the inverse dynamics of the reference increments ``(du, dr)``
with the sway held at zero (a tyre does not slide):

``dtau_x = m11 du' + d11 du``, ``dtau_z = m33 dr' + d33 dr`` and
``dtau_y = m11 (u2 dr + du r2 - du dr)``, the centripetal force of the turn.

From a state on the reference (``u2 = u0 + du``, ``v2 = 0``, ``r2 = r0 + dr``, with
``tau`` holding ``(u0, r0)`` steady as in a shipped scenario) eq. (4) then follows
the reference exactly; off it, the errors decay as eq. (4)'s own do. With every
amplitude zero the vehicle is eq. (4)'s alone.
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

__all__ = ["N_LEGS", "DRIVE_PARAMS", "drive_idle", "drive_reference", "driven_vehicle_rhs",
           "pack_drive", "planned_speed_change"]

#: Legs of a drive profile (speed changes, turns and lane changes, in any order).
N_LEGS = 4


def _legs(name: str, unit: str, what: str) -> Field:
    return Field(name, N_LEGS, unit, what,
                 elements=tuple(f"{name}_{i}" for i in range(1, N_LEGS + 1)))


#: The drive profile's parameters: one entry per leg.
DRIVE_PARAMS = Layout("p_drive", (
    _legs("leg_start", "s", "time the leg starts"),
    _legs("leg_duration", "s", "the leg's duration T (> 0)"),
    _legs("leg_speed_change", "m/s", "surge speed change dv, raised-cosine acceleration"),
    _legs("leg_heading_change", "rad", "heading change dpsi, raised-cosine yaw rate"),
    _legs("leg_lane_rate", "rad/s", "lane change: amplitude A of the yaw rate A sin(2 pi tau)"),
), "the vehicle's drive profile: legs of speed change, turn and lane change")


def drive_idle() -> dict:
    """The values of a profile that drives nothing (every leg 1 s long, amplitudes zero)."""
    zero = [0.0] * N_LEGS
    return dict(leg_start=zero, leg_duration=[1.0] * N_LEGS, leg_speed_change=zero,
                leg_heading_change=zero, leg_lane_rate=zero)


def drive_reference(t, p_drive):
    """``(du, du_dot, dr, dr_dot)``: the profile's speed (m/s) and yaw-rate (rad/s)
    increments at time ``t`` and their rates, summed over the legs."""
    p = DRIVE_PARAMS.unpack(p_drive)
    T = ca.fmax(p["leg_duration"], 1e-6)
    tau = (t - p["leg_start"]) / T
    s = ca.fmin(ca.fmax(tau, 0), 1)
    inside = ca.logic_and(tau > 0, tau < 1)
    two_pi = 2 * ca.pi
    dv, dpsi, A = p["leg_speed_change"], p["leg_heading_change"], p["leg_lane_rate"]
    du = dv * (s - ca.sin(two_pi * s) / two_pi)
    du_dot = dv / T * (1 - ca.cos(two_pi * s))
    dr = dpsi / T * (1 - ca.cos(two_pi * s)) + A * ca.sin(two_pi * s)
    dr_dot = (dpsi / T * two_pi / T * ca.sin(two_pi * s)
              + ca.if_else(inside, A * two_pi / T * ca.cos(two_pi * s), 0))
    return tuple(ca.sum1(e) for e in (du, du_dot, dr, dr_dot))


def driven_vehicle_rhs(xv, t, p_veh, p_drive):
    """``xv_dot`` of eq. (4) under its inputs ``tau`` plus the profile's (module docstring)."""
    p, x = VEHICLE.unpack(p_veh), VEHICLE_STATE.unpack(xv)
    du, du_dot, dr, dr_dot = drive_reference(t, p_drive)
    u2, r2 = x["u2"], x["r2"]
    dtau_x = p["m11"] * du_dot + p["d11"] * du
    dtau_y = p["m11"] * (u2 * dr + du * r2 - du * dr)
    dtau_z = p["m33"] * dr_dot + p["d33"] * dr
    return vehicle_rhs(xv, p_veh) + ca.vertcat(0, 0, 0, dtau_x / p["m11"], dtau_y / p["m22"],
                                               dtau_z / p["m33"])


def pack_drive(start, duration, speed_change, heading_change, lane_offset, u0: float):
    """:data:`DRIVE_PARAMS` of up to :data:`N_LEGS` legs (the rest idle), from a scenario's
    table: the lane changes given by their sideways offset (m, positive to the left).

    A lane change's yaw-rate amplitude is ``A = 2 pi offset / (u T^2)`` at the speed
    ``u`` the profile plans at the leg's middle (``u0``, the initial surge speed, plus
    the speed changes by then). Raises ValueError naming the leg where a lane change
    finds the vehicle at rest or backing.
    """
    legs = dict(leg_start=start, leg_duration=duration, leg_speed_change=speed_change,
                leg_heading_change=heading_change, leg_lane_rate=[0.0] * len(start))
    values = drive_idle()
    for name, given in legs.items():
        values[name] = [float(v) for v in given] + values[name][len(given):]
    rates = []
    for k, offset in enumerate(lane_offset):
        T = float(duration[k])
        u = u0 + planned_speed_change(float(start[k]) + T / 2, DRIVE_PARAMS.pack(values))
        if offset and u <= 0:
            raise ValueError(f"leg {k + 1}: a lane change needs the vehicle moving forward, "
                             f"its planned speed is {u:g} m/s")
        rates.append(2 * float(np.pi) * float(offset) / (u * T ** 2) if offset else 0.0)
    values["leg_lane_rate"] = rates + values["leg_lane_rate"][len(rates):]
    return DRIVE_PARAMS.pack(values)


def planned_speed_change(t: float, p_drive) -> float:
    """``du(t)``, the profile's planned surge speed change by time ``t`` (m/s), a number.

    Remembered per ``t`` and profile: a campaign's every run validates the same
    profile (CasADi's numeric evaluation costs about a millisecond a call)."""
    return _planned_speed_change(float(t), tuple(np.asarray(p_drive, dtype=float).ravel()
                                                 .tolist()))


@functools.lru_cache(maxsize=256)
def _planned_speed_change(t: float, p_drive: tuple[float, ...]) -> float:
    return float(drive_reference(ca.DM(t), ca.DM(list(p_drive)))[0])

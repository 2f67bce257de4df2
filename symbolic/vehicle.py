"""Ground-vehicle model (eq. 3-4) with heave, roll and pitch neglected.

State ``xv`` (layout :data:`VEHICLE_STATE`): planar position in E (m), heading
(rad), surge and sway velocity (m/s) and yaw rate (rad/s). The position is
not used by the controller; it is integrated for the ground track. The deck
altitude z2 is a constant parameter (w2 = 0). The controller measures
``yv = [z2, psi2, r2]`` (:data:`VEHICLE_MEASUREMENT`).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import VEHICLE

__all__ = ["VEHICLE_STATE", "VEHICLE_MEASUREMENT", "vehicle_rhs", "yaw_acceleration",
           "vehicle_function"]

#: The vehicle's state xv (eq. 3-4, planar).
VEHICLE_STATE = Layout("xv", (
    Field("x2", 1, "m", "position x in E"),
    Field("y2", 1, "m", "position y in E"),
    Field("psi2", 1, "rad", "heading"),
    Field("u2", 1, "m/s", "surge velocity"),
    Field("v2", 1, "m/s", "sway velocity"),
    Field("r2", 1, "rad/s", "yaw rate"),
), "ground vehicle state; heave, roll and pitch are neglected")

#: What the controller measures of the vehicle.
VEHICLE_MEASUREMENT = Layout("yv", (
    Field("z2", 1, "m", "deck altitude"),
    Field("psi2", 1, "rad", "heading"),
    Field("r2", 1, "rad/s", "yaw rate"),
), "measured vehicle state")


def yaw_acceleration(u2, v2, r2, p_veh):
    """r2_dot from the third row of eq. (4)."""
    p = VEHICLE.unpack(p_veh)
    tau_z = p["tau"][2]
    return (tau_z - p["d33"] * r2 + (p["m11"] - p["m22"]) * u2 * v2) / p["m33"]


def vehicle_rhs(xv, p_veh):
    """Time derivative of the vehicle state (eq. 3-4).

    ``M1 V2_dot + C1 Omega2 + D1 V2 = Upsilon1`` gives
    ``m11 u2_dot = tau_x + m22 v2 r2 - d11 u2`` and
    ``m22 v2_dot = tau_y - m11 u2 r2 - d22 v2``; eq. (3) with
    ``phi2 = theta2 = 0`` gives ``psi2_dot = r2`` and the planar track.
    """
    p = VEHICLE.unpack(p_veh)
    x = VEHICLE_STATE.unpack(xv)
    psi2, u2, v2, r2 = x["psi2"], x["u2"], x["v2"], x["r2"]
    tau_x, tau_y = p["tau"][0], p["tau"][1]
    x2_dot = ca.cos(psi2) * u2 - ca.sin(psi2) * v2
    y2_dot = ca.sin(psi2) * u2 + ca.cos(psi2) * v2
    u2_dot = (tau_x + p["m22"] * v2 * r2 - p["d11"] * u2) / p["m11"]   # eq. 4, surge
    v2_dot = (tau_y - p["m11"] * u2 * r2 - p["d22"] * v2) / p["m22"]   # eq. 4, sway
    r2_dot = yaw_acceleration(u2, v2, r2, p_veh)                        # eq. 4, yaw
    return ca.vertcat(x2_dot, y2_dot, r2, u2_dot, v2_dot, r2_dot)


def vehicle_function() -> ca.Function:
    """``vehicle(xv, p_veh) -> xv_dot`` (eq. 3-4)."""
    xv, p_veh = VEHICLE_STATE.sym(), VEHICLE.sym()
    return ca.Function("vehicle", [xv, p_veh], [vehicle_rhs(xv, p_veh)],
                       ["xv", "p_veh"], ["xv_dot"])

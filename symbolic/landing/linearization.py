"""Exact Jacobians of the landing loop at hover, broken at the wrench into the mixer.

The loop is written in the deck frame. The plant state is

    z = [x_e, y_e, z_e, phi1, theta1, psi_e, u1, v1, w1, p1, q1, r1, F_1..F_4]   (16)

(:data:`HOVER_PLANT`): the quadrotor's centre from the pad centre in deck
axes, its attitude with the relative yaw ``psi_e = psi1 - psi2``, its body
velocity and rates, and the rotor forces. The deck is frozen: its heave, roll
and pitch are held at zero (their mean; a sum of sinusoids), its yaw psi2 is
set to zero, the vehicle's position to the origin. Eq. (1)-(4) and the
landing law are invariant under a common yaw of both bodies (drag, disturbance
and the wind force are in body axes; the law reads yaw only through
``R_deck``, whose heading it follows), so evaluating them at ``psi2 = 0`` is
exact; the only change is the yaw row ``psi_e_dot = psi1_dot - psi2_dot``. In
these coordinates a vehicle in its steady motion (``u2, v2, r2`` constant,
eq. 4) and a quadrotor hovering over the pad leave an equilibrium, while
``x2, y2, psi2`` and the quadrotor's ``x1, y1, psi1`` grow. The wind must be
given in the heading frame (E turned by the vehicle's heading).

The plant's input is the wrench ``u = [T, M_x, M_y, M_z]`` the landing step
sends to the mixer (:data:`quadland_symbolic.quadrotor.WRENCH`); the motors follow
``rotors_from_wrench(u)`` with their lag. Its output is what the step
measures of the quadrotor (:data:`HOVER_OUTPUT`): ``p_e, v_e`` (landing
sensor) and ``eta1, Omega1`` (IMU). The vehicle's broadcast is frozen at its
steady motion.

The controller is the landing step (:func:`~quadland_symbolic.landing.controller.landing_law`):
its memory ``mem`` (network, robust terms, command filter, saturation
compensator) is updated over ``dt`` with the measurement held, so its
Jacobians at ``dt`` are those of a discrete-time system. Its continuous-time
limit ``mem_dot = d mem_next / d dt`` at ``dt = 0`` is the memory's own
differential equations (eq. 22, the filter and the compensator), which the
step integrates exactly.
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from quadland_symbolic.landing.aero import aero_force
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    landing_controller_params,
    landing_law,
    landing_memory,
)
from quadland_symbolic.landing.deck import deck_pose
from quadland_symbolic.landing.guidance import POSITION_REFERENCE
from quadland_symbolic.landing.plant import LANDING_DISTURBANCE, LANDING_PLANT_PARAMS, wind_force
from quadland_symbolic.landing.quadrotor import QUAD6_STATE, quadrotor6_rhs
from quadland_symbolic.landing.relative import RELATIVE6, relative6
from quadland_symbolic.layout import Layout
from quadland_symbolic.linearization import VEHICLE_SPEEDS
from quadland_symbolic.quadrotor import WRENCH, rotors_from_wrench
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

__all__ = ["HOVER_PLANT", "HOVER_OUTPUT", "hover_vehicle", "hover_quadrotor",
           "hover_plant_rhs", "hover_measurement", "hover_linearization_function",
           "hover_equilibrium_residual_function"]

#: The landing plant in the deck frame at a frozen deck: relative position,
#: attitude with the relative yaw, body velocity and rates, rotor forces.
HOVER_PLANT = Layout("z_land", (
    RELATIVE6["p_e"],
    dataclasses.replace(QUAD6_STATE["eta1"], elements=("phi1", "theta1", "psi_e"),
                        doc="roll, pitch and the yaw relative to the deck, psi1 - psi2"),
    QUAD6_STATE["V1"],
    QUAD6_STATE["Omega1"],
    QUAD6_STATE["F"],
), "landing plant in the deck frame")

#: What the landing step measures of the quadrotor: landing sensor and IMU.
HOVER_OUTPUT = Layout("y_quad", tuple(LANDING_MEASUREMENT[n] for n in ("p_e", "v_e", "eta1",
                                                                       "Omega1")),
                      "the landing step's measurements of the quadrotor")


def hover_vehicle(v2):
    """The vehicle's state at the origin with heading 0 and speeds ``v2 = [u2, v2, r2]``."""
    s = VEHICLE_SPEEDS.unpack(v2)
    return ca.vertcat(*[s[n] if n in s else 0 for n in VEHICLE_STATE.names()])


def hover_quadrotor(z, xv, pp):
    """The 6-DOF quadrotor state ``x1q`` of the deck-frame state ``z`` (``t = 0``)."""
    zs, p = HOVER_PLANT.unpack(z), LANDING_PLANT_PARAMS.unpack(pp)
    deck = deck_pose(xv, 0, p["p_veh"], p["p_deck"])
    psi2 = VEHICLE_STATE.unpack(xv)["psi2"]
    eta1 = zs["eta1"] + ca.vertcat(0, 0, psi2)
    return ca.vertcat(deck.p2 + deck.R_deck @ zs["p_e"], eta1, zs["V1"], zs["Omega1"], zs["F"])


def hover_plant_rhs(z, u, v2, w, pp):
    """``z_dot`` for a wrench command ``u`` (eq. 1-2 with motor lag, eq. 5 in 6-DOF).

    The rotors are commanded ``rotors_from_wrench(u)``; the disturbance is
    :data:`quadland_symbolic.landing.loop.LANDING_DISTURBANCE` (wind in the heading frame,
    ``d_F``, ``d_M``; the quadratic drag and ground effect of
    :func:`~quadland_symbolic.landing.aero.aero_force` on top).
    ``p_e_dot = v_e`` (:func:`~quadland_symbolic.landing.relative.relative6`),
    ``psi_e_dot = psi1_dot - psi2_dot``; the other rows are the quadrotor's own.
    """
    p, ws = LANDING_PLANT_PARAMS.unpack(pp), LANDING_DISTURBANCE.unpack(w)
    xv = hover_vehicle(v2)
    x1q = hover_quadrotor(z, xv, pp)
    eta1 = QUAD6_STATE.unpack(x1q)["eta1"]
    d_F = (ws["d_F"] + wind_force(eta1, ws["v_wind"], p["p_quad"])
           + aero_force(x1q, xv, ws["v_wind"], 0, p["p_act"], p["p_veh"], p["p_deck"]))
    x1q_dot = QUAD6_STATE.unpack(quadrotor6_rhs(x1q, rotors_from_wrench(u, p["p_quad"]), d_F,
                                                ws["d_M"], p["p_quad"], p["p_act"]))
    psi2_dot = VEHICLE_STATE.unpack(vehicle_rhs(xv, p["p_veh"]))["psi2"]
    v_e = relative6(x1q, xv, 0, p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])[1]
    return ca.vertcat(v_e, x1q_dot["eta1"] - ca.vertcat(0, 0, psi2_dot), x1q_dot["V1"],
                      x1q_dot["Omega1"], x1q_dot["F"])


def hover_measurement(z, v2, pp):
    """The step's whole measurement :data:`LANDING_MEASUREMENT`: ``HOVER_OUTPUT`` and the
    broadcast."""
    p = LANDING_PLANT_PARAMS.unpack(pp)
    xv = hover_vehicle(v2)
    x1q = hover_quadrotor(z, xv, pp)
    q = QUAD6_STATE.unpack(x1q)
    p_e, v_e, *_ = relative6(x1q, xv, 0, p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])
    deck = deck_pose(xv, 0, p["p_veh"], p["p_deck"])
    return ca.vertcat(p_e, v_e, q["eta1"], q["Omega1"], deck.eta2, deck.v2E, deck.a2E,
                      deck.w2E, deck.w2E_dot)


def _symbols(l: int):
    return (HOVER_PLANT.sym(), landing_memory(l).sym(), VEHICLE_SPEEDS.sym(),
            LANDING_DISTURBANCE.sym(), LANDING_PLANT_PARAMS.sym(),
            ca.SX.sym("pm", LANDING_PLANT_PARAMS.size), landing_controller_params(l).sym(),
            POSITION_REFERENCE.sym())


def _law(l, y_quad, z, mem, v2, pp, pm, p_ctrl, ref, dt):
    """The step's wrench and next memory with the quadrotor's measurements ``y_quad``:
    the law with the controller's own model ``pm``, the deck's broadcast of the plant
    ``pp``."""
    p = LANDING_PLANT_PARAMS.unpack(pm)
    broadcast = hover_measurement(z, v2, pp)[HOVER_OUTPUT.size:]
    out = landing_law(l, ca.vertcat(y_quad, broadcast), ref, mem, p_ctrl, p["p_quad"],
                      p["p_act"], dt)
    return out["wrench"], out["mem_next"]


def _memory_rate(mem_next, dt):
    """``d mem_next / d dt`` at ``dt = 0``: the memory's differential equations."""
    return ca.substitute(ca.jacobian(mem_next, dt), dt, 0)


@functools.cache
def hover_linearization_function(l: int) -> ca.Function:
    """Plant and landing-step Jacobians at a hover point.

    ``hover_linearization(z, mem, v2, w, pp, pm, p_ctrl, ref, dt) -> (u, z_dot,
    mem_dot, A_p, B_p, C_p, A_c, B_c, Phi_c, Gamma_c, C_c, D_c)`` with, about
    the point,

        d z_dot      = A_p d z + B_p d u              (plant, eq. 1-2, motors)
        d y          = C_p d z                        (y = HOVER_OUTPUT)
        d mem_dot    = A_c d mem + B_c d y            (the step's limit dt -> 0)
        d mem_next   = Phi_c d mem + Gamma_c d y      (the step over dt)
        d u          = C_c d mem + D_c d y            (the wrench, eq. 20)

    ``v2 = [u2, v2, r2]`` are the vehicle's speeds, ``w`` the disturbance
    (:data:`quadland_symbolic.landing.loop.LANDING_DISTURBANCE`, wind in the heading frame),
    ``pp`` the plant's parameters with the deck's motion the caller wants
    (frozen: zero amplitudes), ``pm`` the controller's own model of them (the
    law's ``p_quad`` and ``p_act``), ``ref`` the position reference.

    Parameters
    ----------
    l : int
        Number of RBF nodes.
    """
    z, mem, v2, w, pp, pm, p_ctrl, ref = _symbols(l)
    dt, u_in, y_in = ca.SX.sym("dt"), WRENCH.sym(), HOVER_OUTPUT.sym()
    y = hover_measurement(z, v2, pp)[:HOVER_OUTPUT.size]
    u_y, mem_next_y = _law(l, y_in, z, mem, v2, pp, pm, p_ctrl, ref, dt)
    mem_dot_y = _memory_rate(mem_next_y, dt)
    z_dot_u = hover_plant_rhs(z, u_in, v2, w, pp)
    u = ca.substitute(u_y, y_in, y)
    # one Jacobian per variable for the plant and for the step's three results (the
    # sweeps shared: half the cost of ten), then one substitution of the point for all
    nz, nd, nm = z.shape[0], mem_dot_y.shape[0], mem_next_y.shape[0]
    J_p = ca.jacobian(z_dot_u, ca.vertcat(z, u_in))
    step = ca.vertcat(mem_dot_y, mem_next_y, u_y)
    J_m, J_y = ca.jacobian(step, mem), ca.jacobian(step, y_in)
    rows = [slice(0, nd), slice(nd, nd + nm), slice(nd + nm, step.shape[0])]
    at_point = ca.substitute(ca.substitute(
        [z_dot_u, mem_dot_y, J_p[:, :nz], J_p[:, nz:],
         *[J[r, :] for r in rows for J in (J_m, J_y)]], [y_in], [y]), [u_in], [u])
    outs = [u, *at_point[:4], ca.jacobian(y, z), *at_point[4:]]
    names = ["u", "z_dot", "mem_dot", "A_p", "B_p", "C_p", "A_c", "B_c", "Phi_c", "Gamma_c",
             "C_c", "D_c"]
    return ca.Function("hover_linearization", [z, mem, v2, w, pp, pm, p_ctrl, ref, dt], outs,
                       ["z", "mem", "v2", "w", "pp", "pm", "p_ctrl", "ref", "dt"], names)


def _bias_pinned(l, mem, mem_dot, p_ctrl):
    """``mem_dot`` with each bias estimate whose gain is zero, and each axis's observer
    states whose bandwidth is zero, pinned at zero instead: their rate is then
    identically zero, which would leave them undetermined."""
    lay, c = landing_memory(l), landing_controller_params(l).unpack(p_ctrl)
    gains = dict(d_hat=ca.vertcat(c["ki_p"], c["ki"]), v_hat=c["w_o"], d_o=c["w_o"])
    for name, gain in gains.items():
        rows = lay.slice(name)
        pinned = ca.if_else(gain == 0, mem[rows], mem_dot[rows])
        mem_dot = ca.vertcat(mem_dot[:rows.start], pinned, mem_dot[rows.stop:])
    return mem_dot


@functools.cache
def hover_equilibrium_residual_function(l: int) -> ca.Function:
    """Residual and exact Jacobian of the landing loop's steady hover.

    ``hover_equilibrium_residual(xi, w, pp, pm, p_ctrl, ref) -> (F, dF)`` with
    unknowns ``xi = [z (16), mem (6 l + 29), u2, v2, r2]`` and residual
    ``F = [z_dot, mem_dot, (u2, v2, r2)_dot]``: the vehicle in its steady
    motion (eq. 4), the quadrotor at rest in the deck frame, the memory at
    rest. The step integrates its memory exactly with the measurement held,
    so a rest point of ``mem_dot`` is a fixed point of the step at any ``dt``.
    """
    z, mem, v2, w, pp, pm, p_ctrl, ref = _symbols(l)
    dt = ca.SX.sym("dt")
    y = hover_measurement(z, v2, pp)[:HOVER_OUTPUT.size]
    u, mem_next = _law(l, y, z, mem, v2, pp, pm, p_ctrl, ref, dt)
    xv_dot = VEHICLE_STATE.unpack(vehicle_rhs(hover_vehicle(v2),
                                              LANDING_PLANT_PARAMS.unpack(pp)["p_veh"]))
    mem_dot = _bias_pinned(l, mem, _memory_rate(mem_next, dt), p_ctrl)
    F = ca.vertcat(hover_plant_rhs(z, u, v2, w, pp), mem_dot,
                   *[xv_dot[n] for n in VEHICLE_SPEEDS.names()])
    xi = ca.vertcat(z, mem, v2)
    return ca.Function("hover_equilibrium_residual", [xi, w, pp, pm, p_ctrl, ref],
                       [F, ca.jacobian(F, xi)], ["xi", "w", "pp", "pm", "p_ctrl", "ref"],
                       ["F", "dF"])

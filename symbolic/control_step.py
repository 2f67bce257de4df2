"""Discrete-time control step for flight hardware (eq. 20, 22 sampled).

At a sample the law of eq. (20) is evaluated from the measurements, the
rotor forces are clipped to their limits, and the adaptive laws of eq. (22)
are integrated exactly over ``dt`` with the measurements held (zero-order
hold). With Psi and z2 held, ``W_hat_dot = gamma1 (Psi z2^T - k_w W_hat)``
is linear with constant forcing, so

    W_next = a W_hat + (1 - a) / k_w Psi z2^T,   a = exp(-gamma1 k_w dt),

and likewise for zeta_hat. This is stable for every ``dt > 0``, unlike a
forward-Euler update.

Hold compensation. A command held over ``[t_k, t_k + dt)`` acts on average
half a period late, which is the dominant error of the sampled loop against
the continuous one. The step extrapolates the law's output by ``hold``
periods along its last difference,

    u_cmd = u_k + hold (u_k - u_prev),

so that ``hold = 1/2`` cancels the half-period delay to first order in
``dt`` and the hold's error becomes second order; ``hold = 0`` is the plain
zero-order-hold emulation of eq. (20). ``u_prev`` is the law's output
``u_law`` of the previous step (on the first step, pass ``hold = 0``).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.backstepping import ADAPTIVE_UNITS, PAPER_REFERENCE, control_law
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, controller_layout
from quadland_symbolic.quadrotor import (
    QUAD_STATE,
    ROTORS,
    WRENCH,
    rotors_from_wrench,
    wrench_from_rotors,
)
from quadland_symbolic.relative import VIRTUAL_INPUT, tilt, wrench_from_virtual
from quadland_symbolic.vehicle import VEHICLE_MEASUREMENT

__all__ = ["step_inputs", "step_outputs", "control_step_function"]


@functools.cache
def step_inputs(l: int) -> Layout:
    """The control step's arguments, in order (one field per argument)."""
    return Layout("control_step_in", (
        Field.nested("xq", QUAD_STATE, "measured quadrotor state"),
        Field.nested("yv", VEHICLE_MEASUREMENT, "measured vehicle state"),
        Field.nested("ref", PAPER_REFERENCE, "reference"),
        Field("W_hat", 4 * l, "-", "network weights (eq. 22)", shape=(l, 4)),
        Field("zeta_hat", 4, ADAPTIVE_UNITS, "robust term estimate (eq. 22)"),
        Field("u_prev", 4, ADAPTIVE_UNITS, "the law's output of the previous step"),
        Field.nested("p_quad", QUADROTOR, "quadrotor constants"),
        Field.nested("p_ctrl", controller_layout(l), "controller parameters"),
        Field("rotor_limits", 2, "N", "rotor force limits F_min, F_max",
              elements=("F_min", "F_max")),
        Field("hold", 1, "periods", "hold compensation"),
        Field("dt", 1, "s", "control period"),
    ), "arguments of control_step")


@functools.cache
def step_outputs(l: int) -> Layout:
    """The control step's results, in order (one field per result)."""
    return Layout("control_step_out", (
        Field.nested("u", VIRTUAL_INPUT, "commanded virtual input"),
        Field.nested("wrench", WRENCH, "wrench of the clipped rotors"),
        Field.nested("rotor", ROTORS, "rotor forces, clipped"),
        Field("W_next", 4 * l, "-", "network weights after dt", shape=(l, 4)),
        Field("zeta_next", 4, ADAPTIVE_UNITS, "robust term estimate after dt"),
        Field("u_law", 4, ADAPTIVE_UNITS, "the law of eq. (20) at the measurements"),
        Field("n_clipped", 1, "-", "number of clipped rotors"),
        Field("tilt", 1, "-", "cos(theta1) cos(phi1)"),
    ), "results of control_step")


def control_step_function(l: int) -> ca.Function:
    """The sampled control step for ``l`` RBF nodes.

    ``control_step(xq, yv, ref, W_hat, zeta_hat, u_prev, p_quad, p_ctrl,
    rotor_limits, hold, dt) -> (u, wrench, rotor, W_next, zeta_next, u_law,
    n_clipped, tilt)``

    ``u_law`` is the law of eq. (20) at the measurements and ``u`` the
    commanded virtual input, ``u_law`` extrapolated by ``hold`` periods
    from ``u_prev`` (see the module's docstring); ``rotor`` the rotor
    forces of ``u`` clipped to ``rotor_limits = [F_min, F_max]`` (N) and
    ``wrench`` the wrench they produce; a NaN or infinite force (an
    overflow) is passed through unclipped, never replaced by a limit;
    ``n_clipped`` counts the clipped rotors;
    ``tilt = cos(theta1) cos(phi1)``, which the caller must keep away from
    zero (the thrust map divides by it).
    """
    ins = step_inputs(l)
    xq, yv, ref, W_hat, zeta_hat, u_prev, p_quad, p_ctrl, limits, hold, dt = ins.syms()
    c = controller_layout(l).unpack(p_ctrl)
    law = control_law(xq, yv, ref, W_hat, zeta_hat, p_quad, p_ctrl)
    u = law["u"] + hold * (law["u"] - u_prev)                              # hold compensation
    unclipped = rotors_from_wrench(wrench_from_virtual(xq, u, p_quad), p_quad)
    # Clip finite forces only: fmax(NaN, F_min) would be F_min, hiding an
    # overflow; a NaN or an infinity fails both tests and passes through.
    F_min, F_max = limits[0], limits[1]
    rotor = ca.if_else(ca.logic_and(unclipped < F_min, unclipped > -ca.inf), F_min,
                       ca.if_else(ca.logic_and(unclipped > F_max, unclipped < ca.inf), F_max,
                                  unclipped))
    n_clipped = ca.sum1(unclipped < F_min) + ca.sum1(unclipped > F_max)
    z2, Psi = law["bs_z2"], law["Psi"]
    a_w = ca.exp(-c["gamma1"] * c["k_w"] * dt)
    b_w = -ca.expm1(-c["gamma1"] * c["k_w"] * dt) / c["k_w"]             # (1 - a_w) / k_w
    a_z = ca.exp(-c["gamma2"] * c["k_zeta"] * dt)
    b_z = -ca.expm1(-c["gamma2"] * c["k_zeta"] * dt) / c["k_zeta"]
    W_next = a_w * W_hat + b_w * (Psi @ z2.T)                             # eq. 22, exact ZOH
    zeta_next = a_z * zeta_hat + b_z * (ca.tanh(z2 / c["rho"]) * z2)      # eq. 22, exact ZOH
    return ca.Function(
        "control_step",
        [xq, yv, ref, W_hat, zeta_hat, u_prev, p_quad, p_ctrl, limits, hold, dt],
        [u, wrench_from_rotors(rotor, p_quad), rotor, W_next, zeta_next, law["u"], n_clipped,
         tilt(QUAD_STATE.unpack(xq)["eta1"])],
        list(ins.names()), list(step_outputs(l).names()),
    )

"""The landing controller's sampled step: deck-frame backstepping over the paper's attitude loop.

The design is docs/landing.md's "The controller"; its choices are in
"Implementation". One step, from the measurements at ``t_k``:

1. **Outer loop** (deck frame, per axis, the paper's eq. 9-20 with ``R = I``):
   ``z1 = p_e - p_ref``, ``alpha = -k1p z1 + v_ref``, ``z2 = v_e - alpha``,
   ``alpha_dot`` by symbolic differentiation along ``(v_e, v_ref, a_ref)``;
   ``a_des = -k2p z2 - z1 - W_p^T Psi - tanh(z2_bar / rho) zeta_p + alpha_dot
   - f_g - nominal_model f_r``, where ``f_g`` is gravity in the deck frame
   (always fed forward: the thrust's direction is the attitude command) and
   ``f_r`` the rest of the known part ``f_p`` (drag, the deck's acceleration
   and the frame terms, by symbolic differentiation: :func:`known_acceleration`).
2. **Thrust vector to attitude**: ``t_E = m1 R_deck a_des``; collective thrust
   and desired body z with thrust and tilt limits, PX4's ``bodyzToAttitude``
   with the deck's heading (:mod:`quadland_symbolic.landing.attitude`).
3. **Saturation compensation** (Farrell et al. 2009): the limited thrust
   vector falls short of ``t_E`` by ``delta = R_deck^T (T b3 - t_E) / m1``;
   ``xi1' = -k1p xi1 + xi2``, ``xi2' = -k2p xi2 - xi1 + delta`` and the
   adaptive laws and the robust term of the outer channels see
   ``z2_bar = z2 - xi2``, so that they do not learn the limits.
   The bias estimates ``d_hat`` (integral action, docs/landing.md "Integral
   action") enter ``a_des`` and the inner law as ``- d_hat``.
4. **Command filter** per attitude command: ``x'' = w_f^2 (c - x) - 2 zeta_f
   w_f x'``; its state at ``t_k`` is the inner loop's ``e1d``, ``e1d_dot``
   and ``e1d_ddot = x''``.
5. **Inner loop**: the paper's eq. (9)-(20) on roll, pitch and yaw with
   ``e1 = eta1``, ``e2 = Omega1``, ``e1d = [phi_d, theta_d, psi2]``
   (:func:`quadland_symbolic.backstepping.virtual_control` for eq. 14, 18); moments
   ``M = I u``; with ``nominal_model = 1`` the drag and gyroscopic terms
   (:func:`quadland_symbolic.relative.nominal_drift`) are fed forward.
6. **Rotors**: ``T`` moved into the band where every rotor can make its share of
   the moments (attitude priority), then ``[T, M]`` through the mixer's
   inverse, clipped to ``[0, F_max]``; the compensator's ``delta`` uses this ``T``.
7. **Memory** over ``dt`` with the measurements held: the adaptive laws of
   eq. (22) for all six channels, the filter and the compensator, each
   integrated exactly (the latter two by the 2x2 matrix exponential,
   :func:`linear2_zoh`); the bias estimates ``d_hat' = ki_p z2_bar`` (outer)
   and ``ki z2`` (inner, not while a rotor clips; x, y within ``r_learn``), projected onto
   ``|d_hat_i| <= d_max``; the disturbance observer's ``v_hat, d_o, T_o``
   (:mod:`quadland_symbolic.landing.observer`), whose ``d_o`` ``a_des`` subtracts.

The network: ``W_hat`` is ``l x 6`` (deck-frame x, y, z; body roll, pitch,
yaw), its input ``vartheta = [v_e, Omega_e]`` (:data:`NETWORK_INPUT_DIM`).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.backstepping import virtual_control
from quadland_symbolic.kinematics import euler_rate_matrix, euler_rate_matrix_inv, rotation
from quadland_symbolic.landing import touchdown_policy as tdp
from quadland_symbolic.landing.attitude import thrust_attitude
from quadland_symbolic.landing.bias import learning_gate
from quadland_symbolic.landing.command_filter import command_filter, linear2_zoh
from quadland_symbolic.landing.deck import DECK_POSE, time_derivative
from quadland_symbolic.landing.deck_tilt import tilt_cues
from quadland_symbolic.landing.desaturation import clip_forces, clipped_count, thrust_within_moments
from quadland_symbolic.landing.guidance import (
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
    guidance_step,
)
from quadland_symbolic.landing.observer import OBSERVER_MEMORY, OBSERVER_PARAMS, estimates_next
from quadland_symbolic.landing.quadrotor import ACTUATOR, COMMAND, QUAD6_STATE
from quadland_symbolic.landing.relative import RELATIVE6, deck_gear_gap
from quadland_symbolic.landing.swerve import pad_swerve
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import WRENCH, rotors_from_wrench
from quadland_symbolic.rbf import rbf
from quadland_symbolic.relative import E1, nominal_drift, tilt

__all__ = [
    "N_CHANNELS",
    "NETWORK_INPUT_DIM",
    "LANDING_MEASUREMENT",
    "landing_controller_params",
    "landing_memory", "landing_step_outputs", "deck_rates",
    "known_acceleration",
    "known_acceleration_function",
    "landing_law", "landing_step_function",
    "landing_guidance", "landing_guidance_function", "measured_cues", "measured_cues_function",
]

#: Channels of the network: deck-frame x, y, z and body roll, pitch, yaw.
N_CHANNELS = 6
#: Size of the network's input vartheta = [v_e, Omega_e].
NETWORK_INPUT_DIM = 6

_CHANNEL_UNITS = ("m/s^2",) * 3 + ("rad/s^2",) * 3
#: The six channels' two groups: the outer loop's deck-frame axes, the inner loop's attitude.
_POSITION, _ATTITUDE = slice(0, 3), slice(3, N_CHANNELS)
#: The attitude entries of the paper's 4-vectors ``e1 = [z_e, phi_e, theta_e, psi_e]``.
_PAPER_ATTITUDE = slice(E1.index("phi_e"), E1.index("psi_e") + 1)
_CHANNEL_RATE_UNITS = ("m/s",) * 3 + ("rad/s",) * 3

#: What the step measures: the landing sensor (p_e, v_e, deck frame), the IMU
#: (eta1, Omega1) and the vehicle's broadcast (deck attitude, pad motion, deck
#: rotation in E; the fields of ``deck``'s outputs).
LANDING_MEASUREMENT = Layout("m_land", (
    RELATIVE6["p_e"],
    RELATIVE6["v_e"],
    QUAD6_STATE["eta1"],
    QUAD6_STATE["Omega1"],
    DECK_POSE["eta2"],
    DECK_POSE["v2E"],
    DECK_POSE["a2E"],
    DECK_POSE["w2E"],
    DECK_POSE["w2E_dot"],
), "landing controller measurements: landing sensor, IMU, vehicle broadcast")


@functools.cache
def landing_controller_params(l: int) -> Layout:
    """Layout of the landing controller's parameters for an ``l``-node network."""
    if l < 1:
        raise ValueError(f"RBF node count l must be >= 1, got {l}")
    xyz = ("x", "y", "z")
    att = ("phi", "theta", "psi")
    return Layout("p_land", (
        Field("k1p", 3, "1/s", "outer k1, deck-frame x, y, z (eq. 14)",
              elements=tuple(f"k1p_{a}" for a in xyz)),
        Field("k2p", 3, "1/s", "outer k2 (eq. 20)", elements=tuple(f"k2p_{a}" for a in xyz)),
        Field("k1", 3, "1/s", "inner k1, roll, pitch, yaw (eq. 14)",
              elements=tuple(f"k1_{a}" for a in att)),
        Field("k2", 3, "1/s", "inner k2 (eq. 20)", elements=tuple(f"k2_{a}" for a in att)),
        Field("gamma1", 1, "-", "Gamma1 = gamma1 I_l (eq. 22)"),
        Field("gamma2", 1, "-", "Gamma2 = gamma2 I_6 (eq. 22)"),
        Field("k_w", 1, "-", "leakage of W_hat (eq. 22)"),
        Field("k_zeta", 1, "-", "leakage of zeta_hat (eq. 22)"),
        Field("rho", 1, "-", "tanh smoothing width varrho (eq. 20)"),
        Field("nominal_model", 1, "0 or 1",
              "1 feeds forward the known drag, deck and frame terms and the gyroscopic terms"),
        Field("w_f", 1, "rad/s", "command filter natural frequency"),
        Field("zeta_f", 1, "-", "command filter damping ratio"),
        Field("tilt_max", 1, "rad", "largest tilt of the thrust axis, below pi/2"),
        Field("ki_p", 3, "1/s^2", "outer bias adaptation gain: d_hat_p' = ki_p z2_bar",
              elements=tuple(f"ki_p_{a}" for a in xyz)),
        Field("ki", 3, "1/s", "inner bias adaptation gain: d_hat_a' = ki z2",
              elements=tuple(f"ki_{a}" for a in att)),
        Field("d_max_p", 1, "m/s^2", "projection bound of each outer bias estimate"),
        Field("d_max", 1, "rad/s^2", "projection bound of each inner bias estimate"),
        Field("r_learn", 1, "m", "x, y's outer bias estimates learn within it (0: always)"),
        *OBSERVER_PARAMS.fields,
        Field("centers", NETWORK_INPUT_DIM * l, "-",
              "RBF centres mu_i as the columns of a 6 x l matrix (input [v_e, Omega_e])",
              shape=(NETWORK_INPUT_DIM, l)),
        Field("widths", l, "-", "RBF widths epsilon_i"),
    ), "landing controller parameters")


@functools.cache
def landing_memory(l: int) -> Layout:
    """Layout of what the step carries from one sample to the next."""
    return Layout("mem_land", (
        Field("W_hat", N_CHANNELS * l, "-", "network weights (eq. 22)", shape=(l, N_CHANNELS)),
        Field("zeta_hat", N_CHANNELS, _CHANNEL_UNITS, "robust term estimates (eq. 22)",
              elements=tuple(f"zeta_hat_{i + 1}" for i in range(N_CHANNELS))),
        Field("eta_f", 2, "rad", "command filter state: filtered roll and pitch",
              elements=("phi_f", "theta_f")),
        Field("eta_f_dot", 2, "rad/s", "command filter state: their rates",
              elements=("phi_f_dot", "theta_f_dot")),
        Field("xi1", 3, "m", "saturation compensator, position (deck frame)",
              elements=("xi1_x", "xi1_y", "xi1_z")),
        Field("xi2", 3, "m/s", "saturation compensator, velocity (deck frame)",
              elements=("xi2_x", "xi2_y", "xi2_z")),
        Field("d_hat", N_CHANNELS, _CHANNEL_UNITS,
              "bias estimates (integral action): deck-frame x, y, z; body roll, pitch, yaw",
              elements=tuple(f"d_hat_{i + 1}" for i in range(N_CHANNELS))),
        *OBSERVER_MEMORY.fields,
    ), "landing controller memory")


@functools.cache
def landing_step_outputs(l: int) -> Layout:
    """The step's results, in order (one field per result)."""
    return Layout("landing_step_out", (
        COMMAND["F_cmd"],
        Field.nested("wrench", WRENCH, "thrust T (limited) and moments, the mixer's input"),
        Field("eta_c", 3, "rad", "attitude command: the filter's input and psi2",
              elements=("phi_c", "theta_c", "psi_c")),
        Field("eta_d", 3, "rad", "inner loop reference e1d", elements=("phi_d", "theta_d",
                                                                      "psi_d")),
        Field("eta_d_dot", 3, "rad/s", "its rate", elements=("phi_d_dot", "theta_d_dot",
                                                            "psi_d_dot")),
        Field("eta_d_ddot", 3, "rad/s^2", "its acceleration",
              elements=("phi_d_ddot", "theta_d_ddot", "psi_d_ddot")),
        Field.nested("mem_next", landing_memory(l), "memory after dt"),
        Field("Delta_hat", N_CHANNELS, _CHANNEL_UNITS, "network estimate W_hat^T Psi (eq. 16)",
              elements=tuple(f"Delta_hat_{i + 1}" for i in range(N_CHANNELS))),
        Field("a_des", 3, "m/s^2", "desired thrust acceleration, deck frame, before limits",
              elements=("ax_des", "ay_des", "az_des")),
        Field("bs_z1", N_CHANNELS, ("m",) * 3 + ("rad",) * 3,
              "backstepping errors z1: p_e - p_ref, eta1 - e1d (eq. 9)",
              elements=tuple(f"bs_z1_{i + 1}" for i in range(N_CHANNELS))),
        Field("bs_z2", N_CHANNELS, _CHANNEL_RATE_UNITS,
              "backstepping errors z2 = e2 - alpha, uncompensated (eq. 9)",
              elements=tuple(f"bs_z2_{i + 1}" for i in range(N_CHANNELS))),
        Field("tilt", 1, "-", "cos(theta1) cos(phi1), measured"),
        Field("limits", 3, "-", "thrust limited (0/1), tilt limited (0/1), clipped rotors",
              elements=("thrust_limited", "tilt_limited", "n_clipped")),
    ), "results of landing_step")


# ---------------------------------------------------------------- deck kinematics

@functools.cache
def _deck_rates_function() -> ca.Function:
    eta2, w2E, w2E_dot = ca.SX.sym("eta2", 3), ca.SX.sym("w2E", 3), ca.SX.sym("w2E_dot", 3)
    eta2_dot = euler_rate_matrix(eta2) @ rotation(eta2).T @ w2E        # eq. 3: Rr2 Omega2
    eta2_ddot = time_derivative(eta2_dot, ca.vertcat(eta2, w2E),
                                ca.vertcat(eta2_dot, w2E_dot), ca.SX.sym("t"))
    return ca.Function("deck_rates", [eta2, w2E, w2E_dot], [eta2_dot, eta2_ddot])


def deck_rates(eta2, w2E, w2E_dot):
    """The deck's Euler-angle rates and accelerations from its angular motion in E.

    ``eta2_dot = Rr(eta2) R_deck^T w2E`` (eq. 3); ``eta2_ddot`` by symbolic
    differentiation along ``(eta2_dot, w2E_dot)``.
    """
    return tuple(_deck_rates_function()(eta2, w2E, w2E_dot))


@functools.cache
def known_acceleration_function() -> ca.Function:
    """``known_acceleration(p_e, v_e, eta1, eta2, v2E, a2E, w2E, w2E_dot, p_quad, Kq)
    -> (f_g, f_r)``: the known part ``f_p = f_g + f_r`` of ``p_e''`` (deck frame).

    ``p_e'' = a_T + f_p + d_p`` with ``a_T`` the thrust's acceleration. ``f_g``
    is gravity; ``f_r`` drag, the pad's acceleration and the frame terms. The
    frame terms come out of differentiating ``p1 - p2 = R_deck p_e`` twice
    along the deck's rotation (``R_deck' = S(w2E) R_deck``, here through
    ``eta2_dot``) with ``p_e'' = 0``, as :mod:`quadland_symbolic.landing.relative` does,
    never written by hand. The quadrotor's velocity for the drag is
    ``p1' = v2E + d/dt (R_deck p_e)``; the drag is eq. (2)'s ``Kt V1`` plus the body's
    quadratic drag ``Kq (V1 |V1|)`` (:mod:`quadland_symbolic.landing.aero`), both on the
    velocity over the ground: the law knows no wind.
    """
    p_e, v_e = ca.SX.sym("p_e", 3), ca.SX.sym("v_e", 3)
    eta1, eta2 = ca.SX.sym("eta1", 3), ca.SX.sym("eta2", 3)
    v2E, a2E = ca.SX.sym("v2E", 3), ca.SX.sym("a2E", 3)
    w2E, w2E_dot = ca.SX.sym("w2E", 3), ca.SX.sym("w2E_dot", 3)
    p_quad, Kq = QUADROTOR.sym(), ca.SX.sym("Kq", 3)
    q = QUADROTOR.unpack(p_quad)
    eta2_dot, _ = deck_rates(eta2, w2E, w2E_dot)
    x = ca.vertcat(eta2, p_e, v_e, w2E)
    x_dot = ca.vertcat(eta2_dot, v_e, ca.DM.zeros(3), w2E_dot)        # p_e'' = 0
    t = ca.SX.sym("t")
    R_deck, R1 = rotation(eta2), rotation(eta1)
    rel_dot = time_derivative(R_deck @ p_e, x, x_dot, t)               # (p1 - p2)'
    frame = time_derivative(rel_dot, x, x_dot, t)                      # (p1 - p2)'' at p_e'' = 0
    V1 = R1.T @ (v2E + rel_dot)                                        # body velocity
    drag = -R1 @ (q["Kt"] * V1 + Kq * V1 * ca.fabs(V1)) / q["m1"]      # eq. 2 and aero, in E
    f_g = R_deck.T @ ca.vertcat(0, 0, -q["g"])
    f_r = R_deck.T @ (drag - a2E - frame)
    return ca.Function("known_acceleration",
                       [p_e, v_e, eta1, eta2, v2E, a2E, w2E, w2E_dot, p_quad, Kq], [f_g, f_r],
                       ["p_e", "v_e", "eta1", "eta2", "v2E", "a2E", "w2E", "w2E_dot", "p_quad",
                        "Kq"], ["f_g", "f_r"])


def known_acceleration(p_e, v_e, eta1, eta2, v2E, a2E, w2E, w2E_dot, p_quad, Kq=None):
    """``(f_g, f_r)`` of :func:`known_acceleration_function` (``Kq`` None: no quadratic
    drag)."""
    Kq = ca.DM.zeros(3) if Kq is None else Kq
    return tuple(known_acceleration_function()(p_e, v_e, eta1, eta2, v2E, a2E, w2E, w2E_dot,
                                               p_quad, Kq))


# ---------------------------------------------------------------- the law

def landing_law(l, y, ref, mem, p_ctrl, p_quad, p_act, dt):
    """The step's expressions, a dict keyed by :func:`landing_step_outputs`' names.

    Parameters
    ----------
    l : int
        RBF node count.
    y, ref, mem, p_ctrl, p_quad, p_act, dt : casadi.SX
        :data:`LANDING_MEASUREMENT`, :data:`quadland_symbolic.landing.guidance.POSITION_REFERENCE`,
        :func:`landing_memory`, :func:`landing_controller_params`,
        :data:`~quadland_symbolic.parameters.QUADROTOR`,
        :data:`~quadland_symbolic.landing.quadrotor.ACTUATOR` and the period (s).
    """
    ms, rs = LANDING_MEASUREMENT.unpack(y), POSITION_REFERENCE.unpack(ref)
    mm, c = landing_memory(l).unpack(mem), landing_controller_params(l).unpack(p_ctrl)
    q, act = QUADROTOR.unpack(p_quad), ACTUATOR.unpack(p_act)
    p_e, v_e, Omega1, eta2 = ms["p_e"], ms["v_e"], ms["Omega1"], ms["eta2"]
    td = tdp.bounded_commands(rs, c["tilt_max"])              # the touchdown policy
    # the yaw within half a turn of the deck's heading, its reference (2 pi k away: the same)
    yaw_error = ms["eta1"][2] - eta2[2]
    eta1 = ca.vertcat(ms["eta1"][0:2], eta2[2] + ca.atan2(ca.sin(yaw_error), ca.cos(yaw_error)))
    W_hat, zeta_hat = mm["W_hat"], mm["zeta_hat"]
    m1, rho, nominal, k1p, k2p = q["m1"], c["rho"], c["nominal_model"], c["k1p"], c["k2p"]
    R_deck = rotation(eta2)
    eta2_dot, eta2_ddot = deck_rates(eta2, ms["w2E"], ms["w2E_dot"])

    # network (eq. 16): six channels on the relative velocities and rates
    Omega_e = Omega1 - euler_rate_matrix_inv(eta1) @ eta2_dot                   # eq. 5
    Psi = rbf(ca.vertcat(v_e, Omega_e), c["centers"], c["widths"])
    Delta_hat = W_hat.T @ Psi                                                  # eq. 16

    # outer loop: the paper's backstepping per deck-frame axis (R = I)
    ref = tdp.aim_reference(ref, td["pivot"], eta1, eta2)   # ahead of the level-out's pivot
    z1p = p_e - ref[0:3]                                                       # eq. 9
    alpha_p, alpha_p_dot = _outer_virtual_control(p_e, v_e, ref, k1p)          # eq. 14, 18
    z2p = v_e - alpha_p                                                        # eq. 9
    z2p_bar = z2p - mm["xi2"]                                                  # compensated
    squash_p = ca.tanh(z2p_bar / rho)
    f_g, f_r = known_acceleration(p_e, v_e, eta1, eta2, ms["v2E"], ms["a2E"], ms["w2E"],
                                  ms["w2E_dot"], p_quad, act["drag_quadratic"])
    a_des = (-k2p * z2p - z1p - Delta_hat[_POSITION] - squash_p * zeta_hat[_POSITION] + alpha_p_dot
             - f_g - nominal * f_r - mm["d_hat"][_POSITION] - mm["d_o"])       # eq. 20, bias
    t_E = m1 * R_deck @ a_des                                                  # N, in E
    th = thrust_attitude(t_E, eta2[2], td["tilt_limit"], 4 * act["F_max"], tdp.cone_of(td, R_deck))

    # command filter (its state is the inner loop's reference); the touchdown policy levels
    eta_c = tdp.apply_touchdown_commands(td["level"], ca.vertcat(th["phi"], th["theta"]), eta2[:2])
    eta_f, eta_f_dot = mm["eta_f"], mm["eta_f_dot"]
    eta_f_next, eta_f_dot_next, eta_f_ddot = command_filter(eta_f, eta_f_dot, eta_c, c["w_f"],
                                                            c["zeta_f"], dt)
    e1d = ca.vertcat(eta_f, eta2[2])
    e1d_dot = ca.vertcat(eta_f_dot, eta2_dot[2])
    e1d_ddot = ca.vertcat(eta_f_ddot, eta2_ddot[2])

    z1a, z2a, squash_a, u_a = _inner_loop(eta1, Omega1, (e1d, e1d_dot, e1d_ddot), c,
                                          Delta_hat[_ATTITUDE] + mm["d_hat"][_ATTITUDE],
                                          zeta_hat[_ATTITUDE], p_quad)

    # rotors: the moments first, the collective thrust within what they leave
    T = thrust_within_moments(td["thrust_scale"] * th["T"], q["I"] * u_a, p_quad, act["F_max"],
                              td["airmode"])
    delta = R_deck.T @ (T * th["b3"] - t_E) / m1                               # limits' shortfall
    wrench = ca.vertcat(T, q["I"] * u_a)
    unclipped = rotors_from_wrench(wrench, p_quad)
    F_cmd = td["power"] * clip_forces(unclipped, 0, act["F_max"])
    n_clipped = clipped_count(unclipped, act["F_max"])

    # memory over dt, measurements held
    mem_next = _memory_next(mm, c, Psi, ca.vertcat(z2p_bar, z2a), ca.vertcat(squash_p, squash_a),
                            delta, eta_f_next, eta_f_dot_next, dt)
    mem_next = ca.vertcat(mem_next, estimates_next(                 # x, y within r_learn
        mm, c, ca.vertcat(learning_gate(z1p, c["r_learn"]) * z2p_bar, z2a), n_clipped, v_e,
        (R_deck.T @ rotation(eta1)[:, 2], m1),
        f_g + nominal * f_r, F_cmd, act, dt))
    return dict(
        F_cmd=F_cmd, wrench=wrench, eta_c=ca.vertcat(eta_c, eta2[2]),
        eta_d=e1d, eta_d_dot=e1d_dot, eta_d_ddot=e1d_ddot, mem_next=mem_next,
        Delta_hat=Delta_hat, a_des=a_des, bs_z1=ca.vertcat(z1p, z1a),
        bs_z2=ca.vertcat(z2p, z2a), tilt=tilt(eta1),
        limits=ca.vertcat(th["thrust_limited"], th["tilt_limited"], n_clipped))


def _inner_loop(eta1, Omega1, e1d_all, c, Delta_a, zeta_a, p_quad):
    """The paper's attitude channels (its altitude slot stays empty).

    ``e1d_all`` is the filtered attitude reference and its two derivatives;
    returns ``z1a, z2a, tanh(z2a / rho)`` and the angular acceleration
    command ``u_a`` (eq. 9, 14, 18, 20).
    """
    e1d, e1d_dot, e1d_ddot = e1d_all
    rho, nominal = c["rho"], c["nominal_model"]
    Rr1 = euler_rate_matrix(eta1)
    alpha, alpha_dot = virtual_control(                                        # eq. 14, 18
        ca.vertcat(0, eta1), ca.vertcat(0, Rr1 @ Omega1),
        ca.vertcat(0, e1d, 0, e1d_dot, 0, e1d_ddot), ca.vertcat(0, c["k1"]))
    z1a = eta1 - e1d                                                           # eq. 9
    z2a = Omega1 - alpha[_PAPER_ATTITUDE]                                      # eq. 9
    squash_a = ca.tanh(z2a / rho)
    # the paper's xq = [z1, eta1, V1, Omega1]: its rotational drift reads eta1 and Omega1 only
    xq = ca.vertcat(0, eta1, ca.SX.zeros(3), Omega1)
    f_a = nominal_drift(xq, p_quad)[_PAPER_ATTITUDE]                          # drag, gyroscopic
    u_a = (-c["k2"] * z2a - Rr1.T @ z1a - Delta_a - squash_a * zeta_a
           + alpha_dot[_PAPER_ATTITUDE] - nominal * f_a)                       # eq. 20
    return z1a, z2a, squash_a, u_a


def _memory_next(mm, c, Psi, z2, squash, delta, eta_f_next, eta_f_dot_next, dt):
    """The step's memory at ``t + dt``: the adaptive laws (eq. 22) integrated exactly over
    the period with ``z2`` held (zero-order hold), the command filter's new state, and
    the command-filter compensation ``xi`` (a linear system driven by the limits'
    shortfall ``delta``), each axis integrated exactly too."""
    k1p, k2p = c["k1p"], c["k2p"]
    a_w = ca.exp(-c["gamma1"] * c["k_w"] * dt)
    b_w = -ca.expm1(-c["gamma1"] * c["k_w"] * dt) / c["k_w"]                  # (1 - a_w) / k_w
    a_z = ca.exp(-c["gamma2"] * c["k_zeta"] * dt)
    b_z = -ca.expm1(-c["gamma2"] * c["k_zeta"] * dt) / c["k_zeta"]
    W_next = a_w * mm["W_hat"] + b_w * (Psi @ z2.T)                            # eq. 22, exact ZOH
    zeta_next = a_z * mm["zeta_hat"] + b_z * (squash * z2)                     # eq. 22, exact ZOH
    xi = [linear2_zoh(ca.vertcat(mm["xi1"][i], mm["xi2"][i]),
                      ca.vertcat(ca.horzcat(-k1p[i], 1), ca.horzcat(-1, -k2p[i])),
                      ca.vertcat(0, delta[i]), dt) for i in range(3)]
    return ca.vertcat(ca.vec(W_next), zeta_next, eta_f_next, eta_f_dot_next,
                      *[x[0] for x in xi], *[x[1] for x in xi])


def _outer_virtual_control(p_e, v_e, ref, k1p):
    """alpha = -k1p (p_e - p_ref) + v_ref (eq. 14, R = I) and its time derivative
    (eq. 18) along ``(v_e, v_ref, a_ref)``, by symbolic differentiation."""
    p_es, refs, k1s = ca.SX.sym("p_e", 3), POSITION_REFERENCE.sym(), ca.SX.sym("k1p", 3)
    v_es = ca.SX.sym("v_e", 3)
    r = POSITION_REFERENCE.unpack(refs)
    alpha = -k1s * (p_es - r["p_ref"]) + r["v_ref"]
    alpha_dot = ca.jtimes(alpha, ca.vertcat(p_es, r["p_ref"], r["v_ref"]),
                          ca.vertcat(v_es, r["v_ref"], r["a_ref"]))
    fn = ca.Function("outer_virtual_control", [p_es, v_es, refs, k1s], [alpha, alpha_dot])
    return fn(p_e, v_e, ref, k1p)


def landing_step_function(l: int) -> ca.Function:
    """The landing controller's sampled step for ``l`` RBF nodes.

    ``landing_step(y, ref, mem, p_ctrl, p_quad, p_act, dt) -> (F_cmd, wrench,
    eta_c, eta_d, eta_d_dot, eta_d_ddot, mem_next, Delta_hat, a_des, bs_z1,
    bs_z2, tilt, limits)``

    Inputs: the measurements ``y`` (:data:`LANDING_MEASUREMENT`), the guidance's
    reference ``ref`` (:data:`quadland_symbolic.landing.guidance.POSITION_REFERENCE`), the memory
    ``mem`` (:func:`landing_memory`), the parameters ``p_ctrl``
    (:func:`landing_controller_params`), ``p_quad``
    (:data:`~quadland_symbolic.parameters.QUADROTOR`), ``p_act``
    (:data:`~quadland_symbolic.landing.quadrotor.ACTUATOR`) and the period ``dt`` (s).
    Outputs: :func:`landing_step_outputs`. ``F_cmd`` is clipped to
    ``[0, F_max]`` (a NaN passes through); ``tilt`` is the measured
    ``cos(theta1) cos(phi1)``: the attitude loop's ``Rr1`` is singular at
    ``theta1 = +-pi/2``.
    """
    names_in = ["y", "ref", "mem", "p_ctrl", "p_quad", "p_act", "dt"]
    args = [LANDING_MEASUREMENT.sym(), POSITION_REFERENCE.sym(), landing_memory(l).sym(),
            landing_controller_params(l).sym(), QUADROTOR.sym(), ACTUATOR.sym(),
            ca.SX.sym("dt")]
    out = landing_law(l, *args)
    names_out = list(landing_step_outputs(l).names())
    return ca.Function("landing_step", args, [out[n] for n in names_out], names_in, names_out)


def measured_cues(y, p_guid):
    """The guidance's cues on perfect sensing: the measured gear gap, the marker always seen.

    ``touchdown`` is 1 when the gear gap from ``p_e``, ``eta1`` and ``eta2``
    (:func:`~quadland_symbolic.landing.relative.deck_gear_gap`, the gear
    ``touchdown_height`` below the centre) is zero or below; the others 0 (the loop's switch).
    Returns :data:`quadland_symbolic.landing.guidance.GUIDANCE_CUES`.
    """
    ms = LANDING_MEASUREMENT.unpack(y)
    h = GUIDANCE_PARAMS.unpack(p_guid)["touchdown_height"]
    gap = deck_gear_gap(ms["p_e"], rotation(ms["eta2"]), rotation(ms["eta1"]), h)
    return ca.vertcat(gap <= 0, 0, 0)


@functools.cache
def measured_cues_function() -> ca.Function:
    """``landing_cues(y, p_guid) -> cues``: :func:`measured_cues`."""
    y, p_guid = LANDING_MEASUREMENT.sym(), GUIDANCE_PARAMS.sym()
    return ca.Function("landing_cues", [y, p_guid], [measured_cues(y, p_guid)],
                       ["y", "p_guid"], ["cues"])


def landing_guidance(xg, y, cues, dt, p_guid):
    """One guidance step on the step's measurements and the flight stack's cues.

    The step is :func:`~quadland_symbolic.landing.guidance.guidance_step`: the
    relative position and velocity are the measurement's, the deck's rise is the
    pad velocity's vertical component ``v2E[2]`` and its rate the acceleration's
    ``a2E[2]``, ``cues`` (:data:`quadland_symbolic.landing.guidance.GUIDANCE_CUES`) the
    touchdown verdict and the marker's age (:func:`measured_cues` on perfect sensing), the
    deck tilt's cues the measurement's (:func:`~.deck_tilt.tilt_cues`), the pad's swerve
    its ``a2E``'s horizontal magnitude (:func:`~.swerve.pad_swerve`). Returns ``(xg_next,
    reference)``."""
    ms = LANDING_MEASUREMENT.unpack(y)
    return guidance_step(xg, ms["p_e"], ms["v_e"], ms["v2E"][2], ms["a2E"][2], cues, dt,
                         p_guid, tilt_cues(ms["eta1"], ms["eta2"], ms["w2E"], ms["w2E_dot"]),
                         pad_swerve(ms["a2E"]))


@functools.cache
def landing_guidance_function() -> ca.Function:
    """``landing_guidance(xg, y, cues, dt, p_guid) -> (xg_next, ref)``: :func:`landing_guidance`.

    ``xg``: :data:`quadland_symbolic.landing.guidance.GUIDANCE_STATE`;
    ``y``: :data:`LANDING_MEASUREMENT`; ``cues``:
    :data:`quadland_symbolic.landing.guidance.GUIDANCE_CUES`;
    ``p_guid``: :data:`quadland_symbolic.landing.guidance.GUIDANCE_PARAMS`; ``ref``:
    :data:`quadland_symbolic.landing.guidance.POSITION_REFERENCE`, the landing step's.
    """
    xg, y, cues = GUIDANCE_STATE.sym(), LANDING_MEASUREMENT.sym(), GUIDANCE_CUES.sym()
    dt, p_guid = ca.SX.sym("dt"), GUIDANCE_PARAMS.sym()
    xg_next, ref = landing_guidance(xg, y, cues, dt, p_guid)
    return ca.Function("landing_guidance", [xg, y, cues, dt, p_guid], [xg_next, ref],
                       ["xg", "y", "cues", "dt", "p_guid"], ["xg_next", "ref"])



"""The navigation filter's model: prediction and measurements.

State, packets, parameters, prediction, measurement blocks, outputs.

docs/estimator.md gives the design and the equations (E1)-(E14) cited here. Frame E
has z up. The filter's state :data:`NAV` is PX4's moving-target vision target
estimator's (relative position, the vehicle's and the pad's velocities, the pad's
acceleration, the relative GNSS bias) plus the two biases of the acceleration input,
which quadland forms from the raw accelerometer through an attitude estimate: ``a_b``
(the accelerometer's) and ``a_tilt`` (the attitude's tilt error times g, which the
camera's vector shares) (E1).

The sequencing (delayed horizon, FIFOs, output predictor) is in
:mod:`quadland_symbolic.landing.estimator`; this module holds what one prediction and
one measurement block compute.
"""

from __future__ import annotations

import dataclasses
import functools
import types

import casadi as ca
import numpy as np

from quadland_symbolic.kalman import (
    CovariancePattern,
    block_nis,
    is_finite,
    nilpotent_discretization,
    scalar_update,
    select,
)
from quadland_symbolic.kinematics import rotation, skew
from quadland_symbolic.landing.controller import deck_rates
from quadland_symbolic.landing.correlated_noise import heading_share, memory_count, project_row
from quadland_symbolic.landing.heave import HEAVE_DEFAULTS, HEAVE_FIELDS, heave_transition
from quadland_symbolic.layout import Field, Layout

__all__ = ["NAV", "IMU", "VISION", "GNSS", "RANGE", "DATALINK", "DECK_INIT", "NAV_PACKETS",
           "SENSORS", "Block", "BLOCKS", "COUPLINGS", "estimator_params", "ESTIMATOR_DEFAULTS",
           "covariance_pattern", "acceleration_input", "axis_dynamics", "nav_transition",
           "nav_transition_function", "nav_predict", "nav_predict_function",
           "measurement_model_function", "block_update", "nav_update_function", "deck_at",
           "relative_output"]

_XYZ = ("x", "y", "z")


def _vec3(name: str, unit: str, doc: str) -> Field:
    return Field(name, 3, unit, doc, elements=tuple(f"{name}_{a}" for a in _XYZ))


def _flag(doc: str) -> Field:
    return Field("fresh", 1, "0 or 1", doc)


def _tau(doc: str = "sample time (capture, not arrival)") -> Field:
    return Field("tau", 1, "s", doc)


#: The filter's state (E1); every vector in E.
NAV = Layout("nav", (
    _vec3("p_r", "m", "quadrotor centre minus pad centre"),
    _vec3("v1", "m/s", "quadrotor velocity"),
    _vec3("v_t", "m/s", "pad centre velocity"),
    _vec3("a_t", "m/s^2", "pad centre acceleration (random walk)"),
    _vec3("b", "m", "relative GNSS bias: GNSS-measured (p_pad - p1) minus the true one"),
    _vec3("a_b", "m/s^2", "the accelerometer's bias, body-fixed, in E (random walk)"),
    _vec3("a_tilt", "m/s^2", "bias of the acceleration input from the attitude estimate's "
          "tilt error eps: g eps x e_z (Gauss-Markov; z is 0)"),
), "navigation filter state, frame E (z up)")

#: The IMU's sample of this period (no flag: every period).
IMU = Layout("imu", (
    Field("eta_hat", 3, "rad", "attitude estimate, ZYX", elements=("phi_hat", "theta_hat",
                                                                  "psi_hat")),
    _vec3("f_b", "m/s^2", "accelerometer specific force, body frame"),
    _vec3("omega", "rad/s", "gyro rates, body frame"),
), "IMU and attitude estimate of the current period")

#: Marker detection, already rotated into E with the attitude estimate at capture.
VISION = Layout("vision", (
    _flag("1 when a new detection arrived this period"), _tau(),
    _vec3("r_E", "m", "pad centre minus camera (body origin), E"),
), "vision packet")

#: The two GNSS receivers' relative position and both velocities.
GNSS = Layout("gnss", (
    _flag("1 when a new GNSS epoch arrived this period"), _tau(),
    _vec3("rel", "m", "target receiver minus quadrotor receiver position, E"),
    _vec3("v1", "m/s", "quadrotor receiver velocity, E"),
    _vec3("vt", "m/s", "target receiver velocity, E"),
), "GNSS packet")

#: Range finder along the body's -z axis to the deck plane.
RANGE = Layout("range", (
    _flag("1 when a new range arrived this period"), _tau(),
    Field("s", 1, "m", "distance along -b3 from the body origin to the deck plane"),
    _vec3("b3_E", "-", "body z axis in E from the attitude estimate at capture"),
), "range finder packet")

#: The vehicle's broadcast of its own INS.
DATALINK = Layout("datalink", (
    _flag("1 when a new broadcast arrived this period"), _tau(),
    Field("eta2", 3, "rad", "deck attitude, ZYX", elements=("phi2", "theta2", "psi2")),
    _vec3("v2E", "m/s", "pad centre velocity, E"),
    _vec3("a2E", "m/s^2", "pad centre acceleration, E"),
    _vec3("w2E", "rad/s", "deck angular velocity, E"),
    _vec3("w2E_dot", "rad/s^2", "deck angular acceleration, E"),
), "datalink packet")

#: The deck's rotation the filter assumes before the first broadcast.
DECK_INIT = Layout("deck0", DATALINK.fields[2:3] + DATALINK.fields[5:7],
                   "deck attitude and rotation at handover")

#: Packet layouts in fusion order; the layout's name is the sensor's.
NAV_PACKETS = (VISION, GNSS, RANGE, DATALINK)
SENSORS = tuple(p.name for p in NAV_PACKETS)

COUPLINGS = ("full", "axes")


@dataclasses.dataclass(frozen=True)
class Block:
    """One gated measurement block: a packet field and its model.

    Attributes
    ----------
    name : str
        Block name (``vision``, ``gnss_rel`` ...).
    sensor : str
        Its packet (:data:`SENSORS`).
    field : str
        The packet field measured.
    dim : int
        Number of scalar measurements.
    gate : float
        Default NIS threshold: the chi-square 99 % quantile for ``dim``.
    """

    name: str
    sensor: str
    field: str
    dim: int
    gate: float


_CHI2_99 = {1: 6.634897, 3: 11.344867}     # scipy.stats.chi2.ppf(0.99, k), tested

#: The measurement blocks in fusion order (E10)-(E14).
BLOCKS = (
    Block("vision", "vision", "r_E", 3, _CHI2_99[3]),
    Block("gnss_rel", "gnss", "rel", 3, _CHI2_99[3]),
    Block("gnss_v1", "gnss", "v1", 3, _CHI2_99[3]),
    Block("gnss_vt", "gnss", "vt", 3, _CHI2_99[3]),
    Block("range", "range", "s", 1, _CHI2_99[1]),
    Block("datalink_v", "datalink", "v2E", 3, _CHI2_99[3]),
    Block("datalink_a", "datalink", "a2E", 3, _CHI2_99[3]),
)

#: Default parameter values; docs/estimator.md cites each one's source.
ESTIMATOR_DEFAULTS = types.MappingProxyType(dict(
    g=9.8, q_acc=[0.02] * 3, q_at=[0.1] * 3, q_b=[0.001] * 3, q_ab=[1e-3] * 3,
    tilt_sigma=[0.0855, 0.0855, 0.0], tilt_tau=5.0, tilt_levels_bias=[0.0, 0.0, 0.0],
    vision_sigma0=0.1, vision_k_range=0.02, vision_heading_sigma=0.0,
    gnss_rel_sigma=[0.5] * 3, gnss_v1_sigma=[0.3] * 3, gnss_vt_sigma=[0.3] * 3,
    range_sigma=0.05, range_k_range=0.0, range_min_cos=0.7, range_deck_radius=0.5,
    range_deck_sigmas=2.0, datalink_v_sigma=[0.1] * 3, datalink_a_sigma=[0.3] * 3,
    **{f"gate_{b.name}": b.gate for b in BLOCKS},
    gate_lockout=10.0,
    **{f"max_age_{s}": 0.02 for s in SENSORS},
    deck_extrapolation_max=0.5, **HEAVE_DEFAULTS,
))


@functools.cache
def estimator_params() -> Layout:
    """Layout of the filter's parameters.

    Noise densities, sigmas, gates, ages; defaults :data:`ESTIMATOR_DEFAULTS`.
    """
    return Layout("p_est", (
        Field("g", 1, "m/s^2", "gravitational acceleration"),
        _vec3("q_acc", "m^2/s^3", "PSD of the acceleration input's white noise, per axis"),
        _vec3("q_at", "m^2/s^5", "PSD of the pad acceleration's random walk, per axis"),
        _vec3("q_b", "m^2/s", "PSD of the relative GNSS bias' random walk, per axis"),
        _vec3("q_ab", "m^2/s^5", "PSD of the accelerometer bias' random walk, per axis"),
        _vec3("tilt_sigma", "m/s^2", "stationary standard deviation of the tilt bias, per "
              "axis (z: 0)"),
        Field("tilt_tau", 1, "s", "correlation time of the tilt bias (first-order Gauss-Markov)"),
        _vec3("tilt_levels_bias", "-", "share of the input bias a_b that the attitude's tilt "
              "levels, per axis (E2b): a_tilt = -l a_b + the residual of tilt_sigma, tilt_tau"),
        Field("vision_sigma0", 1, "m", "vision noise at zero range (E10)"),
        Field("vision_k_range", 1, "-", "vision noise growth per metre of range (E10)"),
        Field("vision_heading_sigma", 1, "rad", "standard deviation of the attitude "
              "estimate's heading error that rotates the vision's vector (E10c)"),
        _vec3("gnss_rel_sigma", "m", "relative GNSS position noise"),
        _vec3("gnss_v1_sigma", "m/s", "quadrotor GNSS velocity noise"),
        _vec3("gnss_vt_sigma", "m/s", "target GNSS velocity noise"),
        Field("range_sigma", 1, "m", "range finder noise at zero range (E12)"),
        Field("range_k_range", 1, "-", "range finder noise growth per metre of range (E12)"),
        Field("range_min_cos", 1, "-", "smallest n2 . b3_E of a usable range (E12)"),
        Field("range_deck_radius", 1, "m", "largest distance from the pad centre of the "
              "beam's predicted deck point of a usable range (E12a)"),
        Field("range_deck_sigmas", 1, "-", "standard deviations of the horizontal position "
              "the beam's deck point must lie within range_deck_radius by (E12a)"),
        _vec3("datalink_v_sigma", "m/s", "broadcast pad velocity noise"),
        _vec3("datalink_a_sigma", "m/s^2", "broadcast pad acceleration noise"),
        *[Field(f"gate_{b.name}", 1, "-", f"NIS threshold of the {b.name} block (E8)")
          for b in BLOCKS],
        Field("gate_lockout", 1, "-", "consecutive gate refusals of a block after which its "
              "next one is fused with the covariance inflated to admit it (E8a)"),
        *[Field(f"max_age_{s}", 1, "s", f"oldest {s} sample fused, before the horizon")
          for s in SENSORS],
        Field("deck_extrapolation_max", 1, "s", "longest extrapolation of the broadcast (E7)"),
        *HEAVE_FIELDS,
    ), "navigation filter parameters")


@functools.cache
def covariance_pattern(coupling: str = "full") -> CovariancePattern:
    """The stored covariance entries of a coupling.

    ``full``: 171 entries; ``axes``: x, y, z decoupled, 63 (E9a).
    """
    if coupling == "full":
        return CovariancePattern.full(NAV.size)
    if coupling == "axes":
        nf = len(NAV.fields)
        return CovariancePattern(NAV.size, tuple(tuple(3 * f + a for f in range(nf))
                                                 for a in range(3)))
    raise ValueError(f"coupling must be one of {COUPLINGS}, got {coupling!r}")


# ---------------------------------------------------------------- prediction

def axis_dynamics(x7, a_in):
    """One axis of (E2) without its noise, ``d/dt [p_r, v1, v_t, a_t, b, a_b, a_tilt]``: the
    target's acceleration and the biases are random walks, ``a_tilt`` held (E2a)."""
    _, v1, v_t, a_t, _, a_b, a_tilt = ca.vertsplit(x7)
    return ca.vertcat(v1 - v_t, a_in - a_b - a_tilt, a_t, 0, 0, 0, 0)


#: One axis' ``A7 = df/dx``, ``B7 = df/da_in`` by ``ca.jacobian`` (constants: it is linear).
_x7, _a_in = ca.SX.sym("x", 7), ca.SX.sym("a_in")
_A7, _B7 = (np.array(ca.evalf(ca.jacobian(axis_dynamics(_x7, _a_in), v))) for v in (_x7, _a_in))


def acceleration_input(eta_hat, f_b, g):
    """The quadrotor's acceleration in E from the IMU (E2).

    ``a_in = R(eta_hat) f_b - g e_z``.
    """
    return rotation(eta_hat) @ f_b - ca.vertcat(0, 0, g)


def nav_transition(dt, p_est):
    """``(Phi, Gamma, Q)`` of (E2) over ``dt`` (E2a), (E2b), (E3)-(E5).

    Sizes 21 x 21, 21 x 3, 21 x 21: one axis' 7 x 7 discretization
    (:func:`~quadland_symbolic.kalman.nilpotent_discretization`, ``a_tilt`` held, taking
    ``-l`` times ``a_b``'s random walk, ``l = tilt_levels_bias``) on x, y and z, as
    ``kron(M7, I3)`` and ``sum_a kron(Q7_a, e_a e_a^T)``; then the residual ``a_tilt + l
    a_b`` decays as a sampled Gauss-Markov process (E2a): ``Phi = D Phi_held``, ``Q = D
    Q_held D^T + tilt_sigma^2 (1 - e^(-2 dt / tilt_tau))`` on ``a_tilt``, ``D[a_tilt,
    a_tilt] = e^(-dt / tilt_tau)``, ``D[a_tilt, a_b] = (e^(-dt / tilt_tau) - 1) l``."""
    p = estimator_params().unpack(p_est)
    I3, Q, Qr, D = ca.DM.eye(3), ca.SX(NAV.size, NAV.size), ca.SX(NAV.size, NAV.size), \
        ca.SX.eye(NAV.size)
    decay = ca.exp(-dt / p["tilt_tau"])                                      # (E2a)
    i, j = NAV.slice("a_tilt").start, NAV.slice("a_b").start
    for a in range(3):
        l, q_ab = p["tilt_levels_bias"][a], p["q_ab"][a]
        W7 = ca.SX(ca.diag(ca.vertcat(0, p["q_acc"][a], 0, p["q_at"][a], p["q_b"][a], q_ab, 0)))
        W7[5, 6], W7[6, 5], W7[6, 6] = -l * q_ab, -l * q_ab, l * l * q_ab   # a_b, a_tilt (E2b)
        Phi7, Gamma7, Q7 = nilpotent_discretization(_A7, _B7, W7, dt)
        Q += ca.kron(Q7, I3[:, a] @ I3[a, :])
        D[i + a, i + a], D[i + a, j + a] = decay, (decay - 1) * l
        Qr[i + a, i + a] = p["tilt_sigma"][a] ** 2 * (1 - decay**2)
    return D @ ca.kron(Phi7, I3), ca.kron(Gamma7, I3), D @ Q @ D.T + Qr


@functools.cache
def nav_transition_function() -> ca.Function:
    """``nav_transition(dt, p_est) -> (Phi, Gamma, Q)`` (E3)-(E5)."""
    dt, p = ca.SX.sym("dt"), estimator_params().sym()
    return ca.Function("nav_transition", [dt, p], list(nav_transition(dt, p)),
                       ["dt", "p_est"], ["Phi", "Gamma", "Q"])


def nav_predict(x, P, a_in, dt, p_est, pattern: CovariancePattern, turn=None, omega=None):
    """One prediction over ``dt`` (E6): ``x+ = Phi x + Gamma a_in``, ``P+ = Phi P Phi^T + Q``
    on ``pattern``'s entries; ``turn`` (E, rad) turns ``a_b`` (E6a), ``omega`` the pad (E17b)."""
    Phi, Gamma, Q = nav_transition(dt, p_est)
    if turn is not None:                                                    # (E6a)
        i, k = NAV.slice("a_b"), NAV.slice("a_tilt")
        Phi[i, i] = ca.DM.eye(3) + skew(turn)       # the levelled share turns with it (E2b)
        Phi[k, i] -= ca.diag(estimator_params().unpack(p_est)["tilt_levels_bias"]) @ skew(turn)
    if omega is not None:                                                   # (E17b)
        Phi = heave_transition(Phi, omega, dt, *(NAV.slice(f).start + 2
                                                         for f in ("p_r", "v_t", "a_t")))
    return Phi @ x + Gamma @ a_in, pattern.unpack(pattern.pack(Phi @ P @ Phi.T + Q))


@functools.cache
def nav_predict_function(coupling: str = "full") -> ca.Function:
    """``nav_predict(x, P, a_in, dt, p_est, turn) -> (x_next, P_next)``.

    (E6), (E6a). ``P`` and ``P_next`` are full symmetric 21 x 21 matrices; only the upper
    triangle of the entries :func:`covariance_pattern` keeps is read.
    """
    pattern = covariance_pattern(coupling)
    x, P = NAV.sym("x"), ca.SX.sym("P", NAV.size, NAV.size)
    a_in, dt, turn = ca.SX.sym("a_in", 3), ca.SX.sym("dt"), ca.SX.sym("turn", 3)
    p = estimator_params().sym()
    Ps = pattern.unpack(pattern.pack(P))
    x_next, P_next = nav_predict(x, Ps, a_in, dt, p, pattern, turn)
    return ca.Function("nav_predict", [x, P, a_in, dt, p, turn], [x_next, ca.densify(P_next)],
                       ["x", "P", "a_in", "dt", "p_est", "turn"], ["x_next", "P_next"])


# ---------------------------------------------------------------- measurements

def _model(block: Block, nav, pkt, n2, p):
    """``(z, h, r, valid)`` of one block (E10)-(E13)."""
    z = pkt[block.field]
    ones = ca.DM.ones(3)
    if block.name == "vision":                                               # (E10)
        sigma = p["vision_sigma0"] + p["vision_k_range"] * ca.norm_2(z)
        # the tilt rotates the vector: eps x r_E = (r_E_z / g) a_tilt for a pad below
        # (E10); a non-finite packet, never fused, must not make the row non-finite
        lever = select(is_finite(z[2]), z[2], 0) / p["g"]
        shared = heading_share(z, p["vision_heading_sigma"])             # (E10c)
        return z, -nav["p_r"] + lever * nav["a_tilt"], sigma**2 * ones + shared, 1
    if block.name == "range":                                                # (E12)
        cos_b = n2.T @ pkt["b3_E"]
        steep = cos_b >= p["range_min_cos"]
        c = select(steep, cos_b, 1)
        # the tilt turns the beam (E12b): true n2 . b3 = cos_b - eps . (b3_E x n2), eps_x,
        # eps_y = -a_tilt_y / g, a_tilt_x / g; a non-finite packet's row stays finite
        w = [select(is_finite(wi), wi, 0) for wi in ca.vertsplit(ca.cross(pkt["b3_E"], n2))]
        s = select(is_finite(z), z, 0)
        h = (n2.T @ nav["p_r"]) / c + s / (c * p["g"]) * (nav["a_tilt"][0] * w[1]
                                                          - nav["a_tilt"][1] * w[0])
        return z, h, (p["range_sigma"] + p["range_k_range"] * ca.fabs(s)) ** 2, steep
    h, sigma = {                                                             # (E11), (E13)
        "gnss_rel": (-nav["p_r"] + nav["b"], p["gnss_rel_sigma"]),
        "gnss_v1": (nav["v1"], p["gnss_v1_sigma"]),
        "gnss_vt": (nav["v_t"], p["gnss_vt_sigma"]),
        "datalink_v": (nav["v_t"], p["datalink_v_sigma"]),
        "datalink_a": (nav["a_t"], p["datalink_a_sigma"]),
    }[block.name]
    return z, h, sigma**2, 1


@functools.cache
def measurement_model_function(name: str) -> ca.Function:
    """``h_<name>(x, pkt, n2, p_est) -> (z, h, H, r, valid)``.

    ``z`` the measured values, ``h`` their prediction from the state (E10)-(E14),
    ``H = dh/dx`` by ``ca.jacobian``, ``r`` the variances (diagonal R),
    ``valid`` 0 where the packet cannot be used (a range along the deck).
    ``pkt`` is the block's sensor's packet, ``n2`` the deck normal in E.
    """
    block = _block(name)
    layout = _packet(block.sensor)
    x, pkt, n2, p = NAV.sym("x"), layout.sym(), ca.SX.sym("n2", 3), estimator_params().sym()
    z, h, r, valid = _model(block, NAV.unpack(x), layout.unpack(pkt), n2,
                            estimator_params().unpack(p))
    return ca.Function(f"h_{name}", [x, pkt, n2, p], [z, h, ca.jacobian(h, x), r, valid],
                       ["x", "pkt", "n2", "p_est"], ["z", "h", "H", "r", "valid"])


def _block(name: str) -> Block:
    for b in BLOCKS:
        if b.name == name:
            return b
    raise KeyError(f"no measurement block {name!r}")


def _packet(sensor: str) -> Layout:
    for p in NAV_PACKETS:
        if p.name == sensor:
            return p
    raise KeyError(f"no sensor {sensor!r}")


def _beam_on_deck(x, P, h, pkt, p):
    """1 when the range's beam surely meets the deck (E12a): its predicted deck point
    ``p_r - h b3_E`` lies within ``range_deck_radius`` of the pad centre by
    ``range_deck_sigmas`` standard deviations of the horizontal relative position; a
    beam that may miss the deck measures the ground beside it."""
    nav = NAV.unpack(x)
    i = NAV.slice("p_r").start
    spread = ca.sqrt(ca.fmax(P[i, i] + P[i + 1, i + 1], 0))
    hit = ca.norm_2(nav["p_r"] - h * RANGE.unpack(pkt)["b3_E"])
    return hit + p["range_deck_sigmas"] * spread <= p["range_deck_radius"]


def block_update(name: str, x, P, pkt, n2, p_est, due, pattern: CovariancePattern,
                 streak=0):
    """Gate one block, then fuse it by scalar Joseph updates.

    (E8), (E8a), (E9). Returns ``(x_next, P_next, nu, nis, accept, held)``: the
    innovation ``z - h(x)`` and ``nu^T S^-1 nu`` with ``S = H P H^T + R`` before the
    update, 1 if the block was fused (``due``, valid and NIS within its gate, or
    re-admitted), and 1 if it was due but held back as unusable before the gate (a
    range whose beam grazes the deck (E12) or may miss it (E12a)). A block due,
    neither fused nor held, was refused by its gate. A block not fused leaves ``x``
    and ``P`` unchanged.

    (E8a) ``streak`` counts the block's consecutive gate refusals before this one.
    From ``gate_lockout`` of them on, a valid block its gate refuses is fused with
    the covariance inflated by ``NIS / gate`` (the whole of ``P``, so its pattern
    holds): a filter too sure of a wrong estimate (a GNSS bias beyond its sigmas, a
    velocity whose variance stopped growing) would otherwise refuse every later
    measurement of it and never recover.
    """
    block, model = _block(name), measurement_model_function(name)
    p = estimator_params().unpack(p_est)
    z, h, H, r, valid = model(x, pkt, n2, p_est)
    if name == "range":
        valid = ca.logic_and(valid, _beam_on_deck(x, P, h, pkt, p))
    home = NAV.slice("p_r").start + 2                  # the range's p_r_z (E9a)

    shared = heading_share(z, p["vision_heading_sigma"]) if name == "vision" else 0  # (E10c)

    def projected(P, update=False):                  # the update's noise: (E9b), (E10c)
        rows, r_eff = [], []
        for i in range(block.dim):
            row, extra = project_row(H[i, :].T, P, pattern, home, r[i] if update else None)
            rows.append(row)
            if update and name == "vision":
                extra += (memory_count(r[i] - shared[i], row, P) - 1) * shared[i]
            r_eff.append(r[i] + extra)
        return rows, r_eff

    rows, r_eff = projected(P)
    Hk = ca.horzcat(*rows).T
    S = Hk @ P @ Hk.T + ca.diag(ca.vertcat(*r_eff))
    nu = z - h
    nis = block_nis(S, nu)
    gate = p[f"gate_{name}"]
    usable = ca.logic_and(due, valid)
    readmit = ca.logic_and(ca.logic_and(usable, nis > gate), streak >= p["gate_lockout"])
    accept = ca.logic_and(usable, ca.logic_or(nis <= gate, readmit))
    inflation = ca.if_else(readmit, ca.fmax(nis / ca.fmax(gate, 1e-30), 1), 1)
    P = P * inflation
    rows, r_eff = projected(P, update=True)
    for i in range(block.dim):
        h_i = model(x, pkt, n2, p_est)[1][i]                # at the updated state
        x, P = scalar_update(x, P, rows[i], z[i] - h_i, r_eff[i], accept, pattern)
    return x, P, nu, nis, accept, ca.logic_and(due, ca.logic_not(valid))


@functools.cache
def nav_update_function(name: str, coupling: str = "full") -> ca.Function:
    """One block's gated update as a Function.

    ``nav_update_<name>(x, P, pkt, n2, p_est, due) -> (x_next, P_next, nu, nis,
    fused, held)``: :func:`block_update` with full symmetric 21 x 21 ``P`` in and out (only
    the stored upper-triangle entries of :func:`covariance_pattern` are read).
    """
    pattern = covariance_pattern(coupling)
    layout = _packet(_block(name).sensor)
    x, P, pkt = NAV.sym("x"), ca.SX.sym("P", NAV.size, NAV.size), layout.sym()
    n2, p, due = ca.SX.sym("n2", 3), estimator_params().sym(), ca.SX.sym("due")
    out = block_update(name, x, pattern.unpack(pattern.pack(P)), pkt, n2, p, due, pattern)
    out = [out[0], ca.densify(out[1]), *out[2:]]
    return ca.Function(f"nav_update_{name}", [x, P, pkt, n2, p, due], out,
                       ["x", "P", "pkt", "n2", "p_est", "due"],
                       ["x_next", "P_next", "nu", "nis", "fused", "held"])


# ---------------------------------------------------------------- outputs

def deck_at(eta2, w2E, w2E_dot, age, max_age):
    """The deck's attitude and rate ``age`` after a broadcast (E7).

    ``eta2 + eta2_dot a + eta2_ddot a^2 / 2`` and ``w2E + w2E_dot a`` with
    ``a = age`` clipped to ``[-max_age, max_age]``; ``eta2_dot``,
    ``eta2_ddot`` from :func:`quadland_symbolic.landing.controller.deck_rates` (eq. 3).
    """
    a = ca.fmin(ca.fmax(age, -max_age), max_age)
    eta2_dot, eta2_ddot = deck_rates(eta2, w2E, w2E_dot)
    return eta2 + eta2_dot * a + eta2_ddot * (a**2 / 2), w2E + w2E_dot * a


def relative_output(p_r, v_rel, eta2, w2E):
    """The deck-frame relative position and velocity (E15).

    ``p_e = R2^T p_r``, ``v_e = R2^T v_rel - (R2^T w2E) x p_e`` with
    ``v_rel = v1 - v_t``, ``R2 = R(eta2)``: the derivative of
    ``R2^T (p1 - p2)`` with ``R2' = S(w2E) R2``.
    """
    R2 = rotation(eta2)
    p_e = R2.T @ p_r
    return p_e, R2.T @ v_rel - ca.cross(R2.T @ w2E, p_e)

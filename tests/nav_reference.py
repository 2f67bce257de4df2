"""A textbook Kalman filter in NumPy, and data, for the filter's tests.

Written from the state equations (E2) of docs/estimator.md index by index:
SciPy's matrix exponential for ``Phi`` and ``Gamma``, Van Loan's method for
``Q``, the full-matrix Joseph update with ``K = P H^T S^-1``; no code of
``quadland_symbolic.kalman`` or ``quadland_symbolic.landing.navigation`` besides their layouts.
"""

import numpy as np
from reference import rotation
from scipy.linalg import expm

from quadland_symbolic.landing.estimator import estimator_diagnostics, estimator_init_function
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    IMU,
    NAV,
    NAV_PACKETS,
    covariance_pattern,
    estimator_params,
)

N = NAV.size
PARAMS = estimator_params()
DIAG = estimator_diagnostics()
OPEN_GATES = {**{f"gate_{b.name}": 1e30 for b in BLOCKS}, "range_deck_radius": 1e30,
              "range_deck_sigmas": 0.0}


def sl(name):
    """Slice of a NAV field."""
    return NAV.slice(name)


def col(v):
    """A flat float array."""
    return np.array(v, dtype=float).ravel()


def params(**over):
    """The default parameter vector with ``over`` replaced."""
    return PARAMS.pack({**ESTIMATOR_DEFAULTS, **over})


# ---------------------------------------------------------------- the NumPy reference

def model_matrices(q):
    """A, B, W of (E2), entry by entry from the state equations (``a_tilt`` held: its
    decay over the period is :func:`discrete`'s, (E2a))."""
    A, B, W = np.zeros((N, N)), np.zeros((N, 3)), np.zeros((N, N))
    I3 = np.eye(3)
    A[sl("p_r"), sl("v1")] = I3                     # p_r' = v1 - v_t
    A[sl("p_r"), sl("v_t")] = -I3
    A[sl("v1"), sl("a_b")] = -I3                    # v1' = a_in - a_b - a_tilt
    A[sl("v1"), sl("a_tilt")] = -I3
    B[sl("v1"), :] = I3
    A[sl("v_t"), sl("a_t")] = I3                    # v_t' = a_t
    for name, key in (("v1", "q_acc"), ("a_t", "q_at"), ("b", "q_b"), ("a_b", "q_ab")):
        W[sl(name), sl(name)] = np.diag(np.broadcast_to(q[key], 3))
    return A, B, W


_DISCRETE = {}


def discrete(dt, q, held=False):
    """Phi, Gamma by expm of [[A, B], [0, 0]]; Q by Van Loan; then ``a_tilt`` decays as
    a Gauss-Markov process sampled every ``dt`` (E2a), unless ``held`` (as the output
    predictor carries it, (E17))."""
    key = (dt, held, *(tuple(np.broadcast_to(q[k], 3)) for k in (
        "q_acc", "q_at", "q_b", "q_ab", "tilt_sigma")), q["tilt_tau"])
    if key not in _DISCRETE:
        _DISCRETE[key] = _discrete_uncached(dt, q, held)
    return _DISCRETE[key]


def _discrete_uncached(dt, q, held):
    A, B, W = model_matrices(q)
    M = np.zeros((N + 3, N + 3))
    M[:N, :N], M[:N, N:] = A, B
    E = expm(M * dt)
    V = expm(np.block([[-A, W], [np.zeros((N, N)), A.T]]) * dt)
    Phi, Q = E[:N, :N].copy(), V[N:, N:].T @ V[:N, N:]
    a = 1.0 if held else np.exp(-dt / q["tilt_tau"])   # x+ = a x + sigma sqrt(1 - a^2) n
    i = sl("a_tilt")
    Phi[i, i] = a * np.eye(3)
    Q[i, i] = np.diag(np.asarray(q["tilt_sigma"], dtype=float) ** 2 * (1 - a * a))
    return Phi, E[:N, N:], Q


def h_rows(name, n2=None, b3=None, z=None, g=None):
    """H of each block from (E10)-(E13); the range's row n2^T / c on ``p_r`` and
    ``s / (c g) (w_y, -w_x)`` on ``a_tilt``'s x, y, ``c = n2 . b3``, ``w = b3 x n2``, ``s``
    its packet's (E12b); the vision's ``-p_r + (z_z / g) a_tilt`` with ``z`` its packet's
    ``r_E``."""
    H = np.zeros((3, N))
    I3 = np.eye(3)
    if name == "vision":
        H[:, sl("p_r")] = -I3
        H[:, sl("a_tilt")] = z[2] / g * I3
    elif name == "gnss_rel":
        H[:, sl("p_r")], H[:, sl("b")] = -I3, I3
    elif name == "gnss_v1":
        H[:, sl("v1")] = I3
    elif name in ("gnss_vt", "datalink_v"):
        H[:, sl("v_t")] = I3
    elif name == "datalink_a":
        H[:, sl("a_t")] = I3
    else:
        H = np.zeros((1, N))
        c, w = n2 @ b3, np.cross(b3, n2)
        H[0, sl("p_r")] = n2 / c
        H[0, sl("a_tilt")] = z[0] / (c * g) * np.array([w[1], -w[0], 0.0])
    return H


def variances(name, z, q):
    """The diagonal of R of each block (E10)-(E13)."""
    if name == "vision":
        return (np.full(3, (q["vision_sigma0"] + q["vision_k_range"] * np.linalg.norm(z)) ** 2)
                + q["vision_heading_sigma"] ** 2 * np.array([z[1] ** 2, z[0] ** 2, 0.0]))
    if name == "range":
        return np.array([(q["range_sigma"] + q["range_k_range"] * abs(z[0])) ** 2])
    key = {"gnss_rel": "gnss_rel_sigma", "gnss_v1": "gnss_v1_sigma", "gnss_vt": "gnss_vt_sigma",
           "datalink_v": "datalink_v_sigma", "datalink_a": "datalink_a_sigma"}[name]
    return np.asarray(q[key], dtype=float) ** 2


def joseph_reference(x, P, H, z, R):
    """The textbook update: K = P H^T S^-1, full-matrix Joseph form."""
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    nu = z - H @ x
    I_KH = np.eye(N) - K @ H
    return x + K @ nu, I_KH @ P @ I_KH.T + K @ R @ K.T, nu, nu @ np.linalg.solve(S, nu)


class ReferenceKF:
    """A textbook KF on (E2), fusing packets at their own time."""

    def __init__(self, x0, P0, q):
        self.x, self.P, self.q = np.array(x0, float), np.array(P0, float), q

    def fuse(self, packets, n2):
        """Fuse ``packets`` (sensor -> values); NIS per block."""
        nis = {}
        for b in BLOCKS:
            pk = packets.get(b.sensor)
            if pk is None:
                continue
            z = np.atleast_1d(pk[b.field])
            H = h_rows(b.name, n2, pk.get("b3_E"), z, self.q["g"])
            R = np.diag(variances(b.name, z, self.q))
            self.x, self.P, _, nis[b.name] = joseph_reference(self.x, self.P, H, z, R)
        return nis

    def predict(self, a_in, dt, turn=(0.0, 0.0, 0.0)):
        """Predict over ``dt`` with ``a_in`` held, the accelerometer's bias turned by
        ``turn`` (E6a): ``Phi[a_b, a_b] = I + S(turn)``, ``S(w) v = w x v``."""
        Phi, Gamma, Q = discrete(dt, self.q)
        Phi = Phi.copy()
        Phi[sl("a_b"), sl("a_b")] = np.eye(3) + cross_matrix(turn)
        self.x = Phi @ self.x + Gamma @ a_in
        self.P = Phi @ self.P @ Phi.T + Q


def cross_matrix(w):
    """``S(w)``, written here: ``S(w) v = w x v``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


# ---------------------------------------------------------------- helpers

def random_spd(rng, n, scale=1.0):
    """A random symmetric positive definite matrix."""
    L = rng.normal(size=(n, n))
    return scale * (L @ L.T / n + 0.1 * np.eye(n))


def random_imu(rng):
    """A random IMU packet near hover."""
    eta = rng.normal(size=3) * [0.2, 0.2, 1.0]
    return IMU.pack(dict(eta_hat=eta, f_b=rng.normal(size=3) + [0, 0, 9.8],
                         omega=rng.normal(size=3) * 0.3))


def acceleration(imu, g):
    """a_in = R(eta_hat) f_b - g e_z, written here."""
    v = IMU.unpack(imu)
    return rotation(v["eta_hat"]) @ v["f_b"] - np.array([0, 0, g])


def body_turn(imu, dt):
    """The body's turn over ``dt`` in E (E6a): ``R(eta_hat) omega dt``, written here."""
    v = IMU.unpack(imu)
    return rotation(v["eta_hat"]) @ v["omega"] * dt


def packet_values(rng, sensor, x, tau, eta2, n2):
    """A packet near what the state predicts (noise about 0.3)."""
    e = rng.normal(size=3) * 0.3
    if sensor == "vision":
        return dict(fresh=1.0, tau=tau, r_E=vision_vector(x, e, 9.8))
    if sensor == "gnss":
        return dict(fresh=1.0, tau=tau, rel=-x[sl("p_r")] + x[sl("b")] + e,
                    v1=x[sl("v1")] + e[::-1], vt=x[sl("v_t")] - e)
    if sensor == "range":
        b3 = np.array([0.1, -0.05, 1.0]) + rng.normal(size=3) * 0.05
        b3 /= np.linalg.norm(b3)
        return dict(fresh=1.0, tau=tau, s=n2 @ x[sl("p_r")] / (n2 @ b3) + e[0], b3_E=b3)
    return dict(fresh=1.0, tau=tau, eta2=eta2, v2E=x[sl("v_t")] + e,
                a2E=x[sl("a_t")] + e[::-1], w2E=np.zeros(3), w2E_dot=np.zeros(3))


def vision_vector(x, noise, g):
    """The vision packet's ``r_E = -p_r + (r_z / g) a_tilt + noise`` (E10), solved for its
    own ``r_z`` first."""
    p_r, a_tilt = x[sl("p_r")], x[sl("a_tilt")]
    r_z = (-p_r[2] + noise[2]) / (1 - a_tilt[2] / g)
    return -p_r + r_z / g * a_tilt + noise


def empty(layout):
    """A packet that is not fresh."""
    return np.zeros(layout.size)


def init_memory(n_hist, depth, coupling, x0, P0_diag, eta2=(0, 0, 0), t0=0.0):
    """The filter's memory at handover, the deck level unless ``eta2``."""
    deck0 = np.concatenate([eta2, np.zeros(6)])
    return col(estimator_init_function(n_hist, depth, coupling)(x0, P0_diag, deck0, t0))


def x0_P0(rng):
    """A random handover state and diagonal covariance."""
    x0 = rng.normal(size=N) * 0.5
    x0[sl("p_r")] += [1.0, -2.0, 4.0]
    return x0, rng.uniform(0.05, 1.0, N)


def unpack_P(mem_layout, coupling, mem):
    """The covariance held in a memory vector, as a matrix."""
    return covariance_pattern(coupling).unpack_numeric(mem_layout.unpack(mem)["P_h"])



def block_data(rng, name):
    """A block's packet layout, a state, a covariance, a packet and n2."""
    layout = next(p for p in NAV_PACKETS if p.name == next(b.sensor for b in BLOCKS
                                                         if b.name == name))
    x, P = rng.normal(size=N), random_spd(rng, N, 0.5)
    eta2 = np.array([0.05, 0.02, 0.4])
    n2 = rotation(eta2)[:, 2]
    vals = packet_values(rng, layout.name, x, 0.0, eta2, n2)
    return layout, x, P, vals, n2

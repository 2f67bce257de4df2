"""The paper's closed loop derived again in NumPy, as an oracle.

``numpy_rhs`` is written from the paper (eq. 1-6, 9-22) independently of
the CasADi model in ``symbolic/``: alpha_dot (eq. 18) is differentiated by
hand instead of symbolically, and no expression of ``symbolic/`` is reused.
Only the vectors' named layouts (``closed_loop_state``,
``closed_loop_params``, ``BODY_DISTURBANCE``) are shared, so that both
derivations read and write the same entries.

Used by ``tests/test_numpy_closed_loop.py`` (against ``closed_loop_function``)
and by ``benchmarks/bench_simulate.py`` (the SciPy baseline's right-hand side).
"""

import numpy as np

from quadland_symbolic.closed_loop import closed_loop_params, closed_loop_state
from quadland_symbolic.quadrotor import BODY_DISTURBANCE

__all__ = ["numpy_rhs", "random_states"]


def _leaves(layout, v):
    """Every innermost block of ``v`` by name (nested layouts flattened);
    one-entry blocks as floats."""
    out = {}
    for name, block in layout.unpack(v).items():
        inner = layout[name].layout
        if inner is not None:
            out.update(_leaves(inner, block))
        else:
            out[name] = float(block[0]) if block.size == 1 else block
    return out


def numpy_rhs(p, l):
    """The closed loop's right-hand side ``rhs(t, x, w)`` in NumPy.

    Parameters
    ----------
    p : ndarray
        Closed-loop parameter vector, layout ``closed_loop_params(l)``
        (``quadland.kinds.paper.values.model_values(...).p``).
    l : int
        RBF node count.

    Returns
    -------
    callable
        ``rhs(t, x, w) -> x_dot``, ``x`` in the layout ``closed_loop_state(l)``
        and ``w = [d_F, d_M]`` (``BODY_DISTURBANCE``).
    """
    P = _leaves(closed_loop_params(l), np.asarray(p, dtype=float).ravel())
    m1, I, Kt, Kr, g = P["m1"], P["I"], P["Kt"], P["Kr"], P["g"]
    m11, m22, m33, d11, d22, d33 = (P[k] for k in ("m11", "m22", "m33", "d11", "d22", "d33"))
    tau, z2 = P["tau"], P["z2"]
    k1, k2 = P["k1"], P["k2"]
    gamma1, gamma2, k_w, k_zeta, rho = (P[k] for k in ("gamma1", "gamma2", "k_w", "k_zeta",
                                                       "rho"))
    nominal = P["nominal_model"]
    centers, inv_w2 = P["centers"], 1.0 / P["widths"]**2         # (10, l), (l,)
    e1d, e1d_dot, e1d_ddot = P["e1d"], P["e1d_dot"], P["e1d_ddot"]
    Ix, Iy, Iz = I

    S = closed_loop_state(l)
    s_z1, s_eta, s_V, s_Om = (S.slice(f"xq.{k}") for k in ("z1", "eta1", "V1", "Omega1"))
    s_psi2, s_u2, s_v2, s_r2 = (S.slice(f"xv.{k}") for k in ("psi2", "u2", "v2", "r2"))
    s_xv, s_W, s_zeta, s_pos = (S.slice(k) for k in ("xv", "W_hat", "zeta_hat", "pos1"))
    W_shape = S["W_hat"].shape                                      # (l, 4), column-major
    s_dF, s_dM = BODY_DISTURBANCE.slice("d_F"), BODY_DISTURBANCE.slice("d_M")

    def rhs(t, x, w):
        z1 = x[s_z1][0]
        phi, theta, psi = x[s_eta]
        V = x[s_V]
        Om = x[s_Om]
        pr, qr, rr = Om
        psi2, u2, v2, r2 = x[s_psi2][0], x[s_u2][0], x[s_v2][0], x[s_r2][0]
        W_hat = x[s_W].reshape(W_shape, order="F")
        zeta_hat = x[s_zeta]
        d_F, d_M = w[s_dF], w[s_dM]
        cf, sf, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
        cp, sp = np.cos(psi), np.sin(psi)
        tt = st / ct
        J = np.array([-st, ct * sf, ct * cf])                     # last row of R(eta)
        Rr = np.array([[1.0, tt * sf, tt * cf],                   # eq. 1
                       [0.0, cf, -sf],
                       [0.0, sf / ct, cf / ct]])
        Rr_inv = np.array([[1.0, 0.0, -st],
                           [0.0, cf, sf * ct],
                           [0.0, -sf, cf * ct]])

        # relative states (eq. 5, 7); the deck neither heaves, rolls nor pitches
        e1 = np.array([z1 - z2, phi, theta, psi - psi2])
        e2 = np.concatenate([[J @ V], Om - Rr_inv[:, 2] * r2])
        R = np.zeros((4, 4))
        R[0, 0] = 1.0
        R[1:, 1:] = Rr
        R_inv = np.zeros((4, 4))
        R_inv[0, 0] = 1.0
        R_inv[1:, 1:] = Rr_inv
        e1_dot = R @ e2                                            # eq. 10
        phi_dot, theta_dot = e1_dot[1], e1_dot[2]
        R_inv_dot = np.zeros((4, 4))                               # d/dt R^-1 by hand
        R_inv_dot[1:, 1:] = [
            [0.0, 0.0, -ct * theta_dot],
            [0.0, -sf * phi_dot, cf * ct * phi_dot - sf * st * theta_dot],
            [0.0, -cf * phi_dot, -sf * ct * phi_dot - cf * st * theta_dot]]

        # backstepping (eq. 9, 14, 18)
        z_1 = e1 - e1d
        v = -k1 * z_1 + e1d_dot
        alpha = R_inv @ v
        alpha_dot = R_inv_dot @ v + R_inv @ (-k1 * (e1_dot - e1d_dot) + e1d_ddot)
        z_2 = e2 - alpha

        # RBF network (eq. 8, 16): w2 = 0, p2 = q2 = 0
        w_e, p_e, q_e, r_e = V[2], pr, qr, rr - r2
        theta_in = np.array([w_e, p_e, q_e, r_e, w_e * p_e, w_e * q_e, w_e * r_e,
                             p_e * q_e, p_e * r_e, q_e * r_e])
        diff = centers - theta_in[:, None]
        Psi = np.exp(-np.sum(diff * diff, axis=0) * inv_w2)
        Delta_hat = W_hat.T @ Psi

        # known quadrotor drift, fed forward only with nominal_model = 1
        f_nom = np.array([
            -(J @ (Kt * V)) / m1 - g,
            -Kr[0] * pr / Ix - (Iz - Iy) * qr * rr / Ix,
            -Kr[1] * qr / Iy - (Ix - Iz) * pr * rr / Iy,
            -Kr[2] * rr / Iz - (Iy - Ix) * pr * qr / Iz])
        sq = np.tanh(z_2 / rho)
        u = (-k2 * z_2 - R.T @ z_1 - Delta_hat - sq * zeta_hat + alpha_dot     # eq. 20
             - nominal * f_nom)
        W_dot = gamma1 * (np.outer(Psi, z_2) - k_w * W_hat)                    # eq. 22
        zeta_dot = gamma2 * (sq * z_2 - k_zeta * zeta_hat)                     # eq. 22

        # wrench realising u (eq. 6), quadrotor (eq. 1-2)
        F_total = m1 * u[0] / (ct * cf)
        T = I * u[1:4]
        F = np.array([0.0, 0.0, F_total])
        V_dot = -np.cross(Om, V) + (F - Kt * V + d_F) / m1 - g * J
        Om_dot = (T - Kr * Om + d_M - np.cross(Om, I * Om)) / I

        # vehicle (eq. 3-4)
        c2, s2 = np.cos(psi2), np.sin(psi2)
        xv_dot = np.array([
            c2 * u2 - s2 * v2, s2 * u2 + c2 * v2, r2,
            (tau[0] + m22 * v2 * r2 - d11 * u2) / m11,
            (tau[1] - m11 * u2 * r2 - d22 * v2) / m22,
            (tau[2] - d33 * r2 + (m11 - m22) * u2 * v2) / m33])

        # quadrotor ground track: first two rows of Rz Ry Rx times V1
        pos_dot = np.array([
            cp * ct * V[0] + (cp * st * sf - sp * cf) * V[1] + (cp * st * cf + sp * sf) * V[2],
            sp * ct * V[0] + (sp * st * sf + cp * cf) * V[1] + (sp * st * cf - cp * sf) * V[2]])

        x_dot = np.empty(S.size)
        x_dot[s_z1] = J @ V
        x_dot[s_eta] = Rr @ Om
        x_dot[s_V] = V_dot
        x_dot[s_Om] = Om_dot
        x_dot[s_xv] = xv_dot
        x_dot[s_W] = W_dot.ravel(order="F")
        x_dot[s_zeta] = zeta_dot
        x_dot[s_pos] = pos_dot
        return x_dot

    return rhs


def random_states(mv, n, seed=0):
    """``n`` random closed-loop states and disturbances around a scenario's start.

    Parameters
    ----------
    mv : quadland.kinds.paper.values.ModelValues
    n : int
    seed : int

    Returns
    -------
    X : ndarray, (nx, n)
        ``mv.x0`` plus uniform noise in [-1, 1], roll and pitch drawn in
        [-1, 1] rad (within 57 deg of level, away from the thrust map's
        singularity).
    W : ndarray, (6, n)
        Standard normal disturbances.
    """
    rng = np.random.default_rng(seed)
    S = closed_loop_state(mv.l)
    X = mv.x0[:, None] + rng.uniform(-1, 1, (S.size, n))
    for angle in ("phi1", "theta1"):
        X[S.index(angle)] = rng.uniform(-1.0, 1.0, n)
    W = rng.normal(0.0, 1.0, (BODY_DISTURBANCE.size, n))
    return X, W

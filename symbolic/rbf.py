"""Radial-basis-function network (eq. 8, 16).

``Psi_i(x) = exp(-||x - mu_i||^2 / epsilon_i^2)`` for ``i = 1..l``, with
the input ``vartheta`` of Section 3.2 built from the relative body
velocities ``w_e, p_e, q_e, r_e`` and their six pairwise products.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from quadland_symbolic.parameters import RBF_INPUT_DIM

__all__ = ["rbf_input", "rbf", "default_centers", "rbf_function"]


def rbf_input(w_e, p_e, q_e, r_e):
    """vartheta = [w_e, p_e, q_e, r_e, w_e p_e, w_e q_e, w_e r_e, p_e q_e, p_e r_e, q_e r_e]."""
    return ca.vertcat(w_e, p_e, q_e, r_e,
                      w_e * p_e, w_e * q_e, w_e * r_e, p_e * q_e, p_e * r_e, q_e * r_e)


def rbf(vartheta, centers, widths):
    """Basis vector Psi(vartheta) in R^l (eq. 8).

    Parameters
    ----------
    vartheta : casadi.SX, (m, 1)
    centers : casadi.SX, (m, l)
        Centre mu_i in column i.
    widths : casadi.SX, (l, 1)
        Spread epsilon_i of node i.
    """
    l = centers.shape[1]
    diff = centers - ca.repmat(vartheta, 1, l)
    sq_dist = ca.sum1(diff * diff).T                     # ||vartheta - mu_i||^2
    return ca.exp(-sq_dist / (widths * widths))


def default_centers(l: int, lo: float = -2.0, hi: float = 2.0) -> np.ndarray:
    """Centres on the diagonal of the input space, ``mu_i = c_i [1, ..., 1]``.

    ``c_i`` are ``l`` evenly spaced values on ``[lo, hi]``; returns (10, l).
    """
    c = np.linspace(lo, hi, l) if l > 1 else np.array([(lo + hi) / 2])
    return np.tile(c, (RBF_INPUT_DIM, 1))


def rbf_function(l: int) -> ca.Function:
    """``rbf(vartheta, centers, widths) -> Psi`` for ``l`` nodes."""
    vartheta = ca.SX.sym("vartheta", RBF_INPUT_DIM)
    centers = ca.SX.sym("centers", RBF_INPUT_DIM, l)
    widths = ca.SX.sym("widths", l)
    return ca.Function("rbf", [vartheta, centers, widths], [rbf(vartheta, centers, widths)],
                       ["vartheta", "centers", "widths"], ["Psi"])

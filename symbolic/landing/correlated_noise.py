"""Measurement noise beyond the white: a row's dropped part (E9a), and noise the same in
every packet for seconds (E9b), (E10c).

A noise shared by consecutive packets does not average away as white noise does: the
filter's kept state, which holds the information of about ``m = r_w / h^T P h`` packets
of white variance ``r_w``, carries it whole. The update counts its variance ``m`` times
(at least once); the gate's ``S`` and the NIS, which judge one packet, once.
docs/estimator.md gives the equations.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kalman import CovariancePattern, is_finite, select

__all__ = ["memory_count", "project_row", "heading_share"]


def memory_count(r_white, row, P):
    """``max(1, r_white / row^T P row)``: the packets of variance ``r_white`` whose
    information the state along ``row`` holds (E9b)."""
    return ca.fmax(r_white / ca.fmax(row.T @ P @ row, 1e-30), 1)


def project_row(h, P, pattern: CovariancePattern, home: int, r=None):
    """``(kept, extra)`` of a row across groups: keep ``home``'s group, its rest's
    variance ``h_d^T P h_d`` as noise (E9a), given the update's ``r``
    ``max(1, r / h_z^T P h_z)`` times (E9b)."""
    groups = {pattern.group_of[i] for i in ca.sparsify(h).sparsity().row()}
    if len(groups) <= 1:
        return h, 0
    keep = [i for i in range(pattern.n) if pattern.group_of[i] == pattern.group_of[home]]
    mask = ca.DM.zeros(pattern.n)
    mask[keep] = 1
    kept, dropped = ca.sparsify(h * mask), h * (1 - mask)
    memory = 1 if r is None else memory_count(r, kept, P)
    return kept, memory * (dropped.T @ P @ dropped)


def heading_share(r_E, sigma_psi):
    """The vision's variances from the attitude estimate's heading error (E10c).

    ``eps_z e_z x r_E = eps_z (-r_y, r_x, 0)``: ``sigma_psi^2 (r_y^2, r_x^2, 0)``; a
    non-finite component reads 0 (such a packet is never fused, and its row must stay
    finite).
    """
    x, y = (select(is_finite(r_E[i]), r_E[i], 0) for i in range(2))
    return sigma_psi ** 2 * ca.vertcat(y**2, x**2, 0)

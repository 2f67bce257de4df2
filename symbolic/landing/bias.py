"""The landing controller's bias estimates: integral action as a leakage-free adaptive law.

One estimate per channel of :mod:`quadland_symbolic.landing.controller` (deck-frame
x, y, z in m/s^2; body roll, pitch, yaw in rad/s^2), subtracted from the law's
acceleration command. Its law is the paper's eq. (22) for the constant regressor
``Psi = 1`` with no leakage, ``d_hat' = k z2``, projected onto a box
(docs/landing.md, "Integral action"): a constant mismatch leaves no steady error.
The outer estimates of x and y can be held until the quadrotor is near its reference
(:func:`learning_gate`), so that they do not learn the approach's transient.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["bias_next", "learning_gate"]


def bias_next(d_hat, gains, d_max_p, d_max, z2, n_clipped, dt):
    """The bias estimates after ``dt``: ``d_hat' = k z2`` with ``z2`` held, exact, then
    projected onto the box ``|d_hat_i| <= d_max``.

    Parameters
    ----------
    d_hat : casadi.SX, (6, 1)
        The estimates: the outer three (deck frame), then the inner three (body).
    gains : casadi.SX, (6, 1)
        ``[ki_p, ki]``.
    d_max_p, d_max : casadi.SX
        The box of the outer and of the inner estimates.
    z2 : casadi.SX, (6, 1)
        The outer channels' Farrell-compensated ``z2_bar`` (so that they do not
        learn the thrust and tilt limits), then the inner channels' ``z2``.
    n_clipped : casadi.SX
        Rotor commands clipped this step: the inner three stop while one is (the
        moments asked for are not the moments flown).
    dt : casadi.SX
        The period, s.
    """
    held = ca.vertcat(ca.DM.ones(3), ca.repmat(n_clipped == 0, 3, 1))
    box = ca.vertcat(ca.repmat(d_max_p, 3, 1), ca.repmat(d_max, 3, 1))
    return ca.fmin(ca.fmax(d_hat + dt * gains * z2 * held, -box), box)


def learning_gate(z1p, r_learn):
    """Which outer bias estimates learn this step: ``[g, g, 1]`` (deck-frame x, y, z).

    ``g`` is 1 while the horizontal position error ``|z1p[0:2]|`` is within ``r_learn``
    (m), else 0: the x and y estimates are held (conditional integration) through the
    approach, whose transient they would otherwise learn as a force and carry into the
    descent (docs/landing.md, "highway: integral action from the hover point on").
    ``r_learn = 0``: always 1, the law of before to the bit.
    """
    g = ca.if_else(r_learn > 0, z1p[0]**2 + z1p[1]**2 <= r_learn**2, 1)
    return ca.vertcat(g, g, 1)

"""The navigation filter's outputs: the horizon's state carried to the present (E17), the
pad's heave as an oscillation over that horizon (E17a), and the landing step's measurement
from it (E7), (E15).

Pieces of :mod:`quadland_symbolic.landing.estimator`'s step (which re-exports them), kept
apart from the fusion and the queues.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kalman import select
from quadland_symbolic.landing.heave import heave_factors, heave_gate
from quadland_symbolic.landing.navigation import (
    IMU,
    NAV,
    deck_at,
    estimator_params,
    relative_output,
)
from quadland_symbolic.landing.quiescence import deck_frequency, quiescence_update

__all__ = ["output_predictor", "estimator_output", "heave_frequency"]


def output_predictor(x_h, hist, omega=0):
    """The state carried through the buffered inputs (E17), the pad's z by (E17a).

    The state ``sum(dt_k)`` after the horizon; ``hist`` has ``N`` columns, oldest first,
    whose first four rows are the inputs ``a_k`` (E) held over ``dt_k`` (the body's turns,
    rows 5-7, are not carried: the bias turns by a few milliradians over the horizon).
    With ``T = sum dt_k``, ``S1 = sum a_k dt_k`` and
    ``S2 = sum a_k dt_k (dt_k / 2 + sum_{j>k} dt_j)``: ``v1 += S1 - T a_u`` with
    ``a_u = a_b + a_tilt`` the input's bias, ``p_r += T (v1 - v_t) + S2 - T^2 (a_u + a_t) / 2``,
    ``v_t += T a_t``;
    the rest is constant. The same map as (E6)'s ``Phi``, ``Gamma`` chained.

    The pad's vertical motion (z of ``v_t``, ``a_t`` and the pad's share of ``p_r``) is
    carried as the harmonic oscillator of frequency ``omega`` (rad/s,
    :mod:`quadland_symbolic.landing.heave`): ``v_t_z`` by ``cos(omega T) v + sin(omega T)
    a / omega``, ``a_t_z`` by ``cos(omega T) a - omega sin(omega T) v``. At ``omega = 0``
    it is the constant acceleration above, to the bit.
    """
    x = NAV.unpack(x_h)
    n = hist.shape[1]
    S1, S2, after = ca.DM.zeros(3), ca.DM.zeros(3), 0
    for k in reversed(range(n)):
        a_k, dt_k = hist[0:3, k], hist[3, k]
        S1 = S1 + a_k * dt_k
        S2 = S2 + a_k * (dt_k * (dt_k / 2 + after))
        after = after + dt_k
    T = after
    c, s, h = heave_factors(omega, T)                       # (E17a), each 1 at omega = 0
    v_t, a_t = x["v_t"], x["a_t"]
    a_u = x["a_b"] + x["a_tilt"]                       # the acceleration input's bias
    v1 = x["v1"] + S1 - T * a_u
    v_t_pad = ca.vertcat(v_t[0], v_t[1], v_t[2] * s)       # the pad's displacement over T
    a_t_pad = ca.vertcat(a_t[0], a_t[1], a_t[2] * h)
    p_r = x["p_r"] + T * (x["v1"] - v_t_pad) + S2 - (T**2 / 2) * (a_u + a_t_pad)
    v_t_now = ca.vertcat(v_t[0] + T * a_t[0], v_t[1] + T * a_t[1],
                         v_t[2] * c + (T * a_t[2]) * s)
    # the jerk's share, a literal +0 at omega = 0 (so that a_t's -0 stays -0)
    jerk = select(omega > 0, (omega**2 * T * s) * v_t[2], 0)
    a_t_now = ca.vertcat(a_t[0], a_t[1], a_t[2] * c - jerk)
    return ca.vertcat(p_r, v1, v_t_now, a_t_now, x["b"], x["a_b"], x["a_tilt"])


def _measurement(x_now, deck, ims, t, p):
    """The controller's :data:`LANDING_MEASUREMENT` at ``t`` (E7), (E15)."""
    x = NAV.unpack(x_now)
    eta2, w2E = deck_at(deck["eta2"], deck["w2E"], deck["w2E_dot"], t - deck["tau"],
                        p["deck_extrapolation_max"])
    p_e, v_e = relative_output(x["p_r"], x["v1"] - x["v_t"], eta2, w2E)
    return ca.vertcat(p_e, v_e, ims["eta_hat"], ims["omega"], eta2, x["v_t"], x["a_t"], w2E,
                      deck["w2E_dot"])


def estimator_output(x_h, hist, deck, imu, p_est, t, omega=0):
    """The controller's measurement from the horizon after fusion (E17), (E7), (E15).

    The step's ``y`` (:data:`LANDING_MEASUREMENT`): ``x_h`` carried to the present
    through the buffered inputs ``hist`` (:func:`output_predictor`, the pad's vertical
    motion as the oscillation of frequency ``omega``, (E17a)), the relative motion
    in the deck frame of the latest broadcast ``deck`` (``eta2``, ``w2E``, ``w2E_dot``,
    ``tau``) extrapolated to ``t``, the attitude and rates of the IMU.
    """
    p = estimator_params().unpack(p_est)
    return _measurement(output_predictor(x_h, hist, omega), deck, IMU.unpack(imu), t, p)


def heave_frequency(ms, x_h, p, dt):
    """``(ms_next, omega)``: the averages updated with the horizon's pad (E17a).

    ``omega = sqrt(<a_t_z^2> / <v_t_z^2>)`` on the updated averages
    (:func:`~quadland_symbolic.landing.quiescence.deck_frequency`: the mean zero-crossing
    frequency of the pad's vertical velocity, clamped), each average moving by
    ``min(dt / heave_time, 1)`` of the way to the new square; ``omega`` is 0 (the constant
    acceleration) when ``heave_time`` is 0. A ``heave_frequency`` above 0 (given, from the
    sea's spectrum, (E17b)) is ``omega`` instead. Either is 0 while the horizon's relative
    height is above ``heave_height`` (:func:`~quadland_symbolic.landing.heave.heave_gate`).
    """
    x = NAV.unpack(x_h)
    ms_next = quiescence_update(ms, x["v_t"][2], x["a_t"][2], dt, p["heave_time"])
    own = select(p["heave_time"] > 0, deck_frequency(ms_next), 0)
    omega = select(p["heave_frequency"] > 0, p["heave_frequency"], own)
    return ms_next, heave_gate(omega, x["p_r"][2], p)

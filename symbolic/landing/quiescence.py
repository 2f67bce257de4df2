"""Quiescent-period prediction of a ship deck's heave: when to commit to the final descent.

A ship deck's heave is a narrow-band random motion: groups of large waves with calmer
spells between them. Ship landing practice waits over the deck for such a spell (a
*quiescent period*) and lands inside it: the Landing Period Designator's Energy Index
(Ferrier, Manning et al., the U.S. Navy's Dynamic Interface programme; reviewed by
Sherman 2007, "The examination and evaluation of dynamic ship quiescence prediction and
detection methods", Virginia Tech MSc thesis) signals the start of a descent when the
deck's motion energy is low. This module is the flight code's version of it, on what the
aircraft knows: the pad's vertical velocity ``v`` and acceleration ``a`` from the
vehicle's broadcast (perfect sensing) or from the navigation filter's target states
(sensors), never the sea.

**The deck's frequency.** Two exponential averages of ``v^2`` and ``a^2`` with the time
constant ``motion_time`` (:data:`QUIESCENCE_STATE`) give the heave velocity's mean
frequency, the ratio of spectral moments ``omega^2 = m4 / m2`` of the heave (``m2`` the
velocity's variance, ``m4`` the acceleration's; the mean zero-crossing frequency of the
velocity, Rice 1944): ``omega = sqrt(<a^2> / <v^2>)``, clamped to
[:data:`OMEGA_MIN`, :data:`OMEGA_MAX`]. Both averages start at zero and share their
weights, so their ratio is a weighted mean from the first sample on: no warm-up.

**The prediction.** Over ``tau`` in ``[0, horizon]`` the heave velocity is extrapolated
as the oscillation at ``omega`` through the present ``v`` and ``a``,
``v(t + tau) = v cos(omega tau) + (a / omega) sin(omega tau)``, exact for one sinusoid
of frequency ``omega``. Its amplitude ``sqrt(v^2 + (a / omega)^2)`` is the heave's
share of the Energy Index (kinetic plus "potential" energy of the velocity's
oscillation). The predicted speed is the largest of ``|v(t + tau)|`` at
:data:`N_HORIZON` + 1 evenly spaced ``tau`` from 0 to ``horizon`` (fixed size, no
heap: the samples are unrolled into the generated C); over half a period or more it is
that amplitude. A deck falling fast is no calm window either: the quadrotor chases it
down and meets it as it turns.

All of it is branch-free CasADi, generated into C with the guidance step
(:mod:`quadland_symbolic.landing.guidance`, which commits the final descent when the
predicted speed stays below ``calm_speed``).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.layout import Field, Layout

__all__ = ["QUIESCENCE_STATE", "OMEGA_MIN", "OMEGA_MAX", "MS_FLOOR", "N_HORIZON",
           "quiescence_update", "sine_frequency", "sine_ahead", "deck_frequency",
           "heave_rate_ahead", "predicted_speed", "quiescence_function"]

#: The predictor's memory: the two exponential averages.
QUIESCENCE_STATE = Layout("x_quiet", (
    Field("ms_rise", 1, "m^2/s^2", "exponential average of the deck's vertical velocity squared"),
    Field("ms_rise_rate", 1, "m^2/s^4",
          "exponential average of the deck's vertical acceleration squared"),
), "quiescent-period predictor state")

#: Bounds of the deck frequency estimate, rad/s: ship heave lies within (periods 1 to 30 s);
#: the lower bound also holds a motionless deck (a car's roof: no motion, no frequency).
OMEGA_MIN, OMEGA_MAX = 0.2, 6.0
#: Floor of the velocity's average in the frequency's ratio, m^2/s^2 (a motionless deck;
#: representable in single precision).
MS_FLOOR = 1e-12
#: Intervals the prediction horizon is cut into.
N_HORIZON = 10


def quiescence_update(xq, v, a, dt, motion_time):
    """The averages after one step of length ``dt`` on the deck's rise ``v`` and its rate ``a``.

    Each average moves by ``min(dt / motion_time, 1)`` of the way to the new square.
    Returns ``xq_next`` (:data:`QUIESCENCE_STATE`).
    """
    q = QUIESCENCE_STATE.unpack(xq)
    k = ca.fmin(dt / motion_time, 1)
    return ca.vertcat(q["ms_rise"] + k * (v ** 2 - q["ms_rise"]),
                      q["ms_rise_rate"] + k * (a ** 2 - q["ms_rise_rate"]))


def sine_frequency(ms_x, ms_rate):
    """``sqrt(<x'^2> / <x^2>)`` from the two mean squares, clamped to [:data:`OMEGA_MIN`,
    :data:`OMEGA_MAX`], rad/s: exact for one sinusoid (the deck's heave, its tilt)."""
    ratio = ms_rate / ca.fmax(ms_x, MS_FLOOR)
    return ca.fmin(ca.fmax(ca.sqrt(ca.fmax(ratio, 0)), OMEGA_MIN), OMEGA_MAX)


def sine_ahead(x, x_dot, omega, tau):
    """One sinusoid's value ``tau`` ahead: ``x cos(omega tau) + (x' / omega) sin(omega tau)``."""
    return x * ca.cos(omega * tau) + x_dot / omega * ca.sin(omega * tau)


def deck_frequency(xq):
    """``sqrt(<a^2> / <v^2>)`` clamped to [:data:`OMEGA_MIN`, :data:`OMEGA_MAX`], rad/s."""
    q = QUIESCENCE_STATE.unpack(xq)
    return sine_frequency(q["ms_rise"], q["ms_rise_rate"])


def heave_rate_ahead(v, a, omega, tau):
    """The deck's rise ``tau`` ahead: ``v cos(omega tau) + (a / omega) sin(omega tau)``, m/s."""
    return sine_ahead(v, a, omega, tau)


def predicted_speed(v, a, omega, horizon):
    """Largest predicted vertical speed of the deck (rising or falling) over
    ``[0, horizon]``, at ``N_HORIZON + 1`` even samples, m/s."""
    speed = ca.fabs(v)
    for k in range(1, N_HORIZON + 1):
        speed = ca.fmax(speed, ca.fabs(heave_rate_ahead(v, a, omega, horizon * k / N_HORIZON)))
    return speed


def quiescence_function() -> ca.Function:
    """``quiescence(xq, v, a, dt, motion_time, horizon) -> (xq_next, omega, speed)``.

    One update of the averages, then the frequency and the predicted largest vertical
    speed over the horizon on the updated averages (the guidance's order).
    """
    xq = QUIESCENCE_STATE.sym()
    v, a, dt, tm, horizon = (ca.SX.sym(n) for n in ("v", "a", "dt", "motion_time", "horizon"))
    xq_next = quiescence_update(xq, v, a, dt, tm)
    omega = deck_frequency(xq_next)
    return ca.Function("quiescence", [xq, v, a, dt, tm, horizon],
                       [xq_next, omega, predicted_speed(v, a, omega, horizon)],
                       ["xq", "v", "a", "dt", "motion_time", "horizon"],
                       ["xq_next", "omega", "speed"])

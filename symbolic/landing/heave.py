"""The pad's vertical motion carried over a time as a harmonic oscillator.

docs/estimator.md (E17a). A deck that heaves, rolls and pitches in a sea moves its pad up
and down as a sum of sinusoids; the navigation filter knows the pad's vertical velocity
``v`` and acceleration ``a`` at its horizon and carries them ``T`` ahead. A constant
acceleration (the filter's random-walk model) misses the jerk; the harmonic oscillator of
frequency ``omega`` (``v'' = -omega^2 v``) predicts it as ``-omega^2 v``:

``a(T) = a cos(omega T) - omega v sin(omega T)``,
``v(T) = v cos(omega T) + a sin(omega T) / omega``,
``z(T) - z(0) = v sin(omega T) / omega + a (1 - cos(omega T)) / omega^2``.

Written with ``x = omega T``, ``s = sin(x) / x`` and ``h = (sin(x / 2) / (x / 2))^2``
(``(1 - cos x) / x^2 = h / 2``, without the cancellation of ``1 - cos x``):
``a(T) = a cos x - (omega^2 T s) v``, ``v(T) = v cos x + (T a) s``,
``z(T) - z(0) = (T v) s + (T^2 / 2) a h``. At ``omega = 0`` the factors ``cos x``, ``s``
and ``h`` are exactly 1 and the three are the constant acceleration's to the bit.

The same oscillator can replace the random-walk acceleration in the filter's own
prediction over a period (:func:`heave_transition`, (E17b)): the z rows of the pad's
velocity and acceleration and the pad's share of the relative height in ``Phi``. Its
frequency is the filter's own (E17a) or one given by the scenario
(``heave_frequency``, from the sea's spectrum); :data:`HEAVE_FIELDS` are its
parameters. ``heave_height`` keeps the oscillator (both forms) to the last metres over the
pad: above it the frequency is 0, the constant acceleration (:func:`heave_gate`).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kalman import select
from quadland_symbolic.layout import Field

__all__ = ["sinc", "heave_factors", "heave_transition", "heave_gate", "HEAVE_FIELDS",
           "HEAVE_DEFAULTS"]

#: The heave's parameters in ``p_est`` (docs/estimator.md (E17a), (E17b)).
HEAVE_FIELDS = (
    Field("heave_time", 1, "s", "averaging time of the pad's heave frequency (E17a)"),
    Field("heave_frequency", 1, "rad/s", "the pad's heave frequency given (E17b); 0: the "
          "filter's own (E17a)"),
    Field("heave_in_filter", 1, "-", "1: the pad's z is the oscillator in the filter's "
          "prediction too (E17b); 0: in the output predictor only"),
    Field("heave_height", 1, "m", "the heave's frequency (E17a, E17b) is used only while "
          "the horizon's relative height p_r z is at or below this; above it, 0"),
)
#: Their defaults: the constant acceleration (a flat deck), as before (E17a); no height gate.
HEAVE_DEFAULTS = {"heave_time": 0.0, "heave_frequency": 0.0, "heave_in_filter": 0.0,
                  "heave_height": 1.0e6}


def sinc(x):
    """``sin(x) / x`` for ``x >= 0``; exactly 1 at 0 (no division by it)."""
    pos = x > 0
    return select(pos, ca.sin(x) / select(pos, x, 1), 1)


def heave_factors(omega, T):
    """``(c, s, h)`` of the oscillator of frequency ``omega`` over ``T`` (module docstring).

    ``c = cos(omega T)``, ``s = sinc(omega T)``, ``h = sinc(omega T / 2)^2``; each 1 at
    ``omega T = 0``. ``omega`` and ``T`` are not negative.
    """
    x = omega * T
    half = sinc(x / 2)
    return ca.cos(x), sinc(x), half * half


def heave_transition(Phi, omega, dt, i_p, i_v, i_a):
    """``Phi`` with the pad's z over ``dt`` as the oscillator of frequency ``omega`` (E17b).

    ``i_p``, ``i_v``, ``i_a`` are the z entries of ``p_r``, ``v_t`` and ``a_t``. With
    ``(c, s, h)`` of :func:`heave_factors`: ``v+ = c v + (dt s) a``, ``a+ = c a - (omega^2
    dt s) v`` and ``p_r+`` loses the pad's rise ``(dt s) v + (dt^2 / 2) h a``, the rows'
    other entries as they were. At ``omega = 0`` every entry is the random walk's
    (``1``, ``dt``, ``dt^2 / 2``) and the new one ``-0``: the same prediction.
    """
    c, s, h = heave_factors(omega, dt)
    Phi = ca.SX(Phi)
    Phi[i_p, i_v] = -(dt * s)
    Phi[i_p, i_a] = -((dt * dt / 2) * h)
    Phi[i_v, i_v] = c
    Phi[i_v, i_a] = dt * s
    Phi[i_a, i_v] = -((omega * omega) * (dt * s))
    Phi[i_a, i_a] = c
    return Phi


def heave_gate(omega, p_r_z, p):
    """``omega`` while the relative height ``p_r_z`` is at or below ``p["heave_height"]``, else 0.

    The oscillator of (E17a) and (E17b) kept to the final descent: at 0 both forms are the
    constant acceleration to the bit, so above the gate the filter and its output are the
    random walk's. The default height (1e6 m) never gates.
    """
    return select(p_r_z <= p["heave_height"], omega, 0)

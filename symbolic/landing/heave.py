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
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kalman import select

__all__ = ["sinc", "heave_factors"]


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

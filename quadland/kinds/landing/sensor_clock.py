"""A sensor's unbounded sample clock, and where times fall on it (the sensors' draws,
:mod:`quadland.kinds.landing.sensing`)."""

from __future__ import annotations

import math

import numpy as np

from quadland.engine.loop import GRID_TOL

__all__ = ["SensorClock", "on_clock"]


class SensorClock:
    """A sensor's unbounded clock: ``phase + k / rate_hz`` (the loop's rule, to the bit)."""

    def __init__(self, rate_hz: float, phase: float):
        self.rate, self.phase, self.h = rate_hz, phase, 1.0 / rate_hz

    def times(self, k0: int, k1: int) -> np.ndarray:
        return self.phase + self.h * np.arange(k0, k1)

    def count(self, horizon: float) -> int:
        """Samples before ``horizon``, s; a sample within :data:`GRID_TOL` of a period of
        it counts as at it (not before): a tolerance of the clock's period, whatever the
        horizon (a tolerance growing with the horizon dropped samples of long flights)."""
        return max(0, math.ceil((horizon - self.phase) * self.rate - GRID_TOL))

    def before_tick(self, tick: int, rate: float) -> int:
        """Samples on the ticks of a ``rate`` Hz clock before ``tick``, in integers: the
        sensor's samples fall on its ticks (every ``rate / rate_hz``-th from the
        ``phase * rate``-th, as the schema checks)."""
        stride, first = round(rate / self.rate), round(self.phase * rate)
        return max(0, -(-(int(tick) - first) // stride))

    def ticks(self, k0: int, k1: int, rate: float) -> slice:
        """The ticks of samples ``k0`` to ``k1`` on a ``rate`` Hz clock (:meth:`before_tick`'s)."""
        stride, first = round(rate / self.rate), round(self.phase * rate)
        return slice(first + stride * k0, first + stride * (k1 - 1) + 1, stride)


def on_clock(clock: SensorClock, times: np.ndarray) -> np.ndarray:
    """Each time's tick of ``clock`` where they coincide (within :data:`GRID_TOL` of its
    period: the loop's grid rule), else -1."""
    k = np.rint((times - clock.phase) * clock.rate).astype(np.int64)
    hit = (k >= 0) & (np.abs(clock.phase + clock.h * k - times) <= GRID_TOL * clock.h)
    return np.where(hit, k, -1)

"""The sensors' table as the tests expect it: each sensor's samples from ``draw_sensors``
placed one by one on the row of its tick, every other entry zero."""

from __future__ import annotations

import numpy as np

from quadland_symbolic.landing.sensed_loop import SENSED_TICK
from quadland_symbolic.landing.sensors import SENSOR_NAMES


def placed_table(draws, shape: tuple[int, int], rate: float) -> np.ndarray:
    """A table of ``shape`` with each sample of ``draws`` (``draw_sensors``'s result) on
    the row ``round(t * rate)``: its sampled flag 1, its kept flag and its noise."""
    expect = np.zeros(shape)
    for name in SENSOR_NAMES:
        s = draws[name]
        for t, kept, noise in zip(s.times, s.delivered, s.noise, strict=True):
            row = expect[round(t * rate)]
            row[SENSED_TICK.slice(f"{name}_sampled")] = 1.0
            row[SENSED_TICK.slice(f"{name}_kept")] = float(kept)
            row[SENSED_TICK.slice(f"{name}_noise")] = noise
    return expect

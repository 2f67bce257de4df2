"""Random packets for the navigation filter's step: mostly stale garbage the step must not
read, else due, late, old, from the future, not finite or an outlier (the flights of the
filter's bit-for-bit tests: tests/test_estimator_switch.py, tests/test_lockstep.py)."""

from __future__ import annotations

import math

import numpy as np

#: the control period the packets' times are drawn around (250 Hz)
DT = 0.004


def packet(layout, rng, t, t_h):
    """A packet: mostly not fresh (garbage the step must not read), else of some kind."""
    v = np.zeros(layout.size)
    if rng.uniform() > 0.3:
        v[:] = rng.choice((math.nan, math.inf, 1e30, -3.0), size=v.size)
        v[0] = 0.0
        return v
    kind = rng.choice(("due", "due", "due", "late", "old", "future", "nan", "outlier"))
    v[:] = rng.normal(size=layout.size) * 0.3 + (100.0 if kind == "outlier" else 0.0)
    v[0] = 1.0
    v[1] = {"late": t_h - rng.uniform(0, 0.016), "old": t_h - rng.uniform(0.03, 0.1),
            "future": t + rng.uniform(DT, 0.1)}.get(kind, t - rng.uniform(0, 0.19))
    if layout.name == "range":
        v[layout.slice("b3_E")] = [0.0, 0.0, 1.0] if rng.uniform() > 0.1 else [1.0, 0.0, 0.1]
        v[layout.slice("s")] = 3.0 + rng.normal() * 0.05
    if kind == "nan":
        v[rng.integers(2, v.size)] = math.nan
    return v

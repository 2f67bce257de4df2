"""The output predictor's sums carried from period to period, against the shipped ones.

The filter's output predictor (:func:`quadland_symbolic.landing.nav_output.output_predictor`)
sums its ``n`` buffered inputs newest first every period: ``S1 = sum a_k dt_k``,
``S2 = sum a_k dt_k (dt_k / 2 + sum_{j>k} dt_j)``. Carried instead (the oldest input's
terms taken out, the others aged by the period, the newest added), the sums are those
values in exact arithmetic but not in floating point. This NumPy model of the two, at the
flight's period over a flight's periods of random inputs, counts the periods whose sums
are bit-equal and the largest differences (docs/performance.md, issue 20, thirteenth).

Run: ``python benchmarks/predictor_running_sums.py``.
"""

from __future__ import annotations

import numpy as np

N, PERIODS, DT = 50, 2886, 0.004


def shipped(cols: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """``(S1, S2, T)`` summed newest first, as the predictor does."""
    s1, s2, after = np.zeros(3), np.zeros(3), 0.0
    for k in reversed(range(N)):
        s1 = s1 + cols[k] * DT
        s2 = s2 + cols[k] * (DT * (DT / 2 + after))
        after = after + DT
    return s1, s2, after


def main() -> None:
    rng = np.random.default_rng(0)
    a = np.column_stack([rng.normal(0, 1.5, PERIODS + N), rng.normal(0, 1.5, PERIODS + N),
                         9.80665 + rng.normal(0, 2.0, PERIODS + N)])
    s1c, s2c, total = shipped(a[0:N])
    same1 = same2 = 0
    d1 = d2 = 0.0
    for p in range(1, PERIODS):
        old, new = a[p - 1], a[p - 1 + N]
        s2c = (s2c - old * (DT * (DT / 2 + (total - DT))) + (s1c - old * DT) * DT
               + new * (DT * (DT / 2)))
        s1c = s1c - old * DT + new * DT
        s1, s2, total = shipped(a[p:p + N])
        same1 += np.array_equal(s1, s1c)
        same2 += np.array_equal(s2, s2c)
        d1, d2 = max(d1, np.abs(s1 - s1c).max()), max(d2, np.abs(s2 - s2c).max())
    print(f"{PERIODS - 1} periods: S1 bit-equal in {same1}, largest |dS1| {d1:.2e} m/s; "
          f"S2 bit-equal in {same2}, largest |dS2| {d2:.2e} m")


if __name__ == "__main__":
    main()

"""How often a perfectly consistent filter meets the consistency test's criterion.

tests/test_consistency.py asks the average NEES of 100 hovers to lie within its
two-sided 95 % chi-square bounds at 95 % of the settled ticks. Each tick's average is
one draw whose 95 % bounds are exact, but consecutive ticks are not independent: the
filter's normalized errors are correlated over seconds (the hover's vertical ones:
autocorrelation 0.46 to 0.59 at 1 s, 0.17 to 0.37 at 2 s; docs/estimator.md,
"Consistency", item 8). A 5 s window then holds a few independent draws, and the share
of the ticks inside varies from batch to batch even for a filter that is exactly right.

This script draws that filter: ``runs`` hovers of ``dof`` independent standard normal
errors, each a first-order Gauss-Markov process of correlation time ``tau`` sampled at
250 Hz over the 5 s after the settling time (1250 ticks), so each tick's NEES is
chi-square of ``dof`` as the bounds assume. For each ``tau`` it prints, over
``--batches`` batches, the average share of ticks inside, the share of batches that
meet the 95 % criterion, and the 10th and 5th percentiles of the share.

It then validates the correlation-aware criterion beside it
(:func:`quadland.kinds.landing.time_averaged_nees.time_averaged_nees`: the time-averaged
NEES against bounds with the effective number of independent ticks measured from the
batch's own autocorrelation): the share of batches it accepts for the consistent filter
(about 95 % wanted), and for a filter whose NEES is ``--scales`` times too large
(overconfident, 1.5) or too small (underconfident, 0.67), which it must reject.

Run from the repository root (about a minute)::

    python benchmarks/consistency_criterion_odds.py
"""

from __future__ import annotations

import argparse

import numpy as np
from scipy.signal import lfilter
from scipy.stats import chi2

from quadland.kinds.landing.time_averaged_nees import time_averaged_nees


def shares_inside(tau: float, batches: int, runs: int = 100, dof: int = 6,
                  ticks: int = 1250, dt: float = 0.004, seed: int = 1) -> np.ndarray:
    """The share of ticks inside the bounds in each of ``batches`` batches."""
    rng = np.random.default_rng(seed)
    lo, hi = chi2.ppf(0.025, runs * dof) / runs, chi2.ppf(0.975, runs * dof) / runs
    rho = np.exp(-dt / tau)
    kick = np.sqrt(1.0 - rho ** 2)
    out = np.empty(batches)
    for b in range(batches):
        x = rng.standard_normal((runs, dof))
        mean = np.empty(ticks)
        for k in range(ticks):
            mean[k] = np.mean(np.sum(x * x, axis=1))
            x = rho * x + kick * rng.standard_normal((runs, dof))
        out[b] = np.mean((mean >= lo) & (mean <= hi))
    return out


def nees_batches(tau: float, batches: int, runs: int = 100, dof: int = 6,
                 ticks: int = 1250, dt: float = 0.004, seed: int = 2):
    """``batches`` arrays ``(runs, ticks)`` of a consistent filter's NEES, one at a time:
    the sum of ``dof`` squared unit Gauss-Markov errors of correlation time ``tau``."""
    rng = np.random.default_rng(seed)
    rho = np.exp(-dt / tau)
    for _ in range(batches):
        w = rng.standard_normal((runs, dof, ticks)) * np.sqrt(1.0 - rho ** 2)
        w[:, :, 0] = rng.standard_normal((runs, dof))       # stationary from the start
        x = lfilter([1.0], [1.0, -rho], w, axis=2)
        yield np.sum(x * x, axis=1)


def accepted(tau: float, batches: int, scales=(1.0, 1.5, 0.67), dof: int = 6) -> dict:
    """The share of batches the time-averaged criterion accepts, per NEES scale; and the
    average effective number of independent ticks per run it measured."""
    hits = {s: 0 for s in scales}
    k_eff = []
    for nees in nees_batches(tau, batches, dof=dof):
        for s in scales:
            c = time_averaged_nees(s * nees, dof)
            hits[s] += c.inside
        k_eff.append(c.effective_ticks)
    return {s: h / batches for s, h in hits.items()} | {"k_eff": float(np.mean(k_eff))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--batches", type=int, default=200)
    parser.add_argument("--tau", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0])
    parser.add_argument("--scales", type=float, nargs="+", default=[1.0, 1.5, 0.67])
    parser.add_argument("--skip-per-tick", action="store_true")
    args = parser.parse_args()
    for tau in [] if args.skip_per_tick else args.tau:
        s = shares_inside(tau, args.batches)
        print(f"tau {tau:3.1f} s: inside {s.mean():.3f} on average; "
              f"{np.mean(s >= 0.95):.2f} of the batches meet 95 %; "
              f"10th percentile {np.percentile(s, 10):.3f}, 5th {np.percentile(s, 5):.3f}")

    print("the time-averaged NEES (correlation-aware): share of batches accepted")
    for tau in args.tau:
        a = accepted(tau, args.batches, tuple(args.scales))
        print(f"tau {tau:3.1f} s: " + ", ".join(f"NEES x {s:g}: {a[s]:.3f}" for s in args.scales)
              + f"; K_eff {a['k_eff']:.1f} independent ticks per run")


if __name__ == "__main__":
    main()

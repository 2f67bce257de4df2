"""The filter's consistency criterion over several batches of seeds (issue 17, sec. 6).

tests/test_consistency.py checks the criterion at the highway's own seeds (2024-):
every NEES group's batch average inside its two-sided 95 % chi-square bounds at 95 %
of the settled times, every block's pooled NIS inside its bounds. This script prints
the same figures for other batches (docs/estimator.md, "Other batches of seeds"), one
line per batch: each group's average NEES and the share of the times inside (the
per-tick criterion), the correlation-aware bounds of its time average in brackets
(``OUT`` when outside; quadland.kinds.landing.time_averaged_nees), and the blocks whose
pooled NIS lies outside its bounds (``--nis``: every block's).

Run from the repository root (about 1 s of CPU per hover)::

    python benchmarks/consistency_batches.py                     # 2024, 5000, 7000
    python benchmarks/consistency_batches.py "estimator.q_ab=[...]" --seeds 5000 7000
"""

from __future__ import annotations

import argparse

from quadland.kinds.landing.consistency import NEES_GROUPS, consistency_monte_carlo
from quadland.scenario import load_scenario


def line(scenario, seed: int, runs: int, duration: float, every_nis: bool = False) -> str:
    """One batch's figures, as docs/estimator.md's table gives them."""
    mc = consistency_monte_carlo(scenario, runs=runs, duration=duration, seed=seed)
    s = mc.summary()
    parts = [f"{duration:g} s, seeds {seed}-"]
    for g in NEES_GROUPS:
        ta = s["nees"][g]["time_averaged"]
        parts.append(f"{g} {s['nees'][g]['mean']:.2f}, {100 * s['nees'][g]['inside']:.1f} % "
                     f"[{ta['lo']:.2f}, {ta['hi']:.2f}{'' if ta['inside'] else ' OUT'}]")
    out = [f"{b} {v['mean']:.3f} ({'<' if v['mean'] < v['lo'] else '>'} "
           f"{v['lo'] if v['mean'] < v['lo'] else v['hi']:.3f})"
           for b, v in s["nis"].items() if not v["lo"] <= v["mean"] <= v["hi"]]
    parts.append("NIS outside: " + (", ".join(out) if out else "none"))
    if every_nis:
        parts.append("NIS " + ", ".join(f"{b} {v['mean']:.3f}" for b, v in s["nis"].items()))
    return " | ".join(parts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway")
    parser.add_argument("--seeds", type=int, nargs="+", default=[2024, 5000, 7000])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--nis", action="store_true", help="every block's NIS as well")
    parser.add_argument("overrides", nargs="*", help="key=value, as quadland simulate --set")
    args = parser.parse_args()
    scenario = load_scenario(args.scenario, args.overrides)
    if args.overrides:
        print("with " + " ".join(args.overrides))
    for seed in args.seeds:
        print(line(scenario, seed, args.runs, args.duration, args.nis), flush=True)


if __name__ == "__main__":
    main()

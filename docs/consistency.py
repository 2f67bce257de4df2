"""Regenerate the figures and numbers of docs/estimator.md's "Consistency".

Run from the repository root:  python docs/consistency.py [--runs 100] [--duration 15]
Writes docs/figures/nees_nis.png (the Monte Carlo of hovers over the highway's moving
pad) and docs/figures/navigation.png (the highway's landing at its default seed: the
filter's estimate, the truth, 3 sigma) and prints the measured NEES and NIS.
"""

import argparse
import time
from pathlib import Path

import quadland
from quadland.kinds.landing.consistency import consistency_monte_carlo
from quadland.output import figure_png, write_bytes_atomic
from quadland.plots import consistency_plot, navigation_plot

HERE = Path(__file__).parent


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--duration", type=float, default=15.0, help="s, each hover")
    args = parser.parse_args(argv)
    scenario = quadland.load_scenario("highway")
    start = time.perf_counter()
    # run i flies simulation.seed = the scenario's (2024) + i
    mc = consistency_monte_carlo(scenario, runs=args.runs, duration=args.duration)
    elapsed = time.perf_counter() - start
    # docs/figures is part of the source tree, not a quadland output folder: each PNG is
    # replaced on its own (as docs/reproduce_paper.py does)
    folder = HERE / "figures"
    write_bytes_atomic(folder / "nees_nis.png", figure_png(consistency_plot(mc)))
    landing = quadland.simulate(scenario)
    write_bytes_atomic(folder / "navigation.png", figure_png(navigation_plot(landing)))
    s = mc.summary()
    print(f"{mc.runs} hovers of {args.duration:g} s over the {scenario.name} pad, seeds "
          f"{mc.seeds[0]}-{mc.seeds[-1]}, settled from {mc.settle:g} s ({elapsed:.1f} s)")
    print("| NEES of | dof | average | 95 % bounds | times inside |")
    print("| --- | ---: | ---: | --- | ---: |")
    for g, v in s["nees"].items():
        lo, hi = v["bounds"]
        print(f"| {g} | {v['dof']} | {v['mean']:.2f} | {lo:.2f}-{hi:.2f} | "
              f"{v['inside']:.0%} |")
    print("| NIS of | dof | packets | average | 95 % bounds | times inside |")
    print("| --- | ---: | ---: | ---: | --- | ---: |")
    for b, v in s["nis"].items():
        print(f"| {b} | {v['dof']} | {v['n']} | {v['mean']:.3f} | {v['lo']:.3f}-{v['hi']:.3f} "
              f"| {v['inside']:.0%} |")
    for b, v in s["outliers"].items():
        if v["n"]:
            print(f"{b}: {v['n']} of {v['due']} due packets outliers of the world, kept "
                  f"apart (median NIS {v['median_nis']:.0f})")


if __name__ == "__main__":
    main()

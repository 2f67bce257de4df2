"""Where an envelope's landings spend their time, by outcome (issue 20).

Flies ``--runs`` runs spread evenly over the cells of an envelope (by default issue 20's
``highway`` map: the car's speed 5 to 35 m/s against the crosswind 0 to 20 m/s, 20 x 20
cells of 30 runs), each as a campaign flies it (``quadland.campaign.fly.fly``), and the
landing again, timed alone (CPU: the dispersed scenario and ``quadland.simulate``); groups
the runs by outcome (landed, no touchdown, tipped over, a missed limit, a numerical
failure) and prints each group's share of the runs and of the CPU, its mean CPU, the time
flown and the touchdown's instant::

    nice -n 10 python benchmarks/profile_envelope_outcomes.py --runs 150
"""

from __future__ import annotations

import argparse
import collections
import statistics
import time

from quadland.campaign.cells import failure_modes
from quadland.campaign.dispersed import dispersed
from quadland.campaign.fly import fly
from quadland.campaign.grid import cell_draws, plan_envelope
from quadland.exceptions import SimulationError
from quadland.kinds.landing.simulate import simulate_landing


def outcome(out) -> str:
    if out.status != "ok":
        return "numerical failure"
    if out.metrics.get("touchdown_time") is None:
        return "no touchdown"
    if out.metrics.get("tipped"):
        return "tipped over"
    return "landed" if out.success else "missed: " + ", ".join(
        failure_modes(out.status, out.success, out.message))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway")
    parser.add_argument("--axis", action="append",
                        default=None, help="KEY=LO:HI:N (twice; default issue 20's map)")
    parser.add_argument("--runs-per-cell", type=int, default=30)
    parser.add_argument("--runs", type=int, default=150)
    a = parser.parse_args()
    axes = a.axis or ["initial.velocity2[0]=5:35:20", "wind.mean[1]=0:20:20"]
    env = plan_envelope(a.scenario, None, axes, a.runs_per_cell)
    step = env.runs // a.runs
    indices = [i * step + (i * 7) % step for i in range(a.runs)]
    fly(env.base, next(iter(cell_draws(env, [0]))))          # the simulator built or loaded
    groups = collections.defaultdict(list)
    for draw in cell_draws(env, indices):
        t0 = time.process_time()
        try:
            result = simulate_landing(dispersed(env.base, draw.values))
        except SimulationError as exc:
            result = exc.partial
        cpu = time.process_time() - t0
        out = fly(env.base, draw)
        flown = float(result["t"][-1]) if result is not None and len(result["t"]) else 0.0
        groups[outcome(out)].append((cpu, flown, out.metrics.get("touchdown_time")))
    total = sum(c for rows in groups.values() for c, _, _ in rows)
    print(f"{a.runs} runs of {env.runs}: {1e3 * total / a.runs:.1f} ms CPU a landing")
    print("| outcome | runs | share of the CPU | CPU a landing, ms | flown, s | touchdown, s |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, rows in sorted(groups.items(), key=lambda kv: -sum(r[0] for r in kv[1])):
        td = [r[2] for r in rows if r[2] is not None]
        print(f"| {name} | {len(rows)} | {sum(r[0] for r in rows) / total:.0%} | "
              f"{1e3 * statistics.mean(r[0] for r in rows):.1f} | "
              f"{statistics.mean(r[1] for r in rows):.1f} | "
              f"{statistics.mean(td) if td else float('nan'):.1f} |")


if __name__ == "__main__":
    main()

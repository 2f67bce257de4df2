"""The plant's terms of time alone computed once an instant (issue 20), paired in one process.

The runtime's simulator of a scenario's default landing (``split``: the plant's, free
plant's and event's terms of the time and the parameters alone in functions of their
own, ``<function>_time``, which the driver calls once an instant,
:func:`quadland_symbolic.codegen.time_split.time_split`) against the same model built
without them (``whole``: ``quadland_symbolic.codegen.simulator.HOISTING`` empty, the
model renamed ``<model>_whole``, a build of its own). Each build's flight is checked the
same bits first (every recorded row, state and the end state), then both are flown
alternately in one process (CPU ms, median of ``--rounds``). ``--callgrind NAME`` flies
one build once, for (``<model>``: ``landing_sensed_flat`` for ``highway``,
``landing_sensed`` for ``ship``; ``_whole`` appended for that build; the ``_time``
functions exist only in ``split``)::

    valgrind --tool=callgrind --toggle-collect=qlsim_<model>_controller \\
        --toggle-collect=qlsim_<model>_plant --toggle-collect=qlsim_<model>_free_plant \\
        --toggle-collect=qlsim_<model>_event --toggle-collect=qlsim_<model>_plant_time \\
        --toggle-collect=qlsim_<model>_free_plant_time \\
        --toggle-collect=qlsim_<model>_event_time \\
        python benchmarks/bench_time_split.py --flights ship --callgrind split

The driver's check of the instant (a comparison of 8 bytes a call) is outside the
functions counted, as the driver's loop is.

With ``--before TREE`` (``git archive <commit> | tar -x -C TREE``), a one-worker
campaign of ``--runs`` landings of each of ``--campaigns`` on the tree and on this code,
in fresh child processes, alternately (``--campaign-rounds`` each): its CPU and its
``runs.csv``'s SHA-256.

Run from the repository root: ``nice -n 10 python benchmarks/bench_time_split.py``.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_compiled_flight import report_flights, timed_flights  # noqa: E402
from bench_delivery_ring import captured  # noqa: E402
from bench_landing_costs import child  # noqa: E402

from quadland.engine.compiled import CompiledLoop, built_model  # noqa: E402
from quadland_symbolic.codegen import simulator  # noqa: E402

#: A one-worker campaign of argv[2] runs of argv[1]: CPU, wall, runs.csv's SHA-256.
CAMPAIGN = r"""
import hashlib, json, sys, tempfile, time
from pathlib import Path
from quadland.campaign.execute import run_campaign
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario

warm_up(load_scenario(sys.argv[1]))
with tempfile.TemporaryDirectory() as tmp:
    c0, w0 = time.process_time(), time.perf_counter()
    r = run_campaign(sys.argv[1], runs=int(sys.argv[2]), out=Path(tmp) / "c", plots=False,
                     workers=1)
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    s = json.loads((r.folder / "summary.json").read_text())
    csv = hashlib.sha256((r.folder / "runs.csv").read_bytes()).hexdigest()
print(json.dumps({"cpu": cpu, "wall": wall, "csv": csv, "successes": s["successes"],
                  "runs": s["runs"]}))
"""


def campaigns(before: Path, scenarios, runs: int, rounds: int) -> None:
    """Each scenario's one-worker campaign on ``before`` and on this code, alternately."""
    trees = {"before": before, "now": None}
    for s in scenarios:
        out: dict = {k: [] for k in trees}
        for r in range(rounds):
            for k in (list(trees) if r % 2 == 0 else list(trees)[::-1]):
                out[k].append(child(CAMPAIGN, trees[k], s, str(runs)))
        for k, v in out.items():
            cpu = ", ".join(f"{r['cpu']:.2f}" for r in v)
            print(f"- {s}, {runs} runs, one worker, {k}: CPU {cpu} s, "
                  f"{v[-1]['successes']} of {v[-1]['runs']} landed, runs.csv "
                  f"{v[-1]['csv'][:16]}")
        same = len({r["csv"] for v in out.values() for r in v}) == 1
        print(f"- {s}: runs.csv before and now "
              f"{'byte for byte the same' if same else 'DIFFERENT'}")


def builds(scenario: str):
    """``{"whole": ..., "split": ...}`` simulators of ``scenario`` (``split`` the
    runtime's), its flight's arguments."""
    split, args, kwargs = captured(scenario)
    model = built_model(split.model)
    real = simulator.HOISTING
    simulator.HOISTING = ()
    try:
        whole = CompiledLoop(dataclasses.replace(model, name=f"{model.name}_whole"), "sampled")
    finally:
        simulator.HOISTING = real
    return {"whole": whole, "split": split}, args, kwargs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--flights", default="highway,ship")
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--callgrind", choices=("whole", "split"))
    parser.add_argument("--before", type=Path)
    parser.add_argument("--campaigns", default="ship,highway")
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--campaign-rounds", type=int, default=2)
    a = parser.parse_args()
    print(f"load average {os.getloadavg()}")
    for s in filter(None, a.flights.split(",")):
        loops, args, kwargs = builds(s)
        if a.callgrind:
            loops[a.callgrind].sampled(*args, **kwargs)
            continue
        out = timed_flights({"baseline, libm": loops["whole"], "split": loops["split"]},
                            args, kwargs, a.rounds)
        report_flights(s, out, a.rounds, "of the whole build's")
    if a.before is not None:
        campaigns(a.before.resolve(), a.campaigns.split(","), a.runs, a.campaign_rounds)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()

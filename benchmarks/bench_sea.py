"""Sea states: how many wave components a deck needs, and what they cost.

Measured:

* **the cost** of ``N_SEA`` components per motion
  (``quadland_symbolic.landing.deck.N_SEA``): ``quadland.simulate`` warm (the
  compiled simulator built beforehand), CPU time, median of 5, of the
  ``ship`` scenario on its sensors hovering over the deck for 60 s
  (``landing.dwell_time`` longer than the run: the same flight whatever the
  sea), and its whole landing at the default seed. ``N_SEA = 0`` is the
  deck before sea states (three sinusoids per motion, the ship's old
  ones at ``sea_state = 0``); the others fly sea state 4. Each ``N_SEA`` runs
  in its own process with the constant patched in the deck module's source
  before anything imports it (the layouts are fixed at import);
* **the fidelity** of ``n`` components: the ship's vessel in sea states 4
  and 5, over 20 seeds of 2 hours each at 10 Hz, the pad's vertical velocity
  (small angles: ``heave - x_pad theta2 + y_pad phi2``, differentiated
  analytically): its standard deviation, the share of the time it rises
  faster than ``landing.max_deck_rise`` and the mean length of the windows
  in which it does not, and the heave's kurtosis (3 for the Gaussian sea the
  spectrum describes), against 512 components.

Run from the repository root::

    python benchmarks/bench_sea.py            # about 8 minutes (one build per N_SEA)
    python benchmarks/bench_sea.py --write    # and rewrite docs/sea.md's measured part
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
from pathlib import Path

import numpy as np

DOC = Path(__file__).resolve().parents[1] / "docs" / "sea.md"
BEGIN, END = "<!-- bench_sea: begin -->", "<!-- bench_sea: end -->"
COSTS = (0, 8, 16, 24, 32)
FIDELITY = (8, 16, 24, 32, 48)
REFERENCE = 512
SEEDS = range(20)
OLD_SHIP = ["deck.sea_state=0", "deck.heave_amplitude=[0.68]", "deck.heave_frequency=[0.349]",
            "deck.roll_amplitude_deg=[0.62]", "deck.roll_frequency=[0.286]",
            "deck.roll_phase_deg=[40.0]", "deck.pitch_amplitude_deg=[0.52]",
            "deck.pitch_frequency=[0.524]", "deck.pitch_phase_deg=[110.0]"]

#: The child process: patch N_SEA, then time the ship.
CHILD = r'''
import importlib.util, json, statistics, sys, time
n = int(sys.argv[1])
name = "quadland_symbolic.landing.deck"
spec = importlib.util.find_spec(name)
source = open(spec.origin).read()
assert source.count("\nN_SEA = ") == 1
head, tail = source.split("\nN_SEA = ")
source = head + f"\nN_SEA = {n}" + tail[tail.index("\n"):]
module = importlib.util.module_from_spec(spec)
sys.modules[name] = module
exec(compile(source, spec.origin, "exec"), module.__dict__)
import quadland
from quadland.kinds.landing.report import landing_summary
from quadland.scenario import load_scenario
extra = json.loads(sys.argv[2])
hover = load_scenario("ship", extra + ["simulation.duration=60.0", "landing.dwell_time=1000.0"])
land = load_scenario("ship", extra)

def cpu(sc):
    quadland.simulate(sc)
    times = []
    for _ in range(5):
        start = time.process_time()
        quadland.simulate(sc)
        times.append(time.process_time() - start)
    return statistics.median(times)

summary = landing_summary(quadland.simulate(land))["landing"]
print(json.dumps({"per_second_ms": 1e3 * cpu(hover) / 60.0, "landing_ms": 1e3 * cpu(land),
                  "landed_at": summary["time"], "aborts": summary["aborts"],
                  "success": summary["success"]}))
'''


def cost(n: int) -> dict:
    """The child's figures for ``N_SEA = n``."""
    extra = OLD_SHIP if n == 0 else []
    out = subprocess.run([sys.executable, "-c", CHILD, str(n), json.dumps(extra)],
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _windows(quiet: np.ndarray, dt: float) -> float:
    """Mean length (s) of the runs of True in ``quiet``."""
    edges = np.diff(np.concatenate([[0], quiet.astype(int), [0]]))
    lengths = np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)
    return float(lengths.mean() * dt) if len(lengths) else 0.0


def fidelity(n: int, sea_state: int) -> dict:
    """The pad's vertical velocity and the heave's kurtosis over ``SEEDS`` with ``n``
    components."""
    from quadland.engine.sea import sea_components
    from quadland.kinds.landing.sea import sea_of, sea_seed
    from quadland.scenario import load_scenario

    sc = load_scenario("ship", [f"deck.sea_state={sea_state}"])
    hs, tp, gamma, vessel = sea_of(sc)
    x_pad, y_pad, _ = sc["deck.pad_offset"]
    rise = sc["landing.max_deck_rise"]
    dt, t = 0.1, np.arange(0.0, 7200.0, 0.1)
    std, share, window, kurt = [], [], [], []
    for seed in SEEDS:
        c = sea_components(hs, tp, gamma, vessel, n, np.random.default_rng(sea_seed(seed)),
                           sc["quadrotor.gravity"])
        # each motion as sum Re(C e^(i w t)): a sin(w t + phase) = Re(-i a e^(i phase) e^(i w t))
        C = -1j * c.amp * np.exp(1j * c.phase)                             # (3, n)
        vz_c = 1j * c.freq * (C[0] - x_pad * C[2] + y_pad * C[1])
        heave, vz = np.empty_like(t), np.empty_like(t)
        for start in range(0, len(t), 3600):
            e = np.exp(1j * c.freq[:, None] * t[None, start:start + 3600])
            heave[start:start + 3600] = (C[0] @ e).real
            vz[start:start + 3600] = (vz_c @ e).real
        std.append(vz.std())
        share.append(np.mean(vz > rise))
        window.append(_windows(vz <= rise, dt))
        kurt.append(np.mean((heave - heave.mean()) ** 4) / heave.var() ** 2)
    return {"vz_std": float(np.mean(std)), "rise_share": float(np.mean(share)),
            "quiet_window": float(np.mean(window)), "kurtosis": float(np.mean(kurt))}


def measure() -> dict:
    return {"costs": {n: cost(n) for n in COSTS},
            "fidelity": {ss: {n: fidelity(n, ss) for n in (*FIDELITY, REFERENCE)}
                         for ss in (4, 5)}}


def markdown(m: dict) -> str:
    lines = [f"Measured by `python benchmarks/bench_sea.py` ({platform.machine()}, Python "
             f"{platform.python_version()}).", "",
             "**Cost** (`quadland simulate --scenario ship` warm, CPU time, median of 5; the "
             "ship on its sensors):", "",
             "| `N_SEA` | deck | ms per simulated second (60 s hover) | whole landing (ms) "
             "| touchdown at (s) | aborts |", "| ---: | --- | ---: | ---: | ---: | ---: |"]
    for n, c in m["costs"].items():
        deck = "3 sinusoids (before sea states)" if n == 0 else "sea state 4"
        landed = "none" if c["landed_at"] is None else f"{c['landed_at']:.1f}"
        lines.append(f"| {n} | {deck} | {c['per_second_ms']:.2f} | {c['landing_ms']:.0f} | "
                     f"{landed} | {c['aborts']} |")
    lines += ["", f"**Fidelity** (the ship's vessel; {len(SEEDS)} seeds of 2 h at 10 Hz; the "
              "pad's vertical velocity `vz`; 'quiet' is `vz <= landing.max_deck_rise`):", ""]
    for ss, rows in m["fidelity"].items():
        lines += [f"Sea state {ss}:", "",
                  "| components | `vz` std (m/s) | time rising faster than 0.5 m/s | "
                  "mean quiet window (s) | heave kurtosis |",
                  "| ---: | ---: | ---: | ---: | ---: |"]
        for n, f in rows.items():
            lines.append(f"| {n} | {f['vz_std']:.3f} | {100 * f['rise_share']:.1f} % | "
                         f"{f['quiet_window']:.2f} | {f['kurtosis']:.2f} |")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="rewrite docs/sea.md's part")
    args = parser.parse_args()
    m = measure()
    print(json.dumps(m))
    text = markdown(m)
    print(text)
    if args.write:
        doc = DOC.read_text()
        head, rest = doc.split(BEGIN)
        _, tail = rest.split(END)
        DOC.write_text(f"{head}{BEGIN}\n\n{text}\n{END}{tail}")


if __name__ == "__main__":
    main()

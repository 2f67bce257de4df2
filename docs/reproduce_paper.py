"""Regenerate the figures and numbers of docs/paper-reproduction.md.

Run from the repository root:  python docs/reproduce_paper.py
Writes docs/figures/<variant>/*.png and prints the measured figures of merit.
"""

from pathlib import Path

import numpy as np

import quadland
from quadland.kinds.paper.report import summarize
from quadland.output import figure_png, write_bytes_atomic
from quadland.plots import simulation_figures

VARIANTS = {"printed": ["controller.nominal_model=false"],
            "nominal": ["controller.nominal_model=true"]}
HERE = Path(__file__).parent


def main():
    for variant, overrides in VARIANTS.items():
        res = quadland.simulate(quadland.load_scenario("paper", overrides))
        # docs/figures/<variant> is part of the source tree, not a quadland output folder
        # (write_files would refuse it, and mark it): each PNG is replaced on its own.
        folder = HERE / "figures" / variant
        folder.mkdir(parents=True, exist_ok=True)
        for name, fig in simulation_figures(res).items():
            write_bytes_atomic(folder / name, figure_png(fig))
        s = summarize(res)
        print(f"## {variant}")
        for name, e in s["errors"].items():
            if "settling_time" in e:
                print(f"  {name}: settling {e['settling_time']} s (band {e['settling_band']:.4g}),"
                      f" peak {e['peak']['value']:.4g} at {e['peak']['time']} s,"
                      f" final {e['final']:.3g}")
        print(f"  min z_e {res['z_e'].min():.3f} m at {res['t'][np.argmin(res['z_e'])]:.2f} s")
        inp = s["inputs"]
        print("  peak u:", {k: round(inp[k]["value"], 3) for k in ("u_1", "u_2", "u_3", "u_4")})
        print(f"  peak F_total {inp['F_total']['value']:.1f} N, rotors"
              f" {inp['rotor_min']:.1f} .. {inp['rotor_max']:.1f} N")
        thrust = res["F_total"]
        print(f"  F_total {thrust.min():.2f} .. {thrust.max():.2f} N, positive from"
              f" {res['t'][np.argmax(thrust > 0)]:.2f} s")
        late = res["t"] >= 1.0
        rotors = np.vstack([res[f"F_{i}"][late] for i in range(1, 5)])
        print(f"  rotors after 1 s: {rotors.min():.2f} .. {rotors.max():.2f} N")
        for ch, v in s["estimation_second_half"].items():
            print(f"  {ch}: rms target {v['rms_target']:.4g}, rms error {v['rms_error']:.4g}")
        long = quadland.simulate(quadland.load_scenario(
            "paper", overrides + ["simulation.duration=400", "disturbance.noise=false",
                                  "simulation.output_rate_hz=10"]))
        print(f"  z_e at 100 s {long['z_e'][1000]:.4f} m, at 400 s {long['z_e'][-1]:.4f} m")


if __name__ == "__main__":
    main()

"""The navigation filter's vertical consistency over a batch of hovers (issue 17, sec. 6).

docs/estimator.md ("Consistency", "Other batches of seeds"): the test's 100 hovers
(seeds 2024-) meet the NEES criterion, other batches (5000-, 7000-) do not, and what
they share is the vertical. This script measures, over ``--runs`` 8 s hovers of the
highway from ``--seed`` (after the 3 s settling time, as the test):

* each state's normalized error ``e_i^2 / P_ii`` averaged over the runs and the
  settled ticks (the truth of ``a_b``, the accelerometer's bias in E, from the IMU's
  noise draw: ``R(eta1) b_a``), and the relative vertical velocity's
  (``v1_z - v_t_z``, its variance ``P_v1 + P_vt - 2 P_v1vt``);
* the relative vertical velocity's per-run averages (the largest) and its batch
  average over 0.5 s windows of the horizon time;
* each block's fused packets per second in those windows, and the range's held ones;
* the bias' turn that the ``axes`` coupling drops (E6a): the body's turn moves the
  horizontal bias' error into the vertical, ``de_z = e_x dtheta - e_y dphi``, whose
  variance over ``T`` per second is ``(P_xx var(dtheta_T) + P_yy var(dphi_T)) / T``
  (the filter's own ``P_ab`` after the settling time, the hover's pitch and roll
  changes over ``T``): the random walk ``q_ab`` must add it to the vertical.

Overrides (``key=value``, as ``quadland simulate --set``) remove a cause from the world
(``sensors.imu.accel_bias_sigma=0``) or change the filter's tuning.

Run from the repository root (about 1 s of CPU per hover)::

    python benchmarks/nees_vertical.py --seed 7000 --runs 100
    python benchmarks/nees_vertical.py --seed 7000 --runs 100 sensors.imu.accel_bias_sigma=0
"""

from __future__ import annotations

import argparse

import numpy as np

from quadland.kinds.landing.consistency import HOVER_SETTLE, hover_scenario, run_errors
from quadland.kinds.landing.sensed import tick_table
from quadland.kinds.landing.simulate import simulate_landing
from quadland.scenario import load_scenario
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.navigation import NAV
from quadland_symbolic.landing.sensed_loop import SENSED_TICK
from quadland_symbolic.landing.sensors import IMU_NOISE

STATES = ("p_r", "v1", "v_t", "a_t", "a_b")
BLOCKS = ("vision", "range", "gnss_v1", "datalink_v", "datalink_a")
TURN_WINDOWS = (0.2, 0.5, 1.0, 2.0, 3.0)


def _bias_truth(result) -> np.ndarray:
    """``R(eta1) b_a`` at every row: the accelerometer's bias in E."""
    ticks = tick_table(result.scenario, len(result["t"]))
    b_a = ticks[:, SENSED_TICK.slice("imu_noise")][:, IMU_NOISE.slice("b_a")]
    eta = np.column_stack([result[a] for a in ("phi1", "theta1", "psi1")])
    return np.array([np.asarray(rotation(list(e)), dtype=float) @ b for e, b in zip(eta, b_a,
                                                                                   strict=True)])


def one_hover(scenario, seed: int) -> dict:
    """One hover's normalized errors ``(ticks,)`` per state and axis, and its packets."""
    result = simulate_landing(scenario.replace(**{"simulation.seed": seed}))
    t_h, e, P = run_errors(result)
    rows = np.searchsorted(result["t"], t_h - 1e-9)
    sl = NAV.slice("a_b")
    e[:, sl] = np.column_stack([result[f"x_h_a_b_{a}"] for a in "xyz"]) - _bias_truth(result)[rows]
    out = {"t": t_h}
    for name in STATES:
        for a, axis in enumerate("xyz"):
            i = NAV.slice(name).start + a
            out[f"{name}_{axis}"] = e[:, i] ** 2 / P[:, i, i]
    iv, it = NAV.slice("v1").start + 2, NAV.slice("v_t").start + 2
    out["vrel_z"] = (e[:, iv] - e[:, it]) ** 2 / (P[:, iv, iv] + P[:, it, it] - 2 * P[:, iv, it])
    for b in BLOCKS:
        out[f"fused_{b}"] = np.asarray(result[f"fused_{b}"], dtype=float)
    out["held_range"] = np.diff(result["n_held_range"], prepend=0.0)
    settled = t_h >= HOVER_SETTLE
    i = NAV.slice("a_b").start
    out["P_ab"] = [float(P[settled, i + a, i + a].mean()) for a in range(2)]
    t = result["t"]
    out["turns"] = {}
    for T in TURN_WINDOWS:
        n = int(round(T * scenario.data["controller"]["rate_hz"]))
        k = np.flatnonzero(t >= HOVER_SETTLE)[:-n]
        out["turns"][T] = [float(np.mean((result[a][k + n] - result[a][k]) ** 2))
                           for a in ("theta1", "phi1")]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="highway")
    parser.add_argument("--seed", type=int, default=7000)
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("overrides", nargs="*", help="key=value, as quadland simulate --set")
    args = parser.parse_args()
    scenario = hover_scenario(load_scenario(args.scenario, args.overrides), args.duration)
    runs = [one_hover(scenario, args.seed + i) for i in range(args.runs)]
    t = runs[0]["t"]
    settled = t >= HOVER_SETTLE
    keys = [k for k in runs[0]
            if k not in ("t", "P_ab", "turns") and not k.startswith(("fused_", "held_"))]
    per_run = {k: np.array([r[k][settled].mean() for r in runs]) for k in keys}
    print(f"{args.scenario}: {args.runs} hovers of {args.duration:g} s from seed {args.seed}"
          f"{' with ' + ' '.join(args.overrides) if args.overrides else ''}; "
          f"each state's e^2/P after {HOVER_SETTLE:g} s (batch average +- its standard error):")
    for k in keys:
        v = per_run[k]
        print(f"  {k:8s} {v.mean():.3f} +- {v.std(ddof=1) / np.sqrt(len(v)):.3f}")
    order = np.argsort(-per_run["vrel_z"])[:8]
    print("largest per-run vrel_z: " + ", ".join(
        f"{args.seed + j} {per_run['vrel_z'][j]:.2f}" for j in order))
    print("window   vrel_z  p_r_z  a_b_z  | fused per s: " + " ".join(BLOCKS) + ", held range")
    for w0 in np.arange(0.0, args.duration, 0.5):
        m = (t >= w0) & (t < w0 + 0.5)
        avg = {k: np.mean([r[k][m].mean() for r in runs]) for k in ("vrel_z", "p_r_z", "a_b_z")}
        rates = [np.mean([r[f"fused_{b}"][m].sum() for r in runs]) * 2 for b in BLOCKS]
        held = np.mean([r["held_range"][m].sum() for r in runs]) * 2
        print(f"{w0:3.1f}-{w0 + 0.5:3.1f}  {avg['vrel_z']:6.2f} {avg['p_r_z']:6.2f} "
              f"{avg['a_b_z']:6.2f}  | " + " ".join(f"{x:5.1f}" for x in rates) + f" {held:5.1f}")
    pxx, pyy = np.mean([r["P_ab"] for r in runs], axis=0)
    print(f"the bias' turn: P_ab after {HOVER_SETTLE:g} s x {pxx:.3e}, y {pyy:.3e} (m/s^2)^2")
    for T in TURN_WINDOWS:
        vth, vph = np.mean([r["turns"][T] for r in runs], axis=0)
        print(f"  T {T:3.1f} s: var dtheta {vth:.3e}, var dphi {vph:.3e} rad^2: "
              f"(P_xx var dtheta + P_yy var dphi) / T = {(pxx * vth + pyy * vph) / T:.3e}")


if __name__ == "__main__":
    main()

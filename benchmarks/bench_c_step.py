"""Cost and accuracy of the generated C control steps (docs/performance.md).

Run with ``python benchmarks/bench_c_step.py [--steps N]``. Builds the
pure-C example (``example/bench.c`` against the double and the float
build) from freshly generated sources (the paper scenario's, the same text
as ``generated/``; the landing's for the highway scenario with l = 100,
``quadland codegen --scenario highway --set rbf.nodes=100``) with the
system's ``cc`` at -O2 and reports:

* time per step (l = 100) of ``bench N paper`` (the paper's control step),
  ``bench N landing`` (the landing's guidance and landing step, one
  control period of its flight code) and ``bench N estimator`` (the
  navigation filter's step at its flight sizes, every sensor due) and
  ``bench N detector`` (the land detector's cues and step), double and
  float, the best of several runs;
* instructions per step from valgrind's callgrind (the difference of two
  run lengths, so start-up cost cancels), when valgrind is installed,
  against the double builds' budgets of 20,000 (paper) and 30,000
  (landing; the filter's 250 Hz period, issue 17);
* the cost of one call from Python: the compiled step through ctypes and
  the CasADi function;
* the float build's deviation from the double one over the paper's
  closed loop at 500 Hz, the two backends' difference, and the 500 Hz
  loop's deviation from the continuous-time one, with the shipped hold
  compensation and without it;
* the landing's two backends' difference over the highway landing.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import tempfile
import timeit
from pathlib import Path

import numpy as np

import quadland
from quadland import codegen
from quadland.engine.disturbance import disturbance_samples
from quadland.kinds.paper.flight import CControlStep, load_control_step
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import closed_loop_state
from quadland_symbolic.control_step import control_step_function, step_outputs
from quadland_symbolic.loop import rk4_step
from quadland_symbolic.paper_loop import paper_loop
from quadland_symbolic.parameters import VEHICLE

ANGLES = ("phi_e", "theta_e", "psi_e")
#: Instructions one double step (l = 100) may cost at -O2, by controller (docs/codegen.md).
BUDGET = {"paper": 20_000, "landing": 30_000, "estimator": 30_000}
#: The landing's node count for the budget (the shipped highway flies l = 10).
LANDING_L = 100


def _build(root: Path) -> Path:
    landing = quadland.load_scenario("highway", [f"rbf.nodes={LANDING_L}"])
    codegen.write(root, codegen.generated_files(landing))
    subprocess.run(["make", "-s", "-j2", "build/bench", "build/bench_float"],
                   cwd=root / "example", check=True)
    return root / "example" / "build"


def _time_per_step(exe: Path, n: int, repeats: int, which: str) -> float:
    best = np.inf
    for _ in range(repeats):
        out = subprocess.run([str(exe), str(n), which], capture_output=True, text=True,
                             check=True).stdout
        best = min(best, float(re.search(r"([\d.]+) ns/step", out).group(1)))
    return best


def _instructions(exe: Path, n: int, which: str) -> float | None:
    if shutil.which("valgrind") is None:
        return None
    counts = []
    for steps in (n, 2 * n):
        with tempfile.NamedTemporaryFile() as f:
            res = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={f.name}",
                                  str(exe), str(steps), which], capture_output=True, text=True,
                                 check=True)
        counts.append(int(re.search(r"Collected : (\d+)", res.stderr).group(1)))
    return (counts[1] - counts[0]) / n


def _python_call_cost(l: int) -> tuple[float, float]:
    mv = model_values(quadland.load_scenario("paper"))
    args = (mv.x0[0:10], np.array([0.0, mv.x0[12], mv.x0[15]]), mv.ref, np.zeros((l, 4)),
            np.zeros(4), np.zeros(4), mv.p_quad, mv.p_ctrl, np.array(mv.rotor_limits), mv.hold,
            0.002)
    out = []
    for fn in (load_control_step(l), control_step_function(l)):
        n = 2000
        out.append(min(timeit.repeat(lambda fn=fn: fn(*args), number=n, repeat=5)) / n)
    return out[0], out[1]


def _simulate(overrides):
    return quadland.simulate(quadland.load_scenario("paper", overrides))


def _fly(precision: str, rate: float = 500.0, duration: float = 10.0) -> dict:
    """The paper's sampled loop flown with one build of the step, in Python.

    ``quadland.simulate`` runs its loop in C with the double step; to fly the
    float build, this loop calls it through ctypes (``CControlStep``) and
    steps the plant with the same RK4 (``quadland_symbolic.loop.rk4_step``),
    one step per control period, the disturbance (bias and sine) held at its
    sample rate. Returns ``z_e``, the attitude and the rotor forces per step.
    """
    sc = quadland.load_scenario("paper", ["disturbance.noise=false", f"controller.rate_hz={rate}",
                                          f"simulation.duration={duration}"])
    mv = model_values(sc)
    m = paper_loop(mv.l)
    step, plant = CControlStep(mv.l, precision), rk4_step(m.plant)
    x0 = closed_loop_state(mv.l).unpack(mv.x0)
    xp = m.plant_state.pack({n: x0[n] for n in m.plant_state.names()})
    xc = m.controller_state.zeros()
    pp = m.plant_params.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh))
    pc = m.controller_params.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh, p_ctrl=mv.p_ctrl,
                                       ref=mv.ref, rotor_limits=mv.rotor_limits, hold=mv.hold,
                                       dt=1.0 / rate))
    n = int(round(duration * rate))
    t = np.arange(n) / rate
    w_rate = sc["disturbance.sample_rate_hz"]
    w = disturbance_samples(sc, np.floor(t * w_rate + 1e-9) / w_rate)
    z2 = float(VEHICLE.unpack(mv.p_veh)["z2"][0])
    rows = {k: np.empty(n) for k in ("z_e", *ANGLES, "F_1", "F_2", "F_3", "F_4")}
    for k in range(n):
        args = m.step_args(xp, xc, pc, 1.0 if k == 0 else 0.0, k / rate)
        out = dict(zip(step_outputs(mv.l).names(), step(*(np.asarray(a) for a in args)),
                       strict=True))
        xc = np.concatenate([out["W_next"].ravel(order="F"), out["zeta_next"].ravel(),
                             out["u_law"].ravel()])
        xp = np.asarray(plant(xp, out["wrench"], w[:, k], k / rate, pp, 1.0 / rate)).ravel()
        q = m.plant_state.unpack(xp)
        rows["z_e"][k] = q["xq"][0] - z2
        eta, psi2 = q["xq"][1:4], m.plant_state.unpack(xp)["xv"][2]
        for name, v in zip(ANGLES, (eta[0], eta[1], eta[2] - psi2), strict=True):
            rows[name][k] = v
        for i in range(4):
            rows[f"F_{i + 1}"][k] = out["rotor"][i, 0]
    return rows


def _max_dev(a, b, names):
    return max(float(np.max(np.abs(a[k] - b[k]))) for k in names)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200000, help="steps per timing run")
    parser.add_argument("--repeats", type=int, default=7, help="timing runs (best is kept)")
    args = parser.parse_args()
    l = model_values(quadland.load_scenario("paper")).l
    with tempfile.TemporaryDirectory() as tmp:
        build = _build(Path(tmp))
        for which, nodes in (("paper", l), ("landing", LANDING_L), ("estimator", "-"),
                             ("detector", "-")):
            for name in ("bench", "bench_float"):
                ns = _time_per_step(build / name, args.steps, args.repeats, which)
                ir = _instructions(build / name, 1000, which)
                ir_text = f"{ir:,.0f} instructions" if ir is not None else "valgrind not found"
                if name == "bench" and ir is not None and which in BUDGET:
                    budget = BUDGET[which]
                    ir_text += f" (budget {budget:,}: {'met' if ir <= budget else 'EXCEEDED'})"
                print(f"{name} {which}: {ns / 1000:.3f} us/step, {ir_text} per step "
                      f"(l = {nodes}, -O2)")
    c_call, casadi_call = _python_call_cost(l)
    print(f"python call: compiled C via ctypes {c_call * 1e6:.1f} us, "
          f"CasADi Function {casadi_call * 1e6:.1f} us")
    sampled = ["controller.rate_hz=500.0"]
    ref = _simulate(sampled + ['controller.backend="c"'])
    cas = _simulate(sampled)
    dbl, flt = _fly("double"), _fly("float")
    cont = _simulate([])
    print(f"float vs double control step, 500 Hz, 10 s: z_e {_max_dev(flt, dbl, ['z_e']):.2e} m, "
          f"attitude {_max_dev(flt, dbl, ANGLES):.2e} rad, "
          f"rotor forces {_max_dev(flt, dbl, ['F_1', 'F_2', 'F_3', 'F_4']):.2e} N")
    # row k of the Python loop is the state after step k, at (k + 1) / 500 s; simulate's
    # rows are at j / 100 s
    quiet = _simulate(sampled + ['controller.backend="c"', "disturbance.noise=false"])
    check = np.max(np.abs(dbl["z_e"][4::5] - quiet["z_e"][1:]))
    print(f"the Python loop with the double step vs simulate: z_e {check:.2e} m "
          "(checks the loop that flies the float build)")
    diff = np.max(np.abs(ref.states - cas.states))
    print(f"backend c vs casadi, 500 Hz, 10 s: states {diff:.2e}")
    plain = _simulate(sampled + ["controller.hold_compensation=0.0"])
    for name, run in (("hold compensation 1/2", cas), ("plain zero-order hold", plain)):
        print(f"500 Hz vs continuous, {name}: z_e {_max_dev(run, cont, ['z_e']):.2e} m, "
              f"attitude {_max_dev(run, cont, ANGLES):.2e} rad")
    landings = [quadland.simulate(quadland.load_scenario("highway", [f'controller.backend="{b}"']))
                for b in ("casadi", "c")]
    print(f"landing backend c vs casadi, highway: states "
          f"{np.max(np.abs(landings[0].states - landings[1].states)):.2e}")


if __name__ == "__main__":
    main()

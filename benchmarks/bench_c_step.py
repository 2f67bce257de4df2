"""Cost and accuracy of the generated C control step (docs/performance.md).

Run with ``python benchmarks/bench_c_step.py [--steps N]``. Builds the
pure-C example (``example/bench.c`` against the double and the float
build) from freshly generated sources (the paper scenario's, the same text
as ``generated/``) with the system's ``cc`` at -O2 and reports:

* time per control step (l = 100) of ``bench``, double and float, the
  best of several runs;
* instructions per step from valgrind's callgrind (the difference of two
  run lengths, so start-up cost cancels), when valgrind is installed,
  against the double build's budget of 20,000;
* the cost of one call from Python: the compiled step through ctypes and
  the CasADi function;
* the float build's deviation from the double one over the paper's
  closed loop at 500 Hz, the two backends' difference, and the 500 Hz
  loop's deviation from the continuous-time one, with the shipped hold
  compensation and without it.
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
from quadland import cbackend, codegen
from quadland.model import model_values
from symbolic.control_step import control_step_function

ANGLES = ("phi_e", "theta_e", "psi_e")
#: Instructions one double control step (l = 100) may cost at -O2 (docs/codegen.md).
BUDGET = 20_000


def _build(root: Path) -> Path:
    codegen.write(root, codegen.generated_files())
    subprocess.run(["make", "-s", "-j2", "build/bench", "build/bench_float"],
                   cwd=root / "example", check=True)
    return root / "example" / "build"


def _time_per_step(exe: Path, n: int, repeats: int) -> float:
    best = np.inf
    for _ in range(repeats):
        out = subprocess.run([str(exe), str(n)], capture_output=True, text=True,
                             check=True).stdout
        best = min(best, float(re.search(r"([\d.]+) ns/step", out).group(1)))
    return best


def _instructions(exe: Path, n: int) -> float | None:
    if shutil.which("valgrind") is None:
        return None
    counts = []
    for steps in (n, 2 * n):
        with tempfile.NamedTemporaryFile() as f:
            res = subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={f.name}",
                                  str(exe), str(steps)], capture_output=True, text=True, check=True)
        counts.append(int(re.search(r"Collected : (\d+)", res.stderr).group(1)))
    return (counts[1] - counts[0]) / n


def _python_call_cost(l: int) -> tuple[float, float]:
    mv = model_values(quadland.load_scenario("paper"))
    args = (mv.x0[0:10], np.array([0.0, mv.x0[12], mv.x0[15]]), mv.ref, np.zeros((l, 4)),
            np.zeros(4), np.zeros(4), mv.p_quad, mv.p_ctrl, np.array(mv.rotor_limits), mv.hold,
            0.002)
    out = []
    for fn in (cbackend.load_control_step(l), control_step_function(l)):
        n = 2000
        out.append(min(timeit.repeat(lambda: fn(*args), number=n, repeat=5)) / n)
    return out[0], out[1]


def _simulate(overrides, precision=None):
    sc = quadland.load_scenario("paper", overrides)
    if precision is None:
        return quadland.simulate(sc)
    original = cbackend.load_control_step
    cbackend.load_control_step = lambda l: cbackend.CControlStep(l, precision)
    try:
        return quadland.simulate(sc)
    finally:
        cbackend.load_control_step = original


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
        for name in ("bench", "bench_float"):
            ns = _time_per_step(build / name, args.steps, args.repeats)
            ir = _instructions(build / name, 1000)
            ir_text = f"{ir:,.0f} instructions" if ir is not None else "valgrind not found"
            if name == "bench" and ir is not None:
                ir_text += f" (budget {BUDGET:,}: {'met' if ir <= BUDGET else 'EXCEEDED'})"
            print(f"{name}: {ns / 1000:.3f} us/step, {ir_text} per step (l = {l}, -O2)")
    c_call, casadi_call = _python_call_cost(l)
    print(f"python call: compiled C via ctypes {c_call * 1e6:.1f} us, "
          f"CasADi Function {casadi_call * 1e6:.1f} us")
    sampled = ["controller.rate_hz=500.0"]
    ref = _simulate(sampled + ['controller.backend="c"'], "double")
    flt = _simulate(sampled + ['controller.backend="c"'], "float")
    cas = _simulate(sampled)
    cont = _simulate([])
    print(f"float vs double control step, 500 Hz, 10 s: z_e {_max_dev(flt, ref, ['z_e']):.2e} m, "
          f"attitude {_max_dev(flt, ref, ANGLES):.2e} rad, "
          f"rotor forces {_max_dev(flt, ref, ['F_1', 'F_2', 'F_3', 'F_4']):.2e} N")
    diff = np.max(np.abs(ref.states - cas.states))
    print(f"backend c vs casadi, 500 Hz, 10 s: states {diff:.2e}")
    plain = _simulate(sampled + ["controller.hold_compensation=0.0"])
    for name, run in (("hold compensation 1/2", cas), ("plain zero-order hold", plain)):
        print(f"500 Hz vs continuous, {name}: z_e {_max_dev(run, cont, ['z_e']):.2e} m, "
              f"attitude {_max_dev(run, cont, ANGLES):.2e} rad")


if __name__ == "__main__":
    main()

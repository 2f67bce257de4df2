"""The navigation filter's cost: operations and instructions.

The operations of its SX functions and the instructions of its C.

Measured:

* the operation counts (:func:`quadland_symbolic.kalman.operation_counts`) of
  ``estimator_step`` for both covariance couplings at the default sizes
  (``n_hist = 50``, FIFO depth 8) and of its parts (one prediction, one
  update per block, the output predictor);
* with ``--callgrind``, the instructions of one call of ``estimator_step``
  compiled from CasADi's own C (``Function.generate``, ``gcc -O2``, double),
  counted by ``valgrind --tool=callgrind`` on a filter that is running (a
  handover state, packets due for every sensor). This is CasADi's raw C, not
  the project's generated tree: the flight C (``generated/``'s
  ``ql_estimator_step``, its checks included) is measured against the budget of
  issue 17 (30,000 instructions per 250 Hz period in double) by
  ``benchmarks/bench_c_step.py`` (``bench N estimator``).

Run from the repository root::

    python benchmarks/bench_estimator.py              # a few seconds
    python benchmarks/bench_estimator.py --callgrind  # and compile, about a minute
"""

from __future__ import annotations

import argparse
import re
import subprocess
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from quadland_symbolic.kalman import operation_counts
from quadland_symbolic.landing.estimator import (
    FIFO_DEPTH,
    N_HIST,
    estimator_init_function,
    estimator_step_function,
    output_predictor_function,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    IMU,
    NAV,
    NAV_PACKETS,
    estimator_params,
    nav_predict_function,
    nav_update_function,
)


def _row(name: str, f: ca.Function) -> str:
    c = operation_counts(f)
    return f"| {name} | {c['arithmetic']} | {c['instructions']} |"


def operation_table() -> str:
    """Markdown table of operation counts."""
    rows = ["| function | arithmetic operations | SX instructions |", "| --- | ---: | ---: |"]
    for coupling in ("full", "axes"):
        rows.append(_row(f"estimator_step, {coupling}, n_hist {N_HIST}, depth {FIFO_DEPTH}",
                         estimator_step_function(N_HIST, FIFO_DEPTH, coupling)))
    for coupling in ("full", "axes"):
        rows.append(_row(f"nav_predict, {coupling}", nav_predict_function(coupling)))
        for b in BLOCKS:
            rows.append(_row(f"nav_update_{b.name}, {coupling}",
                             nav_update_function(b.name, coupling)))
    rows.append(_row(f"nav_output_predictor, n_hist {N_HIST}",
                     output_predictor_function(N_HIST)))
    return "\n".join(rows)


def _c_array(name: str, v) -> str:
    values = ", ".join(repr(float(x)) for x in np.ravel(v))
    return f"static const casadi_real {name}[{max(np.size(v), 1)}] = {{{values or '0'}}};"


def _inputs(coupling: str) -> list[np.ndarray]:
    """A running filter: a handover state, every sensor due."""
    x0 = np.zeros(NAV.size)
    x0[NAV.slice("p_r")] = [0.3, -0.2, 3.0]
    mem = np.array(estimator_init_function(N_HIST, FIFO_DEPTH, coupling)(
        x0, np.full(NAV.size, 0.5), np.zeros(9), 0.0)).ravel()
    t = 0.0                                      # the horizon is at t0 while the buffer fills
    imu = IMU.pack(dict(eta_hat=[0.02, -0.01, 0.5], f_b=[0.1, 0.2, 9.7], omega=[0.01] * 3))
    values = dict(fresh=1.0, tau=t, r_E=[-0.3, 0.2, -3.0], rel=[-0.2, 0.3, -3.1],
                  v1=[0.1] * 3, vt=[0.1] * 3, s=3.0, b3_E=[0.0, 0.0, 1.0],
                  eta2=[0.01, 0.0, 0.5], v2E=[0.1] * 3, a2E=[0.0] * 3, w2E=[0.0] * 3,
                  w2E_dot=[0.0] * 3)
    pkts = [p.pack({f.name: values[f.name] for f in p.fields}) for p in NAV_PACKETS]
    p_est = estimator_params().pack(dict(ESTIMATOR_DEFAULTS))
    return [mem, imu, *pkts, p_est, np.array([0.004]), np.array([t])]


def callgrind_instructions(coupling: str) -> int:
    """Instructions of one ``estimator_step`` call (CasADi's C, -O2)."""
    f = estimator_step_function(N_HIST, FIFO_DEPTH, coupling)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cg = ca.CodeGenerator("step.c", {"with_header": True})
        cg.add(f)
        cg.generate(f"{work}/")
        ins = _inputs(coupling)
        arrays = "\n".join(_c_array(f"in{i}", v) for i, v in enumerate(ins))
        outs = "\n".join(f"static casadi_real out{i}[{f.nnz_out(i)}];" for i in range(f.n_out()))
        driver = f"""#include "step.h"
{arrays}
{outs}
static casadi_real w[{f.sz_w()}];
static casadi_int iw[{f.sz_iw() + 1}];
int main(void) {{
    const casadi_real *arg[{f.sz_arg()}] = {{{", ".join(f"in{i}" for i in range(f.n_in()))}}};
    casadi_real *res[{f.sz_res()}] = {{{", ".join(f"out{i}" for i in range(f.n_out()))}}};
    return estimator_step(arg, res, iw, w, 0);
}}
"""
        (work / "main.c").write_text(driver)
        subprocess.run(["gcc", "-O2", "-o", "bench", "main.c", "step.c", "-lm"], cwd=work,
                       check=True)
        subprocess.run(["valgrind", "--tool=callgrind", "--toggle-collect=estimator_step",
                        "--callgrind-out-file=cg.out", "./bench"], cwd=work, check=True,
                       capture_output=True)
        text = (work / "cg.out").read_text()
        return int(re.search(r"^summary: (\d+)", text, re.M).group(1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--callgrind", action="store_true",
                        help="compile CasADi's C of the step and count one call's instructions")
    args = parser.parse_args()
    print(operation_table())
    if args.callgrind:
        for coupling in ("full", "axes"):
            print(f"estimator_step, {coupling}: {callgrind_instructions(coupling)} instructions "
                  "(callgrind, gcc -O2, double, one call)")


if __name__ == "__main__":
    main()

"""Speed of ``quadland.simulate`` against a plain SciPy baseline.

The requirement: for the paper scenario, a warm ``simulate`` is at least 50x
faster than a straightforward SciPy ``solve_ivp`` (RK45) with a NumPy
right-hand side at matched accuracy, and a cold first call (model build
included) is still faster than that baseline.

The baseline's right-hand side, ``numpy_rhs``, is derived again from the
paper (eq. 1-6, 9-22), independently of ``symbolic/``: alpha_dot (eq. 18) is
written out by hand instead of differentiated symbolically. The script
first checks it against CasADi's ``closed_loop_function`` at random states.
Accuracy is measured against CasADi cvodes at reltol = abstol = 1e-12 on
the relative altitude and the three attitude errors; the baseline's
``rtol`` is the loosest of a sweep whose error does not exceed quadland's.

Run from the repository root::

    python benchmarks/bench_simulate.py              # measure, update docs/performance.md
    python benchmarks/bench_simulate.py --no-write   # measure only
    python benchmarks/bench_simulate.py --profile    # break down simulate's time

The breakdown (integrator with and without ``expand`` or JIT, output
evaluation variants) is also measured whenever the warm target is missed.

It rewrites only the ``## Simulation`` section of ``docs/performance.md``.
Takes about a minute.
"""

from __future__ import annotations

import argparse
import datetime
import json
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np
import scipy
from scipy.integrate import solve_ivp

import quadland
from quadland.model import disturbance_samples, model_values
from quadland.simulate import time_grid
from symbolic.closed_loop import closed_loop_function, closed_loop_outputs

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "performance.md"
SECTION = "## Simulation"
TARGET_WARM = 50.0
RTOL_SWEEP = (1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 1e-8)
SINGLE_RTOL_SWEEP = (1e-9, 3e-10, 1e-10, 3e-11, 1e-11)
REFERENCE = ['simulation.integrator="cvodes"', "simulation.reltol=1e-12",
             "simulation.abstol=1e-12"]
ERROR_SIGNALS = ("z_e", "phi_e", "theta_e", "psi_e")


# --- the closed loop again, in NumPy --------------------------------------

def numpy_rhs(p, l):
    """The closed loop's right-hand side ``rhs(t, x, w)`` in NumPy.

    Parameters
    ----------
    p : ndarray
        Closed-loop parameter vector ``[p_quad, p_veh, p_ctrl, ref]``
        (``quadland.model.model_values(...).p``).
    l : int
        RBF node count.

    Returns
    -------
    callable
        ``rhs(t, x, w) -> x_dot`` with the state layout of
        ``symbolic.closed_loop``.
    """
    p = np.asarray(p, dtype=float).ravel()
    m1, I, Kt, Kr, g = p[0], p[1:4], p[4:7], p[7:10], p[10]
    m11, m22, m33, d11, d22, d33 = p[13:19]
    tau, z2 = p[19:22], p[22]
    c = p[23:]
    k1, k2 = c[0:4], c[4:8]
    gamma1, gamma2, k_w, k_zeta, rho, nominal = c[8:14]
    centers = c[14:14 + 10 * l].reshape((10, l), order="F")
    widths = c[14 + 10 * l:14 + 11 * l]
    ref = c[14 + 11 * l:14 + 11 * l + 12]
    e1d, e1d_dot, e1d_ddot = ref[0:4], ref[4:8], ref[8:12]
    Ix, Iy, Iz = I
    inv_w2 = 1.0 / widths**2

    def rhs(t, x, w):
        z1, phi, theta, psi = x[0:4]
        V = x[4:7]
        Om = x[7:10]
        pr, qr, rr = Om
        psi2, u2, v2, r2 = x[12:16]
        W_hat = x[16:16 + 4 * l].reshape((l, 4), order="F")
        zeta_hat = x[16 + 4 * l:20 + 4 * l]
        d_F, d_M = w[0:3], w[3:6]
        cf, sf, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
        cp, sp = np.cos(psi), np.sin(psi)
        tt = st / ct
        J = np.array([-st, ct * sf, ct * cf])                     # last row of R(eta)
        Rr = np.array([[1.0, tt * sf, tt * cf],                   # eq. 1
                       [0.0, cf, -sf],
                       [0.0, sf / ct, cf / ct]])
        Rr_inv = np.array([[1.0, 0.0, -st],
                           [0.0, cf, sf * ct],
                           [0.0, -sf, cf * ct]])

        # relative states (eq. 5, 7); the deck neither heaves, rolls nor pitches
        e1 = np.array([z1 - z2, phi, theta, psi - psi2])
        e2 = np.concatenate([[J @ V], Om - Rr_inv[:, 2] * r2])
        R = np.zeros((4, 4))
        R[0, 0] = 1.0
        R[1:, 1:] = Rr
        R_inv = np.zeros((4, 4))
        R_inv[0, 0] = 1.0
        R_inv[1:, 1:] = Rr_inv
        e1_dot = R @ e2                                            # eq. 10
        phi_dot, theta_dot = e1_dot[1], e1_dot[2]
        R_inv_dot = np.zeros((4, 4))                               # d/dt R^-1 by hand
        R_inv_dot[1:, 1:] = [
            [0.0, 0.0, -ct * theta_dot],
            [0.0, -sf * phi_dot, cf * ct * phi_dot - sf * st * theta_dot],
            [0.0, -cf * phi_dot, -sf * ct * phi_dot - cf * st * theta_dot]]

        # backstepping (eq. 9, 14, 18)
        z_1 = e1 - e1d
        v = -k1 * z_1 + e1d_dot
        alpha = R_inv @ v
        alpha_dot = R_inv_dot @ v + R_inv @ (-k1 * (e1_dot - e1d_dot) + e1d_ddot)
        z_2 = e2 - alpha

        # RBF network (eq. 8, 16): w2 = 0, p2 = q2 = 0
        w_e, p_e, q_e, r_e = V[2], pr, qr, rr - r2
        theta_in = np.array([w_e, p_e, q_e, r_e, w_e * p_e, w_e * q_e, w_e * r_e,
                             p_e * q_e, p_e * r_e, q_e * r_e])
        diff = centers - theta_in[:, None]
        Psi = np.exp(-np.sum(diff * diff, axis=0) * inv_w2)
        Delta_hat = W_hat.T @ Psi

        # known quadrotor drift, fed forward only with nominal_model = 1
        f_nom = np.array([
            -(J @ (Kt * V)) / m1 - g,
            -Kr[0] * pr / Ix - (Iz - Iy) * qr * rr / Ix,
            -Kr[1] * qr / Iy - (Ix - Iz) * pr * rr / Iy,
            -Kr[2] * rr / Iz - (Iy - Ix) * pr * qr / Iz])
        sq = np.tanh(z_2 / rho)
        u = (-k2 * z_2 - R.T @ z_1 - Delta_hat - sq * zeta_hat + alpha_dot     # eq. 20
             - nominal * f_nom)
        W_dot = gamma1 * (np.outer(Psi, z_2) - k_w * W_hat)                    # eq. 22
        zeta_dot = gamma2 * (sq * z_2 - k_zeta * zeta_hat)                     # eq. 22

        # wrench realising u (eq. 6), quadrotor (eq. 1-2)
        F_total = m1 * u[0] / (ct * cf)
        T = I * u[1:4]
        F = np.array([0.0, 0.0, F_total])
        V_dot = -np.cross(Om, V) + (F - Kt * V + d_F) / m1 - g * J
        Om_dot = (T - Kr * Om + d_M - np.cross(Om, I * Om)) / I
        xq_dot = np.concatenate([[J @ V], Rr @ Om, V_dot, Om_dot])

        # vehicle (eq. 3-4)
        c2, s2 = np.cos(psi2), np.sin(psi2)
        xv_dot = np.array([
            c2 * u2 - s2 * v2, s2 * u2 + c2 * v2, r2,
            (tau[0] + m22 * v2 * r2 - d11 * u2) / m11,
            (tau[1] - m11 * u2 * r2 - d22 * v2) / m22,
            (tau[2] - d33 * r2 + (m11 - m22) * u2 * v2) / m33])

        # quadrotor ground track: first two rows of Rz Ry Rx times V1
        pos_dot = np.array([
            cp * ct * V[0] + (cp * st * sf - sp * cf) * V[1] + (cp * st * cf + sp * sf) * V[2],
            sp * ct * V[0] + (sp * st * sf + cp * cf) * V[1] + (sp * st * cf - cp * sf) * V[2]])
        return np.concatenate([xq_dot, xv_dot, W_dot.ravel(order="F"), zeta_dot, pos_dot])

    return rhs


def random_states(mv, n, seed=0):
    """``n`` random closed-loop states and disturbances around the paper's start."""
    rng = np.random.default_rng(seed)
    nx = mv.x0.size
    X = mv.x0[:, None] + rng.uniform(-1, 1, (nx, n))
    X[1:3] = rng.uniform(-1.0, 1.0, (2, n))          # roll, pitch within +-57 deg
    W = rng.normal(0.0, 1.0, (6, n))
    return X, W


def rhs_mismatch(mv, n=20, seed=0):
    """Largest ``|f_numpy - f_casadi| / (1 + |f_casadi|)`` over random states."""
    f_ca = closed_loop_function(mv.l)
    rhs = numpy_rhs(mv.p, mv.l)
    X, W = random_states(mv, n, seed)
    worst = 0.0
    for k in range(n):
        ref = np.asarray(f_ca(X[:, k], W[:, k], mv.p)).ravel()
        mine = rhs(0.0, X[:, k], W[:, k])
        worst = max(worst, float(np.max(np.abs(mine - ref) / (1.0 + np.abs(ref)))))
    return worst


# --- the baseline ----------------------------------------------------------

def baseline(scenario, rtol, atol):
    """States at the output times, by ``solve_ivp`` RK45 over each hold interval.

    The solver restarts at every point of ``time_grid``'s merged grid, with
    the disturbance held as ``quadland.simulate`` holds it.
    """
    mv = model_values(scenario)
    t_out, t_dist, t_all = time_grid(scenario)
    w_dist = disturbance_samples(scenario, t_dist)
    rhs = numpy_rhs(mv.p, mv.l)
    x = mv.x0.copy()
    X = [x]
    for t0, t1 in zip(t_all[:-1], t_all[1:]):
        k = np.searchsorted(t_dist, t0 + 1e-12, side="right") - 1
        sol = solve_ivp(rhs, (t0, t1), x, method="RK45", rtol=rtol, atol=atol,
                        args=(w_dist[:, k],))
        x = sol.y[:, -1]
        X.append(x)
    keep = np.isin(np.round(t_all, 12), np.round(t_out, 12))
    return np.array(X).T[:, keep]


def baseline_single_call(scenario, rtol, atol):
    """States at the output times, by one ``solve_ivp`` RK45 call over the whole run.

    The plain use of SciPy: the right-hand side looks up the disturbance held
    at time t, and the solver's error control finds the 10 ms switches.
    """
    mv = model_values(scenario)
    t_out, t_dist, _ = time_grid(scenario)
    w_dist = disturbance_samples(scenario, t_dist)
    rhs = numpy_rhs(mv.p, mv.l)

    def f(t, x):
        k = np.searchsorted(t_dist, t + 1e-12, side="right") - 1
        return rhs(t, x, w_dist[:, min(max(k, 0), w_dist.shape[1] - 1)])

    sol = solve_ivp(f, (t_out[0], t_out[-1]), mv.x0, method="RK45", rtol=rtol, atol=atol,
                    t_eval=t_out)
    return sol.y


def attitude_errors(X, mv):
    """``[z_e, phi_e, theta_e, psi_e]`` rows from closed-loop states (eq. 5)."""
    z2 = mv.p_veh[-1]
    return np.vstack([X[0] - z2, X[1], X[2], X[3] - X[12]])


def max_error(E, E_ref):
    """Largest absolute deviation per signal of ``ERROR_SIGNALS``."""
    return dict(zip(ERROR_SIGNALS, np.max(np.abs(E - E_ref), axis=1).tolist()))


# --- timings -----------------------------------------------------------------

_COLD = """
import json, time
t0 = time.perf_counter()
import quadland
t1 = time.perf_counter()
quadland.simulate(quadland.load_scenario("paper"))
t2 = time.perf_counter()
print(json.dumps({"total": t2 - t0, "after_import": t2 - t1}))
"""


def time_cold(runs):
    """Import + model build + run in fresh interpreters; medians in s."""
    rows = []
    for _ in range(runs):
        out = subprocess.run([sys.executable, "-c", _COLD], capture_output=True, text=True,
                             check=True, cwd=ROOT)
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    return {k: statistics.median(r[k] for r in rows) for k in ("total", "after_import")}


def time_call(fn, runs):
    """Median wall time of ``fn()`` over ``runs`` calls, s."""
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def profile_simulate(scenario):
    """Where a warm ``simulate`` spends its time, and what the alternatives cost.

    Returns a list of ``(label, seconds)`` rows; integrators are built
    through ``ca.integrator`` exactly as ``quadland.simulate`` builds them.
    """
    from quadland.simulate import _held, _integrator_options

    mv = model_values(scenario)
    t_out, t_dist, t_all = time_grid(scenario)
    w_dist = disturbance_samples(scenario, t_dist)
    w = _held(t_dist, w_dist, t_all[:-1])
    w_out = _held(t_dist, w_dist, t_out)
    plugin, opts = _integrator_options(scenario, len(t_all) - 1)
    n = len(t_out)
    f = closed_loop_function(mv.l)
    g = closed_loop_outputs(mv.l)
    rows = []

    def build(extra):
        x, u, p = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("u", 6), ca.SX.sym("p", f.size1_in(2))
        dae = {"x": x, "u": u, "p": p, "ode": f(x, u, p)}
        return ca.integrator("closed_loop_sim", plugin, dae, t_all[0], list(t_all[1:]),
                             {**dict(opts), **extra})

    variants = (
        ("default", {}),
        ("expand", {"expand": True}),
        ("JIT -O1", {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"]}}),
        ("JIT -O3", {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O3"]}}),
    )
    for label, extra in variants:
        t0 = time.perf_counter()
        integ = build(extra)
        integ(x0=mv.x0, u=w, p=mv.p)
        t1 = time.perf_counter()
        run = time_call(lambda: integ(x0=mv.x0, u=w, p=mv.p), 5)
        rows.append((f"integrator, {label}: build + first call", t1 - t0))
        rows.append((f"integrator, {label}: warm call", run))
    X = np.column_stack([mv.x0, np.asarray(integ(x0=mv.x0, u=w, p=mv.p)["xf"])])

    rows.append(("outputs: `closed_loop_outputs(l).map(n)` built and evaluated (as now)",
                 time_call(lambda: g.map(n)(X, w_out, mv.p), 5)))
    rows.append(("outputs: of which NumPy -> DM conversion of the state matrix",
                 time_call(lambda: ca.DM(X), 5)))
    for label, par in (("serial", ()), ("thread, 2", ("thread", 2))):
        m = g.map(n, *par)
        m(X, w_out, mv.p)
        rows.append((f"outputs: cached `map(n{', ' if par else ''}"
                     f"{', '.join(repr(a) for a in par)})` evaluate ({label})",
                     time_call(lambda m=m: m(X, w_out, mv.p), 5)))
    chunk = 101
    mc = g.map(chunk)
    starts = range(0, n, chunk)
    rows.append((f"outputs: cached `map({chunk})` over chunks of {chunk} samples",
                 time_call(lambda: [mc(X[:, s:s + chunk], w_out[:, s:s + chunk], mv.p)
                                    if s + chunk <= n else
                                    g.map(n - s)(X[:, s:], w_out[:, s:], mv.p)
                                    for s in starts], 5)))
    t0 = time.perf_counter()
    gj = ca.Function("closed_loop_outputs", g.sx_in(), g.call(g.sx_in()),
                     {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"]}})
    mj = gj.map(chunk)
    mj(X[:, :chunk], w_out[:, :chunk], mv.p)
    rows.append(("outputs, JIT -O1: build + first call", time.perf_counter() - t0))
    rows.append((f"outputs, JIT -O1: cached `map({chunk})` over chunks",
                 time_call(lambda: [mj(X[:, s:s + chunk], w_out[:, s:s + chunk], mv.p)
                                    if s + chunk <= n else
                                    gj.map(n - s)(X[:, s:], w_out[:, s:], mv.p)
                                    for s in starts], 5)))
    rows.append(("simulate, warm (whole call)",
                 time_call(lambda: quadland.simulate(scenario), 5)))
    return rows


# --- report ------------------------------------------------------------------

def machine():
    """CPU model, core count and library versions."""
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os
    return {"CPU": f"{cpu}, {os.cpu_count()} logical cores",
            "Python": platform.python_version(), "NumPy": np.__version__,
            "SciPy": scipy.__version__, "CasADi": ca.__version__,
            "date": datetime.date.today().isoformat()}


def render(m):
    """The ``## Simulation`` section as Markdown."""
    e = lambda d: ", ".join(f"{k} {v:.1e}" for k, v in d.items())   # noqa: E731
    warm_ok = m["ratio_warm"] >= TARGET_WARM
    cold_ok = m["cold"]["total"] < m["single"]
    lines = [
        SECTION, "",
        "Requirement: for the paper scenario (10 s, l = 100, 422 states, disturbance held "
        "over 1000 intervals of 10 ms), a warm `quadland.simulate` is at least "
        f"{TARGET_WARM:.0f}x faster than SciPy `solve_ivp` (RK45) with a NumPy right-hand "
        "side at matched accuracy, and a cold first call is still faster than that "
        "baseline. Measured by `python benchmarks/bench_simulate.py`.", "",
        "Two baselines, both RK45 with the same independent NumPy right-hand side at "
        "matched accuracy: the **straightforward** one is a single `solve_ivp` call over "
        "the run whose right-hand side looks up the held disturbance (what the "
        "requirement names); the **restarted** one restarts the solver at each 10 ms "
        "switch, which spares RK45 the discontinuities and is much faster, so it is shown "
        "as the harder comparison.", "",
        "| | time (s) | straightforward / this | restarted / this |", "|---|---:|---:|---:|",
        f"| straightforward baseline: one `solve_ivp` call, rtol = {m['single_rtol']:.0e}, "
        f"atol = rtol / 10 | {m['single']:.3f} | 1 | |",
        f"| restarted baseline: `solve_ivp` per hold interval, rtol = {m['rtol']:.0e}, "
        f"atol = {m['atol']:.0e} (median of {m['baseline_runs']}) | {m['baseline']:.3f} | | 1 |",
        f"| `simulate`, warm (median of {m['warm_runs']}) | {m['warm']:.3f} | "
        f"{m['ratio_warm']:.1f} | {m['ratio_warm_restart']:.1f} |",
        f"| `simulate`, cold: import + build + run, fresh interpreter (median of "
        f"{m['cold_runs']}) | {m['cold']['total']:.3f} | {m['ratio_cold']:.1f} | "
        f"{m['ratio_cold_restart']:.1f} |",
        f"| `simulate`, cold, after import | {m['cold']['after_import']:.3f} | "
        f"{m['single'] / m['cold']['after_import']:.1f} | "
        f"{m['baseline'] / m['cold']['after_import']:.1f} |", "",
        f"- Against the straightforward baseline: warm target ({TARGET_WARM:.0f}x) "
        f"**{'met' if warm_ok else 'not met'}** ({m['ratio_warm']:.1f}x); cold target "
        f"(faster than the baseline) **{'met' if cold_ok else 'not met'}** "
        f"({m['ratio_cold']:.1f}x).",
        f"- Against the restarted baseline the warm call is only "
        f"{m['ratio_warm_restart']:.1f}x faster: both then take one RK4-class step per "
        "10 ms, and what remains is the cost of one right-hand side evaluation in CasADi's "
        "virtual machine against NumPy's (the breakdown below).",
        "- Accuracy, max |error| over the run against CasADi cvodes at reltol = abstol = "
        "1e-12 (z_e in m, angles in rad):",
        f"  - `simulate` default (CasADi \"rk\", one RK4 step per 10 ms hold interval): "
        f"{e(m['err_quadland'])};",
        f"  - straightforward baseline: {e(m['err_single'])};",
        f"  - restarted baseline: {e(m['err_baseline'])}.",
        "  Each baseline's rtol is the loosest of its sweep ("
        + ", ".join(f"{r:.0e}" for r in SINGLE_RTOL_SWEEP) + " and "
        + ", ".join(f"{r:.0e}" for r in RTOL_SWEEP)
        + ", atol = rtol / 10) whose largest error does not exceed `simulate`'s.",
        f"- The NumPy right-hand side of the baseline is derived separately from the paper "
        f"and agrees with `closed_loop_function` to {m['rhs_mismatch']:.1e} (relative) at "
        "random states; `tests/test_bench_rhs.py` checks the same.",
        "- Machine: " + "; ".join(f"{k} {v}" for k, v in m["machine"].items()) + ".",
    ]
    if m.get("profile"):
        budget = m["baseline"] / TARGET_WARM
        fastest = min(t for label, t in m["profile"]
                      if label.startswith("integrator") and label.endswith("warm call"))
        lines += ["", "Where a warm call's time goes, and alternatives (measured with "
                  "`--profile` or whenever the warm target is missed; each integrator is "
                  "built as `quadland.simulate` builds it, plus the options named):", "",
                  "| step | time (s) |", "|---|---:|"]
        lines += [f"| {label} | {t:.4f} |" for label, t in m["profile"]]
        lines += ["", f"50x against the restarted baseline would leave {budget * 1e3:.1f} ms "
                  "for the whole call: out of reach without compiling the model, since "
                  f"the fastest integrator variant above alone takes {fastest * 1e3:.1f} ms "
                  f"({m['baseline'] / fastest:.0f}x), output evaluation not counted."]
    return "\n".join(lines) + "\n"


def write_section(text, path=DOC):
    """Replace the ``## Simulation`` section of ``path``, or create the file."""
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("# Performance\n\n" + text)
        return
    old = path.read_text()
    lines = old.splitlines(keepends=True)
    start = next((i for i, s in enumerate(lines) if s.rstrip() == SECTION), None)
    if start is None:
        path.write_text(old.rstrip("\n") + "\n\n" + text)
        return
    stop = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")),
                len(lines))
    tail = "".join(lines[stop:])
    path.write_text("".join(lines[:start]) + text + ("\n" + tail if tail else ""))


def loosest_matching(run, label, sweep, sc, mv, E_ref, tol):
    """The loosest rtol of ``sweep`` (atol = rtol / 10) whose error is within ``tol``."""
    for rtol in sweep:
        err = max_error(attitude_errors(run(sc, rtol, rtol / 10), mv), E_ref)
        print(f"{label} rtol {rtol:.0e}: max error {max(err.values()):.2e}")
        if max(err.values()) <= tol:
            return rtol, err
    raise SystemExit(f"no {label} tolerance in the sweep matches simulate's accuracy")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-write", action="store_true", help="do not update docs/performance.md")
    ap.add_argument("--profile", action="store_true", help="break down simulate's time")
    ap.add_argument("--cold-runs", type=int, default=3)
    ap.add_argument("--warm-runs", type=int, default=7)
    ap.add_argument("--baseline-runs", type=int, default=3)
    args = ap.parse_args(argv)

    # cold first: nothing of this process is shared with the fresh interpreters
    cold = time_cold(args.cold_runs)
    print(f"cold: {cold['total']:.3f} s total, {cold['after_import']:.3f} s after import")

    sc = quadland.load_scenario("paper")
    mv = model_values(sc)
    mismatch = rhs_mismatch(mv)
    print(f"NumPy rhs vs closed_loop_function: {mismatch:.2e}")
    if mismatch > 1e-9:
        raise SystemExit("the NumPy right-hand side disagrees with CasADi's")

    res = quadland.simulate(sc)
    warm = time_call(lambda: quadland.simulate(sc), args.warm_runs)
    print(f"warm: {warm:.4f} s")

    E_ref = np.vstack([quadland.simulate(quadland.load_scenario("paper", REFERENCE))[n]
                       for n in ERROR_SIGNALS])
    err_q = max_error(np.vstack([res[n] for n in ERROR_SIGNALS]), E_ref)
    tol_q = max(err_q.values())
    print("quadland error:", err_q)
    rtol, err_b = loosest_matching(baseline, "baseline", RTOL_SWEEP, sc, mv, E_ref, tol_q)
    t_base = time_call(lambda: baseline(sc, rtol, rtol / 10), args.baseline_runs)
    print(f"baseline: {t_base:.3f} s")

    rtol1, err_1 = loosest_matching(baseline_single_call, "single-call baseline",
                                    SINGLE_RTOL_SWEEP, sc, mv, E_ref, tol_q)
    t_single = time_call(lambda: baseline_single_call(sc, rtol1, rtol1 / 10), 1)
    print(f"single-call baseline: {t_single:.3f} s")

    m = dict(rtol=rtol, atol=rtol / 10, baseline=t_base, baseline_runs=args.baseline_runs,
             single=t_single, single_rtol=rtol1, err_single=err_1,
             warm=warm, warm_runs=args.warm_runs, cold=cold, cold_runs=args.cold_runs,
             ratio_warm=t_single / warm, ratio_cold=t_single / cold["total"],
             ratio_warm_restart=t_base / warm, ratio_cold_restart=t_base / cold["total"],
             err_quadland=err_q, err_baseline=err_b, rhs_mismatch=mismatch,
             machine=machine())
    if args.profile or m["ratio_warm_restart"] < TARGET_WARM:
        m["profile"] = profile_simulate(sc)
    text = render(m)
    print(text)
    if not args.no_write:
        write_section(text)
        print(f"updated {DOC}")


if __name__ == "__main__":
    main()

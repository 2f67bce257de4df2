"""Closed-loop simulation on CasADi's integrators.

Two loops share one symbolic model:

* continuous (``controller.rate_hz = 0``, the paper's): the whole closed
  loop of ``symbolic.closed_loop`` is one ODE, integrated in a single call
  of a CasADi integrator over a time grid on which the disturbance is
  piecewise constant;
* sampled-data (``rate_hz > 0``): the control step of
  ``symbolic.control_step`` (CasADi or compiled C) runs at that rate and
  its wrench is held on the plant between samples.
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import io
from collections.abc import Mapping

import casadi as ca
import numpy as np

from quadland.exceptions import QuadlandError
from quadland.model import ModelValues, disturbance_samples, model_values
from quadland.scenario import Scenario
from symbolic.closed_loop import (OUTPUTS, closed_loop_function, closed_loop_layout,
                                  closed_loop_outputs, plant_function)
from symbolic.control_step import control_step_function

__all__ = ["SimulationError", "SimulationResult", "simulate", "COLUMNS", "time_grid"]

#: Minimum |cos(theta) cos(phi)| the simulator accepts before it stops.
TILT_MIN = 1e-3


class SimulationError(QuadlandError, RuntimeError):
    """The simulated loop left the model's domain (singular attitude, NaN)."""


def _columns():
    cols = [("t", "s")]
    cols += [(n, u) for n, u in zip(("z_e", "phi_e", "theta_e", "psi_e"),
                                    ("m", "rad", "rad", "rad"))]
    cols += [(n, u) for n, u in zip(("dz_e", "p_e", "q_e", "r_e"),
                                    ("m/s", "rad/s", "rad/s", "rad/s"))]
    cols += [(f"u_{i}", "m/s^2" if i == 1 else "rad/s^2") for i in range(1, 5)]
    cols += [("F_total", "N"), ("M_x", "N m"), ("M_y", "N m"), ("M_z", "N m")]
    cols += [(f"F_{i}", "N") for i in range(1, 5)]
    for name in ("Delta", "Delta_hat", "Delta_target"):
        cols += [(f"{name}_{i}", "m/s^2" if i == 1 else "rad/s^2") for i in range(1, 5)]
    cols += [("zeta_hat_1", "-"), ("zeta_hat_2", "-"), ("zeta_hat_3", "-"), ("zeta_hat_4", "-")]
    cols += [("norm_W_hat", "-"), ("V1", "-")]
    cols += [("z1", "m"), ("phi1", "rad"), ("theta1", "rad"), ("psi1", "rad"),
             ("x1", "m"), ("y1", "m"), ("x2", "m"), ("y2", "m"), ("psi2", "rad"),
             ("u2", "m/s"), ("v2", "m/s"), ("r2", "rad/s")]
    cols += [(f"d_F{a}", "N") for a in "xyz"] + [(f"d_M{a}", "N m") for a in "xyz"]
    return tuple(cols)


#: Columns of trajectory.csv: (name, unit).
COLUMNS = _columns()


@dataclasses.dataclass(frozen=True)
class SimulationResult(Mapping):
    """The outputs of one simulation, each a NumPy array by name.

    ``result["t"]``, ``result["z_e"]``, ... (see ``COLUMNS``); ``states``
    is the closed-loop state at each row, ``(len(t), nx)``.
    """

    scenario: Scenario
    columns: Mapping[str, np.ndarray]
    states: np.ndarray

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def __iter__(self):
        return iter(self.columns)

    def __len__(self) -> int:
        return len(self.columns)

    def to_csv(self, path=None) -> str:
        """The trajectory as CSV text (header ``name [unit]``); written to ``path`` if given."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow([f"{n} [{u}]" for n, u in COLUMNS])
        data = np.column_stack([self.columns[n] for n, _ in COLUMNS])
        for row in data:
            writer.writerow([f"{v:.12g}" for v in row])
        text = buf.getvalue()
        if path is not None:
            from quadland.output import write_text_atomic
            write_text_atomic(path, text)
        return text


def time_grid(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output times, disturbance sample times and their merged grid.

    Returns ``(t_out, t_dist, t_all)``; every interval of ``t_all`` has a
    constant disturbance. ``t_dist`` ends with the final time, whose sample
    is only reported, never integrated.
    """
    sim, dist = scenario.data["simulation"], scenario.data["disturbance"]
    T = sim["duration"]
    t_out = _arange(T, 1.0 / sim["output_rate_hz"])
    t_dist = _arange(T, 1.0 / dist["sample_rate_hz"])
    t_all = np.unique(np.round(np.concatenate([t_out, t_dist]), 12))
    return t_out, t_dist, t_all


def _arange(T, h):
    n = int(np.floor(T / h + 1e-9))
    t = h * np.arange(n + 1)
    return t if np.isclose(t[-1], T) else np.append(t, T)


def _held(t_switch, values, times):
    """Column of ``values`` in force at each of ``times`` (zero-order hold)."""
    idx = np.searchsorted(t_switch, np.asarray(times) + 1e-12, side="right") - 1
    return values[:, np.clip(idx, 0, values.shape[1] - 1)]


@functools.lru_cache(maxsize=8)
def _continuous_integrator(l: int, plugin: str, opts: tuple, grid: tuple):
    f = closed_loop_function(l)
    x, w, p = ca.SX.sym("x", f.size1_in(0)), ca.SX.sym("w", 6), ca.SX.sym("p", f.size1_in(2))
    dae = {"x": x, "u": w, "p": p, "ode": f(x, w, p)}
    return ca.integrator("closed_loop_sim", plugin, dae, grid[0], list(grid[1:]), dict(opts))


@functools.lru_cache(maxsize=16)
def _plant_integrator(plugin: str, opts: tuple, h: float):
    f = plant_function()
    xp, u = ca.SX.sym("xp", 18), ca.SX.sym("u", 10)
    pq, pv = ca.SX.sym("pq", f.size1_in(3)), ca.SX.sym("pv", f.size1_in(4))
    dae = {"x": xp, "u": u, "p": ca.vertcat(pq, pv), "ode": f(xp, u[0:4], u[4:10], pq, pv)}
    return ca.integrator("plant_sim", plugin, dae, 0.0, h, dict(opts))


def _integrator_options(scenario: Scenario, n_intervals: int) -> tuple[str, tuple]:
    """Plugin and options for a grid of ``n_intervals`` hold intervals.

    cvodes runs Adams with functional iteration: the loop is not stiff, and
    the disturbance restarts the solver every hold interval, which makes a
    BDF method's Jacobian factorizations the dominant cost. CasADi's "rk"
    spreads ``number_of_finite_elements`` over the whole horizon, so it is
    scaled by the number of intervals.
    """
    sim = scenario.data["simulation"]
    if sim["integrator"] == "cvodes":
        opts = {"abstol": sim["abstol"], "reltol": sim["reltol"], "max_num_steps": 100000,
                "linear_multistep_method": "adams", "nonlinear_solver_iteration": "functional"}
    else:
        opts = {"number_of_finite_elements": sim["rk_steps_per_interval"] * n_intervals}
    return sim["integrator"], tuple(sorted(opts.items()))


def simulate(scenario: Scenario) -> SimulationResult:
    """Simulate a scenario's closed loop.

    Parameters
    ----------
    scenario : Scenario
        From :func:`quadland.load_scenario`.

    Returns
    -------
    SimulationResult
        Every output of ``COLUMNS`` sampled at ``simulation.output_rate_hz``.

    Raises
    ------
    SimulationError
        When the attitude reaches the thrust map's singularity or the state
        stops being finite.

    Examples
    --------
    >>> import quadland
    >>> sc = quadland.load_scenario("paper", ["simulation.duration=0.5"])
    >>> res = quadland.simulate(sc)
    >>> res["t"][-1]
    0.5
    """
    mv = model_values(scenario)
    t_out, t_dist, t_all = time_grid(scenario)
    w_dist = disturbance_samples(scenario, t_dist)
    if scenario.data["controller"]["rate_hz"] > 0:
        X, held = _simulate_sampled(scenario, mv, t_out, t_dist, w_dist)
    else:
        X, held = _simulate_continuous(scenario, mv, t_out, t_dist, t_all, w_dist), None
    X_np = X.full() if isinstance(X, ca.DM) else X
    if not np.all(np.isfinite(X_np)):
        bad = int(np.argmax(~np.all(np.isfinite(X_np), axis=0)))
        raise SimulationError(f"state became non-finite at t = {t_out[bad]:.4g} s "
                              "(check gains and the initial attitude)")
    return _result(scenario, mv, t_out, t_dist, w_dist, X, X_np, held)


def _simulate_continuous(scenario, mv, t_out, t_dist, t_all, w_dist):
    plugin, opts = _integrator_options(scenario, len(t_all) - 1)
    integ = _continuous_integrator(mv.l, plugin, opts, tuple(t_all))
    w = _held(t_dist, w_dist, t_all[:-1])
    try:
        out = integ(x0=mv.x0, u=w, p=mv.p)
    except RuntimeError as exc:
        raise SimulationError(f"integrator {plugin} failed: {str(exc).splitlines()[-1]}") from None
    X = ca.horzcat(ca.DM(mv.x0), out["xf"])           # stays a DM: no NumPy round trip
    keep = np.flatnonzero(np.isin(np.round(t_all, 12), np.round(t_out, 12)))
    return X if len(keep) == X.shape[1] else X[:, keep.tolist()]


def _control_step(scenario, l):
    backend = scenario.data["controller"]["backend"]
    if backend == "c":
        from quadland.cbackend import load_control_step
        return load_control_step(l)
    return control_step_function(l)


def _simulate_sampled(scenario, mv, t_out, t_dist, w_dist):
    """Control step at ``rate_hz`` with zero-order hold on the plant.

    The step's hold compensation (``controller.hold_compensation``) is off
    on the first sample, which has no previous command, and on from the
    second.
    """
    rate = scenario.data["controller"]["rate_hz"]
    T = scenario.data["simulation"]["duration"]
    t_ctrl = _arange(T, 1.0 / rate)[:-1] if T > 0 else np.zeros(1)
    grid = np.unique(np.round(np.concatenate([t_out, t_dist, t_ctrl]), 12))
    step = _control_step(scenario, mv.l)
    plugin, opts = _integrator_options(scenario, 1)
    lay = closed_loop_layout(mv.l)
    xq_idx = np.r_[0:16, lay.nx - 2:lay.nx]
    xp = mv.x0[xq_idx].copy()
    W = np.zeros((mv.l, 4))
    zeta = np.zeros(4)
    u_law = np.zeros(4)
    hold = 0.0                     # no previous command on the first step
    yv_z2 = mv.p_veh[-1]
    limits = np.asarray(mv.rotor_limits, dtype=float)
    ctrl_set = set(np.round(t_ctrl, 12))
    out_set = {t: k for k, t in enumerate(np.round(t_out, 12))}
    X = np.zeros((lay.nx, len(t_out)))
    held = np.zeros((12, len(t_out)))
    wrench = u = rotor = np.zeros(4)
    pv = np.concatenate([mv.p_quad, mv.p_veh])
    dt = 1.0 / rate
    for i, t in enumerate(grid):
        if t in ctrl_set:
            yv = np.array([yv_z2, xp[12], xp[15]])
            r = step(xp[0:10], yv, mv.ref, W, zeta, u_law, mv.p_quad, mv.p_ctrl, limits, hold,
                     dt)
            u, wrench, rotor, W, zeta, u_law, _, tilt = (np.asarray(v, dtype=float) for v in r)
            if abs(tilt.item()) < TILT_MIN:
                raise SimulationError(f"singular attitude at t = {t:.4g} s: "
                                      f"cos(theta) cos(phi) = {tilt.item():.2e}")
            u, wrench, rotor = u.ravel(), wrench.ravel(), rotor.ravel()
            zeta, u_law, hold = zeta.ravel(), u_law.ravel(), mv.hold
        if t in out_set:
            k = out_set[t]
            X[:, k] = np.concatenate([xp[0:16], W.ravel(order="F"), zeta, xp[16:18]])
            held[:, k] = np.concatenate([u, wrench, rotor])
        if i + 1 < len(grid):
            h = round(grid[i + 1] - t, 12)
            w = _held(t_dist, w_dist, [t])[:, 0]
            integ = _plant_integrator(plugin, opts, h)
            xp = np.asarray(integ(x0=xp, u=np.concatenate([wrench, w]), p=pv)["xf"]).ravel()
            if not np.all(np.isfinite(xp)):
                raise SimulationError(f"state became non-finite at t = {t:.4g} s")
    return X, held


@functools.lru_cache(maxsize=8)
def _mapped_outputs(l: int, n: int) -> ca.Function:
    return closed_loop_outputs(l).map(n)


def _result(scenario, mv, t_out, t_dist, w_dist, X, X_np, held):
    lay = closed_loop_layout(mv.l)
    w_out = _held(t_dist, w_dist, t_out)
    n = len(t_out)
    outs = _mapped_outputs(mv.l, n)(X, w_out, mv.p)
    X = X_np
    sig = {name: np.asarray(v) for (name, _), v in zip(OUTPUTS, outs)}
    tilt = np.cos(X[1]) * np.cos(X[2])
    if np.any(np.abs(tilt) < TILT_MIN):
        k = int(np.argmax(np.abs(tilt) < TILT_MIN))
        raise SimulationError(f"singular attitude at t = {t_out[k]:.4g} s: "
                              f"cos(theta) cos(phi) = {tilt[k]:.2e}")
    if held is not None:
        sig["u"], sig["wrench"], sig["rotor"] = held[0:4], held[4:8], held[8:12]
    cols = {"t": t_out}
    names4 = {"e1": ("z_e", "phi_e", "theta_e", "psi_e"), "e2": ("dz_e", "p_e", "q_e", "r_e"),
              "wrench": ("F_total", "M_x", "M_y", "M_z")}
    for key, names in names4.items():
        cols.update({nm: sig[key][i] for i, nm in enumerate(names)})
    for key, stem in (("u", "u"), ("rotor", "F"), ("Delta", "Delta"),
                      ("Delta_hat", "Delta_hat"), ("Delta_target", "Delta_target")):
        cols.update({f"{stem}_{i + 1}": sig[key][i] for i in range(4)})
    zeta = X[16 + 4 * mv.l:20 + 4 * mv.l]
    cols.update({f"zeta_hat_{i + 1}": zeta[i] for i in range(4)})
    cols["norm_W_hat"] = np.linalg.norm(X[16:16 + 4 * mv.l], axis=0)
    cols["V1"] = sig["V1"][0]
    for i, nm in enumerate(("z1", "phi1", "theta1", "psi1")):
        cols[nm] = X[i]
    cols["x1"], cols["y1"] = X[lay.nx - 2], X[lay.nx - 1]
    for i, nm in enumerate(("x2", "y2", "psi2", "u2", "v2", "r2")):
        cols[nm] = X[10 + i]
    for i, nm in enumerate(("d_Fx", "d_Fy", "d_Fz", "d_Mx", "d_My", "d_Mz")):
        cols[nm] = w_out[i]
    return SimulationResult(scenario, {k: np.asarray(v, dtype=float).ravel()
                                       for k, v in cols.items()}, X.T)

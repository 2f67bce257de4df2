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

from quadland.compiled import SIM_CONTROLLER, SIM_GUARD, compiled_loop
from quadland.constants import TILT_MIN
from quadland.exceptions import ScenarioError, SimulationError
from quadland.model import disturbance_samples, model_values
from quadland.scenario import Scenario
from symbolic.closed_loop import (
    OUTPUTS,
    PLANT_STATE,
    POSITION1,
    closed_loop_function,
    closed_loop_outputs,
    closed_loop_state,
    plant_function,
    vehicle_measurement,
)
from symbolic.control_step import control_step_function, step_outputs
from symbolic.layout import Field, Layout
from symbolic.quadrotor import DISTURBANCE
from symbolic.quadrotor import STATE as QUAD_STATE
from symbolic.simulation import rk4_step
from symbolic.vehicle import STATE as VEHICLE_STATE

__all__ = ["SimulationResult", "simulate", "TRAJECTORY", "COLUMNS", "columns_sidecar",
           "time_grid", "SimulationPlan", "simulation_plan", "check_plan", "MEMORY_BUDGET",
           "MAX_RK4_STEPS"]

#: Most memory a simulation may plan for its arrays, bytes.
MEMORY_BUDGET = 2 << 30
#: Most RK4 steps one simulation may take (about 7 min at l = 100).
MAX_RK4_STEPS = 2e8
#: RK4 is stable on lambda h inside about -2.785 on the real axis.
_RK4_REAL_STABILITY = 2.785


@dataclasses.dataclass(frozen=True)
class SimulationPlan:
    """What a simulation will need, estimated from its scenario before it starts.

    Attributes
    ----------
    rows : int
        Output rows (trajectory.csv).
    intervals : int
        Hold intervals of the merged time grid (an upper bound).
    rk4_steps : int
        RK4 steps of the whole run (an upper bound).
    memory_bytes : int
        Memory for its arrays (states, outputs, columns, grid), bytes.
    """

    rows: int
    intervals: int
    rk4_steps: int
    memory_bytes: int


def simulation_plan(scenario: Scenario) -> SimulationPlan:
    """Estimate a run's size from its scenario alone (no allocation).

    Examples
    --------
    >>> import quadland
    >>> plan = simulation_plan(quadland.load_scenario("paper"))
    >>> plan.rows, plan.rk4_steps <= 2004, plan.memory_bytes < 2**23
    (1001, True, True)
    """
    sim, ctrl, dist = (scenario.data[k] for k in ("simulation", "controller", "disturbance"))
    T = sim["duration"]
    rows = int(T * sim["output_rate_hz"]) + 2
    clocks = rows + int(T * dist["sample_rate_hz"]) + 2
    if ctrl["rate_hz"] > 0:
        clocks += int(T * ctrl["rate_hz"]) + 2
    l = scenario.data["rbf"]["nodes"]
    nx, nw = closed_loop_state(l).size, DISTURBANCE.size
    per_row = 2 * nx + OUTPUTS.size + len(COLUMNS) + nw + 12
    return SimulationPlan(rows - 1, clocks, clocks * sim["rk_steps_per_interval"],
                          8 * (rows * per_row + clocks * (nw + 4)))


def check_plan(scenario: Scenario) -> None:
    """Refuse, with one line naming the keys, a run over the memory or step budget."""
    plan = simulation_plan(scenario)
    if plan.memory_bytes > MEMORY_BUDGET:
        raise ScenarioError(
            f"simulation.duration x simulation.output_rate_hz: {plan.rows:,} output rows need "
            f"about {plan.memory_bytes / 2**30:.1f} GiB, over the {MEMORY_BUDGET / 2**30:g} GiB "
            "limit; lower either")
    if plan.rk4_steps > MAX_RK4_STEPS:
        raise ScenarioError(
            f"simulation.duration: the run needs {plan.rk4_steps:.2g} RK4 steps (duration x "
            f"the fastest clock x simulation.rk_steps_per_interval), over the "
            f"{MAX_RK4_STEPS:.0e} limit; lower one of them")

#: The columns of trajectory.csv, composed from the model's layouts.
TRAJECTORY = Layout("trajectory", (
    Field("t", 1, "s", "time"),
    *(OUTPUTS[n] for n in ("e1", "e2", "u", "wrench", "rotor", "Delta", "Delta_hat",
                           "Delta_target")),
    dataclasses.replace(closed_loop_state(1)["zeta_hat"], doc="robust term estimate zeta_hat"),
    Field("norm_W_hat", 1, "-", "Frobenius norm of the network weights W_hat"),
    OUTPUTS["lyapunov_V1"],
    QUAD_STATE["z1"],
    QUAD_STATE["eta1"],
    *POSITION1.fields,
    *VEHICLE_STATE.fields,
    *DISTURBANCE.fields,
), "one row per output time of a simulation")

#: Columns of trajectory.csv: (name, unit).
COLUMNS = tuple(zip(TRAJECTORY.element_names(), TRAJECTORY.element_units(), strict=True))


@dataclasses.dataclass(frozen=True)
class SimulationResult(Mapping):
    """The outputs of one simulation, each a NumPy array by name.

    ``result["t"]``, ``result["z_e"]``, ... (the entries of ``TRAJECTORY``);
    ``states`` is the closed-loop state at each row, ``(len(t), nx)``.
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
        """The trajectory as CSV text with a header of plain names; written to ``path`` if given.

        Units are in :func:`columns_sidecar` (``columns.json``) and ``docs/simulation.md``.
        """
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow([n for n, _ in COLUMNS])
        data = np.column_stack([self.columns[n] for n, _ in COLUMNS])
        for row in data:
            writer.writerow([f"{v:.12g}" for v in row])
        text = buf.getvalue()
        if path is not None:
            from quadland.output import write_text_atomic
            write_text_atomic(path, text)
        return text


def columns_sidecar() -> dict:
    """``columns.json``: each CSV column's unit and meaning, in column order."""
    return {"columns": [dict(name=n, unit=u, doc=d) for n, u, d in
                        zip(TRAJECTORY.element_names(), TRAJECTORY.element_units(),
                            TRAJECTORY.element_docs(), strict=True)]}


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
    x, w, p = (ca.SX.sym(f.name_in(i), f.size1_in(i)) for i in range(3))
    dae = {"x": x, "u": w, "p": p, "ode": f(x, w, p)}
    return ca.integrator("closed_loop_sim", plugin, dae, grid[0], list(grid[1:]), dict(opts))


@functools.lru_cache(maxsize=16)
def _plant_integrator(plugin: str, opts: tuple, h: float):
    f = plant_function()
    xp, u = PLANT_STATE.sym(), ca.SX.sym("u", f.size1_in(1) + f.size1_in(2))
    pq, pv = ca.SX.sym("pq", f.size1_in(3)), ca.SX.sym("pv", f.size1_in(4))
    nwr = f.size1_in(1)
    dae = {"x": xp, "u": u, "p": ca.vertcat(pq, pv), "ode": f(xp, u[:nwr], u[nwr:], pq, pv)}
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
    >>> float(res["t"][-1]), len(res["t"])
    (0.5, 51)
    """
    check_plan(scenario)
    mv = model_values(scenario)
    t_out, t_dist, t_all = time_grid(scenario)
    w_dist = disturbance_samples(scenario, t_dist)
    w_out = _held(t_dist, w_dist, t_out).T                       # (n_out, nw)
    failure = None
    if scenario.data["controller"]["rate_hz"] > 0:
        flight = scenario.data["controller"]["backend"] == "c"
        loop = compiled_loop(mv.l, "sampled_flight" if flight else "sampled")
        if loop is not None:
            X, held, failure = _sampled_compiled(loop, scenario, mv, t_out, t_dist, w_dist)
        else:
            X, held = _simulate_sampled(scenario, mv, t_out, t_dist, w_dist)
    else:
        loop = compiled_loop(mv.l, "continuous")
        held = None
        if loop is not None and scenario.data["simulation"]["integrator"] == "rk":
            X, failure = _continuous_compiled(loop, scenario, mv, t_out, t_dist, t_all, w_dist)
        else:
            X = _simulate_continuous(scenario, mv, t_out, t_dist, t_all, w_dist)
    n = len(X) if failure is None else failure[0]
    finite = np.all(np.isfinite(X[:n]), axis=1)
    if not finite.all():
        n = int(np.argmin(finite))
        failure = (n, t_out[n], "the state became non-finite")
    Y = (loop.outputs(X[:n], w_out[:n], mv.p) if loop is not None
         else _vm_outputs(mv, X[:n], w_out[:n]))
    finite = np.all(np.isfinite(Y), axis=1)
    if not finite.all():
        bad = int(np.argmin(finite))
        name = OUTPUTS.element_names()[int(np.argmin(np.isfinite(Y[bad])))]
        n, failure = bad, (bad, t_out[bad], f"the output {name} became non-finite")
    result = _result(scenario, mv, t_out[:n], w_out[:n], X[:n], Y[:n],
                     None if held is None else held[:, :n])
    tilt = np.cos(result["phi1"]) * np.cos(result["theta1"])
    if np.any(np.abs(tilt) < TILT_MIN):
        k = int(np.argmax(np.abs(tilt) < TILT_MIN))
        failure = (k, t_out[k], f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}")
        result = _truncated(result, k)
    if failure is not None:
        _, t_fail, what = failure
        raise SimulationError(f"flight failed at t = {t_fail:.4g} s: {what}"
                              f"{_divergence_hint(scenario)}", t_fail,
                              result if len(result["t"]) else None)
    return result


def _truncated(result: SimulationResult, n: int) -> SimulationResult:
    return SimulationResult(result.scenario, {k: v[:n] for k, v in result.columns.items()},
                            result.states[:n])


def _divergence_hint(scenario: Scenario) -> str:
    """A hint where the fixed-step integrator is the likely cause, else the usual suspects.

    The loop's fastest modes are set by the gains (eq. 15, 24: z1 decays at
    k1, z2 at k2), and RK4 is stable for ``|lambda| h < 2.785``.
    """
    sim, ctrl = scenario.data["simulation"], scenario.data["controller"]
    if sim["integrator"] != "rk":
        return " (check the gains and the initial attitude)"
    clocks = [scenario.data["simulation"]["output_rate_hz"],
              scenario.data["disturbance"]["sample_rate_hz"]]
    if ctrl["rate_hz"] > 0:
        clocks.append(ctrl["rate_hz"])
    h = 1.0 / max(clocks) / sim["rk_steps_per_interval"]
    fastest = max(max(ctrl["k1"]), max(ctrl["k2"]))
    if fastest * h > _RK4_REAL_STABILITY / 2:
        need = int(np.ceil(fastest * sim["rk_steps_per_interval"] * h
                           / (_RK4_REAL_STABILITY / 4)))
        return (f" (the RK4 step h = {h:.3g} s is likely too coarse for gains up to "
                f"{fastest:g} 1/s: try simulation.rk_steps_per_interval={need} or "
                "simulation.integrator=\"cvodes\")")
    return " (check the gains and the initial attitude)"


def _grid_index(grid, times):
    """For each point of ``grid``, its index in the sorted ``times`` (both rounded
    to 1e-12 s), or -1 where it is not one of them."""
    g, t = np.round(grid, 12), np.round(times, 12)
    k = np.clip(np.searchsorted(t, g), 0, len(t) - 1)
    return np.where(t[k] == g, k, -1).astype(np.int_)


def _continuous_compiled(loop, scenario, mv, t_out, t_dist, t_all, w_dist):
    """The continuous loop in one compiled call: one RK4 step (times
    ``rk_steps_per_interval``) per interval of the merged grid, exactly."""
    W = _held(t_dist, w_dist, t_all[:-1]).T
    rec = _grid_index(t_all[1:], t_out)
    X, _, failure = loop.integrate(mv.x0, W, np.diff(t_all), rec,
                                   scenario.data["simulation"]["rk_steps_per_interval"], mv.p,
                                   len(t_out))
    if failure is None:
        return X, None
    done = int(np.max(rec[:failure.index], initial=0)) + 1      # rows recorded before it
    return X, (done, t_all[failure.index + 1], "the state became non-finite")


def _sampled_compiled(loop, scenario, mv, t_out, t_dist, w_dist):
    """The sampled-data loop in one compiled call (see ``_simulate_sampled``)."""
    rate = scenario.data["controller"]["rate_hz"]
    T = scenario.data["simulation"]["duration"]
    t_ctrl = _arange(T, 1.0 / rate)[:-1] if T > 0 else np.zeros(1)
    grid = np.unique(np.round(np.concatenate([t_out, t_dist, t_ctrl]), 12))
    model = loop.model
    x0 = closed_loop_state(mv.l).unpack(mv.x0)
    xp0 = model.plant_state.pack({n: x0[n] for n in model.plant_state.names()})
    xc0 = model.controller_state.pack(dict(W_hat=x0["W_hat"], zeta_hat=x0["zeta_hat"],
                                           u_prev=np.zeros(4)))
    pp = model.plant_params.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh))
    pc = model.controller_params.pack(dict(
        p_quad=mv.p_quad, p_veh=mv.p_veh, p_ctrl=mv.p_ctrl, ref=mv.ref,
        rotor_limits=mv.rotor_limits, hold=mv.hold, dt=1.0 / rate))
    ctrl = _grid_index(grid[:-1], t_ctrl) >= 0
    rec = _grid_index(grid, t_out)
    W = _held(t_dist, w_dist, grid[:-1]).T
    X, R, _, _, failure = loop.sampled(
        xp0, xc0, W, np.diff(grid), ctrl, rec, scenario.data["simulation"]["rk_steps_per_interval"],
        pp, pc, TILT_MIN, len(t_out))
    if failure is None:
        return X, R.T, None
    t = grid[min(failure.index, len(grid) - 1)]
    done = int(np.max(rec[:failure.index + 1], initial=-1)) + 1
    what = {SIM_GUARD: f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}",
            SIM_CONTROLLER: "the flight control step (controller.backend = \"c\") returned "
                            "an error status"}.get(failure.status, "the state became non-finite")
    return X, R.T, (done, t, what)


@functools.lru_cache(maxsize=4)
def _rk4_closed_loop(l: int) -> ca.Function:
    return rk4_step(closed_loop_function(l))


def _simulate_continuous(scenario, mv, t_out, t_dist, t_all, w_dist):
    if scenario.data["simulation"]["integrator"] == "rk":
        return _continuous_rk4_vm(scenario, mv, t_out, t_dist, t_all, w_dist)
    plugin, opts = _integrator_options(scenario, len(t_all) - 1)
    integ = _continuous_integrator(mv.l, plugin, opts, tuple(t_all))
    w = _held(t_dist, w_dist, t_all[:-1])
    try:
        out = integ(x0=mv.x0, u=w, p=mv.p)
    except RuntimeError as exc:
        raise SimulationError(f"integrator {plugin} failed: {str(exc).splitlines()[-1]}") from None
    X = np.hstack([mv.x0[:, None], np.asarray(out["xf"])])
    keep = np.flatnonzero(np.isin(np.round(t_all, 12), np.round(t_out, 12)))
    return np.ascontiguousarray(X[:, keep].T)


def _continuous_rk4_vm(scenario, mv, t_out, t_dist, t_all, w_dist):
    """The compiled driver's method on CasADi's virtual machine: one RK4 step (times
    ``rk_steps_per_interval``) per interval of the merged grid."""
    step, m = _rk4_closed_loop(mv.l), scenario.data["simulation"]["rk_steps_per_interval"]
    W = _held(t_dist, w_dist, t_all[:-1])
    rec = _grid_index(t_all[1:], t_out)
    X = np.zeros((len(t_out), len(mv.x0)))
    X[0] = x = mv.x0
    for j, h in enumerate(np.diff(t_all)):
        for _ in range(m):
            x = step(x, W[:, j], mv.p, h / m)
        if rec[j] >= 0:
            X[rec[j]] = np.asarray(x).ravel()
    return X


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
    lay = closed_loop_state(mv.l)
    x0 = lay.unpack(mv.x0)
    xp = PLANT_STATE.pack({n: x0[n] for n in PLANT_STATE.names()})
    xq_of, xv_of = PLANT_STATE.slice("xq"), PLANT_STATE.slice("xv")
    W, zeta = x0["W_hat"], x0["zeta_hat"]
    u_law = np.zeros(4)
    hold = 0.0                     # no previous command on the first step
    limits = np.asarray(mv.rotor_limits, dtype=float)
    ctrl_set = set(np.round(t_ctrl, 12))
    out_set = {t: k for k, t in enumerate(np.round(t_out, 12))}
    X = np.zeros((lay.size, len(t_out)))
    held = np.zeros((12, len(t_out)))
    wrench = u = rotor = np.zeros(4)
    pv = np.concatenate([mv.p_quad, mv.p_veh])
    dt = 1.0 / rate
    for i, t in enumerate(grid):
        if t in ctrl_set:
            yv = np.asarray(vehicle_measurement(xp[xv_of], mv.p_veh), dtype=float).ravel()
            r = step(xp[xq_of], yv, mv.ref, W, zeta, u_law, mv.p_quad, mv.p_ctrl, limits, hold,
                     dt)
            u, wrench, rotor, W, zeta, u_law, _, tilt = (np.asarray(v, dtype=float) for v in r)
            if abs(tilt.item()) < TILT_MIN:
                raise SimulationError(f"singular attitude at t = {t:.4g} s: "
                                      f"cos(theta) cos(phi) = {tilt.item():.2e}")
            u, wrench, rotor = u.ravel(), wrench.ravel(), rotor.ravel()
            zeta, u_law, hold = zeta.ravel(), u_law.ravel(), mv.hold
        if t in out_set:
            k = out_set[t]
            ps = PLANT_STATE.unpack(xp)
            X[:, k] = lay.pack(dict(xq=ps["xq"], xv=ps["xv"], W_hat=W, zeta_hat=zeta,
                                    pos1=ps["pos1"]))
            held[:, k] = np.concatenate([u, wrench, rotor])
        if i + 1 < len(grid):
            h = round(grid[i + 1] - t, 12)
            w = _held(t_dist, w_dist, [t])[:, 0]
            integ = _plant_integrator(plugin, opts, h)
            xp = np.asarray(integ(x0=xp, u=np.concatenate([wrench, w]), p=pv)["xf"]).ravel()
            if not np.all(np.isfinite(xp)):
                raise SimulationError(f"state became non-finite at t = {t:.4g} s")
    return np.ascontiguousarray(X.T), held


#: Samples per call of the mapped output function on CasADi's virtual machine.
_VM_CHUNK = 256


@functools.lru_cache(maxsize=4)
def _mapped_outputs(l: int) -> ca.Function:
    # the parameter vector (input 2) is shared by every sample, not repeated
    return closed_loop_outputs(l).map("outputs_map", "serial", _VM_CHUNK, [2], [])


def _vm_outputs(mv, X, w_out) -> np.ndarray:
    """Output signals on CasADi's virtual machine, in chunks, ``(n, ny)``."""
    fn, n = _mapped_outputs(mv.l), X.shape[0]
    Y = np.empty((n, OUTPUTS.size))
    for a in range(0, n, _VM_CHUNK):
        b = min(a + _VM_CHUNK, n)
        Xc, Wc = np.zeros((_VM_CHUNK, X.shape[1])), np.zeros((_VM_CHUNK, w_out.shape[1]))
        Xc[: b - a], Wc[: b - a] = X[a:b], w_out[a:b]
        outs = fn(Xc.T, Wc.T, mv.p)
        Y[a:b] = np.vstack([np.asarray(v) for v in outs]).T[: b - a]
    return Y


def _result(scenario, mv, t_out, w_out, X, Y, held):
    """Columns of ``TRAJECTORY`` from states ``X`` (n, nx) and outputs ``Y`` (n, ny)."""
    lay = closed_loop_state(mv.l)
    xs = lay.unpack(X.T)
    sig = OUTPUTS.unpack(Y.T)
    if held is not None:
        so = step_outputs(mv.l)
        for name in ("u", "wrench", "rotor"):
            sig[name] = held[so.slice(name)]
    data = dict(sig, t=t_out[None, :], zeta_hat=xs["zeta_hat"],
                norm_W_hat=np.sqrt(np.einsum("ij,ij->i", X[:, lay.slice("W_hat")],
                                             X[:, lay.slice("W_hat")]))[None, :],
                **QUAD_STATE.unpack(xs["xq"]), **POSITION1.unpack(xs["pos1"]),
                **VEHICLE_STATE.unpack(xs["xv"]), **DISTURBANCE.unpack(w_out.T))
    cols = {}
    for f in TRAJECTORY.fields:
        rows = np.asarray(data[f.name], dtype=float).reshape(f.size, -1)
        cols.update(zip(f.element_names(), rows, strict=True))
    return SimulationResult(scenario, {k: np.ascontiguousarray(v, dtype=float)
                                       for k, v in cols.items()}, X)

"""Closed-loop simulation, compiled (or on CasADi's virtual machine without a compiler).

Two loops share one symbolic model (``quadland_symbolic.paper_loop``), and both run
in one call of a simulator (:func:`quadland.compiled.compiled_loop`): RK4,
one step (times ``simulation.rk_steps_per_interval``) per interval of the
exact grid on which the disturbance, the outputs and the control are held:

* continuous (``controller.rate_hz = 0``, the paper's): the whole closed
  loop of ``quadland_symbolic.closed_loop`` is one ODE; ``simulation.integrator =
  "cvodes"`` integrates it with CasADi's cvodes instead (the reference);
* sampled-data (``rate_hz > 0``): the control step (``controller.backend``:
  the CasADi function or the flight code's ``ql_control_step``) runs at that
  rate and its wrench is held on the plant.

A run's size is checked first (:func:`check_plan`); a flight that fails
raises :class:`SimulationError` carrying the trajectory up to the failure.
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import io
import re
from collections.abc import Mapping

import casadi as ca
import numpy as np

from quadland.compiled import SIM_CONTROLLER, SIM_ENVELOPE, SIM_GUARD, SIM_OK, Run, compiled_loop
from quadland.constants import TILT_MIN
from quadland.engine.loop import Clock, merged_grid
from quadland.envelope import ENVELOPE_FACTOR, Envelope, rk4_steps_needed
from quadland.exceptions import ScenarioError, SimulationError
from quadland.model import disturbance_samples, model_values
from quadland.scenario import Scenario
from quadland_symbolic.closed_loop import (
    PAPER_ENVELOPE,
    PAPER_OUTPUTS,
    POSITION1,
    closed_loop_function,
    closed_loop_jacobian_function,
    closed_loop_state,
    paper_envelope_function,
)
from quadland_symbolic.control_step import step_outputs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE, WRENCH
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["SimulationResult", "simulate", "TRAJECTORY", "COLUMNS", "columns_sidecar",
           "time_grid", "run_clocks", "SimulationPlan", "simulation_plan", "check_plan",
           "paper_envelope", "slow_control_hint", "longest_rk4_step",
           "rk4_hint", "LOOP_DIVERGED", "MEMORY_BUDGET", "MAX_RK4_STEPS"]

#: Most memory a simulation may plan for its arrays, bytes.
MEMORY_BUDGET = 2 << 30
#: Most RK4 steps one simulation may take (about 7 min at l = 100).
MAX_RK4_STEPS = 2e8
#: The node count MAX_RK4_STEPS is for; the limit scales with 100 / l (a step's
#: cost grows with the node count).
_REFERENCE_NODES = 100
#: Gain times control period beyond which a sampled loop is likely too slow
#: (the paper's loop needs 40 Hz for gains of 10 1/s: docs/margins.md).
_SLOW_CONTROL = 0.25
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
    if scenario.model == "landing":
        from quadland_symbolic.landing.loop import LANDING_RECORDED, landing_loop_state
        from quadland_symbolic.landing.plant import LANDING_DISTURBANCE
        from quadland_symbolic.landing.signals import LANDING_SIGNALS

        nx, nw = landing_loop_state(l).size, LANDING_DISTURBANCE.size
        per_row = 2 * nx + 2 * (LANDING_SIGNALS.size + LANDING_RECORDED.size) + nw + 12
    else:
        nx, nw = closed_loop_state(l).size, BODY_DISTURBANCE.size
        per_row = 2 * nx + PAPER_OUTPUTS.size + len(COLUMNS) + nw + 12
    memory = 8 * (rows * per_row + clocks * (nw + 4))
    if sim.get("integrator") == "cvodes":      # cvodes returns the state at every grid point
        memory += 8 * 2 * clocks * nx
    return SimulationPlan(rows - 1, clocks, clocks * sim["rk_steps_per_interval"], memory)


def check_plan(scenario: Scenario) -> None:
    """Refuse, with one line naming the keys, a run over the memory or step budget."""
    plan = simulation_plan(scenario)
    if scenario.model == "landing":
        _check_motor_step(scenario)
    if plan.memory_bytes > MEMORY_BUDGET:
        raise ScenarioError(
            f"simulation.duration x simulation.output_rate_hz: {plan.rows:,} output rows need "
            f"about {plan.memory_bytes / 2**30:.1f} GiB, over the {MEMORY_BUDGET / 2**30:g} GiB "
            "limit; lower either")
    l = scenario.data["rbf"]["nodes"]
    limit = MAX_RK4_STEPS * _REFERENCE_NODES / max(l, _REFERENCE_NODES // 10)
    if plan.rk4_steps > limit:
        raise ScenarioError(
            f"simulation.duration: the run needs {plan.rk4_steps:.2g} RK4 steps (duration x "
            f"the fastest clock x simulation.rk_steps_per_interval), over the limit of "
            f"{limit:.2g} for {l} RBF nodes; lower one of them")

def _check_motor_step(scenario: Scenario) -> None:
    """Refuse a landing whose fixed RK4 step cannot follow the motors' lag.

    The motors are ``F' = (F_cmd - F) / tau_m``: RK4 is stable for
    ``h / tau_m < 2.785``; half of that is required, with ``h`` the longest
    step of the merged grid (at most the shortest clock period over
    ``rk_steps_per_interval``).
    """
    sim, q = scenario.data["simulation"], scenario.data["quadrotor"]
    rates = (sim["output_rate_hz"], scenario.data["disturbance"]["sample_rate_hz"],
             scenario.data["controller"]["rate_hz"])
    h = 1.0 / max(rates) / sim["rk_steps_per_interval"]
    tau = q["motor_time_constant"]
    if h / tau > _RK4_REAL_STABILITY / 2:
        need = int(np.ceil(sim["rk_steps_per_interval"] * h / tau / (_RK4_REAL_STABILITY / 2)))
        raise ScenarioError(
            f"quadrotor.motor_time_constant: {tau:g} s is too fast for the RK4 step h = "
            f"{h:.3g} s (h / tau_m must stay below {_RK4_REAL_STABILITY / 2:.3g}); raise "
            f"simulation.rk_steps_per_interval to {need}")


#: The columns of trajectory.csv, composed from the model's layouts.
TRAJECTORY = Layout("trajectory", (
    Field("t", 1, "s", "time"),
    *(PAPER_OUTPUTS[n] for n in ("e1", "e2", "u", "wrench", "rotor", "Delta", "Delta_hat",
                           "Delta_target")),
    dataclasses.replace(closed_loop_state(1)["zeta_hat"], doc="robust term estimate zeta_hat"),
    Field("norm_W_hat", 1, "-", "Frobenius norm of the network weights W_hat"),
    PAPER_OUTPUTS["lyapunov_V1"],
    QUAD_STATE["z1"],
    QUAD_STATE["eta1"],
    *POSITION1.fields,
    *VEHICLE_STATE.fields,
    *BODY_DISTURBANCE.fields,
), "one row per output time of a simulation")

#: Columns of trajectory.csv: (name, unit).
COLUMNS = tuple(zip(TRAJECTORY.element_names(), TRAJECTORY.element_units(), strict=True))


@dataclasses.dataclass(frozen=True)
class SimulationResult(Mapping):
    """The outputs of one simulation, each a NumPy array by name.

    ``result["t"]``, ``result["z_e"]``, ... (the entries of ``TRAJECTORY``);
    ``states`` is the closed-loop state at each row, ``(len(t), nx)``.
    ``layout`` names the columns of ``trajectory.csv``: ``TRAJECTORY`` for
    the paper's loop, ``quadland.landing.LANDING_TRAJECTORY`` for the
    landing loop, whose result holds more signals than its CSV.
    """

    scenario: Scenario
    columns: Mapping[str, np.ndarray]
    states: np.ndarray
    layout: Layout = TRAJECTORY

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
        names = self.layout.element_names()
        writer.writerow(names)
        data = np.column_stack([self.columns[n] for n in names])
        for row in data:
            writer.writerow([f"{v:.12g}" for v in row])
        text = buf.getvalue()
        if path is not None:
            from quadland.output import write_text_atomic
            write_text_atomic(path, text)
        return text


def columns_sidecar(layout: Layout = TRAJECTORY) -> dict:
    """``columns.json``: each CSV column's unit and meaning, in column order.

    ``layout`` is the result's (``SimulationResult.layout``).
    """
    return {"columns": [dict(name=n, unit=u, doc=d) for n, u, d in
                        zip(layout.element_names(), layout.element_units(),
                            layout.element_docs(), strict=True)]}


def run_clocks(scenario: Scenario) -> tuple[Clock, ...]:
    """The clocks of a run: output rows and disturbance samples (both closing: they also
    tick at the final time), then, for a sampled loop, the control steps (not closing)."""
    sim, dist = scenario.data["simulation"], scenario.data["disturbance"]
    T = sim["duration"]
    clocks = [Clock(sim["output_rate_hz"], 0.0, T, True),
              Clock(dist["sample_rate_hz"], 0.0, T, True)]
    if scenario.data["controller"]["rate_hz"] > 0:
        clocks.append(Clock(scenario.data["controller"]["rate_hz"], 0.0, T, False))
    return tuple(clocks)


def time_grid(scenario: Scenario) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output times, disturbance sample times and their merged grid.

    Returns ``(t_out, t_dist, t_all)``; the disturbance is held over each
    interval of ``t_all`` (:mod:`quadland.engine.loop`'s rule). ``t_dist``
    ends with the final time, whose sample is only reported, never integrated.
    """
    out, dist = run_clocks(scenario)[:2]
    return out.times(), dist.times(), merged_grid([out, dist])[0]


@functools.lru_cache(maxsize=1)     # keyed by the whole grid: keep only the last one
def _continuous_integrator(l: int, plugin: str, opts: tuple, grid: tuple):
    f = closed_loop_function(l)
    x, w, p = (ca.SX.sym(f.name_in(i), f.size1_in(i)) for i in range(3))
    dae = {"x": x, "u": w, "p": p, "ode": f(x, w, p)}
    return ca.integrator("closed_loop_sim", plugin, dae, grid[0], list(grid[1:]), dict(opts))


def _cvodes_options(scenario: Scenario) -> tuple:
    """cvodes runs Adams with functional iteration: the loop is not stiff, and the
    disturbance restarts the solver every hold interval, which makes a BDF
    method's Jacobian factorizations the dominant cost."""
    sim = scenario.data["simulation"]
    opts = {"abstol": sim["abstol"], "reltol": sim["reltol"], "max_num_steps": 100000,
            "linear_multistep_method": "adams", "nonlinear_solver_iteration": "functional",
            "disable_internal_warnings": True}      # one line on failure, not a flood
    return tuple(sorted(opts.items()))


def paper_envelope(scenario: Scenario, mv=None) -> Envelope:
    """The paper loop's flight envelope: ``ENVELOPE_FACTOR`` times each initial scale.

    Scales (each at least 1 in its unit): altitude, the largest of the initial
    relative altitude and the reference; speed, the initial body velocity;
    rate, the initial body rates and the vehicle's yaw rate (initial, or
    ``tau_z / d33`` at its steady state). The network's weights then follow
    from the leakage of eq. (22): ``W' = Gamma1 (Psi z2^T - k_w W)`` with
    ``|Psi| <= 1`` keeps ``|W| <= |z2| / k_w`` (likewise ``zeta_hat`` with
    ``k_zeta``), and ``|z2| <= |e2| + k1 |z1|`` inside the envelope. The
    sampled step's held wrench is bounded by twice what its clipped rotors
    produce.
    """
    mv = mv or model_values(scenario)
    d = scenario.data
    q, v, init, c = d["quadrotor"], d["vehicle"], d["initial"], d["controller"]
    z2 = v["deck_altitude"]
    L0 = max(1.0, abs(init["z1"] - z2), abs(d["reference"]["e1d"][0]))
    V0 = max(1.0, *np.abs(init["velocity1"]))
    yaw_rate = abs(init["r2_deg_s"]) * np.pi / 180
    if v["d33"] > 0:
        yaw_rate = max(yaw_rate, abs(v["tau"][2]) / v["d33"])
    W0 = max(1.0, *np.abs(np.radians(init["omega1_deg_s"])), yaw_rate)
    k = ENVELOPE_FACTOR
    altitude, speed, rate = abs(z2) + k * L0, k * V0, k * W0
    angle = k * max(np.pi, *np.abs(np.radians(init["eta1_deg"])))
    z2_bound = max(speed, rate) + max(c["k1"]) * max(k * L0, angle)
    F = max(abs(q["rotor_force_min"]), abs(q["rotor_force_max"]))
    wrench = 2 * 4 * F * max(1.0, q["arm_length"], q["rotor_drag_factor"])
    bounds = np.array([altitude, speed, rate, wrench, z2_bound / c["k_w"],
                       z2_bound / c["k_zeta"]])
    basis = (f"|deck altitude| + {k:g} x the initial relative altitude or reference, "
             "at least 1 m",
             f"{k:g} x the initial body speed, at least 1 m/s",
             f"{k:g} x the initial body rate or the vehicle's yaw rate, at least 1 rad/s",
             "twice the wrench of four rotors at their force limit",
             "the leakage bound |z2| / k_w of eq. (22), |z2| <= |e2| + k1 |z1| in the envelope",
             "the leakage bound |z2| / k_zeta of eq. (22)")
    return Envelope(PAPER_ENVELOPE, bounds, basis)


def _force_bound(scenario: Scenario, initial: np.ndarray) -> float:
    """Largest rotor force of the continuous loop's outputs, N.

    The continuous law is unclipped (the rotor limits are the sampled step's):
    ``ENVELOPE_FACTOR`` times the largest of the hover thrust, the rotor limits
    and the rotor forces commanded at the start, ``initial``.
    """
    q = scenario.data["quadrotor"]
    return ENVELOPE_FACTOR * max(q["mass"] * q["gravity"], abs(q["rotor_force_min"]),
                                 abs(q["rotor_force_max"]), *np.abs(initial))


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
        When the attitude reaches the thrust map's singularity, the flight
        leaves its envelope (:func:`paper_envelope`) or a value stops being
        finite; it carries the trajectory up to then.

    Notes
    -----
    A landing scenario (``scenario.model = "landing"``) runs the landing
    loop instead: :func:`quadland.landing.simulate_landing`.

    Examples
    --------
    >>> import quadland
    >>> sc = quadland.load_scenario("paper", ["simulation.duration=0.5"])
    >>> res = quadland.simulate(sc)
    >>> float(res["t"][-1]), len(res["t"])
    (0.5, 51)
    """
    if scenario.model == "landing":
        from quadland.landing import simulate_landing

        return simulate_landing(scenario)
    check_plan(scenario)
    mv = model_values(scenario)
    envelope = paper_envelope(scenario, mv)
    w_dist = disturbance_samples(scenario, run_clocks(scenario)[1].times())
    if scenario.data["controller"]["rate_hz"] > 0:
        flight = scenario.data["controller"]["backend"] == "c"
        loop = compiled_loop(mv.l, "sampled_flight" if flight else "sampled")
        run, failure = _sampled_run(loop, scenario, mv, w_dist, envelope)
    else:
        loop = compiled_loop(mv.l, "continuous")
        if scenario.data["simulation"]["integrator"] == "rk":
            run, failure = _continuous_run(loop, scenario, mv, w_dist, envelope)
        else:
            run, failure = _continuous_cvodes(scenario, mv, w_dist, envelope)
    X, t_out, w_out = run.X, run.times, w_dist[:, run.w_index].T
    n = len(X)
    Y = loop.outputs(X, w_out, t_out, mv.p)
    finite = np.all(np.isfinite(Y), axis=1)
    if not finite.all():
        bad = int(np.argmin(finite))
        name = PAPER_OUTPUTS.element_names()[int(np.argmin(np.isfinite(Y[bad])))]
        n, failure = bad, (t_out[bad], f"the output {name} became non-finite")
    rotors = np.abs(Y[:n, PAPER_OUTPUTS.slice("rotor")]).max(axis=1) if n else np.zeros(0)
    bound = _force_bound(scenario, Y[0, PAPER_OUTPUTS.slice("rotor")]) if n else np.inf
    if run.R is None and np.any(rotors > bound):
        bad = int(np.argmax(rotors > bound))
        n, failure = bad, (t_out[bad], (
            f"a rotor force reached {rotors[bad]:.3g} N, beyond its envelope of {bound:.3g} N "
            f"({ENVELOPE_FACTOR:g} x the hover thrust, the rotor limit or the initial command)"))
    result = _result(scenario, mv, t_out[:n], w_out[:n], X[:n], Y[:n],
                     None if run.R is None else run.R[:n].T)
    tilt = np.cos(result["phi1"]) * np.cos(result["theta1"])
    if np.any(np.abs(tilt) < TILT_MIN):
        k = int(np.argmax(np.abs(tilt) < TILT_MIN))
        failure = (t_out[k], f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}")
        result = _truncated(result, k)
    if failure is not None:
        t_fail, what = failure
        last = X[len(result["t"]) - 1] if len(result["t"]) else None
        raise SimulationError(f"flight failed at t = {t_fail:.4g} s: {what}"
                              f"{_divergence_hint(scenario, mv, last)}", t_fail,
                              result if len(result["t"]) else None)
    return result


def _truncated(result: SimulationResult, n: int) -> SimulationResult:
    return SimulationResult(result.scenario, {k: v[:n] for k, v in result.columns.items()},
                            result.states[:n])


def slow_control_hint(scenario: Scenario, gains: list[float]) -> str | None:
    """A hint when the control period is likely too long for the gains, else None.

    A sampled loop whose gain times period exceeds :data:`_SLOW_CONTROL` is
    likely unstable for that reason (the paper's loop needs 40 Hz for gains
    of 10 1/s: docs/margins.md).
    """
    rate = scenario.data["controller"]["rate_hz"]
    if gains and rate > 0 and max(gains) / rate > _SLOW_CONTROL:
        need = int(np.ceil(max(gains) / _SLOW_CONTROL))
        return (f" (the control period 1/{rate:g} s is likely too long for gains up to "
                f"{max(gains):g} 1/s: try controller.rate_hz={need} or more)")
    return None


def _divergence_hint(scenario: Scenario, mv=None, x_last=None) -> str:
    """Why the paper loop likely diverged: the fixed RK4 step, the control rate, or the loop.

    For the continuous loop on RK4, the closed loop's eigenvalues at the
    initial state and at the last state recorded are checked against RK4's
    stability region (:func:`quadland.envelope.rk4_steps_needed`): where a
    mode lies outside it, the step is the likely cause.
    """
    sim, ctrl = scenario.data["simulation"], scenario.data["controller"]
    slow = slow_control_hint(scenario, [max(ctrl["k1"]), max(ctrl["k2"])])
    if slow:
        return slow
    if ctrl["rate_hz"] > 0 or sim["integrator"] != "rk":
        return LOOP_DIVERGED
    mv = mv or model_values(scenario)
    h = longest_rk4_step(scenario)
    jac = closed_loop_jacobian_function(mv.l)
    lam = []
    for x in (mv.x0, x_last):
        if x is not None and np.all(np.isfinite(x)):
            A = np.asarray(jac(x, np.zeros(BODY_DISTURBANCE.size), mv.p), dtype=float)
            if np.all(np.isfinite(A)):
                lam.append(np.linalg.eigvals(A))
    lam = np.concatenate(lam) if lam else np.zeros(0)
    return rk4_hint(lam, h, sim["rk_steps_per_interval"], cvodes=True) or LOOP_DIVERGED


#: The hint where neither the step nor the control rate is the likely cause.
LOOP_DIVERGED = (" (the loop itself left its envelope: check the gains, the disturbance, the "
                  "vehicle's drive and the initial state)")


def rk4_hint(eigenvalues, h: float, steps: int, cvodes: bool = False) -> str | None:
    """A hint naming ``simulation.rk_steps_per_interval`` where a mode of ``eigenvalues`` is
    outside RK4's stability region for the step ``h``, else None."""
    lam = np.asarray(eigenvalues, dtype=complex)
    need = rk4_steps_needed(lam, h, steps)
    if need is None:
        return None
    fastest = lam[np.argmax(np.abs(lam))]
    alternative = " or simulation.integrator=\"cvodes\"" if cvodes else ""
    return (f" (the RK4 step h = {h:.3g} s is outside RK4's stability region for the loop's "
            f"fastest mode, {fastest.real:.3g}{fastest.imag:+.3g}j 1/s: try "
            f"simulation.rk_steps_per_interval={need}{alternative})")


def longest_rk4_step(scenario: Scenario) -> float:
    """The longest RK4 step of the run: the shortest clock period over the substeps."""
    sim, ctrl = scenario.data["simulation"], scenario.data["controller"]
    clocks = [sim["output_rate_hz"], scenario.data["disturbance"]["sample_rate_hz"]]
    if ctrl["rate_hz"] > 0:
        clocks.append(ctrl["rate_hz"])
    return 1.0 / max(clocks) / sim["rk_steps_per_interval"]


def _continuous_run(loop, scenario, mv, w_dist, envelope):
    """The continuous loop in one call of ``loop`` (compiled or on the VM): one RK4
    step (times ``rk_steps_per_interval``) per interval of the merged grid, exactly."""
    run = loop.integrate(mv.x0, run_clocks(scenario), w_dist.T,
                         scenario.data["simulation"]["rk_steps_per_interval"], mv.p,
                         envelope.bounds)
    return run, _failure_text(run, envelope)


def _failure_text(run, envelope) -> tuple[float, str] | None:
    """``(time, what)`` of a run that stopped early, or None."""
    if run.status == SIM_OK:
        return None
    what = {SIM_GUARD: f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}",
            SIM_CONTROLLER: "the flight control step (controller.backend = \"c\") returned "
                            "an error status",
            SIM_ENVELOPE: "" if run.envelope is None else envelope.describe(run.envelope),
            }.get(run.status, "the state became non-finite")
    return run.t_stop, what


def _sampled_run(loop, scenario, mv, w_dist, envelope):
    """The sampled-data loop in one call of ``loop`` (compiled or on the VM).

    The control step runs at ``rate_hz`` and its wrench is held on the plant
    until the next; the step's hold compensation is off on the first sample,
    which has no previous command, and on from the second.
    """
    rate = scenario.data["controller"]["rate_hz"]
    model = loop.model
    x0 = closed_loop_state(mv.l).unpack(mv.x0)
    xp0 = model.plant_state.pack({n: x0[n] for n in model.plant_state.names()})
    xc0 = model.controller_state.pack(dict(W_hat=x0["W_hat"], zeta_hat=x0["zeta_hat"],
                                           u_prev=np.zeros(4)))
    pp = model.plant_params.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh))
    pc = model.controller_params.pack(dict(
        p_quad=mv.p_quad, p_veh=mv.p_veh, p_ctrl=mv.p_ctrl, ref=mv.ref,
        rotor_limits=mv.rotor_limits, hold=mv.hold, dt=1.0 / rate))
    run = loop.sampled(xp0, xc0, run_clocks(scenario), w_dist.T,
                       scenario.data["simulation"]["rk_steps_per_interval"], pp, pc, TILT_MIN,
                       envelope.bounds)
    return run, _failure_text(run, envelope)


def _continuous_cvodes(scenario, mv, w_dist, envelope):
    """The continuous loop on CasADi's cvodes (the variable-step reference).

    The envelope is checked on the rows afterwards (cvodes integrates the whole
    grid in one call): the result ends before the first row outside it.
    """
    plugin = "cvodes"
    clocks = run_clocks(scenario)
    t_all, (out, dist) = merged_grid(clocks)
    integ = _continuous_integrator(mv.l, plugin, _cvodes_options(scenario), tuple(t_all))
    w = w_dist[:, np.maximum.accumulate(np.where(dist >= 0, dist, 0))[:-1]]
    try:
        sol = integ(x0=mv.x0, u=w, p=mv.p)
    except RuntimeError as exc:
        code = re.search(r'returned "(\w+)"', str(exc))
        raise SimulationError(f"integrator {plugin} failed: "
                              f"{code.group(1) if code else str(exc).splitlines()[-1]}"
                              f"{_divergence_hint(scenario)}") from None
    X = np.hstack([mv.x0[:, None], np.asarray(sol["xf"])])
    keep = np.flatnonzero(out >= 0)
    X = np.ascontiguousarray(X[:, keep].T)
    w_index = np.maximum.accumulate(np.where(dist >= 0, dist, 0))[keep]
    times = clocks[0].times()
    env = paper_envelope_function(mv.l).map(len(X))(X.T, np.zeros((WRENCH.size, len(X))))
    S = np.asarray(env, dtype=float).T
    outside = ~np.all(S <= envelope.bounds, axis=1)
    n = int(np.argmax(outside)) if outside.any() else len(X)
    status = SIM_ENVELOPE if outside.any() else SIM_OK
    run = Run(status, X[:n], None, times[:n], w_index[:n], X[n - 1] if n else mv.x0,
              times[n] if outside.any() else np.nan, S[n] if outside.any() else None)
    return run, _failure_text(run, envelope)


def _result(scenario, mv, t_out, w_out, X, Y, held):
    """Columns of ``TRAJECTORY`` from states ``X`` (n, nx) and outputs ``Y`` (n, ny)."""
    lay = closed_loop_state(mv.l)
    xs = lay.unpack(X.T)
    sig = PAPER_OUTPUTS.unpack(Y.T)
    if held is not None:
        so = step_outputs(mv.l)
        for name in ("u", "wrench", "rotor"):
            sig[name] = held[so.slice(name)]
    data = dict(sig, t=t_out[None, :], zeta_hat=xs["zeta_hat"],
                norm_W_hat=np.sqrt(np.einsum("ij,ij->i", X[:, lay.slice("W_hat")],
                                             X[:, lay.slice("W_hat")]))[None, :],
                **QUAD_STATE.unpack(xs["xq"]), **POSITION1.unpack(xs["pos1"]),
                **VEHICLE_STATE.unpack(xs["xv"]), **BODY_DISTURBANCE.unpack(w_out.T))
    cols = {}
    for f in TRAJECTORY.fields:
        rows = np.asarray(data[f.name], dtype=float).reshape(f.size, -1)
        cols.update(zip(f.element_names(), rows, strict=True))
    return SimulationResult(scenario, {k: np.ascontiguousarray(v, dtype=float)
                                       for k, v in cols.items()}, X)

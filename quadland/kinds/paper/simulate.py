"""The paper's 4-DOF loop flown: continuous (RK4 or cvodes) or sampled-data.

Both loops of ``quadland_symbolic.paper_loop`` run in one call of a simulator
(:mod:`quadland.engine.compiled`): RK4, one step (times
``simulation.rk_steps_per_interval``) per interval of the exact grid on which
the disturbance, the outputs and the control are held:

* continuous (``controller.rate_hz = 0``, the paper's): the whole closed
  loop of ``quadland_symbolic.closed_loop`` is one ODE; ``simulation.integrator =
  "cvodes"`` integrates it with CasADi's cvodes instead (the reference);
* sampled-data (``rate_hz > 0``): the control step (``controller.backend``:
  the CasADi function or the flight code's ``ql_control_step``) runs at that
  rate and its wrench is held on the plant.

A flight that fails (its envelope, :func:`paper_envelope`; the singular
tilt; a non-finite value) raises :class:`SimulationError` carrying the
trajectory up to the failure.
"""

from __future__ import annotations

import dataclasses
import functools
import re

import casadi as ca
import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.compiled import (
    SIM_CONTROLLER,
    SIM_ENVELOPE,
    SIM_GUARD,
    SIM_OK,
    Run,
)
from quadland.engine.disturbance import disturbance_samples
from quadland.engine.envelope import (
    ENVELOPE_FACTOR,
    LOOP_DIVERGED,
    MAX_RK_STEPS,
    Envelope,
    fewest_stable_steps,
    likely_cause,
    longest_rk4_step,
    loop_modes,
    rk4_steps_needed,
)
from quadland.engine.loop import Clock, merged_grid
from quadland.engine.plan import SimulationPlan, check_plan, plan_run
from quadland.engine.result import SimulationResult
from quadland.exceptions import SimulationError
from quadland.kinds.paper.values import model_values
from quadland.scenario import Scenario
from quadland_symbolic.closed_loop import (
    PAPER_ENVELOPE,
    PAPER_OUTPUTS,
    POSITION1,
    closed_loop_function,
    closed_loop_state,
    paper_envelope_function,
)
from quadland_symbolic.control_step import step_outputs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.paper_loop import paper_loop, paper_loop_recipe
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, QUAD_STATE, WRENCH
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["TRAJECTORY", "COLUMNS", "run_clocks", "time_grid", "paper_envelope", "paper_plan",
           "check_paper_plan", "simulate_paper", "paper_loop_part"]


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
    relative altitude and the reference; speed, the initial body velocity or
    what the law commands for that offset, ``k1_z`` times it; rate, the
    initial body rates, the vehicle's yaw rate (initial, or ``tau_z / d33`` at
    its steady state) or what the law commands for the initial attitude
    offset, ``k1`` times it. The network's weights then follow from the
    leakage of eq. (22): ``W' = Gamma1 (Psi z2^T - k_w W)`` with ``|Psi| <= 1``
    keeps ``|W| <= |z2| / k_w`` (likewise ``zeta_hat`` with ``k_zeta``), and
    ``|z2| <= |e2| + k1 |z1|`` inside the envelope. The sampled step's held
    wrench is bounded by twice what its clipped rotors produce. The tilt may
    not pass 90 degrees, where the thrust map of eq. (6) is singular; the
    vehicle's speed is bounded by its initial speed or its steady speed under
    its drive, ``|tau| / d``.
    """
    mv = mv or model_values(scenario)
    d = scenario.data
    q, v, init, c = d["quadrotor"], d["vehicle"], d["initial"], d["controller"]
    e1d = d["reference"]["e1d"]
    z2 = v["deck_altitude"]
    L0 = max(1.0, abs(init["z1"] - z2), abs(e1d[0]))
    V0 = max(1.0, *np.abs(init["velocity1"]), c["k1"][0] * L0)
    yaw_rate = abs(init["r2_deg_s"]) * np.pi / 180
    if v["d33"] > 0:
        yaw_rate = max(yaw_rate, abs(v["tau"][2]) / v["d33"])
    offset = max(*np.abs(np.radians(init["eta1_deg"])), abs(np.radians(init["psi2_deg"])),
                 *np.abs(e1d[1:]))
    W0 = max(1.0, *np.abs(np.radians(init["omega1_deg_s"])), yaw_rate,
             max(c["k1"][1:]) * offset)
    steady = [abs(tau) / damping for tau, damping in ((v["tau"][0], v["d11"]),
                                                       (v["tau"][1], v["d22"])) if damping > 0]
    U0 = max(1.0, *np.abs(init["velocity2"]), *steady)
    k = ENVELOPE_FACTOR
    altitude, speed, rate = abs(z2) + k * L0, k * V0, k * W0
    angle = k * max(np.pi, offset)
    z2_bound = max(speed, rate) + max(c["k1"]) * max(k * L0, angle)
    F = max(abs(q["rotor_force_min"]), abs(q["rotor_force_max"]))
    wrench = 2 * 4 * F * max(1.0, q["arm_length"], q["rotor_drag_factor"])
    bounds = np.array([altitude, speed, rate, wrench, z2_bound / c["k_w"],
                       z2_bound / c["k_zeta"], np.pi / 2, k * U0])
    basis = (f"|deck altitude| + {k:g} x the initial relative altitude or reference, "
             "at least 1 m",
             f"{k:g} x the initial body speed or k1_z x the altitude offset, at least 1 m/s",
             f"{k:g} x the initial body rate, the vehicle's yaw rate or k1 x the attitude "
             "offset, at least 1 rad/s",
             "twice the wrench of four rotors at their force limit",
             "the leakage bound |z2| / k_w of eq. (22), |z2| <= |e2| + k1 |z1| in the envelope",
             "the leakage bound |z2| / k_zeta of eq. (22)",
             "90 degrees: the thrust map of eq. (6) is singular at cos(phi) cos(theta) = 0",
             f"{k:g} x the vehicle's initial speed or its steady speed |tau| / d, "
             "at least 1 m/s")
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


def paper_plan(scenario: Scenario) -> SimulationPlan:
    """A paper run's size, estimated from its scenario alone (no allocation).

    Examples
    --------
    >>> import quadland
    >>> plan = paper_plan(quadland.load_scenario("paper"))
    >>> plan.rows, plan.rk4_steps <= 2004, plan.memory_bytes < 2**23
    (1001, True, True)
    """
    nx = closed_loop_state(scenario.data["rbf"]["nodes"]).size
    cvodes = 2 * nx if scenario.data["simulation"]["integrator"] == "cvodes" else 0
    return plan_run(scenario, nx, BODY_DISTURBANCE.size,
                    2 * nx + PAPER_OUTPUTS.size + len(COLUMNS), cvodes)


def check_paper_plan(scenario: Scenario) -> None:
    """Refuse, in one line naming the keys, a paper run over the budgets."""
    check_plan(paper_plan(scenario))


#: Optimization level of the paper's continuous simulator. CasADi's straight-line C
#: of its right-hand side and outputs compiles at -Os in 60 % of -O2's CPU time (2.9
#: against 4.5 s at l = 100) and flies as fast (53.5 against 56.5 ms for the 60 s run),
#: bit for bit: neither level reorders floating-point operations.
CONTINUOUS_OPT = "-Os"


def paper_loop_part(l: int, part: str):
    """The compiled (or VM) ``part`` of the paper loop's simulator for ``l`` nodes: the
    loop's CasADi functions are built only if the simulator is not in the cache
    (:func:`quadland_symbolic.paper_loop.paper_loop_recipe`)."""
    from quadland.engine.compiled import compiled_loop

    flight = None
    if part == "sampled_flight":                 # (the flight code's module only for it)
        from quadland.kinds.paper.flight import flight_code

        flight = flight_code(l)
    return compiled_loop(paper_loop_recipe(l), part, flight,
                         CONTINUOUS_OPT if part == "continuous" else "-O2")


def simulate_paper(scenario: Scenario) -> SimulationResult:
    """Simulate a paper scenario's closed loop.

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

    Examples
    --------
    >>> import quadland
    >>> sc = quadland.load_scenario("paper", ["simulation.duration=0.5"])
    >>> res = simulate_paper(sc)
    >>> float(res["t"][-1]), len(res["t"])
    (0.5, 51)
    """
    check_paper_plan(scenario)
    mv = model_values(scenario)
    envelope = paper_envelope(scenario, mv)
    w_dist = disturbance_samples(scenario, run_clocks(scenario)[1].times())
    if scenario.data["controller"]["rate_hz"] > 0:
        flight = scenario.data["controller"]["backend"] == "c"
        loop = paper_loop_part(mv.l, "sampled_flight" if flight else "sampled")
        run, failure = _sampled_run(loop, scenario, mv, w_dist, envelope)
    else:
        loop = paper_loop_part(mv.l, "continuous")
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
        result = result.truncated(k)
    if failure is not None:
        t_fail, what = failure
        last = X[len(result["t"]) - 1] if len(result["t"]) else None
        hint = _cvodes_hint(scenario, mv, last) if what.startswith("the integrator cvodes") \
            else _divergence_hint(scenario, mv, last)
        raise SimulationError(f"flight failed at t = {t_fail:.4g} s: {what}{hint}", t_fail,
                              result if len(result["t"]) else None)
    return result


def _modes(scenario: Scenario, mv, x) -> np.ndarray:
    """Eigenvalues the RK4 step integrates at the loop state ``x``: the whole closed
    loop's (continuous), or the plant's with its command held (sampled)."""
    if x is None:
        return np.zeros(0, dtype=complex)
    loop = paper_loop(mv.l)
    if scenario.data["controller"]["rate_hz"] == 0:
        return loop_modes(loop.rhs, x, np.zeros(BODY_DISTURBANCE.size), 0.0, mv.p)
    xs = closed_loop_state(mv.l).unpack(x)
    xp = loop.plant_state.pack({n: xs[n] for n in loop.plant_state.names()})
    pp = loop.plant_params.pack(dict(p_quad=mv.p_quad, p_veh=mv.p_veh))
    return loop_modes(loop.plant, xp, np.zeros(loop.held.size), np.zeros(BODY_DISTURBANCE.size),
                      0.0, pp)


def _divergence_hint(scenario: Scenario, mv=None, x_last=None) -> str:
    """Why the paper loop likely diverged: the fixed RK4 step, the control rate, or the loop.

    The modes RK4 integrates (the closed loop's, or in a sampled loop the
    plant's) at the initial state and at the last state recorded are checked
    against RK4's stability region
    (:func:`quadland.engine.envelope.likely_cause`).
    """
    mv = mv or model_values(scenario)
    ctrl = scenario.data["controller"]
    return likely_cause(scenario, _modes(scenario, mv, mv.x0), _modes(scenario, mv, x_last),
                        [max(ctrl["k1"]), max(ctrl["k2"])])


def _cvodes_hint(scenario: Scenario, mv, x_last) -> str:
    """Why cvodes stopped: its Adams method, iterated without a Jacobian, needs steps
    far below the interval on fast stable modes; a fixed RK4 step that holds them
    is named where one exists (:func:`quadland.engine.envelope.rk4_steps_needed`)."""
    lam = np.concatenate([_modes(scenario, mv, mv.x0), _modes(scenario, mv, x_last)])
    stable = lam[np.isfinite(lam) & (lam.real <= 0)]
    steps = scenario.data["simulation"]["rk_steps_per_interval"]
    h = longest_rk4_step(scenario)
    need = rk4_steps_needed(stable, h, steps)
    if stable.size == 0 or fewest_stable_steps(stable, h * steps) > MAX_RK_STEPS:
        return LOOP_DIVERGED
    need = None if need is None else min(need, MAX_RK_STEPS)
    mode = stable[np.argmax(np.abs(stable))]
    fix = 'simulation.integrator="rk"' + (
        "" if need is None else f" with simulation.rk_steps_per_interval={int(need)}")
    return (f" (cvodes' Adams method needs tiny steps on the loop's fast mode "
            f"{mode.real:.3g}{mode.imag:+.3g}j 1/s: try {fix})")


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
    grid in one call): the result ends before the first row outside it. Where
    cvodes fails, the grid is integrated again one interval per call up to the
    interval that fails, so that the rows before it are kept.
    """
    clocks = run_clocks(scenario)
    t_all, (out, dist) = merged_grid(clocks)
    opts = _cvodes_options(scenario)
    w = w_dist[:, np.maximum.accumulate(np.where(dist >= 0, dist, 0))[:-1]]
    failed = None
    try:
        sol = _continuous_integrator(mv.l, "cvodes", opts, tuple(t_all))(x0=mv.x0, u=w, p=mv.p)
        X = np.hstack([mv.x0[:, None], np.asarray(sol["xf"])])
    except RuntimeError as exc:
        X, failed = _cvodes_by_interval(mv, opts, t_all, w)
        code = re.search(r'returned "(\w+)"', str(exc))
        failed = (t_all[failed], "the integrator cvodes failed: "
                  f"{code.group(1) if code else str(exc).splitlines()[-1]}")
    keep = np.flatnonzero(out[:X.shape[1]] >= 0)
    X = np.ascontiguousarray(X[:, keep].T)
    w_index = np.maximum.accumulate(np.where(dist >= 0, dist, 0))[keep]
    times = clocks[0].times()[:len(keep)]
    env = paper_envelope_function(mv.l).map(len(X))(X.T, np.zeros((WRENCH.size, len(X))))
    S = np.asarray(env, dtype=float).T.reshape(len(X), -1)
    outside = ~np.all(S <= envelope.bounds, axis=1)
    n = int(np.argmax(outside)) if outside.any() else len(X)
    status = SIM_ENVELOPE if outside.any() else SIM_OK
    run = Run(status, X[:n], None, times[:n], w_index[:n], X[n - 1] if n else mv.x0,
              times[n] if outside.any() else np.nan, S[n] if outside.any() else None)
    return run, _failure_text(run, envelope) or failed


def _cvodes_by_interval(mv, opts, t_all, w) -> tuple[np.ndarray, int]:
    """States on ``t_all`` from cvodes restarted at every grid point (as the one call
    restarts at each held sample), up to the first interval it fails on: ``(X, k)``
    with ``X`` (nx, k + 1) and ``k`` that interval's index."""
    f = closed_loop_function(mv.l)
    x, u, p = (ca.SX.sym(f.name_in(i), f.size1_in(i)) for i in range(3))
    dae = {"x": x, "u": u, "p": p, "ode": f(x, u, p)}
    steps, xs = {}, [np.asarray(mv.x0, dtype=float)]
    for k in range(len(t_all) - 1):
        dt = float(t_all[k + 1] - t_all[k])
        if dt not in steps:
            steps[dt] = ca.integrator("closed_loop_step", "cvodes", dae, 0.0, dt, dict(opts))
        try:
            xs.append(np.asarray(steps[dt](x0=xs[-1], u=w[:, k], p=mv.p)["xf"]).ravel())
        except RuntimeError:
            return np.column_stack(xs), k
    return np.column_stack(xs), len(t_all) - 1


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
                                       for k, v in cols.items()}, X, TRAJECTORY, lay)

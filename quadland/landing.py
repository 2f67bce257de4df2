"""Landing scenarios: their vectors, wind, the simulation and the ride on the deck.

A landing scenario (``scenario.model = "landing"``, schema
``quadland.scenario.LANDING_SCHEMA``) flies the landing loop of
``quadland_symbolic.landing.loop`` in one call of its compiled simulator (on CasADi's
virtual machine without a C compiler): the guidance and the landing step at
``controller.rate_hz`` (CasADi's functions, or with ``controller.backend =
"c"`` the generated flight code of ``quadland_landing.h``), their rotor
commands held on the 6-DOF plant, RK4 on
the exact grid of the output, disturbance and control times, and the
touchdown (the gear gap's zero crossing) located within its step, where the
integration ends. From then on the quadrotor rides on the deck, pinned at its
touchdown pose with its rotors idle: the rows up to ``landing.settle_time``
after touchdown (or the duration) are computed from the vehicle's motion and
the deck's, phase 3 (touchdown), then 4 (landed) at the end of the settling.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from quadland.compiled import (
    SIM_CONTROLLER,
    SIM_ENVELOPE,
    SIM_EVENT,
    SIM_GUARD,
    SIM_OK,
    compiled_loop,
)
from quadland.constants import TILT_MIN
from quadland.engine.loop import Clock, grid_tolerance
from quadland.envelope import ENVELOPE_FACTOR, Envelope
from quadland.exceptions import SimulationError
from quadland.model import disturbance_samples
from quadland.scenario import Scenario, require_model
from quadland.simulate import (
    LOOP_DIVERGED,
    SimulationResult,
    check_plan,
    longest_rk4_step,
    rk4_hint,
    slow_control_hint,
)
from quadland.wind import OneCosineGust, dryden_low_altitude, gust_samples, turbulence_samples
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.contact import anchor_function, landed_outputs_function
from quadland_symbolic.landing.controller import landing_controller_params, landing_memory
from quadland_symbolic.landing.deck import DECK_PARAMS, N_DECK, deck_pose
from quadland_symbolic.landing.guidance import (
    APPROACH,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    LANDED,
    TOUCHDOWN,
)
from quadland_symbolic.landing.loop import (
    LANDING_ENVELOPE,
    LANDING_RECORDED,
    landing_loop_memory,
    landing_loop_params,
    landing_loop_state,
)
from quadland_symbolic.landing.plant import (
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.landing.signals import LANDING_SIGNALS, LANDING_TRAJECTORY
from quadland_symbolic.loop import rk4_step
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_function

__all__ = ["LANDING_TRAJECTORY", "LandingValues", "landing_values", "landing_envelope",
           "landing_clocks",
           "wind_samples", "landing_disturbance", "simulate_landing"]

#: The columns of a landing run's trajectory.csv (docs/landing.md), from the loop's layouts.
LANDING_TRAJECTORY = LANDING_TRAJECTORY


@dataclasses.dataclass(frozen=True)
class LandingValues:
    """A landing scenario as the landing loop's vectors.

    Attributes
    ----------
    l : int
        RBF node count.
    pp : ndarray
        Plant parameters (``quadland_symbolic.landing.plant.LANDING_PLANT_PARAMS``).
    pc : ndarray
        Controller parameters (``quadland_symbolic.landing.loop.landing_loop_params(l)``).
    xp0, xc0 : ndarray
        Initial plant state and controller memory.
    F_max : float
        Largest rotor force, N.
    """

    l: int
    pp: np.ndarray
    pc: np.ndarray
    xp0: np.ndarray
    xc0: np.ndarray
    F_max: float


def _padded(values, scale: float = 1.0) -> np.ndarray:
    out = np.zeros(N_DECK)
    out[:len(values)] = np.multiply(values, scale)
    return out


def landing_values(scenario: Scenario) -> LandingValues:
    """Translate a validated landing scenario into the landing loop's vectors.

    The quadrotor starts with its rotors at hover thrust, ``m1 g / 4`` each,
    and its velocity ``initial.relative_velocity`` plus the pad's; the
    command filter starts at its initial roll and pitch, the guidance in the
    approach with the reference at the hover point.
    """
    require_model(scenario, "landing", "the landing loop")
    d = scenario.data
    q, v, dk, c, r, g = (d[k] for k in ("quadrotor", "vehicle", "deck", "controller", "rbf",
                                        "landing"))
    l, deg = r["nodes"], np.pi / 180
    p_quad = QUADROTOR.pack(dict(
        m1=q["mass"], I=q["inertia"], Kt=q["drag_translational"], Kr=q["drag_rotational"],
        g=q["gravity"], arm=q["arm_length"], c=q["rotor_drag_factor"]))
    F_max = q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4
    p_act = ACTUATOR.pack(dict(motor_time_constant=q["motor_time_constant"], F_max=F_max,
                               gear_height=q["gear_height"]))
    p_veh = VEHICLE.pack(dict(m11=v["m11"], m22=v["m22"], m33=v["m33"], d11=v["d11"],
                              d22=v["d22"], d33=v["d33"], tau=v["tau"], z2=0.0))
    deck = {}
    for name, scale in (("heave", 1.0), ("roll", deg), ("pitch", deg)):
        amp = dk[f"{name}_amplitude" + ("_deg" if name != "heave" else "")]
        deck[f"{name}_amp"] = _padded(amp, scale)
        deck[f"{name}_freq"] = _padded(dk[f"{name}_frequency"])
        deck[f"{name}_phase"] = _padded(dk[f"{name}_phase_deg"], deg)
    p_deck = DECK_PARAMS.pack(dict(deck, pad_offset=dk["pad_offset"], deck_height=dk["height"]))
    pp = LANDING_PLANT_PARAMS.pack(dict(p_quad=p_quad, p_act=p_act, p_veh=p_veh, p_deck=p_deck))

    centers = np.linspace(r["center_min"], r["center_max"], l) if l > 1 else \
        np.array([(r["center_min"] + r["center_max"]) / 2])
    lay = landing_controller_params(l)
    p_ctrl = lay.pack(dict(
        k1p=c["k1p"], k2p=c["k2p"], k1=c["k1"], k2=c["k2"], gamma1=c["gamma1"],
        gamma2=c["gamma2"], k_w=c["k_w"], k_zeta=c["k_zeta"], rho=c["rho"],
        nominal_model=float(c["nominal_model"]), w_f=c["filter_frequency"],
        zeta_f=c["filter_damping"], tilt_max=c["tilt_max_deg"] * deg,
        centers=np.tile(centers, (lay["centers"].shape[0], 1)), widths=np.full(l, r["width"])))
    p_guid = GUIDANCE_PARAMS.pack(dict(
        hover_height=g["hover_height"], align_radius=g["align_radius"],
        dwell_time=g["dwell_time"], descent_speed=g["descent_speed"],
        descent_time=g["descent_time"], touchdown_speed=g["touchdown_speed"],
        touchdown_height=q["gear_height"], max_offset=g["max_offset"],
        max_relative_speed=g["max_relative_speed"], max_deck_rise=g["max_deck_rise"],
        settle_time=g["settle_time"]))
    rate = c["rate_hz"]
    pc = landing_loop_params(l).pack(dict(pp=pp, p_ctrl=p_ctrl, p_guid=p_guid, dt=1.0 / rate))

    init = d["initial"]
    (x2, y2), (u2, v2) = init["position2"], init["velocity2"]
    xv = VEHICLE_STATE.pack(dict(x2=x2, y2=y2, psi2=init["psi2_deg"] * deg, u2=u2, v2=v2,
                                 r2=init["r2_deg_s"] * deg))
    v_pad = np.asarray(deck_pose(xv, 0.0, p_veh, p_deck).v2E, dtype=float).ravel()
    eta1 = np.multiply(init["eta1_deg"], deg)
    V1 = np.asarray(rotation(eta1), dtype=float).T @ (v_pad + np.asarray(
        init["relative_velocity"]))
    x1q = QUAD6_STATE.pack(dict(
        p1=[*init["position1"], init["z1"]], eta1=eta1, V1=V1,
        Omega1=np.multiply(init["omega1_deg_s"], deg),
        F=np.full(4, q["mass"] * q["gravity"] / 4)))
    xp0 = LANDING_PLANT_STATE.pack(dict(x1q=x1q, xv=xv))
    mem = landing_memory(l).zeros()
    mem[landing_memory(l).slice("eta_f")] = eta1[:2]
    xg = GUIDANCE_STATE.pack(dict(phase=APPROACH, timer=0.0, z_ref=g["hover_height"],
                                  aborts=0.0))
    xc0 = landing_loop_memory(l).pack(dict(xg=xg, mem=mem))
    return LandingValues(l, pp, pc, xp0, xc0, F_max)


def landing_envelope(scenario: Scenario) -> Envelope:
    """The landing's flight envelope: ``ENVELOPE_FACTOR`` times each initial scale.

    Scales (each at least 1 in its unit): distance, the largest of the
    initial distance from the pad, the hover height and the pad's offset;
    speed, the initial speed plus the most the vehicle can gain over the run
    (``|tau| T / m``, its drive force alone); rate, the initial body rates.
    A rotor's force lags a command clipped to ``[0, F_max]``, so twice
    ``F_max`` is out of reach; the network's weights follow from the leakage
    of eq. (22) as in :func:`quadland.simulate.paper_envelope`.
    """
    d = scenario.data
    q, v, dk, init, c, g = (d[k] for k in ("quadrotor", "vehicle", "deck", "initial",
                                           "controller", "landing"))
    T = d["simulation"]["duration"]
    offset = float(np.linalg.norm(dk["pad_offset"]))
    start = np.array([*init["position1"], init["z1"]]) - np.array(
        [*init["position2"], dk["height"]])
    L0 = max(1.0, float(np.linalg.norm(start)) + offset, g["hover_height"])
    vehicle = float(np.hypot(*init["velocity2"])) + T * float(np.hypot(*v["tau"][:2])) / min(
        v["m11"], v["m22"])
    V0 = max(1.0, vehicle + float(np.linalg.norm(init["relative_velocity"])))
    W0 = max(1.0, *np.abs(np.radians(init["omega1_deg_s"])))
    k = ENVELOPE_FACTOR
    distance, speed, rate = k * L0 + offset, k * V0, k * W0
    height = abs(dk["height"]) + sum(dk["heave_amplitude"]) + k * L0
    F_max = q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4
    z2_bound = max(speed, rate) + max(*c["k1p"], *c["k1"]) * max(distance, k * np.pi)
    bounds = np.array([distance, height, speed, rate, 2 * F_max, z2_bound / c["k_w"],
                       z2_bound / c["k_zeta"]])
    basis = (f"{k:g} x the initial distance from the pad or the hover height, at least 1 m",
             f"|deck height| + heave + {k:g} x that distance",
             f"{k:g} x the initial speed plus what the vehicle's drive can add over the run, "
             "at least 1 m/s",
             f"{k:g} x the initial body rate, at least 1 rad/s",
             "twice F_max: a rotor lags a command clipped to [0, F_max]",
             "the leakage bound |z2| / k_w of eq. (22), |z2| <= |e2| + k1 |z1| in the envelope",
             "the leakage bound |z2| / k_zeta of eq. (22)")
    return Envelope(LANDING_ENVELOPE, bounds, basis)


def _landing_hint(scenario: Scenario, lv: LandingValues, xp_last) -> str:
    """Why a landing likely diverged: the RK4 step, the control rate, or the loop itself.

    The plant's eigenvalues (its Jacobian with the commands held) at the
    initial state and at the last state recorded are checked against RK4's
    stability region for the run's step: a body spun up to hundreds of
    radians per second leaves it. Else the sampled controller's rate is
    checked against its gains.
    """
    c, sim = scenario.data["controller"], scenario.data["simulation"]
    f = loop_plant_function()
    xp, uh, w, t, pp = (f.mx_in(i) for i in range(5))
    jac = ca.Function("plant_jacobian", [xp, uh, w, t, pp], [ca.jacobian(f(xp, uh, w, t, pp), xp)])
    lam = []
    for x in (lv.xp0, xp_last):
        if x is not None and np.all(np.isfinite(x)):
            A = np.asarray(jac(x, np.zeros(f.size1_in(1)), np.zeros(f.size1_in(2)), 0.0, lv.pp))
            if np.all(np.isfinite(A)):
                lam.append(np.linalg.eigvals(A))
    step = rk4_hint(np.concatenate(lam) if lam else np.zeros(0), longest_rk4_step(scenario),
                    sim["rk_steps_per_interval"])
    return step or slow_control_hint(scenario, [max(c[k]) for k in ("k1p", "k2p", "k1", "k2")]) \
        or LOOP_DIVERGED


def landing_clocks(scenario: Scenario) -> tuple[Clock, Clock, Clock]:
    """The clocks of a landing: output rows, disturbance samples (both closing at the
    final time) and control steps."""
    sim = scenario.data["simulation"]
    T = sim["duration"]
    return (Clock(sim["output_rate_hz"], 0.0, T, True),
            Clock(scenario.data["disturbance"]["sample_rate_hz"], 0.0, T, True),
            Clock(scenario.data["controller"]["rate_hz"], 0.0, T, False))


def wind_samples(scenario: Scenario, times: np.ndarray) -> np.ndarray:
    """Wind velocity in E at ``times`` (the disturbance's sample times), ``(3, n)``, m/s.

    ``wind.mean`` plus Dryden turbulence (MIL-F-8785C low altitude, its
    intensity from ``wind.turbulence_w20``, at the hover point's altitude
    ``deck.height + landing.hover_height``, crossed at the vehicle's initial
    speed through the mean wind) plus a 1-cosine gust. The turbulence's
    draws come from their own generator seeded with ``(simulation.seed, 1)``,
    independent of the disturbance's.
    """
    w, d = scenario.data["wind"], scenario.data
    times = np.asarray(times, dtype=float)
    psi2 = d["initial"]["psi2_deg"] * np.pi / 180
    u2, v2 = d["initial"]["velocity2"]
    ground = np.array([np.cos(psi2) * u2 - np.sin(psi2) * v2,
                       np.sin(psi2) * u2 + np.cos(psi2) * v2, 0.0])
    airspeed = float(np.linalg.norm(ground - np.asarray(w["mean"])))
    height = d["deck"]["height"] + d["landing"]["hover_height"]
    turbulence = dryden_low_altitude(w["turbulence_w20"], height, airspeed)
    rng = np.random.default_rng((d["simulation"]["seed"], 1))
    out = np.asarray(w["mean"], dtype=float)[:, None] + turbulence_samples(turbulence, times, rng)
    if w["gust_amplitude"] > 0:
        gust = OneCosineGust(w["gust_start"], w["gust_half_length"], w["gust_amplitude"],
                             tuple(w["gust_direction"]))
        out = out + gust_samples(gust, times)
    return out


def landing_disturbance(scenario: Scenario, times: np.ndarray) -> np.ndarray:
    """The landing loop's held disturbance at ``times``, ``(9, n)``: wind (E), d_F, d_M (body).

    ``d_F``, ``d_M`` are ``[disturbance]``'s, drawn as for the paper's loop
    (:func:`quadland.model.disturbance_samples`).
    """
    return np.vstack([wind_samples(scenario, times), disturbance_samples(scenario, times)])


def simulate_landing(scenario: Scenario) -> SimulationResult:
    """Fly a landing scenario: approach, align, descend, touchdown, ride on the deck.

    Returns
    -------
    SimulationResult
        Every signal of ``quadland_symbolic.landing.loop.LANDING_SIGNALS`` and ``LANDING_RECORDED``
        by name, at the output times up to touchdown, one row at the
        touchdown instant, then the ride on the deck; its ``layout`` is
        :data:`LANDING_TRAJECTORY` (the CSV's columns) and ``states`` the
        loop's state ``[xp, xc]`` per row.

    Raises
    ------
    SimulationError
        When the attitude reaches the singular tilt or the state stops
        being finite, with the trajectory up to then.
    """
    check_plan(scenario)
    lv = landing_values(scenario)
    envelope = landing_envelope(scenario)
    sim = scenario.data["simulation"]
    clocks = landing_clocks(scenario)
    t_out, t_dist = clocks[0].times(), clocks[1].times()
    w_dist = landing_disturbance(scenario, t_dist)
    flight = scenario.data["controller"]["backend"] == "c"
    loop = compiled_loop(lv.l, "sampled_flight" if flight else "sampled", "landing")
    run = loop.sampled(lv.xp0, lv.xc0, clocks, w_dist.T, sim["rk_steps_per_interval"], lv.pp,
                       lv.pc, TILT_MIN, envelope.bounds)
    done, times, X, R = run.rows, run.times, run.X, run.R
    Y = loop.outputs(X, w_dist[:, run.w_index].T, times, lv.pp)
    what = None
    if run.status == SIM_EVENT:
        t_td = run.t_stop
        x_td = run.x_end
        i_w = int(np.searchsorted(t_dist, t_td - grid_tolerance(clocks), side="right")) - 1
        y_td = loop.outputs(x_td[None, :], w_dist[:, [i_w]].T, np.array([t_td]), lv.pp)
        R_td = R[-1] if len(R) else np.zeros(LANDING_RECORDED.size)
        ride = _ride(scenario, lv, t_out, t_td, x_td, y_td[0], R_td)
        times = np.concatenate([times, [t_td], ride[0]])
        X = np.vstack([X, x_td, ride[1]])
        R = np.vstack([R, R_td, ride[2]])
        Y = np.vstack([Y, y_td, ride[3]])
        Y[done, LANDING_SIGNALS.index("phase")] = TOUCHDOWN
    elif run.status != SIM_OK:
        what = {SIM_GUARD: f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}",
                SIM_CONTROLLER: "the flight code (controller.backend = \"c\") returned an "
                                "error status"}.get(run.status, "the state became non-finite")
        if run.status == SIM_ENVELOPE:
            what = envelope.describe(run.envelope)
        t_fail = run.t_stop
    bad = ~np.all(np.isfinite(Y), axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        name = LANDING_SIGNALS.element_names()[int(np.argmin(np.isfinite(Y[k])))]
        what, t_fail = f"the output {name} became non-finite", times[k]
        times, X, R, Y = times[:k], X[:k], R[:k], Y[:k]
    result = _result(scenario, times, X, R, Y)
    if what is not None:
        xp_last = X[-1, landing_loop_state(lv.l).slice("xp")] if len(X) else None
        raise SimulationError(f"flight failed at t = {t_fail:.4g} s: {what}"
                              f"{_landing_hint(scenario, lv, xp_last)}", t_fail,
                              result if len(times) else None)
    return result


def _ride(scenario, lv, t_out, t_td, x_td, y_td, R_td):
    """Rows after touchdown: the quadrotor pinned to the deck, its rotors winding down.

    The vehicle goes on by eq. (4), integrated by RK4 in steps of at most
    one control period; the quadrotor keeps its touchdown pose in the deck
    frame and its rotor forces decay as ``F_td exp(-(t - t_td) / tau_m)``
    (commands zero, the motors' lag). Returns times, states, recorded
    signals and outputs.
    """
    settle = scenario.data["landing"]["settle_time"]
    T = scenario.data["simulation"]["duration"]
    t_end = min(t_td + settle, T)
    later = t_out[(t_out > t_td + 1e-12) & (t_out < t_end - 1e-12)]
    times = np.append(later, t_end) if t_end > t_td + 1e-12 else later
    n = len(times)
    lay, ys = landing_loop_state(lv.l), LANDING_SIGNALS.unpack(y_td)
    xp_td = lay.unpack(x_td)["xp"]
    s = LANDING_PLANT_STATE.unpack(xp_td)
    anchor = np.asarray(anchor_function()(y_td), dtype=float).ravel()
    F_td = QUAD6_STATE.unpack(s["x1q"])["F"]
    p = LANDING_PLANT_PARAMS.unpack(lv.pp)
    tau_m = ACTUATOR.unpack(p["p_act"])["motor_time_constant"][0]
    aborts = ys["aborts"][0]
    step = rk4_step(vehicle_function())
    h_max = float(landing_loop_params(lv.l).unpack(lv.pc)["dt"][0])
    landed = landed_outputs_function()
    X, Y = np.zeros((n, lay.size)), np.zeros((n, LANDING_SIGNALS.size))
    if n:                                          # every row in one call of each function
        before = np.concatenate([[t_td], times[:-1]])
        m = np.maximum(1, np.ceil((times - before) / h_max - 1e-9).astype(int))
        h = np.repeat((times - before) / m, m)      # the RK4 steps, m per row
        XV = np.asarray(step.mapaccum(len(h))(s["xv"], p["p_veh"], h[None, :]),
                        dtype=float)[:, np.cumsum(m) - 1]
        F = F_td[:, None] * np.exp(-(times - t_td) / tau_m)[None, :]
        phase = np.where(times >= t_td + settle - 1e-12, LANDED, TOUCHDOWN).astype(float)
        y, x1q = (np.asarray(v, dtype=float) for v in landed.map(n)(
            XV, times[None, :], lv.pp, anchor, F, phase[None, :], aborts))
        Y[:] = y.T
        X[:, lay.slice("xp")] = np.vstack([x1q, XV]).T
        X[:, lay.slice("xc")] = lay.unpack(x_td)["xc"]
    if n:                                          # yaw continuous with the touchdown's
        psi = np.unwrap(np.concatenate([[ys["eta1"][2]], Y[:, LANDING_SIGNALS.index("psi1")]]))[1:]
        Y[:, LANDING_SIGNALS.index("psi1")] = psi
        X[:, lay.slice("xp")][:, LANDING_PLANT_STATE.index("psi1")] = psi
    held = np.tile(R_td, (n, 1))                   # the last commands, rotors idle
    held[:, LANDING_RECORDED.slice("F_cmd")] = 0.0
    return times, X, held, Y


def _result(scenario, times, X, R, Y) -> SimulationResult:
    """The result's columns: ``t``, every output and every recorded signal by name."""
    cols = {"t": times}
    cols.update(zip(LANDING_SIGNALS.element_names(), Y.T, strict=True))
    cols.update(zip(LANDING_RECORDED.element_names(), R.T, strict=True))
    return SimulationResult(scenario, {k: np.ascontiguousarray(v, dtype=float)
                                       for k, v in cols.items()}, X, LANDING_TRAJECTORY)

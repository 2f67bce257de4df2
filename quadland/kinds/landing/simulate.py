"""A landing flown: approach, align, descend, touchdown, the ride on the deck.

A landing scenario (``scenario.model = "landing"``, schema
``quadland.schema.LANDING_SCHEMA``) flies the landing loop of
``quadland_symbolic.landing.loop`` in one call of its compiled simulator (on CasADi's
virtual machine without a C compiler): the guidance and the landing step at
``controller.rate_hz`` (CasADi's functions, or with ``controller.backend =
"c"`` the generated flight code of ``quadland_landing.h``; on sensors, the
sensed loop of ``quadland_symbolic.landing.sensed_loop``, whose flight part is
then also the filter's and the land detector's C), their rotor
commands held on the 6-DOF plant, RK4 on
the exact grid of the output, disturbance and control times, and the
touchdown (the gear gap's zero crossing) located within its step, where the
integration ends. From then on the quadrotor rides on the deck, pinned at its
touchdown pose with its rotors idle: the rows up to ``landing.settle_time``
after touchdown (or the duration) are computed from the vehicle's motion and
the deck's, phase 3 (touchdown), then 4 (landed) at the end of the settling.
"""

from __future__ import annotations

import contextlib

import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.columns import columns_of
from quadland.engine.compiled import (
    SIM_CONTROLLER,
    SIM_ENVELOPE,
    SIM_EVENT,
    SIM_GUARD,
    SIM_NONFINITE,
    SIM_OK,
    compiled_loop,
)
from quadland.engine.envelope import (
    ENVELOPE_FACTOR,
    RK4_REAL_STABILITY,
    Envelope,
    likely_cause,
    loop_modes,
)
from quadland.engine.loop import grid_tolerance
from quadland.engine.plan import SimulationPlan, check_plan, plan_run
from quadland.engine.result import SimulationResult
from quadland.exceptions import ScenarioError, SimulationError
from quadland.kinds.landing.contact_report import gear_columns
from quadland.kinds.landing.gear import contact_step, free_flight_gap
from quadland.kinds.landing.sensed import drawn_table, sensed_vectors, sensors_enabled
from quadland.kinds.landing.values import (
    LandingValues,
    deck_params,
    landing_clocks,
    landing_disturbance,
    landing_values,
    rotor_force_max,
)
from quadland.scenario import Scenario
from quadland_symbolic.landing.deck import DECK_PARAMS
from quadland_symbolic.landing.flat_deck import amplitude_indices
from quadland_symbolic.landing.guidance import TOUCHDOWN
from quadland_symbolic.landing.loop import (
    LANDING_ENVELOPE,
    LANDING_RECORDED,
    landing_loop_params,
    landing_loop_state,
    landing_ride_start,
)
from quadland_symbolic.landing.loop_recipe import landing_loop_recipe
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.sensed_loop import SENSED_TRAJECTORY, sensed_loop_params
from quadland_symbolic.landing.signals import LANDING_SIGNALS, LANDING_TRAJECTORY

__all__ = ["landing_envelope", "landing_plan", "check_landing_plan", "simulate_landing",
           "landing_loop_part", "flat_deck"]


def landing_envelope(scenario: Scenario) -> Envelope:
    """The landing's flight envelope: ``ENVELOPE_FACTOR`` times each initial scale.

    Scales (each at least 1 in its unit): distance, the largest of the
    initial distance from the pad, the hover height and the pad's offset;
    speed, the initial speed plus the most the vehicle can gain over the run
    (``|tau| T / m``, its drive force alone); rate, the initial body rates.
    A rotor's force lags a command clipped to ``[0, F_max]``, so twice
    ``F_max`` is out of reach; the network's weights follow from the leakage
    of eq. (22) as in :func:`quadland.kinds.paper.simulate.paper_envelope`.
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
    # a vehicle that outruns the quadrotor draws away at most at its own speed
    distance, speed, rate = k * L0 + offset + T * vehicle, k * V0, k * W0
    heave = DECK_PARAMS.unpack(deck_params(scenario))["heave_amp"]
    height = abs(dk["height"]) + float(np.sum(np.abs(heave))) + k * L0
    F_max = rotor_force_max(scenario)
    z2_bound = max(speed, rate) + max(*c["k1p"], *c["k1"]) * max(distance, k * np.pi)
    bounds = np.array([distance, height, speed, rate, 2 * F_max, z2_bound / c["k_w"],
                       z2_bound / c["k_zeta"], np.pi / 2])
    basis = (f"{k:g} x the initial distance from the pad or the hover height, at least 1 m, "
             "plus the vehicle's speed bound times the duration (a vehicle that outruns the "
             "quadrotor)",
             f"|deck height| + heave + {k:g} x that distance",
             f"{k:g} x the initial speed plus what the vehicle's drive can add over the run, "
             "at least 1 m/s",
             f"{k:g} x the initial body rate, at least 1 rad/s",
             "twice F_max: a rotor lags a command clipped to [0, F_max]",
             "the leakage bound |z2| / k_w of eq. (22), |z2| <= |e2| + k1 |z1| in the envelope",
             "the leakage bound |z2| / k_zeta of eq. (22)",
             "90 degrees: the thrust points sideways at cos(phi) cos(theta) = 0")
    return Envelope(LANDING_ENVELOPE, bounds, basis)


def _landing_hint(scenario: Scenario, lv: LandingValues, xp_last) -> str:
    """Why a landing likely diverged: the RK4 step, the control rate, or the loop itself.

    The plant's modes (its Jacobian with the commands held) at the initial
    state and at the last state recorded are checked against RK4's stability
    region for the run's step (:func:`quadland.engine.envelope.likely_cause`):
    a body spun up to hundreds of radians per second leaves it.
    """
    c = scenario.data["controller"]
    f = loop_plant_function(contact=False)      # in flight; the gear's step is its own
    held = (np.zeros(f.size1_in(1)), np.zeros(f.size1_in(2)), 0.0, lv.pp)
    initial = loop_modes(f, lv.xp0, *held)
    last = loop_modes(f, xp_last, *held) if xp_last is not None else np.zeros(0)
    return likely_cause(scenario, initial, last, [max(c[k]) for k in ("k1p", "k2p", "k1", "k2")])


def landing_plan(scenario: Scenario) -> SimulationPlan:
    """A landing's size, estimated from its scenario alone (no allocation)."""
    nx = landing_loop_state(scenario.data["rbf"]["nodes"]).size
    return plan_run(scenario, nx, LANDING_DISTURBANCE.size,
                    2 * nx + 2 * (LANDING_SIGNALS.size + LANDING_RECORDED.size))


def check_landing_plan(scenario: Scenario) -> None:
    """Refuse, in one line naming the keys, a landing over the budgets or whose RK4 step
    cannot follow its motors."""
    _check_motor_step(scenario)
    check_plan(landing_plan(scenario))


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
    if h / tau > RK4_REAL_STABILITY / 2:
        need = int(np.ceil(sim["rk_steps_per_interval"] * h / tau / (RK4_REAL_STABILITY / 2)))
        raise ScenarioError(
            f"quadrotor.motor_time_constant: {tau:g} s is too fast for the RK4 step h = "
            f"{h:.3g} s (h / tau_m must stay below {RK4_REAL_STABILITY / 2:.3g}); raise "
            f"simulation.rk_steps_per_interval to {need}")


def landing_loop_part(l: int, part: str, sensed: bool = False, welded: bool = False,
                      flat: bool = False):
    """The compiled (or VM) ``part`` of the landing loop's simulator for ``l`` nodes: the
    loop on the true state, or (``sensed``) on the sensors and the navigation filter;
    ``welded``: the idealization pinned to the deck at touchdown (``gear.welded``);
    ``flat``: on a deck whose sinusoids' amplitudes are all zero, without their sums
    (:func:`quadland_symbolic.landing.flat_deck.flat_deck_loop`, the same results)."""
    from quadland.kinds.landing.flight import flight_code

    flight = flight_code(l, sensed) if part == "sampled_flight" else None
    # a recipe: the model's CasADi functions are built only for a build (0.7 s a process)
    return compiled_loop(landing_loop_recipe(l, sensed, welded, flat), part, flight)


def flat_deck(pp, pc, pc_layout) -> bool:
    """True when every amplitude of the deck's sinusoids is zero, in the plant's
    parameters ``pp`` and in the controller's model within ``pc`` (laid out as
    ``pc_layout``): the loop on a flat deck then computes the same numbers."""
    amps = (np.asarray(pp, dtype=float).ravel()[list(amplitude_indices(LANDING_PLANT_PARAMS))],
            np.asarray(pc, dtype=float).ravel()[list(amplitude_indices(pc_layout, "pp."))])
    return not any(np.any(a) for a in amps)


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
    check_landing_plan(scenario)
    lv = landing_values(scenario)
    envelope = landing_envelope(scenario)
    sim = scenario.data["simulation"]
    clocks = landing_clocks(scenario)
    t_dist = clocks[1].times()
    w_dist = landing_disturbance(scenario, t_dist)
    flight = scenario.data["controller"]["backend"] == "c"
    sensed = sensors_enabled(scenario)
    welded = scenario.data["gear"]["welded"]
    hover = QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(lv.xp0)["x1q"])["F"]
    pc, xc0, table = lv.pc, lv.xc0, contextlib.nullcontext()
    if sensed:
        pc, xc0 = sensed_vectors(scenario, lv)
        table = drawn_table(scenario, clocks[2].count())     # a kept one in an envelope
    pc_layout = (sensed_loop_params if sensed else landing_loop_params)(lv.l)
    loop = landing_loop_part(lv.l, "sampled_flight" if flight else "sampled", sensed, welded,
                             flat_deck(lv.pp, pc, pc_layout))
    p_quad = LANDING_PLANT_PARAMS.unpack(lv.pp)["p_quad"]
    with table as N:
        run = loop.sampled(lv.xp0, xc0, clocks, w_dist.T, sim["rk_steps_per_interval"], lv.pp,
                           pc, TILT_MIN, envelope.bounds,
                           delay=scenario.data["controller"]["delay_periods"], uh0=hover, N=N,
                           h_after=contact_step(scenario,
                                                np.asarray(p_quad, dtype=float).ravel()),
                           after=scenario.data["landing"]["settle_time"],
                           near=free_flight_gap(scenario))
    recorded = loop.model.recorded
    if welded:
        times, X, R, Y, what, t_fail = _welded(scenario, run, loop, clocks, w_dist, lv,
                                               envelope)
    else:
        times, X, R, Y, what, t_fail = _first_contact(run, loop, clocks, w_dist, lv, envelope)
    touched = None if welded else (times >= run.t_event).astype(float)
    bad = ~np.all(np.isfinite(Y), axis=1)
    if bad.any():
        k = int(np.argmax(bad))
        name = LANDING_SIGNALS.element_names()[int(np.argmin(np.isfinite(Y[k])))]
        what, t_fail = f"the output {name} became non-finite", times[k]
        times, X, R, Y = times[:k], X[:k], R[:k], Y[:k]
        touched = None if touched is None else touched[:k]
    held = None if touched is None else _held_disturbance(clocks, w_dist, times)
    result = _result(scenario, times, X, R, Y, recorded, touched, lv.pp, held)
    if what is not None:
        xp_last = X[-1, landing_loop_state(lv.l).slice("xp")] if len(X) else None
        raise SimulationError(f"flight failed at t = {t_fail:.4g} s: {what}"
                              f"{_landing_hint(scenario, lv, xp_last)}", t_fail,
                              result if len(times) else None)
    return result


def _first_contact(run, loop, clocks, w_dist, lv, envelope):
    """The rows of a landing on the gear's contact, with the first contact's row.

    The run went on through the first contact (the event, located by bisection):
    its row is inserted at its instant, the loop's state then and the recorded
    signals of the control step in force. A run that stopped after the contact
    at the singular attitude or outside its envelope is a landing that went
    wrong on the deck (tipped over): its rows up to then are the result, the
    report judges them. Returns ``times, X, R, Y`` and, for a failure before
    the contact (or a non-finite state), its description and time.
    """
    times, X, R = run.times, run.X, run.R
    Y = loop.outputs(X, w_dist[:, run.w_index].T, times, lv.pp)
    if run.x_event is not None:
        t_ev = run.t_event
        k = int(np.searchsorted(times, t_ev, side="left"))
        t_dist = clocks[1].times()
        i_w = int(np.searchsorted(t_dist, t_ev - grid_tolerance(clocks), side="right")) - 1
        y_ev = loop.outputs(run.x_event[None, :], w_dist[:, [i_w]].T, np.array([t_ev]), lv.pp)
        R_ev = R[k - 1] if k > 0 else np.zeros(loop.model.recorded.size)
        times = np.insert(times, k, t_ev)
        X = np.insert(X, k, run.x_event, axis=0)
        # the recorded and output signals' columns with the contact's row, in one copy each
        # (the rows are views of them; the result's columns are their rows as they are)
        R, Y = (columns_of(a, k, v).T for a, v in ((R, R_ev), (Y, y_ev[0])))
        if run.status in (SIM_GUARD, SIM_ENVELOPE):
            return times, X, R, Y, None, None
    if run.status == SIM_OK:
        return times, X, R, Y, None, None
    return (times, X, R, Y, *_failure(run, envelope))


def _welded(scenario, run, loop, clocks, w_dist, lv, envelope):
    """The rows of the welded idealization: the flight to the gear gap's zero crossing,
    its row, then the ride pinned to the deck (:func:`_ride`)."""
    recorded = loop.model.recorded
    done, times, X, R = run.rows, run.times, run.X, run.R
    Y = loop.outputs(X, w_dist[:, run.w_index].T, times, lv.pp)
    if run.status == SIM_EVENT:
        t_td = run.t_stop
        nxp = LANDING_PLANT_STATE.size
        x_td = np.asarray(loop.model.assemble(run.x_end[:nxp], run.x_end[nxp:]),
                          dtype=float).ravel()
        t_dist = clocks[1].times()
        i_w = int(np.searchsorted(t_dist, t_td - grid_tolerance(clocks), side="right")) - 1
        y_td = loop.outputs(x_td[None, :], w_dist[:, [i_w]].T, np.array([t_td]), lv.pp)
        R_td = R[-1] if len(R) else np.zeros(recorded.size)
        ride = _ride(scenario, lv, loop, clocks[0], t_td, x_td, y_td[0], R_td)
        times = np.concatenate([times, [t_td], ride.times])
        X = np.vstack([X, x_td, ride.X])
        R = np.vstack([R, R_td, ride.R])
        Y = np.vstack([Y, y_td, ride.Y])
        Y[done, LANDING_SIGNALS.index("phase")] = TOUCHDOWN
        if ride.status != SIM_OK:                    # after touchdown: no flight hint
            t_fail = float(ride.times[-1]) if len(ride.times) else t_td
            how = "became non-finite" if ride.status == SIM_NONFINITE else "stopped"
            raise SimulationError(f"flight failed at t = {t_fail:.4g} s: the ride on the deck "
                                  f"after touchdown {how}", t_fail,
                                  _result(scenario, times, X, R, Y, recorded))
        return times, X, R, Y, None, None
    if run.status == SIM_OK:
        return times, X, R, Y, None, None
    return (times, X, R, Y, *_failure(run, envelope))


def _failure(run, envelope) -> tuple[str, float]:
    """What stopped a run, and when."""
    what = {SIM_GUARD: f"singular attitude, |cos(theta) cos(phi)| < {TILT_MIN:g}",
            SIM_CONTROLLER: "the flight code (controller.backend = \"c\") returned an "
                            "error status"}.get(run.status, "the state became non-finite")
    if run.status == SIM_ENVELOPE:
        what = envelope.describe(run.envelope)
    return what, run.t_stop


def _ride(scenario, lv, loop, rows, t_td, x_td, y_td, R_td):
    """Rows after touchdown: the quadrotor pinned to the deck, its rotors winding down.

    The loop's ride (``quadland_symbolic.landing.loop``: the vehicle goes on by
    eq. (4), RK4 in steps of at most one control period; the quadrotor keeps
    its touchdown pose in the deck frame, its rotor forces decay as
    ``F_td exp(-(t - t_td) / tau_m)``), run by the simulator
    (``quadland_loop.h``'s ``qll_ride``, or its mirror on the VM); here only
    the yaw is unwrapped, continuous with the touchdown's.
    """
    settle = scenario.data["landing"]["settle_time"]
    t_end = min(t_td + settle, scenario.data["simulation"]["duration"])
    z0, a = (np.asarray(v, dtype=float).ravel()
             for v in landing_ride_start(lv.l, loop.model.recorded)(x_td, y_td, R_td, t_td,
                                                                      settle))
    h_max = float(landing_loop_params(lv.l).unpack(lv.pc)["dt"][0])
    ride = loop.ride(z0, a, rows, t_td, t_end, h_max, lv.pp)
    if len(ride.times):
        ys, k = LANDING_SIGNALS.unpack(y_td), LANDING_SIGNALS.index("psi1")
        psi = np.unwrap(np.concatenate([[ys["eta1"][2]], ride.Y[:, k]]))[1:]
        ride.Y[:, k] = psi
        ride.X[:, LANDING_PLANT_STATE.index("psi1")] = psi     # xp leads the loop's state
    return ride


def _held_disturbance(clocks, w_dist, times) -> np.ndarray:
    """The disturbance held at each row, ``(n, 9)``: the last sample at or before its time
    (a row on a sample's instant holds that sample, as the simulator does)."""
    i_w = np.searchsorted(clocks[1].times(), times + grid_tolerance(clocks), side="right") - 1
    return w_dist[:, np.maximum(i_w, 0)].T


def _result(scenario, times, X, R, Y, recorded=LANDING_RECORDED,
            touched=None, pp=None, held=None) -> SimulationResult:
    """The result's columns: ``t``, every output and every recorded signal by name; on the
    gear's contact also ``touched`` (1 from the first contact's row on) and the gear's
    signals (:func:`quadland.kinds.landing.contact_report.gear_columns`, under the
    disturbance ``held`` at each row)."""
    cols = {"t": times}
    # one transposed copy each (none where the rows are already views of their columns):
    # its rows are the columns, contiguous (a copy per column was 280 small copies a landing)
    cols.update(zip(LANDING_SIGNALS.element_names(), columns_of(Y), strict=True))
    cols.update(zip(recorded.element_names(), columns_of(R), strict=True))
    if touched is not None:
        cols["touched"] = touched
        cols.update(gear_columns(pp, times, X, touched, held))
    layout = LANDING_TRAJECTORY if recorded is LANDING_RECORDED else SENSED_TRAJECTORY
    return SimulationResult(scenario, {k: np.ascontiguousarray(v, dtype=float)
                                       for k, v in cols.items()}, X, layout,
                            landing_loop_state(scenario["rbf.nodes"]))

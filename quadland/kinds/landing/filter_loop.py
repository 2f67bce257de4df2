"""The sampled hover loop with the navigation filter in it, linearized at its steady state.

:func:`quadland.kinds.landing.linearize.hover_sampled_models` closes the loop on
perfect sensing: the law reads the quadrotor's state. The flown loop
(:mod:`quadland_symbolic.landing.sensed_loop`) reads the navigation filter's
estimate instead. :func:`hover_filter_models` builds that loop at the control rate,
about the hover point, from the flight code's own functions
(:mod:`quadland_symbolic.landing.filter_linearization`):

* **plant**: the hover plant under a zero-order hold of the wrench, its outputs the
  sensors' packets as the filter reads them (the world's sensor models, zero noise);
* **filter**: the horizon state ``x_h``, ``n_hist`` periods behind the present. At
  step ``k`` it fuses the packets sampled at ``k - n_hist`` (a packet of latency
  ``L`` arrives ``ceil(L / T)`` periods after its sample and waits in its FIFO for
  the horizon: a latency up to the horizon adds nothing, a longer one the
  difference, one past ``max_age`` more is never fused), with its gain frozen at the
  steady covariance (:func:`steady_covariance`); the output predictor carries it to
  the present through the buffered accelerations of the IMU; the controller's
  measurement is the flight step's (relative position and velocity from the
  estimate, the pad's velocity and acceleration estimated, attitude and rates from
  the IMU);
* **delays**: one line of the packets' values (compressed to the rank of their
  Jacobian in the plant's state) of ``n_hist`` plus the longest extra delay;
* **controller**: the landing step's Jacobians in its whole measurement, and the
  computation delay on its command.

The filter is multirate: each sensor fuses at its own rate. The linear model is
time-invariant at the control rate with the **rate-equivalent** filter: every
sensor fused every period with its variance times ``rate_hz / (sensor rate x (1 -
dropout))`` (the same information per second). The covariance is the fixed point of
the flight code's own recursion (fusion then prediction) with those variances;
:func:`steady_covariance` also iterates the periodic multirate schedule, for the
comparison docs/margins.md reports.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from quadland.engine.function_store import stored_function
from quadland.kinds.landing.linearize import (
    LANDING_INPUT_NAMES,
    LANDING_LOOP_NAMES,
    hover_jacobians,
    hover_values,
    kept_memory,
)
from quadland.kinds.landing.sensed import estimator_p, sensor_settings
from quadland.kinds.landing.sensor_settings import sensor_params
from quadland.linear import (
    LinearModels,
    OperatingPoint,
    Realization,
    assemble,
    check_delay_periods,
    delayed,
    zoh,
)
from quadland.scenario import Scenario
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, landing_memory
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    HIST_ROWS,
    N_HIST,
    estimator_memory,
)
from quadland_symbolic.landing.filter_linearization import (
    NAV_SENSOR,
    filter_fusion_function,
    filter_output_function,
    filter_prediction_function,
    hover_law_function,
    hover_sensing_function,
    packet_values,
)
from quadland_symbolic.landing.linearization import hover_measurement
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    IMU,
    NAV,
    NAV_PACKETS,
    covariance_pattern,
    estimator_params,
)
from quadland_symbolic.landing.sensed_loop import delivery_delay

__all__ = ["FilterSchedule", "filter_schedule", "steady_covariance", "hover_filter_models",
           "delayed_plant_loop", "RICCATI_TOL", "truth_measurement", "sensor_params",
           "sensor_settings"]

#: Relative change of the covariance per step at which the recursion has converged.
RICCATI_TOL = 1e-12


class FilterSchedule:
    """When and how each of the filter's packets is fused at the hover point.

    Attributes
    ----------
    rate_hz : float
        The control rate.
    n_hist : int
        The horizon's delay, periods.
    period : dict
        Packet -> control periods between its samples (0: never fused).
    extra : dict
        Packet -> periods of delay beyond the horizon (its latency past ``n_hist``).
    variance_scale : dict
        Packet -> the rate-equivalent factor on its variances.
    reason : dict
        Packet -> why it is not fused ('' when it is).
    """

    def __init__(self, rate_hz, n_hist, period, extra, variance_scale, reason):
        self.rate_hz, self.n_hist = rate_hz, n_hist
        self.period, self.extra = period, extra
        self.variance_scale, self.reason = variance_scale, reason

    def due(self) -> np.ndarray:
        """1 for each packet fused at all (:data:`NAV_PACKETS`' order)."""
        return np.array([1.0 if self.period[p.name] else 0.0 for p in NAV_PACKETS])

    def due_at(self, tick: int) -> np.ndarray:
        """The packets whose sample falls on control tick ``tick`` (periodic schedule)."""
        return np.array([1.0 if self.period[p.name] and tick % self.period[p.name] == 0
                         else 0.0 for p in NAV_PACKETS])

    def hyperperiod(self) -> int:
        """Control periods after which the schedule repeats."""
        return math.lcm(*[n for n in self.period.values() if n] or [1])


def filter_schedule(scenario: Scenario, valid: np.ndarray, p_est: np.ndarray) -> FilterSchedule:
    """Each packet's rate, extra delay and rate-equivalent variance factor.

    ``valid`` is each packet's validity at the hover point (a marker out of view, a
    range past its maximum are never fused there).
    """
    rate = float(scenario.data["controller"]["rate_hz"])
    settings, pe = sensor_settings(scenario), estimator_params().unpack(p_est)
    period, extra, scale, reason = {}, {}, {}, {}
    for k, p in enumerate(NAV_PACKETS):
        s = settings[NAV_SENSOR[p.name]]
        lag = delivery_delay(float(s["latency"]), 1.0 / rate) - N_HIST
        kept = float(s["rate_hz"]) * (1.0 - float(s.get("dropout", 0.0)))
        why = ("" if valid[k] > 0.5 else "not valid at the hover point")
        if not why and not kept > 0:
            why = "no packets"
        if not why and lag / rate > float(pe[f"max_age_{p.name}"][0]) + 0.5 / rate:
            why = "its latency is past the horizon by more than max_age"
        reason[p.name] = why
        period[p.name] = 0 if why else max(1, round(rate / float(s["rate_hz"])))
        extra[p.name] = max(0, lag)
        scale[p.name] = rate / kept if kept > 0 else math.inf
    return FilterSchedule(rate, N_HIST, period, extra, scale, reason)


def _equivalent_p_est(p_est: np.ndarray, schedule: FilterSchedule) -> np.ndarray:
    """``p_est`` with each block's noise scaled to the rate-equivalent variance."""
    lay = estimator_params()
    p = lay.unpack(p_est)
    for b in BLOCKS:
        f = math.sqrt(schedule.variance_scale[b.sensor]) if schedule.period[b.sensor] else 1.0
        for key in (f"{b.name}_sigma", f"{b.name}_sigma0", f"{b.name}_k_range"):
            if key in p:
                p[key] = np.asarray(p[key]) * f
    return lay.pack(p)


def _cycle_function(hover: dict, schedule: FilterSchedule, periodic: bool):
    """One cycle of the flight recursion (fusion, prediction) on ``P`` and its Jacobian:
    one period (rate-equivalent) or the schedule's hyperperiod (periodic)."""
    import casadi as ca

    pattern = covariance_pattern(FLIGHT_COUPLING)
    fuse, pred = filter_fusion_function(FLIGHT_COUPLING), filter_prediction_function(
        FLIGHT_COUPLING)
    p_fuse = hover["p_est"] if periodic else _equivalent_p_est(hover["p_est"], schedule)
    P0 = ca.SX.sym("P", pattern.size)
    P = P0
    for j in range(schedule.hyperperiod() if periodic else 1):
        due = schedule.due_at(j) if periodic else schedule.due()
        P = fuse(hover["x_nav"], P, *hover["packets"], due, hover["n2"], p_fuse)[1]
        P = pred(hover["x_nav"], P, hover["a_in"], hover["dt"], hover["p_est"])[1]
    return ca.Function("riccati_cycle", [P0], [P, ca.jacobian(P, P0)])


def steady_covariance(hover: dict, schedule: FilterSchedule, periodic: bool = False,
                      tol: float = RICCATI_TOL) -> tuple[np.ndarray, int]:
    """The horizon's covariance before fusion at the filter's steady state.

    The fixed point of the flight code's recursion (fusion of the due packets, then
    one period's prediction): with every packet fused every period at its
    rate-equivalent variance, or (``periodic``) on the multirate schedule over its
    hyperperiod, the covariance at the start of it (the tick every sensor samples).
    Found by Newton's method on ``P = f(P)`` with ``f``'s exact Jacobian, from the
    initial covariance after a few cycles. Returns ``(P, Newton steps)``, the stored
    entries of the flight coupling's pattern.
    """
    pattern = covariance_pattern(FLIGHT_COUPLING)
    f = _cycle_function(hover, schedule, periodic)
    P = pattern.pack_numeric(np.diag(hover["P0_diag"]))
    for _ in range(20):
        P = np.asarray(f(P)[0], dtype=float).ravel()
    n = P.size
    for it in range(1, 60):
        fP, J = (np.asarray(v, dtype=float) for v in f(P))
        r = fP.ravel() - P
        if np.max(np.abs(r)) <= tol * np.max(np.abs(P)):
            return P, it
        # least squares: an entry no measurement and no noise moves is a fixed point
        # of its own (eigenvalue 1), determined by the start
        P = P - np.linalg.lstsq(J - np.eye(n), r, rcond=None)[0]
    raise RuntimeError("the filter's covariance did not converge in 60 Newton steps "
                       f"(residual {np.max(np.abs(r)):.3g})")


def _hover_filter(scenario: Scenario, point: OperatingPoint, dt: float) -> dict:
    """The filter's nominal values at the hover point."""
    hv = hover_values(scenario)
    g = float(scenario.data["quadrotor"]["gravity"])
    p_est = estimator_p(scenario, g)
    out = stored_function(hover_sensing_function)(point.xr, point.u, point.vehicle, point.w,
                                                  hv.pp, sensor_params(sensor_settings(scenario)))
    out = [np.asarray(v, dtype=float) for v in out]
    imu, packets = out[0].ravel(), [v.ravel() for v in out[1:5]]
    valid, S_z, S_u, x_nav = out[5].ravel(), out[6], out[7], out[8].ravel()
    eta2, w2E, w2E_dot = (v.ravel() for v in out[9:12])
    e = scenario.data["estimator"]
    P0 = np.concatenate([np.asarray(e[k], dtype=float) ** 2 for k in (
        "p0_position", "p0_velocity", "p0_target_velocity", "p0_target_acceleration",
        "p0_bias", "p0_input_bias", "p0_tilt_bias")])
    a_in = np.asarray(rotation(imu[0:3]), dtype=float) @ imu[3:6] - np.array([0, 0, g])
    return dict(hv=hv, p_est=p_est, imu=imu, packets=packets, valid=valid, S_z=S_z, S_u=S_u,
                x_nav=x_nav, eta2=eta2, w2E=w2E, w2E_dot=w2E_dot, a_in=a_in, P0_diag=P0,
                n2=np.asarray(rotation(eta2), dtype=float)[:, 2], dt=dt)


def _output_jacobians(h: dict, x_plus: np.ndarray):
    """The flight step's measurement and its Jacobians at the nominal horizon."""
    lay = estimator_memory(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)
    dt = h["dt"]
    mem = lay.zeros()
    deck = dict(deck_eta2=h["eta2"], deck_w2E=h["w2E"], deck_w2E_dot=h["w2E_dot"],
                deck_tau=[0.0], t_h=[-N_HIST * dt])
    for name, v in deck.items():
        mem[lay.slice(name)] = v
    # the hover's periods: its acceleration input, the period, no turn of the body (the
    # bias's turn (E6a) is bilinear in the turn and the bias estimate, both zero here)
    hist = np.vstack([np.tile(h["a_in"][:, None], (1, N_HIST)), np.full((1, N_HIST), dt),
                      np.zeros((len(HIST_ROWS) - 4, N_HIST))])
    out = filter_output_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING)(
        x_plus, hist, h["imu"], mem, h["p_est"], dt, 0.0)
    return [np.asarray(v, dtype=float) for v in out]


def _law(scenario: Scenario, point: OperatingPoint, y0: np.ndarray, dt: float):
    """The landing step's Jacobians in its whole measurement, the zero-gain biases dropped."""
    hv = hover_values(scenario)
    out = stored_function(hover_law_function, hv.l)(y0, point.xc, hv.p_ctrl, hv.pm, hv.ref, dt)
    Phi, Gam, C, D = (np.asarray(v, dtype=float) for v in out[2:])
    keep = kept_memory(hv.l, hv.p_ctrl)
    return Phi[np.ix_(keep, keep)], Gam[keep, :], C[:, keep], D, keep


class _Taps:
    """The line of the packets' values: ``s[k - j]`` as a map of the controller's state
    (the line's ``j``-th slot) and of the plant's outputs now (``j = 0``)."""

    def __init__(self, S_z: np.ndarray, length: int, offset: int, n_state: int):
        U, sv, _ = np.linalg.svd(S_z, full_matrices=False)
        r = int(np.sum(sv > 1e-10 * sv[0])) if sv.size and sv[0] > 0 else 0
        self.U, self.W = U[:, :r], U[:, :r].T
        self.r, self.length, self.offset, self.n = r, length, offset, n_state

    def at(self, j: int, rows) -> tuple[np.ndarray, np.ndarray]:
        """``(X, Y)``: the outputs ``rows`` sampled ``j`` periods ago are ``X xi + Y y``."""
        X, Y = np.zeros((len(rows), self.n)), np.zeros((len(rows), self.U.shape[0]))
        if j == 0:
            Y[:, rows] = np.eye(len(rows))
        else:
            start = self.offset + (j - 1) * self.r
            X[:, start:start + self.r] = self.U[rows, :]
        return X, Y


def _rows(h: dict):
    """The rows of the IMU and of each packet in the stacked sensor outputs."""
    sizes = [h["imu"].size] + [v.size for v in h["packets"]]
    edges = np.cumsum([0] + sizes)
    return [np.arange(edges[i], edges[i + 1]) for i in range(len(sizes))]


def _filter_controller(h: dict, schedule: FilterSchedule, J_fuse, J_pred, out, law):
    """The filter and the landing step as one controller from the sensors' packets to the
    wrench: states ``[mem, x_h, line]``; returns ``(A, B, C, D, names of the states)``."""
    X_x, X_pkt = J_fuse
    Phi, Gamma = J_pred
    Y_x, Y_hist, Y_imu, A_imu = out
    Phi_c, Gam_c, C_c, D_c, mem_names = law
    N, nc, nx = schedule.n_hist, Phi_c.shape[0], X_x.shape[0]
    rows = _rows(h)
    extra = max(schedule.extra.values())
    length = N + extra
    taps = _Taps(h["S_z"], length, nc + nx, 0)
    n = nc + nx + taps.r * length
    taps.n = n
    ny = h["S_z"].shape[0]
    # the horizon after fusion: x_h+ = X_x x_h + X_pkt (each packet k - N - extra ago)
    Hx, Hy = np.zeros((nx, n)), np.zeros((nx, ny))
    Hx[:, nc:nc + nx] = X_x
    col = 0
    for k, p in enumerate(NAV_PACKETS):
        width = rows[k + 1].size
        Xs, Ys = taps.at(N + schedule.extra[p.name], rows[k + 1])
        Hx += X_pkt[:, col:col + width] @ Xs
        Hy += X_pkt[:, col:col + width] @ Ys
        col += width
    # the measurement: y = Y_x x_h+ + Y_hist a[k-N .. k-1] + Y_imu imu[k]
    Fx, Fy = Y_x @ Hx, Y_x @ Hy
    Xi, Yi = taps.at(0, rows[0])
    Fx, Fy = Fx + Y_imu @ Xi, Fy + Y_imu @ Yi
    for i in range(N):                                    # hist column i: a[k - N + i]
        Xa, Ya = taps.at(N - i, rows[0])
        Fx += Y_hist[:, 3 * i:3 * i + 3] @ A_imu @ Xa
        Fy += Y_hist[:, 3 * i:3 * i + 3] @ A_imu @ Ya
    A, B = np.zeros((n, n)), np.zeros((n, ny))
    A[:nc, :] = Gam_c @ Fx
    A[:nc, :nc] += Phi_c
    B[:nc, :] = Gam_c @ Fy
    # the horizon's prediction over the oldest buffered input a[k - N]
    Xa, Ya = taps.at(N, rows[0])
    A[nc:nc + nx, :] = Phi @ Hx + Gamma @ A_imu @ Xa
    B[nc:nc + nx, :] = Phi @ Hy + Gamma @ A_imu @ Ya
    # the line: slot 1 takes the packets now, each slot the one before
    o = nc + nx
    if length:
        B[o:o + taps.r, :] = taps.W
        for j in range(1, length):
            A[o + j * taps.r:o + (j + 1) * taps.r, o + (j - 1) * taps.r:o + j * taps.r] = \
                np.eye(taps.r)
    C, D = C_c @ np.eye(nc, n) + D_c @ Fx, D_c @ Fy
    nav = NAV.element_names() if nx == NAV.size else [str(i) for i in range(nx)]
    names = (list(mem_names) + [f"x_h_{e}" for e in nav]
             + [f"line{j + 1}[{i}]" for j in range(length) for i in range(taps.r)])
    return A, B, C, D, names


def hover_filter_models(scenario: Scenario, point: OperatingPoint, rate_hz: float,
                        delay_periods: int = 1, compact: bool = True) -> LinearModels:
    """The sampled hover loop with the navigation filter in it (module docstring).

    The plant's outputs are the sensors' packets; the controller is the filter (its
    gain frozen at the rate-equivalent steady covariance) and the landing step, with
    ``delay_periods`` unit delays on its command. With ``compact`` the loop broken at
    the plant input (``loop_input``, what the margins read) is realized with the plant's
    state delayed (:func:`delayed_plant_loop`: 357 states on ``highway`` instead of
    773); the plant, the controller and the other loops are the full ones.
    """
    delay_periods = check_delay_periods(delay_periods)
    dt = 1.0 / rate_hz
    h = _hover_filter(scenario, point, dt)
    if np.max(np.abs(h["S_u"]), initial=0.0) > 0:
        raise ValueError("hover_filter_models: a sensor reads the command directly")
    schedule = filter_schedule(scenario, h["valid"], h["p_est"])
    P, _ = steady_covariance(h, schedule)
    p_fuse = _equivalent_p_est(h["p_est"], schedule)
    fz = filter_fusion_function(FLIGHT_COUPLING)(h["x_nav"], P, *h["packets"], schedule.due(),
                                                 h["n2"], p_fuse)
    x_plus = np.asarray(fz[0], dtype=float).ravel()
    pr = filter_prediction_function(FLIGHT_COUPLING)(x_plus, P, h["a_in"], dt, h["p_est"])
    y0, _, Y_x, Y_hist, Y_imu, A_imu = _output_jacobians(h, x_plus)
    law = _law(scenario, point, y0.ravel(), dt)
    names = landing_memory(hover_values(scenario).l).element_names()
    A, B, C, D, c_names = _filter_controller(
        h, schedule, [np.asarray(v, dtype=float) for v in fz[3:5]],
        [np.asarray(v, dtype=float) for v in pr[2:4]], (Y_x, Y_hist, Y_imu, A_imu),
        (*law[:4], [names[i] for i in law[4]]))
    J = hover_jacobians(scenario, point, dt)
    Phi_p, Gam_p = zoh(J["A_p"], J["B_p"], dt)
    K = delayed(A, B, C, D, delay_periods)
    y_names = [f"{layout.name}_{e}" for layout in (IMU, *NAV_PACKETS)
               for n in packet_values(layout) for e in layout[n].element_names()]
    models = assemble(point, Phi_p, Gam_p, h["S_z"], *K, dt,
                      dict(x=list(point.state_names), y=y_names, u=list(LANDING_INPUT_NAMES),
                           c=c_names, loops=LANDING_LOOP_NAMES), delay_periods)
    if not compact:
        return models
    L = delayed_plant_loop(Phi_p, Gam_p, h["S_z"], h, schedule,
                           [np.asarray(v, dtype=float) for v in fz[3:5]],
                           [np.asarray(v, dtype=float) for v in pr[2:4]],
                           (Y_x, Y_hist, Y_imu, A_imu), law[:4], delay_periods)
    li = models.realizations["loop_input"]
    states = tuple(f"x[{i}]" for i in range(L[0].shape[0]))    # python-control's defaults
    loop = Realization(*L, li.dt, li.inputs, li.outputs, states, "loop_input")
    return dataclasses.replace(models, realizations={**models.realizations, "loop_input": loop})


def truth_measurement(scenario: Scenario, point: OperatingPoint) -> np.ndarray:
    """The law's measurement with perfect sensing at the point, for comparison."""
    hv = hover_values(scenario)
    return np.asarray(hover_measurement(point.xr, point.vehicle, hv.pp),
                      dtype=float).ravel()[:LANDING_MEASUREMENT.size]


def delayed_plant_loop(Phi_p, Gam_p, S_z, h: dict, schedule: FilterSchedule, J_fuse, J_pred,
                       out, law, delay_periods: int):
    """``L = -K P`` broken at the plant input, realized with the plant's state delayed.

    The same loop as :func:`quadland.linear.assemble` makes of the plant and the filter
    controller, with ``M = n_hist + extra`` periods of the plant's inputs in a line
    instead of ``M`` periods of its packets: states ``[z[k - M], u[k - M] .. u[k - 1],
    mem, x_h, commands]``, and every past packet ``S_z z[k - m]`` rebuilt from them
    (``z[k - m + 1] = Phi_p z[k - m] + Gam_p u[k - m]``). The wrench has 4 entries and
    the packets' Jacobian rank 13: 4 M states instead of 13 M. Returns ``(A, B, C, D)``.
    """
    X_x, X_pkt = J_fuse
    Phi, Gamma = J_pred
    Y_x, Y_hist, Y_imu, A_imu = out
    Phi_c, Gam_c, C_c, D_c = law
    N, nz, m = schedule.n_hist, Phi_p.shape[0], Gam_p.shape[1]
    M, nc, nx = N + max(schedule.extra.values()), Phi_c.shape[0], X_x.shape[0]
    o_c, o_h = nz + m * M, nz + m * M + nc
    n0 = o_h + nx
    T = [None] * (M + 1)                    # T[j]: z[k - j] as a map of the state
    T[M] = np.eye(nz, n0)
    for j in range(M, 0, -1):
        Eu = np.zeros((m, n0))
        Eu[:, nz + m * (M - j):nz + m * (M - j + 1)] = np.eye(m)
        T[j - 1] = Phi_p @ T[j] + Gam_p @ Eu
    rows = _rows(h)
    Hx = np.zeros((nx, n0))
    Hx[:, o_h:] = X_x
    col = 0
    for k, p in enumerate(NAV_PACKETS):
        width = rows[k + 1].size
        Hx += X_pkt[:, col:col + width] @ S_z[rows[k + 1], :] @ T[N + schedule.extra[p.name]]
        col += width
    imu = S_z[rows[0], :]
    Fx = Y_x @ Hx + Y_imu @ imu @ T[0]
    for i in range(N):
        Fx += Y_hist[:, 3 * i:3 * i + 3] @ A_imu @ imu @ T[N - i]
    A, B = np.zeros((n0, n0)), np.zeros((n0, m))
    A[:nz, :] = T[M - 1]                                 # z[k - M + 1]
    for j in range(M - 1):                               # the inputs' line moves up
        A[nz + m * j:nz + m * (j + 1), nz + m * (j + 1):nz + m * (j + 2)] = np.eye(m)
    B[nz + m * (M - 1):nz + m * M, :] = np.eye(m)
    A[o_c:o_h, :] = Gam_c @ Fx
    A[o_c:o_h, o_c:o_h] += Phi_c
    A[o_h:, :] = Phi @ Hx + Gamma @ A_imu @ imu @ T[N]
    C = C_c @ np.eye(nc, n0, o_c) + D_c @ Fx             # the command, before its delay
    Ad, Bd, Cd, Dd = delayed(A, np.zeros((n0, 0)), C, np.zeros((m, 0)), delay_periods)
    Ad[:n0, :n0] = A
    Bd = np.vstack([B, np.zeros((Ad.shape[0] - n0, m))])
    if delay_periods == 0:
        return A, B, -C, np.zeros((m, m))
    return Ad, Bd, -Cd, np.zeros((m, m))

"""The navigation filter in the hover loop: its pieces' Jacobians at the hover point.

:mod:`quadland_symbolic.landing.linearization` linearizes the landing loop with
perfect sensing: the law reads the quadrotor's state. The flown loop reads the
navigation filter (:mod:`quadland_symbolic.landing.estimator`) instead. This module
gives, from the same symbolic functions the flight code and the world use, the
Jacobians a linear model of that loop needs at the hover point
(:func:`quadland_symbolic.landing.linearization.hover_linearization_function`'s
deck-frame state ``z``, the deck frozen, the vehicle heading along E's x):

* :func:`hover_sensing_function`: the sensors' packets at ``z``
  (:func:`~quadland_symbolic.landing.sensors.sensor_function`, zero noise) as the
  filter reads them, and their Jacobian in ``z``; with the filter's nominal state
  (the truth, :func:`~quadland_symbolic.landing.sensors.navigation_truth_function`);
* :func:`filter_fusion_function`: one fusion of every sensor's packet at the
  horizon by the flight code's gated block updates
  (:func:`~quadland_symbolic.landing.navigation.block_update`, in fusion order),
  the covariance after it, and the state's Jacobians in the prior state and the
  packets at a given covariance (the gain frozen there);
* :func:`filter_prediction_function`: the covariance's prediction over one period
  (:func:`~quadland_symbolic.landing.navigation.nav_predict`);
* :func:`filter_output_function`: the controller's measurement as the flight step
  forms it (:func:`~quadland_symbolic.landing.estimator.estimator_output`, no packet
  fused) from the horizon state, the buffered inputs and the IMU, and its Jacobians;
* :func:`hover_law_function`: the landing step's Jacobians in its whole
  measurement :data:`~quadland_symbolic.landing.controller.LANDING_MEASUREMENT`
  (the broadcast's pad velocity and acceleration are the filter's estimates).

The assembly (delays, the steady covariance, the loop) is the runtime's
(:mod:`quadland.kinds.landing.filter_loop`).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kalman import select
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    landing_controller_params,
    landing_law,
    landing_memory,
)
from quadland_symbolic.landing.estimator import (
    HIST_ROWS,
    estimator_memory,
    estimator_output,
)
from quadland_symbolic.landing.gear import GEAR_STATE
from quadland_symbolic.landing.guidance import POSITION_REFERENCE
from quadland_symbolic.landing.heave import heave_gate
from quadland_symbolic.landing.linearization import HOVER_PLANT, hover_quadrotor, hover_vehicle
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    IMU,
    NAV,
    NAV_PACKETS,
    acceleration_input,
    block_update,
    covariance_pattern,
    estimator_params,
    nav_predict,
)
from quadland_symbolic.landing.plant import LANDING_DISTURBANCE, LANDING_PLANT_PARAMS
from quadland_symbolic.landing.sensors import (
    NAV_TRUTH,
    NOISES,
    SENSOR_PACKETS,
    SENSOR_PARAMS,
    navigation_truth_function,
    sensor_function,
)
from quadland_symbolic.linearization import VEHICLE_SPEEDS
from quadland_symbolic.quadrotor import WRENCH, rotors_from_wrench

__all__ = ["NAV_SENSOR", "packet_values", "hover_sensing_function", "filter_fusion_function",
           "filter_prediction_function", "filter_output_function", "hover_law_function"]

#: The world's sensor (:data:`~quadland_symbolic.landing.sensors.SENSOR_NAMES`) behind each
#: of the filter's packets (:data:`~quadland_symbolic.landing.navigation.NAV_PACKETS`).
NAV_SENSOR = {"vision": "vision", "gnss": "gnss", "range": "rangefinder",
              "datalink": "datalink"}


def packet_values(layout) -> tuple[str, ...]:
    """The names of a filter packet's fields a sensor fills (all but ``fresh`` and
    ``tau``; the IMU's, all)."""
    return tuple(f.name for f in (layout.fields if layout is IMU else layout.fields[2:]))


def _xp(z, v2, pp):
    """The landing plant's state at the deck-frame hover state ``z`` (gear at rest)."""
    xv = hover_vehicle(v2)
    return ca.vertcat(hover_quadrotor(z, xv, pp), xv, ca.DM.zeros(GEAR_STATE.size))


@functools.cache
def hover_sensing_function() -> ca.Function:
    """The filter's inputs at a hover state and their Jacobians.

    ``hover_sensing(z, u, v2, w, pp, p_sens) -> (imu, vision, gnss, range, datalink,
    valid, S_z, S_u, x_nav, eta2, w2E, w2E_dot)``: each packet's values as the
    filter reads them (:func:`packet_values` of :data:`IMU` and of each of
    :data:`NAV_PACKETS`), by the world's sensor at time 0 with zero noise, the
    rotors commanded ``rotors_from_wrench(u)`` (the plant's mixer); ``valid`` each
    of the filter's packets' validity flag (1 when the sensor has none); ``S_z``,
    ``S_u`` the Jacobians of the stacked values ``[imu, vision, gnss, range,
    datalink]`` in ``z`` and ``u``; ``x_nav`` the filter's nominal state (the true
    relative motion, zero biases); the deck's attitude and rotation.
    """
    z, u, v2 = HOVER_PLANT.sym(), WRENCH.sym(), VEHICLE_SPEEDS.sym()
    w, pp, ps = LANDING_DISTURBANCE.sym(), LANDING_PLANT_PARAMS.sym(), SENSOR_PARAMS.sym()
    xp = _xp(z, v2, pp)
    uh = rotors_from_wrench(u, LANDING_PLANT_PARAMS.unpack(pp)["p_quad"])
    sensed, valid = [], []
    for layout, name in ((IMU, "imu"), *((p, NAV_SENSOR[p.name]) for p in NAV_PACKETS)):
        y = SENSOR_PACKETS[name].unpack(sensor_function(name)(
            xp, uh, w, 0, pp, ps, ca.DM.zeros(NOISES[name].size)))
        sensed.append(ca.vertcat(*[y[n] for n in packet_values(layout)]))
        if layout is not IMU:
            valid.append(y["valid"] if "valid" in y else ca.DM.ones(1))
    s = ca.vertcat(*sensed)
    truth = NAV_TRUTH.unpack(navigation_truth_function()(xp, 0, pp, ca.DM.zeros(3)))
    x_nav = ca.vertcat(*[truth[f.name] if f.name in truth else ca.DM.zeros(f.size)
                         for f in NAV.fields])
    dl = dict(zip(packet_values(NAV_PACKETS[-1]), ca.vertsplit(sensed[-1], _offsets(
        NAV_PACKETS[-1])), strict=True))
    return ca.Function("hover_sensing", [z, u, v2, w, pp, ps],
                       [*sensed, ca.vertcat(*valid), ca.jacobian(s, z), ca.jacobian(s, u),
                        x_nav, dl["eta2"], dl["w2E"], dl["w2E_dot"]],
                       ["z", "u", "v2", "w", "pp", "p_sens"],
                       ["imu", *(p.name for p in NAV_PACKETS), "valid", "S_z", "S_u",
                        "x_nav", "eta2", "w2E", "w2E_dot"])


def _offsets(layout) -> list[int]:
    names = packet_values(layout)
    out = [0]
    for n in names:
        out.append(out[-1] + layout[n].size)
    return out


def _packet(layout, values, tau=0):
    """A filter packet: ``fresh = 1``, sample time ``tau``, the values."""
    return ca.vertcat(1, tau, values)


@functools.cache
def filter_fusion_function(coupling: str) -> ca.Function:
    """One fusion of every sensor's packet at the horizon, as the flight step fuses them.

    ``filter_fusion(x, P, vision, gnss, range, datalink, due, n2, p_est) -> (x_next,
    P_next, fused, X_x, X_pkt)``: the packets' values (:func:`packet_values`), ``due``
    one flag per packet (1: its FIFO's head is fused at this step), ``n2`` the deck's
    normal in E; ``P`` and ``P_next`` the stored entries of :func:`covariance_pattern`.
    The blocks run in fusion order through
    :func:`~quadland_symbolic.landing.navigation.block_update` (gated, scalar Joseph
    updates; the streak of refusals 0). ``fused`` is each block's flag, ``X_x`` and
    ``X_pkt`` the Jacobians of ``x_next`` in ``x`` and in the stacked values at the
    given ``P`` (the gain frozen: ``P`` is an input, not a function of ``x``).
    """
    pattern = covariance_pattern(coupling)
    x, Pv, p_est = NAV.sym("x"), ca.SX.sym("P", pattern.size), estimator_params().sym("p_est")
    due, n2 = ca.SX.sym("due", len(NAV_PACKETS)), ca.SX.sym("n2", 3)
    values = [ca.SX.sym(p.name, p.size - 2) for p in NAV_PACKETS]
    xs, P, fused = x, pattern.unpack(Pv), []
    for k, (layout, v) in enumerate(zip(NAV_PACKETS, values, strict=True)):
        for b in (b for b in BLOCKS if b.sensor == layout.name):
            xs, P, _, _, ok, _ = block_update(b.name, xs, P, _packet(layout, v), n2, p_est,
                                              due[k] > 0.5, pattern)
            fused.append(ok)
    v_all = ca.vertcat(*values)
    return ca.Function("filter_fusion", [x, Pv, *values, due, n2, p_est],
                       [xs, pattern.pack(P), ca.vertcat(*fused), ca.jacobian(xs, x),
                        ca.jacobian(xs, v_all)],
                       ["x", "P", *(p.name for p in NAV_PACKETS), "due", "n2", "p_est"],
                       ["x_next", "P_next", "fused", "X_x", "X_pkt"])


@functools.cache
def filter_prediction_function(coupling: str) -> ca.Function:
    """``filter_prediction(x, P, a_in, dt, p_est) -> (x_next, P_next, Phi, Gamma)``.

    :func:`~quadland_symbolic.landing.navigation.nav_predict` on the stored entries of
    :func:`covariance_pattern`, and its Jacobians in ``x`` and ``a_in``.
    """
    pattern = covariance_pattern(coupling)
    x, Pv, a_in = NAV.sym("x"), ca.SX.sym("P", pattern.size), ca.SX.sym("a_in", 3)
    dt, p_est = ca.SX.sym("dt"), estimator_params().sym("p_est")
    p = estimator_params().unpack(p_est)                    # a given heave frequency (E17b)
    omega = heave_gate(select(p["heave_in_filter"] > 0.5, p["heave_frequency"], 0),
                       NAV.unpack(x)["p_r"][2], p)
    xn, Pn = nav_predict(x, pattern.unpack(Pv), a_in, dt, p_est, pattern, None, omega)
    return ca.Function("filter_prediction", [x, Pv, a_in, dt, p_est],
                       [xn, pattern.pack(Pn), ca.jacobian(xn, x), ca.jacobian(xn, a_in)],
                       ["x", "P", "a_in", "dt", "p_est"], ["x_next", "P_next", "Phi", "Gamma"])


@functools.cache
def filter_output_function(n_hist: int, depth, coupling: str) -> ca.Function:
    """The flight step's measurement for the controller, from its horizon and its inputs.

    ``filter_output(x_h, hist, imu, mem, p_est, dt, t) -> (y, a_in, Y_x, Y_hist, Y_imu,
    A_imu)``: ``y`` (:data:`LANDING_MEASUREMENT`) as
    :func:`~quadland_symbolic.landing.estimator.estimator_step_function` forms it
    (:func:`~quadland_symbolic.landing.estimator.estimator_output`) when no packet is
    fused: from the horizon state ``x_h``, the input buffer ``hist``
    (:data:`~quadland_symbolic.landing.estimator.HIST_ROWS` by ``n_hist``, oldest first),
    the IMU and the deck's broadcast kept in the memory ``mem``
    (:func:`~quadland_symbolic.landing.estimator.estimator_memory`; ``dt`` is not read);
    ``a_in`` this period's acceleration input (E2) from the IMU; their Jacobians in
    ``x_h``, in ``hist``'s acceleration rows (column-major: ``a_x, a_y, a_z`` of the
    oldest first) and in the IMU.
    """
    lay = estimator_memory(n_hist, depth, coupling)
    x_h, hist, imu = NAV.sym("x_h"), ca.SX.sym("hist", len(HIST_ROWS), n_hist), IMU.sym("imu")
    mem, p_est = lay.sym("mem"), estimator_params().sym("p_est")
    dt, t = ca.SX.sym("dt"), ca.SX.sym("t")
    m = lay.unpack(mem)
    deck = dict(eta2=m["deck_eta2"], w2E=m["deck_w2E"], w2E_dot=m["deck_w2E_dot"],
                tau=m["deck_tau"])
    p = estimator_params().unpack(p_est)
    y = estimator_output(x_h, hist, deck, imu, p_est, t,                 # (E17b)
                         heave_gate(p["heave_frequency"], NAV.unpack(x_h)["p_r"][2], p))
    ims = IMU.unpack(imu)
    a_in = acceleration_input(ims["eta_hat"], ims["f_b"], estimator_params().unpack(p_est)["g"])
    acc = hist[0:3, :]
    return ca.Function("filter_output", [x_h, hist, imu, mem, p_est, dt, t],
                       [y, a_in, ca.jacobian(y, x_h), ca.jacobian(y, ca.vec(acc)),
                        ca.jacobian(y, imu), ca.jacobian(a_in, imu)],
                       ["x_h", "hist", "imu", "mem", "p_est", "dt", "t"],
                       ["y", "a_in", "Y_x", "Y_hist", "Y_imu", "A_imu"])


@functools.cache
def hover_law_function(l: int) -> ca.Function:
    """The landing step's Jacobians in its whole measurement.

    ``hover_law(y, mem, p_ctrl, pm, ref, dt) -> (u, mem_next, Phi_c, Gamma_c, C_c, D_c)``:
    the wrench and next memory of
    :func:`~quadland_symbolic.landing.controller.landing_law` with the controller's
    own model ``pm`` (:data:`LANDING_PLANT_PARAMS`), and ``d mem_next / d (mem, y)``,
    ``d u / d (mem, y)`` with ``y`` all of :data:`LANDING_MEASUREMENT`.
    """
    y, mem = LANDING_MEASUREMENT.sym("y"), landing_memory(l).sym("mem")
    p_ctrl, pm = landing_controller_params(l).sym("p_ctrl"), ca.SX.sym("pm",
                                                                       LANDING_PLANT_PARAMS.size)
    ref, dt = POSITION_REFERENCE.sym("ref"), ca.SX.sym("dt")
    p = LANDING_PLANT_PARAMS.unpack(pm)
    out = landing_law(l, y, ref, mem, p_ctrl, p["p_quad"], p["p_act"], dt)
    u, mn = out["wrench"], out["mem_next"]
    return ca.Function("hover_law", [y, mem, p_ctrl, pm, ref, dt],
                       [u, mn, ca.jacobian(mn, mem), ca.jacobian(mn, y), ca.jacobian(u, mem),
                        ca.jacobian(u, y)],
                       ["y", "mem", "p_ctrl", "pm", "ref", "dt"],
                       ["u", "mem_next", "Phi_c", "Gamma_c", "C_c", "D_c"])


"""A landing scenario as the landing loop's vectors, its clocks and its disturbance."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from quadland.engine.direct_call import DirectCall
from quadland.engine.disturbance import disturbance_samples
from quadland.engine.kept import KEPT, kept_bytes
from quadland.engine.loop import Clock
from quadland.engine.wind import (
    OneCosineGust,
    dryden_low_altitude,
    gust_samples,
    turbulence_samples,
)
from quadland.kinds.landing.gear import gear_params, lock_params, policy_params, touchdown_guidance
from quadland.kinds.landing.sea import deck_components
from quadland.scenario import Scenario, require_model
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.controller import landing_controller_params, landing_memory
from quadland_symbolic.landing.deck import (
    DECK_PARAMS,
    N_DECK,
    N_SEA,
    DeckPose,
    deck_function,
)
from quadland_symbolic.landing.drive import pack_drive
from quadland_symbolic.landing.guidance import APPROACH, GUIDANCE_PARAMS, GUIDANCE_STATE
from quadland_symbolic.landing.loop import (
    gear_gap_function,
    landing_loop_memory,
    landing_loop_params,
)
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["LandingValues", "rotor_force_max", "deck_params", "deck_pose_values",
           "rotation_values", "landing_values", "landing_clocks", "wind_samples",
           "landing_disturbance"]


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
        Controller parameters (``quadland_symbolic.landing.loop.landing_loop_params(l)``);
        its ``pp`` is the controller's own model (``[controller_model]``).
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


def deck_params(scenario: Scenario) -> np.ndarray:
    """``[deck]`` as the deck's parameters ``p_deck`` (:data:`DECK_PARAMS`).

    The explicit sinusoids fill the first slots of each motion (zeros after
    them); at ``sea_state > 0`` the sea's :data:`N_SEA` wave components
    (:func:`quadland.kinds.landing.sea.deck_components`, seeded) fill the
    last ones, added to them. The vehicle's drive profile (``[vehicle]``'s
    ``profile_*``, :func:`~quadland_symbolic.landing.drive.pack_drive`) rides along.
    """
    dk, deg = scenario.data["deck"], np.pi / 180
    sea = deck_components(scenario)
    deck = {}
    for row, (name, scale) in enumerate((("heave", 1.0), ("roll", deg), ("pitch", deg))):
        amp = dk[f"{name}_amplitude" + ("_deg" if name != "heave" else "")]
        parts = {"amp": np.multiply(amp, scale), "freq": np.asarray(dk[f"{name}_frequency"]),
                 "phase": np.multiply(dk[f"{name}_phase_deg"], deg)}
        for part, values in parts.items():
            out = np.zeros(N_DECK)
            out[:len(values)] = values
            if sea is not None:
                out[N_DECK - N_SEA:] = sea.freq if part == "freq" else getattr(sea, part)[row]
            deck[f"{name}_{part}"] = out
    v = scenario.data["vehicle"]
    drive = pack_drive(v["profile_start"], v["profile_duration"], v["profile_speed_change"],
                       np.multiply(v["profile_heading_change_deg"], deg),
                       v["profile_lane_offset"], scenario.data["initial"]["velocity2"][0])
    return DECK_PARAMS.pack(dict(deck, pad_offset=dk["pad_offset"], deck_height=dk["height"],
                                 drive=drive))


@functools.cache
def _deck_call() -> DirectCall:
    return DirectCall(deck_function())


def deck_pose_values(xv, t: float, p_veh, p_deck) -> DeckPose:
    """:func:`~quadland_symbolic.landing.deck.deck_pose` on numbers, each field an array
    (``numpy.asarray`` of the ``casadi.DM`` it gives, the same bits), evaluated on the
    arguments in place (:class:`~quadland.engine.direct_call.DirectCall`)."""
    return DeckPose(*_deck_call()(xv, t, p_veh, p_deck))


def _product(a, b) -> list[list[float]]:
    """``a @ b`` of 3 x 3 lists as CasADi's dense ``mtimes`` sums it: each entry from
    ``0.0`` plus the products in the order of the inner index."""
    return [[((0.0 + a[i][0] * b[0][j]) + a[i][1] * b[1][j]) + a[i][2] * b[2][j]
             for j in range(3)] for i in range(3)]


def rotation_values(eta) -> np.ndarray:
    """:func:`~quadland_symbolic.kinematics.rotation` on numbers, ``(3, 3)``: the same
    sines, cosines, products and sums as its ``casadi.DM`` evaluation (the C library's
    ``sin`` and ``cos``, ``Rz @ Ry @ Rx`` summed as CasADi does, with the explicit zeros),
    so the same bits (``tests/test_run_python.py``), in a thirtieth of its time. An
    infinite angle (whose sine ``math`` refuses) takes the ``casadi.DM`` evaluation."""
    phi, theta, psi = float(eta[0]), float(eta[1]), float(eta[2])
    if math.isinf(phi) or math.isinf(theta) or math.isinf(psi):
        return np.asarray(rotation(np.array([phi, theta, psi])), dtype=float)
    cf, sf = math.cos(phi), math.sin(phi)
    ct, st = math.cos(theta), math.sin(theta)
    cp, sp = math.cos(psi), math.sin(psi)
    Rx = [[1.0, 0.0, 0.0], [0.0, cf, -sf], [0.0, sf, cf]]
    Ry = [[ct, 0.0, st], [0.0, 1.0, 0.0], [-st, 0.0, ct]]
    Rz = [[cp, -sp, 0.0], [sp, cp, 0.0], [0.0, 0.0, 1.0]]
    return np.array(_product(_product(Rz, Ry), Rx))


def rotor_force_max(scenario) -> float:
    """``F_max``, the largest force of one rotor, N: ``thrust_to_weight m1 g / 4``."""
    q = scenario.data["quadrotor"]
    return q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4


def _controller_model(d: dict, p_veh: np.ndarray, p_deck: np.ndarray, gear: dict) -> np.ndarray:
    """The controller's own model as plant parameters: ``[controller_model]``'s mass,
    inertia, drag, motor lag and rotor limit; the geometry (gravity, arm, rotor drag
    factor, gear) and the vehicle's and the deck's parameters (its sensors' models)
    are the plant's; its rotors are whole and its centre of gravity centred."""
    q, cm = d["quadrotor"], d["controller_model"]
    return LANDING_PLANT_PARAMS.pack(dict(
        p_quad=QUADROTOR.pack(dict(
            m1=cm["mass"], I=cm["inertia"], Kt=cm["drag_translational"],
            Kr=cm["drag_rotational"], g=q["gravity"], arm=q["arm_length"],
            c=q["rotor_drag_factor"])),
        p_act=ACTUATOR.pack(dict(
            motor_time_constant=cm["motor_time_constant"],
            F_max=cm["thrust_to_weight"] * cm["mass"] * q["gravity"] / 4,
            gear_height=q["gear_height"], drag_quadratic=cm["drag_quadratic"],
            rotor_radius=q["rotor_radius"], air_density=d["wind"]["air_density"],
            rotor_efficiency=np.ones(4), cg_offset=np.zeros(3))),
        p_veh=p_veh, p_deck=p_deck, **gear))


#: The [landing] keys passed to the guidance's parameters as they are (the commit's
#: withdrawal and lean average, the swerve's hold, the crawl's gate and abort floor).
_PASSED_KEYS = ("withdraw_height", "lean_time", "swerve_accel", "crawl_gate",
                "crawl_gate_time", "crawl_gate_floor", "crawl_gate_wait", "crawl_gate_rise",
                "crawl_gate_wait_height", "abort_floor", "crawl_abort_offset",
                "crawl_gate_count_height", "crawl_abort_budget", "withdraw_budget")


def _commit_keys(g) -> dict:
    """The commit's and the crawl's guidance parameters from the ``[landing]`` table ``g``:
    angles in radians, flags as 0/1, the others (:data:`_PASSED_KEYS`) as they are."""
    return dict(calm_tilt=np.radians(g["calm_tilt_deg"]), calm_lean=np.radians(g["calm_lean_deg"]),
                crawl_pause=float(g["crawl_pause"]), lean_withdraw=float(g["lean_withdraw"]),
                **{k: g[k] for k in _PASSED_KEYS})


def landing_values(scenario: Scenario) -> LandingValues:
    """Translate a validated landing scenario into the landing loop's vectors.

    The quadrotor starts with its rotors at hover thrust, ``m1 g / 4`` each,
    and its velocity ``initial.relative_velocity`` plus the pad's; the
    command filter starts at its initial roll and pitch, the guidance in the
    approach with the reference at the hover point.
    """
    require_model(scenario, "landing", "the landing loop")
    d = scenario.data
    q, v, c, r, g = (d[k] for k in ("quadrotor", "vehicle", "controller", "rbf", "landing"))
    l, deg = r["nodes"], np.pi / 180
    p_quad = QUADROTOR.pack(dict(
        m1=q["mass"], I=q["inertia"], Kt=q["drag_translational"], Kr=q["drag_rotational"],
        g=q["gravity"], arm=q["arm_length"], c=q["rotor_drag_factor"]))
    F_max = rotor_force_max(scenario)
    p_act = ACTUATOR.pack(dict(motor_time_constant=q["motor_time_constant"], F_max=F_max,
                               gear_height=q["gear_height"], drag_quadratic=q["drag_quadratic"],
                               rotor_radius=q["rotor_radius"],
                               air_density=d["wind"]["air_density"],
                               rotor_efficiency=q["rotor_efficiency"], cg_offset=q["cg_offset"]))
    p_veh = VEHICLE.pack(dict(m11=v["m11"], m22=v["m22"], m33=v["m33"], d11=v["d11"],
                              d22=v["d22"], d33=v["d33"], tau=v["tau"], z2=0.0))
    p_deck = deck_params(scenario)
    gear = dict(p_gear=gear_params(scenario), p_lock=lock_params(scenario),
                p_td=policy_params(scenario))
    pp = LANDING_PLANT_PARAMS.pack(dict(p_quad=p_quad, p_act=p_act, p_veh=p_veh, p_deck=p_deck,
                                        **gear))
    model = _controller_model(d, p_veh, p_deck, gear)

    centers = np.linspace(r["center_min"], r["center_max"], l) if l > 1 else \
        np.array([(r["center_min"] + r["center_max"]) / 2])
    lay = landing_controller_params(l)
    p_ctrl = lay.pack(dict(
        k1p=c["k1p"], k2p=c["k2p"], k1=c["k1"], k2=c["k2"], gamma1=c["gamma1"],
        gamma2=c["gamma2"], k_w=c["k_w"], k_zeta=c["k_zeta"], rho=c["rho"],
        nominal_model=float(c["nominal_model"]), w_f=c["filter_frequency"],
        zeta_f=c["filter_damping"], tilt_max=c["tilt_max_deg"] * deg,
        ki_p=c["ki_p"], ki=c["ki"], d_max_p=c["bias_max_p"], d_max=c["bias_max"],
        r_learn=c["bias_radius"], w_o=c["observer_frequency"],
        centers=np.tile(centers, (lay["centers"].shape[0], 1)), widths=np.full(l, r["width"])))
    p_guid = GUIDANCE_PARAMS.pack(dict(
        hover_height=g["hover_height"], align_radius=g["align_radius"],
        dwell_time=g["dwell_time"], descent_speed=g["descent_speed"],
        descent_time=g["descent_time"], touchdown_speed=g["touchdown_speed"],
        touchdown_height=q["gear_height"], max_offset=g["max_offset"],
        max_relative_speed=g["max_relative_speed"], max_deck_rise=g["max_deck_rise"],
        settle_time=g["settle_time"], marker_timeout=g["marker_timeout"],
        search_height=g["search_height"], commit_height=g["commit_height"],
        commit_horizon=g["commit_horizon"], calm_speed=g["calm_speed"],
        motion_time=g["motion_time"], descent_leash=g["descent_leash"],
        leash_height=g["leash_height"], **_commit_keys(g), **touchdown_guidance(scenario)))
    rate = c["rate_hz"]
    pc = landing_loop_params(l).pack(dict(pp=model, p_ctrl=p_ctrl, p_guid=p_guid, dt=1.0 / rate))

    init = d["initial"]
    (x2, y2), (u2, v2) = init["position2"], init["velocity2"]
    xv = VEHICLE_STATE.pack(dict(x2=x2, y2=y2, psi2=init["psi2_deg"] * deg, u2=u2, v2=v2,
                                 r2=init["r2_deg_s"] * deg))
    v_pad = np.asarray(deck_pose_values(xv, 0.0, p_veh, p_deck).v2E, dtype=float).ravel()
    eta1 = np.multiply(init["eta1_deg"], deg)
    V1 = rotation_values(eta1).T @ (v_pad + np.asarray(
        init["relative_velocity"]))
    x1q = QUAD6_STATE.pack(dict(
        p1=[*init["position1"], init["z1"]], eta1=eta1, V1=V1,
        Omega1=np.multiply(init["omega1_deg_s"], deg),
        F=np.full(4, q["mass"] * q["gravity"] / 4)))
    xp0 = _cleared(LANDING_PLANT_STATE.pack(dict(x1q=x1q, xv=xv, gear=np.zeros(3))), pp,
                   init["handover_clearance"])
    mem = landing_memory(l).zeros()
    mem[landing_memory(l).slice("eta_f")] = eta1[:2]
    xg = GUIDANCE_STATE.pack(dict(phase=APPROACH, timer=0.0, z_ref=g["hover_height"],
                                  aborts=0.0, committed=0.0, armed=0.0, ms_rise=0.0,
                                  ms_rise_rate=0.0, ms_tilt_rate=0.0, ms_tilt_acc=0.0,
                                  lean_x=0.0, lean_y=0.0, lean_gust=0.0))
    xc0 = landing_loop_memory(l).pack(dict(xg=xg, mem=mem))
    return LandingValues(l, pp, pc, xp0, xc0, F_max)


def _cleared(xp0: np.ndarray, pp: np.ndarray, clearance: float) -> np.ndarray:
    """The plant's initial state ``xp0`` with the quadrotor raised along E's z until its
    gear is ``clearance`` above the deck plane at t = 0, where it is lower (a clearance of
    0 returns ``xp0`` itself). The gear's gap is linear in the altitude, ``n2 . (p1 - ...)``,
    so one step of ``(clearance - gap) / n2_z`` lands on it (``n2_z`` the deck normal's
    vertical component, ``cos`` of the deck's tilt)."""
    if clearance <= 0:
        return xp0
    gap = float(gear_gap_function()(xp0, 0.0, pp))
    if gap >= clearance:
        return xp0
    p = LANDING_PLANT_PARAMS.unpack(pp)
    xv = LANDING_PLANT_STATE.unpack(xp0)["xv"]
    n2_z = float(deck_pose_values(xv, 0.0, p["p_veh"], p["p_deck"]).R_deck[2, 2])
    z1 = LANDING_PLANT_STATE.slice("x1q").start + QUAD6_STATE.slice("p1").start + 2
    out = np.array(xp0, dtype=float, copy=True)
    out[z1] += (clearance - gap) / n2_z
    return out


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
    independent of the disturbance's. Within :func:`quadland.engine.kept.keeping` (an
    envelope's runs), the turbulence's normals (the seed's and the sample count's) and
    the gust (its settings' and the times') are kept for the next run of the same; the
    turbulence's filter (the airspeed: the velocities and ``wind.mean``) and the sums
    are computed each run.
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
    seed = d["simulation"]["seed"]
    gust = gust_v = None
    if w["gust_amplitude"] > 0:
        gust = OneCosineGust(w["gust_start"], w["gust_half_length"], w["gust_amplitude"],
                             tuple(w["gust_direction"]))
    if kept_bytes():
        normals = KEPT.shared(("wind normals", seed, len(times)), lambda: np.random.default_rng(
            (seed, 1)).standard_normal((len(times), 3)))
        turb = turbulence_samples(turbulence, times, normals=normals)
        if gust is not None:
            times = np.ascontiguousarray(times)
            gust_v = KEPT.shared(("gust", repr(gust), times.tobytes()),
                                 lambda: gust_samples(gust, times))
    else:
        turb = turbulence_samples(turbulence, times, np.random.default_rng((seed, 1)))
        gust_v = None if gust is None else gust_samples(gust, times)
    out = np.asarray(w["mean"], dtype=float)[:, None] + turb
    if gust is not None:
        out = out + gust_v
    return out


def landing_disturbance(scenario: Scenario, times: np.ndarray) -> np.ndarray:
    """The landing loop's held disturbance at ``times``, ``(9, n)``: wind (E), d_F, d_M (body).

    ``d_F``, ``d_M`` are ``[disturbance]``'s, drawn as for the paper's loop
    (:func:`quadland.engine.disturbance.disturbance_samples`); within
    :func:`quadland.engine.kept.keeping` (an envelope's runs), those of a run's seed,
    ``[disturbance]`` and ``times`` are kept for the next run of the same (of the wind,
    its turbulence's normals and its gust, :func:`wind_samples`).
    """
    if not kept_bytes():
        return np.vstack([wind_samples(scenario, times), disturbance_samples(scenario, times)])
    # an envelope's: the force and moment noise of the run's seed and [disturbance], kept
    times = np.ascontiguousarray(times, dtype=float)
    key = ("disturbance", scenario.data["simulation"]["seed"],
           repr(sorted(scenario.data["disturbance"].items())), times.tobytes())
    return np.vstack([wind_samples(scenario, times),
                      KEPT.shared(key, lambda: disturbance_samples(scenario, times))])



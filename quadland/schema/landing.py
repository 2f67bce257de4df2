"""The schema of the 6-DOF landing loop (``scenario.model = "landing"``)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from types import MappingProxyType

from quadland.exceptions import ScenarioError
from quadland.schema.fields import MAX_DURATION_S, MAX_RATE_HZ, Field, tilt_within
from quadland.schema.guidance import GUIDANCE_FIELDS
from quadland.schema.paper import PAPER_SCHEMA, check_rbf
from quadland.schema.sea_state import SEA_STATES
from quadland.schema.sensors import check_sensor_timing, sensor_fields
from quadland.schema.touchdown import TOUCHDOWN_FIELDS
from quadland_symbolic.landing.deck import N_SINES
from quadland_symbolic.landing.drive import N_LEGS, pack_drive, planned_speed_change
from quadland_symbolic.landing.land_detector import LAND_DETECTOR_PARAMS
from quadland_symbolic.landing.navigation import BLOCKS, estimator_params
from quadland_symbolic.landing.sensors import SENSOR_NAMES
from quadland_symbolic.loop import MAX_DELAY_PERIODS

__all__ = ["LANDING_SCHEMA", "check_landing"]

_POS = dict(lo=0.0, lo_open=True)
#: [estimator] keys that must be positive, as the flight code's parameter check has them
#: (quadland_symbolic.codegen.estimator_api.ESTIMATOR_PARAM_RANGES; a test keeps the two
#: equal): a zero density or sigma makes a covariance or an innovation variance singular,
#: a zero gate refuses every measurement, the tilt bias decays as exp(-dt / tilt_tau).
_ESTIMATOR_POSITIVE = ("q_acc", "q_at", "q_b", "q_ab", "vision_sigma0", "tilt_tau",
                       "gnss_rel_sigma", "gnss_v1_sigma", "gnss_vt_sigma", "range_sigma",
                       "range_min_cos", "range_deck_radius", "datalink_v_sigma", "datalink_a_sigma",
                       *(f"gate_{b.name}" for b in BLOCKS))
#: [estimator] keys with an upper bound of their own: the range model divides by
#: ``n2 . b3_E`` once it is at least ``range_min_cos``, a cosine in (0, 1].
_ESTIMATOR_HI = {"range_min_cos": 1.0, "tilt_levels_bias": 1.0, "heave_in_filter": 1.0}
#: [estimator] keys added after the shipped scenarios, with the defaults that fly as before:
#: the tilt apart from the accelerometer's bias (E2b), the pad's heave not in the prediction
#: (E17b).
_ESTIMATOR_ADDED = {"tilt_levels_bias": [0.0, 0.0, 0.0], "heave_frequency": 0.0,
                    "heave_in_filter": 0.0, "heave_height": 1.0e6}


def _sines(name: str, unit: str, what: str, amp_hi: float) -> dict[str, Field]:
    """The three keys of one prescribed deck motion: up to N_SINES sinusoids."""
    amp = f"{name}_amplitude" + ("_deg" if unit == "deg" else "")
    return {
        amp: Field(float, unit, f"{what} amplitudes a_i of sum a_i sin(w_i t + phase_i)",
                   N_SINES, min_length=1, lo=0.0, hi=amp_hi),
        f"{name}_frequency": Field(float, "rad/s", f"{what} frequencies w_i", N_SINES,
                                   min_length=1, lo=0.0, hi=100.0),
        f"{name}_phase_deg": Field(float, "deg", f"{what} phases", N_SINES, min_length=1,
                                   lo=-3600.0, hi=3600.0),
    }


def _profile() -> dict[str, Field]:
    """The drive profile's keys of [vehicle] (docs/landing.md, "Cars that drive"): one
    value per leg, up to N_LEGS legs, the legs' effects adding up."""
    def leg(unit, doc, lo, hi, **kw):
        return Field(float, unit, doc, N_LEGS, min_length=1, lo=lo, hi=hi, **kw)
    return {
        "profile_start": leg("s", "time each leg starts", 0.0, MAX_DURATION_S),
        "profile_duration": leg("s", "each leg's duration T", 0.0, 1e3, lo_open=True),
        "profile_speed_change": leg("m/s", "surge speed change (raised-cosine acceleration, "
                                    "peak 2 dv / T)", -100.0, 100.0),
        "profile_heading_change_deg": leg("deg", "heading change (raised-cosine yaw rate), "
                                          "positive to the left", -360.0, 360.0),
        "profile_lane_offset": leg("m", "lane change: sideways offset (sinusoidal yaw rate "
                                   "over the leg), positive to the left", -100.0, 100.0),
    }


def _sea() -> dict[str, Field]:
    """The sea state's keys of [deck] (docs/sea.md): the waves and the vessel's response."""
    return {
        "sea_state": Field(int, "-", "WMO sea state code: 1 to 6 add that sea's wave components "
                           "to the sinusoids; 0: the sinusoids alone", lo=0, hi=max(SEA_STATES)),
        "significant_wave_height": Field(float, "m", "Hs (0: the sea state's most probable); "
                                         "within the sea state's WMO band", lo=0.0, hi=20.0),
        "peak_period": Field(float, "s", "Tp, the spectrum's peak period (0: the sea state's most "
                             "probable)", lo=1.0, hi=30.0, zero_ok=True),
        "peak_enhancement": Field(float, "-", "JONSWAP's gamma: 1 is Pierson-Moskowitz, 3.3 "
                                  "JONSWAP's mean", lo=1.0, hi=10.0),
        "wave_heading_deg": Field(float, "deg", "the waves' direction of travel from the bow "
                                  "toward port: 180 head seas, 0 following, 90 from starboard",
                                  lo=-360.0, hi=360.0),
        "vessel_length": Field(float, "m", "waterline length: the hull averages the waves over it",
                               hi=1e3, **_POS),
        "vessel_beam": Field(float, "m", "waterline breadth", hi=1e3, **_POS),
        "roll_period": Field(float, "s", "natural roll period", hi=100.0, **_POS),
        "roll_damping": Field(float, "-", "roll damping ratio (linearized)", hi=2.0, **_POS),
    }


F, I, B, S = float, int, bool, str
#: The landing scenario schema (``scenario.model = "landing"``): the 6-DOF
#: loop of ``quadland_symbolic.landing`` with guidance, motor lag, rotor limits, the
#: sampled step, a moving deck and wind (docs/landing.md).
_THRUST_TO_WEIGHT = Field(F, "-", "4 F_max / (m1 g): sets the rotor limit F_max", lo=1.0,
                          hi=20.0, lo_open=True)
_DRAG_QUADRATIC = Field(F, "N s^2/m^2", "quadratic (bluff-body) drag Kq1..Kq3 on the airspeed, "
                        "body axes", 3, lo=0.0, hi=1e3)
_MOTOR_TIME_CONSTANT = Field(F, "s", "first-order lag of each rotor force", lo=1e-3, hi=1.0)

LANDING_SCHEMA: Mapping[str, Mapping[str, Field]] = MappingProxyType({
    "scenario": {
        **PAPER_SCHEMA["scenario"],
        "model": Field(S, "-", "the loop simulated", choices=("landing",)),
    },
    "simulation": {
        "duration": PAPER_SCHEMA["simulation"]["duration"],
        "output_rate_hz": PAPER_SCHEMA["simulation"]["output_rate_hz"],
        "rk_steps_per_interval": Field(I, "-", "RK4 steps per hold interval", lo=1, hi=1000),
        "seed": PAPER_SCHEMA["simulation"]["seed"],
    },
    "quadrotor": {
        **{k: PAPER_SCHEMA["quadrotor"][k] for k in ("mass", "inertia", "drag_translational",
                                               "drag_rotational", "gravity", "arm_length",
                                               "rotor_drag_factor")},
        "thrust_to_weight": _THRUST_TO_WEIGHT,
        "motor_time_constant": _MOTOR_TIME_CONSTANT,
        "gear_height": Field(F, "m", "landing gear's lowest point below the centre", lo=0.0,
                             hi=10.0),
        "drag_quadratic": _DRAG_QUADRATIC,
        "rotor_radius": Field(F, "m", "rotor radius R of the ground effect (Cheeseman-Bennett; "
                              "0: none)", lo=0.0, hi=10.0),
        "rotor_efficiency": Field(F, "-", "force each rotor makes per newton commanded (1: as "
                                  "the controller models it; a damaged rotor less)", 4, lo=0.0,
                                  hi=2.0),
        "cg_offset": Field(F, "m", "centre of gravity from the rotors' centre, body axes (the "
                           "controller assumes it centred)", 3, lo=-1.0, hi=1.0),
    },
    "vehicle": {**{k: PAPER_SCHEMA["vehicle"][k] for k in ("m11", "m22", "m33", "d11", "d22",
                                                     "d33", "tau")},
                **_profile()},
    "deck": {
        "height": Field(F, "m", "altitude of the vehicle's reference point (the centre of roll "
                        "and pitch) at zero heave", lo=-1e4, hi=1e4),
        "pad_offset": Field(F, "m", "pad centre from the reference point, deck frame (x "
                            "forward, z up)", 3, lo=-1e3, hi=1e3),
        **_sines("heave", "m", "heave", 100.0),
        **_sines("roll", "deg", "roll", 45.0),
        **_sines("pitch", "deg", "pitch", 45.0),
        **_sea(),
    },
    "initial": {
        "position1": Field(F, "m", "quadrotor x1, y1 in E", 2, lo=-1e7, hi=1e7),
        "z1": Field(F, "m", "quadrotor altitude in E", lo=-1e4, hi=1e4),
        "eta1_deg": Field(F, "deg", "roll, pitch, yaw", 3, lo=-3600.0, hi=3600.0,
                          check=tilt_within(60.0)),
        "omega1_deg_s": PAPER_SCHEMA["initial"]["omega1_deg_s"],
        "relative_velocity": Field(F, "m/s", "quadrotor velocity in E minus the pad's "
                                   "(0: moving with the pad)", 3, lo=-1e3, hi=1e3),
        "position2": PAPER_SCHEMA["initial"]["position2"],
        "psi2_deg": PAPER_SCHEMA["initial"]["psi2_deg"],
        "r2_deg_s": PAPER_SCHEMA["initial"]["r2_deg_s"],
        "velocity2": PAPER_SCHEMA["initial"]["velocity2"],
        "handover_clearance": Field(F, "m", "gear point's least height over the deck plane "
                                    "at t = 0 (0: as drawn)", lo=0.0, hi=1e3, default=0.0),
    },
    "controller": {
        "k1p": Field(F, "1/s", "outer k1: deck-frame x, y, z", 3, hi=1e3, **_POS),
        "k2p": Field(F, "1/s", "outer k2: deck-frame x, y, z", 3, hi=1e3, **_POS),
        "k1": Field(F, "1/s", "inner k1: roll, pitch, yaw", 3, hi=1e3, **_POS),
        "k2": Field(F, "1/s", "inner k2: roll, pitch, yaw", 3, hi=1e3, **_POS),
        "ki_p": Field(F, "1/s^2", "outer bias adaptation (integral action): deck-frame x, y, z; "
                      "0: none", 3, lo=0.0, hi=1e3),
        "ki": Field(F, "1/s", "inner bias adaptation (integral action): roll, pitch, yaw; 0: none",
                    3, lo=0.0, hi=1e3),
        "bias_max_p": Field(F, "m/s^2", "projection bound of each outer bias estimate", lo=0.0,
                            hi=1e3),
        "bias_max": Field(F, "rad/s^2", "projection bound of each inner bias estimate", lo=0.0,
                          hi=1e4),
        "bias_radius": Field(F, "m", "x, y's outer bias estimates learn only within this "
                             "horizontal error; 0: always", lo=0.0, hi=1e3, default=0.0),
        "observer_frequency": Field(F, "rad/s", "disturbance observer bandwidth (its double "
                                    "pole): deck-frame x, y, z; 0: none", 3, lo=0.0, hi=1e3),
        **{k: PAPER_SCHEMA["controller"][k] for k in ("gamma1", "gamma2", "k_w", "k_zeta", "rho",
                                                "nominal_model")},
        "filter_frequency": Field(F, "rad/s", "command filter w_f", hi=1e4, **_POS),
        "filter_damping": Field(F, "-", "command filter zeta_f", hi=10.0, **_POS),
        "tilt_max_deg": Field(F, "deg", "largest tilt the outer loop commands", lo=1.0, hi=80.0),
        "rate_hz": Field(F, "Hz", "control rate of the sampled step", lo=1.0, hi=MAX_RATE_HZ),
        "backend": PAPER_SCHEMA["controller"]["backend"],
        "delay_periods": Field(I, "-", "computation delay: the rotor commands computed at one "
                               "step act from the delay_periods-th next step on",
                               lo=0, hi=MAX_DELAY_PERIODS),
    },
    # The controller's own model of the quadrotor: what its law assumes (the plant is
    # [quadrotor]). A campaign's dispersions of [quadrotor] leave it at its nominal.
    "controller_model": {
        k: dataclasses.replace(f, doc=f"the controller's model: {f.doc}")
        for k, f in (("mass", PAPER_SCHEMA["quadrotor"]["mass"]),
                     ("inertia", PAPER_SCHEMA["quadrotor"]["inertia"]),
                     ("drag_translational", PAPER_SCHEMA["quadrotor"]["drag_translational"]),
                     ("drag_rotational", PAPER_SCHEMA["quadrotor"]["drag_rotational"]),
                     ("drag_quadratic", _DRAG_QUADRATIC),
                     ("thrust_to_weight", _THRUST_TO_WEIGHT),
                     ("motor_time_constant", _MOTOR_TIME_CONSTANT))},
    "rbf": PAPER_SCHEMA["rbf"],
    "landing": GUIDANCE_FIELDS,
    # The landing gear on the deck (docs/contact.md): four feet at (+-feet_x, +-feet_y,
    # -quadrotor.gear_height) in the body frame.
    "gear": {
        "welded": Field(B, "-", "true: the idealization of a touchdown that ends the flight at "
                        "the gear gap's zero crossing, the quadrotor then pinned to the deck; "
                        "false: the gear's contact carries it"),
        "feet_x": Field(F, "m", "the feet's distance from the centre along body x (half the "
                        "skids' length)", hi=10.0, **_POS),
        "feet_y": Field(F, "m", "the feet's distance from the centre along body y (half the "
                        "track)", hi=10.0, **_POS),
        "stiffness": Field(F, "N/m", "normal stiffness of one foot", hi=1e7, **_POS),
        "damping": Field(F, "N s/m", "normal damping of one foot", lo=0.0, hi=1e5),
        "friction": Field(F, "-", "Coulomb friction coefficient of a foot on the deck", lo=0.0,
                          hi=2.0),
        "slip_speed": Field(F, "m/s", "friction's regularisation speed at light loads",
                            hi=1.0, **_POS),
        "slip_damping_max": Field(F, "N s/m", "largest friction slope of a foot at zero slip",
                                  hi=1e5, **_POS),
        "onset_width": Field(F, "m", "smoothing width of the contact's onset", hi=0.01, **_POS),
    },
    # What happens once the gear touches (docs/landing.md, "Touchdown policy").
    "touchdown": TOUCHDOWN_FIELDS,
    # What the aircraft can know (docs/sensors.md): false flies on the true state.
    "sensors": {
        "enabled": Field(B, "-", "true: the controller flies on the sensors and the navigation "
                         "filter; false: on the true state, at once"),
        "random": Field(B, "-", "false: the world's draws are zero (no noise, biases, "
                        "dropouts or outliers; the filter starts at the truth)"),
    },
    **{f"sensors.{name}": sensor_fields(name) for name in SENSOR_NAMES},
    # The navigation filter's own tuning (docs/estimator.md): what it assumes of the
    # sensors. A campaign's dispersions of [sensors.*] leave it at its nominal.
    "estimator": {
        **{f.name: Field(F, f.unit if isinstance(f.unit, str) else f.unit[0], f.doc,
                         f.size if f.size > 1 else None, lo=0.0,
                         hi=_ESTIMATOR_HI.get(f.name, 1e6),
                         lo_open=f.name in _ESTIMATOR_POSITIVE,
                         default=_ESTIMATOR_ADDED.get(f.name))
           for f in estimator_params().fields if f.name != "g"},
        **{f"p0_{name}": Field(F, unit, f"initial standard deviation of {what}, per axis",
                               3, lo=0.0, hi=1e4)
           for name, unit, what in (
               ("position", "m", "the relative position"),
               ("velocity", "m/s", "the quadrotor's velocity"),
               ("target_velocity", "m/s", "the pad's velocity"),
               ("target_acceleration", "m/s^2", "the pad's acceleration"),
               ("bias", "m", "the relative GNSS bias"),
               ("input_bias", "m/s^2", "the accelerometer's bias in the acceleration input"),
               ("tilt_bias", "m/s^2", "the acceleration input's bias from the attitude "
                "estimate's tilt error"))},
        "handover_velocity": Field(S, "-", "the quadrotor's velocity at the handover: gnss: "
                                   "the GNSS's (its error drawn at sensors.gnss."
                                   "velocity_sigma, as EKF2 resets its velocity to the "
                                   "GNSS); p0: the truth plus a draw from p0_velocity (a "
                                   "cold start)", choices=("gnss", "p0"), default="p0"),
        "handover_lockout_gnss": Field(F, "-", "refusals after which a GNSS block not yet "
                                       "fused since the handover is re-admitted (E8a), 0: "
                                       "gate_lockout's as for any block", lo=0.0, hi=1e6,
                                       default=0.0),
    },
    # The flight code's land detector (docs/land_detector.md): its cues' thresholds and
    # windows. Only the sensed loop has it; on the true state the touchdown is the gap's.
    "land_detector": {**{
        name: Field(F, unit, LAND_DETECTOR_PARAMS[name].doc, lo=lo, hi=hi,
                    **({"lo_open": True} if name == "accel_tau" else {}))
        for name, unit, lo, hi in (
            ("gap_max", "m", 0.0, 100.0), ("vz_max", "m/s", 0.0, 100.0),
            ("thrust_low", "-", 0.0, 10.0), ("contact_time", "s", 0.0, 1e3),
            ("maybe_time", "s", 0.0, 1e3), ("landed_time", "s", 0.0, 1e3),
            ("hold_factor", "-", 1.0, 100.0), ("no_range_factor", "-", 1.0, 100.0),
            ("range_timeout", "s", 0.0, 1e3), ("spike_min", "m/s^2", 0.0, 1e3),
            ("spike_window", "s", 0.0, 1e3), ("accel_tau", "s", 0.0, 1e3))},
        "contact_thrust": Field(B, "-", "true: ground contact also needs the thrust at or "
                                "below thrust_low (a hover near the deck is no contact)",
                                default=False)},
    "disturbance": PAPER_SCHEMA["disturbance"],
    "wind": {
        "mean": Field(F, "m/s", "steady wind in E", 3, lo=-100.0, hi=100.0),
        "turbulence_w20": Field(F, "m/s", "Dryden turbulence: wind speed at 20 ft (0: none)",
                                lo=0.0, hi=50.0),
        "gust_amplitude": Field(F, "m/s", "1-cosine gust peak v_m (0: none)", lo=0.0,
                                hi=100.0),
        "gust_start": Field(F, "s", "gust start t0", lo=0.0, hi=MAX_DURATION_S),
        "gust_half_length": Field(F, "s", "gust build-up time d", hi=1e3, **_POS),
        "gust_direction": Field(F, "-", "gust direction in E (normalized)", 3, lo=-1.0,
                                hi=1.0),
        "air_density": Field(F, "kg/m^3", "air density rho (the ground effect's induced "
                             "velocity)", lo=0.1, hi=2.0),
    },
})
del F, I, B, S


def check_landing(data: dict) -> None:
    """The landing schema's cross-key rules."""
    check_rbf(data)
    deck = data["deck"]
    for name in ("heave", "roll", "pitch"):
        keys = [k for k in deck if k.startswith(f"{name}_") and
                k.endswith(("_amplitude", "_amplitude_deg", "_frequency", "_phase_deg"))]
        if len({len(deck[k]) for k in keys}) != 1:
            raise ScenarioError(f"deck.{keys[1]}: must have as many values as deck.{keys[0]}")
    _check_sea(deck)
    _check_profile(data)
    wind = data["wind"]
    if wind["gust_amplitude"] > 0 and not any(wind["gust_direction"]):
        raise ScenarioError("wind.gust_direction: must not be all zero when "
                            "wind.gust_amplitude > 0")
    check_sensor_timing(data)
    guidance = data["landing"]
    if guidance["touchdown_speed"] > guidance["descent_speed"]:
        raise ScenarioError("landing.touchdown_speed: must be <= landing.descent_speed")
    if guidance["hover_height"] <= data["quadrotor"]["gear_height"]:
        raise ScenarioError("landing.hover_height: must be above quadrotor.gear_height")
    _check_gear(data)
    if guidance["search_height"] < guidance["hover_height"]:
        raise ScenarioError("landing.search_height: must be at or above landing.hover_height "
                            "(the search for the marker climbs)")
    vision_period = 1.0 / data["sensors.vision"]["rate_hz"]
    if guidance["marker_timeout"] < vision_period:
        raise ScenarioError(f"landing.marker_timeout: must be at least one camera period "
                            f"(1 / sensors.vision.rate_hz = {vision_period:g} s), got "
                            f"{guidance['marker_timeout']:g}: the descent could never start")
    lockout = data["estimator"]["gate_lockout"]
    if lockout < 1 or lockout != int(lockout):
        raise ScenarioError(f"estimator.gate_lockout: must be a whole number of refusals >= 1, "
                            f"got {lockout:g}")
    if data["estimator"]["handover_velocity"] == "gnss" and \
            data["sensors.gnss"]["dropout"] >= 1.0:
        raise ScenarioError("estimator.handover_velocity: gnss needs a GNSS velocity, but "
                            "sensors.gnss.dropout = 1 loses every sample; use p0")
    k = data["estimator"]["handover_lockout_gnss"]
    if k != int(k) or k > lockout:
        raise ScenarioError(f"estimator.handover_lockout_gnss: must be a whole number of "
                            f"refusals from 0 to gate_lockout ({lockout:g}), got {k:g}")


def _check_gear(data: dict) -> None:
    """The gear's contact needs a positive gear height; a friction of 0 is allowed; the
    landing area holds the first contact's offset limit (by the centre, and by every foot
    unless welded: "on the pad" is judged by the feet); the rotors' idle command is within
    their force ``F_max``."""
    g = data["landing"]
    if g["pad_radius"] < g["max_offset"]:
        raise ScenarioError(f"landing.pad_radius: {g['pad_radius']:g} m is smaller than "
                            f"landing.max_offset ({g['max_offset']:g} m): a first contact "
                            "within the limit would already be off the pad")
    feet = math.hypot(data["gear"]["feet_x"], data["gear"]["feet_y"])
    if not data["gear"]["welded"] and g["pad_radius"] < g["max_offset"] + feet:
        raise ScenarioError(f"landing.pad_radius: {g['pad_radius']:g} m is smaller than "
                            f"landing.max_offset plus the gear's corner (hypot(gear.feet_x, "
                            f"gear.feet_y) = {feet:g} m): a first contact within the limit "
                            "could already put a foot off the pad")
    if not data["gear"]["welded"] and data["quadrotor"]["gear_height"] <= 0:
        raise ScenarioError("quadrotor.gear_height: must be positive for the gear's contact "
                            "(the feet's depth below the centre; gear.welded = true takes none)")
    q, idle = data["quadrotor"], data["touchdown"]["idle_thrust"]
    f_max = q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4
    if idle > f_max:
        raise ScenarioError(f"touchdown.idle_thrust: {idle:g} N is more than a rotor's F_max "
                            f"(quadrotor.thrust_to_weight x mass x gravity / 4 = {f_max:g} N): "
                            "the rotors could not give it")


def _check_profile(data: dict) -> None:
    """The profile's lists are as long as each other; the planned speed stays forward."""
    v = data["vehicle"]
    keys = [k for k in v if k.startswith("profile_")]
    if len({len(v[k]) for k in keys}) != 1:
        raise ScenarioError(f"vehicle.{keys[1]}: must have as many values as vehicle.{keys[0]} "
                            "(one per leg of the drive profile)")
    u0 = data["initial"]["velocity2"][0]
    try:
        p = pack_drive(v["profile_start"], v["profile_duration"], v["profile_speed_change"],
                       [0.0] * len(v["profile_start"]), v["profile_lane_offset"], u0)
    except ValueError as e:
        raise ScenarioError(f"vehicle.profile_lane_offset: {e}") from None
    for start, T in zip(v["profile_start"], v["profile_duration"], strict=True):
        u = u0 + planned_speed_change(start + T, p)
        if u < 0:
            raise ScenarioError(f"vehicle.profile_speed_change: the planned speed falls to "
                                f"{u:g} m/s by t = {start + T:g} s: the profile drives forward "
                                f"(initial.velocity2 = {u0:g} m/s)")


def _check_sea(deck: dict) -> None:
    """A significant wave height given lies in its sea state's WMO band."""
    hs, code = deck["significant_wave_height"], deck["sea_state"]
    if code == 0 or hs == 0:
        return
    lo, hi = SEA_STATES[code].hs_band
    if not lo <= hs <= hi:
        raise ScenarioError(f"deck.significant_wave_height: {hs:g} m is outside sea state "
                            f"{code}'s band, {lo:g} to {hi:g} m (WMO; 0 takes its most probable "
                            f"{SEA_STATES[code].hs:g} m)")

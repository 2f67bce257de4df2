"""The landing's sensors as truth models: what the aircraft knows.

Each sensor is one named CasADi Function
``sense_<name>(xp, uh, w, t, pp, p_sens, noise) -> y``: the packet ``y`` the
sensor delivers, computed from the true plant state ``xp``
(:data:`~quadland_symbolic.landing.plant.LANDING_PLANT_STATE`) at its sample time ``t``, the
held rotor commands ``uh`` (:data:`~quadland_symbolic.landing.quadrotor.COMMAND`), the
loop's disturbance ``w`` (:data:`~quadland_symbolic.landing.loop.LANDING_DISTURBANCE`), the
plant's parameters ``pp``, the sensors' constants ``p_sens``
(:data:`SENSOR_PARAMS`) and a noise vector drawn outside (one layout per
sensor), so that every Function is deterministic; a zero noise vector gives
the exact truth. The random parts (Gauss-Markov and random-walk processes,
dropouts, outliers) are drawn by :mod:`quadland.kinds.landing.sensing`; latency and
delivery are the simulator's. docs/sensors.md gives each model, its
equations and every default with its source.

Packets (:data:`SENSOR_PACKETS`):

* **imu** (:data:`IMU_PACKET`): the attitude estimate
  ``eta_hat = eta1 + e_att``, the accelerometer's specific force
  ``f_b = R1^T (a1 - g_vec) + b_a + n_a`` with ``g_vec = [0, 0, -g]`` and
  ``a1 = p1'' = R1 (V1' + Omega1 x V1)`` from the plant's own right-hand
  side, and the gyro ``omega = Omega1 + b_g + n_g``.
* **vision** (:data:`VISION_PACKET`): a downward camera at the body origin,
  looking along ``-b3``, detects a marker at the pad centre; the body-frame
  vector ``d_b = R1^T (p2 - p1)`` with noise of standard deviation
  ``sigma0 + k |d|`` per axis and an outlier offset, rotated to E with the
  attitude estimate at capture: ``r_E = R(eta1 + e_att) (d_b + ...)``.
  ``valid`` is 1 inside the field of view (a cone of half-angle
  ``vision_half_angle`` around ``-b3``) and a marker's range interval.
* **gnss** (:data:`GNSS_PACKET`): ``rel = (p2 + e_t) - (p1 + e_q)`` with each
  receiver's own slowly varying error, and both velocities with white noise.
* **rangefinder** (:data:`RANGEFINDER_PACKET`): the distance along ``-b3``
  to the first surface: the deck plane within its extent, else the ground or
  sea at ``z = 0``; and ``b3`` in E from the attitude estimate.
* **datalink** (:data:`DATALINK_PACKET`): the vehicle's broadcast of its deck
  attitude, velocity, acceleration, angular rate and angular acceleration,
  truth plus the vehicle INS's white noise.
"""

from __future__ import annotations

import functools
from types import MappingProxyType

import casadi as ca

from quadland_symbolic.kinematics import rotation, skew
from quadland_symbolic.landing.deck import DECK_POSE, deck_pose
from quadland_symbolic.landing.navigation import NAV
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from quadland_symbolic.landing.quadrotor import COMMAND, QUAD6_STATE
from quadland_symbolic.landing.relative import relative6
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR

__all__ = ["measurement_function", "SENSOR_NAMES", "SENSOR_PARAMS", "IMU_PACKET",
           "VISION_PACKET", "GNSS_PACKET", "RANGEFINDER_PACKET", "DATALINK_PACKET", "IMU_NOISE",
           "VISION_NOISE", "GNSS_NOISE", "RANGEFINDER_NOISE", "DATALINK_NOISE", "SENSOR_PACKETS",
           "NOISES", "specific_force", "rangefinder_distance", "sense_imu_function",
           "sense_vision_function", "sense_gnss_function", "sense_rangefinder_function",
           "sense_datalink_function", "sensor_function", "NAV_TRUTH", "navigation_truth_function",
           "range_on_deck_function"]

#: The sensors, in the order of their random streams (:mod:`quadland.kinds.landing.sensing`).
SENSOR_NAMES = ("imu", "vision", "gnss", "rangefinder", "datalink")

_XYZ = ("x", "y", "z")
_ATT = ("phi", "theta", "psi")


def _named(prefix: str, names=_XYZ) -> tuple[str, ...]:
    return tuple(f"{prefix}_{n}" for n in names)


#: Constants of the sensor models that the Functions need (the rest of each
#: sensor's settings, rates, latencies and noise levels, stay in the runtime).
SENSOR_PARAMS = Layout("p_sens", (
    Field("vision_sigma0", 1, "m", "vision noise per axis at zero range"),
    Field("vision_sigma_per_m", 1, "m/m", "growth of the vision noise per metre of range"),
    Field("vision_half_angle", 1, "rad", "half-angle of the camera's field-of-view cone"),
    Field("vision_range_min", 1, "m", "nearest range at which the marker is detected"),
    Field("vision_range_max", 1, "m", "farthest range at which the marker is detected"),
    Field("vision_small_range_min", 1, "m", "nearest range of the second, smaller marker"),
    Field("vision_small_range_max", 1, "m", "farthest range of the second marker (0: none)"),
    Field("rangefinder_sigma0", 1, "m", "rangefinder noise at zero distance"),
    Field("rangefinder_sigma_per_m", 1, "m/m", "growth of the rangefinder noise per metre"),
    Field("rangefinder_range_min", 1, "m", "shortest distance the rangefinder reports"),
    Field("rangefinder_range_max", 1, "m", "longest distance the rangefinder reports"),
    Field("deck_half_length", 1, "m", "deck's extent along the deck x axis from the pad centre"),
    Field("deck_half_width", 1, "m", "deck's extent along the deck y axis from the pad centre"),
), "constants of the sensor models")

#: The IMU's packet: the attitude estimator's output, accelerometer and gyro.
IMU_PACKET = Layout("y_imu", (
    Field("eta_hat", 3, "rad", "attitude estimate, ZYX", elements=_named("eta_hat", _ATT)),
    Field("f_b", 3, "m/s^2", "accelerometer: specific force in body axes",
          elements=_named("f_b")),
    Field("omega", 3, "rad/s", "gyro: body rates", elements=_named("omega")),
), "IMU sample: attitude estimate, specific force, body rates")

#: The camera's packet: the pad centre relative to the camera, in E.
VISION_PACKET = Layout("y_vision", (
    Field("r_E", 3, "m", "pad centre minus camera in E, rotated with the attitude estimate",
          elements=_named("r_E")),
    Field("valid", 1, "-", "1: the marker is in the field of view and range, else 0"),
), "marker detection")

#: The GNSS packet: both receivers' positions differenced, both velocities.
GNSS_PACKET = Layout("y_gnss", (
    Field("rel", 3, "m", "pad receiver minus quadrotor receiver, E", elements=_named("rel")),
    Field("v1", 3, "m/s", "quadrotor velocity in E", elements=_named("v1")),
    Field("vt", 3, "m/s", "pad (target) velocity in E", elements=_named("vt")),
), "GNSS: relative position and both velocities")

#: The rangefinder's packet.
RANGEFINDER_PACKET = Layout("y_rangefinder", (
    Field("s", 1, "m", "distance along -b3 to the first surface (deck or z = 0)"),
    Field("b3_E", 3, "-", "body z axis in E from the attitude estimate",
          elements=_named("b3_E")),
    Field("valid", 1, "-", "1: a surface within the rangefinder's range, else 0"),
), "rangefinder: distance along the body's down axis")

#: The vehicle's broadcast (its INS).
DATALINK_PACKET = Layout("y_datalink", tuple(DECK_POSE[n] for n in (
    "eta2", "v2E", "a2E", "w2E", "w2E_dot")), "vehicle broadcast: deck attitude and motion")

_E_ATT = Field("e_att", 3, "rad", "attitude estimator error (shared by imu, vision, "
               "rangefinder at equal times)", elements=_named("e_att", _ATT))

#: Noise of the IMU packet (drawn by quadland.kinds.landing.sensing).
IMU_NOISE = Layout("n_imu", (
    _E_ATT,
    Field("b_a", 3, "m/s^2", "accelerometer bias (turn-on + random walk)",
          elements=_named("b_a")),
    Field("n_a", 3, "m/s^2", "accelerometer white noise", elements=_named("n_a")),
    Field("b_g", 3, "rad/s", "gyro bias (turn-on + random walk)", elements=_named("b_g")),
    Field("n_g", 3, "rad/s", "gyro white noise", elements=_named("n_g")),
), "IMU noise")

#: Noise of the vision packet.
VISION_NOISE = Layout("n_vision", (
    _E_ATT,
    Field("n_r", 3, "-", "standard normal draws, scaled by sigma0 + k range (body axes)",
          elements=_named("n_r")),
    Field("o_r", 3, "m", "outlier offset in body axes (0 but for outliers)",
          elements=_named("o_r")),
), "vision noise")

#: Noise of the GNSS packet.
GNSS_NOISE = Layout("n_gnss", (
    Field("e_q", 3, "m", "quadrotor receiver's position error (Gauss-Markov)",
          elements=_named("e_q")),
    Field("e_t", 3, "m", "pad receiver's position error (Gauss-Markov)",
          elements=_named("e_t")),
    Field("n_v1", 3, "m/s", "quadrotor velocity white noise", elements=_named("n_v1")),
    Field("n_vt", 3, "m/s", "pad velocity white noise", elements=_named("n_vt")),
), "GNSS noise")

#: Noise of the rangefinder packet.
RANGEFINDER_NOISE = Layout("n_rangefinder", (
    _E_ATT,
    Field("n_s", 1, "-", "standard normal draw, scaled by sigma0 + k s"),
    Field("o_s", 1, "m", "outlier offset (0 but for outliers)"),
), "rangefinder noise")

#: Noise of the datalink packet (white, the vehicle INS's).
DATALINK_NOISE = Layout("n_datalink", tuple(
    Field(f"n_{f.name}", f.size, f.unit, f"white noise on {f.name}",
          elements=tuple(f"n_{e}" for e in f.element_names()))
    for f in DATALINK_PACKET.fields), "datalink noise")

#: Packet layout of each sensor.
SENSOR_PACKETS = MappingProxyType({"imu": IMU_PACKET, "vision": VISION_PACKET, "gnss": GNSS_PACKET,
                            "rangefinder": RANGEFINDER_PACKET,
                            "datalink": DATALINK_PACKET})
#: Noise layout of each sensor.
NOISES = MappingProxyType({"imu": IMU_NOISE, "vision": VISION_NOISE, "gnss": GNSS_NOISE,
                           "rangefinder": RANGEFINDER_NOISE, "datalink": DATALINK_NOISE})


def _truth(xp, t, pp):
    """Quadrotor state blocks, the deck's pose, the parameters."""
    x, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    q = QUAD6_STATE.unpack(x["x1q"])
    return q, deck_pose(x["xv"], t, p["p_veh"], p["p_deck"]), p


def specific_force(xp, uh, w, t, pp, contact: bool = True):
    """``R1^T (a1 - g_vec)``: an ideal accelerometer's reading, m/s^2.

    ``a1 = p1'' = R1 (V1' + Omega1 x V1)`` with ``V1'`` from
    :func:`~quadland_symbolic.landing.loop.loop_plant_function` (wind, disturbance
    and rotor states included); ``g_vec = [0, 0, -g]`` (E, z up), so a level
    hover reads ``+g`` along ``b3`` and free fall reads 0. ``contact = False``: the
    plant without the gear's contact (the same reading where its forces are zero).
    """
    q, _, p = _truth(xp, t, pp)
    xp_dot = LANDING_PLANT_STATE.unpack(loop_plant_function(contact)(xp, uh, w, t, pp))
    V1_dot = QUAD6_STATE.unpack(xp_dot["x1q"])["V1"]
    R1 = rotation(q["eta1"])
    a1 = R1 @ (V1_dot + skew(q["Omega1"]) @ q["V1"])                   # p1'' in E
    g_vec = ca.vertcat(0, 0, -QUADROTOR.unpack(p["p_quad"])["g"])
    return R1.T @ (a1 - g_vec)


def _inside(v, lo, hi):
    return ca.logic_and(v >= lo, v <= hi)


def _deck_hit(p1, d, p2, R_deck, half_length, half_width):
    """``(s_deck, on_deck)``: the beam ``p1 + s d`` against the deck's extent."""
    n2 = R_deck[:, 2]
    den = ca.dot(n2, d)
    s_deck = ca.dot(n2, p2 - p1) / ca.if_else(den < 0, den, -1)
    q = R_deck.T @ (p1 + s_deck * d - p2)                              # hit in deck axes
    on_deck = ca.logic_and(ca.logic_and(den < 0, s_deck >= 0),
                           ca.logic_and(ca.fabs(q[0]) <= half_length,
                                        ca.fabs(q[1]) <= half_width))
    return s_deck, on_deck


def rangefinder_distance(p1, b3, p2, R_deck, half_length, half_width):
    """Distance along ``-b3`` from ``p1`` to the deck or to ``z = 0``.

    The deck is the plane ``n2 . (x - p2) = 0``, ``n2 = R_deck e_z``, and
    counts where the hit point lies within ``half_length`` and
    ``half_width`` of the pad centre along the deck's x and y axes. Returns
    ``(s, hit)``: ``hit`` is 0 (and ``s`` 0) when the ray meets neither,
    i.e. when the body's down axis points at or above the horizon.
    """
    d = -b3                                                            # the beam, E
    s_deck, on_deck = _deck_hit(p1, d, p2, R_deck, half_length, half_width)
    s_ground = p1[2] / ca.if_else(d[2] < 0, -d[2], 1)
    ground = ca.logic_and(d[2] < 0, s_ground >= 0)
    s = ca.if_else(on_deck, s_deck, ca.if_else(ground, s_ground, 0))
    return s, ca.logic_or(on_deck, ground)


def _args():
    return (LANDING_PLANT_STATE.sym(), COMMAND.sym(), LANDING_DISTURBANCE.sym(), ca.SX.sym("t"),
            LANDING_PLANT_PARAMS.sym(), SENSOR_PARAMS.sym())


_IN_NAMES = ["xp", "uh", "w", "t", "pp", "p_sens", "noise"]


@functools.cache
def sense_imu_function(contact: bool = True) -> ca.Function:
    """``sense_imu``: the :data:`IMU_PACKET` under :data:`IMU_NOISE`.

    Signature ``(xp, uh, w, t, pp, p_sens, noise) -> y`` (as every sensor's).
    ``eta_hat = eta1 + e_att``, ``f_b = specific_force + b_a + n_a``,
    ``omega = Omega1 + b_g + n_g``. ``contact = False``: ``sense_imu_free``, its
    specific force of the plant without the gear's contact (:func:`specific_force`).
    """
    xp, uh, w, t, pp, ps = _args()
    noise = IMU_NOISE.sym()
    n = IMU_NOISE.unpack(noise)
    q, _, _ = _truth(xp, t, pp)
    y = ca.vertcat(q["eta1"] + n["e_att"],
                   specific_force(xp, uh, w, t, pp, contact) + n["b_a"] + n["n_a"],
                   q["Omega1"] + n["b_g"] + n["n_g"])
    return ca.Function("sense_imu" if contact else "sense_imu_free",
                       [xp, uh, w, t, pp, ps, noise], [y], _IN_NAMES, ["y"])


@functools.cache
def sense_vision_function() -> ca.Function:
    """``sense_vision``: the camera's marker detection under noise.

    ``d_b = R1^T (p2 - p1)``; ``r_E = R(eta1 + e_att) (d_b + (sigma0 + k |d_b|)
    n_r + o_r)``; ``valid`` when ``-b3 . d >= cos(half_angle) |d|`` and
    ``|d|`` lies in the large marker's or the small marker's interval.
    """
    xp, uh, w, t, pp, ps = _args()
    noise = VISION_NOISE.sym()
    n, c = VISION_NOISE.unpack(noise), SENSOR_PARAMS.unpack(ps)
    q, deck, _ = _truth(xp, t, pp)
    d_b = rotation(q["eta1"]).T @ (deck.p2 - q["p1"])                   # true, body axes
    rng = ca.norm_2(d_b)
    sigma = c["vision_sigma0"] + c["vision_sigma_per_m"] * rng
    r_E = rotation(q["eta1"] + n["e_att"]) @ (d_b + sigma * n["n_r"] + n["o_r"])
    in_view = -d_b[2] >= ca.cos(c["vision_half_angle"]) * rng
    in_range = ca.logic_or(_inside(rng, c["vision_range_min"], c["vision_range_max"]),
                           _inside(rng, c["vision_small_range_min"],
                                   c["vision_small_range_max"]))
    y = ca.vertcat(r_E, ca.logic_and(in_view, in_range))
    return ca.Function("sense_vision", [xp, uh, w, t, pp, ps, noise], [y], _IN_NAMES, ["y"])


@functools.cache
def sense_gnss_function() -> ca.Function:
    """``sense_gnss``: :data:`GNSS_PACKET` under :data:`GNSS_NOISE`.

    Receivers at the body origin and at the pad centre:
    ``rel = (p2 + e_t) - (p1 + e_q)``, ``v1 = R1 V1 + n_v1``, ``vt = v2E + n_vt``.
    """
    xp, uh, w, t, pp, ps = _args()
    noise = GNSS_NOISE.sym()
    n = GNSS_NOISE.unpack(noise)
    q, deck, _ = _truth(xp, t, pp)
    y = ca.vertcat((deck.p2 + n["e_t"]) - (q["p1"] + n["e_q"]),
                   rotation(q["eta1"]) @ q["V1"] + n["n_v1"],
                   deck.v2E + n["n_vt"])
    return ca.Function("sense_gnss", [xp, uh, w, t, pp, ps, noise], [y], _IN_NAMES, ["y"])


@functools.cache
def sense_rangefinder_function() -> ca.Function:
    """``sense_rangefinder``: the rangefinder's packet, noisy.

    ``s = s_true + (sigma0 + k s_true) n_s + o_s`` with ``s_true`` from
    :func:`rangefinder_distance`; ``b3_E`` is the third column of
    ``R(eta1 + e_att)``; ``valid`` when ``s_true`` is in
    ``[range_min, range_max]`` (0 when nothing is hit, and then ``s = 0``).
    """
    xp, uh, w, t, pp, ps = _args()
    noise = RANGEFINDER_NOISE.sym()
    n, c = RANGEFINDER_NOISE.unpack(noise), SENSOR_PARAMS.unpack(ps)
    q, deck, _ = _truth(xp, t, pp)
    b3 = rotation(q["eta1"])[:, 2]
    s, hit = rangefinder_distance(q["p1"], b3, deck.p2, deck.R_deck, c["deck_half_length"],
                                  c["deck_half_width"])
    sigma = c["rangefinder_sigma0"] + c["rangefinder_sigma_per_m"] * s
    valid = ca.logic_and(hit, _inside(s, c["rangefinder_range_min"],
                                      c["rangefinder_range_max"]))
    s_meas = ca.if_else(hit, s + sigma * n["n_s"] + n["o_s"], 0)
    y = ca.vertcat(s_meas, rotation(q["eta1"] + n["e_att"])[:, 2], valid)
    return ca.Function("sense_rangefinder", [xp, uh, w, t, pp, ps, noise], [y], _IN_NAMES,
                       ["y"])


@functools.cache
def sense_datalink_function() -> ca.Function:
    """``sense_datalink``: the vehicle's broadcast under its noise.

    The deck's ``eta2, v2E, a2E, w2E, w2E_dot`` (:func:`~quadland_symbolic.landing.
    deck.deck_pose`) plus the matching white noise of :data:`DATALINK_NOISE`.
    """
    xp, uh, w, t, pp, ps = _args()
    noise = DATALINK_NOISE.sym()
    _, deck, _ = _truth(xp, t, pp)
    truth = ca.vertcat(*(getattr(deck, f.name) for f in DATALINK_PACKET.fields))
    return ca.Function("sense_datalink", [xp, uh, w, t, pp, ps, noise], [truth + noise],
                       _IN_NAMES, ["y"])


_BUILDERS = MappingProxyType({"imu": sense_imu_function, "vision": sense_vision_function,
                              "gnss": sense_gnss_function,
                              "rangefinder": sense_rangefinder_function,
                              "datalink": sense_datalink_function})


def sensor_function(name: str, contact: bool = True) -> ca.Function:
    """The Function ``sense_<name>`` of one of :data:`SENSOR_NAMES`; ``contact = False``:
    the IMU's of the plant without the gear's contact (:func:`sense_imu_function`)."""
    if name == "imu" and not contact:
        return sense_imu_function(False)
    try:
        return _BUILDERS[name]()
    except KeyError:
        raise KeyError(f"no sensor {name!r}; sensors are {', '.join(SENSOR_NAMES)}") from None


def measurement_function() -> ca.Function:
    """``landing_sensors(xp, t, pp) -> y``: perfect sensors on the landing plant.

    ``y`` (:data:`LANDING_MEASUREMENT`) from the plant's state
    (:data:`~quadland_symbolic.landing.plant.LANDING_PLANT_STATE`) and parameters
    (:data:`~quadland_symbolic.landing.plant.LANDING_PLANT_PARAMS`) at time ``t``: ``p_e, v_e``
    from :func:`~quadland_symbolic.landing.relative.relative6`, the deck's broadcast
    from :func:`~quadland_symbolic.landing.deck.deck_pose`.
    """
    xp, t, pp = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    x, p = LANDING_PLANT_STATE.unpack(xp), LANDING_PLANT_PARAMS.unpack(pp)
    q = QUAD6_STATE.unpack(x["x1q"])
    p_e, v_e, *_ = relative6(x["x1q"], x["xv"], t, p["p_quad"], p["p_act"], p["p_veh"],
                             p["p_deck"])
    deck = deck_pose(x["xv"], t, p["p_veh"], p["p_deck"])
    y = ca.vertcat(p_e, v_e, q["eta1"], q["Omega1"], deck.eta2, deck.v2E, deck.a2E, deck.w2E,
                   deck.w2E_dot)
    return ca.Function("landing_sensors", [xp, t, pp], [y], ["xp", "t", "pp"], ["y"])


#: The navigation filter's states whose truth the world defines at every control tick:
#: those of :data:`~quadland_symbolic.landing.navigation.NAV` but the relative GNSS bias
#: ``b`` (the receivers' errors exist only at the GNSS's samples) and the accelerometer
#: bias ``a_b`` (it also carries what the filter does not model).
NAV_TRUTH = Layout("nav_truth", (*NAV.fields[:4], NAV["a_tilt"]),
                   "the navigation state's true part, E")


@functools.cache
def navigation_truth_function() -> ca.Function:
    """``nav_truth(xp, t, pp, e_att) -> x``: :data:`NAV_TRUTH` from the true plant state.

    ``p_r = p1 - p2``, ``v1 = R1 V1``, ``v_t = v2E``, ``a_t = a2E``
    (:func:`~quadland_symbolic.landing.deck.deck_pose`), and the tilt bias of the
    acceleration input ``a_tilt = g eps x e_z`` of the attitude estimate's error
    ``e_att`` (the IMU's noise of the tick): ``eps`` is the rotation vector of
    ``R(eta1 + e_att) R1^T`` (its skew part, exact to second order in ``e_att``), so that
    ``R(eta1 + e_att) f = f + eps x f`` (docs/estimator.md, (E1)). World-side: the
    filter never reads it.
    """
    xp, t, pp = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym()
    e_att = ca.SX.sym("e_att", 3)
    q, deck, p = _truth(xp, t, pp)
    R1 = rotation(q["eta1"])
    D = rotation(q["eta1"] + e_att) @ R1.T
    eps = ca.vertcat(D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]) / 2
    g = QUADROTOR.unpack(p["p_quad"])["g"]
    x = ca.vertcat(q["p1"] - deck.p2, R1 @ q["V1"], deck.v2E, deck.a2E,
                   g * ca.cross(eps, ca.vertcat(0, 0, 1)))
    return ca.Function("nav_truth", [xp, t, pp, e_att], [x], ["xp", "t", "pp", "e_att"],
                       ["x"])


@functools.cache
def range_on_deck_function() -> ca.Function:
    """``range_on_deck(xp, t, pp, p_sens) -> on_deck``: 1 where the range finder's beam
    meets the deck within its extent (:func:`rangefinder_distance`'s deck), 0 where it
    reads the ground beside it or nothing.

    World-side, as :func:`navigation_truth_function`: the filter's range model (E12)
    describes a distance to the deck's plane, so a beam that reads the road is an
    outlier of the world, not noise (docs/estimator.md, "Consistency").
    """
    xp, t, pp, ps = LANDING_PLANT_STATE.sym(), ca.SX.sym("t"), LANDING_PLANT_PARAMS.sym(), \
        SENSOR_PARAMS.sym()
    q, deck, _ = _truth(xp, t, pp)
    c = SENSOR_PARAMS.unpack(ps)
    _, on_deck = _deck_hit(q["p1"], -rotation(q["eta1"])[:, 2], deck.p2, deck.R_deck,
                           c["deck_half_length"], c["deck_half_width"])
    return ca.Function("range_on_deck", [xp, t, pp, ps], [on_deck],
                       ["xp", "t", "pp", "p_sens"], ["on_deck"])

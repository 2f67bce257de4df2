"""Landing gear on the deck: feet, friction, a lock-down device.

Each of the :data:`N_FEET` feet (four feet, or two skids by their end
points) is a point ``r_i`` fixed in the body frame. Against the deck plane
(through the pad centre ``p2``, normal ``n2 = R_deck e_z``) it has

* the penetration ``delta_i = -n2 . (p_i - p2)``, ``p_i = p1 + R1 r_i``;
* its velocity relative to the deck's material point under it,
  ``v_i = v1E + w1E x (R1 r_i) - v2E - w2E x (p_i - p2)``, so that
  ``delta_i_dot = -n2 . v_i``;
* a normal force: a linear spring-damper (Kelvin-Voigt) on the *smoothed*
  penetration ``delta+ = eps softplus(delta / eps)``, whose rate is
  ``sigma(delta / eps) delta_dot`` (``sigma`` the logistic function),
  clipped so that it never pulls:
  ``F_n = max(0, k delta+ + c sigma delta_dot)``;
* a friction force opposing the slip ``v_t`` (``v_i``'s part in the deck
  plane), Coulomb's law regularised at the speed
  ``v_s = sqrt(v_eps^2 + (mu F_n / b_slip)^2)``:
  ``F_t = -mu F_n v_t / sqrt(|v_t|^2 + v_s^2)``. Its slope at zero slip,
  ``mu F_n / v_s``, is at most ``b_slip`` whatever the normal load (an
  impact, a lock-down), which bounds the stiffest mode and so RK4's step.

Every force is continuous in the state and in time (the clip is Lipschitz;
the rest is smooth), so a fixed-step RK4 stays well posed. The sum acts on
the body as the disturbance of eq. (2): ``d_F`` and the moment ``d_M`` about
the centre, both in the body frame (:func:`contact_wrench`).

A lock-down device (an electro-permanent magnet, or a harpoon in a deck
grid) pulls the gear's centre point (or, ``at_feet``, each foot by its own
gap) along ``-n2`` once engaged: a dead time
``lock_delay`` after a contact signal whose rise time ``t_signal`` is an
input, then a first-order rise (:func:`lock_wrench`).

:func:`friction_margin` and :func:`tip_over_angles` judge a resting
quadrotor. docs/contact.md gives the model, its checks and the defaults'
sources (:func:`gear_defaults`, :func:`lock_defaults`).
"""

from __future__ import annotations

import functools
import math

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.deck import DECK_PARAMS, deck_pose
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.landing.swivel_foot import swivel_edge
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = [
    "N_FEET",
    "GEAR",
    "LOCK",
    "FOOT",
    "HOLD",
    "SURFACES",
    "DEVICES",
    "smooth_penetration",
    "contact_wrench",
    "lock_wrench",
    "contact_function",
    "friction_margin",
    "friction_margin_function",
    "tip_over_angles",
    "tip_over_function",
    "restitution",
    "RK4_REAL_STABILITY",
    "stiffest_rate",
    "gear_defaults",
    "lock_defaults",
]

#: Contact points of the gear: four feet, or two skids by their end points.
N_FEET = 4

_FEET = tuple(range(1, N_FEET + 1))


def _per_foot(name: str, unit: str, doc: str) -> Field:
    return Field(name, N_FEET, unit, doc, elements=tuple(f"{name}_{i}" for i in _FEET))


#: The gear's parameters ``p_gear``.
GEAR = Layout("p_gear", (
    Field("r_feet", 3 * N_FEET, "m", "foot positions in the body frame, one column per foot",
          shape=(3, N_FEET),
          elements=tuple(f"{a}_foot_{i}" for i in _FEET for a in ("x", "y", "z"))),
    Field("k", 1, "N/m", "normal stiffness of one foot"),
    Field("c", 1, "N s/m", "normal damping of one foot"),
    Field("mu", 1, "-", "Coulomb friction coefficient of a foot on the deck"),
    Field("v_eps", 1, "m/s", "friction's regularisation speed at light loads"),
    Field("b_slip", 1, "N s/m", "largest friction slope of a foot at zero slip (caps stiffness)"),
    Field("delta_eps", 1, "m", "smoothing width of the contact onset (softplus)"),
), "landing gear: feet, linear spring-damper normal law, regularised Coulomb friction")

#: The lock-down device's parameters ``p_lock``.
LOCK = Layout("p_lock", (
    Field("F_hold", 1, "N", "largest holding force, at zero gap once engaged"),
    Field("lock_delay", 1, "s", "dead time from the contact signal to the start of the pull"),
    Field("lock_rise_time", 1, "s", "time constant of the pull's first-order rise (> 0)"),
    Field("lock_gap_scale", 1, "m",
          "gap at which the pull falls to a quarter (a magnet); large for a harpoon"),
    Field("at_feet", 1, "-",
          "0: one device at the gear's centre; 1: F_hold shared by a device in each foot, "
          "each pulled by its own gap"),
    Field("swivel", 1, "rad",
          "a foot device's swivel: the largest angle between its face's normal and its "
          "neutral axis (0 to pi/2; pi/2: flush up to 90 deg off the axis, an "
          "idealization; past pi/2 the law edges every face, swivel_foot.swivel_edge)"),
    Field("swivel_pitch", 1, "rad",
          "the foot devices' neutral axis, pitched nose down from the body's z axis"),
    Field("face_width", 1, "m",
          "a foot device's face across: past its swivel it meets the deck on its edge, "
          "its centre half this times the sine of the excess up"),
), "lock-down device: holding force, delay and rise, fall-off with the gap, where it pulls")

#: Per-foot signals of :func:`contact_wrench`, for reports.
FOOT = Layout("foot", (
    _per_foot("delta", "m", "penetration of the foot below the deck plane (negative above)"),
    _per_foot("F_n", "N", "normal force of the deck on the foot"),
    _per_foot("F_t", "N", "magnitude of the friction force on the foot"),
    _per_foot("slip", "m/s", "slip speed of the foot on the deck"),
    _per_foot("in_contact", "-", "1 where the foot is below the plane and pressing, else 0"),
), "per-foot contact signals: penetration, normal and friction force, slip, contact flag")

#: Signals of :func:`lock_wrench`.
HOLD = Layout("hold", (
    Field("engaged", 1, "-", "engagement of the lock-down, 0 (off) to 1 (fully on)"),
    Field("F_lock", 1, "N", "holding force pulling the gear centre along -n2"),
    Field("lock_gap", 1, "m", "gear centre's height above the deck plane"),
    _per_foot("foot_pull", "N", "the pull of the device in each foot (0 at the centre's)"),
), "lock-down signals")

#: Deck surfaces with default gear parameters (:func:`gear_defaults`).
SURFACES = ("ship_deck", "car_roof")

#: Lock-down devices with default parameters (:func:`lock_defaults`).
DEVICES = ("magnet", "foot_magnets")


def smooth_penetration(delta, delta_eps):
    """Smoothed penetration ``delta+`` and its slope ``sigma``.

    ``delta+ = eps softplus(delta / eps)`` (always positive, ``delta`` for
    ``delta >> eps``) and ``sigma = d delta+ / d delta``, the logistic
    function of ``delta / eps``. Both are written so that neither overflows.
    ``delta+ - max(delta, 0)`` and ``sigma - H(delta)`` integrate, over
    ``delta``, to ``eps pi^2 / 6`` and to zero: the onset's impulse error is
    of second order in ``eps`` (docs/contact.md).
    """
    x = delta / delta_eps
    delta_plus = delta_eps * (ca.fmax(x, 0) + ca.log1p(ca.exp(-ca.fabs(x))))
    sigma = 0.5 * (1 + ca.tanh(x / 2))
    return delta_plus, sigma


def _feet_kinematics(x1q, deck, r_feet):
    """R1, n2; per foot (columns) penetration and relative velocity."""
    q = QUAD6_STATE.unpack(x1q)
    R1 = rotation(q["eta1"])
    v1E, w1E = R1 @ q["V1"], R1 @ q["Omega1"]
    n2 = deck.R_deck[:, 2]
    ones = ca.DM.ones(1, r_feet.shape[1])
    arm = R1 @ r_feet                                                   # m, E
    d = q["p1"] @ ones + arm - deck.p2 @ ones                           # p_i - p2
    delta = -(n2.T @ d)                                                 # m, 1 x N
    v_rel = (v1E @ ones + ca.cross(w1E @ ones, arm)
             - deck.v2E @ ones - ca.cross(deck.w2E @ ones, d))          # m/s, E
    return R1, n2, delta, v_rel


def contact_wrench(x1q, xv, t, p_veh, p_deck, p_gear):
    """The feet's contact forces as a body-frame wrench.

    Parameters
    ----------
    x1q : casadi.SX
        Quadrotor state (:data:`quadland_symbolic.landing.quadrotor.QUAD6_STATE`).
    xv : casadi.SX
        Vehicle state (:data:`quadland_symbolic.vehicle.VEHICLE_STATE`).
    t : casadi.SX
        Time, s (drives the deck's prescribed motion).
    p_veh, p_deck, p_gear : casadi.SX
        :data:`~quadland_symbolic.parameters.VEHICLE`,
        :data:`~quadland_symbolic.landing.deck.DECK_PARAMS` and :data:`GEAR`.

    Returns
    -------
    d_F : casadi.SX
        Sum of the feet's forces in the body frame, N (add to eq. 2's ``d_F``).
    d_M : casadi.SX
        Their moment about the centre in the body frame, N m (eq. 2's ``d_M``).
    foot : casadi.SX
        Per-foot signals laid out as :data:`FOOT`.

    Notes
    -----
    See the module docstring for the laws. The deck's velocity and rotation
    come from :func:`quadland_symbolic.landing.deck.deck_pose`.
    """
    g = GEAR.unpack(p_gear)
    r_feet, k, c, mu = g["r_feet"], g["k"], g["c"], g["mu"]
    deck = deck_pose(xv, t, p_veh, p_deck)
    R1, n2, delta, v_rel = _feet_kinematics(x1q, deck, r_feet)
    delta_dot = -(n2.T @ v_rel)                                         # m/s, 1 x N
    delta_plus, sigma = smooth_penetration(delta, g["delta_eps"])
    push = k * delta_plus + c * sigma * delta_dot                       # N, Kelvin-Voigt
    F_n = ca.fmax(push, 0)                                              # never pulls
    v_t = v_rel - n2 @ (n2.T @ v_rel)                                   # slip, deck plane
    slip2 = ca.sum1(v_t ** 2)                                           # (m/s)^2
    v_s2 = g["v_eps"] ** 2 + (mu * F_n / g["b_slip"]) ** 2             # (m/s)^2
    scale = mu * F_n / ca.sqrt(slip2 + v_s2)                            # N s/m, smooth at 0
    slip = ca.sqrt(slip2)                                               # m/s, signal only
    F_E = n2 @ F_n - v_t * (ca.DM.ones(3, 1) @ scale)                   # N per foot, E
    F_B = R1.T @ F_E
    d_F = ca.sum2(F_B)
    d_M = ca.sum2(ca.cross(r_feet, F_B))
    in_contact = ca.logic_and(delta > 0, push > 0)
    foot = ca.vertcat(delta.T, F_n.T, (scale * slip).T, slip.T, in_contact.T)
    return d_F, d_M, foot


def _gear_centre(r_feet):
    return ca.sum2(r_feet) / r_feet.shape[1]


def _pulls(R1, p1, p2, n2, r, engaged, lk, share, edge=0):
    """The pull ``F_hold share s / (1 + (gap+ + edge) / g0)^2`` at each column of ``r``
    (body frame) along ``-n2``: the body-frame force and moment sums, the pulls (a row)
    and the gaps."""
    gap = n2.T @ (p1 @ ca.DM.ones(1, r.shape[1]) + R1 @ r - p2 @ ca.DM.ones(1, r.shape[1]))
    pull = lk["F_hold"] * share * engaged / (1 + (ca.fmax(gap, 0) + edge)
                                             / lk["lock_gap_scale"]) ** 2
    F_B = R1.T @ (-n2 @ pull)                                           # N per point
    return ca.sum2(F_B), ca.sum2(ca.cross(r, F_B)), pull, gap


def lock_wrench(x1q, xv, t, t_signal, p_veh, p_deck, p_gear, p_lock):
    """The lock-down device's pull as a body-frame wrench.

    The device pulls the gear's centre point ``r_c`` (the mean of the feet)
    along ``-n2`` with ``F_lock = F_hold s(t) / (1 + gap+ / g0)^2``: the
    engagement ``s = 1 - exp(-max(0, t - t_signal - lock_delay) / lock_rise_time)``
    (continuous in time, no state), ``gap+`` the centre's height above the
    deck plane (0 when below it) and ``g0 = lock_gap_scale``. With ``at_feet = 1``
    a device in each foot pulls that foot with ``F_hold / N_FEET`` by the same law on
    its own gap (between 0 and 1, that share of the force is the feet's).

    Parameters
    ----------
    x1q, xv, t, p_veh, p_deck, p_gear
        As in :func:`contact_wrench`.
    t_signal : casadi.SX
        Time the contact/touchdown signal rose, s; ``+inf`` or NaN while it
        has not (then ``s = 0``). Who raises it is the integrator's choice.
    p_lock : casadi.SX
        :data:`LOCK`.

    Returns
    -------
    d_F, d_M : casadi.SX
        Body-frame force (N) and moment about the centre (N m).
    hold : casadi.SX
        Signals laid out as :data:`HOLD` (``F_lock`` the devices' total pull,
        ``lock_gap`` the gear centre's gap).
    """
    lk = LOCK.unpack(p_lock)
    r_feet = GEAR.unpack(p_gear)["r_feet"]
    r_c = _gear_centre(r_feet)
    deck = deck_pose(xv, t, p_veh, p_deck)
    q = QUAD6_STATE.unpack(x1q)
    R1 = rotation(q["eta1"])
    n2 = deck.R_deck[:, 2]
    age = ca.fmax(t - t_signal - lk["lock_delay"], 0)                   # s; NaN, inf -> 0
    engaged = 1 - ca.exp(-age / lk["lock_rise_time"])
    a = lk["at_feet"]
    F_c, M_c, P_c, gap = _pulls(R1, q["p1"], deck.p2, n2, r_c, engaged, lk, 1 - a)
    F_f, M_f, P_f, _ = _pulls(R1, q["p1"], deck.p2, n2, r_feet, engaged, lk, a / N_FEET,
                              swivel_edge(R1, n2, lk))
    return F_c + F_f, M_c + M_f, ca.vertcat(engaged, P_c + ca.sum2(P_f), gap, P_f.T)


@functools.cache
def contact_function() -> ca.Function:
    """The named Function ``contact``: the feet and the lock-down.

    ``contact(x1q, xv, t, t_signal, p_veh, p_deck, p_gear, p_lock) ->
    (d_F, d_M, foot, hold)``: the feet (:func:`contact_wrench`) and the
    lock-down (:func:`lock_wrench`) together: ``d_F``, ``d_M`` are their
    sum, body frame, to add to the plant's disturbance; ``foot`` is
    :data:`FOOT`, ``hold`` :data:`HOLD`.
    """
    x1q, xv, t, t_signal = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t"), \
        ca.SX.sym("t_signal")
    p_veh, p_deck, p_gear, p_lock = VEHICLE.sym(), DECK_PARAMS.sym(), GEAR.sym(), LOCK.sym()
    F_c, M_c, foot = contact_wrench(x1q, xv, t, p_veh, p_deck, p_gear)
    F_l, M_l, hold = lock_wrench(x1q, xv, t, t_signal, p_veh, p_deck, p_gear, p_lock)
    return ca.Function(
        "contact", [x1q, xv, t, t_signal, p_veh, p_deck, p_gear, p_lock],
        [F_c + F_l, M_c + M_l, foot, hold],
        ["x1q", "xv", "t", "t_signal", "p_veh", "p_deck", "p_gear", "p_lock"],
        ["d_F", "d_M", "foot", "hold"],
    )


def friction_margin(x1q, xv, t, F_other, p_quad, p_veh, p_deck, p_gear):
    """Friction a resting body needs over what its feet can give.

    The body is taken at rest on the deck at its pose in ``x1q`` (moving
    with the deck's material point under its centre): its centre
    accelerates with ``a_c = a2E + w2E_dot x r + w2E x (w2E x r)``,
    ``r = p1 - p2``, so the feet together must supply
    ``F = m1 (a_c + g e_z) - F_other``. The margin is
    ``|F - (n2 . F) n2| / (mu n2 . F)``: below 1 the feet hold, at or above
    1 the body slides; ``inf`` where ``n2 . F <= 0`` (the body lifts off).

    Parameters
    ----------
    F_other : casadi.SX
        Every other force on the body but gravity, in E, N: the rotors'
        thrust ``R1 [0, 0, F_total]``, drag and wind, the lock-down's pull
        ``-F_lock n2``.
    p_quad : casadi.SX
        :data:`~quadland_symbolic.parameters.QUADROTOR` (``m1``, ``g``).

    Notes
    -----
    The aggregate Coulomb condition, which every foot's own condition
    implies; it is also sufficient when the feet share the tangential load
    in proportion to their normal loads. Moments are judged by
    :func:`tip_over_angles`.
    """
    p = QUADROTOR.unpack(p_quad)
    deck = deck_pose(xv, t, p_veh, p_deck)
    r = QUAD6_STATE.unpack(x1q)["p1"] - deck.p2
    a_c = deck.a2E + ca.cross(deck.w2E_dot, r) + ca.cross(deck.w2E, ca.cross(deck.w2E, r))
    F = p["m1"] * (a_c + ca.vertcat(0, 0, p["g"])) - F_other           # N, E
    n2 = deck.R_deck[:, 2]
    F_n = n2.T @ F
    F_t = ca.norm_2(F - F_n * n2)
    return ca.if_else(F_n > 0, F_t / (GEAR.unpack(p_gear)["mu"] * F_n), ca.inf)


@functools.cache
def friction_margin_function() -> ca.Function:
    """The named Function of :func:`friction_margin`.

    ``friction_margin(x1q, xv, t, F_other, p_quad, p_veh, p_deck, p_gear) -> margin``.
    """
    x1q, xv, t, F_other = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t"), \
        ca.SX.sym("F_other", 3)
    p_quad, p_veh, p_deck, p_gear = QUADROTOR.sym(), VEHICLE.sym(), DECK_PARAMS.sym(), \
        GEAR.sym()
    return ca.Function(
        "friction_margin", [x1q, xv, t, F_other, p_quad, p_veh, p_deck, p_gear],
        [friction_margin(x1q, xv, t, F_other, p_quad, p_veh, p_deck, p_gear)],
        ["x1q", "xv", "t", "F_other", "p_quad", "p_veh", "p_deck", "p_gear"], ["margin"],
    )


def _casadi(v):
    """A CasADi matrix: numbers (lists, NumPy arrays) become ``DM``."""
    return v if isinstance(v, ca.SX | ca.MX | ca.DM) else ca.DM(v)


def tip_over_angles(p_gear):
    """Static tip-over angles about the body's x and y axes, rad.

    ``atan(half_track / h_cg)``: ``h_cg`` is the centre's height above the
    feet's plane (the mean of ``-z_i``; the feet are taken coplanar and
    parallel to the body's x-y plane) and the half-track the distance from
    the centre to the nearer edge of the support rectangle: ``min(max y_i,
    -min y_i)`` for a roll (about x), ``min(max x_i, -min x_i)`` for a pitch
    (about y). A deck tilted beyond it tips a resting body with no thrust,
    lock or friction limit.
    """
    r = GEAR.unpack(_casadi(p_gear))["r_feet"]
    h_cg = -ca.sum2(r[2, :]) / r.shape[1]

    def half(row):
        return ca.fmin(ca.mmax(row), -ca.mmin(row))

    return ca.vertcat(ca.atan2(half(r[1, :]), h_cg), ca.atan2(half(r[0, :]), h_cg))


@functools.cache
def tip_over_function() -> ca.Function:
    """``tip_over(p_gear) -> (roll, pitch)``: tip-over angles, rad."""
    p_gear = GEAR.sym()
    a = tip_over_angles(p_gear)
    return ca.Function("tip_over", [p_gear], [a[0], a[1]], ["p_gear"], ["roll", "pitch"])


def restitution(zeta):
    """Coefficient of restitution of the clipped linear spring-damper.

    ``e = exp(-(zeta / s) (pi - 2 atan(zeta / s)))``, ``s = sqrt(1 - zeta^2)``,
    for ``0 <= zeta < 1`` (Schwager and Poeschel 2007): contact ends where
    the force, not the penetration, returns to zero. Without the clip
    (a pulling damper) it would be ``exp(-pi zeta / s)``. Works on numbers
    and on CasADi expressions.
    """
    r = zeta / ca.sqrt(1 - zeta ** 2)
    return ca.exp(-r * (ca.pi - 2 * ca.atan(r)))


#: Where classical RK4's stability region meets the negative real axis: a real
#: eigenvalue ``-lambda`` is integrated stably for ``h lambda`` below it.
RK4_REAL_STABILITY = 2.785293563405282


def stiffest_rate(p_quad, p_gear):
    """Largest eigenvalue the gear adds to a resting body, 1/s.

    The friction's slope is at most ``b_slip`` per foot. Through the feet,
    ``h_cg`` below the centre, it damps the slide-and-rock motion at the
    rate ``N b_slip (1/m1 + h_cg^2 / I)`` (``I`` the smaller of ``Ix``,
    ``Iy``; the exact rate of a rank-one damper on ``diag(m1, I)``) and the
    yaw at ``b_slip sum(x_i^2 + y_i^2) / Iz``; the normal springs oscillate
    at ``sqrt(N k / m1)`` and rock at most at ``sqrt(k sum x_i^2 / Iy)`` (about
    the centre, feet sliding freely; slower about pinned feet). Classical
    RK4 is stable for a step below ``RK4_REAL_STABILITY / stiffest_rate``;
    accuracy of the bounce asks ``h sqrt(N k / m1)`` of about 0.1
    (docs/contact.md).
    """
    p, g = QUADROTOR.unpack(_casadi(p_quad)), GEAR.unpack(_casadi(p_gear))
    r, b, k = g["r_feet"], g["b_slip"], g["k"]
    n = r.shape[1]
    x2, y2 = ca.sum2(r[0, :] ** 2), ca.sum2(r[1, :] ** 2)
    h_cg = -ca.sum2(r[2, :]) / n
    I_rock = ca.fmin(p["I"][0], p["I"][1])
    return ca.mmax(ca.vertcat(
        n * b * (1 / p["m1"] + h_cg ** 2 / I_rock),
        b * (x2 + y2) / p["I"][2],
        ca.sqrt(n * k / p["m1"]),
        ca.sqrt(k * ca.fmax(x2 / p["I"][1], y2 / p["I"][0])),
    ))


def gear_defaults(surface: str = "ship_deck") -> dict:
    """Default :data:`GEAR` values: a 2 kg quadrotor on a surface.

    Parameters
    ----------
    surface : {"ship_deck", "car_roof"}
        Rubber feet on a steel deck with a non-skid coating, or on a car's
        painted steel roof.

    Returns
    -------
    dict
        A fresh dict for :meth:`GEAR.pack <quadland_symbolic.layout.Layout.pack>`;
        the sources are in docs/contact.md.
    """
    if surface not in SURFACES:
        raise ValueError(f"surface must be one of {SURFACES}, got {surface!r}")
    x, y, z = 0.15, 0.125, -0.2                                  # m; z = -gear_height
    r_feet = [[x, y, z], [-x, y, z], [-x, -y, z], [x, -y, z]]
    return dict(
        r_feet=[v for foot in r_feet for v in foot],
        k=5000.0,                                                # N/m per foot
        c=30.0,                                                  # N s/m: zeta 0.3 at 2 kg
        mu={"ship_deck": 0.6, "car_roof": 0.5}[surface],
        v_eps=0.01,                                              # m/s
        b_slip=300.0,                                            # N s/m per foot
        delta_eps=1e-4,                                          # m
    )


def lock_defaults(device: str = "magnet") -> dict:
    """Default :data:`LOCK` values of a lock-down device.

    Parameters
    ----------
    device : {"magnet", "foot_magnets"}
        An electro-permanent magnet under the gear's centre, or the same holding
        force shared by one in each foot (docs/contact.md).

    Returns
    -------
    dict
        A fresh dict for :meth:`LOCK.pack <quadland_symbolic.layout.Layout.pack>`.
    """
    if device not in DEVICES:
        raise ValueError(f"device must be one of {DEVICES}, got {device!r}")
    return dict(F_hold=100.0, lock_delay=0.25, lock_rise_time=0.17, lock_gap_scale=1e-3,
                at_feet=float(device == "foot_magnets"),
                swivel=math.radians(18.0),      # a DIN 71802 angled ball joint's swivel
                swivel_pitch=0.0, face_width=0.03)   # m: a face a few centimetres across



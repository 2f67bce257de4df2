"""A landing scenario's gear, touchdown policy and lock-down device as the plant's vectors."""

from __future__ import annotations

import math

import numpy as np

from quadland.scenario import Scenario
from quadland_symbolic.landing.contact import (
    GEAR,
    LOCK,
    RK4_REAL_STABILITY,
    lock_defaults,
    stiffest_rate,
)
from quadland_symbolic.landing.gear import PEAK_RATE, TOUCHDOWN_POLICY
from quadland_symbolic.parameters import QUADROTOR

__all__ = ["gear_params", "lock_params", "policy_params", "touchdown_guidance", "contact_step",
           "stiffest_rate_value", "STEP_MARGIN", "FREE_GAP_WIDTHS", "free_flight_gap", "gear_span"]

#: RK4's step on the deck is this fraction of its stability edge on the stiffest mode
#: (docs/contact.md: 5 steps per 4 ms for the default gear, ``h lambda = 2.0``).
STEP_MARGIN = 0.8

#: The simulator flies the plant without the contact while the lowest foot is more than
#: this many onset widths above the deck (:func:`free_flight_gap`).
FREE_GAP_WIDTHS = 1000.0


def gear_span(data: dict) -> float:
    """Twice the farthest foot's distance from the centre, m (``[gear]`` feet_x, feet_y
    and ``quadrotor.gear_height``): a body touching the deck anywhere has its lowest foot
    within it of the deck."""
    g = data["gear"]
    return 2.0 * float(np.sqrt(g["feet_x"] ** 2 + g["feet_y"] ** 2
                               + data["quadrotor"]["gear_height"] ** 2))


def gear_params(scenario: Scenario) -> np.ndarray:
    """``[gear]`` as :data:`~quadland_symbolic.landing.contact.GEAR`: four feet at
    ``(+-feet_x, +-feet_y, -quadrotor.gear_height)``; ``welded`` zeroes the feet's
    stiffness, damping and friction (the pinned idealization feels no contact)."""
    g, h = scenario.data["gear"], scenario.data["quadrotor"]["gear_height"]
    x, y = g["feet_x"], g["feet_y"]
    feet = [[x, y, -h], [-x, y, -h], [-x, -y, -h], [x, -y, -h]]
    on = 0.0 if g["welded"] else 1.0
    return GEAR.pack(dict(r_feet=[v for foot in feet for v in foot], k=on * g["stiffness"],
                          c=on * g["damping"], mu=on * g["friction"], v_eps=g["slip_speed"],
                          b_slip=g["slip_damping_max"], delta_eps=g["onset_width"]))


def lock_params(scenario: Scenario) -> np.ndarray:
    """``[touchdown]``'s lock-down device as :data:`~quadland_symbolic.landing.contact.LOCK`
    (``lock = "none"``: no holding force; ``"foot_magnets"``: the holding force shared by a
    magnet in each foot)."""
    td = scenario.data["touchdown"]
    if td["lock"] == "none" or scenario.data["gear"]["welded"]:
        return LOCK.pack(dict(lock_defaults(), F_hold=0.0))
    return LOCK.pack(dict(F_hold=td["lock_hold_force"], lock_delay=td["lock_delay"],
                          lock_rise_time=td["lock_rise_time"],
                          lock_gap_scale=td["lock_gap_scale"],
                          at_feet=float(td["lock"] == "foot_magnets"),
                          swivel=math.radians(td["lock_swivel_deg"]),
                          swivel_pitch=math.radians(td["lock_swivel_pitch_deg"]),
                          face_width=td["lock_face_width"]))


def policy_params(scenario: Scenario) -> np.ndarray:
    """``[touchdown]``'s policy as :data:`~quadland_symbolic.landing.gear.TOUCHDOWN_POLICY`."""
    td = scenario.data["touchdown"]
    return TOUCHDOWN_POLICY.pack(dict(cut=float(td["policy"] == "idle"),
                                      cut_delay=td["cut_delay"], F_idle=td["idle_thrust"],
                                      s_switch=td["switch_impulse"]))


def touchdown_guidance(scenario: Scenario) -> dict:
    """``[touchdown]``'s flight-code policy as the guidance's parameters
    (:mod:`quadland_symbolic.landing.touchdown_policy`): ``policy = "secure"`` turns it
    on; otherwise it is inert (``fly_on = 0``) and the hardware cut (or none) acts. The
    aim point's pivot arm is ``pivot_aim`` times the gear's (``[gear]`` feet_x, feet_y,
    ``[quadrotor]`` gear_height). The profile's ``contact_drop`` is how much lower the
    lowest foot of the gear pitched ``contact_lean_deg`` reaches than the level gear's,
    ``fx sin th + hc cos th - hc`` (0 at 0 deg; at least 0: a lean that keeps a short gear's
    feet above the level gear's leaves the level profile)."""
    td, gear = scenario.data["touchdown"], scenario.data["gear"]
    aim, hc = td["pivot_aim"], scenario.data["quadrotor"]["gear_height"]
    lean = np.radians(td["contact_lean_deg"])
    return dict(contact_drop=max(gear["feet_x"] * np.sin(lean) + hc * np.cos(lean) - hc, 0.0),
                fly_on=float(td["policy"] == "secure"), flare_height=td["flare_height"],
                flare_tilt=np.radians(td["flare_tilt_deg"]), hold_time=td["hold_time"],
                level_time=td["level_time"], cut_time=td["cut_time"],
                aim_height=td["aim_height"], pivot_x=aim * gear["feet_x"],
                pivot_y=aim * gear["feet_y"],
                pivot_h=aim * hc, ground_airmode=float(td["ground_airmode"]),
                flare_deck_tilt=np.radians(td["flare_deck_tilt_deg"]),
                flare_deck_height=td["flare_deck_height"])


def contact_step(scenario: Scenario, p_quad: np.ndarray) -> float:
    """The longest RK4 step on the deck, s: :data:`STEP_MARGIN` of RK4's stability edge
    on the gear's stiffest mode (``stiffest_rate``) and the peak follower's rate."""
    rate = max(stiffest_rate_value(p_quad, gear_params(scenario)), PEAK_RATE)
    return STEP_MARGIN * RK4_REAL_STABILITY / rate


def stiffest_rate_value(p_quad, p_gear) -> float:
    """:func:`~quadland_symbolic.landing.contact.stiffest_rate` on numbers: the same
    operations in the same order as its ``casadi.DM`` evaluation (the sums over the feet
    from zero, the squares by the C library's ``pow``), so the same bits
    (``tests/test_run_python.py``), in a fiftieth of its time (0.25 ms a landing).
    Parameters off the physical domain (not finite; a division by zero, a negative root
    or an overflow, which Python raises; a NaN, which ``max`` keeps and ``mmax`` drops)
    take the ``casadi.DM`` evaluation."""
    q = np.asarray(p_quad, dtype=float).ravel()
    g = np.asarray(p_gear, dtype=float).ravel()
    if np.isfinite(q).all() and np.isfinite(g).all():
        try:
            rate = _stiffest_rate_floats(q, g)
        except (ArithmeticError, ValueError):
            rate = math.nan
        if math.isfinite(rate):
            return rate
    return float(stiffest_rate(q, g))


def _stiffest_rate_floats(q: np.ndarray, g: np.ndarray) -> float:
    """:func:`stiffest_rate_value` in Python's floats (raising where CasADi would not)."""
    p, g = QUADROTOR.unpack(q), GEAR.unpack(g)
    r, b, k = g["r_feet"], float(g["b_slip"][0]), float(g["k"][0])
    m1, (Ix, Iy, Iz) = float(p["m1"][0]), (float(v) for v in p["I"])
    n = r.shape[1]

    def total(values):
        out = 0.0
        for v in values:
            out += float(v)
        return out

    # ``** 2`` is the C library's pow, as CasADi's (not always x * x in the last bit)
    x2, y2 = total(x ** 2 for x in r[0].tolist()), total(y ** 2 for y in r[1].tolist())
    h_cg = -total(r[2].tolist()) / n
    I_rock = min(Ix, Iy)
    return max(n * b * (1 / m1 + h_cg ** 2 / I_rock), b * (x2 + y2) / Iz,
               math.sqrt(n * k / m1), math.sqrt(k * max(x2 / Iy, y2 / Ix)))


def free_flight_gap(scenario: Scenario) -> float:
    """The lowest foot's height above the deck, m, above which the simulator integrates
    the plant without the gear's contact (the loop's ``free_plant``, ``near`` of its
    sampled driver): :data:`FREE_GAP_WIDTHS` onset widths (10 cm for the default 0.1 mm).

    There the contact is exactly zero in double precision, so the run is the same bit
    for bit: a foot ``delta`` below the plane (negative above) presses with ``k
    delta_eps softplus(delta / delta_eps) + c sigma delta_dot``, whose ``exp(-|x|)``
    underflows to zero for ``|x| > 745.2`` and whose ``sigma = (1 + tanh(x / 2)) / 2``
    is zero for ``x < -38``; the lock-down's engagement and the rotor cut are zero
    until the contact switch closes (``t_contact = 0``), the gear's memory still. The
    margin beyond 746 widths covers the motion within a grid interval (both of whose
    ends must be above the gap; the driver integrates the whole plant otherwise).
    """
    return FREE_GAP_WIDTHS * float(scenario.data["gear"]["onset_width"])

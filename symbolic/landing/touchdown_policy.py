"""The flight code's touchdown policy: fly on until the lock-down holds, then cut.

At high airspeed a quadrotor on a car's roof cannot let go of the air at the
contact: at 100 km/h the drag (``Kt V + Kq V^2``, 17.8 N for the shipped
2 kg quadrotor) is close to its weight and acts 0.2 m above the feet, so a
body resting level on the deck with its rotors cut is rolled backwards over
its rear feet (``D h > m g a``: 3.6 N m against 2.9 N m) and slides (``D >
mu m g``) until the lock-down holds it; and it flies in leaning about 39 deg
into the airflow, past the gear's static tip-over angle about y (36.9 deg).
A rotor cut at the contact switch (``[touchdown] policy = "idle"``) lets the
drag slam the body from its lean onto its rear feet before the magnet has
engaged: it bounces or goes over (issue 18).

What a real system does is keep flying until the lock-down holds, then cut.
A ship helicopter landing with a haul-down system hovers on its own thrust while
the winch's cable (its tension up to the aircraft's weight) draws it into the
trap that grabs its probe, and the rotor is unloaded once it is held (the
Canadian "Beartrap", Helicopters Magazine, "Big helicopter - Little ship",
2007). PX4's multicopter land detector unloads in stages: at ground contact the
position controller drops the horizontal thrust, at "maybe landed" it sets the
thrust to zero, and the motors are disarmed only once "landed" has held
(PX4 land_detector module documentation; COM_DISARM_LAND). With
``fly_on = 1`` this module's schedule, a function of the guidance's phase,
its timer (the time since touchdown) and its reference height, tells the
landing step (:func:`~quadland_symbolic.landing.controller.landing_law`)
through :data:`TOUCHDOWN_COMMANDS`, appended to the position reference:

1. **flare** (descend, the reference within ``flare_height`` of touchdown,
   and after): the tilt of the thrust axis is limited to ``flare_tilt``
   (below the static tip-over angle), so the gear meets the deck inside it.
   The horizontal thrust it gives up is a small backward drift relative to
   the deck over the last few centimetres. With ``flare_deck_tilt`` below
   ``pi / 2`` the thrust axis is also held within it of the deck's normal
   (below ``flare_deck_height`` above touchdown, and on the deck)
   (the axis the contact's tilt is judged from; ``deck_tilt_limit``, applied by
   :func:`~quadland_symbolic.landing.attitude.thrust_attitude` after the
   vertical's cone): a lean into the airflow over a deck rolled or pitched the
   other way is cut back only where the two add past it;
2. **hold** (touchdown, the first ``hold_time``): the flight code keeps
   flying as in the descent, its reference crawling on into the deck at
   ``touchdown_speed`` (:func:`touchdown_crawl`: the gear stays pressed on it
   rather than hovering at the contact's height), while the lock-down's delay
   runs (the contact switch starts it);
3. **level** (the next ``level_time``): the attitude command is blended
   linearly from the position loop's to the deck's level attitude and the
   collective thrust down to zero (the attitude loop keeps priority over the
   collective, :func:`~quadland_symbolic.landing.desaturation.thrust_within_moments`):
   the body rotates onto its rear feet under control, and the gap closing
   brings the engaging lock's pull in;
4. **cut** (from ``cut_time`` after touchdown, at least ``hold_time +
   level_time``): the rotor commands are zero. ``cut_time`` is chosen where
   the lock's pull exceeds what the drag needs of it (the shipped
   highway_100: 77 N at 0.5 s against 16 N to stop the slide and 4 N to stop
   the roll-over).

With ``ground_airmode = 0`` the collective is not raised for the moments from touchdown
on (:data:`TOUCHDOWN_COMMANDS`' ``airmode``, read by
:func:`~quadland_symbolic.landing.desaturation.thrust_within_moments`): a body that pivots
onto its rear feet faster than the level-out's blend makes the attitude loop ask for
moments that, in air mode, buy themselves collective thrust, which unloads the feet the
drag is sliding (docs/landing.md, "highway_100: the level-out without air mode"). The
rotor the moments would take below 0 is clipped, which still adds its deficit to the
thrust made; PX4's mixer with ``MC_AIRMODE`` disabled never raises the thrust to
unsaturate a rotor and scales roll and pitch back instead, a different allocation.

With ``pivot_x``, ``pivot_y``, ``pivot_h`` set (the gear's arm, times ``[touchdown]
pivot_aim``), the policy also aims ahead of the level-out: the body meets the deck
leaning into the airflow, lowest feet first, and levelling it about those feet moves its
centre of mass back by ``(R1 - R_level) r`` (:func:`pivot_shift`; ``fx (1 - cos th) + hc
sin th`` for a pitch ``th``); from ``aim_height`` above touchdown and on the deck the
landing step tracks the reference minus that move (:func:`aim_reference`), so that the
levelled body sits on the pad (docs/landing.md, "The pivot at the level-out").

The commands come from the flight code's own touchdown verdict (the
guidance's touchdown phase: the contact switch, or the land detector on
sensors): a false verdict in the air would level out and cut there, as
PX4's false ground contact does (PX4-Autopilot issue 11683).

With ``fly_on = 0`` every command is inert (no tilt limit beyond the
controller's, no blend, full thrust, no cut), and the rotor cut, if any, is
the gear's contact switch's in hardware (:mod:`quadland_symbolic.landing.gear`).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.layout import Field, Layout

__all__ = ["TOUCHDOWN_COMMANDS", "NO_TILT_LIMIT", "INERT_COMMANDS", "touchdown_commands",
           "touchdown_crawl", "bounded_commands", "apply_touchdown_commands", "pivot_shift",
           "aim_reference", "cone_of"]

#: rad: the tilt limit of an inert policy, above any controller's (``tilt_max < pi/2``).
NO_TILT_LIMIT = ca.pi / 2

#: What the guidance's touchdown policy tells the landing step each period.
TOUCHDOWN_COMMANDS = Layout("td_cmd", (
    Field("tilt_limit", 1, "rad", "largest tilt of the thrust axis (with the controller's own)"),
    Field("level", 1, "-", "blend of the attitude command towards the deck's level, 0 to 1"),
    Field("thrust_scale", 1, "-", "factor on the collective thrust before the mixer, 0 to 1"),
    Field("power", 1, "-", "factor on the rotor commands: 0 cuts them"),
    Field("airmode", 1, "0/1", "1: the collective rises for the moments (air mode); 0: it "
          "does not, the moments give way"),
    Field("pivot", 3, "m", "the gear's pivot arm whose levelling the aim point anticipates "
          "(feet x, y half-spacings, height below the centre of mass; 0: no shift)",
          elements=("pivot_x", "pivot_y", "pivot_h")),
    Field("deck_tilt_limit", 1, "rad", "largest angle of the thrust axis from the deck's normal "
          "(pi/2: none)"),
), "touchdown policy's commands to the landing step")

#: :data:`TOUCHDOWN_COMMANDS` that change nothing (the policy off, or before its flare).
INERT_COMMANDS = dict(tilt_limit=float(NO_TILT_LIMIT), level=0.0, thrust_scale=1.0, power=1.0,
                      airmode=1.0, pivot=[0.0, 0.0, 0.0], deck_tilt_limit=float(NO_TILT_LIMIT))


def touchdown_commands(down, descending, timer_next, z_next, p):
    """The policy's :data:`TOUCHDOWN_COMMANDS` for the step (module docstring).

    ``down`` is 1 when the guidance's phase after the step is touchdown or landed,
    ``descending`` when it is the descent; ``timer_next`` the guidance's timer after
    the step (the time since touchdown in the touchdown phase; it holds once landed),
    ``z_next`` the reference height after the step (m), ``p`` the unpacked
    :data:`~quadland_symbolic.landing.guidance.GUIDANCE_PARAMS`.
    """
    on = p["fly_on"] > 0.5
    low = z_next - p["touchdown_height"] - p["contact_drop"] <= p["flare_height"]
    flaring = ca.logic_or(down, ca.logic_and(descending, low))
    tilt_limit = ca.if_else(ca.logic_and(on, flaring), p["flare_tilt"], NO_TILT_LIMIT)
    ramp = ca.fmin(ca.fmax((timer_next - p["hold_time"]) / p["level_time"], 0), 1)
    level = on * down * ramp
    cut = on * down * (timer_next >= ca.fmax(p["cut_time"], p["hold_time"] + p["level_time"]))
    aiming = on * ca.logic_or(down, ca.logic_and(descending, z_next - p["touchdown_height"]
                                                 - p["contact_drop"] <= p["aim_height"]))
    pivot = aiming * ca.vertcat(p["pivot_x"], p["pivot_y"], p["pivot_h"])
    airmode = 1 - on * down * (1 - p["ground_airmode"])
    h_next = z_next - p["touchdown_height"] - p["contact_drop"]
    deck_low = ca.logic_or(down, ca.logic_and(descending, ca.logic_and(
        low, h_next <= p["flare_deck_height"])))
    deck_limit = ca.if_else(ca.logic_and(on, deck_low), p["flare_deck_tilt"], NO_TILT_LIMIT)
    return ca.vertcat(tilt_limit, level, 1 - level, 1 - cut, airmode, pivot, deck_limit)


def touchdown_crawl(in_touchdown, p):
    """The reference's descent rate in the touchdown phase, m/s (down): the crawl
    ``touchdown_speed`` goes on into the deck while the policy flies on (so that the
    position loop keeps the gear pressed on it instead of hovering at the height of the
    contact), else 0 (the reference holds). ``in_touchdown``: the phase after the step
    is touchdown; ``p`` the unpacked guidance parameters."""
    return ca.if_else(ca.logic_and(p["fly_on"] > 0.5, in_touchdown), p["touchdown_speed"], 0)


def bounded_commands(commands: dict, tilt_max) -> dict:
    """The landing step's reading of :data:`TOUCHDOWN_COMMANDS` (``commands``, unpacked):
    the tilt limit within ``[0, tilt_max]`` (the controller's own), the deck's within
    ``[0, pi/2]``, the blend, the
    collective's factor, the power and the air-mode flag within ``[0, 1]``, whatever the
    caller passed, so that the rotor commands stay within ``[0, F_max]`` and the thrust
    within ``[0, 4 F_max]``."""
    def unit(v):
        return ca.fmin(ca.fmax(v, 0), 1)
    return dict(tilt_limit=ca.fmin(tilt_max, ca.fmax(commands["tilt_limit"], 0)),
                level=unit(commands["level"]), thrust_scale=unit(commands["thrust_scale"]),
                power=unit(commands["power"]), airmode=unit(commands["airmode"]),
                pivot=ca.fmax(commands["pivot"], 0),
                deck_tilt_limit=ca.fmin(NO_TILT_LIMIT, ca.fmax(commands["deck_tilt_limit"], 0)))


def apply_touchdown_commands(level, eta_c, eta_level):
    """The attitude command ``eta_c`` blended towards ``eta_level`` by
    :data:`TOUCHDOWN_COMMANDS`' ``level``; ``level = 0`` returns ``eta_c`` exactly."""
    return eta_c + level * (eta_level - eta_c)


def pivot_shift(pivot, eta1, eta2):
    """The deck-frame move of the centre of mass that levelling the body about its lowest
    feet would make, m (its third element 0): the aim point's correction.

    A body leaning into the airflow meets the deck with its lowest feet first; the
    lock-down pins them, and the level-out (:func:`apply_touchdown_commands`: roll and
    pitch to the deck's, the yaw held) turns the body about them. A foot at ``r`` in
    body axes stays at ``p + R1 r = p' + R_lvl r``, so the centre moves by ``(R1 - R_lvl)
    r``: for a pitch ``th`` (nose down, feet at ``x = fx``, ``z = -hc``), by ``fx (1 - cos
    th) + hc sin th`` backwards. The position loop tracks ``p_ref`` minus this move, so
    that the body levelled about its feet sits on the reference.

    ``pivot`` is the :data:`TOUCHDOWN_COMMANDS`' arm ``(fx, fy, hc)`` (zero: no shift), the
    lowest feet taken at ``(+-fx, +-fy, -hc)`` on the side of the lean; ``eta1``, ``eta2``
    the body's and the deck's Euler angles in E.
    """
    R1, R_deck = rotation(eta1), rotation(eta2)
    R_level = rotation(ca.vertcat(eta2[0], eta2[1], eta1[2]))
    n_body = R1.T @ R_deck[:, 2]                    # the deck normal in body axes
    r = ca.vertcat(pivot[0] * ca.sign(-n_body[0]), pivot[1] * ca.sign(-n_body[1]), -pivot[2])
    move = R_deck.T @ (R1 - R_level) @ r
    return ca.vertcat(move[0], move[1], 0)


def aim_reference(ref, pivot, eta1, eta2):
    """The position reference ``ref`` (``p_ref`` first, then its rates and the rest) with
    ``p_ref`` moved against :func:`pivot_shift`; ``pivot = 0`` returns it unchanged."""
    return ca.vertcat(ref[0:3] - pivot_shift(pivot, eta1, eta2), ref[3:])


def cone_of(commands: dict, R_deck):
    """The deck's cone for :func:`~quadland_symbolic.landing.attitude.thrust_attitude`'s
    ``deck``: :func:`bounded_commands`' ``deck_tilt_limit`` about ``R_deck``'s normal."""
    return commands["deck_tilt_limit"], R_deck

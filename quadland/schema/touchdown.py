"""The ``[touchdown]`` keys of the landing schema: what the flight code does once the gear
touches (docs/landing.md, "Touchdown policy"), the lock-down device's keys spliced in."""

from __future__ import annotations

from quadland.schema.fields import Field
from quadland.schema.lock import LOCK_FIELDS

__all__ = ["TOUCHDOWN_FIELDS"]

F, B, S = float, bool, str
_POS = dict(lo=0.0, lo_open=True)

#: ``[touchdown]``'s keys, the landing schema's table of that name.
TOUCHDOWN_FIELDS = {
    "policy": Field(S, "-", "idle: the gear's contact switch cuts the rotors to idle_thrust; "
                    "hold: the flight code keeps commanding them; secure: it flies on "
                    "until the lock holds, then cuts them", choices=("idle", "hold", "secure")),
    "cut_delay": Field(F, "s", "time from the contact switch closing to the rotor cut",
                       lo=0.0, hi=10.0),
    "idle_thrust": Field(F, "N", "each rotor's command once cut, at most F_max "
                         "(thrust_to_weight mass gravity / 4)", lo=0.0, hi=1e3),
    "switch_impulse": Field(F, "s", "load impulse over the weight that closes the contact "
                            "switch", hi=1.0, **_POS),
    "flare_height": Field(F, "m", "secure: reference height above touchdown from which the "
                          "tilt is limited to flare_tilt_deg", lo=0.0, hi=100.0),
    "flare_tilt_deg": Field(F, "deg", "secure: tilt limit of the thrust axis from the flare "
                            "on", hi=89.0, **_POS),
    "hold_time": Field(F, "s", "secure: time from touchdown during which the flight code "
                       "flies on as in the descent", lo=0.0, hi=10.0),
    "level_time": Field(F, "s", "secure: time of the level-out to the deck's attitude and "
                        "the thrust's ramp-down, after hold_time", hi=10.0, **_POS),
    "cut_time": Field(F, "s", "secure: time from touchdown to the rotor cut (at least "
                      "hold_time + level_time)", lo=0.0, hi=10.0),
    "pivot_aim": Field(F, "-", "secure: share of the level-out's pivot about the lowest "
                       "feet the aim point anticipates (0: none, 1: all)", lo=0.0, hi=1.0),
    "aim_height": Field(F, "m", "secure: reference height above touchdown from which the "
                        "aim point anticipates the pivot", lo=0.0, hi=100.0),
    "contact_lean_deg": Field(F, "deg", "the pitch at which the descent profile expects "
                              "the gear to meet the deck: its crawl ends where the lowest "
                              "foot of a body pitched this much does (0: level)", lo=0.0,
                              hi=80.0, default=0.0),
    "ground_airmode": Field(B, "-", "secure: false: from touchdown on the collective is not "
                            "raised for the attitude's moments (air mode off)", default=True),
    "flare_deck_tilt_deg": Field(F, "deg", "secure: the flare's limit from the deck's "
                                 "normal too (90: none)", hi=90.0, default=90.0, **_POS),
    "flare_deck_height": Field(F, "m", "secure: flare_deck_tilt_deg below this reference "
                               "height above touchdown", lo=0.0, hi=1e3, default=1e3),
    **LOCK_FIELDS,
}

"""The ``[touchdown]`` keys of the lock-down device (docs/contact.md, "The lock-down device"):
an electro-permanent magnet under the gear's centre, or one in each foot on a ball joint."""

from __future__ import annotations

from quadland.schema.fields import Field

__all__ = ["LOCK_FIELDS"]

F, S = float, str
_POS = dict(lo=0.0, lo_open=True)

#: ``[touchdown]``'s lock keys, spliced into the landing schema.
LOCK_FIELDS = {
    "lock": Field(S, "-", "lock-down device: none, magnet (an EPM under the gear's centre) or "
                  "foot_magnets (one per foot)", choices=("none", "magnet", "foot_magnets")),
    "lock_hold_force": Field(F, "N", "the lock's largest holding force", lo=0.0, hi=1e5),
    "lock_delay": Field(F, "s", "dead time from the contact switch to the lock's pull",
                        lo=0.0, hi=10.0),
    "lock_rise_time": Field(F, "s", "time constant of the lock's first-order rise",
                            hi=10.0, **_POS),
    "lock_gap_scale": Field(F, "m", "gap at which the lock's pull falls to a quarter",
                            hi=1e6, **_POS),
    "lock_swivel_deg": Field(F, "deg", "foot_magnets: each magnet's face swivels flush "
                             "within this of its neutral axis (a DIN 71802 ball joint's "
                             "18 deg; 90: flush at any lean, an idealization)",
                             lo=0.0, hi=90.0, default=18.0),
    "lock_swivel_pitch_deg": Field(F, "deg", "foot_magnets: the neutral axis pitched nose "
                                   "down from the body's z axis", lo=-90.0, hi=90.0,
                                   default=0.0),
    "lock_face_width": Field(F, "m", "foot_magnets: a magnet's face across, which past its "
                             "swivel meets the deck on its edge", lo=0.0, hi=1.0,
                             default=0.03),
}

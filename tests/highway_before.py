"""highway's touchdown and descent before issue 19's flare and leash (``42d6c22``): the
rotors cut at the contact switch (the "idle" policy, the secure policy's keys inert) and
the descent's reference not leashed (docs/landing.md, "highway: the flare and the leash").
The tests that pin flights of highway's law of before (campaign rows recorded on ``main``,
the judge's forced contacts, the mechanisms checked on the calm flight) fly these, on the
pad of before: the large marker alone (no nested marker, docs/landing.md, "The nested
marker"), and with no crawl gate and the land detector of before
(``reference.HIGHWAY_SIXTEENTH``)."""

from reference import HIGHWAY_SIXTEENTH

BEFORE = [*HIGHWAY_SIXTEENTH, 'touchdown.policy="idle"', "touchdown.flare_tilt_deg=34.0",
          "touchdown.level_time=0.35", "touchdown.cut_time=0.5", "landing.descent_leash=0.0",
          "sensors.vision.small_range_max=0.0"]

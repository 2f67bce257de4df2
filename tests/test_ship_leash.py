"""The ships' descent on a leash: their last sink-rate failures replayed (issue 19 item 4;
docs/landing.md, "The ships on a leash").

On main's 300-run campaigns the ships' sink-rate failures (0.51-0.55 m/s against 0.5) were
descents committed in a still moment of a broad sea whose deck then fell away: the
quadrotor, a few centimetres behind its falling reference, caught up with the deck at the
crawl's 0.3 m/s plus 0.11-0.18 m/s of tracking (the filter's own relative vertical velocity
past the crawl) plus the estimate's error. ``landing.descent_leash`` (the guidance's rule,
``z_next = max(z_ref - rate dt, min(z_ref, z - l))``, tests/test_descent_leash.py) stops
the falling reference where it would lead the quadrotor down by more than ``l``; the ships
ship ``l = 0.02`` m. Here each campaign failure is flown from its draw without the leash
(the campaign's row, to the bit: a reproducer) and as shipped, and the rule is checked on
the shipped flight itself: wherever the filter's height is more than the leash (and a
centimetre of the trajectory's 100 Hz sampling) above the reference, the reference does
not fall.
"""

import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)

#: The ships' leash, m, and the crawl, m/s (their TOMLs).
LEASH, CRAWL = 0.02, 0.3
#: The guidance before the ships' leash.
NO_LEASH = ["landing.descent_leash=0.0", "landing.leash_height=1000.0"]
#: The touchdown height (the gear, m) and one step, s, of the by-hand steps below.
TOUCHDOWN, DT = 0.2, 0.1


def _z_next(z_ref, z, leash_height):
    """The reference height after one step of a committed descent over the pad from
    ``z_ref``, the quadrotor at height ``z`` and at rest horizontally, on a 2 cm leash that
    holds below ``leash_height`` above touchdown."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=1, ms_rise=0.0, ms_rise_rate=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=TOUCHDOWN, descent_leash=LEASH,
                                   leash_height=leash_height))
    xg_next, _ = (np.asarray(v, dtype=float).ravel() for v in guidance_function()(
        xg, [0.0, 0.0, z], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
    return GUIDANCE_STATE.unpack(xg_next)["z_ref"][0]


@pytest.mark.parametrize(("z_ref", "z", "leash_height", "expected"), [
    # 0.8 m above touchdown, the quadrotor 20 cm behind: above leash_height the profile's
    # fall (h / descent_time = 0.8 m/s clamped to 0.7: 7 cm), below it (the default, the
    # whole descent) the reference waits
    (1.0, 1.2, 0.3, 1.0 - 0.7 * DT),
    (1.0, 1.2, 1e3, 1.0),
    # in the crawl (0.25 m above touchdown: 0.3 m/s, 3 cm a step) the same 20 cm behind:
    # the reference waits; 1 cm behind, it falls 1 cm of the step's 3, to 2 cm below it
    (0.45, 0.65, 0.3, 0.45),
    (0.45, 0.46, 0.3, 0.44),
    # on the reference: the step's 3 cm fall stops at the leash's 2 cm; above the leash's
    # height the whole step
    (0.45, 0.45, 0.3, 0.43),
    (0.45, 0.45, 0.2, 0.45 - 0.3 * DT),
])
def test_the_leash_holds_only_below_its_height(z_ref, z, leash_height, expected):
    """``z_next = max(z_ref - rate dt, min(z_ref, z - l))`` where ``z_ref - touchdown`` is
    at or below ``leash_height``, ``z_ref - rate dt`` above it; by hand."""
    assert _z_next(z_ref, z, leash_height) == pytest.approx(expected, abs=1e-12)


"""``landing.max_deck_fall``: the committed descent pauses above the crawl while the deck
falls faster (symbolic/landing/guidance.py, "Abort"; docs/landing.md, "ship_ss5: a
wave-off and a pause on a deck dropping away").

One guidance step is checked against the profile written out by hand: the reference's
next height is ``z_ref - clamp(h / descent_time, touchdown_speed, descent_speed) dt``
(``h`` its height above touchdown) when it falls, ``z_ref`` when it pauses.
"""

import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    guidance_function,
)

DT = 0.004
GUIDANCE = guidance_function()
#: The pause's threshold, m/s.
FALL = 1.5


def _step(z_ref, committed, deck_rise, max_deck_fall=FALL, deck_rise_rate=0.0):
    """One step of a quadrotor on its reference over the pad's centre, at rest relative
    to the deck: the state after it."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=committed, armed=1.0, ms_rise=0.04,
                                  ms_rise_rate=0.08))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, max_deck_fall=max_deck_fall))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0, marker_age=0, contact_switch=0.0))
    out = GUIDANCE(xg, [0, 0, z_ref], [0, 0, 0], deck_rise, deck_rise_rate, cues, DT, pg)[0]
    g = GUIDANCE_STATE.unpack(np.asarray(out, dtype=float).ravel())
    return g["z_ref"][0], g["committed"][0], g["aborts"][0], g["phase"][0]


def _fall(z_ref):
    """The profile's next height by hand."""
    h = z_ref - GUIDANCE_P["touchdown_height"]
    rate = min(max(h / GUIDANCE_P["descent_time"], GUIDANCE_P["touchdown_speed"]),
               GUIDANCE_P["descent_speed"])
    return z_ref - rate * DT


@pytest.mark.parametrize("z_ref", [1.1, 0.8, 0.55])
def test_a_deck_falling_faster_pauses_the_committed_descent_above_the_crawl(z_ref):
    """Committed, above the crawl (h = 0.9, 0.6, 0.35 m > touchdown_speed x descent_time
    = 0.3 m): a deck falling at 1.6 m/s holds the reference where it is, committed, no
    abort; at 1.4 m/s it falls on by the profile."""
    assert _step(z_ref, 1, -1.6) == (z_ref, 1, 0, DESCEND)
    z, committed, aborts, phase = _step(z_ref, 1, -1.4)
    assert z == pytest.approx(_fall(z_ref), rel=1e-12, abs=1e-15)
    assert (committed, aborts, phase) == (1, 0, DESCEND)


def test_the_crawl_goes_on_over_a_falling_deck():
    """In the crawl (h = 0.25 m) the descent does not pause (a hover centimetres over the
    deck reads as a touchdown): at 3 m/s of fall the reference falls at touchdown_speed."""
    z, committed, aborts, _ = _step(0.45, 1, -3.0)
    assert z == pytest.approx(0.45 - GUIDANCE_P["touchdown_speed"] * DT, rel=1e-12)
    assert (committed, aborts) == (1, 0)


def test_the_uncommitted_descent_is_not_paused_by_the_fall():
    """Above the wait height (z_ref = 2 m, uncommitted) the reference falls toward it at
    descent_speed whatever the deck does, as before the key."""
    z, committed, aborts, _ = _step(2.0, 0, -3.0)
    assert z == pytest.approx(2.0 - GUIDANCE_P["descent_speed"] * DT, rel=1e-12)
    assert (committed, aborts) == (0, 0)


def test_the_default_never_pauses():
    """At the default (1000 m/s) a 50 m/s fall leaves the step as a deck at rest."""
    assert load_scenario("highway")["landing.max_deck_fall"] == 1e3
    for z_ref in (1.1, 0.8, 0.55):
        assert _step(z_ref, 1, -50.0, max_deck_fall=1e3)[0] == pytest.approx(
            _fall(z_ref), rel=1e-12)


def test_no_scenario_sets_the_pause():
    """A trial key: every landing scenario takes the default (``ship_ss5`` measured at 1.2
    and 1.5 m/s with ``--set``: the same counts as without it)."""
    for name in ("ship", "ship_ss5", "highway", "turning", "highway_100"):
        assert load_scenario(name)["landing.max_deck_fall"] == 1e3

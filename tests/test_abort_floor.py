"""``abort_floor``: the crawl's out-of-limits abort is not started once the gear's estimated
height above the deck is within it (symbolic/landing/abort_floor.py), by hand on one guidance
step: the abort sends the phase back to align, counts one abort and resets the reference to
the hover height; without it the committed crawl falls on at ``touchdown_speed``."""

import pytest
from crawl_step import CRAWLED, H
from crawl_step import aborted as _aborted
from crawl_step import crawl_step as _step
from reference import GUIDANCE_P

from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import ALIGN, DESCEND


def test_the_default_aborts_down_to_the_contact():
    """-1000 m (the schema's default): an offset past max_offset (0.25 > 0.2 m) or a speed
    past max_relative_speed (0.6 > 0.5 m/s) aborts with the gear 1 cm over the deck, as
    the guidance did before the key."""
    assert GUIDANCE_P["abort_floor"] == -1e3
    for kw in (dict(offset=0.25), dict(speed=0.6)):
        phase, aborts, h = _step(0.01, **kw)
        assert (phase, aborts) == _aborted()[:2]
        assert h == pytest.approx(_aborted()[2], rel=1e-12)


@pytest.mark.parametrize("kw", [dict(offset=0.25), dict(speed=0.6)])
def test_within_the_floor_the_crawl_goes_on(kw):
    """abort_floor 0.06 m: with the gear 1 cm over the deck the same step does not abort, the
    crawl falls on at touchdown_speed; 10 cm over it, it aborts as before."""
    phase, aborts, h = _step(0.01, abort_floor=0.06, **kw)
    assert (phase, aborts) == CRAWLED[:2]
    assert h == pytest.approx(CRAWLED[2], rel=1e-12)
    assert _step(0.10, abort_floor=0.06, **kw)[:2] == _aborted()[:2]


def test_at_the_floor_no_abort_and_just_above_it_one():
    """'At or below': with exact binary heights (touchdown_height 0.25, the floor 0.125 m)
    the gear at 0.125 m does not abort, at 0.125 + 2^-20 m it does."""
    p = dict(touchdown_height=0.25, abort_floor=0.125)
    assert _step(0.125, offset=0.25, **p)[:2] == (DESCEND, 0.0)
    assert _step(0.125 + 2.0 ** -20, offset=0.25, **p)[:2] == (ALIGN, 1.0)


def test_the_floor_counts_from_the_expected_contact():
    """With contact_drop 0.05 m the contact is expected 0.05 m lower than the level gear's:
    the centre 0.29 m over the pad is 0.04 m over the contact (within 0.06 m: no abort),
    while with no drop it is 0.09 m over it (an abort)."""
    z_centre = 0.29
    drop = 0.05
    gap_drop = z_centre - GUIDANCE_P["touchdown_height"] - drop
    gap_level = z_centre - GUIDANCE_P["touchdown_height"]
    assert _step(gap_drop, offset=0.25, abort_floor=0.06, contact_drop=drop)[:2] == (DESCEND, 0)
    assert _step(gap_level, offset=0.25, abort_floor=0.06)[:2] == (ALIGN, 1.0)


def test_within_the_limits_the_floor_changes_nothing():
    """An offset and a speed within the limits abort nothing, with or without the floor: the
    same step, to the bit."""
    a = _step(0.01, offset=0.15, speed=0.4)
    b = _step(0.01, offset=0.15, speed=0.4, abort_floor=0.06)
    assert a == b and a[:2] == CRAWLED[:2]


def test_a_scenario_that_leaves_it_out_aborts_down_to_the_contact():
    """The schema's default is -1000 m: ship leaves the key out."""
    assert load_scenario("ship").data["landing"]["abort_floor"] == -1e3


def test_with_crawl_pause_the_floor_holds_the_crawl_instead():
    """crawl_pause 1: past the limits is out of the align band (0.25 > 0.2 / 2), so within
    the 0.06 m floor the step neither aborts nor falls: the reference stays H over the
    contact (the pause), the phase and abort count as before the step; without the floor
    it aborts as with the pause off."""
    phase, aborts, h = _step(0.01, offset=0.25, abort_floor=0.06, crawl_pause=1.0)
    assert (phase, aborts) == (DESCEND, 0.0)
    assert h == pytest.approx(H, rel=1e-12)
    assert _step(0.01, offset=0.25, crawl_pause=1.0)[:2] == _aborted()[:2]

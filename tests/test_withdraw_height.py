"""``withdraw_height``: where a rising deck no longer withdraws the committed descent
(symbolic/landing/guidance.py), by hand on one guidance step."""

import pytest
from crawl_step import DT, withdraw_step
from reference import GUIDANCE_P

TOUCHDOWN = GUIDANCE_P["touchdown_height"]


def _step(h, rise, withdraw_height):
    """One step committed with the reference ``h`` above touchdown, the quadrotor on it,
    at rest, the deck rising at ``rise``. Returns z_ref, committed and aborts after it."""
    return withdraw_step(h, rise, withdraw_height=withdraw_height)


@pytest.mark.parametrize("rise", [GUIDANCE_P["max_deck_rise"] + 0.1, 1.5])
def test_the_default_withdraws_down_to_the_contact(rise):
    """-1000 m: a deck rising past max_deck_rise withdraws the commit in the crawl (0.1 m)
    and below touchdown (-0.05 m): one abort, the reference glides up at descent_speed."""
    for h in (0.1, -0.05, 0.6):
        z, committed, aborts = _step(h, rise, -1e3)
        assert (committed, aborts) == (0.0, 1.0)
        assert z == pytest.approx(TOUCHDOWN + h + GUIDANCE_P["descent_speed"] * DT, rel=1e-12)


def test_the_crawl_goes_on_below_the_withdraw_height():
    """withdraw_height 0.3 m (the crawl, touchdown_speed x descent_time): at 0.1 m the
    committed crawl goes on at touchdown_speed, no abort; at 0.6 m the commit is withdrawn
    as before; a deck within max_deck_rise withdraws nothing anywhere."""
    rise = GUIDANCE_P["max_deck_rise"] + 0.1
    z, committed, aborts = _step(0.1, rise, 0.3)
    assert (committed, aborts) == (1.0, 0.0)
    assert z == pytest.approx(TOUCHDOWN + 0.1 - GUIDANCE_P["touchdown_speed"] * DT, rel=1e-12)
    assert _step(0.3, rise, 0.3)[1:] == (1.0, 0.0)          # at the height: no withdrawal
    assert _step(0.6, rise, 0.3)[1:] == (0.0, 1.0)
    assert _step(0.6, GUIDANCE_P["max_deck_rise"] - 0.1, 0.3)[1:] == (1.0, 0.0)


def test_the_withdraw_height_is_above_the_expected_contact():
    """With contact_drop 0.1 m the contact is expected 0.1 m lower (contact_height), and the
    crawl (0.3 m above it) and withdraw_height count from there: a reference 0.35 m above
    touchdown_height is 0.25 m above the contact, in the crawl, and goes on at
    touchdown_speed; 0.45 m (0.35 m above it) is withdrawn. Counted from touchdown_height
    (the merge's other side) the first would have been withdrawn inside the crawl."""
    rise, drop = GUIDANCE_P["max_deck_rise"] + 0.1, 0.1
    for h, expected in ((0.35, (1.0, 0.0)), (0.45, (0.0, 1.0))):
        z, committed, aborts = withdraw_step(h, rise, withdraw_height=0.3, contact_drop=drop)
        assert (committed, aborts) == expected
        if expected[0]:
            assert z == pytest.approx(TOUCHDOWN + h - GUIDANCE_P["touchdown_speed"] * DT,
                                      rel=1e-12)

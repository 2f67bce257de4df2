"""The plant without the gear's contact before the deck is near (issue 20).

The sampled driver integrates the loop's ``free_plant`` over each grid interval
whose lowest foot is more than ``free_flight_gap`` above the deck at both ends:
there the contact's forces are exactly zero in double precision, so a landing is
the same bit for bit as one on the whole plant throughout.
"""

from __future__ import annotations

import numpy as np
import pytest

import quadland
from quadland.kinds.landing import simulate as landing_simulate
from quadland.kinds.landing.gear import FREE_GAP_WIDTHS, free_flight_gap
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.loop import first_contact_function
from quadland_symbolic.landing.plant import LANDING_PLANT_STATE, loop_plant_function


def _fly(monkeypatch, scenario, near):
    monkeypatch.setattr(landing_simulate, "free_flight_gap", lambda sc: near)
    return quadland.simulate(scenario)


def _same(a, b) -> bool:
    return set(a.columns) == set(b.columns) and all(
        np.array_equal(a[k], b[k], equal_nan=True) for k in a.columns) and np.array_equal(
        a.states, b.states)


@pytest.mark.parametrize("name", ["highway", "ship"])
def test_the_free_plant_far_from_the_deck_changes_no_bit(monkeypatch, name):
    """highway (flat roof) and ship (a heaving, rolling deck): the landing with the free
    plant far from the deck equals, bit for bit, the one on the whole plant throughout
    (``near`` infinite); with the switch at the deck itself (``near = 0``) the gear's
    memory differs (the contact's tiny forces in the last centimetres are lost)."""
    sc = load_scenario(name)
    whole = _fly(monkeypatch, sc, np.inf)
    free = _fly(monkeypatch, sc, free_flight_gap(sc))
    assert free_flight_gap(sc) == FREE_GAP_WIDTHS * 1e-4 == pytest.approx(0.1)
    assert _same(whole, free)
    late = _fly(monkeypatch, sc, 0.0)
    assert not np.array_equal(late.states, whole.states)


def _state_at_gap(gap_widths: float, sc) -> tuple[np.ndarray, float]:
    """The initial state of ``sc`` lowered so that its lowest foot is ``gap_widths``
    onset widths above the deck (the first contact function's own gap), and that gap."""
    lv = landing_values(sc)
    xp = np.array(lv.xp0, dtype=float)
    g0 = float(first_contact_function()(xp, 0.0, lv.pp))
    z = LANDING_PLANT_STATE.index("z1")
    target = gap_widths * 1e-4
    xp[z] -= g0 - target
    return xp, float(first_contact_function()(xp, 0.0, lv.pp))


def test_the_contact_vanishes_exactly_beyond_746_onset_widths():
    """By hand (quadland.kinds.landing.gear.free_flight_gap): a foot ``x`` onset widths
    above the deck presses with ``k eps log1p(exp(-x))``, exactly zero once ``exp(-x)``
    underflows (x > 745.2), a subnormal force below that. So at 800 widths the whole
    plant's derivative equals the free plant's bit for bit, at 700 it does not (the
    gear's load impulse moves)."""
    sc = load_scenario("highway")
    lv = landing_values(sc)
    F_cmd, w = np.full(4, 5.0), np.zeros(9)
    whole, free = loop_plant_function(True), loop_plant_function(False)
    impulse = LANDING_PLANT_STATE.slice("gear").start
    for widths, equal in ((800.0, True), (700.0, False)):
        xp, gap = _state_at_gap(widths, sc)
        assert gap == pytest.approx(widths * 1e-4, rel=1e-9)
        a = np.asarray(whole(xp, F_cmd, w, 0.0, lv.pp), dtype=float).ravel()
        b = np.asarray(free(xp, F_cmd, w, 0.0, lv.pp), dtype=float).ravel()
        assert np.array_equal(a, b) == equal
        if not equal:
            assert 0 < a[impulse] < 1e-300 and b[impulse] == 0

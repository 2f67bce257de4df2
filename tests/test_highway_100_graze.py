"""highway_100's contact switch feels a front foot's graze (issue 19).

``touchdown.switch_impulse`` 0.0005 s (was 0.002 s; docs/landing.md, "highway_100: the graze
the switch did not feel"). A body leaning 35-46 deg into the airflow meets the roof on a front
foot, often in a graze of about 1 N for a few hundredths of a second while the crawl is paused
or withdrawn; the switch of before stayed open, no touchdown was declared, and the body flew
back up off the roof, which the judge counts as a bounce. Checked against a hand integration
of the gear's logged load (the trapezoid rule over the rows of a 1 kHz replay) and the switch's
threshold, on the default seed's run 1145, which the file of before (``HIGHWAY_100_GRAZE``)
loses that way and the eighteenth's file (the switch shipped, no crawl gate yet:
``HIGHWAY_100_GATE``) lands.
"""

import numpy as np
import pytest
from graze_rig import assert_graze_closes, assert_graze_open, flown
from reference import HIGHWAY_100_GATE, HIGHWAY_100_GRAZE


def _flown(index, *extra):
    return flown("highway_100", index, *extra)


def test_the_thresholds_straddle_a_hand_integrated_graze():
    """Default seed, run 1145: the front foot meets the roof at 9.58 s under a paused crawl
    (reference 0.23 m over touchdown, the body 5 cm under it, leaning 36 deg with 10 deg of
    roll). The logged load peaks near 1 N (a twentieth of the weight) and its impulse over the
    graze lies between the shipped threshold (0.5 ms of the weight) and the old one (2 ms).
    Before: the switch stays open through the graze, the body rises back to the reference
    and the judge reads the rebound (1.65 m after the later abort: bounced, not secured).
    Shipped: the switch closes no later than the row where the logged impulse alone passes
    0.5 ms, inside the graze; the guidance enters touchdown there and the run lands."""
    before, rep_before = _flown(1145, *HIGHWAY_100_GRAZE)
    k0, _ = assert_graze_open(before)
    assert 9.55 < before["t"][k0] < 9.6
    assert not rep_before.success and rep_before.bounced and rep_before.bounce > 1.0

    res, rep = _flown(1145, *HIGHWAY_100_GATE)
    assert res.scenario.data["touchdown"]["switch_impulse"] == 0.0005
    assert_graze_closes(res, rep, rep_before)


@pytest.mark.parametrize("index", [1145, 860])
def test_the_graze_closes_the_switch_through_its_penetration(index):
    """Review: the contact's onset smoothing (``gear.onset_width`` 0.1 mm) loads a foot
    ``k eps ln 2`` (0.35 N at 5000 N/m) already at a zero gap, a third of a graze's peak, so
    part of a graze's impulse could be the smoothing's cushion rather than the foot pressing
    into the roof. A second model of the contact, ten times thinner (0.01 mm: 0.035 N at a
    zero gap), must give the same verdicts on the default seed's 1145 (a paused crawl) and 860
    (a withdrawn one): the switch of before stays open and the run bounces; the shipped one
    closes within 20 ms of the same contact and the run lands secured, with the contact's
    figures of the 0.1 mm model to 1 mm."""
    thin = "gear.onset_width=1e-05"
    ref, rep_ref = _flown(index, *HIGHWAY_100_GATE)
    before, rep_before = _flown(index, thin, *HIGHWAY_100_GRAZE)
    res, rep = _flown(index, thin, *HIGHWAY_100_GATE)
    assert rep_ref.success and not rep_before.success and rep_before.bounced
    assert np.all(np.nan_to_num(before["t_contact"]) == 0.0)
    closed = int(np.argmax(res["t_contact"] > 0))
    assert res["t_contact"][closed] > 0
    assert 0.0 <= res["t"][closed] - rep.time < 0.02
    assert rep.success and rep.secured and not rep.bounced
    assert rep.time == pytest.approx(rep_ref.time, abs=2e-3)
    assert rep.offset == pytest.approx(rep_ref.offset, abs=1e-3)

"""highway's crawl gate and land detector as the sixteenth session shipped them (issue 19,
docs/landing.md, "The crawl's gate and a ground contact that needs the deck to carry the
weight"): ``landing.crawl_gate`` 0.04 m over at most 0.3 s to contact above a 0.10 m floor
(``reference.HIGHWAY_GATE_SIXTEENTH``: the seventeenth's floor and wait are pinned back),
and ``land_detector.contact_thrust`` on.

Checked on the replayed run that made the case, seed 13's run 133, against the plant's own
signals rather than the flight code's: the reference's holds (its height flat while the
phase is the descent) lie above the floor; no touchdown is declared with the true gear gap
still open (:func:`~quadland.kinds.landing.report.false_touchdown`); without the key the
guidance's touchdown comes with the gear centimetres over the roof and the rotors carrying
more than ``thrust_low`` of the weight, and the gear meets the roof faster than
``max_sink_rate``.
"""

import numpy as np
import pytest
from reference import HANDOVER_COLD, HIGHWAY_GATE_SIXTEENTH

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import false_touchdown, touchdown_report
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import DESCEND, TOUCHDOWN

SEED, INDEX = 13, 133


def _fly(*overrides):
    """Seed 13's run 133 on highway with the sixteenth's gate (``HIGHWAY_GATE_SIXTEENTH``:
    the 0.10 m floor, no wait) plus ``overrides``: result, report, scenario."""
    d = draws(campaign_spec_of(load_scenario("highway", [f"campaign.seed={SEED}"])),
              [INDEX])[0]
    sc = load_scenario("highway", [*d.overrides(), *HANDOVER_COLD,
                                   *HIGHWAY_GATE_SIXTEENTH, *overrides])
    res = quadland.simulate(sc)
    return res, touchdown_report(res), sc


def _holds(res, sc, shortest=0.2):
    """The reference's heights above touchdown (m) at each stretch of at least ``shortest``
    seconds in the descent below the commit height where it stands still."""
    t, z = np.asarray(res["t"]), np.asarray(res["z_ref"])
    hc = sc["quadrotor.gear_height"]
    crawl = (np.asarray(res["phase"]) == DESCEND) & (z - hc < sc["landing.commit_height"] - 0.01)
    still = crawl[1:] & crawl[:-1] & (np.abs(np.diff(z)) < 1e-9)
    out, k = [], 0
    while k < still.size:
        if not still[k]:
            k += 1
            continue
        j = k
        while j + 1 < still.size and still[j + 1]:
            j += 1
        if t[j + 1] - t[k] >= shortest:
            out.append(float(z[k] - hc))
        k = j + 1
    return out


@pytest.mark.slow
def test_the_shipped_gate_holds_above_its_floor_and_lands_run_133():
    res, rep, sc = _fly()
    assert (sc["landing.crawl_gate"], sc["landing.crawl_gate_floor"],
            sc["landing.crawl_gate_time"], sc["land_detector.contact_thrust"]) == (
                0.04, 0.10, 0.3, True)
    holds = _holds(res, sc)
    assert holds                                   # the gate held the crawl at least once
    assert min(holds) > sc["landing.crawl_gate_floor"]
    assert false_touchdown(res) is None            # the touchdown is the gear's own contact
    assert rep.success and rep.sink_rate <= sc["landing.max_sink_rate"]
    # without the gate the crawl falls straight through: no hold below the commit height
    assert _holds(_fly("landing.crawl_gate=0.0")[0], sc) == []


@pytest.mark.slow
def test_without_the_key_the_hold_is_called_a_touchdown_in_the_air():
    """The same gate with the detector of before: the guidance enters its touchdown phase
    with the true gear gap open by centimetres, the rotors then carrying more than
    thrust_low (0.6) of the drawn weight, so the key's thrust cue is what keeps it off; the
    cut in the air drops the gear onto the roof past max_sink_rate."""
    res, rep, sc = _fly("land_detector.contact_thrust=false")
    gap = false_touchdown(res)
    assert gap is not None and gap > 0.02
    k = int(np.flatnonzero(np.asarray(res["phase"]) >= TOUCHDOWN)[0])
    weight = sc["quadrotor.mass"] * sc["quadrotor.gravity"]
    assert res["F_total"][k] / weight > sc["land_detector.thrust_low"]
    assert rep.sink_rate > sc["landing.max_sink_rate"] and not rep.success

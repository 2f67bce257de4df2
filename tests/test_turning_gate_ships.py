"""turning's crawl gate and land detector (issue 19, docs/landing.md, "turning: a stiffer
horizontal loop and the crawl's gate"): ``landing.crawl_gate`` 0.05 m above a 0.07 m floor,
its holds bounded by a 2 s wait at and below 0.10 m (highway's wait), and
``land_detector.contact_thrust`` on; the gains and the prediction's horizon as before.

Checked here: the values reach the flight's guidance parameters, and seed 13's run 185,
which the gate without the wait lost (no touchdown by 40 s after three aborts, the
sixteenth's campaign), replayed: it lands as the shipped file's campaign row says, and is
lost again with the wait taken out (the row was flown on the handover and the command
filter of before: ``reference.HANDOVER_COLD`` and ``TURNING_FILTER``). The replays of
turning's earlier rows fly ``reference.TURNING_SEVENTEENTH``.
"""

import numpy as np
import pytest
from reference import HANDOVER_COLD, TURNING_FILTER

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import GUIDANCE_PARAMS
from quadland_symbolic.landing.loop import landing_loop_params

GATE_KEYS = ("crawl_gate", "crawl_gate_time", "crawl_gate_floor", "crawl_gate_wait",
             "crawl_gate_wait_height")


def _flight_guidance(sc):
    v = landing_values(sc)
    p_guid = landing_loop_params(v.l).unpack(np.asarray(v.pc, dtype=float).ravel())["p_guid"]
    return GUIDANCE_PARAMS.unpack(np.asarray(p_guid, dtype=float).ravel())


def test_turning_ships_the_gate_the_wait_and_the_key():
    """The gate's values in the file and in the flight's guidance parameters; the wait's
    height is highway's, above the floor (the wait bounds the holds between the two); the
    gains are highway's (test_turning_filter.py)."""
    sc = load_scenario("turning")
    shipped = (0.05, 1e3, 0.07, 2.0, 0.1)
    assert tuple(sc[f"landing.{k}"] for k in GATE_KEYS) == shipped
    assert tuple(p[0] for p in (_flight_guidance(sc)[k] for k in GATE_KEYS)) == shipped
    assert sc["landing.crawl_gate_floor"] < sc["landing.crawl_gate_wait_height"]
    assert sc["landing.crawl_gate_wait_height"] == load_scenario("highway")[
        "landing.crawl_gate_wait_height"]
    assert sc["land_detector.contact_thrust"] is True


#: Seed 13's run 185 as shipped: the offset at first contact (m), the touchdown time (s)
#: and the aborts, its row of the shipped file's 300-run campaign (runs.csv).
SEED, INDEX, OFFSET_M, TIME_S, ABORTS = 13, 185, 0.088032, 22.9652, 1


def _fly(*overrides):
    d = draws(campaign_spec_of(load_scenario("turning", [f"campaign.seed={SEED}"])),
              [INDEX])[0]
    return touchdown_report(quadland.simulate(load_scenario("turning", [
        *d.overrides(), *HANDOVER_COLD, *TURNING_FILTER, *overrides])))


@pytest.mark.slow
def test_the_wait_lands_seed_13s_run_185():
    now = _fly()
    assert now.success and now.on_pad and now.secured
    assert now.offset == pytest.approx(OFFSET_M, abs=5e-6)
    assert now.time == pytest.approx(TIME_S, abs=5e-4) and now.aborts == ABORTS
    unbounded = _fly("landing.crawl_gate_wait=1000.0", "landing.crawl_gate_wait_height=1000.0")
    assert not unbounded.success and unbounded.aborts >= 2

"""highway's descent leash at 2 cm (issue 19, the offset at first contact).

docs/landing.md, "The cars' offset at first contact: the tail taken apart, and a shorter
leash" (nineteenth session). ``landing.descent_leash`` 0.02 m on highway (was 0.05 m,
``reference.HIGHWAY_LEASH``). Of the sixteen runs past 0.1 m in the eighteenth's 1,500 runs
of the default seed, five met the roof while the crawl's gate held the reference about 0.1 m
above touchdown: the quadrotor, leaning 12-22 deg, sank below the held reference until a
foot touched, at the offset the gate was waiting out. Checked here: the shipped value and
its catch-up bound against the judge's sink-rate limit (by hand from the file), and run
1442 of that campaign replayed with the leash of before and as shipped.
"""

import numpy as np
import pytest
from reference import HANDOVER_COLD, HIGHWAY_LEASH

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

#: run 1442's row in the eighteenth's 1,500-run campaign of the default seed
#: (``runs.csv``: offset at first contact, m), flown with the 5 cm leash
ROW_1442_OFFSET = 0.12946805805375275


def test_highway_ships_the_2_cm_leash_and_the_pin_restores_the_old():
    """The shipped leash and the pin; the catch-up it allows, ``touchdown_speed + k1p_z x
    leash`` = 0.3 + 1.5 x 0.02 = 0.33 m/s, worked from the file's own values, stays under
    the judge's 0.5 m/s sink-rate limit (and under 5 cm's 0.375 m/s)."""
    sc = load_scenario("highway")
    assert sc["landing.descent_leash"] == 0.02
    assert sc["landing.leash_height"] == 1000.0          # the whole descent, as before
    assert load_scenario("highway", HIGHWAY_LEASH)["landing.descent_leash"] == 0.05
    catch_up = sc["landing.touchdown_speed"] + sc["controller.k1p"][2] * 0.02
    assert catch_up == pytest.approx(0.33, abs=1e-12)
    assert catch_up < sc["landing.max_sink_rate"]


def _fly_1442(*overrides):
    """Default seed, run 1442 (a 4.6 m/s crosswind gust from 10.06 s): the report, the
    reference's height above touchdown and the time."""
    sc = load_scenario("highway")
    d = draws(campaign_spec_of(sc), [1442])[0]
    sc = load_scenario("highway", [*d.overrides(), *HANDOVER_COLD, *overrides])
    res = quadland.simulate(sc)
    h = np.asarray(res["z_ref"]) - sc["quadrotor.gear_height"]
    return touchdown_report(res), h, np.asarray(res["t"])


@pytest.mark.slow
def test_run_1442_touches_down_in_the_gates_hold_on_5_cm_and_near_the_centre_on_2_cm():
    """With the 5 cm leash the run replays its campaign row (0.129 m off, over issue 19's
    0.1 m): the gate holds the reference still (to 1e-9 m) at 0.09-0.11 m above touchdown
    for the last 0.1 s before the first contact, so the contact is made from the hold. With
    the shipped 2 cm leash the same draw lands secured, within every limit, less than 0.05 m
    off, and its first contact does not come from a hold at that height."""
    rep, h, t = _fly_1442(*HIGHWAY_LEASH)
    assert rep.success and rep.secured
    assert rep.offset == pytest.approx(ROW_1442_OFFSET, abs=1e-6)
    last = (t > rep.time - 0.1) & (t <= rep.time)
    assert np.ptp(h[last]) < 1e-9 and 0.09 < h[last][0] < 0.11

    rep, h, t = _fly_1442()
    assert rep.success and rep.secured and rep.on_pad and rep.failures == []
    assert rep.offset < 0.05
    last = (t > rep.time - 0.1) & (t <= rep.time)
    assert not (np.ptp(h[last]) < 1e-9 and 0.09 < h[last][0] < 0.11)

"""The road hardware of highway over 30 to 100 km/h (benchmarks/highway_30_100.toml).

Its choices against the statics of a body on its gear in the fastest car's airflow, and
one 100 km/h landing it makes where highway's own gear and touchdown fail
(docs/landing.md, "The road hardware over 30 to 100 km/h").
"""

import math
from pathlib import Path

import numpy as np
import pytest
from highway_before import BEFORE as HIGHWAY_BEFORE
from reference import HANDOVER_COLD, HIGHWAY_GRAZE

import quadland
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
#: 100 km/h and the drive force d11 V that holds it (highway's d11 = 150 kg/s).
FASTEST = ["initial.velocity2=[27.77777777777778, 0.0]",
           "vehicle.tau=[4166.666666666667, 0.0, 0.0]"]


def test_the_road_hardware_by_the_statics_of_the_fastest_car():
    """At 100 km/h with the drag at the table's +30 %: D = 1.3 (0.3 x 27.78 + 0.01225 x
    27.78^2) = 23.1 N, a steady lean of atan(23.1 / 19.6) = 49.7 deg at the nominal mass,
    past PX4's 45 deg: the controller's 55 deg leaves 2 m g - m g / cos(55 deg) = 0.26
    m g of thrust for control; the wider gear tips at atan(0.24 / 0.2) = 50.2 deg about y,
    above that lean and the flare's 47 deg; resting level the drag cannot roll it over its rear feet
    (23.1 x 0.2 = 4.6 N m < 19.6 x 0.24 = 4.7 N m) and the two magnets pull 200 (1 -
    exp(-0.1 / 0.17)) = 88.9 N at the cut, 0.1 s after touchdown, against 23.1 / 0.5 -
    19.6 = 26.6 N to stop the slide. The magnets' 0.25 s dead time runs from the flare,
    at least 0.15 / 0.2 = 0.75 s before the reference reaches the deck."""
    d = load_scenario(BENCH / "highway_30_100.toml").data
    q, g, td, c = d["quadrotor"], d["gear"], d["touchdown"], d["controller"]
    m, grav, h = q["mass"], q["gravity"], q["gear_height"]
    V = 27.77777777777778
    D = 1.3 * (q["drag_translational"][0] * V + q["drag_quadratic"][0] * V ** 2)
    assert D == pytest.approx(23.13, abs=0.01)
    assert math.degrees(math.atan(D / (m * grav))) == pytest.approx(49.7, abs=0.05)
    assert q["thrust_to_weight"] - 1 / math.cos(math.radians(c["tilt_max_deg"])) == (
        pytest.approx(0.257, abs=0.001))
    tip_y = math.degrees(math.atan(g["feet_x"] / h))
    tip_x = math.degrees(math.atan(g["feet_y"] / h))
    assert tip_y == pytest.approx(50.19, abs=0.01) and tip_x == pytest.approx(41.50, abs=0.01)
    assert tip_y > 49.7 > td["flare_tilt_deg"] == 47.0
    assert D * h < m * grav * g["feet_x"]
    F = td["lock_hold_force"] * (1 - math.exp(-(td["cut_time"] - td["lock_delay"])
                                              / td["lock_rise_time"]))
    assert F == pytest.approx(88.9, abs=0.05)
    assert g["friction"] * (m * grav + F) > D
    assert td["policy"] == "secure"
    assert td["flare_height"] / d["landing"]["touchdown_speed"] == pytest.approx(0.75)


def test_a_100_km_h_car_meets_highway_s_gear_past_its_tip_over_angle():
    """The default seed on its sensors at 100 km/h on highway's gear: it meets the deck at
    a tilt past the gear's static tip-over angle about y, atan(0.15 / 0.2) = 36.87 deg,
    which the judge reads as "tilted" (issue 18's review: the tilt at contact against
    the tip-over angle; "tipped" is kept for a gear rolled over with the rotors cut)."""
    # the law without the disturbance observer, whose flight this is (with it the contact
    # comes at 36.5 deg, just inside, and fails on tilt, a bounce and the pad instead), and
    # highway's touchdown of before its flare (tests/highway_before.py: with the 30 deg
    # flare this flight lands, leaning 31.4 deg)
    before = touchdown_report(quadland.simulate(load_scenario(
        "highway", [*FASTEST, "controller.observer_frequency=[0.0, 0.0, 0.0]",
                    *HIGHWAY_BEFORE])))
    assert before.tilt_deg > math.degrees(math.atan2(0.15, 0.2))
    assert not before.success and "tilted" in before.failures


def _farthest_foot(res):
    return float(np.max(res["foot_offset"][res["touched"] > 0.5]))


#: The law without the disturbance observer (docs/landing.md): the flights the feet fix
#: was measured on.
#: the law before the observer: none, and the outer bias estimates on every axis
NO_OBSERVER = ("controller.observer_frequency=[0.0, 0.0, 0.0]", "controller.ki_p=[0.5, 0.5, 1.0]")


def test_a_100_km_h_car_lands_on_the_road_hardware():
    """The default seed on its sensors at 100 km/h on the road hardware: landed, secured,
    touching down inside the wider gear's 50.2 deg. Without the disturbance observer,
    with the 0.35 s level-out and the cut at 0.5 s of before (issue 19's feet fix), the
    body slid back under the drag while the rotors still carried it and a rear foot
    reached 0.542 m on the 0.5 m pad (seed 6); with the 0.1 s level-out and cut it drops
    onto its rear feet and the magnets, and its farthest foot stays 0.487 m out
    (docs/landing.md, "The feet on the pad"). As shipped (the observer on) it lands too.
    (The default seed was the reproducer, 0.5115 and 0.473 m, until the sensors' draws
    came in blocks, issue 20: its new realization keeps the feet on the pad either way,
    0.489 and 0.461 m. Of seeds 1 to 16, 12 went off the pad before the fix without the
    observer, and the fix alone kept only 3 of them on it, seeds 2, 6 and 9: the observer
    is what lands the others.) The fix's two flights keep highway's contact switch of
    before (``HIGHWAY_GRAZE``, 2 ms), which they were measured with; with the 0.5 ms one
    the switch closes earlier in the contact and the farthest foot comes, before the fix, to
    0.541 m, after it 0.485 m (docs/landing.md, "highway: the graze switch"). Both fly the
    handover's cold start they were measured with (``HANDOVER_COLD``)."""
    before = quadland.simulate(load_scenario(BENCH / "highway_30_100.toml", [
        *FASTEST, *NO_OBSERVER, "touchdown.level_time=0.35", "touchdown.cut_time=0.5",
        "simulation.seed=6", *HIGHWAY_GRAZE, *HANDOVER_COLD]))
    assert _farthest_foot(before) == pytest.approx(0.5419, abs=5e-4)
    assert touchdown_report(before).failures == ["off the pad"]
    after = quadland.simulate(load_scenario(BENCH / "highway_30_100.toml",
                                            [*FASTEST, *NO_OBSERVER, "simulation.seed=6",
                                             *HIGHWAY_GRAZE, *HANDOVER_COLD]))
    assert _farthest_foot(after) == pytest.approx(0.4866, abs=5e-4)
    assert touchdown_report(after).failures == []
    res = quadland.simulate(load_scenario(BENCH / "highway_30_100.toml", FASTEST))
    rep = touchdown_report(res)
    assert rep.tilt_deg < 50.19
    assert rep.success and rep.secured and not rep.tipped

"""turning: the navigation filter's accelerations tuned for the turning car, and a shorter
flare (issue 19's bar; docs/landing.md, "turning: what the offset at contact is made of").

On the sensors' draws in blocks the turning campaign landed 298 of 300 on the default
campaign seed (runs 60 and 128 off by 0.209 and 0.224 m) and 298 on ``campaign.seed = 7``
(runs 183 and 274, 0.226 and 0.203 m). Half of the offset's variance was the velocities'
noise (the GNSS's and the datalink's) through a filter tuned with PX4's defaults
(``q_acc`` 0.02, ``q_at`` 0.1), which let its velocity and the pad's acceleration follow
each fusion. The shipped file takes highway's consistency-measured ``q_acc`` (the same
IMU and gains), a ``q_at`` from the turn's own jerk, and a flare over the last 0.2 m
instead of the whole 0.3 m crawl. The reproducers below are the four offset failures,
replayed from their campaigns' draws with the settings of before (``FILTER_BEFORE``) and
as shipped; each number is its campaign's runs.csv row.
"""

import tomllib
from importlib.resources import files

import pytest
from reference import HANDOVER_COLD, TURNING_SEVENTEENTH

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

#: turning's filter tuning and flare before this change (the file of ``5c8b10b``).
FILTER_BEFORE = ("estimator.q_acc=[0.02, 0.02, 0.02]", "estimator.q_at=[0.1, 0.1, 0.1]",
                 "touchdown.flare_height=0.3", "sensors.vision.small_range_max=0.0")
#: the pad of before the nested marker (docs/landing.md, "The nested marker"): the rows
#: of the campaigns that pinned the offsets below.
PAD_BEFORE = "sensors.vision.small_range_max=0.0"


def _toml(name):
    return tomllib.loads(files("quadland.scenarios").joinpath(f"{name}.toml").read_text())


def _campaign_run(seed, index, *overrides):
    """Run ``index`` of turning's campaign drawn with campaign seed ``seed``, replayed, with
    the crawl and land detector these rows were measured with
    (``TURNING_SEVENTEENTH``)."""
    spec = campaign_spec_of(load_scenario("turning", [f"campaign.seed={seed}"]))
    d = draws(spec, [index])[0]
    return touchdown_report(quadland.simulate(load_scenario("turning", [
        *d.overrides(), *HANDOVER_COLD, *TURNING_SEVENTEENTH, *overrides])))


def test_q_at_is_the_turning_cars_jerk_squared_over_a_second():
    """The car's steady turn from its own table (eq. 4 with ``v2 = 0``): ``d11 u = tau1``
    gives u = 10 m/s, ``m11 u r = tau2`` gives r = 0.1 rad/s. Its acceleration in E, ``u r
    = 1 m/s^2``, turns at ``r``: a jerk of ``u r^2 = 0.1 m/s^3``, whose square over 1 s is
    the filter's random walk ``q_at`` = 0.01 m^2/s^5 (PX4's 0.1 is a hundredfold jerk's
    worth: the pad's acceleration followed the datalink's noise)."""
    t = _toml("turning")
    v = t["vehicle"]
    u = v["tau"][0] / v["d11"]
    r = v["tau"][1] / (v["m11"] * u)
    assert (u, r) == pytest.approx((10.0, 0.1))
    assert v["tau"][2] == pytest.approx(v["d33"] * r)          # the yaw moment holds r
    jerk = u * r**2
    assert jerk == pytest.approx(0.1)
    assert t["estimator"]["q_at"] == pytest.approx([jerk**2 * 1.0] * 3)


def test_q_acc_is_highways_measured_one_for_the_same_imu_and_gains():
    """``q_acc`` is the accelerometer's noise and the attitude estimate's error times the
    accelerations the law flies, measured on highway (docs/estimator.md, "Consistency",
    item 7): turning flies the same IMU, the same outer and inner gains and observer, so
    it takes the same numbers (PX4's 0.02 m^2/s^3 is 500 to 3,600 times them)."""
    t, h = _toml("turning"), _toml("highway")
    assert t["sensors"]["imu"] == h["sensors"]["imu"]
    for key in ("k1p", "k2p", "k1", "k2", "observer_frequency", "ki_p", "rate_hz"):
        assert t["controller"][key] == h["controller"][key], key
    assert t["estimator"]["q_acc"] == h["estimator"]["q_acc"]
    assert min(0.02 / q for q in t["estimator"]["q_acc"]) == pytest.approx(502, abs=1)
    assert max(0.02 / q for q in t["estimator"]["q_acc"]) == pytest.approx(3636, abs=1)


#: The offset failures of turning's 300-run campaigns (default campaign seed 2025 and
#: seed 7) on ``5c8b10b``, replayed: seed, run, the offset at first contact before and as
#: shipped (m), each its campaign's runs.csv row (docs/landing.md's table).
OFFSETS = [(2025, 60, 0.208843, 0.024859), (2025, 128, 0.224002, 0.189960),
           (7, 183, 0.225988, 0.037596), (7, 274, 0.202919, 0.050413)]


@pytest.mark.parametrize(("seed", "index", "before_m", "now_m"), OFFSETS)
def test_the_campaigns_offset_failures_land_with_the_filter_tuned_for_the_turn(
        seed, index, before_m, now_m):
    """Each met the roof more than the 0.2 m limit off the pad centre with the filter's
    PX4 defaults and the 0.3 m flare (run 60 drifting back 0.2 m while the flare held its
    tilt at 21 deg against a headwind gust; run 128 pushed sideways by a gust after the
    camera lost the marker). With the filter as shipped each lands on the pad and is
    secured, at its campaign's offset (on the pad of that campaign, the large marker
    alone), and with the file as shipped (the nested marker) too."""
    before = _campaign_run(seed, index, *FILTER_BEFORE)
    assert "offset" in before.failures and before.offset > 0.2
    assert before.offset == pytest.approx(before_m, abs=5e-6)
    now = _campaign_run(seed, index, PAD_BEFORE)
    assert now.success and now.on_pad and now.secured
    assert now.offset == pytest.approx(now_m, abs=5e-6)
    nested = _campaign_run(seed, index)
    assert nested.success and nested.on_pad and nested.secured

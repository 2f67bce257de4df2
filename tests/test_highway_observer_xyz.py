"""highway's observer on all three axes and no outer bias estimates on x, y (issue 19).

docs/landing.md, "The bias estimates' slow tail". With the disturbance observer on an
axis its ``d_o`` is the integral action there; the bias estimate beside it only bleeds
off, slowly, what it learnt in the approach, and holds the quadrotor off its reference
through the descent: at x = +3.4 cm, y = -1.9 cm (deck frame) at the first contact of
the calm default flight on perfect sensing, about that on average over the campaign. The checks
here are the flights themselves: the calm flight's contact with and without the bias
estimates, and two runs of the campaign replayed from their draws, whose outcomes the
campaigns of before and after recorded (``runs.csv`` of `quadland campaign --scenario
highway --runs 300`, default campaign seed; a replay equals its row to the bit).
Every flight here has highway's touchdown and descent of before its flare and leash
(``highway_before.BEFORE``, the rotors cut at the contact switch, no leash), the law these
rows were recorded with; the flare and the leash are tests/test_highway_flare_leash.py's.
"""

from __future__ import annotations

import numpy as np
import pytest
from highway_before import BEFORE as TOUCHDOWN_BEFORE
from reference import HANDOVER_COLD

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

#: highway's law before: the observer on x, y only, the bias estimates on every axis.
BEFORE = ("controller.observer_frequency=[12.0, 12.0, 0.0]", "controller.ki_p=[0.5, 0.5, 1.0]")
#: the calm default flight: perfect sensing, no turbulence, gust or disturbance noise.
CALM = ("sensors.enabled=false", "wind.turbulence_w20=0.0", "wind.gust_amplitude=0.0",
        "disturbance.noise=false")


def test_the_shipped_law_has_the_observer_on_every_axis_and_no_outer_bias_estimates_beside_it():
    sc = load_scenario("highway")
    assert list(sc["controller.observer_frequency"]) == [12.0, 12.0, 12.0]
    assert list(sc["controller.ki_p"]) == [0.0, 0.0, 1.0]


def _contact(*overrides):
    res = quadland.simulate(load_scenario("highway", [*CALM, *TOUCHDOWN_BEFORE, *overrides]))
    k = int(np.flatnonzero(res["touched"] > 0.5)[0])
    return np.array([res["x_e"][k], res["y_e"][k]]), float(res["t"][k])


def test_the_bias_estimates_beside_the_observer_hold_the_calm_flight_off_the_pad_centre():
    """Nothing in the calm flight is random and the model is the plant's: what holds the
    quadrotor off the centre at contact is the approach's transient. With the bias
    estimates it has not bled off when the descent starts (at 2.1 rad/s the position
    loop's own modes are gone within 3 s; the bias estimate's is slower); without them the
    contact is within 1 cm of the centre, and 0.82 s sooner (the align band is met
    sooner)."""
    before, t_before = _contact(*BEFORE)
    now, t_now = _contact()
    np.testing.assert_allclose(before, [0.0339, -0.0191], atol=5e-4)
    np.testing.assert_allclose(now, [0.0054, -0.0060], atol=5e-4)
    assert np.hypot(*now) < 0.01 < 0.03 < np.hypot(*before)
    assert t_before - t_now == pytest.approx(0.82, abs=0.01)


def _run(index, *overrides):
    sc = load_scenario("highway")
    d = draws(campaign_spec_of(sc), [index])[0]
    return touchdown_report(quadland.simulate(load_scenario("highway", [
        *d.overrides(), *HANDOVER_COLD, *TOUCHDOWN_BEFORE, *overrides])))


def test_campaign_run_237_no_longer_meets_the_deck_past_the_tilt_limit():
    """Run 237, the one failure of the campaign before (on the sensors' draws in blocks,
    issue 20): it met the roof leaning 33.3 deg against highway's 32.6 deg limit; as
    shipped it lands leaning 24.5 deg, 4.4 cm from the centre. (On the draws of before
    the law of before failed three runs on the sink rate, the worst run 162 at 0.561
    m/s, and one off the pad; as shipped, one off the pad.)"""
    before = _run(237, *BEFORE)
    assert before.tilt_deg == pytest.approx(33.349, abs=1e-3)
    assert not before.success and before.failures == ["tilt_deg"]
    now = _run(237)
    assert now.tilt_deg == pytest.approx(24.498, abs=1e-3)
    assert now.offset == pytest.approx(0.0436, abs=1e-4)
    assert now.success and now.secured and now.on_pad


@pytest.mark.parametrize(("index", "sink_before", "sink_now"),
                         [(122, 0.4411, 0.5493), (166, 0.3224, 0.5372)])
def test_the_shipped_campaigns_two_failures_landed_before(index, sink_before, sink_now):
    """Runs 122 and 166 are the shipped campaign's two failures (sink rates 0.549 and
    0.537 m/s against 0.5): the law of before landed them, at 0.441 and 0.322 m/s. Left as
    measured: over the two draws of the campaign (before and after issue 20's blocks) the
    law of before lands 595 of the 600 (296 and 299), the shipped one 597 (299 and 298)."""
    before = _run(index, *BEFORE)
    assert before.success and before.sink_rate == pytest.approx(sink_before, abs=1e-4)
    now = _run(index)
    assert now.sink_rate == pytest.approx(sink_now, abs=1e-4)
    assert not now.success and now.failures == ["sink_rate"]

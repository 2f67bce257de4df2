"""The land detector's ground contact with ``contact_thrust``: the thrust cue required at
stage 1 too (PX4's ground contact needs low thrust as well as a commanded descent; issue 19,
docs/landing.md, "The crawl's gate and a ground contact that needs the deck to carry the
weight"). Checked on hand-built cue sequences against hand-counted windows, and on random
cues against the detector without it."""

import numpy as np
import pytest

from quadland.scenario import load_scenario
from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_CUES,
    LAND_DETECTOR_DEFAULTS,
    LAND_DETECTOR_FLAGS,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_STATE,
    land_detector_function,
)

DETECTOR = land_detector_function()
DT = 0.004                                     # the 250 Hz control period: windows of 83 steps
FLAG = {n: i for i, n in enumerate(LAND_DETECTOR_FLAGS.element_names())}
ON_DECK = dict(range_gap=0.0, range_valid=1.0, est_gap=0.0, est_vz=0.0, thrust_ratio=0.5,
               f_z=9.81, in_descend=1.0)
#: The gate's loss: the gear held 3 cm over the roof, still, the descent phase, the range
#: agreeing, the rotors carrying the weight (thrust at hover).
HOVER_3CM = dict(ON_DECK, range_gap=0.03, est_gap=0.03, thrust_ratio=1.0)


def _run(rows, **changes):
    cues = np.column_stack([LAND_DETECTOR_CUES.pack(r) for r in rows])
    p = LAND_DETECTOR_PARAMS.pack({**LAND_DETECTOR_DEFAULTS, **changes})
    _, fl = DETECTOR.mapaccum(len(rows))(LAND_DETECTOR_STATE.zeros(), cues, p, DT)
    return np.asarray(fl).T


def _first(flags, name):
    hits = np.flatnonzero(flags[:, FLAG[name]] > 0.5)
    return int(hits[0]) + 1 if hits.size else 0


def test_a_hover_within_the_gap_is_contact_only_without_the_key():
    """Without the key every stage-1 cue holds (gap 0.03 <= 0.1 m, still, descending, the
    range agreeing): ground contact on step 83 (83 x 4 ms >= 1/3 s - 2 ms), the guidance's
    touchdown in the air. With it the thrust at hover (1.0 > 0.6) is no contact in 4 s."""
    rows = [HOVER_3CM] * 1000
    assert _first(_run(rows), "ground_contact") == 83
    assert _run(rows, contact_thrust=1.0)[:, :3].max() == 0


@pytest.mark.parametrize("thrust", [0.5, 0.6])
def test_on_the_deck_the_stages_keep_their_hand_counted_steps(thrust):
    """The weight on the deck (thrust at or below thrust_low 0.6): the stages set on steps
    83, 83 + 83 - 1 = 165 and 83 + 83 + 83 - 2 = 247, with the key as without it."""
    rows = [dict(ON_DECK, thrust_ratio=thrust)] * 300
    for flags in (_run(rows), _run(rows, contact_thrust=1.0)):
        assert (_first(flags, "ground_contact"), _first(flags, "maybe_landed"),
                _first(flags, "landed")) == (83, 165, 247)


def test_the_thrust_must_hold_through_the_window_and_its_rise_drops_the_contact():
    """The window counts only steps with the thrust low: 50 low, one at hover, then low
    again sets the contact 83 steps after the break (step 51 + 83 = 134); without the key
    on step 83. A thrust back over thrust_low after the contact (step 100) drops it at once
    with the key, before maybe landed (step 165); without it the contact holds."""
    rows = [ON_DECK] * 50 + [dict(ON_DECK, thrust_ratio=0.61)] + [ON_DECK] * 200
    assert _first(_run(rows, contact_thrust=1.0), "ground_contact") == 134
    assert _first(_run(rows), "ground_contact") == 83
    rows = [ON_DECK] * 100 + [dict(ON_DECK, thrust_ratio=1.0)] * 5
    key, off = _run(rows, contact_thrust=1.0), _run(rows)
    assert key[99, FLAG["ground_contact"]] == 1 and key[100:, :3].max() == 0
    assert off[99:, FLAG["ground_contact"]].min() == 1


def test_with_the_key_no_stage_ever_sets_before_it_does_without():
    """On random cues (gaps, speeds and thrusts about their thresholds, the range fresh or
    not, the descent on or off) each stage with the key is set only where it is set
    without it: the key only adds a condition to stage 1, so by induction its thresholds
    are never wider and its times never longer."""
    rng = np.random.default_rng(19)
    n, k = 20000, 200
    # runs of k steps of each cue (so that windows are met) rather than white noise
    def runs(lo, hi):
        return np.repeat(rng.uniform(lo, hi, n // k), k)
    rows = [dict(range_gap=g, range_valid=float(v > 0.1), est_gap=e, est_vz=w,
                 thrust_ratio=t, f_z=9.81, in_descend=float(d > 0.2))
            for g, v, e, w, t, d in zip(runs(-0.05, 0.15), rng.uniform(0, 1, n),
                                        runs(-0.05, 0.15), runs(-0.3, 0.3), runs(0.3, 1.0),
                                        runs(0, 1), strict=True)]
    off, key = _run(rows), _run(rows, contact_thrust=1.0)
    assert np.all(key[:, :3] <= off[:, :3])
    assert off[:, FLAG["ground_contact"]].sum() > key[:, FLAG["ground_contact"]].sum() > 0


def test_highway_and_turning_alone_ship_it():
    """highway and turning fly the key with their crawl's gates (docs/landing.md, the
    section above; turning since "turning: a stiffer horizontal loop and the crawl's
    gate"); every other shipped scenario leaves it off."""
    for name in ("highway", "turning"):
        assert load_scenario(name).data["land_detector"]["contact_thrust"] is True
    for name in ("ship", "ship_ss5", "highway_100"):
        assert load_scenario(name).data["land_detector"]["contact_thrust"] is False

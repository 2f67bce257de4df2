"""The nested landing marker on highway, turning, ship_ss5 (issue 19, eleventh session) and
highway_100 (sixteenth).

The pads of the two scenarios carry a second, 0.1 m marker in the centre of the 0.6 m
one (nested fiducials: Romero-Ramirez et al., "Fractal Markers", IEEE Access 7, 2019;
Wubben et al., Electronics 8(12):1532, 2019, select the smallest marker seen), detected
from ``small_range_min`` to ``small_range_max`` = 0.6 m. docs/landing.md, "The nested
marker". Checked here: the interval against the pinhole model by hand (the marker fills
the image no farther than ``small_range_min``; over the interval the camera's noise model
is never finer than one pixel of the small marker's depth; the interval overlaps the large
marker's, so no range is blind), and the default flight of ``highway``: the filter fuses
a detection in the last tenth of a second before the contact, where without the small
marker its last one is about half a second old. highway_100's wide lens (130 deg on the
same sensor) is checked on its own pinhole figures (docs/landing.md, "highway_100: what the
offset at contact is made of, and the nested marker"), and its default flight as highway's.
"""

import math

import numpy as np
import pytest

import quadland
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

#: Raspberry Pi Camera Module 3 Wide, docs/sensors.md: 1536 px across 102 deg.
FOCAL_PX = 768 / math.tan(math.radians(51.0))
SMALL_SIDE = 0.1                                  # m, the nested marker
SCENARIOS = ("highway", "turning", "ship_ss5")   # the same camera (102 deg lens)
#: highway_100's 130 deg lens on the same sensor: each pixel spans 130 / 102 times the angle,
#: so its focal length in pixels is FOCAL_PX / WIDE and its noise model WIDE times highway's.
WIDE = 130 / 102


@pytest.mark.parametrize("name", SCENARIOS)
def test_the_small_markers_interval_is_the_pinholes(name):
    v = load_scenario(name).data["sensors.vision"]
    assert v["small_range_max"] == 0.6 and v["small_range_min"] == 0.08
    # the lens FOCAL_PX is for: its cone is half of the 67 deg height or of the 102 deg width
    assert round(math.degrees(v["half_angle"]), 6) in (33.5, 51.0)
    # the 0.1 m marker fills the 67 deg image height (half-angle 33.5 deg) at 0.0755 m
    fills = (SMALL_SIDE / 2) / math.tan(math.radians(33.5))
    assert fills == pytest.approx(0.0755, abs=1e-4) and fills < v["small_range_min"]
    # spans at least 30 px (a reliable detection, as the large marker at 12 m) out to max
    assert SMALL_SIDE * FOCAL_PX / v["small_range_max"] > 30
    # one pixel of its depth, r^2 / (f s), never finer than the model's sigma0 + k r
    for r in np.linspace(v["small_range_min"], v["small_range_max"], 50):
        pinhole = r ** 2 / (FOCAL_PX * SMALL_SIDE)
        assert pinhole < v["sigma0"] + 0.5 * v["sigma_per_m"] * r   # the campaign's lowest k
    # the two intervals overlap: no range between them is blind
    assert v["small_range_min"] < v["range_min"] < v["small_range_max"] < v["range_max"]


def test_highway_100_s_interval_is_its_wide_lens_pinholes():
    """The same checks on highway_100's lens: f = 622 / 1.27 = 488 px; the marker fills the
    85 deg image height at 0.054 m, spans 81 px at 0.6 m, and one pixel of its depth,
    ``r^2 / 48.8`` m, stays under the campaign's lowest noise model over the interval
    (7.4 mm against 2.9 cm at 0.6 m)."""
    v = load_scenario("highway_100").data["sensors.vision"]
    assert v["small_range_max"] == 0.6 and v["small_range_min"] == 0.08
    assert math.degrees(v["half_angle"]) == pytest.approx(65.0)          # half of 130 deg
    assert v["sigma0"] == pytest.approx(0.02 * WIDE, abs=1e-4)
    assert v["sigma_per_m"] == pytest.approx(0.01 * WIDE, abs=1e-4)
    focal = FOCAL_PX / WIDE
    assert focal == pytest.approx(488.0, abs=0.1)
    fills = (SMALL_SIDE / 2) / math.tan(math.radians(33.5 * WIDE))
    assert fills == pytest.approx(0.0542, abs=1e-4) and fills < v["small_range_min"]
    assert SMALL_SIDE * focal / v["small_range_max"] == pytest.approx(81.3, abs=0.1)
    for r in np.linspace(v["small_range_min"], v["small_range_max"], 50):
        pinhole = r ** 2 / (focal * SMALL_SIDE)
        assert pinhole < v["sigma0"] + 0.5 * v["sigma_per_m"] * r
    assert 0.6 ** 2 / (focal * SMALL_SIDE) == pytest.approx(0.0074, abs=1e-4)
    assert v["small_range_min"] < v["range_min"] < v["small_range_max"] < v["range_max"]


def test_highway_100_s_range_min_is_inside_the_small_interval():
    """highway_100 keeps the 102 deg lens's ``range_min``, 0.3 / tan 33.5 deg = 0.45 m; its
    130 deg lens's own is 0.3 / tan 42.7 deg = 0.325 m (the 0.6 m marker filling the 85 deg
    height). Both lie inside the small marker's 0.08 to 0.6 m, so with the nested marker the
    union of the two intervals, the ranges the camera detects at, is 0.08 m to ``range_max``
    with either figure (docs/landing.md, "highway_100: what the offset at contact is made of,
    and the nested marker", the review's check)."""
    v = load_scenario("highway_100").data["sensors.vision"]
    large = 0.6                                                        # m, the pad's marker
    narrow = (large / 2) / math.tan(math.radians(33.5))
    own = (large / 2) / math.tan(math.radians(33.5 * WIDE))
    assert narrow == pytest.approx(0.453, abs=1e-3) and v["range_min"] == 0.45
    assert own == pytest.approx(0.325, abs=1e-3)
    for r_min in (v["range_min"], own):
        assert v["small_range_min"] < r_min < v["small_range_max"]


def _marker_age_at_contact(*overrides, name="highway"):
    result = quadland.simulate(load_scenario(name, list(overrides)))
    report = touchdown_report(result)
    k = int(np.flatnonzero(result["touched"] > 0.5)[0])
    return report, float(result["marker_age"][k])


def test_highway_sees_the_pad_to_the_contact():
    """The default flight: the last fused detection at the contact is at most a frame
    period (0.04 s) and a dropout old with the small marker, and about half a second old
    without it (the large marker is lost at 0.45 m, the last 0.25 m of the gear)."""
    now, age_now = _marker_age_at_contact()
    before, age_before = _marker_age_at_contact("sensors.vision.small_range_max=0.0")
    assert now.success and before.success
    assert age_now <= 0.1
    assert 0.3 <= age_before <= 1.0


def test_highway_100_sees_the_pad_to_the_contact():
    """highway_100's default flight, sensors on: with the small marker the last fused
    detection at the contact is at most 0.1 s old; without it (the pad of before) the large
    marker is lost at 0.45 m, a few tenths of a second before the contact (0.26 to 0.50 s
    over the campaign's first 40 runs, docs/landing.md); both land."""
    now, age_now = _marker_age_at_contact(name="highway_100")
    before, age_before = _marker_age_at_contact("sensors.vision.small_range_max=0.0",
                                                name="highway_100")
    assert now.success and before.success
    assert age_now <= 0.1
    assert 0.2 <= age_before <= 1.0

"""The descent profile's contact height for a gear that meets the deck leaning
(``touchdown.contact_lean_deg``; docs/landing.md, "highway_100: the observer and the
leash").

A body pitched ``th`` nose down meets a flat deck on its front feet, ``fx sin th + hc cos
th`` below its centre, not ``hc``: on highway_100's gear (``fx`` 0.30 m, ``hc`` 0.15 m) at
the 38.7 deg of the steady lean at 100 km/h, 0.305 m. The guidance's profile (its crawl, the
align band's pause above it, the wait height, the flare and the aim) counts its heights above
``touchdown_height + contact_drop``. Checked here: the drop against the four feet rotated by
hand, the crawl's start moved up by it in one guidance step, the flare's and the aim's heights
too (one step each), and the key's default leaving
every shipped scenario's profile on the level gear. ``landing.crawl_pause`` lets the align
band pause the crawl as it pauses the descent above it; checked in one guidance step.
The drop is off in every shipped scenario (measured on highway_100 and not shipped); the
pause ships on highway_100 alone.
"""

import math

import numpy as np
import pytest
from hand_rotations import Ry
from reference import GUIDANCE_P

from quadland.kinds.landing.gear import touchdown_guidance
from quadland.scenario import load_scenario
from quadland_symbolic.landing.guidance import (
    ALIGN,
    DESCEND,
    GUIDANCE_CUES,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
    guidance_function,
)
from quadland_symbolic.landing.touchdown_policy import TOUCHDOWN_COMMANDS

#: highway_100's gear: the feet's half spacings and their depth below the centre, m.
FX, FY, HC = 0.30, 0.20, 0.15
#: One guidance step, s.
DT = 0.01


def _lowest_foot(th_deg):
    """Depth of the lowest of the four feet ``(+-FX, +-FY, -HC)`` below the centre, m, the
    body pitched ``th_deg`` nose down (``Ry`` written out by hand)."""
    feet = np.array([[sx * FX, sy * FY, -HC] for sx in (1, -1) for sy in (1, -1)])
    return -min((Ry(math.radians(th_deg)) @ f)[2] for f in feet)


@pytest.mark.parametrize("lean", [0.0, 25.0, 38.7, 50.5])
def test_the_drop_is_the_lowest_foot_of_the_pitched_gear(lean):
    """``contact_drop`` is the lowest foot's depth at the lean less the level gear's:
    0.155 m at 38.7 deg (0.305 - 0.15), 0.177 m at the table corner's 50.5 deg."""
    sc = load_scenario("highway_100", [f"touchdown.contact_lean_deg={lean}"])
    drop = touchdown_guidance(sc)["contact_drop"]
    assert drop == pytest.approx(_lowest_foot(lean) - HC, abs=1e-12)
    if lean == 38.7:
        assert drop == pytest.approx(0.1547, abs=1e-4)


@pytest.mark.parametrize("name", ["highway", "turning", "ship", "ship_ss5", "highway_100"])
def test_other_scenarios_keep_the_level_profile(name):
    """Without the key the drop is exactly 0: the profile of before; the crawl is committed
    (``crawl_pause`` false) but on highway_100, which pauses it since docs/landing.md's
    "highway_100: the crawl paused under the lower flare"."""
    sc = load_scenario(name)
    assert touchdown_guidance(sc)["contact_drop"] == 0.0
    assert sc["landing.crawl_pause"] is (name == "highway_100")


def _rate(z_ref, drop):
    """The reference's fall per second in one committed guidance step from ``z_ref`` over
    the pad, the quadrotor on the reference at rest, the level gear 0.15 m down."""
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC, contact_drop=drop))
    xg_next, _ = (np.asarray(v, dtype=float).ravel() for v in guidance_function()(
        xg, [0.0, 0.0, z_ref], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
    return (z_ref - GUIDANCE_STATE.unpack(xg_next)["z_ref"][0]) / DT


def test_the_profile_counts_from_the_contact_height():
    """The rate is ``clamp(h / descent_time, touchdown_speed, descent_speed)`` with ``h``
    above ``touchdown_height + contact_drop``: at 0.5 m the level gear's ``h`` is 0.35 m
    (0.35 m/s at GUIDANCE_P's 1 s), the leaning gear's 0.5 - 0.305 = 0.195 m, in the crawl
    (its 0.3 m/s)."""
    drop = _lowest_foot(38.7) - HC
    speed, time = GUIDANCE_P["touchdown_speed"], GUIDANCE_P["descent_time"]
    assert _rate(0.5, 0.0) == pytest.approx((0.5 - HC) / time, abs=1e-9)
    assert _rate(0.5, drop) == pytest.approx(speed, abs=1e-9)
    # the crawl starts touchdown_speed x descent_time above the contact height
    start = HC + drop + speed * time
    assert _rate(start + 0.05, drop) == pytest.approx((start + 0.05 - HC - drop) / time,
                                                      abs=1e-9)
    assert _rate(start - 0.05, drop) == pytest.approx(speed, abs=1e-9)


def _policy_after(h, drop):
    """The touchdown policy's tilt limit and aim (the pivot's x arm) after one committed
    descent step from ``h`` m above the contact height, the policy on (GUIDANCE_P's flare
    0.15 m at 0.6 rad, aim 0.3 m), the quadrotor on the reference at rest over the pad."""
    z_ref = HC + drop + h
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC, contact_drop=drop,
                                   fly_on=1.0, pivot_x=0.15))
    _, ref = (np.asarray(v, dtype=float).ravel() for v in guidance_function()(
        xg, [0.0, 0.0, z_ref], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
    c = TOUCHDOWN_COMMANDS.unpack(ref[POSITION_REFERENCE.slice("tilt_limit").start:])
    return float(c["tilt_limit"][0]), float(c["pivot"][0])


def test_the_flare_and_the_aim_count_from_the_contact_height():
    """The flare (0.15 m) and the aim (0.3 m) start that far above ``touchdown_height +
    contact_drop``: 0.1 m above the leaning gear's contact height (0.255 m above the level
    gear's, one crawl step of 3 mm lower) the leaning profile flares and aims, the level one
    only aims; 0.25 m above it the leaning one aims and the level one (0.405 m) does not."""
    drop, flare_tilt = _lowest_foot(38.7) - HC, GUIDANCE_P["flare_tilt"]
    assert _policy_after(0.1, drop) == (pytest.approx(flare_tilt, abs=1e-12), 0.15)
    level = _policy_after(0.1 + drop, 0.0)
    assert level[0] == pytest.approx(math.pi / 2, abs=1e-12) and level[1] == 0.15
    assert _policy_after(0.25, drop)[1] == 0.15
    assert _policy_after(0.25 + drop, 0.0)[1] == 0.0


def _crawl_step(x, crawl_pause):
    """The reference height and the phase after one committed guidance step from 0.1 m
    above the contact height (in the crawl: 0.1 < 0.3 m/s x 1 s), the quadrotor on the
    reference ``x`` m ahead of the pad at rest."""
    z_ref = HC + 0.1
    xg = GUIDANCE_STATE.pack(dict(phase=DESCEND, timer=0.0, z_ref=z_ref, aborts=0,
                                  committed=1, armed=1.0, ms_rise=0.0, ms_rise_rate=0.0,
                                  ms_tilt_rate=0.0, ms_tilt_acc=0.0, lean_x=0.0, lean_y=0.0,
                                  lean_gust=0.0))
    cues = GUIDANCE_CUES.pack(dict(touchdown=0.0, marker_age=0.0, contact_switch=0.0))
    pg = GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, touchdown_height=HC, crawl_pause=crawl_pause))
    xg_next, _ = (np.asarray(v, dtype=float).ravel() for v in guidance_function()(
        xg, [x, 0.0, z_ref], [0.0, 0.0, 0.0], 0.0, 0.0, cues, DT, pg))
    g = GUIDANCE_STATE.unpack(xg_next)
    return g["z_ref"][0], g["phase"][0]


def test_the_crawl_pauses_out_of_the_band_only_with_crawl_pause():
    """The align band is half ``max_offset`` (GUIDANCE_P's 0.2 m: 0.1 m). 5 cm off, both
    crawls fall one step of 0.3 m/s; 15 cm off (out of the band, within the limit) the
    committed crawl falls on and the pausing one holds its height; 25 cm off (past the
    limit) both abort back to align."""
    z_ref, step = HC + 0.1, GUIDANCE_P["touchdown_speed"] * DT
    for pause in (0.0, 1.0):
        assert _crawl_step(0.05, pause) == (pytest.approx(z_ref - step, abs=1e-12), DESCEND)
        assert _crawl_step(0.25, pause)[1] == ALIGN
    assert _crawl_step(0.15, 0.0) == (pytest.approx(z_ref - step, abs=1e-12), DESCEND)
    assert _crawl_step(0.15, 1.0) == (z_ref, DESCEND)

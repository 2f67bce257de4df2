"""highway_100's crawl gate (issue 19, docs/landing.md, "highway_100: the crawl's gate on the
predicted offset, its wait over the whole crawl").

The off-pad failures of the eighteenth's file are contacts behind the pad's centre: under the
flare's 46 deg lean limit the body drifts back in the last second, its front feet meet the roof
(and their magnets hold them), and the level-out pivots the body about them, so its centre
comes to rest at least ``fx (1 - cos th) + hc sin th`` (0.20 m at 46 deg, the front foot
``(fx, -hc)`` pitched by ``th`` and then level) behind its contact, and a rear foot past the
pad's 0.7 m. Checked on the default seed's run 165 against that hand-derived pivot; the shipped
gate (0.10 m on the offset predicted at the contact, a 1 s wait) holds that crawl while it
drifts, and the run lands on the pad.
"""

import numpy as np
from graze_rig import flown
from reference import HIGHWAY_100_GATE

FX, HC, PAD = 0.30, 0.15, 0.7   # m: gear.feet_x, quadrotor.gear_height, landing.pad_radius


def _at(res, t):
    return int(np.searchsorted(res["t"], t))


def test_the_level_out_pivots_a_contact_behind_the_pad_off_it_without_the_gate():
    """Default seed, run 165, the eighteenth's file (``HIGHWAY_100_GATE``): the contact is
    0.15-0.21 m behind the centre, leaning 40-48 deg, after a drift back of over 5 cm in the last
    second; the centre comes to rest behind the contact by at least the hand-derived pivot
    (less 1 cm), and the judge puts the run off the pad. The file's values are the ones flown."""
    res, rep = flown("highway_100", 165, *HIGHWAY_100_GATE)
    assert res.scenario.data["landing"]["crawl_gate"] == 0.0
    k = _at(res, rep.time)
    x_c = res["x_e"][k]
    th = res["theta1"][k]
    assert -0.21 < x_c < -0.15 and 40.0 < np.degrees(th) < 48.0
    assert x_c < res["x_e"][_at(res, rep.time - 1.0)] - 0.05
    pivot = FX * (1.0 - np.cos(th)) + HC * np.sin(th)
    assert 0.17 < pivot < 0.21
    x_rest = res["x_e"][-1]
    assert x_rest < x_c - pivot + 0.01
    assert np.hypot(x_rest - FX, res["y_e"][-1]) > PAD - 0.02
    assert not rep.success and rep.on_pad is False and rep.secured


def test_the_shipped_gate_lands_it_on_the_pad():
    """The same draw on the shipped file (gate 0.10 m over at most 0.3 s, 1 s wait): the run
    lands, secured, and rests on the pad, its contact within 0.1 m of the centre and at least
    0.1 m nearer it than the eighteenth's."""
    before, rep_before = flown("highway_100", 165, *HIGHWAY_100_GATE)
    res, rep = flown("highway_100", 165)
    land = res.scenario.data["landing"]
    assert (land["crawl_gate"], land["crawl_gate_time"], land["crawl_gate_wait"]) == (0.1, 0.3, 1.0)
    assert rep.success and rep.secured and rep.on_pad
    assert rep.offset < 0.1 and rep.offset < rep_before.offset - 0.1


def test_the_flights_part_where_the_hand_prediction_passes_the_gate_inside_the_align_band():
    """Why the shipped file's 165 differs (review, nineteenth): the two flights are the same
    bits until the gate's first hold of its own. Over the 10 ms before the body's state first
    differs, the prediction worked by hand from the logged estimate, ``|p + v t_go|`` with the
    horizon's 0.3 s (the crawl's time left is longer: the reference leads the body down by at
    most ``descent_leash``, so ``t_go >= (gap - 0.05) / touchdown_speed``), passes the 0.10 m
    gate, while the estimate is inside the align band (half ``max_offset`` and
    ``max_relative_speed``: 0.1 m, 0.25 m/s), where
    ``crawl_pause`` alone lets the crawl fall (and the eighteenth's did); at the start of those
    10 ms it was inside the gate. The gated reference then holds over the falling one."""
    before, _ = flown("highway_100", 165, *HIGHWAY_100_GATE)
    res, _ = flown("highway_100", 165)
    land = res.scenario.data["landing"]
    n = min(len(before["t"]), len(res["t"]))
    k = int(np.flatnonzero(before["x_e"][:n] != res["x_e"][:n])[0])
    rows = slice(k - 10, k + 1)
    p = np.stack([res["x_e_hat"][rows], res["y_e_hat"][rows]])
    v = np.stack([res["vx_e_hat"][rows], res["vy_e_hat"][rows]])
    gap = res["gear_gap"][rows]
    assert np.all((gap - land["descent_leash"]) / land["touchdown_speed"] > land["crawl_gate_time"])
    predicted = np.hypot(*(p + v * land["crawl_gate_time"]))
    assert predicted.max() > land["crawl_gate"]
    assert np.all(np.hypot(*p) <= land["max_offset"] / 2)            # 0.1 m
    assert np.all(np.hypot(*v) <= land["max_relative_speed"] / 2)    # 0.25 m/s
    assert np.hypot(*(p[:, 0] + v[:, 0] * land["crawl_gate_time"])) < land["crawl_gate"]
    later = _at(res, res["t"][k] + 0.05)
    assert res["z_ref"][later] > before["z_ref"][later]

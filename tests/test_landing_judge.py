"""The landed-and-secured judge's rules (issue 18's adversarial review), each against a
case worked by hand: tip-over judged by the gear (a foot off the deck past the static
tip-over angle with the rotors cut), the tilt at contact against the gear's tip-over
angle, the wind in the friction margin of a landing's rows, and ``phases.landed``.

quadland.kinds.landing.contact_report has the rules; docs/landing.md, "Landed and
secured", their sources.
"""

import json
import types

import numpy as np
import pytest
from highway_before import BEFORE as HIGHWAY_BEFORE
from reference import HANDOVER_COLD, HIGHWAY_100_OLD, rotation
from turning_before import BEFORE

import quadland
from quadland.kinds.landing.contact_report import contact_figures
from quadland.kinds.landing.report import landing_summary, touchdown_report
from quadland.kinds.landing.values import landing_clocks, landing_disturbance, landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.gear import CUT_THRUST, GEAR_SIGNALS
from quadland_symbolic.landing.loop import landing_gear_signals_function
from quadland_symbolic.landing.plant import LANDING_PLANT_STATE

#: The limits of the synthetic rows: the shipped highway's.
LIMITS = dict(max_gear_load=424.0, max_bounce=0.02, max_friction_margin=1.0, pad_radius=0.5)
M, G = 2.0, 9.8


class _Rows(dict):
    """A landing's result as :func:`contact_figures` reads it: columns and a scenario."""

    def __init__(self, columns, settle=0.03, rate=100.0):
        super().__init__(columns)
        self.scenario = types.SimpleNamespace(data=dict(
            landing=dict(settle_time=settle), simulation=dict(output_rate_hz=rate, duration=40.0),
            quadrotor=dict(gravity=G)))


def _rows(tip, feet, thrust):
    """Four rows from a contact at t = 1 s, all on the pad and held, whose second row has
    the given tip margin, feet down and total thrust (the others resting level)."""
    n = 4
    col = dict(t=1.0 + 0.01 * np.arange(n), touched=np.ones(n), feet_down=np.full(n, 4.0),
               foot_gap=np.zeros(n), tip_margin=np.full(n, 0.1), tilt_rel=np.full(n, 0.05),
               engaged=np.ones(n), friction_margin=np.zeros(n), F_peak=np.full(n, 30.0),
               foot_sink_rate=np.full(n, 0.3), foot_offset=np.full(n, 0.2),
               F_total=np.zeros(n))
    col["tip_margin"][1], col["feet_down"][1], col["F_total"][1] = tip, feet, thrust
    return _Rows(col)


@pytest.mark.parametrize("tip,feet,thrust,tipped", [
    (1.2, 2.0, 0.0, True),                  # past the angle, on two feet, rotors cut
    (1.2, 2.0, M * G, False),               # the same held up by the rotors: flying
    (1.2, 4.0, 0.0, False),                 # every foot on the deck: not going over
    (0.9, 2.0, 0.0, False),                 # on an edge within the angle: falls back
    (1.2, 2.0, 0.99 * CUT_THRUST * M * G, True),   # thrust just below the cut's share
    (1.2, 2.0, 1.01 * CUT_THRUST * M * G, False),
])
def test_tipped_is_past_the_angle_on_a_lifted_foot_with_the_rotors_cut(tip, feet, thrust,
                                                                       tipped):
    fig = contact_figures(_rows(tip, feet, thrust), LIMITS, M)
    assert fig["tipped"] is tipped
    assert ("tipped" in fig["failures"]) is tipped
    assert fig["secured"] and fig["on_pad"]


def test_the_tilt_at_contact_is_judged_against_the_tip_over_angle_in_its_direction():
    # the first row's tilt 0.6 rad at a margin 0.95 (within): the centre's projection
    # scales with tan(tilt), so the gear's angle in that direction is atan(tan 0.6 / 0.95)
    # rad; at a margin 1.05 the contact is tilted past it
    rows = _rows(0.1, 4.0, 0.0)
    rows["tilt_rel"][0], rows["tip_margin"][0] = 0.6, 0.95
    fig = contact_figures(rows, LIMITS, M)
    assert fig["tip_over_deg"] == pytest.approx(np.degrees(np.arctan(np.tan(0.6) / 0.95)),
                                                rel=1e-12)
    assert "tilted" not in fig["failures"]
    rows["tip_margin"][0] = 1.05
    assert contact_figures(rows, LIMITS, M)["failures"] == ["tilted"]


def test_on_the_pad_is_every_foot_within_the_pad_radius():
    rows = _rows(0.1, 4.0, 0.0)
    rows["foot_offset"][2] = 0.5                      # on the edge: still on the pad
    assert contact_figures(rows, LIMITS, M)["on_pad"]
    rows["foot_offset"][2] = 0.5 + 1e-9
    fig = contact_figures(rows, LIMITS, M)
    assert not fig["on_pad"] and fig["failures"] == ["off the pad"]


def test_highway_100_flared_to_40_deg_is_tilted_not_tipped():
    """On highway_100's old airframe (``HIGHWAY_100_OLD``, where it was measured; issue 19's
    gear made for the speed tips at 63.4 deg). Flaring to 40 deg (its default was 34),
    it meets the roof leaning 38.9 deg, past its gear's static tip-over angle about y,
    atan(0.15 / 0.2) = 36.87 deg (the tilt mostly pitch: the angle in its direction,
    atan(d / 0.2) with d the distance from the centre to the 0.15 x 0.125 m support
    rectangle's edge in the tilt's azimuth, is 36.94 deg since the sensors' draws come
    in blocks, issue 20; 36.87 before), while the rotors still fly it; they level it
    onto the magnet. Before the review it read "tipped" (any row past the angle, rotors
    or not) and its tilt passed the 48.7 deg limit: now the contact is "tilted" and
    nothing tipped over. (Without the aim point's pivot shift, ``pivot_aim = 0``, as it
    was measured: aiming ahead, the body meets the roof at 36.75 deg and lands. And
    without the heading's share of the camera's noise, ``estimator.vision_heading_sigma
    = 0``, as it was measured: with it, docs/estimator.md (E10c), this one flight meets
    the roof at 36.70 deg, inside the angle, and lands.)"""
    res = quadland.simulate(load_scenario(
        "highway_100", [*HIGHWAY_100_OLD, "touchdown.flare_tilt_deg=40.0",
                        "touchdown.pivot_aim=0.0",
                        "estimator.vision_heading_sigma=0.0"]))
    rep = touchdown_report(res)
    k0 = int(np.argmax(res["touched"] > 0.5))
    roll, pitch = res["roll_rel"][k0], res["pitch_rel"][k0]
    # the deck normal's horizontal part in body axes, (-sin p, sin r cos p): its azimuth
    azimuth = np.arctan2(abs(np.sin(roll) * np.cos(pitch)), abs(np.sin(pitch)))
    edge = min(0.15 / np.cos(azimuth), 0.125 / np.sin(azimuth))
    assert 0 < np.degrees(azimuth) < 10 and edge > 0.15          # mostly pitch
    assert rep.tilt_deg > np.degrees(np.arctan(edge / 0.2)) and rep.tilt_deg < 48.7
    assert rep.tip_over_deg == pytest.approx(np.degrees(np.arctan(edge / 0.2)), rel=1e-9)
    assert rep.failures == ["tilted"] and not rep.tipped and rep.secured


def test_a_landing_s_rows_carry_the_held_wind_in_the_friction_margin():
    """The turning car with no lock on the true state: the last row's margin is the gear's
    signals under the wind sample held then (the scenario's mean, turbulence and gust at
    that time), not under still air; and summary.json's phases.landed is that row's time,
    settle_time after the first contact."""
    sc = load_scenario("turning", ["sensors.enabled=false", 'touchdown.lock="none"'])
    res = quadland.simulate(sc)
    clocks = landing_clocks(sc)
    t_w = clocks[1].times()
    w = landing_disturbance(sc, t_w)
    t = res["t"][-1]
    held = w[:, np.searchsorted(t_w, t + 1e-9, side="right") - 1]
    assert np.linalg.norm(held[:3]) > 0.1                      # a wind to feel
    pp = landing_values(sc).pp
    xp = res.states[-1, :LANDING_PLANT_STATE.size]

    def margin(wind):
        s = landing_gear_signals_function()(xp, np.concatenate([wind, held[3:]]), t, pp)
        return float(GEAR_SIGNALS.unpack(np.asarray(s, dtype=float).ravel())["friction_margin"][0])

    assert res["friction_margin"][-1] == pytest.approx(margin(held[:3]), rel=1e-12)
    assert abs(margin(held[:3]) - margin(np.zeros(3))) > 1e-3
    summary = landing_summary(res)
    rep = summary["landing"]
    assert rep["secured"] and summary["phases"]["landed"] == t
    assert abs(t - (rep["time"] + sc["landing.settle_time"])) <= 0.01 + 1e-9


def test_no_lock_in_a_headwind_is_judged_with_the_friction_the_wind_consumes():
    """highway with no lock on the true state in a 6 m/s headwind (mean, -x; the car drives
    +x at 50 km/h): the airspeed on the roof is about 20 m/s, whose drag (Kt V + Kq V^2,
    about 10.8 N) passes mu m g = 9.8 N. The last row's margin is the closed form from the
    plant's state and the wind sample held then, multiplied out here with numpy: the feet
    must supply F = m g e_z - R1 (-Kt V_b - Kq V_b |V_b|), V_b = V1 - R1^T v_wind (the car
    steady, the deck level and still, the rotors cut), margin |F_xy| / (mu F_z). It is
    above 1: not secured. With the still air's drag, as before the review, it read 0.56
    and the body that slid 2 m off the pad "secured"."""
    # the law without the disturbance observer and with the outer bias estimates on every
    # axis, whose end state this is (with it the body
    # ends turned so that the wind's drag asks 0.97 of the friction: a judge's test)
    sc = load_scenario("highway", ["sensors.enabled=false", 'touchdown.lock="none"',
                                   "wind.mean=[-6.0, 0.0, 0.0]",
                                   "controller.observer_frequency=[0.0, 0.0, 0.0]",
                                   "controller.ki_p=[0.5, 0.5, 1.0]", *HIGHWAY_BEFORE])
    res = quadland.simulate(sc)
    t_w = landing_clocks(sc)[1].times()
    t = res["t"][-1]
    wind = landing_disturbance(sc, t_w)[:3, np.searchsorted(t_w, t + 1e-9, side="right") - 1]
    x = res.states[-1]
    R1 = rotation(x[3:6])
    V_b = x[6:9] - R1.T @ wind
    q = sc.data["quadrotor"]
    drag = -np.asarray(q["drag_translational"]) * V_b \
        - np.asarray(q["drag_quadratic"]) * V_b * np.abs(V_b)
    assert res["F_total"][-1] < 1e-9                          # the rotors cut
    F = q["mass"] * q["gravity"] * np.array([0.0, 0.0, 1.0]) - R1 @ drag
    hand = np.hypot(F[0], F[1]) / (sc["gear.friction"] * F[2])
    assert res["friction_margin"][-1] == pytest.approx(hand, rel=1e-9)
    assert hand > 1
    rep = touchdown_report(res)
    assert not rep.secured and "not secured" in rep.failures
    assert landing_summary(res)["phases"]["landed"] is None


def test_off_the_pad_names_both_of_its_causes_when_no_foot_left_the_pad(tmp_path, capsys):
    """The turning car's crawl forced to 2.5 m/s with no lock, on the true state: it meets
    the roof at 3.1 m/s and tips over, the run stopping on the deck 0.35 s after the first
    contact. Every foot stays within the 0.5 m pad (the farthest 0.29 m, multiplied out
    here from the CSV's poses and the gear's corners), so it is not on the pad only because
    the run ended before the settle time. The verdict read "a foot left the pad (0.5 m)
    before the settle time" until this review; it names both causes now."""
    from quadland.cli import main

    out = tmp_path / "hard"
    # the rotors cut at the contact switch: turning's touchdown of before its flare
    sets = ["sensors.enabled=false", 'touchdown.lock="none"', "landing.touchdown_speed=2.5",
            "landing.descent_speed=2.5", *BEFORE]
    assert main(["simulate", "--scenario", "turning", "--no-plots", "--out", str(out),
                 *(a for s in sets for a in ("--set", s))]) == 0
    line = capsys.readouterr().out.splitlines()[1]
    land = json.loads((out / "summary.json").read_text())["landing"]
    sc = load_scenario("turning", sets)
    fx, fy, h = sc["gear.feet_x"], sc["gear.feet_y"], sc["quadrotor.gear_height"]
    feet = np.array([[sx * fx, sy * fy, -h] for sx in (1, -1) for sy in (1, -1)]).T
    rows = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    rows = rows[rows["t"] >= land["time"] - 1e-9]
    farthest = 0.0
    for r in rows:
        R1 = rotation([r["phi1"], r["theta1"], r["psi1"]])
        R2 = rotation([r["phi2"], r["theta2"], r["psi2"]])
        d = R2.T @ (np.array([r["x1"] - r["x2"], r["y1"] - r["y2"], r["z1"] - r["z2"]])[:, None]
                    + R1 @ feet)
        farthest = max(farthest, float(np.max(np.hypot(d[0], d[1]))))
    assert rows["t"][-1] < land["time"] + sc["landing.settle_time"] - 1.0    # stopped early
    assert land["tipped"] and not land["on_pad"] and farthest < 0.5
    assert "off the pad" in land["failures"]
    assert "off the pad (0.5 m): a foot left it or the run ended before the settle time" in line
    assert "a foot left the pad" not in line


def test_an_engaged_magnet_on_a_slippery_roof_that_slides_is_not_secured():
    """highway with mu = 0.03 (its sensors on, its magnet): the magnet engages, but the
    feet can hold mu (m g + F_lock) = 0.03 x 119.6 = 3.6 N against the 50 km/h airflow's
    Kt V + Kq V^2 = 0.3 x 13.9 + 0.01225 x 13.9^2 = 6.5 N: at the last row the body
    slides back across the roof at 1.07 m/s (0.92 m/s on the sensors' draws before they
    came in blocks, issue 20; about 2 m/s with highway's law before the observer on z and
    no outer bias estimates on x, y), the margin (with the lock's pull) over 1."""
    sc = load_scenario("highway", ["gear.friction=0.03", *HIGHWAY_BEFORE])
    res = quadland.simulate(sc)
    V = sc["initial.velocity2"][0]
    drag = 0.3 * V + 0.01225 * V ** 2
    assert drag / (0.03 * (M * G + 100.0)) > 1.5
    assert res["engaged"][-1] > 0.95 and res["friction_margin"][-1] > 1
    assert np.hypot(res["dx_e"][-1], res["dy_e"][-1]) == pytest.approx(1.073, abs=1e-3)
    assert not touchdown_report(res).secured


def test_a_body_that_flies_off_the_deck_has_not_tipped_over_on_it():
    """highway with the rotors cut to their F_max (touchdown.idle_thrust = 9.8 N: 2 m1 g in all, a
    valid 'idle'): the body lifts off the roof at the contact and tumbles away; the run ends
    at the settle time with its centre 14.5 m above the deck, rolled 44.0 deg (on the
    handover's cold start it was measured with, ``HANDOVER_COLD``; 12.3 m and 64.5 deg on
    the sensors' draws before they came in blocks, issue 20; before the observer on z and no
    outer bias estimates on x, y it stopped at the singular attitude, roll 89.6 deg, 6.6 m
    above); the verdict once read 'bounced 645.6 cm > 2 cm; tipped over on the deck; ...'."""
    res = quadland.simulate(load_scenario("highway", ["touchdown.idle_thrust=9.8",
                                                       *HIGHWAY_BEFORE, *HANDOVER_COLD]))
    assert res["z1"][-1] - res["z2"][-1] > 5.0                 # far above the deck
    assert np.degrees(abs(res["phi1"][-1])) == pytest.approx(43.97, abs=0.05)
    rep = touchdown_report(res)
    assert not rep.tipped and "bounced" in rep.failures

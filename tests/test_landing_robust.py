"""The landing controller against a world that differs from its model (issue 19, item 1).

The controller keeps its own model (``[controller_model]``: the nominal airframe, whole
rotors, a centred centre of gravity); each case makes the plant ([quadrotor],
[disturbance]) differ from it on purpose, and ``highway`` (and, below, the ships) is
flown on its sensors at its default seed. The checks are the touchdown report's,
against the scenario's limits.

No controller can hold the pad against a horizontal force ``F`` with its thrust tilted
less than ``atan(F / (m g))``: each drag and side-force case checks that premise by hand
against the scenario's limits first. With issue 18's drag, three times it cannot hold
the highway car at any tilt allowed, nor the ship in its crosswind (21.1 deg against
17.9): there a landing is the flare's drift, and 8 of 11 seeds land.

The bias estimates' effect is checked where it is exact: at the hover equilibrium a
constant mismatch leaves no position error with them, and leaves one without.
"""

import math

import numpy as np
import pytest
from campaign_corners import airframe_corners, corner_id

import quadland
from quadland.kinds.landing.report import touchdown_report
from quadland.linearization import equilibrium
from quadland.scenario import load_scenario
from quadland_symbolic.landing.controller import landing_memory
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE, quadrotor6_rhs
from quadland_symbolic.parameters import QUADROTOR

M, G = 2.0, 9.8
#: highway's car speed, m/s (50 km/h): the quadrotor flies through still air at it.
U_CAR = 50 / 3.6


def _lands(*overrides):
    rep = touchdown_report(quadland.simulate(load_scenario("highway", list(overrides))))
    assert rep.touchdown and rep.success, rep
    return rep


# ---------------------------------------------------------------- the plant's departures

def test_a_weak_rotor_and_an_offset_centre_of_gravity_by_hand():
    """Rotor i makes e_i times its command (its motor state settles there); a centre of
    gravity r from the rotors' centre adds the thrust's moment -r x T e_z = T [-r_y, r_x, 0]
    (body), so p', q' change by that over the inertia."""
    p_quad = QUADROTOR.pack(dict(m1=M, I=[0.025, 0.025, 0.045], Kt=[0.1] * 3,
                                 Kr=[0.001] * 3, g=G, arm=0.25, c=0.05))

    def act(eff, r):
        return ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=9.8, gear_height=0.2,
                                  drag_quadratic=[0.0] * 3, rotor_radius=0.0,
                                  air_density=1.225, rotor_efficiency=eff, cg_offset=r))

    F = np.array([4.0, 5.0, 6.0, 5.5])
    x = QUAD6_STATE.pack(dict(p1=[0, 0, 3], eta1=[0.05, -0.03, 0.2], V1=[1, 0.5, 0],
                              Omega1=[0.1, -0.2, 0.05], F=F))
    cmd, zero = np.array([5.0, 5.0, 5.0, 5.0]), np.zeros(3)
    base = QUAD6_STATE.unpack(np.asarray(quadrotor6_rhs(x, cmd, zero, zero, p_quad,
                                                        act([1.0] * 4, zero))).ravel())
    r = np.array([0.02, -0.01, 0.03])
    off = QUAD6_STATE.unpack(np.asarray(quadrotor6_rhs(x, cmd, zero, zero, p_quad,
                                                       act([0.8, 1, 1, 1], r))).ravel())
    np.testing.assert_allclose(off["F"], (np.array([4.0, 5, 5, 5]) - F) / 0.02, rtol=1e-14)
    T = F.sum()
    np.testing.assert_allclose(off["Omega1"] - base["Omega1"],
                               T * np.array([-r[1], r[0], 0.0]) / [0.025, 0.025, 0.045],
                               rtol=1e-12)
    for name in ("p1", "eta1", "V1"):
        np.testing.assert_allclose(off[name], base[name], rtol=1e-15)


# ---------------------------------------------------------------- integral action, exactly

#: The outer bias estimates on every axis, as highway shipped them before its observer
#: took their place on x and y (docs/landing.md, "The bias estimates' slow tail").
KI_P = "controller.ki_p=[0.5, 0.5, 1.0]"


@pytest.mark.parametrize("case", ["controller_model.mass=2.4",
                                  "quadrotor.drag_translational=[0.6, 0.6, 0.6]",
                                  "disturbance.force_bias=[0.0, 4.0, 0.0]"])
def test_a_constant_mismatch_leaves_no_hover_error_with_the_bias_estimates(case):
    """At the hover equilibrium (the vehicle in its steady motion) the bias estimates'
    rates are ki z2, so z2 = 0 there; with z2 = v_e + k1p z1 at rest, z1 = 0: the
    quadrotor hovers exactly at its reference. Without them (ki_p = 0) the same mismatch
    leaves it off (a proportional loop needs an error to push back)."""
    ref = np.array([0.0, 0.0, 3.0])                          # landing.hover_height
    off = "controller.observer_frequency=[0.0, 0.0, 0.0]"   # the bias estimates alone
    # (highway ships them on z only, beside its observer: docs/landing.md)
    with_bias = equilibrium(load_scenario("highway", [case, off, KI_P]))
    np.testing.assert_allclose(with_bias.xr[:3], ref, atol=1e-9)
    without = equilibrium(load_scenario("highway", [case, off,
                                                    "controller.ki_p=[0.0, 0.0, 0.0]"]))
    assert np.max(np.abs(without.xr[:3] - ref)) > 5e-3


def _memory(point):
    """The equilibrium's landing memory, unpacked (its size is 6 l + a constant)."""
    l = (point.xc.size - landing_memory(1).size) // 6 + 1
    return landing_memory(l).unpack(point.xc)


@pytest.mark.parametrize("case", ["controller_model.mass=2.4",
                                  "quadrotor.drag_translational=[0.6, 0.6, 0.6]",
                                  "disturbance.force_bias=[0.0, 4.0, 0.0]"])
def test_the_observer_learns_what_the_bias_estimates_learn(case):
    """Two mechanisms, one force balance. At rest the bias estimates settle where the
    law's acceleration balances the mismatch with z1 = z2 = 0: d_hat_p = d. The
    disturbance observer alone (ki_p = 0) settles where its velocity estimate is at rest
    on the measured one: d_o = -(a_T + f_k) = d, and then the law's own balance puts the
    quadrotor on its reference too. Both on: the same hover, d_o = d and d_hat_p = 0."""
    ref = np.array([0.0, 0.0, 3.0])
    on = "controller.observer_frequency=[2.0, 2.0, 2.0]"
    bias = equilibrium(load_scenario("highway", [case, "controller.observer_frequency=[0.0, 0.0, "
                                                       "0.0]", KI_P]))
    observer = equilibrium(load_scenario("highway", [case, on, "controller.ki_p=[0.0, 0.0, 0.0]"]))
    both = equilibrium(load_scenario("highway", [case, on, KI_P]))
    d = _memory(bias)["d_hat"][:3]
    assert np.max(np.abs(d)) > 0.05
    for point in (observer, both):
        np.testing.assert_allclose(point.xr[:3], ref, atol=1e-9)
        np.testing.assert_allclose(_memory(point)["d_o"], d, atol=1e-9)
    np.testing.assert_allclose(_memory(both)["d_hat"][:3], 0.0, atol=1e-9)


# ---------------------------------------------------------------- the cases land

def test_lands_with_a_rotor_at_80_percent_thrust():
    _lands("quadrotor.rotor_efficiency=[0.8, 1.0, 1.0, 1.0]")


@pytest.mark.parametrize("mass", [1.6, 2.4])
def test_lands_with_the_mass_20_percent_off_the_model(mass):
    _lands(f"quadrotor.mass={mass}")


@pytest.mark.parametrize("offset", ["[0.02, 0.0, 0.0]", "[0.0, 0.02, 0.0]"])
def test_lands_with_the_centre_of_gravity_2_cm_off(offset):
    _lands(f"quadrotor.cg_offset={offset}")


def _drag_lean_deg(Kt, Kq, u, side=0.0):
    """deg: the steady tilt that holds the pad at airspeed u against the drag Kt u + Kq u^2
    and a side force, by the force balance alone."""
    return math.degrees(math.atan(math.hypot(Kt * u + Kq * u * u, side) / (M * G)))


def test_three_times_the_drag_cannot_land_on_the_highway_car():
    """Issue 18's drag (Kt = 0.3 N s/m, Kq = 0.01225 N s^2/m^2) three times over, at the
    car's 50 km/h: 19.6 N, a 45 deg lean: all of the controller's 45 deg tilt limit
    (PX4's; 30 deg before issue 19's bar), nothing left to hold the pad with, and past the
    gear's static tip-over angle about y, atan(feet_x / gear_height) = 36.9 deg. (Flown,
    it holds the pad, touches down leaning 42.8 deg and tips over on the deck.) The
    issue's case was three times the old 0.1 N s/m."""
    sc = load_scenario("highway")
    Kt, Kq = sc["quadrotor.drag_translational"][0], sc["quadrotor.drag_quadratic"][0]
    assert (Kt, Kq) == (0.3, 0.01225)
    lean = _drag_lean_deg(3 * Kt, 3 * Kq, U_CAR)
    assert lean == pytest.approx(45.0, abs=0.1)
    assert lean > sc["controller.tilt_max_deg"] - 0.1
    tip = math.degrees(math.atan2(sc["gear.feet_x"], sc["quadrotor.gear_height"]))
    assert tip == pytest.approx(36.87, abs=0.01) and lean > tip


def _ship_lean_deg(Kt, Kq, air):
    """deg: the tilt of the thrust that holds a quadrotor at rest over the pad against the
    plant's drag (docs/landing.md, "Real drag and thrust": ``-Kt V`` and ``-Kq V |V|`` per
    body axis, ``V`` the air's velocity past the body, body axes), solved by hand from the
    force balance ``R (T e_z + f_body) = m g e_z`` for roll, pitch and thrust (yaw 0: the
    vessel's heading)."""
    import scipy.optimize

    def rot(phi, theta):
        cp, sp, ct, st = math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta)
        return np.array([[ct, sp * st, cp * st], [0.0, cp, -sp], [-st, sp * ct, cp * ct]])

    def balance(x):
        R = rot(x[0], x[1])
        vb = R.T @ air
        return R @ (np.array([0.0, 0.0, x[2]]) - Kt * vb - Kq * vb * np.abs(vb)) - [0, 0, M * G]

    phi, theta, _ = scipy.optimize.fsolve(balance, [0.1, 0.1, M * G], xtol=1e-12)
    return math.degrees(math.acos(math.cos(phi) * math.cos(theta)))


def test_three_times_the_drag_cannot_be_held_on_the_ship():
    """The ship's air: the vessel's 5 m/s ahead and the 5 m/s mean crosswind from port
    (``wind.mean``), 7.07 m/s past a quadrotor holding the pad. Three times the drag there
    (Kt = 0.9 N s/m, Kq = 0.03675 N s^2/m^2) takes 21.1 deg of steady lean by the force
    balance: past the ship's 17.9 deg contact limit and the flare's 15 deg. (The linear
    drag alone, 0.9 x 7.07 = 6.36 N, takes 18.0 deg.) Until the eleventh session this
    test's premise read 15.4 deg, the vessel's 5 m/s without the crosswind: inside the
    limit. As on the highway car, no controller can hold the pad at the contact's tilt;
    a landing is the drift the flare's tilt limit leaves, ``(tan 21.1 - tan 15) g`` =
    1.2 m/s^2 downwind, within the 0.5 m/s relative-speed limit until the contact
    (docs/landing.md, "The ship with three times the drag")."""
    sc = load_scenario("ship")
    v2, wind = sc["initial.velocity2"], sc["wind.mean"]
    assert sc["initial.psi2_deg"] == 0.0
    air = np.array([v2[0], v2[1], 0.0]) - np.asarray(wind, dtype=float)
    np.testing.assert_allclose(air, [5.0, 5.0, 0.0])
    lean = _ship_lean_deg(0.9, 0.03675, air)
    assert lean == pytest.approx(21.14, abs=0.01)
    assert lean > sc["landing.max_tilt_deg"] + 3 and lean > sc["touchdown.flare_tilt_deg"] + 6
    assert math.degrees(math.atan(0.9 * math.hypot(5, 5) / (M * G))) > sc["landing.max_tilt_deg"]
    # the drag the ship was built for: 7.4 deg, the 7.9 of its limit's comment by the
    # magnitude's formula, inside the flare's 15 deg
    assert _ship_lean_deg(0.3, 0.01225, air) == pytest.approx(7.41, abs=0.01)
    assert _drag_lean_deg(0.3, 0.01225, math.hypot(5, 5)) == pytest.approx(7.9, abs=0.05)
    # without the crosswind: the old premise, 15.4 deg, still over the flare's 15
    assert _ship_lean_deg(0.9, 0.03675, np.array([5.0, 0.0, 0.0])) == pytest.approx(15.37,
                                                                                  abs=0.01)


#: The ship with three times the modelled drag at its default seed (2026) and seeds 0-9:
#: the seeds that do not land, as measured, and what they fail on (strict xfails): each
#: crawl's drift downwind under the flare's tilt limit (the test above).
DRAG3_FAILS = {2026: "relative speed 0.533 m/s, 0.52 of it downwind",
               6: "no touchdown: 4 crawl aborts on the drift (0.48-0.68 m/s)",
               7: "relative speed 0.502 m/s, downwind 0.49",
               # since the handover takes the GNSS velocity: 0.495 m/s (landed) on the cold
               # start of before, a draw on the limit
               9: "relative speed 0.594 m/s at 30.75 s after one abort, then a bounce"}


@pytest.mark.parametrize("seed", [
    pytest.param(s, marks=pytest.mark.xfail(strict=True, reason=f"issue 19 item 1 unmet at "
                                             f"this seed: {DRAG3_FAILS[s]}"))
    if s in DRAG3_FAILS else s for s in (2026, *range(10))])
def test_the_ship_with_three_times_the_modelled_drag(seed):
    """Flown where the force balance cannot hold the pad (the test above): 7 of the 11 seeds land
    (8 on the handover's cold start of before the twentieth session: seed 9 met the deck at
    0.495 m/s, on the limit, and now at 0.594), each in the flare's drift before it reaches
    0.5 m/s; the default seed (2026) and seed 7 meet the deck over the 0.5 m/s relative-
    speed limit, nearly all of it downwind, and bounce (the crawl's abort climbs away from
    the contact), seed 6's four crawls each drift past 0.5 m/s and abort, and it does not
    touch down in the scenario's time. A shorter flare (0.2-0.25 m) lands 10 of the 11, a
    different one failing at each height, and costs `ship`'s campaign a run
    (docs/landing.md, "The ship with three times the drag"). (Until the descent waited for a
    calm window at the wait height, issue 19 item 4, it never touched down in 120 s; before
    the ships' flare 1 to 3 of 10 landed, the others tilted at contact.)"""
    sc = load_scenario("ship")
    rep = touchdown_report(quadland.simulate(load_scenario("ship", [
        "quadrotor.drag_translational=[0.9, 0.9, 0.9]",
        "quadrotor.drag_quadratic=[0.03675, 0.03675, 0.03675]",
        f"simulation.seed={seed}"])))
    assert rep.touchdown and rep.success, rep
    assert rep.tilt_deg < sc["touchdown.flare_tilt_deg"] + 2.9


#: Issue 19 item 1's other cases, flown on the ships (their default seeds; seeds 0-9 land
#: too, docs/landing.md).
SHIP_CASES = ["quadrotor.rotor_efficiency=[0.8, 1.0, 1.0, 1.0]", "quadrotor.mass=1.6",
              "quadrotor.mass=2.4", "quadrotor.cg_offset=[0.02, 0.0, 0.0]",
              "quadrotor.cg_offset=[0.0, 0.02, 0.0]", "disturbance.force_bias=[0.0, 4.0, 0.0]"]


@pytest.mark.parametrize("name", ["ship", "ship_ss5"])
@pytest.mark.parametrize("case", SHIP_CASES)
def test_the_ships_land_with_the_other_cases_of_item_1(name, case):
    """A rotor at 80 %, the mass 20 % off either way, the centre of gravity 2 cm forward or
    to the side, 4 N sideways (body y): the ships on their sensors land within their
    limits. The side force's lean by hand: in the ship's 7.07 m/s air, 4 N along body y
    beside the drag's (-1.81, -1.81) N on the body's level axes, 8.2 deg: inside the
    flare's 15."""
    if case.startswith("disturbance"):
        drag = 0.3 * 5.0 + 0.01225 * 25.0
        lean = math.degrees(math.atan(math.hypot(drag, drag - 4.0) / (M * G)))
        assert lean == pytest.approx(8.25, abs=0.01)
        assert lean < load_scenario(name)["touchdown.flare_tilt_deg"]
    rep = touchdown_report(quadland.simulate(load_scenario(name, [case])))
    assert rep.touchdown and rep.success, rep


def test_lands_with_a_4_newton_steady_side_force():
    """4 N sideways beside the 6.5 N of drag at 50 km/h needs a 21.3 deg lean: inside the
    highway's 32.6 deg contact limit (the drag's own 22.6 deg at its campaign's fastest
    car, 60 km/h, plus 10)."""
    sc = load_scenario("highway")
    need = _drag_lean_deg(0.3, 0.01225, U_CAR, side=4.0)
    assert need == pytest.approx(21.34, abs=0.01) and need < sc["landing.max_tilt_deg"]
    _lands("disturbance.force_bias=[0.0, 4.0, 0.0]")


# ---------------------------------------------------------------- the margins (item 2)

#: The shipped landing scenarios: each is checked at its hover point and at the corners of
#: its own campaign's dispersions of the airframe (``campaign_corners``: the file's nominal
#: values and ``[campaign]`` ranges; today mass and inertia +-10 %, both drags +-30 % of the
#: file's 0.3 N s/m and 0.01225 N s^2/m^2, motor lag 15 and 30 ms: 32 corners each).
LANDING = ("highway", "highway_100", "turning", "ship", "ship_ss5")

#: (scenario, corner's id): the multiloop disk phase margins, deg, continuous / sampled /
#: sampled with the navigation filter in the loop (the flown loop, the review's verdict),
#: of each corner that misses 45 deg in one of them, as measured (strict xfails).
#: highway_100's eight corners with 30 ms of motor lag keep 45 deg continuous and lose it
#: sampled (one period of computation delay); with the filter in the loop two of them keep
#: 45.09 deg. Two of highway's and six of turning's corners at 30 ms and 1.8 kg pass on
#: perfect sensing and miss with the filter in the loop (docs/landing.md, "The margins at
#: every campaign's own corners" and its review).
_MISSES = {
    "highway_100": {"m1.8-I0.0225-kt0.21-kq0.008575-tau0.03": (49.47, 43.56, 43.89),
                    "m1.8-I0.0225-kt0.21-kq0.015925-tau0.03": (48.89, 44.69, 45.09),
                    "m1.8-I0.0225-kt0.39-kq0.008575-tau0.03": (50.04, 44.78, 45.09),
                    "m1.8-I0.0275-kt0.21-kq0.015925-tau0.03": (45.40, 42.63, 42.66),
                    "m1.8-I0.0275-kt0.39-kq0.015925-tau0.03": (47.34, 44.69, 44.66),
                    "m2.2-I0.0225-kt0.21-kq0.008575-tau0.03": (49.95, 44.01, 44.24),
                    "m2.2-I0.0225-kt0.21-kq0.015925-tau0.03": (50.88, 44.54, 44.81),
                    "m2.2-I0.0225-kt0.39-kq0.008575-tau0.03": (50.87, 44.51, 44.74)},
    "highway": {"m1.8-I0.0225-kt0.21-kq0.008575-tau0.03": (49.16, 45.96, 44.84),
                "m1.8-I0.0275-kt0.21-kq0.008575-tau0.03": (49.16, 45.96, 44.84)},
    "turning": {"m1.8-I0.0225-kt0.21-kq0.008575-tau0.03": (49.09, 45.89, 44.71),
                "m1.8-I0.0225-kt0.21-kq0.015925-tau0.03": (49.22, 46.01, 44.82),
                "m1.8-I0.0275-kt0.21-kq0.008575-tau0.03": (48.17, 45.55, 44.28),
                "m1.8-I0.0275-kt0.21-kq0.015925-tau0.03": (48.15, 45.47, 44.12),
                "m1.8-I0.0275-kt0.39-kq0.008575-tau0.03": (48.55, 45.73, 44.68),
                "m1.8-I0.0275-kt0.39-kq0.015925-tau0.03": (48.45, 45.37, 44.48)}}
CORNER_FAILS = {(name, cid): "issue 19 item 2 unmet: multiloop disk phase margin " + ", ".join(
    f"{what} {pm:.2f}" for what, pm in zip(("continuous", "sampled", "filtered"), pms,
                                           strict=True)) + " deg (45 required)"
    for name, misses in _MISSES.items() for cid, pms in misses.items()}


def _points():
    for name in LANDING:
        for corner in [[], *airframe_corners(name)]:
            cid = f"{name}-{corner_id(corner)}"
            why = CORNER_FAILS.get((name, corner_id(corner)))
            marks = () if why is None else pytest.mark.xfail(strict=True, reason=why)
            yield pytest.param(name, corner, id=cid, marks=marks)


def _meets(name, overrides=(), filtered=False):
    """The margin review of ``name`` with ``overrides``, asserted to pass continuous and
    sampled, and with ``filtered`` also with the navigation filter in the loop (the flown
    loop, ``quadland margins``' verdict; about twice the review's CPU)."""
    from threadpoolctl import threadpool_limits

    from quadland.margins import margin_report

    with threadpool_limits(1):
        report = margin_report(load_scenario(name, list(overrides)), filtered=filtered)
    sections = [report.continuous, report.sampled]
    if filtered:
        assert report.filtered is not None, name
        sections.append(report.filtered)
    assert all(s.passed for s in sections), (
        name, overrides, [s.multiloop_disk.disk.phase_margin for s in sections])
    return report


def test_the_corners_are_each_campaigns_own():
    """The corners come from each file: its nominal drag (issue 18's, not the 0.1 N s/m of
    before) and its table's ranges, worked by hand for the two drags; every scenario has the
    2^5 corners of its five dispersed airframe keys, each key at both ends."""
    for name in LANDING:
        corners = airframe_corners(name)
        assert len(corners) == 32 and len({tuple(c) for c in corners}) == 32
        flat = {o for c in corners for o in c}
        assert "quadrotor.drag_translational=[0.21, 0.21, 0.21]" in flat
        assert "quadrotor.drag_translational=[0.39, 0.39, 0.39]" in flat
        assert "quadrotor.drag_quadratic=[0.008575, 0.008575, 0.008575]" in flat
        assert "quadrotor.drag_quadratic=[0.015925, 0.015925, 0.015925]" in flat
        assert {"quadrotor.motor_time_constant=0.015",
                "quadrotor.motor_time_constant=0.03", "quadrotor.mass=1.8",
                "quadrotor.mass=2.2"} <= flat
    # the file's own nominal moves its corners: 0.02 N s^2/m^2 +-30 %
    moved = {float(o.split("[")[1].split(",")[0])
             for c in airframe_corners("highway", ["quadrotor.drag_quadratic=[0.02, 0.02, 0.02]"])
             for o in c if o.startswith("quadrotor.drag_quadratic=")}
    assert sorted(moved) == pytest.approx([0.014, 0.026], rel=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize(("name", "corner"), list(_points()))
def test_the_gains_meet_6_db_and_45_deg_at_every_hover_point_and_corner(name, corner):
    """6 dB / 45 deg per loop with the others closed and the multiloop disk margin,
    continuous, sampled with one period of computation delay, and sampled with the
    navigation filter in the loop (issue 19 item 2: "the computation delay and the filter
    in the loop"), at the hover point and at each corner of the scenario's campaign (the
    controller's model at the nominal)."""
    _meets(name, corner, filtered=True)


def test_highway_meets_its_margins_at_the_worst_corner():
    """The hover point, and the corner with the least multiloop disk margin: 30 ms of
    motor lag with -10 % mass and +10 % inertia (docs/landing.md, "Gains")."""
    hover = _meets("highway")
    worst = _meets("highway", ["quadrotor.mass=1.8", "quadrotor.inertia=[0.0275, 0.0275, "
                               "0.0495]", "quadrotor.motor_time_constant=0.03"])
    assert (worst.sampled.multiloop_disk.disk.phase_margin
            < hover.sampled.multiloop_disk.disk.phase_margin - 3.0)

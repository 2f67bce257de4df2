"""Cars that drive and real drag (issue 18, items 4 and 5), against independent checks.

* the top speed at the tilt limit: the body-x balance ``m g sin(theta) = Kt V cos(theta)
  + Kq (V cos(theta))^2``, a quadratic solved by hand, is where the plant stops
  accelerating (faster decelerates, slower accelerates), and it is realistic;
* the ground effect's thrust ratio against Cheeseman and Bennett's formula, written out
  here, in hover and in forward flight;
* the drive profile's integrated path against hand computations: a lane change's
  sideways offset (``u A T^2 / (2 pi)``, and the exact quadrature of ``u sin(psi)``),
  a speed change's distance, a turn's heading;
* bad profiles: one line naming the key, exit 2;
* the law's feed-forward of the quadratic drag is the plant's (eq. 5 at zero thrust).
"""

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from quadland.cli import main
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.aero import aero_force
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT, known_acceleration
from quadland_symbolic.landing.deck import DECK_PARAMS, vehicle_motion
from quadland_symbolic.landing.drive import DRIVE_PARAMS, pack_drive
from quadland_symbolic.landing.gear import GEAR_STATE
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    loop_plant_function,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.landing.relative import relative6_acceleration
from quadland_symbolic.landing.sensors import measurement_function
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.vehicle import VEHICLE_STATE

DEG = math.pi / 180


def _params(name="highway", *overrides):
    sc = load_scenario(name, list(overrides))
    return sc, LANDING_PLANT_PARAMS.unpack(landing_values(sc).pp)


def _top_speed(m, g, Kt, Kq, theta):
    """The positive root of Kq c^2 V^2 + Kt c V - m g s = 0 (c, s of the tilt)."""
    c, s = math.cos(theta), math.sin(theta)
    a, b = Kq * c * c, Kt * c
    return (-b + math.sqrt(b * b + 4 * a * m * g * s)) / (2 * a)


def _cruise_state(p, V, theta, z=100.0):
    """Pitched forward by theta at V m/s along x in still air, the rotors' thrust holding
    the body-z balance T = m g c + Kt s V + Kq (s V)^2, at z m over the road."""
    q, a = QUADROTOR.unpack(p["p_quad"]), ACTUATOR.unpack(p["p_act"])
    m, g = q["m1"][0], q["g"][0]
    c, s = math.cos(theta), math.sin(theta)
    T = m * g * c + q["Kt"][2] * s * V + a["drag_quadratic"][2] * (s * V) ** 2
    x1q = QUAD6_STATE.pack(dict(p1=[0.0, 0.0, z], eta1=[0.0, theta, 0.0],
                                V1=[c * V, 0.0, s * V], Omega1=np.zeros(3), F=np.full(4, T / 4)))
    xv = VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=0, u2=0, v2=0, r2=0))
    return (LANDING_PLANT_STATE.pack(dict(x1q=x1q, xv=xv, gear=np.zeros(GEAR_STATE.size))),
            np.full(4, T / 4))


def _body_acceleration(xp, F, pp):
    xp_dot = np.array(loop_plant_function()(xp, F, LANDING_DISTURBANCE.zeros(), 0.0, pp)).ravel()
    return QUAD6_STATE.unpack(LANDING_PLANT_STATE.unpack(xp_dot)["x1q"])["V1"]


# ---------------------------------------------------------------- real drag

def test_top_speed_at_the_tilt_limit_is_the_closed_form_and_realistic():
    """At the shipped drag (PX4's EKF2_MCOEF and EKF2_BCOEF_X defaults for 2 kg) the
    quadrotor at a 30 deg tilt limit (the ships' until their flare, docs/landing.md "The
    ships' flare"; every landing scenario's is PX4's 45 deg since issue 19's bar, 33.3 m/s)
    stops accelerating at 21.45 m/s (15-25 m/s for a 2 kg quadrotor); it would fly 113 m/s
    on the old Kt = 0.1 N s/m alone."""
    sc, p = _params("ship", "quadrotor.rotor_radius=0.0", "controller.tilt_max_deg=30.0")
    pp = LANDING_PLANT_PARAMS.pack(p)
    q, a = QUADROTOR.unpack(p["p_quad"]), ACTUATOR.unpack(p["p_act"])
    m, g, Kt, Kq = q["m1"][0], q["g"][0], q["Kt"][0], a["drag_quadratic"][0]
    theta = sc["controller.tilt_max_deg"] * DEG
    assert theta == 30.0 * DEG
    V = _top_speed(m, g, Kt, Kq, theta)
    assert V == pytest.approx(21.45, abs=0.01) and 15 < V < 25
    assert m * g * math.tan(theta) / 0.1 == pytest.approx(113.2, abs=0.1)
    highway = load_scenario("highway")["controller.tilt_max_deg"] * DEG
    assert _top_speed(m, g, Kt, Kq, highway) == pytest.approx(33.3, abs=0.05)
    xp, F = _cruise_state(p, V, theta)
    np.testing.assert_allclose(_body_acceleration(xp, F, pp), 0.0, atol=1e-12)
    # an equilibrium the body falls back to: slower speeds up, faster slows down
    for dV, sign in ((-1.0, 1), (1.0, -1)):
        xp, F = _cruise_state(p, V + dV, theta)
        assert sign * _body_acceleration(xp, F, pp)[0] > 0.05


def test_quadratic_drag_acts_on_the_airspeed():
    """In a steady wind the body force beyond eq. (2)'s linear drag is -Kq V_air |V_air|
    per body axis, V_air = V1 - R^T v_wind (a level body: R = I), far above the deck."""
    _, p = _params("highway")
    V1, wind = np.array([12.0, -3.0, 0.5]), np.array([-5.0, 2.0, 0.0])
    x1q = QUAD6_STATE.pack(dict(p1=[0.0, 0.0, 500.0], eta1=np.zeros(3), V1=V1,
                                Omega1=np.zeros(3), F=np.full(4, 4.9)))
    xv = VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=0, u2=0, v2=0, r2=0))
    f = np.array(aero_force(x1q, xv, wind, 0.0, p["p_act"], p["p_veh"], p["p_deck"])).ravel()
    Kq = ACTUATOR.unpack(p["p_act"])["drag_quadratic"]
    V_air = V1 - wind
    np.testing.assert_allclose(f[:2], -Kq[:2] * V_air[:2] * np.abs(V_air[:2]), rtol=1e-12)
    # z: the drag and a ground effect 500 m up, (R / 2000)^2 of the thrust at most
    assert f[2] == pytest.approx(-Kq[2] * 0.25, abs=19.6 * (0.127 / 2000) ** 2)


@pytest.mark.parametrize("height", [0.0635, 0.1, 0.2, 0.4, 1.0])
@pytest.mark.parametrize("airspeed", [0.0, 5.0, 13.9])
def test_ground_effect_is_cheeseman_bennett(height, airspeed):
    """The lift over the deck is (k - 1) F_total with k = 1 / (1 - (R / 4z)^2 / (1 + (V /
    v_i)^2)), v_i = sqrt(T_rotor / (2 rho pi R^2)) (Cheeseman and Bennett 1955), the height
    held at R / 2 below it; a level body in a wind along x, the car at rest."""
    _, p = _params("highway")
    a = ACTUATOR.unpack(p["p_act"])
    R, rho = a["rotor_radius"][0], a["air_density"][0]
    F = np.array([4.0, 5.0, 6.0, 5.5])
    deck_z = 1.5                                            # the roof's height, highway's
    x1q = QUAD6_STATE.pack(dict(p1=[0.0, 0.0, deck_z + height], eta1=np.zeros(3),
                                V1=np.zeros(3), Omega1=np.zeros(3), F=F))
    xv = VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=0, u2=0, v2=0, r2=0))
    wind = np.array([-airspeed, 0.0, 0.0])                   # V_air = +airspeed along x
    f = np.array(aero_force(x1q, xv, wind, 0.0, p["p_act"], p["p_veh"], p["p_deck"])).ravel()
    T = F.sum()
    v_i = math.sqrt(T / 4 / (2 * rho * math.pi * R ** 2))
    z = max(height, R / 2)
    k = 1 / (1 - (R / (4 * z)) ** 2 / (1 + (airspeed / v_i) ** 2))
    assert f[2] == pytest.approx((k - 1) * T, rel=1e-9, abs=1e-12)
    if airspeed == 0 and height <= R / 2:
        assert k == pytest.approx(4 / 3)


def test_the_ground_effect_at_the_shipped_touchdown_is_a_few_percent():
    """At the gear's 0.2 m over a still deck, 10 in rotors make 2.6 % more thrust in hover
    (1 / (1 - (0.127 / 0.8)^2)), and 0.5 % at the highway's 13.9 m/s airspeed."""
    _, p = _params("highway")
    a = ACTUATOR.unpack(p["p_act"])
    R, rho = a["rotor_radius"][0], a["air_density"][0]
    assert 1 / (1 - (R / 0.8) ** 2) == pytest.approx(1.026, abs=1e-3)
    v_i = math.sqrt(19.6 / 4 / (2 * rho * math.pi * R ** 2))
    assert v_i == pytest.approx(6.28, abs=0.01)
    k = 1 / (1 - (R / 0.8) ** 2 / (1 + (13.889 / v_i) ** 2))
    assert k == pytest.approx(1.0043, abs=1e-4)


# ---------------------------------------------------------------- cars that drive

def _drive(p, xv0, t_end):
    """The vehicle alone (eq. 4 and the profile), integrated tightly by SciPy."""
    xv, t = VEHICLE_STATE.sym(), ca.SX.sym("t")
    f = ca.Function("f", [t, xv], [vehicle_motion(xv, t, p["p_veh"], p["p_deck"])])
    sol = solve_ivp(lambda tt, x: np.array(f(tt, x)).ravel(), (0.0, t_end), xv0,
                    method="DOP853", rtol=1e-11, atol=1e-11, dense_output=True)
    return sol


def test_highway_100_lane_change_moves_the_car_3_5_m_left():
    """highway_100's lane change (12 to 16 s at 100 km/h): the heading returns to zero,
    the speed stays, the sway stays zero, and the car is displaced by the exact
    u int sin(psi) dt, psi = A T / (2 pi) (1 - cos(2 pi tau)), which is 3.5 m to second
    order in the heading (within 3.5 psi_max^2 / 4)."""
    sc, p = _params("highway_100")
    u0 = sc["initial.velocity2"][0]
    start, T = sc["vehicle.profile_start"][0], sc["vehicle.profile_duration"][0]
    A = DRIVE_PARAMS.unpack(DECK_PARAMS.unpack(p["p_deck"])["drive"])["leg_lane_rate"][0]
    assert A == pytest.approx(2 * math.pi * 3.5 / (u0 * T ** 2), rel=1e-12)
    xv0 = VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=0, u2=u0, v2=0, r2=0))
    sol = _drive(p, xv0, start + T + 2.0)
    end = VEHICLE_STATE.unpack(sol.y[:, -1])
    psi = lambda t: A * T / (2 * math.pi) * (1 - math.cos(2 * math.pi * (t - start) / T))  # noqa: E731
    y_exact = u0 * quad(lambda t: math.sin(psi(t)), start, start + T, epsabs=1e-13)[0]
    assert end["y2"][0] == pytest.approx(y_exact, abs=1e-6)
    psi_max = A * T / math.pi
    assert abs(end["y2"][0] - 3.5) < 3.5 * psi_max ** 2 / 4
    assert end["y2"][0] == pytest.approx(3.5, abs=2e-3)
    assert end["psi2"][0] == pytest.approx(0.0, abs=1e-9)
    assert end["u2"][0] == pytest.approx(u0, abs=1e-7)
    np.testing.assert_allclose(sol.y[4], 0.0, atol=1e-7)            # no sway
    mid = VEHICLE_STATE.unpack(sol.sol(start + T / 4))                # the peak yaw rate
    assert mid["r2"][0] == pytest.approx(A, rel=1e-7)


def test_braking_and_a_turn_follow_the_profile():
    """Highway's car braking by 5 m/s over 4 s from t = 1 s covers u0 T + dv T / 2 in the
    leg; a 30 deg turn over 5 s from t = 6 s ends at that heading at the new speed."""
    sc, p = _params("highway", "vehicle.profile_start=[1.0, 6.0]",
                    "vehicle.profile_duration=[4.0, 5.0]",
                    "vehicle.profile_speed_change=[-5.0, 0.0]",
                    "vehicle.profile_heading_change_deg=[0.0, 30.0]",
                    "vehicle.profile_lane_offset=[0.0, 0.0]")
    u0 = sc["initial.velocity2"][0]
    xv0 = VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=0, u2=u0, v2=0, r2=0))
    sol = _drive(p, xv0, 12.0)
    x = lambda t: VEHICLE_STATE.unpack(sol.sol(t))  # noqa: E731
    assert x(5.0)["x2"][0] - x(1.0)["x2"][0] == pytest.approx(u0 * 4 - 5.0 * 4 / 2, abs=1e-7)
    assert x(5.0)["u2"][0] == pytest.approx(u0 - 5.0, abs=1e-8)
    assert x(3.0)["u2"][0] == pytest.approx(u0 - 2.5, abs=1e-8)        # half-way, by symmetry
    end = x(12.0)
    assert end["psi2"][0] == pytest.approx(30 * DEG, abs=1e-9)
    assert end["u2"][0] == pytest.approx(u0 - 5.0, abs=1e-7)
    assert end["r2"][0] == pytest.approx(0.0, abs=1e-9)


def test_pack_drive_converts_the_offset_at_the_planned_speed():
    """A lane change after a speed change takes the speed the profile plans by its middle."""
    p = DRIVE_PARAMS.unpack(pack_drive([0.0, 10.0], [4.0, 4.0], [-5.0, 0.0], [0.0, 0.0],
                                       [0.0, 3.5], 27.0))
    assert p["leg_lane_rate"][1] == pytest.approx(2 * math.pi * 3.5 / (22.0 * 16.0), rel=1e-12)
    assert p["leg_duration"].tolist() == [4.0, 4.0, 1.0, 1.0]                # idle legs
    with pytest.raises(ValueError, match="leg 2: a lane change needs the vehicle moving"):
        pack_drive([0.0, 10.0], [4.0, 4.0], [-27.0, 0.0], [0.0, 0.0], [0.0, 3.5], 27.0)


@pytest.mark.parametrize("overrides,message", [
    (["vehicle.profile_start=[1.0, 2.0]"],
     "quadland: error: vehicle.profile_duration: must have as many values as "
     "vehicle.profile_start (one per leg of the drive profile)"),
    (["vehicle.profile_duration=[0.0]"], "quadland: error: vehicle.profile_duration"),
    (["vehicle.profile_speed_change=[-20.0]"],
     "quadland: error: vehicle.profile_speed_change: the planned speed falls to -6.11111 m/s "
     "by t = 1 s: the profile drives forward (initial.velocity2 = 13.8889 m/s)"),
    (["vehicle.profile_start=[0.0, 5.0]", "vehicle.profile_duration=[1.0, 4.0]",
      "vehicle.profile_speed_change=[-13.88888888888889, 0.0]",
      "vehicle.profile_heading_change_deg=[0.0, 0.0]", "vehicle.profile_lane_offset=[0.0, 3.5]"],
     "quadland: error: vehicle.profile_lane_offset: leg 2: a lane change needs the vehicle "
     "moving forward, its planned speed is"),
    (["vehicle.profile_start=[0.0, 1.0, 2.0, 3.0, 4.0]"], "quadland: error: vehicle.profile_start"),
])
def test_bad_profiles_are_one_line_and_exit_2(overrides, message, capsys, tmp_path):
    argv = ["simulate", "--scenario", "highway", "--no-plots", "--out", str(tmp_path / "o")]
    for o in overrides:
        argv += ["--set", o]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(message), err
    assert not (tmp_path / "o").exists()


def test_the_law_feeds_forward_the_plants_quadratic_drag():
    """The law's known acceleration with the shipped Kq is the plant's own at zero thrust
    (no ground effect without thrust) and no wind: the relative acceleration of eq. (5)
    under the disturbance aero_force, for a car in highway_100's lane change."""
    sc, p = _params("highway_100")
    rng = np.random.default_rng(7)
    pp = LANDING_PLANT_PARAMS.pack(p)
    Kq = ACTUATOR.unpack(p["p_act"])["drag_quadratic"]
    assert Kq.tolist() == [0.01225] * 3
    for _ in range(5):
        x1q = QUAD6_STATE.pack(dict(p1=rng.normal(0, 2, 3) + [0, 0, 5],
                                    eta1=rng.uniform(-0.6, 0.6, 3), V1=rng.normal(0, 15, 3),
                                    Omega1=rng.normal(0, 0.5, 3), F=np.zeros(4)))
        xv = VEHICLE_STATE.pack(dict(x2=1, y2=2, psi2=0.02, u2=27.7, v2=0.0, r2=0.03))
        t = rng.uniform(12.0, 16.0)                                       # in the lane change
        d_F = np.array(aero_force(x1q, xv, np.zeros(3), t, p["p_act"], p["p_veh"],
                                  p["p_deck"])).ravel()
        a_e, _ = relative6_acceleration(x1q, xv, t, np.zeros(4), np.concatenate([d_F, [0] * 3]),
                                        p["p_quad"], p["p_act"], p["p_veh"], p["p_deck"])
        xp = np.concatenate([x1q, xv, np.zeros(GEAR_STATE.size)])
        m = LANDING_MEASUREMENT.unpack(np.array(measurement_function()(xp, t, pp)).ravel())
        f_g, f_r = (np.array(v).ravel() for v in known_acceleration(
            m["p_e"], m["v_e"], m["eta1"], m["eta2"], m["v2E"], m["a2E"], m["w2E"],
            m["w2E_dot"], p["p_quad"], Kq))
        np.testing.assert_allclose(f_g + f_r, np.array(a_e).ravel(), atol=1e-10)

"""Sensors against hand derivations, noise against closed forms.

The symbolic models (quadland_symbolic.landing.sensors) are checked at chosen states
whose readings are derived by hand (a level hover over a level pad, a
30 degree roll over a flat deck, free fall, ...); the runtime's random parts
(quadland.kinds.landing.sensing) against the closed-form statistics of the processes they
simulate, with tolerances from each estimator's own sampling distribution.
"""

import math

import numpy as np
import pytest
from hand_rotations import R_zyx, Rx, Rz
from reference import NO_AERO
from scipy import stats

from quadland.engine.loop import Clock
from quadland.engine.noise import gauss_markov, gauss_markov_fill, random_walk, sample_times
from quadland.exceptions import ScenarioError
from quadland.kinds.landing.sensing import draw_sensors
from quadland.kinds.landing.sensor_settings import (
    SENSOR_DEFAULTS,
    SETTINGS,
    sensor_params,
    validate_settings,
)
from quadland_symbolic.landing.deck import pack_deck
from quadland_symbolic.landing.gear import contact_params
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR
from quadland_symbolic.landing.sensors import (
    DATALINK_NOISE,
    GNSS_NOISE,
    IMU_NOISE,
    NOISES,
    RANGEFINDER_NOISE,
    SENSOR_NAMES,
    SENSOR_PACKETS,
    SENSOR_PARAMS,
    VISION_NOISE,
    sensor_function,
)
from quadland_symbolic.parameters import QUADROTOR, VEHICLE

M1, G, KT = 2.0, 9.8, np.array([0.1, 0.2, 0.3])
DEG = math.pi / 180






def params(deck_height=1.5, pad_offset=(0.0, 0.0, 0.0), roll=0.0, u2_hold=0.0):
    """Plant parameters: a 2 kg quadrotor, a car, a rolled deck."""
    zeros = np.zeros(3)
    deck = {f"{n}_{w}": zeros for n in ("heave", "roll", "pitch")
            for w in ("amp", "freq", "phase")}
    deck.update(roll_amp=[roll, 0, 0], roll_phase=[math.pi / 2, 0, 0],
                pad_offset=pad_offset, deck_height=deck_height)
    return LANDING_PLANT_PARAMS.pack({
        "p_quad": QUADROTOR.pack(dict(m1=M1, I=[0.025, 0.025, 0.045], Kt=KT,
                                      Kr=[0.001] * 3, g=G, arm=0.25, c=0.05)),
        "p_act": ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=20.0, gear_height=0.2,
                                    rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3, **NO_AERO)),
        "p_veh": VEHICLE.pack(dict(m11=1500, m22=1500, m33=2500, d11=150, d22=1500, d33=2500,
                                   tau=[150 * u2_hold, 0, 0], z2=0)),
        "p_deck": pack_deck(deck),
        **contact_params(),
    })


def state(p1=(0, 0, 5), eta1=(0, 0, 0), V1=(0, 0, 0), Omega1=(0, 0, 0), F=None,
          xv=(0, 0, 0, 0, 0, 0)):
    F = [M1 * G / 4] * 4 if F is None else F
    return LANDING_PLANT_STATE.pack({"x1q": np.concatenate([p1, eta1, V1, Omega1, F]), "xv": xv,
                                     "gear": np.zeros(3)})


def sense(name, xp, pp, noise=None, settings=None, uh=None, w=None, t=0.0):
    f = sensor_function(name)
    noise = np.zeros(NOISES[name].size) if noise is None else noise
    uh = np.full(4, M1 * G / 4) if uh is None else uh
    w = np.zeros(LANDING_DISTURBANCE.size) if w is None else w
    y = np.asarray(f(xp, uh, w, t, pp, sensor_params(settings), noise)).ravel()
    return SENSOR_PACKETS[name].unpack(y)


# ---- vision ----------------------------------------------------------------------------

def test_vision_in_a_level_hover_reads_pad_minus_camera():
    pad = np.array([0.2, -0.1, 0.05])
    xv = (3.0, 1.0, 0.3, 0, 0, 0)
    p2 = np.array([3.0, 1.0, 1.5]) + Rz(0.3) @ pad            # the pad centre, by hand
    p1 = p2 + np.array([0.5, -0.3, 3.0])
    y = sense("vision", state(p1=p1, eta1=(0, 0, 0.7), xv=xv), params(pad_offset=pad))
    np.testing.assert_allclose(y["r_E"], p2 - p1, atol=1e-12)
    assert y["valid"] == 1


def test_vision_rotates_with_the_attitude_estimate_and_scales_its_noise():
    p1 = np.array([0.4, 0.3, 6.5])
    d = np.array([0.0, 0.0, 1.5]) - p1
    e = np.zeros(VISION_NOISE.size)
    e[VISION_NOISE.slice("e_att")] = [0, 0, 0.05]              # a pure yaw error
    y = sense("vision", state(p1=p1), params(), e)
    np.testing.assert_allclose(y["r_E"], Rz(0.05) @ d, atol=1e-12)
    n = np.zeros(VISION_NOISE.size)
    n[VISION_NOISE.slice("n_r")] = [1.0, -2.0, 0.5]
    n[VISION_NOISE.slice("o_r")] = [0.0, 0.3, 0.0]
    s0, k = SENSOR_DEFAULTS["vision"]["sigma0"], SENSOR_DEFAULTS["vision"]["sigma_per_m"]
    y = sense("vision", state(p1=p1), params(), n)
    sigma = s0 + k * np.linalg.norm(d)                         # level, yaw 0: body = E
    np.testing.assert_allclose(y["r_E"], d + sigma * np.array([1, -2, 0.5]) + [0, 0.3, 0],
                               atol=1e-12)


@pytest.mark.parametrize("inside", [True, False])
def test_vision_field_of_view_edge(inside):
    half = SENSOR_DEFAULTS["vision"]["half_angle"]
    angle = half - 1e-6 if inside else half + 1e-6
    h = 4.0
    p1 = np.array([-h * math.tan(angle), 0.0, 1.5 + h])        # the pad at `angle` off -b3
    assert sense("vision", state(p1=p1), params())["valid"] == inside
    # the same edge reached by rolling above the pad: roll phi tilts -b3 by phi
    y = sense("vision", state(p1=(0, 0, 1.5 + h), eta1=(angle, 0, 0)), params())
    assert y["valid"] == inside


@pytest.mark.parametrize("height, valid", [(0.45 - 1e-6, 0), (0.45 + 1e-6, 1),
                                           (12.0 - 1e-6, 1), (12.0 + 1e-6, 0)])
def test_vision_range_edges(height, valid):
    y = sense("vision", state(p1=(0, 0, 1.5 + height)), params())
    assert y["valid"] == valid


def test_vision_second_marker_covers_the_last_decimetres():
    xp, pp = state(p1=(0, 0, 1.5 + 0.3)), params()
    assert sense("vision", xp, pp)["valid"] == 0               # the large marker is lost
    small = {"vision": {"small_range_min": 0.08, "small_range_max": 2.0}}
    assert sense("vision", xp, pp, settings=small)["valid"] == 1
    assert sense("vision", state(p1=(0, 0, 1.5 + 0.05)), pp, settings=small)["valid"] == 0


# ---- rangefinder ------------------------------------------------------------------------

def test_rangefinder_at_30_degrees_roll_over_a_flat_deck():
    h = 1.0                                                    # lateral hit 0.577 m < 0.7 m
    y = sense("rangefinder", state(p1=(0, 0, 1.5 + h), eta1=(30 * DEG, 0, 0)), params())
    assert y["s"] == pytest.approx(h / math.cos(30 * DEG), abs=1e-12)
    np.testing.assert_allclose(y["b3_E"], [0, -math.sin(30 * DEG), math.cos(30 * DEG)],
                               atol=1e-12)
    assert y["valid"] == 1


def test_rangefinder_beyond_the_deck_reads_the_ground():
    z1 = 1.5 + 3.0                                             # lateral hit 1.73 m > 0.7 m
    y = sense("rangefinder", state(p1=(0, 0, z1), eta1=(30 * DEG, 0, 0)), params())
    assert y["s"] == pytest.approx(z1 / math.cos(30 * DEG), abs=1e-12)


def test_rangefinder_over_a_rolled_deck_reads_the_height_above_the_pad():
    pp = params(deck_height=4.0, pad_offset=(0, 0, 2.0), roll=10 * DEG)
    p2 = np.array([0, 0, 4.0]) + Rx(10 * DEG) @ [0, 0, 2.0]
    y = sense("rangefinder", state(p1=p2 + [0, 0, 2.5]), pp)
    assert y["s"] == pytest.approx(2.5, abs=1e-12)             # the plane contains p2


def test_rangefinder_validity_and_no_return():
    r_max = SENSOR_DEFAULTS["rangefinder"]["range_max"]
    for d, valid in ((r_max - 1e-6, 1), (r_max + 1e-6, 0)):
        assert sense("rangefinder", state(p1=(0, 0, 1.5 + d)), params())["valid"] == valid
    y = sense("rangefinder", state(p1=(0, 0, 5), eta1=(100 * DEG, 0, 0)), params())
    assert (y["s"], y["valid"]) == (0.0, 0.0)                  # looking above the horizon
    n = np.zeros(RANGEFINDER_NOISE.size)
    n[RANGEFINDER_NOISE.slice("n_s")] = 2.0
    y = sense("rangefinder", state(p1=(0, 0, 3.5)), params(), n)
    rf = SENSOR_DEFAULTS["rangefinder"]
    assert y["s"] == pytest.approx(2.0 + 2.0 * (rf["sigma0"] + rf["sigma_per_m"] * 2.0))


# ---- imu --------------------------------------------------------------------------------

def test_accelerometer_reads_g_in_a_level_hover_and_zero_in_free_fall():
    y = sense("imu", state(eta1=(0, 0, 1.1)), params())
    np.testing.assert_allclose(y["f_b"], [0, 0, G], atol=1e-12)
    y = sense("imu", state(F=[0, 0, 0, 0]), params(), uh=np.zeros(4))
    np.testing.assert_allclose(y["f_b"], 0, atol=1e-12)


def test_accelerometer_reads_every_force_but_gravity_over_the_mass():
    """Eq. (2) by hand: f_b = (F_total e3 - Kt (V1 - R^T v_wind) + d_F) / m1, the
    rotor states' thrust (not the commands'), at a rolling, pitching, moving state."""
    eta1, V1, Om = np.array([0.2, -0.3, 0.8]), np.array([1.0, -0.5, 0.3]), [0.4, -0.2, 0.9]
    F = np.array([4.0, 5.5, 6.0, 3.5])
    v_wind, d_F = np.array([2.0, -1.0, 0.5]), np.array([0.3, 0.1, -0.2])
    w = LANDING_DISTURBANCE.pack({"v_wind": v_wind, "d_F": d_F, "d_M": [0.01, 0.02, 0.0]})
    y = sense("imu", state(eta1=eta1, V1=V1, Omega1=Om, F=F), params(), w=w,
              uh=np.array([9.0, 0.0, 1.0, 7.0]))
    expected = (np.array([0, 0, F.sum()]) - KT * (V1 - R_zyx(eta1).T @ v_wind) + d_F) / M1
    np.testing.assert_allclose(y["f_b"], expected, atol=1e-12)


def test_gyro_and_attitude_estimate_read_truth_plus_their_errors():
    eta1, Om = np.array([0.1, 0.2, -0.4]), np.array([0.3, -0.1, 0.05])
    n = IMU_NOISE.pack({"e_att": [0.01, -0.02, 0.03], "b_a": [0.1, 0.2, 0.3],
                        "n_a": [0.01, 0.0, -0.01], "b_g": [1e-3, 2e-3, 3e-3],
                        "n_g": [1e-4, 0, 0]})
    y0 = sense("imu", state(eta1=eta1, Omega1=Om), params())
    y = sense("imu", state(eta1=eta1, Omega1=Om), params(), n)
    np.testing.assert_allclose(y0["omega"], Om, atol=1e-15)
    np.testing.assert_allclose(y["omega"], Om + [1.1e-3, 2e-3, 3e-3], atol=1e-15)
    np.testing.assert_allclose(y["eta_hat"], eta1 + [0.01, -0.02, 0.03], atol=1e-15)
    np.testing.assert_allclose(y["f_b"] - y0["f_b"], [0.11, 0.2, 0.29], atol=1e-12)


# ---- gnss and datalink ------------------------------------------------------------------

def test_gnss_differences_the_receivers_and_reads_both_velocities():
    u2, psi2 = 13.0, 0.4
    xv = (10.0, -4.0, psi2, u2, 0, 0)
    p1, V1 = np.array([7.0, -2.0, 6.0]), np.array([2.0, 0.5, -0.3])
    n = GNSS_NOISE.pack({"e_q": [1.0, -2.0, 3.0], "e_t": [0.5, 0.5, -1.0],
                         "n_v1": [0.01, 0.02, 0.03], "n_vt": [-0.01, 0, 0]})
    y = sense("gnss", state(p1=p1, eta1=(0, 0, math.pi / 2), V1=V1, xv=xv), params(), n)
    p2 = np.array([10.0, -4.0, 1.5])
    np.testing.assert_allclose(y["rel"], (p2 + [0.5, 0.5, -1]) - (p1 + [1, -2, 3]),
                               atol=1e-12)
    np.testing.assert_allclose(y["v1"], [-0.5, 2.0, -0.3] + np.array([0.01, 0.02, 0.03]),
                               atol=1e-12)                     # yaw 90 deg: [-v, u, w]
    np.testing.assert_allclose(y["vt"], [u2 * math.cos(psi2) - 0.01, u2 * math.sin(psi2), 0],
                               atol=1e-12)


def test_datalink_broadcasts_a_cruising_car_s_motion_plus_noise():
    u2, psi2 = 13.0, -0.2
    xv = (0, 0, psi2, u2, 0, 0)
    pp = params(u2_hold=u2)                                    # tau_x = d11 u2: no surge
    y = sense("datalink", state(xv=xv), pp)
    np.testing.assert_allclose(y["eta2"], [0, 0, psi2], atol=1e-12)
    np.testing.assert_allclose(y["v2E"], [u2 * math.cos(psi2), u2 * math.sin(psi2), 0],
                               atol=1e-12)
    for f in ("a2E", "w2E", "w2E_dot"):
        np.testing.assert_allclose(y[f], 0, atol=1e-12)
    n = np.arange(1, DATALINK_NOISE.size + 1) * 1e-3
    y_n = sense("datalink", state(xv=xv), pp, n)
    packet = SENSOR_PACKETS["datalink"]
    np.testing.assert_allclose(packet.pack(y_n) - packet.pack(y), n, atol=1e-12)


# ---- the runtime: processes against closed forms ----------------------------------------

def _acf(x, k):
    x = x - x.mean()
    return float(np.dot(x[:-k], x[k:]) / np.dot(x, x))


def test_gauss_markov_variance_and_autocorrelation_against_closed_form():
    """AR(1) with a = 0.5 on 100,000 samples: the sample variance's standard
    error is sigma^2 sqrt(2 (1 + a^2) / ((1 - a^2) N)) and Bartlett's formula
    gives the autocorrelation estimate's; each is held to 4.5 of them."""
    N, tau, sigma = 100_000, 1.0, np.array([2.0, 0.3])
    dt = tau * math.log(2.0)                                   # a = exp(-dt / tau) = 0.5
    a = 0.5
    t = dt * np.arange(N)
    x = gauss_markov(t, sigma, tau, np.random.default_rng(11).standard_normal((N, 2)))
    se_var = math.sqrt(2 * (1 + a * a) / ((1 - a * a) * N))
    for col in range(2):
        assert abs(np.var(x[:, col]) / sigma[col] ** 2 - 1) < 4.5 * se_var
        for k in (1, 2, 4):
            bartlett = ((1 + a * a) * (1 - a ** (2 * k)) / (1 - a * a) - 2 * k * a ** (2 * k)) / N
            assert abs(_acf(x[:, col], k) - a ** k) < 4.5 * math.sqrt(bartlett)


def test_gauss_markov_limits_white_and_constant():
    n = np.random.default_rng(2).standard_normal((5, 2))
    x = gauss_markov(np.arange(5.0), [1.5, 1.5], [0.0, math.inf], n)
    np.testing.assert_allclose(x[:, 0], 1.5 * n[:, 0])         # tau = 0: white
    np.testing.assert_allclose(x[:, 1], 1.5 * n[0, 1])         # tau = inf: constant


def test_filled_gauss_markov_has_the_process_s_joint_covariance():
    """20,000 independent columns: values at 0 and 1 s, then 0.3, 0.6 and 1.7 s
    filled in; the empirical covariance against sigma^2 exp(-|ti - tj| / tau),
    each entry within 4.5 standard errors sigma^2 sqrt((1 + rho^2) / M)."""
    M, sigma, tau = 20_000, 1.3, 0.8
    rng = np.random.default_rng(5)
    known_t, new_t = np.array([0.0, 1.0]), np.array([0.3, 0.6, 1.7])
    known = gauss_markov(known_t, sigma, tau, rng.standard_normal((2, M)))
    new = gauss_markov_fill(known_t, known, new_t, sigma, tau, rng.standard_normal((3, M)))
    t = np.concatenate([known_t, new_t])
    X = np.vstack([known, new])
    C = X @ X.T / M
    rho = np.exp(-np.abs(t[:, None] - t[None, :]) / tau)
    se = sigma ** 2 * np.sqrt((1 + rho ** 2) / M)
    assert np.all(np.abs(C - sigma ** 2 * rho) < 4.5 * se)


def test_random_walk_variance_grows_linearly():
    M, q, b0 = 20_000, 0.2, 0.5
    rng = np.random.default_rng(8)
    t = np.linspace(0.0, 9.0, 31)
    start = b0 * rng.standard_normal(M)
    b = random_walk(t, start, q, rng.standard_normal((31, M)))
    var = b0 ** 2 + q ** 2 * t[-1]                             # 0.25 + 0.36
    assert abs(np.var(b[-1]) / var - 1) < 4.5 * math.sqrt(2 / M)


def test_imu_white_noise_is_density_times_root_rate():
    s = draw_sensors({"imu": {"rate_hz": 400.0}}, 50.0, seed=3)["imu"]
    d = SENSOR_DEFAULTS["imu"]
    n = len(s.times) * 3
    for field, key in (("n_a", "accel_noise_density"), ("n_g", "gyro_noise_density")):
        ratio = np.var(s.noise_of(field)) / (d[key] ** 2 * 400.0)
        assert abs(ratio - 1) < 4.5 * math.sqrt(2 / n)


# ---- the runtime: times, delivery, seeds ------------------------------------------------

def test_sample_times_and_arrivals():
    s = draw_sensors({"gnss": {"phase": 0.05}}, 2.0, seed=1)["gnss"]
    np.testing.assert_allclose(s.times, 0.05 + 0.2 * np.arange(10))
    np.testing.assert_allclose(s.arrival, s.times + SENSOR_DEFAULTS["gnss"]["latency"])
    # the control clock's rule: ticks below the final time, none at it
    assert len(sample_times(25.0, 40.0)) == 1000
    np.testing.assert_array_equal(sample_times(250.0, 2.0),
                                  Clock(250.0, 0.0, 2.0, closing=False).times())


def test_dropout_and_outlier_rates_lie_in_their_binomial_intervals():
    p, q = 0.07, 0.02
    on_one_grid = {"imu": {"rate_hz": 30.0}, "rangefinder": {"rate_hz": 30.0}}
    s = draw_sensors({**on_one_grid, "vision": {"dropout": p, "outlier_rate": q,
                                                "rate_hz": 30.0}}, 2000.0, seed=9)["vision"]
    n = len(s.times)
    lost = int(np.sum(~s.delivered))
    outliers = int(np.sum(np.any(s.noise_of("o_r") != 0, axis=1)))
    for count, rate in ((lost, p), (outliers, q)):
        lo, hi = stats.binom.ppf(1e-6, n, rate), stats.binom.isf(1e-6, n, rate)
        assert lo <= count <= hi


def test_same_seed_same_draws_other_seed_other_draws():
    a, b, c = (draw_sensors(None, 5.0, seed=s) for s in (4, 4, 5))
    for name in SENSOR_NAMES:
        np.testing.assert_array_equal(a[name].noise, b[name].noise)
        np.testing.assert_array_equal(a[name].delivered, b[name].delivered)
        assert not np.array_equal(a[name].noise, c[name].noise)


def test_one_sensor_s_settings_leave_the_others_draws_alone():
    base = draw_sensors(None, 5.0, seed=12)
    other = draw_sensors({"vision": {"dropout": 0.3, "sigma0": 0.5, "rate_hz": 12.5,
                                     "outlier_rate": 0.2},
                          "gnss": {"position_sigma": [5, 5, 5]}}, 5.0, seed=12)
    for name in ("imu", "rangefinder", "datalink"):
        np.testing.assert_array_equal(base[name].noise, other[name].noise)
        np.testing.assert_array_equal(base[name].delivered, other[name].delivered)
    np.testing.assert_array_equal(base["gnss"].delivered, other["gnss"].delivered)


def test_attitude_error_is_one_process_shared_at_equal_times():
    s = draw_sensors(None, 3.0, seed=21)
    imu_t, imu_e = s["imu"].times, s["imu"].noise_of("e_att")
    for name in ("vision", "rangefinder"):
        k = np.rint(s[name].times * 250.0).astype(int)
        np.testing.assert_allclose(imu_t[k], s[name].times, atol=1e-12)
        np.testing.assert_array_equal(s[name].noise_of("e_att"), imu_e[k])
    off = draw_sensors({"vision": {"phase": 0.001}}, 3.0, seed=21)
    np.testing.assert_array_equal(off["imu"].noise, s["imu"].noise)
    # 1 ms after an IMU sample: two white draws and at most 1 ms of drift apart,
    # std sqrt(2 w^2 + sigma^2 (1 - exp(-2 dt / tau))) per axis; held to 6 of them
    d = off["vision"].noise_of("e_att") - imu_e[np.rint(off["vision"].times * 250 - 0.25)
                                               .astype(int)]
    imu = SENSOR_DEFAULTS["imu"]
    sd = np.sqrt(2 * imu["attitude_white_sigma"] ** 2 + np.square(imu["attitude_sigma"])
                 * (1 - np.exp(-2e-3 / np.asarray(imu["attitude_tau"]))))
    assert np.all(np.abs(d) < 6 * sd)


def test_all_random_parts_off_gives_exact_truth():
    s = draw_sensors({"vision": {"dropout": 0.5}}, 2.0, seed=3, random=False)
    for name in SENSOR_NAMES:
        assert np.all(s[name].noise == 0) and np.all(s[name].delivered)
    xp, pp = state(p1=(0.3, -0.2, 5.0)), params()
    y = sense("vision", xp, pp, s["vision"].noise[0])
    np.testing.assert_array_equal(y["r_E"], np.array([0, 0, 1.5]) - [0.3, -0.2, 5.0])


# ---- settings ---------------------------------------------------------------------------

def test_defaults_meet_the_issue_s_minimums_and_their_own_ranges():
    v, g, d = (SENSOR_DEFAULTS[n] for n in ("vision", "gnss", "datalink"))
    assert v["latency"] >= 0.05 and v["rate_hz"] <= 30 and v["dropout"] >= 0.05
    assert g["latency"] >= 0.1 and g["rate_hz"] <= 10
    assert d["latency"] >= 0.05 and d["rate_hz"] <= 20 and d["dropout"] >= 0.02
    for name in SENSOR_NAMES:
        assert set(SENSOR_DEFAULTS[name]) == set(SETTINGS[name])
        validate_settings(name, dict(SENSOR_DEFAULTS[name]))


@pytest.mark.parametrize("name, values, words", [
    ("vision", {"latncy": 0.1}, "sensors.vision.latncy: unknown key"),
    ("gnss", {"dropout": 1.5}, "sensors.gnss.dropout: must be in [0, 1]"),
    ("imu", {"attitude_tau": [1.0, 2.0]}, "sensors.imu.attitude_tau: must be a list of 3"),
    ("datalink", {"rate_hz": True}, "sensors.datalink.rate_hz: must be a finite number"),
    ("rangefinder", {"range_min": 8.0}, "sensors.rangefinder.range_min: must not exceed"),
    ("sonar", {}, "sensors.sonar: unknown sensor"),
])
def test_bad_settings_name_their_key(name, values, words):
    with pytest.raises(ScenarioError, match=words.replace("[", r"\[").replace("]", r"\]")):
        validate_settings(name, values)


def test_sensor_params_carry_the_settings():
    p = SENSOR_PARAMS.unpack(sensor_params({"vision": {"half_angle": 0.4},
                                            "rangefinder": {"deck_half_width": 2.0}}))
    assert p["vision_half_angle"] == 0.4 and p["deck_half_width"] == 2.0
    assert p["rangefinder_range_max"] == SENSOR_DEFAULTS["rangefinder"]["range_max"]


# ---- the scenario switch sensors.random --------------------------------------------------

def test_scenario_switch_random_off_samples_on_time_with_zero_draws():
    """sensors.random = false: each sensor samples every control_rate / rate_hz ticks from
    its phase, every packet is kept, every noise entry is zero, and the filter starts at
    the true relative motion; true (the shipped value) draws noise and loses packets."""
    import quadland
    from quadland.kinds.landing.sensed import handover, tick_table
    from quadland.kinds.landing.values import landing_values
    from quadland_symbolic.landing.navigation import NAV
    from quadland_symbolic.landing.sensed_loop import SENSED_TICK

    off = quadland.load_scenario("highway", ["sensors.random=false"])
    n = 2500                                       # 10 s of ticks at 250 Hz
    N = tick_table(off, n)
    every = {"imu": 1, "vision": 10, "gnss": 50, "rangefinder": 2, "datalink": 25}  # 250 / rate
    for name, k in every.items():
        sampled = N[:, SENSED_TICK.index(f"{name}_sampled")]
        np.testing.assert_array_equal(sampled, (np.arange(n) % k == 0).astype(float))
        np.testing.assert_array_equal(N[:, SENSED_TICK.index(f"{name}_kept")], sampled)
        assert not np.any(N[:, SENSED_TICK.slice(f"{name}_noise")])
    x0, P0, _ = handover(off, landing_values(off))
    init = off.data["initial"]
    truth = np.array([*init["position1"], init["z1"]]) - np.array(
        [*init["position2"], off.data["deck"]["height"]])
    np.testing.assert_allclose(x0[NAV.slice("p_r")], truth - off.data["deck"]["pad_offset"],
                               atol=1e-12)
    # every initial variance positive but the tilt bias' vertical one (none, by its model)
    tilt_z = NAV.slice("a_tilt").start + 2
    assert not np.any(x0[NAV.slice("b")]) and np.all(np.delete(P0, tilt_z) > 0)
    assert P0[tilt_z] == 0
    on = quadland.load_scenario("highway")
    N_on = tick_table(on, n)
    vision = SENSED_TICK.index("vision_sampled"), SENSED_TICK.index("vision_kept")
    assert np.any(N_on[:, vision[0]] > N_on[:, vision[1]])          # a packet lost
    assert np.any(N_on[:, SENSED_TICK.slice("vision_noise")])
    x0_on, _, _ = handover(on, landing_values(on))
    assert np.any(x0_on[NAV.slice("p_r")] != x0[NAV.slice("p_r")])


def test_rtk_receivers_scale_the_gnss_position_errors_to_the_rtk_fix():
    """sensors.gnss.rtk = true: the same seeded draws, each receiver's Gauss-Markov error
    scaled per axis from the standard receiver's sigma to the RTK fix's (the process is
    linear in its sigma); the rest of the GNSS draws unchanged."""
    from quadland.kinds.landing.sensed import sensor_settings
    from quadland.kinds.landing.sensor_settings import GNSS_RTK
    from quadland.scenario import load_scenario

    std, rtk = (sensor_settings(load_scenario("highway", [f"sensors.gnss.rtk={v}"]))
                for v in ("false", "true"))
    a, b = (draw_sensors(s, 10.0, 7)["gnss"] for s in (std, rtk))
    ratio = np.asarray(GNSS_RTK["position_sigma"]) / np.asarray(std["gnss"]["position_sigma"])
    layout = NOISES["gnss"]
    for name in ("e_q", "e_t"):
        np.testing.assert_allclose(b.noise[:, layout.slice(name)],
                                   a.noise[:, layout.slice(name)] * ratio, rtol=1e-12)
    for name in ("n_v1", "n_vt"):
        np.testing.assert_array_equal(b.noise[:, layout.slice(name)],
                                      a.noise[:, layout.slice(name)])
    with pytest.raises(ScenarioError, match="sensors.gnss.rtk: expected true or false"):
        load_scenario("highway", ["sensors.gnss.rtk=1"])

"""Sensitivity peaks and sensor-side delay margins against closed forms and python-control."""

import math

import control
import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from quadland.analysis import allmargin
from quadland.analysis.sensitivity import group_delay_margin, sensitivity_peaks
from quadland.margins import margin_report
from quadland.scenario import load_scenario

# ---------------------------------------------------------------- closed forms


@pytest.mark.parametrize("k, a", [(3.0, 2.0), (5.0, 4.0), (1.5, 1.0)])
def test_first_order_loop_peaks_at_zero_frequency(k, a):
    """L = k/(s - a), k > a: S = (s - a)/(s - a + k), |S|^2 = (w^2 + a^2)/(w^2 + (k - a)^2),
    largest at w = 0 when k < 2a: Ms = a/(k - a); T = k/(s - a + k), Mt = k/(k - a) at 0."""
    (p,), multi = sensitivity_peaks(control.tf([k], [1, -a]))
    assert p.ms.value == pytest.approx(a / (k - a), rel=1e-12)
    assert p.mt.value == pytest.approx(k / (k - a), rel=1e-12)
    assert p.ms.frequency == 0.0 and p.mt.frequency == 0.0
    assert multi.ms.value == pytest.approx(p.ms.value, rel=1e-12)


@pytest.mark.parametrize("k, a", [(4.0, 0.0), (2.0, 1.0)])
def test_peaks_at_the_ends_of_the_axis(k, a):
    """L = k/(s + a): |S| = |jw + a|/|jw + a + k| rises to 1 as w -> inf; |T| = k/|jw + a + k|
    is largest at w = 0, k/(k + a) (1 for the integrator, whose L(0) is not defined)."""
    (p,), _ = sensitivity_peaks(control.tf([k], [1, a]))
    assert p.ms.value == pytest.approx(1.0, rel=1e-12) and p.ms.frequency == math.inf
    assert p.mt.value == pytest.approx(k / (k + a), rel=1e-12) and p.mt.frequency == 0.0


@pytest.mark.parametrize("zeta", [0.2, 0.35, 0.5])
def test_second_order_resonance(zeta):
    """L = wn^2/(s (s + 2 zeta wn)): T is the standard second-order system,
    Mt = 1/(2 zeta sqrt(1 - zeta^2)) at wn sqrt(1 - 2 zeta^2)."""
    wn = 3.0
    (p,), _ = sensitivity_peaks(control.tf([wn ** 2], [1, 2 * zeta * wn, 0]))
    assert p.mt.value == pytest.approx(1 / (2 * zeta * math.sqrt(1 - zeta ** 2)), rel=1e-9)
    assert p.mt.frequency == pytest.approx(wn * math.sqrt(1 - 2 * zeta ** 2), rel=1e-4)


def test_ms_is_the_inverse_distance_to_minus_one():
    """1/Ms = min_w |1 + L(jw)|: on L = 1/(s(s+1)(s+2)) a dense independent grid."""
    L = control.tf([1], [1, 3, 2, 0])
    (p,), _ = sensitivity_peaks(L)
    w = np.linspace(0.01, 5, 400001)
    dist = np.abs(1 + 1 / (1j * w * (1j * w + 1) * (1j * w + 2)))
    assert 1 / p.ms.value == pytest.approx(dist.min(), rel=1e-9)
    assert p.ms.frequency == pytest.approx(w[np.argmin(dist)], abs=2e-5)


def test_unstable_loop_has_unbounded_peaks():
    (p,), multi = sensitivity_peaks(control.tf([1], [1, -2]))     # closed pole at +1
    assert math.isinf(p.ms.value) and p.ms.frequency is None and math.isinf(multi.mt.value)


def test_diagonal_loop_multiloop_is_the_worst_channel():
    """A diagonal L is normal: sigma_max(S) = max_i |S_ii| at every frequency."""
    L = control.append(control.ss(control.tf([1], [1, 3, 2, 0])),
                       control.ss(control.tf([9], [1, 1.2, 0])))
    per, multi = sensitivity_peaks(L)
    assert multi.ms.value == pytest.approx(max(p.ms.value for p in per), rel=1e-9)
    assert multi.mt.value == pytest.approx(max(p.mt.value for p in per), rel=1e-9)


def test_single_channel_delay_margin_closed_form():
    """L = k/(s + a), k > a: |L| = 1 at wc = sqrt(k^2 - a^2), PM = 180 - atan(wc/a)."""
    k, a = 5.0, 3.0
    wc = math.sqrt(k * k - a * a)
    dm = group_delay_margin(control.tf([k], [1, a]), [0])
    assert dm.frequency == pytest.approx(wc, rel=1e-10)
    assert dm.delay_margin == pytest.approx((math.pi - math.atan(wc / a)) / wc, rel=1e-10)
    assert dm.delay_to(45.0) == pytest.approx((math.pi * 3 / 4 - math.atan(wc / a)) / wc,
                                              rel=1e-10)


def _pd_loop(kp, kd):
    """A double integrator measured in position and velocity, u = -kp y1 - kd y2,
    broken at the measurements: L_o = P K, 2 x 2."""
    P = control.ss([[0, 1], [0, 0]], [[0], [1]], np.eye(2), np.zeros((2, 1)))
    K = control.ss([], [], [], [[kp, kd]])
    return P * K


def test_a_sensor_s_delay_margin_with_the_others_closed():
    """Only the position delayed, the velocity closed: L_1 = kp/(s (s + kd)), |L_1| = 1 at
    w^2 = (sqrt(kd^4 + 4 kp^2) - kd^2)/2, PM = atan(kd/w), tau = PM/w."""
    kp, kd = 4.0, 1.5
    w = math.sqrt((math.sqrt(kd ** 4 + 4 * kp ** 2) - kd ** 2) / 2)
    dm = group_delay_margin(_pd_loop(kp, kd), [0])
    assert dm.frequency == pytest.approx(w, rel=1e-10)
    assert dm.phase_margin == pytest.approx(math.degrees(math.atan(kd / w)), rel=1e-10)
    assert dm.delay_margin == pytest.approx(math.atan(kd / w) / w, rel=1e-10)


def test_every_measurement_delayed_is_the_input_delay():
    """Both outputs delayed alike is the same delay at the input: L_i = (kd s + kp)/s^2,
    |L_i| = 1 at w^4 = kd^2 w^2 + kp^2, PM = atan(kd w / kp)."""
    kp, kd = 4.0, 1.5
    w = math.sqrt((kd ** 2 + math.sqrt(kd ** 4 + 4 * kp ** 2)) / 2)
    dm = group_delay_margin(_pd_loop(kp, kd), [0, 1])
    assert dm.frequency == pytest.approx(w, rel=1e-10)
    assert dm.delay_margin == pytest.approx(math.atan(kd * w / kp) / w, rel=1e-10)


def test_group_delay_margin_refuses_a_bad_group():
    with pytest.raises(ValueError, match="channels"):
        group_delay_margin(_pd_loop(1.0, 1.0), [2])


# ---------------------------------------------------------------- the landing loop


@pytest.fixture(scope="module")
def highway():
    with threadpool_limits(1):
        return margin_report(load_scenario("highway"))


def _dense(resp_sys, omega, dt=0.0):
    """sigma_max of S and T from python-control's own frequency response."""
    m = resp_sys.ninputs
    S = control.feedback(control.ss([], [], [], np.eye(m), dt=dt or 0), resp_sys)
    fr = control.frequency_response(S, omega)
    G = np.moveaxis(np.asarray(fr.complex).reshape(m, m, -1), -1, 0)
    return (np.linalg.norm(G, 2, axis=(-2, -1)), np.linalg.norm(np.eye(m) - G, 2, axis=(-2, -1)),
            G)


@pytest.mark.parametrize("section", ["continuous", "sampled"])
def test_landing_peaks_agree_with_python_control(highway, section):
    """python-control's S = feedback(I, L) on the same models: at the reported frequencies
    its sigma_max and |S_ii| are the reported peaks, and on a dense grid never above them."""
    models = highway.models if section == "continuous" else highway.sampled_models
    rep = getattr(highway, section).sensitivity
    L = models.loop_input
    hi = math.pi * 250 if section == "sampled" else 1e3
    dense = np.logspace(-2, math.log10(hi * (1 - 1e-9)), 4000)
    sS, sT, G = _dense(L, dense, L.dt)
    assert sS.max() <= rep.multiloop.ms.value * (1 + 1e-9)
    assert sT.max() <= rep.multiloop.mt.value * (1 + 1e-9)
    assert sS.max() >= rep.multiloop.ms.value * (1 - 1e-3)
    sS_at = _dense(L, [rep.multiloop.ms.frequency], L.dt)[0]
    sT_at = _dense(L, [rep.multiloop.mt.frequency], L.dt)[1]
    assert sS_at[0] == pytest.approx(rep.multiloop.ms.value, rel=1e-9)
    assert sT_at[0] == pytest.approx(rep.multiloop.mt.value, rel=1e-9)
    for i, (name, p) in enumerate(rep.loops):
        assert np.abs(G[:, i, i]).max() <= p.ms.value * (1 + 1e-9), name
        assert np.abs(1 - G[:, i, i]).max() <= p.mt.value * (1 + 1e-9), name
        _, _, Gi = _dense(L, [p.ms.frequency], L.dt)
        assert abs(Gi[0, i, i]) == pytest.approx(p.ms.value, rel=1e-9), name
    # a loop's Ms bounds its disk margin: alpha = 1/max|S - 1/2| >= 1/(Ms + 1/2)
    for (name, p), lm in zip(rep.loops, getattr(highway, section).loops, strict=True):
        assert lm.disk.disk_margin >= 1 / (p.ms.value + 0.5) * (1 - 1e-9), name


def _closed_with_delay(L, channels, tau, order=10):
    """Poles of the loop L (negative feedback) with a Pade delay on ``channels``."""
    m = L.ninputs
    num, den = control.pade(tau, order)
    blocks = [control.ss(control.tf(num, den)) if i in channels else control.ss([], [], [], 1)
              for i in range(m)]
    D = control.append(*blocks)
    loop = D * L
    return control.feedback(control.ss([], [], [], np.eye(m)), loop).poles()


@pytest.mark.parametrize("sensor", ["imu", "gnss", "vision"])
def test_landing_sensor_delay_margin_is_where_pade_delays_destabilize(highway, sensor):
    """The continuous loop with a 10th-order Pade delay on the sensor's outputs (python-control's
    own interconnection): stable 1 % below the reported delay margin, unstable 1 % above."""
    s = {m.sensor: m for m in highway.continuous.sensors}[sensor]
    L = highway.models.loop_output
    channels = [list(L.input_labels).index(o) for o in s.outputs]
    below = _closed_with_delay(L, channels, 0.99 * s.delay_margin_s)
    above = _closed_with_delay(L, channels, 1.01 * s.delay_margin_s)
    assert below.real.max() < 0
    assert above.real.max() > 0
    crossing = above[np.argmax(above.real)]
    assert abs(crossing.imag) == pytest.approx(s.frequency, rel=0.02)


def test_landing_sensor_margins_are_consistent(highway):
    """One output alone is the classical delay margin at the plant output; the datalink
    feeds no loop at hover; every measurement delayed alike is a delay common to every input,
    near the weakest loop's own delay margin: the loops are nearly decoupled (with issue 18's
    drag and ground effect they differ by 1.02e-3 relative, 0.7e-3 before; a coupled loop
    would differ by tens of per cent), hence 2e-3."""
    for section, models in (("continuous", highway.models), ("sampled", highway.sampled_models)):
        sensors = {m.sensor: m for m in getattr(highway, section).sensors}
        rng = sensors["rangefinder"]
        assert rng.outputs == ("z_e",)
        classical = allmargin(models.loop_output)[2]
        assert rng.delay_margin_s == pytest.approx(min(classical.delay_margin), rel=1e-9)
        assert math.isinf(sensors["datalink"].delay_margin_s)
        assert sensors["imu"].outputs == ("phi1", "theta1", "psi1", "p1", "q1", "r1")
        assert sensors["gnss"].delay_margin_s <= sensors["vision"].delay_margin_s
        everything = group_delay_margin(models.loop_output, range(12))
        loops = getattr(highway, section).loops
        assert everything.delay_margin == pytest.approx(min(m.delay_margin_s for m in loops),
                                                        rel=2e-3)


@pytest.mark.parametrize("sensor", ["imu", pytest.param("gnss", marks=pytest.mark.xfail(
    strict=True, reason="with the disturbance observer the GNSS group's loop has an "
    "eigenvalue of modulus 0.984 at 1.1e-5 rad/s (0.0093 without): the observer's "
    "differentiate-and-integrate of the velocity is a unit gain at low frequency; the "
    "premise below does not hold there, not analysed further (docs/landing.md, 'The "
    "disturbance observer')"))])
def test_no_sensor_crossing_where_the_return_difference_is_unresolved(highway, sensor):
    """Below 1e-2 rad/s the integral action makes ``I + L`` ill-conditioned (1e21 at
    3e-5 rad/s), and inverting it gave dozens of rounding-noise "crossings" (the IMU's
    latency to 45 deg printed as -9.65e4 s). python-control closes the other channels in
    the state space instead (no inversion of ``I + L``): there the group's loop has no
    eigenvalue within a factor of 20 of the unit circle on 1e-6..1e-2 rad/s, so no
    crossing may be reported there, and the latency to the requirement is the one the
    reported crossings give by hand."""
    models = highway.models
    L = models.loop_output
    outputs = list(L.input_labels)
    group = [outputs.index(f) for f in {m.sensor: m for m in highway.continuous.sensors}[
        sensor].outputs]
    others_closed = control.feedback(L, np.diag([0.0 if i in group else 1.0
                                                 for i in range(L.ninputs)]))
    w = np.logspace(-6, -2, 200)
    resp = others_closed(1j * w)[np.ix_(group, group)]
    moduli = np.abs(np.linalg.eigvals(np.moveaxis(resp, -1, 0)))
    assert np.all(np.abs(np.log(moduli)) > math.log(20.0))
    dm = group_delay_margin(L, group)
    assert dm.unresolved > 0
    assert min(c[0] for c in dm.crossings) > 1.0
    by_hand = min(math.radians(pm % 360.0 - 45.0) / wc for wc, pm, _ in dm.crossings)
    margin = {m.sensor: m for m in highway.continuous.sensors}[sensor]
    assert margin.latency_to_requirement_s == pytest.approx(by_hand, rel=1e-12)
    assert abs(margin.latency_to_requirement_s) < 1.0


@pytest.mark.parametrize("section", ["continuous", "sampled"])
def test_landing_peaks_bound_the_classical_margins(highway, section):
    """|1 + l_i| >= 1/Ms_i and |l_i / (1 + l_i)| <= Mt_i everywhere: GM up >= Ms/(Ms - 1)
    and >= 1 + 1/Mt, GM down <= Ms/(Ms + 1), PM >= 2 asin(1/(2 Ms)) and 2 asin(1/(2 Mt))."""
    def db(ratio):
        return 20 * math.log10(ratio)

    sec = getattr(highway, section)
    for lm in sec.loops:
        p = sec.sensitivity.loop(lm.name)
        ms, mt = p.ms.value, p.mt.value
        assert lm.gain_margin_up_db >= db(ms / (ms - 1)) and lm.gain_margin_up_db >= db(1 + 1 / mt)
        assert lm.gain_margin_down_db <= db(ms / (ms + 1))
        pm = math.radians(lm.phase_margin_deg)
        assert pm >= 2 * math.asin(1 / (2 * ms)) and pm >= 2 * math.asin(1 / (2 * mt))

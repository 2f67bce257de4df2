"""The landing controller's step against NumPy derivations and a closed-loop hover.

The references are written here from their definitions: rotations multiplied
out, PX4's attitude conventions as properties (body z, heading of body x),
the critically damped step response in closed form, the matrix exponential
of SciPy, the deck-frame acceleration as the textbook's transport, Coriolis,
centripetal and Euler terms, and ODE solutions from ``solve_ivp``.
"""

import numpy as np
import pytest
from reference import NO_AERO, euler_rate_matrix, rotation
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from quadland_symbolic.landing.attitude import thrust_attitude_function
from quadland_symbolic.landing.command_filter import command_filter_function, linear2_zoh
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    NETWORK_INPUT_DIM,
    known_acceleration,
    landing_controller_params,
    landing_memory,
    landing_step_function,
    landing_step_outputs,
)
from quadland_symbolic.landing.deck import DECK_PARAMS, pack_deck
from quadland_symbolic.landing.gear import contact_params
from quadland_symbolic.landing.guidance import POSITION_REFERENCE
from quadland_symbolic.landing.plant import LANDING_PLANT_STATE, landing_plant_function
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.landing.relative import relative6, relative6_acceleration
from quadland_symbolic.landing.sensors import measurement_function
from quadland_symbolic.landing.touchdown_policy import INERT_COMMANDS
from quadland_symbolic.loop import rk4_step
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

L_NODES = 10
M1, G = 2.0, 9.8
F_MAX = 2 * M1 * G / 4                   # thrust_to_weight = 2
P_QUAD = QUADROTOR.pack(dict(m1=M1, I=[1.2416, 1.2416, 2.4832], Kt=[0.01] * 3, Kr=[0.001] * 3,
                             g=G, arm=0.25, c=0.05))
P_ACT = ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=F_MAX, gear_height=0.2,
                           rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3, **NO_AERO))
#: The hover test's controller parameters (besides the network's centres and widths).
GAINS = dict(k1p=[1.0] * 3, k2p=[1.0] * 3, k1=[3.0] * 3, k2=[3.0] * 3, gamma1=0.05,
             gamma2=0.1, k_w=5.0, k_zeta=0.1, rho=0.1, w_f=12.0, zeta_f=1.0, tilt_max=0.5,
             ki_p=[0.5, 0.7, 0.9], ki=[1.0, 2.0, 3.0], d_max_p=0.4, d_max=5.0, r_learn=0.0,
             w_o=[3.0, 4.0, 0.0])
CENTERS = np.tile(np.linspace(-2.0, 2.0, L_NODES), (NETWORK_INPUT_DIM, 1))
WIDTHS = np.full(L_NODES, 2.0)


def _p_ctrl(nominal=1.0, **over):
    return landing_controller_params(L_NODES).pack(
        {**GAINS, **over, "nominal_model": nominal, "centers": CENTERS, "widths": WIDTHS})


@pytest.fixture(scope="module")
def step():
    return landing_step_function(L_NODES)


def _call(step, *args):
    return {n: np.array(v) for n, v in zip(step.name_out(), step(*args), strict=True)}


# ---------------------------------------------------------------- references (NumPy)



def _deck_euler_rates(eta2, w2E):
    """eta2_dot = Rr(eta2) R_deck^T w2E (eq. 3)."""
    return euler_rate_matrix(eta2[0], eta2[1]) @ rotation(eta2).T @ w2E


def _known_acceleration(m, pq):
    """f_p in the deck frame: R^T (g + drag - a2) - 2 w x v_e - w' x p_e - w x (w x p_e)."""
    R, R1 = rotation(m["eta2"]), rotation(m["eta1"])
    w, w_dot = R.T @ m["w2E"], R.T @ m["w2E_dot"]
    p_e, v_e = m["p_e"], m["v_e"]
    V1 = R1.T @ (m["v2E"] + R @ (v_e + np.cross(w, p_e)))
    drag = -R1 @ (pq["Kt"] * V1) / pq["m1"][0]
    f_g = R.T @ [0.0, 0.0, -pq["g"][0]]
    f_r = (R.T @ (drag - m["a2E"]) - 2 * np.cross(w, v_e) - np.cross(w_dot, p_e)
           - np.cross(w, np.cross(w, p_e)))
    return f_g, f_r


def _mix():
    """The mixer of eq. (2): [T, M] = mix F."""
    pq = QUADROTOR.unpack(P_QUAD)
    d, cq = pq["arm"][0], pq["c"][0]
    return np.array([[1, 1, 1, 1], [0, d, 0, -d], [-d, 0, d, 0], [cq, -cq, cq, -cq]])


def _rbf(x):
    return np.exp(-np.sum((CENTERS - x[:, None]) ** 2, axis=0) / WIDTHS**2)


def _random_case(rng, scale=1.0):
    """Measurements over a rolling, pitching, turning deck; a reference; memory."""
    y = LANDING_MEASUREMENT.pack(dict(
        p_e=rng.normal(0, 0.3, 3) * scale + [0, 0, 1.5], v_e=rng.normal(0, 0.3, 3) * scale,
        eta1=rng.uniform(-0.15, 0.15, 3) + [0, 0, 0.4], Omega1=rng.normal(0, 0.2, 3),
        eta2=rng.uniform(-0.1, 0.1, 3) + [0, 0, 0.4], v2E=rng.normal(0, 2, 3),
        a2E=rng.normal(0, 0.5, 3), w2E=rng.normal(0, 0.1, 3), w2E_dot=rng.normal(0, 0.1, 3)))
    ref = POSITION_REFERENCE.pack(dict(p_ref=rng.normal(0, 0.3, 3) + [0, 0, 1.5],
                              v_ref=rng.normal(0, 0.2, 3), a_ref=rng.normal(0, 0.2, 3),
                              **INERT_COMMANDS))
    mem = landing_memory(L_NODES).pack(dict(
        W_hat=rng.normal(0, 0.05, (L_NODES, 6)), zeta_hat=rng.uniform(0, 0.2, 6),
        eta_f=rng.uniform(-0.1, 0.1, 2), eta_f_dot=rng.normal(0, 0.1, 2),
        xi1=rng.normal(0, 0.05, 3), xi2=rng.normal(0, 0.05, 3),
        d_hat=np.concatenate([rng.uniform(-0.4, 0.4, 3), rng.uniform(-5, 5, 3)]),
        v_hat=rng.normal(0, 0.3, 3) * scale, d_o=rng.uniform(-0.4, 0.4, 3),
        T_o=M1 * G + rng.normal(0, 2.0)))
    return y, ref, mem


# ---------------------------------------------------------------- thrust vector to attitude

def test_body_z_to_attitude(rng):
    """R(phi, theta, psi) e_z is the thrust direction and the body x axis heads along psi."""
    f = thrust_attitude_function()
    for _ in range(200):
        tilt, az, psi = rng.uniform(0, 1.4), rng.uniform(-np.pi, np.pi), rng.uniform(-3, 3)
        b = np.array([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), np.cos(tilt)])
        T, b3, phi, theta, tilt_lim, thrust_lim = (np.array(v).ravel()
                                                   for v in f(7.0 * b, psi, 1.45, 100.0))
        R = rotation([phi[0], theta[0], psi])
        np.testing.assert_allclose(R[:, 2], b, atol=1e-12)
        np.testing.assert_allclose(b3, b, atol=1e-12)
        np.testing.assert_allclose(np.arctan2(R[1, 0], R[0, 0]), np.angle(np.exp(1j * psi)),
                                   atol=1e-12)
        np.testing.assert_allclose(T, 7.0, rtol=1e-12)
        assert tilt_lim == 0 and thrust_lim == 0


def test_tilt_and_thrust_limits(rng):
    """Outside the cone the axis lands on it in the same vertical plane, and the thrust
    keeps the vertical demand; zero or downward demands give the level attitude."""
    f = thrust_attitude_function()
    tilt_max, T_max = 0.5, 40.0
    for _ in range(200):
        t_E = rng.normal(size=3) * [10, 10, 15]
        T, b3, phi, theta, tilt_lim, thrust_lim = (np.array(v).ravel()
                                                   for v in f(t_E, 0.3, tilt_max, T_max))
        angle = np.arccos(np.clip(b3[2], -1, 1))
        assert angle <= tilt_max + 1e-12
        np.testing.assert_allclose(rotation([phi[0], theta[0], 0.3])[:, 2], b3, atol=1e-12)
        inside = t_E[2] > np.cos(tilt_max) * np.linalg.norm(t_E)
        assert tilt_lim == (not inside)
        if inside:
            np.testing.assert_allclose(b3, t_E / np.linalg.norm(t_E), atol=1e-12)
            T_raw = np.linalg.norm(t_E)
        else:
            np.testing.assert_allclose(angle, tilt_max, atol=1e-9)
            h = t_E[:2] / np.linalg.norm(t_E[:2])
            np.testing.assert_allclose(b3[:2] / np.linalg.norm(b3[:2]), h, atol=1e-12)
            T_raw = t_E[2] / np.cos(tilt_max)
        np.testing.assert_allclose(T, np.clip(T_raw, 0, T_max), atol=1e-12)
        assert thrust_lim == (T_raw < 0 or T_raw > T_max)
    for t_E in ([0, 0, 0], [0, 0, -5]):
        T, b3, phi, theta, *_ = (np.array(v).ravel() for v in f(t_E, 0.3, tilt_max, T_max))
        np.testing.assert_allclose(b3, [0, 0, 1], atol=1e-15)
        assert T == 0 and phi == 0 and theta == 0


# ---------------------------------------------------------------- linear pieces

def test_command_filter_step_response():
    """A critically damped filter from rest: x = c (1 - (1 + w t) e^-wt), x' = c w^2 t e^-wt,
    x'' = c w^2 (1 - w t) e^-wt, at every sample."""
    f = command_filter_function(2)
    w, dt, c = 7.0, 0.01, np.array([0.3, -0.2])
    x, xd = np.zeros(2), np.zeros(2)
    for k in range(300):
        t = k * dt
        e = np.exp(-w * t)
        np.testing.assert_allclose(x, c * (1 - (1 + w * t) * e), atol=1e-13)
        np.testing.assert_allclose(xd, c * w**2 * t * e, atol=1e-12)
        x_next, xd_next, xdd = (np.array(v).ravel() for v in f(x, xd, c, w, 1.0, dt))
        np.testing.assert_allclose(xdd, c * w**2 * (1 - w * t) * e, atol=1e-11)
        x, xd = x_next, xd_next


@pytest.mark.parametrize("zeta", [0.3, 0.9862, 1.0 - 1e-7, 1.0, 1.0 + 1e-5, 1.0138, 2.5])
def test_command_filter_matches_expm(rng, zeta):
    """Under-, critically and over-damped; zeta = 1 +- 0.0138 puts (zeta^2 - 1) (w dt)^2
    just inside the series branch."""
    f = command_filter_function(1)
    w, dt = 9.0, 0.02
    A = np.array([[0, 1], [-w**2, -2 * zeta * w]])
    for _ in range(5):
        x0, c = rng.normal(size=2), rng.normal()
        x_eq = np.array([c, 0.0])
        exact = x_eq + expm(A * dt) @ (x0 - x_eq)
        got = np.array([np.array(v).item() for v in f(x0[0], x0[1], c, w, zeta, dt)[:2]])
        np.testing.assert_allclose(got, exact, rtol=1e-12, atol=1e-13)


def test_linear2_zoh_against_expm(rng):
    """x(dt) of x' = A x + f against SciPy's expm of the augmented system."""
    import casadi as ca

    x, A, f_, dt = ca.SX.sym("x", 2), ca.SX.sym("A", 2, 2), ca.SX.sym("f", 2), ca.SX.sym("dt")
    fn = ca.Function("zoh", [x, A, f_, dt], [linear2_zoh(x, A, f_, dt)])
    for _ in range(50):
        A_num = rng.normal(size=(2, 2)) * 3
        if abs(np.linalg.det(A_num)) < 0.1:
            continue
        x0, f0, h = rng.normal(size=2), rng.normal(size=2), rng.uniform(0.001, 0.3)
        aug = np.zeros((3, 3))
        aug[:2, :2], aug[:2, 2] = A_num, f0
        exact = (expm(aug * h) @ np.append(x0, 1.0))[:2]
        np.testing.assert_allclose(np.array(fn(x0, A_num, f0, h)).ravel(), exact,
                                   rtol=1e-10, atol=1e-12)


# ---------------------------------------------------------------- the law, term by term

def test_known_acceleration_is_the_plants_at_zero_thrust(rng):
    """f_p = a_e of the plant's own derivation with the rotors off and no disturbance,
    for a rough deck on a turning vehicle."""
    DEG = np.pi / 180
    pd = pack_deck(dict(
        heave_amp=[0.7, 0.2, 0.1], heave_freq=[1.5, 0.7, 2.1], heave_phase=rng.uniform(0, 6, 3),
        roll_amp=[15 * DEG, 3 * DEG, 0], roll_freq=[2.0, 0.9, 1], roll_phase=rng.uniform(0, 6, 3),
        pitch_amp=[10 * DEG, 2 * DEG, 0], pitch_freq=[2.5, 1.1, 1],
        pitch_phase=rng.uniform(0, 6, 3), pad_offset=[1.0, -0.5, 0.3], deck_height=2.0))
    pv = VEHICLE.pack(dict(m11=100, m22=100, m33=80, d11=100, d22=100, d33=80,
                           tau=[150, 30, 40], z2=0))
    pq = QUADROTOR.unpack(P_QUAD)
    for _ in range(5):
        x1q = QUAD6_STATE.pack(dict(p1=rng.normal(0, 2, 3) + [0, 0, 5],
                                    eta1=rng.uniform(-0.4, 0.4, 3), V1=rng.normal(0, 2, 3),
                                    Omega1=rng.normal(0, 0.5, 3), F=np.zeros(4)))
        xv = VEHICLE_STATE.pack(dict(x2=1, y2=2, psi2=0.3, u2=3, v2=0.5, r2=0.2))
        t = rng.uniform(0, 10)
        args = (x1q, xv, t, P_QUAD, P_ACT, pv, pd)
        p_e, v_e, *_ = relative6(*args)
        a_e, _ = relative6_acceleration(x1q, xv, t, np.zeros(4), np.zeros(6), P_QUAD, P_ACT, pv,
                                        pd)
        xp = np.concatenate([x1q, xv, np.zeros(3)])
        pp = np.concatenate([P_QUAD, P_ACT, pv, pd, *contact_params().values()])
        m = LANDING_MEASUREMENT.unpack(np.array(measurement_function()(xp, t, pp)).ravel())
        np.testing.assert_allclose(m["p_e"], np.array(p_e).ravel(), atol=1e-14)
        np.testing.assert_allclose(m["v_e"], np.array(v_e).ravel(), atol=1e-13)
        f_g, f_r = (np.array(v).ravel() for v in known_acceleration(
            m["p_e"], m["v_e"], m["eta1"], m["eta2"], m["v2E"], m["a2E"], m["w2E"],
            m["w2E_dot"], P_QUAD))
        np.testing.assert_allclose(f_g + f_r, np.array(a_e).ravel(), atol=1e-12)
        ref_g, ref_r = _known_acceleration(m, pq)
        np.testing.assert_allclose(f_g, ref_g, atol=1e-14)
        np.testing.assert_allclose(f_r, ref_r, atol=1e-12)


@pytest.mark.parametrize("nominal", [0.0, 1.0])
def test_outer_law_by_hand(step, rng, nominal):
    """a_des = -k2p z2 - z1 - W_p^T Psi - tanh(z2_bar / rho) zeta_p + alpha_dot - f_g
    - nominal f_r - d_hat_p - d_o, with alpha_dot = -k1p (v_e - v_ref) + a_ref; the thrust is
    |m1 R a_des| along the commanded body z."""
    p_ctrl = _p_ctrl(nominal, k1p=[0.8, 1.0, 1.3], k2p=[1.1, 0.9, 1.6])
    for _ in range(5):
        y, ref, mem = _random_case(rng)
        out = _call(step, y, ref, mem, p_ctrl, P_QUAD, P_ACT, 0.004)
        m, r = LANDING_MEASUREMENT.unpack(y), POSITION_REFERENCE.unpack(ref)
        mm = landing_memory(L_NODES).unpack(mem)
        k1p, k2p, rho = np.array([0.8, 1.0, 1.3]), np.array([1.1, 0.9, 1.6]), GAINS["rho"]
        z1 = m["p_e"] - r["p_ref"]
        z2 = m["v_e"] - (-k1p * z1 + r["v_ref"])
        alpha_dot = -k1p * (m["v_e"] - r["v_ref"]) + r["a_ref"]
        eta2_dot = _deck_euler_rates(m["eta2"], m["w2E"])
        Omega_e = m["Omega1"] - np.linalg.solve(euler_rate_matrix(*m["eta1"][:2]), eta2_dot)
        Delta = mm["W_hat"].T @ _rbf(np.concatenate([m["v_e"], Omega_e]))
        f_g, f_r = _known_acceleration(m, QUADROTOR.unpack(P_QUAD))
        a_des = (-k2p * z2 - z1 - Delta[:3] - np.tanh((z2 - mm["xi2"]) / rho) * mm["zeta_hat"][:3]
                 + alpha_dot - f_g - nominal * f_r - mm["d_hat"][:3] - mm["d_o"])
        np.testing.assert_allclose(out["bs_z1"].ravel()[:3], z1, atol=1e-14)
        np.testing.assert_allclose(out["bs_z2"].ravel()[:3], z2, atol=1e-14)
        np.testing.assert_allclose(out["Delta_hat"].ravel(), Delta, atol=1e-14)
        np.testing.assert_allclose(out["a_des"].ravel(), a_des, atol=1e-12)
        t_E = M1 * rotation(m["eta2"]) @ a_des
        assert out["limits"].ravel()[:2].tolist() == [0, 0]
        # |t_E|, moved into the band where every rotor can make its share of the moments
        wrench = out["wrench"].ravel()
        share = np.linalg.solve(_mix(), np.r_[0.0, wrench[1:]])
        band = (4 * np.max(-share), 4 * (F_MAX - np.max(share)))
        T = max(min(max(np.linalg.norm(t_E), band[0]), band[1]), 0.0)
        np.testing.assert_allclose(wrench[0], T, rtol=1e-12)
        eta_c = out["eta_c"].ravel()
        np.testing.assert_allclose(eta_c[2], m["eta2"][2])
        np.testing.assert_allclose(rotation(eta_c)[:, 2], t_E / np.linalg.norm(t_E), atol=1e-12)


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("nominal", [0.0, 1.0])
def test_inner_law_by_hand(step, nominal, seed):
    """M / I = -k2 z2 - Rr^T z1 - W_a^T Psi - tanh(z2 / rho) zeta_a + alpha_dot - nominal f_a
    - d_hat_a (eq. 20 and the bias estimate) with e1d = [filter state, psi2]; alpha_dot
    by a central difference of alpha = Rr^-1 (-k1 z1 + e1d_dot) (eq. 14); the rotors
    realise [T, M] (eq. 2)."""
    p_ctrl = _p_ctrl(nominal, k1=[2.0, 3.0, 1.5], k2=[2.5, 3.5, 1.0])
    k1, k2, rho = np.array([2.0, 3.0, 1.5]), np.array([2.5, 3.5, 1.0]), GAINS["rho"]
    w_f, zeta_f = GAINS["w_f"], GAINS["zeta_f"]
    pq = QUADROTOR.unpack(P_QUAD)
    I = pq["I"]
    y, ref, mem = _random_case(np.random.default_rng(seed))
    out = _call(step, y, ref, mem, p_ctrl, P_QUAD, P_ACT, 0.004)
    m, mm = LANDING_MEASUREMENT.unpack(y), landing_memory(L_NODES).unpack(mem)
    eta1, Om = m["eta1"], m["Omega1"]

    def eta2_rates(s, m=m):
        """psi2_dot and d/ds of it along the deck's motion, at s seconds from now."""
        eta2 = m["eta2"] + s * _deck_euler_rates(m["eta2"], m["w2E"])
        return _deck_euler_rates(eta2, m["w2E"] + s * m["w2E_dot"])[2]

    h = 1e-5
    c = out["eta_c"].ravel()[:2]
    e1d = np.append(mm["eta_f"], m["eta2"][2])
    e1d_dot = np.append(mm["eta_f_dot"], eta2_rates(0))
    e1d_ddot = np.append(w_f**2 * (c - mm["eta_f"]) - 2 * zeta_f * w_f * mm["eta_f_dot"],
                         (eta2_rates(h) - eta2_rates(-h)) / (2 * h))
    np.testing.assert_allclose(out["eta_d"].ravel(), e1d, atol=1e-15)
    np.testing.assert_allclose(out["eta_d_dot"].ravel(), e1d_dot, atol=1e-14)
    np.testing.assert_allclose(out["eta_d_ddot"].ravel(), e1d_ddot, atol=1e-8)

    def alpha(s):
        """alpha along the motion: eta1' = Rr Omega1, e1d' = e1d_dot, e1d_dot' = e1d_ddot."""
        eta = eta1 + s * euler_rate_matrix(*eta1[:2]) @ Om
        ref_dot = e1d_dot + s * e1d_ddot
        return np.linalg.solve(euler_rate_matrix(*eta[:2]),
                               -k1 * (eta - e1d - s * e1d_dot) + ref_dot)

    z1, Rr = eta1 - e1d, euler_rate_matrix(*eta1[:2])
    z2 = Om - alpha(0)
    alpha_dot = (alpha(h) - alpha(-h)) / (2 * h)
    eta2_dot = _deck_euler_rates(m["eta2"], m["w2E"])
    Omega_e = Om - np.linalg.solve(Rr, eta2_dot)
    Delta = mm["W_hat"].T @ _rbf(np.concatenate([m["v_e"], Omega_e]))
    f_a = -pq["Kr"] * Om / I - np.cross(Om, I * Om) / I
    u = (-k2 * z2 - Rr.T @ z1 - Delta[3:] - np.tanh(z2 / rho) * mm["zeta_hat"][3:]
         + alpha_dot - nominal * f_a - mm["d_hat"][3:])
    np.testing.assert_allclose(out["bs_z1"].ravel()[3:], z1, atol=1e-14)
    np.testing.assert_allclose(out["bs_z2"].ravel()[3:], z2, atol=1e-12)
    wrench = out["wrench"].ravel()
    np.testing.assert_allclose(wrench[1:] / I, u, rtol=1e-7, atol=1e-7)
    rotors = np.linalg.solve(_mix(), wrench)
    np.testing.assert_allclose(out["F_cmd"].ravel(), np.clip(rotors, 0, F_MAX), atol=1e-12)
    tol = 1e-5 * F_MAX                      # a rotor at its limit to roundoff is not clipped
    assert out["limits"].ravel()[2] == np.sum((rotors < -tol) | (rotors > F_MAX + tol))


def test_the_moments_come_first_and_the_thrust_takes_what_they_leave(step):
    """Level deck, at rest 1.5 m below the reference (a climb: |t_E| = 25.6 N) and rolled
    -0.15 rad from a level command: the roll moment needs rotor 2 near F_max, so the
    collective thrust drops to 4 (F_max - max m_i) and the rotors make the moments
    exactly, none clipped."""
    y = LANDING_MEASUREMENT.pack(dict(
        p_e=[0.0, 0.0, 1.5], v_e=np.zeros(3), eta1=[-0.15, 0.0, 0.4], Omega1=np.zeros(3),
        eta2=[0.0, 0.0, 0.4], v2E=np.zeros(3), a2E=np.zeros(3), w2E=np.zeros(3),
        w2E_dot=np.zeros(3)))
    ref = POSITION_REFERENCE.pack(dict(p_ref=[0.0, 0.0, 3.0], v_ref=np.zeros(3),
                                       a_ref=np.zeros(3), **INERT_COMMANDS))
    out = _call(step, y, ref, landing_memory(L_NODES).zeros(), _p_ctrl(1.0), P_QUAD, P_ACT,
                0.004)
    wrench = out["wrench"].ravel()
    share = np.linalg.solve(_mix(), np.r_[0.0, wrench[1:]])
    t_E = M1 * rotation([0.0, 0.0, 0.4]) @ out["a_des"].ravel()
    assert out["limits"].ravel()[:2].tolist() == [0, 0]            # no thrust or tilt limit
    assert wrench[0] < np.linalg.norm(t_E) - 1.0                   # the thrust gave way
    np.testing.assert_allclose(wrench[0], 4 * (F_MAX - np.max(share)), rtol=1e-12)
    assert out["limits"].ravel()[2] == 0
    np.testing.assert_allclose(_mix() @ out["F_cmd"].ravel(), wrench, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------- memory over dt

@pytest.mark.parametrize("seed", range(3))
def test_memory_update_is_the_exact_solution(step, seed):
    """W_hat, zeta_hat (eq. 22), the saturation compensator and the disturbance observer
    after dt, against solve_ivp of their linear ODEs with Psi, z2_bar, the limits'
    shortfall and the observer's inputs held; the observer's thrust in closed form."""
    dt = 0.05
    p_ctrl = _p_ctrl(1.0, tilt_max=0.2)        # a small cone: the tilt limit acts
    lay = landing_memory(L_NODES)
    y, ref, mem = _random_case(np.random.default_rng(seed), scale=3.0)
    out = _call(step, y, ref, mem, p_ctrl, P_QUAD, P_ACT, dt)
    assert out["limits"].ravel()[1] == 1
    m, mm = LANDING_MEASUREMENT.unpack(y), lay.unpack(mem)
    nxt = lay.unpack(out["mem_next"].ravel())
    eta2_dot = _deck_euler_rates(m["eta2"], m["w2E"])
    Omega_e = m["Omega1"] - np.linalg.solve(euler_rate_matrix(*m["eta1"][:2]), eta2_dot)
    Psi = _rbf(np.concatenate([m["v_e"], Omega_e]))
    z2 = out["bs_z2"].ravel() - np.concatenate([mm["xi2"], np.zeros(3)])
    g1, g2, kw, kz = GAINS["gamma1"], GAINS["gamma2"], GAINS["k_w"], GAINS["k_zeta"]
    sq = np.tanh(z2 / GAINS["rho"])

    def rhs(_t, s):
        W, zeta = s[:6 * L_NODES].reshape(L_NODES, 6), s[6 * L_NODES:]
        return np.concatenate([(g1 * (np.outer(Psi, z2) - kw * W)).ravel(),
                               g2 * (sq * z2 - kz * zeta)])

    s0 = np.concatenate([mm["W_hat"].ravel(), mm["zeta_hat"]])
    sol = solve_ivp(rhs, (0, dt), s0, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    np.testing.assert_allclose(nxt["W_hat"], sol[:6 * L_NODES].reshape(L_NODES, 6),
                               atol=1e-13)
    np.testing.assert_allclose(nxt["zeta_hat"], sol[6 * L_NODES:], atol=1e-13)

    # compensator: delta = R_deck^T (T b3 - t_E) / m1, b3 = R(eta_c) e_z
    R = rotation(m["eta2"])
    T, b3 = out["wrench"].ravel()[0], rotation(out["eta_c"].ravel())[:, 2]
    delta = R.T @ (T * b3 - M1 * R @ out["a_des"].ravel()) / M1
    assert np.linalg.norm(delta) > 0.1
    k1p, k2p = np.array(GAINS["k1p"]), np.array(GAINS["k2p"])

    def comp(_t, s):
        xi1, xi2 = s[:3], s[3:]
        return np.concatenate([-k1p * xi1 + xi2, -k2p * xi2 - xi1 + delta])

    sol = solve_ivp(comp, (0, dt), np.concatenate([mm["xi1"], mm["xi2"]]), method="DOP853",
                    rtol=1e-13, atol=1e-15).y[:, -1]
    np.testing.assert_allclose(np.concatenate([nxt["xi1"], nxt["xi2"]]), sol, atol=1e-13)

    # bias estimates: d_hat' = k z2 (outer on z2_bar; inner frozen while a rotor clips),
    # then each clipped to its box
    clipped = out["limits"].ravel()[2] > 0
    rate = np.concatenate([np.array(GAINS["ki_p"]) * z2[:3],
                           np.array(GAINS["ki"]) * z2[3:] * (not clipped)])
    box = np.repeat([GAINS["d_max_p"], GAINS["d_max"]], 3)
    np.testing.assert_allclose(nxt["d_hat"], np.clip(mm["d_hat"] + dt * rate, -box, box),
                               atol=1e-14)

    # disturbance observer, per axis with w > 0: v_hat' = a_k + d_o + 2 w (v_e - v_hat),
    # d_o' = w^2 (v_e - v_hat), a_k = R_deck^T R1 e_z T_o / m1 + f_g + f_r (v_e, a_k held),
    # then d_o clipped to the outer box; the thrust T_o' = (sum F_cmd - T_o) / tau_m
    f_g, f_r = _known_acceleration(m, QUADROTOR.unpack(P_QUAD))
    a_k = R.T @ rotation(m["eta1"])[:, 2] * mm["T_o"] / M1 + f_g + f_r
    for i, w in enumerate(GAINS["w_o"]):
        if w == 0:                                          # no observer: held
            assert nxt["v_hat"][i] == mm["v_hat"][i] and nxt["d_o"][i] == mm["d_o"][i]
            continue

        def obs(_t, s, i=i, w=w):
            return [a_k[i] + s[1] + 2 * w * (m["v_e"][i] - s[0]), w**2 * (m["v_e"][i] - s[0])]

        sol = solve_ivp(obs, (0, dt), [mm["v_hat"][i], mm["d_o"][i]], method="DOP853",
                        rtol=1e-13, atol=1e-15).y[:, -1]
        np.testing.assert_allclose(nxt["v_hat"][i], sol[0], atol=1e-12)
        np.testing.assert_allclose(nxt["d_o"][i], np.clip(sol[1], -GAINS["d_max_p"],
                                                          GAINS["d_max_p"]), atol=1e-12)
    T_cmd = out["F_cmd"].sum()
    np.testing.assert_allclose(nxt["T_o"], T_cmd + (mm["T_o"] - T_cmd) * np.exp(-dt / 0.02),
                               rtol=1e-14)


# ---------------------------------------------------------------- closed loop

@pytest.mark.parametrize("nominal", [0.0, 1.0])
def test_hover_over_a_stationary_deck(step, nominal):
    """From 1-1.5 m off the hover point in every axis (and 3 deg of yaw) over a still,
    level deck heading 0.4 rad: at 250 Hz with the plant integrated by RK4, the quadrotor
    settles within 3 cm and 0.5 deg in 6 s; the rotor commands stay in [0, F_max]."""
    pv = VEHICLE.pack(dict(m11=100, m22=100, m33=80, d11=100, d22=100, d33=80,
                           tau=[0, 0, 0], z2=0))
    pd = DECK_PARAMS.zeros()
    pd[DECK_PARAMS.slice("deck_height")] = 1.0
    pp = np.concatenate([P_QUAD, P_ACT, pv, pd, *contact_params().values()])
    psi2, hover = 0.4, np.array([0.0, 0.0, 2.0])
    xp = LANDING_PLANT_STATE.pack(dict(
        x1q=QUAD6_STATE.pack(dict(p1=[1.5, -1.0, 1.0 + 3.0], eta1=[0, 0, psi2 + 0.05],
                                  V1=np.zeros(3),
                            Omega1=np.zeros(3), F=[M1 * G / 4] * 4)),
        xv=VEHICLE_STATE.pack(dict(x2=0, y2=0, psi2=psi2, u2=0, v2=0, r2=0)),
        gear=np.zeros(3)))
    ref = POSITION_REFERENCE.pack(dict(p_ref=hover, v_ref=np.zeros(3), a_ref=np.zeros(3),
                                       **INERT_COMMANDS))
    p_ctrl, mem = _p_ctrl(nominal), landing_memory(L_NODES).zeros()
    measure, rk4 = measurement_function(), rk4_step(landing_plant_function())
    out_lay = landing_step_outputs(L_NODES)
    dt, n = 1 / 250, 1500
    F_log, y = np.empty((n, 4)), None
    for k in range(n):
        y = np.array(measure(xp, k * dt, pp)).ravel()
        out = out_lay.unpack(np.concatenate(
            [np.array(v).ravel() for v in step(y, ref, mem, p_ctrl, P_QUAD, P_ACT, dt)]))
        F_log[k], mem = out["F_cmd"], out["mem_next"]
        xp = np.array(rk4(xp, out["F_cmd"], np.zeros(6), k * dt, pp, dt)).ravel()
    m = LANDING_MEASUREMENT.unpack(y)
    assert np.all(np.isfinite(F_log)) and F_log.min() >= 0 and F_log.max() <= F_MAX
    assert np.linalg.norm(m["p_e"] - hover) < 0.03
    assert np.linalg.norm(m["v_e"]) < 0.03
    assert np.max(np.abs(m["eta1"] - [0, 0, psi2])) < np.radians(0.5)

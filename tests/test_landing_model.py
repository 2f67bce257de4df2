"""The 6-DOF landing plant against Newton-Euler and the deck's motion written here.

The references below are written from the paper's eq. (1)-(4) and from the
deck's prescribed sinusoids in NumPy; the two bodies are integrated apart in E
with scipy, and the relative state is formed from them and differentiated by
finite differences, never taken from the code under test.
"""

import numpy as np
import pytest
from reference import NO_AERO, euler_rate_matrix, rotation
from scipy.integrate import solve_ivp

from quadland_symbolic.landing.deck import DECK_PARAMS, N_DECK, N_SINES, deck_function, pack_deck
from quadland_symbolic.landing.gear import contact_params
from quadland_symbolic.landing.plant import (
    LANDING_PLANT_OUTPUTS,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
    landing_outputs_function,
    landing_plant_function,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE, quadrotor6_function
from quadland_symbolic.landing.relative import (
    gear_gap,
    relative6_acceleration_function,
    relative6_function,
)
from quadland_symbolic.parameters import QUADROTOR, VEHICLE

DECK = deck_function()
QUAD6 = quadrotor6_function()
REL6 = relative6_function()
ACC6 = relative6_acceleration_function()
DEG = np.pi / 180
TAU_M, F_MAX, GEAR = 0.05, 10.0, 0.2
P_ACT = ACTUATOR.pack(dict(motor_time_constant=TAU_M, F_max=F_MAX, gear_height=GEAR,
                           rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3, **NO_AERO))


# ---------------------------------------------------------------- references (NumPy)



def _quad6(x, F_cmd, d_F, d_M, pq):
    """x1q_dot from eq. (1)-(2), the paper's mixer and a first-order motor lag."""
    m, I, Kt, Kr, g = pq["m1"][0], pq["I"], pq["Kt"], pq["Kr"], pq["g"][0]
    d, c = pq["arm"][0], pq["c"][0]
    eta, V, Om, F = x[3:6], x[6:9], x[9:12], x[12:16]
    R = rotation(eta)
    thrust = np.array([0.0, 0.0, F.sum()])
    M = np.array([d * (F[1] - F[3]), d * (F[2] - F[0]), c * (F[0] - F[1] + F[2] - F[3])])
    V_dot = (thrust - Kt * V - m * R.T @ [0, 0, g] + d_F) / m - np.cross(Om, V)
    Om_dot = (M - Kr * Om + d_M - np.cross(Om, I * Om)) / I
    F_dot = (np.clip(F_cmd, 0.0, F_MAX) - F) / TAU_M
    return np.concatenate([R @ V, euler_rate_matrix(eta[0], eta[1]) @ Om, V_dot, Om_dot,
                           F_dot])


def _vehicle(xv, pv):
    """xv_dot from eq. (4), planar."""
    psi2, u2, v2, r2 = xv[2:6]
    m11, m22, m33 = pv["m11"][0], pv["m22"][0], pv["m33"][0]
    tx, ty, tz = pv["tau"]
    return np.array([
        np.cos(psi2) * u2 - np.sin(psi2) * v2, np.sin(psi2) * u2 + np.cos(psi2) * v2, r2,
        (tx + m22 * v2 * r2 - pv["d11"][0] * u2) / m11,
        (ty - m11 * u2 * r2 - pv["d22"][0] * v2) / m22,
        (tz - m22 * v2 * u2 + m11 * u2 * v2 - pv["d33"][0] * r2) / m33])


def _sines(d, name, t, order=0):
    """The ``order``-th time derivative of sum a sin(w t + phase)."""
    a, w, ph = d[f"{name}_amp"], d[f"{name}_freq"], d[f"{name}_phase"]
    return np.sum(a * w**order * np.sin(w * t + ph + order * np.pi / 2))


def _deck(xv, t, d):
    """Pad centre p2, eta2 and R_deck in closed form."""
    eta2 = np.array([_sines(d, "roll", t), _sines(d, "pitch", t), xv[2]])
    R = rotation(eta2)
    origin = np.array([xv[0], xv[1], d["deck_height"][0] + _sines(d, "heave", t)])
    return origin + R @ d["pad_offset"], eta2, R


def _relative(x, xv, t, d):
    """p_e, eta_e, Omega_e and the gear gap, written from their definitions."""
    p2, eta2, R2 = _deck(xv, t, d)
    eta1 = x[3:6]
    eta2_dot = np.array([_sines(d, "roll", t, 1), _sines(d, "pitch", t, 1), xv[5]])
    Omega_e = x[9:12] - np.linalg.solve(euler_rate_matrix(eta1[0], eta1[1]), eta2_dot)
    gear = x[0:3] - GEAR * rotation(eta1)[:, 2]
    return R2.T @ (x[0:3] - p2), eta1 - eta2, Omega_e, R2[:, 2] @ (gear - p2)


def _stencil(f, h):
    """First and second derivatives at the middle of five samples (4th order)."""
    d1 = (f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * h)
    d2 = (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * h * h)
    return d1, d2


def _vee(S):
    A = (S - S.T) / 2
    return np.array([A[2, 1], A[0, 2], A[1, 0]])


# ---------------------------------------------------------------- scenarios

def _deck_params(rng, kind):
    """Random deck motions: a ship (heave ~0.7 m at ~0.35 rad/s, roll and pitch
    ~1 deg), a rough sea that makes the frame terms large, and a car."""
    amp, freq = {"ship": ((0.7, 1 * DEG, 1 * DEG), (0.35, 0.5, 0.5)),
                 "rough": ((0.7, 15 * DEG, 10 * DEG), (1.5, 2.0, 2.5)),
                 "car": ((0.0, 0.0, 0.0), (0.35, 0.5, 0.5))}[kind]
    vals = {}
    for name, a, w in zip(("heave", "roll", "pitch"), amp, freq, strict=True):
        vals[f"{name}_amp"] = a * rng.uniform(0.3, 1.0, N_SINES) / np.sqrt(N_SINES)
        vals[f"{name}_freq"] = w * rng.uniform(0.5, 1.5, N_SINES)
        vals[f"{name}_phase"] = rng.uniform(-np.pi, np.pi, N_SINES)
    vals["pad_offset"] = rng.normal(size=3) * [2.0, 1.0, 0.3]
    vals["deck_height"] = rng.uniform(0.5, 3.0)
    return pack_deck(vals)


def _params(values, rng, kind):
    p_veh = values.p_veh.copy()
    p_veh[VEHICLE.slice("m22")] = 80.0                     # m22 != m11 exercises C1, C2
    p_veh[VEHICLE.slice("tau")] = rng.normal(size=3) * [50, 30, 20]
    return values.p_quad, P_ACT, p_veh, _deck_params(rng, kind)


def _random_states(rng):
    x1q = np.concatenate([rng.normal(size=3) * [3, 3, 2] + [0, 0, 4],
                          rng.uniform(-0.5, 0.5, 2), rng.uniform(-3, 3, 1),
                          rng.normal(size=3), rng.normal(size=3) * 0.5,
                          rng.uniform(0, F_MAX, 4)])
    xv = np.concatenate([rng.normal(size=2) * 5, rng.uniform(-3, 3, 1),
                         rng.normal(size=2) * 2, rng.normal(size=1) * 0.3])
    return x1q, xv


def _col(v):
    return np.array(v, dtype=float).ravel()


# ---------------------------------------------------------------- two bodies in E

@pytest.mark.parametrize("kind", ["ship", "rough", "car"])
@pytest.mark.parametrize("seed", range(3))
def test_relative_state_against_two_bodies_integrated_in_E(values, kind, seed):
    """p_e, v_e, a_e, eta_e, Omega_e and its rate from two bodies integrated apart."""
    rng = np.random.default_rng([seed, len(kind)])
    p_quad, p_act, p_veh, p_deck = params = _params(values, rng, kind)
    pq, pv, d = QUADROTOR.unpack(p_quad), VEHICLE.unpack(p_veh), DECK_PARAMS.unpack(p_deck)
    x1q, xv = _random_states(rng)
    F_cmd = rng.uniform(-2, F_MAX + 2, 4)                  # saturation inside the flow too
    d_F, d_M = rng.normal(size=3), rng.normal(size=3) * 0.1
    w = np.concatenate([d_F, d_M])

    def flow(_t, z):
        return np.concatenate([_quad6(z[:16], F_cmd, d_F, d_M, pq), _vehicle(z[16:], pv)])

    t0, h = rng.uniform(0, 30), 2e-3
    centres = t0 + np.array([0.3, 0.6, 0.9])
    t_eval = (centres[:, None] + h * np.arange(-2, 3)).ravel()
    sol = solve_ivp(flow, (t0, t_eval[-1]), np.concatenate([x1q, xv]), method="DOP853",
                    t_eval=t_eval, rtol=1e-13, atol=1e-12)
    assert sol.success
    for k, tc in enumerate(centres):
        ts, zs = sol.t[5 * k:5 * k + 5], sol.y[:, 5 * k:5 * k + 5].T
        rel = [_relative(z[:16], z[16:], t, d) for t, z in zip(ts, zs, strict=True)]
        p_e, eta_e, Omega_e = (np.array([r[i] for r in rel]) for i in range(3))
        v_fd, a_fd = _stencil(p_e, h)
        eta_dot_fd, _ = _stencil(eta_e, h)
        Omega_dot_fd, _ = _stencil(Omega_e, h)
        xc, xvc = zs[2, :16], zs[2, 16:]
        s_p, s_v, s_eta, s_Om, s_gap = map(_col, REL6(xc, xvc, tc, *params))
        s_a, s_Om_dot = map(_col, ACC6(xc, xvc, tc, F_cmd, w, *params))
        np.testing.assert_allclose(s_p, p_e[2], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(s_eta, eta_e[2], atol=1e-12)
        np.testing.assert_allclose(s_Om, Omega_e[2], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(s_gap, rel[2][3], atol=1e-12)
        np.testing.assert_allclose(s_v, v_fd, rtol=1e-7, atol=1e-8)
        np.testing.assert_allclose(s_a, a_fd, rtol=1e-7, atol=1e-7)
        np.testing.assert_allclose(s_Om_dot, Omega_dot_fd, rtol=1e-7, atol=1e-8)
        # eq. (5) generalised: eta_e_dot = Rr1 Omega_e
        np.testing.assert_allclose(euler_rate_matrix(*xc[3:5]) @ s_Om, eta_dot_fd,
                                   rtol=1e-7, atol=1e-8)


@pytest.mark.parametrize("kind", ["ship", "rough"])
def test_relative_acceleration_is_the_rotating_frame_formula(values, rng, kind):
    """a_e = R^T (p1'' - p2'') - 2 w x v_e - w' x p_e - w x (w x p_e), w in deck axes,
    with p1'' from Newton's law written here and the deck's terms of ``deck``."""
    for _ in range(10):
        p_quad, p_act, p_veh, p_deck = params = _params(values, rng, kind)
        pq = QUADROTOR.unpack(p_quad)
        x1q, xv = _random_states(rng)
        t = rng.uniform(0, 30)
        F_cmd, w = rng.uniform(0, F_MAX, 4), rng.normal(size=6)
        x_dot = _quad6(x1q, F_cmd, w[:3], w[3:], pq)
        R1, V1, Om1 = rotation(x1q[3:6]), x1q[6:9], x1q[9:12]
        p1_ddot = R1 @ (x_dot[6:9] + np.cross(Om1, V1))
        _, _, R, _, a2E, w2E, w2E_dot = (np.array(v) for v in DECK(xv, t, p_veh, p_deck))
        wd, wd_dot = R.T @ w2E.ravel(), R.T @ w2E_dot.ravel()
        p_e, v_e = (_col(v) for v in REL6(x1q, xv, t, *params)[:2])
        expected = (R.T @ (p1_ddot - a2E.ravel()) - 2 * np.cross(wd, v_e)
                    - np.cross(wd_dot, p_e) - np.cross(wd, np.cross(wd, p_e)))
        a_e = _col(ACC6(x1q, xv, t, F_cmd, w, *params)[0])
        np.testing.assert_allclose(a_e, expected, rtol=1e-10, atol=1e-10)


# ---------------------------------------------------------------- the deck's frames

@pytest.mark.parametrize("kind", ["ship", "rough", "car"])
def test_deck_pose_and_its_derivatives(values, rng, kind):
    """R_deck is a rotation; p2, eta2 in closed form; v2E, a2E, w2E, w2E_dot against
    finite differences along an integrated vehicle track; S(w2E) = R_dot R^T."""
    _, _, p_veh, p_deck = _params(values, rng, kind)
    pv, d = VEHICLE.unpack(p_veh), DECK_PARAMS.unpack(p_deck)
    _, xv0 = _random_states(rng)
    t0, h = rng.uniform(0, 30), 2e-3
    ts = t0 + 0.5 + h * np.arange(-2, 3)
    sol = solve_ivp(lambda _t, x: _vehicle(x, pv), (t0, ts[-1]), xv0, method="DOP853",
                    t_eval=ts, rtol=1e-13, atol=1e-12)
    out = [[np.array(v) for v in DECK(x, t, p_veh, p_deck)]
           for t, x in zip(ts, sol.y.T, strict=True)]
    p2, eta2, R, v2E, a2E, w2E, w2E_dot = out[2]
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
    p2_ref, eta2_ref, R_ref = _deck(sol.y[:, 2], ts[2], d)
    np.testing.assert_allclose(p2.ravel(), p2_ref, atol=1e-12)
    np.testing.assert_allclose(eta2.ravel(), eta2_ref, atol=1e-14)
    np.testing.assert_allclose(R, R_ref, atol=1e-14)
    v_fd, a_fd = _stencil(np.array([o[0].ravel() for o in out]), h)
    np.testing.assert_allclose(v2E.ravel(), v_fd, rtol=1e-7, atol=1e-8)
    np.testing.assert_allclose(a2E.ravel(), a_fd, rtol=1e-7, atol=1e-7)
    R_dot, _ = _stencil(np.array([o[2] for o in out]), h)
    np.testing.assert_allclose(R_dot @ R.T + (R_dot @ R.T).T, 0, atol=1e-8)
    np.testing.assert_allclose(w2E.ravel(), _vee(R_dot @ R.T), rtol=1e-7, atol=1e-8)
    w_dot_fd, _ = _stencil(np.array([o[5].ravel() for o in out]), h)
    np.testing.assert_allclose(w2E_dot.ravel(), w_dot_fd, rtol=1e-7, atol=1e-8)
    if kind == "car":                                       # level deck: yaw rate only
        np.testing.assert_allclose(w2E.ravel(), [0, 0, sol.y[5, 2]], atol=1e-15)
        np.testing.assert_allclose(v2E.ravel()[2], 0, atol=1e-15)


# ---------------------------------------------------------------- the quadrotor

@pytest.mark.parametrize("seed", range(6))
def test_newtons_law_in_E(values, seed):
    """m a_E = R (F_total e_z - Kt V1 + d_F) - m g e_z, with a_E = d/dt (R V1)
    = R (V1_dot + Omega1 x V1); Euler's law with the paper's mixer; p1_dot = R V1."""
    rng = np.random.default_rng(seed)
    pq = QUADROTOR.unpack(values.p_quad)
    m, I, Kt, Kr, g = pq["m1"][0], pq["I"], pq["Kt"], pq["Kr"], pq["g"][0]
    d, c = pq["arm"][0], pq["c"][0]
    x1q, _ = _random_states(rng)
    F = x1q[12:16]                                          # logged rotor forces (states)
    d_F, d_M = rng.normal(size=3) * 2, rng.normal(size=3) * 0.1
    x_dot = _col(QUAD6(x1q, rng.uniform(0, F_MAX, 4), d_F, d_M, values.p_quad, P_ACT))
    R, V, Om = rotation(x1q[3:6]), x1q[6:9], x1q[9:12]
    a_E = R @ (x_dot[6:9] + np.cross(Om, V))
    np.testing.assert_allclose(m * a_E, R @ (np.array([0, 0, F.sum()]) - Kt * V + d_F)
                               - [0, 0, m * g], rtol=1e-12, atol=1e-12)
    M = [d * (F[1] - F[3]), d * (F[2] - F[0]), c * (F[0] - F[1] + F[2] - F[3])]
    np.testing.assert_allclose(I * x_dot[9:12] + np.cross(Om, I * Om), M - Kr * Om + d_M,
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(x_dot[0:3], R @ V, atol=1e-13)


def test_motor_lag_step_and_saturation(values):
    """From rest, a step command gives F = sat(F_cmd) (1 - exp(-t / tau_m)),
    sat clipping to [0, F_max] whatever the command."""
    F_cmd = np.array([-3.0, 2.0, 7.5, 1e6])
    target = np.array([0.0, 2.0, 7.5, F_MAX])
    x0 = np.zeros(16)
    x0[5] = 0.3
    ts = np.linspace(0, 5 * TAU_M, 11)
    sol = solve_ivp(lambda _t, x: _col(QUAD6(x, F_cmd, np.zeros(3), np.zeros(3),
                                             values.p_quad, P_ACT)),
                    (0, ts[-1]), x0, t_eval=ts, method="DOP853", rtol=1e-12, atol=1e-12)
    F = sol.y[12:16].T
    np.testing.assert_allclose(F, target * (1 - np.exp(-ts / TAU_M))[:, None], atol=1e-9)
    assert np.all(F >= 0) and np.all(F <= F_MAX)
    # the lag's rate at any rotor state, for commands on both sides of the range
    for cmd in ([-1e9, -1e-3, 0.0, 4.0], [F_MAX, F_MAX + 1e-3, 1e9, np.inf]):
        x = x0.copy()
        x[12:16] = [1.0, 2.0, 3.0, 4.0]
        F_dot = _col(QUAD6(x, cmd, np.zeros(3), np.zeros(3), values.p_quad, P_ACT))[12:16]
        np.testing.assert_allclose(F_dot, (np.clip(cmd, 0, F_MAX) - x[12:16]) / TAU_M)
    # a NaN command is no command: the motor winds down
    F_dot = _col(QUAD6(x, [np.nan] * 4, np.zeros(3), np.zeros(3), values.p_quad, P_ACT))
    np.testing.assert_allclose(F_dot[12:16], -x[12:16] / TAU_M)


# ---------------------------------------------------------------- touchdown

def _fixed_deck(roll=0.0, pitch=0.0, heave=0.0, pad=(0.0, 0.0, 0.0), height=1.0):
    """A deck held still: zero frequency, phase pi/2, so each sum is its amplitude."""
    vals = {"pad_offset": pad, "deck_height": height}
    for name, a in (("heave", heave), ("roll", roll), ("pitch", pitch)):
        vals[f"{name}_amp"] = [a, 0, 0]
        vals[f"{name}_freq"] = np.zeros(N_DECK)
        vals[f"{name}_phase"] = np.full(N_DECK, np.pi / 2)
    return pack_deck(vals)


def test_gear_gap_level_quadrotor_over_a_tilted_deck(values):
    """By hand: a deck rolled by phi has the normal [0, -sin phi, cos phi], pitched by
    theta [sin theta, 0, cos theta]; the level quadrotor's gear is at p1 - gear e_z."""
    x1q = np.zeros(16)
    x1q[0:3] = [0.8, -0.5, 2.0]
    x1q[5] = 1.1                                            # yaw does not tilt the gear
    xv = np.zeros(6)
    phi, theta, h0, hv = 0.2, -0.15, 1.2, 0.3
    cases = [(_fixed_deck(roll=phi, height=h0),
              -np.sin(phi) * -0.5 + np.cos(phi) * (2.0 - GEAR - h0)),
             (_fixed_deck(pitch=theta, height=h0),
              np.sin(theta) * 0.8 + np.cos(theta) * (2.0 - GEAR - h0)),
             (_fixed_deck(heave=hv, height=h0), 2.0 - GEAR - h0 - hv),
             (_fixed_deck(height=h0, pad=(0.5, 0.2, 0.1)), 2.0 - GEAR - h0 - 0.1)]
    for p_deck, by_hand in cases:
        gap = float(gear_gap(x1q, xv, 7.0, P_ACT, values.p_veh, p_deck))
        assert gap == pytest.approx(by_hand, abs=1e-14)
    # a tilted quadrotor over a level deck: its gear reaches down gear cos(phi1) cos(theta1)
    x1q[3:5] = [0.3, -0.2]
    gap = float(gear_gap(x1q, xv, 7.0, P_ACT, values.p_veh, _fixed_deck(height=h0)))
    assert gap == pytest.approx(2.0 - GEAR * np.cos(0.3) * np.cos(-0.2) - h0, abs=1e-14)


# ---------------------------------------------------------------- plant and outputs

def test_landing_plant_and_outputs(values, rng):
    """The plant's ODE is both bodies' Newton-Euler; its outputs carry the issue's names."""
    p_quad, p_act, p_veh, p_deck = _params(values, rng, "ship")
    pp = LANDING_PLANT_PARAMS.pack(dict(p_quad=p_quad, p_act=p_act, p_veh=p_veh, p_deck=p_deck,
                                        **contact_params()))
    x1q, xv = _random_states(rng)
    xp = LANDING_PLANT_STATE.pack(dict(x1q=x1q, xv=xv, gear=np.zeros(3)))
    F_cmd, w, t = rng.uniform(-1, F_MAX + 1, 4), rng.normal(size=6), 3.0
    xp_dot = _col(landing_plant_function()(xp, F_cmd, w, t, pp))
    pq, pv = QUADROTOR.unpack(p_quad), VEHICLE.unpack(p_veh)
    # far above the deck the gear's forces and memory's rates are exactly zero
    np.testing.assert_allclose(xp_dot, np.concatenate([_quad6(x1q, F_cmd, w[:3], w[3:], pq),
                                                       _vehicle(xv, pv), np.zeros(3)]),
                               rtol=1e-12, atol=1e-12)
    y = LANDING_PLANT_OUTPUTS.unpack(_col(landing_outputs_function()(xp, F_cmd, w, t, pp)))
    names = LANDING_PLANT_OUTPUTS.element_names()
    for required in ("x1 y1 z1 phi1 theta1 psi1 x2 y2 z2 phi2 theta2 psi2 x_e y_e z_e "
                     "F_1 F_2 F_3 F_4 d_Fx d_Fy d_Fz").split():
        assert required in names
    assert len(set(names)) == len(names)
    p2, eta2, _ = _deck(xv, t, DECK_PARAMS.unpack(p_deck))
    p_e, *_ = _relative(x1q, xv, t, DECK_PARAMS.unpack(p_deck))
    np.testing.assert_allclose(y["p1"], x1q[0:3])
    np.testing.assert_allclose(y["p2"], p2, atol=1e-12)
    np.testing.assert_allclose(y["eta2"], eta2, atol=1e-14)
    np.testing.assert_allclose(y["p_e"], p_e, atol=1e-12)
    np.testing.assert_allclose(y["F"], x1q[12:16])
    np.testing.assert_allclose(y["d_F"], w[:3])


def test_a_car_gives_the_papers_relative_altitude_and_rates(values, rng):
    """Zero amplitudes, pad at the reference point: z_e = z1 - deck_height,
    dz_e = J(eta1) V1 and Omega_e = Omega1 - Rr1^-1 [0, 0, r2] (eq. 5)."""
    p_quad, p_act, p_veh, _ = _params(values, rng, "car")
    p_deck = _fixed_deck(height=0.7)
    x1q, xv = _random_states(rng)
    p_e, v_e, eta_e, Omega_e, _ = (_col(v) for v in
                                   REL6(x1q, xv, 2.0, p_quad, p_act, p_veh, p_deck))
    R1 = rotation(x1q[3:6])
    assert p_e[2] == pytest.approx(x1q[2] - 0.7, abs=1e-13)
    assert v_e[2] == pytest.approx(R1[2] @ x1q[6:9], abs=1e-13)
    np.testing.assert_allclose(eta_e, x1q[3:6] - [0, 0, xv[2]], atol=1e-15)
    Rr1 = euler_rate_matrix(*x1q[3:5])
    np.testing.assert_allclose(Omega_e, x1q[9:12] - np.linalg.solve(Rr1, [0, 0, xv[5]]),
                               atol=1e-13)
    assert QUAD6_STATE.size == 16 and LANDING_PLANT_STATE.size == 22 + 3      # + the gear

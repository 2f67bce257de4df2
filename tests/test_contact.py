"""The gear contact (quadland_symbolic.landing.contact) against closed forms.

A small harness integrates the 6-DOF quadrotor (``quadrotor6_rhs``, drag off)
with the contact and lock-down wrench of ``contact_function`` on a deck that
is fixed, tilted or moving as prescribed, by classical RK4 with a fixed step
(CasADi ``mapaccum``). Each check names its closed form:

* a drop on a level deck: the clipped linear spring-damper's restitution
  and peak force (analytic solution of the oscillator, the separation where
  the force returns to zero), without and with gravity;
* an inclined deck: the friction angle, the sliding acceleration
  ``g (sin theta - mu cos theta)`` and the creep of the regularised law;
* tipping: the static angle ``atan(half_track / h_cg)`` about each axis;
* energy with neither damping nor friction (softplus potential in closed
  form through the dilogarithm), continuity, a rolling deck and the lock;
* the Jacobian against central differences; the judging functions.

Steps: 1e-4 s for impacts (0.3 % of the contact's period), 5e-4 s for slow
cases; each is shown converged by halving it in the drop and energy checks.
"""

import functools

import casadi as ca
import numpy as np
import pytest
from reference import NO_AERO
from scipy.optimize import brentq
from scipy.special import spence

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.contact import (
    FOOT,
    GEAR,
    HOLD,
    LOCK,
    N_FEET,
    RK4_REAL_STABILITY,
    contact_function,
    friction_margin_function,
    gear_defaults,
    lock_defaults,
    restitution,
    stiffest_rate,
    tip_over_angles,
    tip_over_function,
)
from quadland_symbolic.landing.deck import DECK_PARAMS, deck_function, pack_deck
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE, quadrotor6_rhs
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE, vehicle_rhs

M, G = 2.0, 9.8                                  # kg, m/s^2
INERTIA = np.array([0.025, 0.025, 0.045])        # kg m^2
GEAR_HEIGHT = 0.2                                # m, the defaults' -z of the feet
NZ = QUAD6_STATE.size + VEHICLE_STATE.size + 1         # [x1q, xv, t]
_PARAMS = (("F_cmd", 4), ("t_signal", 1), ("p_quad", QUADROTOR.size),
           ("p_act", ACTUATOR.size), ("p_veh", VEHICLE.size), ("p_deck", DECK_PARAMS.size),
           ("p_gear", GEAR.size), ("p_lock", LOCK.size))
_SIN = np.pi / 2                                 # the phase that makes a sinusoid a constant


# --- harness -----------------------------------------------------------------

@functools.cache
def _model():
    """RK4 step, right-hand side and signals of ``z = [x1q, xv, t]``."""
    z = ca.SX.sym("z", NZ)
    P = {n: ca.SX.sym(n, s) for n, s in _PARAMS}
    x1q, xv, t = z[:QUAD6_STATE.size], z[QUAD6_STATE.size:NZ - 1], z[NZ - 1]
    d_F, d_M, foot, hold = contact_function()(x1q, xv, t, P["t_signal"], P["p_veh"],
                                              P["p_deck"], P["p_gear"], P["p_lock"])
    z_dot = ca.vertcat(quadrotor6_rhs(x1q, P["F_cmd"], d_F, d_M, P["p_quad"], P["p_act"]),
                       vehicle_rhs(xv, P["p_veh"]), 1)
    p, h = ca.vertcat(*P.values()), ca.SX.sym("h")
    f = ca.Function("f", [z, p], [z_dot])
    k1 = f(z, p)
    k2 = f(z + h / 2 * k1, p)
    k3 = f(z + h / 2 * k2, p)
    k4 = f(z + h * k3, p)
    step = ca.Function("step", [z, p, h], [z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)])
    signals = ca.Function("signals", [z, p], [foot, hold, d_F, d_M])
    return step, f, signals


def simulate(z0, p, h, T):
    """States at ``0, h, .., T`` (columns) by classical RK4."""
    step = _model()[0]
    Z = np.array(step.mapaccum(int(round(T / h)))(z0, p, h))
    return np.hstack([np.reshape(z0, (-1, 1)), Z])


def signals(Z, p):
    """``(foot, hold)`` along a trajectory, each laid out by rows."""
    out = _model()[2].map(Z.shape[1])(Z, p)
    return np.array(out[0]), np.array(out[1])


def total_normal(Z, p):
    return signals(Z, p)[0][FOOT.slice("F_n")].sum(axis=0)


def params(F_cmd=(0.0,) * 4, t_signal=np.inf, gear=None, lock=None, deck=None, veh=None,
           surface="ship_deck"):
    """The harness's parameter vector: 2 kg quadrotor, drag off, a still level deck."""
    quad = dict(m1=M, I=INERTIA, Kt=[0.0] * 3, Kr=[0.0] * 3, g=G, arm=0.25, c=0.05)
    act = dict(motor_time_constant=0.02, F_max=20.0, gear_height=GEAR_HEIGHT, **NO_AERO,
               rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3)
    vehicle = dict(m11=1500.0, m22=1500.0, m33=2500.0, d11=150.0, d22=1500.0, d33=2500.0,
                   tau=[0.0, 0.0, 0.0], z2=0.0)
    vehicle.update(veh or {})
    d = {f"{n}_{w}": np.zeros(3) for n in ("heave", "roll", "pitch")
         for w in ("amp", "freq", "phase")}
    d.update(pad_offset=[0.0, 0.0, 0.0], deck_height=0.0)
    d.update(deck or {})
    g = gear_defaults(surface)
    g.update(gear or {})
    lk = lock_defaults()
    lk.update(lock or {})
    return np.concatenate([np.asarray(F_cmd, float), [t_signal], QUADROTOR.pack(quad),
                           ACTUATOR.pack(act), VEHICLE.pack(vehicle), pack_deck(d),
                           GEAR.pack(g), LOCK.pack(lk)])


def part(p, name):
    """The block ``name`` of a :func:`params` vector."""
    start = 0
    for n, size in _PARAMS:
        if n == name:
            return p[start:start + size]
        start += size
    raise KeyError(name)


def tilted(axis, theta):
    """Deck parameters of a still deck rolled (axis 0) or pitched (axis 1) by theta."""
    name = ("roll", "pitch")[axis]
    return {f"{name}_amp": [theta, 0, 0], f"{name}_phase": [_SIN, 0, 0]}


def state_on_deck(eta2, depth, p2=(0.0, 0.0, 0.0), psi2=0.0, xv=None):
    """The body aligned with the deck, its feet ``depth`` below the deck plane, at rest."""
    z = np.zeros(NZ)
    R = np.array(rotation(ca.DM(eta2)))
    z[0:3] = np.asarray(p2) + R @ np.array([0.0, 0.0, GEAR_HEIGHT - depth])
    z[3:6] = eta2
    xv = np.zeros(VEHICLE_STATE.size) if xv is None else xv
    xv[VEHICLE_STATE.index("psi2")] = psi2
    z[QUAD6_STATE.size:NZ - 1] = xv
    return z


def relative_tilt_deg(Z, R_deck):
    """Angle between the body's z axis and a fixed deck normal, deg, per column."""
    n2 = R_deck[:, 2]
    tilt = [np.arccos(np.clip(np.array(rotation(ca.DM(Z[3:6, i])))[:, 2] @ n2, -1, 1))
            for i in range(Z.shape[1])]
    return np.degrees(tilt)


# --- closed forms (independent of the module) -------------------------------------

def oscillator(v0, K, C, g_eff):
    """The clipped linear oscillator ``M d'' + C d' + K d = M g_eff``, ``d(0) = 0``,
    ``d'(0) = v0`` (d: penetration): functions d(t), d'(t) and the separation time,
    the first t > 0 where ``K d + C d' = 0``."""
    w0, beta = np.sqrt(K / M), C / (2 * M)
    w = np.sqrt(w0 ** 2 - beta ** 2)
    ds = M * g_eff / K
    A, B = -ds, (v0 - beta * ds) / w

    def d(t):
        return ds + np.exp(-beta * t) * (A * np.cos(w * t) + B * np.sin(w * t))

    def d_dot(t):
        e = np.exp(-beta * t)
        return e * ((B * w - beta * A) * np.cos(w * t) - (A * w + beta * B) * np.sin(w * t))

    def force(t):
        return K * d(t) + C * d_dot(t)

    grid = np.linspace(1e-9, 2 * np.pi / w, 4001)
    below = np.flatnonzero(force(grid) < 0)
    assert below.size, "no separation: gravity keeps the feet on the deck"
    return d, d_dot, brentq(force, grid[below[0] - 1], grid[below[0]], xtol=1e-15)


def peak_force(v0, K, C):
    """Largest force of the gravity-free oscillator for zeta < 0.5 (interior maximum)."""
    w0, beta = np.sqrt(K / M), C / (2 * M)
    w = np.sqrt(w0 ** 2 - beta ** 2)
    t = np.arctan2(w * (w ** 2 - 3 * beta ** 2), beta * (3 * w ** 2 - beta ** 2)) / w
    return M * v0 * np.exp(-beta * t) * ((w ** 2 - beta ** 2) / w * np.sin(w * t)
                                         + 2 * beta * np.cos(w * t))


def onset_bound(v0, K, eps):
    """Twice the leading term of the smoothed onset's relative impulse error.

    The softplus spring exceeds ``K max(d, 0)`` by an impulse ``K eps^2 (pi^2/6) / v0``;
    the logistic damper's excess integrates to zero. Relative to ``M v0``:
    ``(pi^2 / 6) (w0 eps / v0)^2`` (docs/contact.md)."""
    return 2 * np.pi ** 2 / 6 * (np.sqrt(K / M) * eps / v0) ** 2


def creep_speed(F_t, F_n, mu, v_eps, b, feet):
    """Steady slip speed of the regularised law when ``feet`` feet share ``F_n`` and
    ``F_t`` equally: ``mu (F_n/feet) v / sqrt(v^2 + v_s^2) = F_t/feet``, solved for v.
    ``feet = N_FEET`` is the least creep for these totals and ``feet = 1`` the most
    (the friction at a given speed is concave in the normal load)."""
    v_s = np.hypot(v_eps, mu * F_n / (feet * b))
    return F_t * v_s / np.sqrt((mu * F_n) ** 2 - F_t ** 2)


def _dilog_neg_exp(x):
    """Li2(-exp(x)) for x <= 0 (scipy's spence(z) is Li2(1 - z))."""
    return spence(1 + np.exp(x))


def softplus_potential(delta, k, eps):
    """``k * integral of eps softplus(s / eps) ds`` from -inf to delta, J."""
    x = delta / eps
    ax = np.abs(x)
    inner = np.where(x > 0, x ** 2 / 2 + np.pi ** 2 / 6 + _dilog_neg_exp(-ax),
                     -_dilog_neg_exp(-ax))
    return k * eps ** 2 * inner


# --- drops on a level deck -------------------------------------------------------

def _drop(zeta, v0, h, gear=None, thrust=True):
    g = gear_defaults()
    g.update(gear or {})
    K = N_FEET * g["k"]
    g["c"] = 2 * zeta * np.sqrt(K * M) / N_FEET
    p = params(F_cmd=[M * G / N_FEET] * 4 if thrust else [0.0] * 4, gear=g)
    eps = g["delta_eps"]
    z0 = np.zeros(NZ)
    z0[2] = GEAR_HEIGHT + 30 * eps               # feet clear of the smoothed onset
    z0[8] = -v0
    z0[12:16] = M * G / N_FEET if thrust else 0.0
    return simulate(z0, p, h, 0.1 + 30 * eps / v0), p, K, N_FEET * g["c"], eps


@pytest.mark.parametrize("zeta", [0.1, 0.3, 0.6])
@pytest.mark.parametrize("height", [0.05, 0.2, 0.5])
def test_drop_rebounds_with_the_clipped_oscillators_restitution(zeta, height):
    # Rotors at the weight: the contact is gravity-free, so the rebound over the
    # impact speed is the oscillator's e, whatever the drop height (v0 = sqrt(2 g h)).
    v0 = np.sqrt(2 * G * height)
    Z, p, K, C, eps = _drop(zeta, v0, 1e-4)
    d, d_dot, t_c = oscillator(v0, K, C, 0.0)
    e_closed = -d_dot(t_c) / v0
    assert restitution(zeta) == pytest.approx(e_closed, rel=1e-12)
    assert Z[8, -1] / v0 == pytest.approx(e_closed, abs=onset_bound(v0, K, eps))
    assert np.abs(Z[[6, 7, 9, 10, 11], -1]).max() < 1e-9       # level: no slip, no spin


@pytest.mark.parametrize("zeta", [0.1, 0.3])
@pytest.mark.parametrize("height", [0.05, 0.5])
def test_drop_peak_gear_load_is_the_oscillators(zeta, height):
    v0 = np.sqrt(2 * G * height)
    Z, p, K, C, eps = _drop(zeta, v0, 1e-4)
    assert total_normal(Z, p).max() == pytest.approx(peak_force(v0, K, C),
                                                     rel=onset_bound(v0, K, eps))


def test_drop_is_converged_in_the_step_and_second_order_in_the_onset():
    v0, zeta = 1.0, 0.3
    e = {h: _drop(zeta, v0, h)[0][8, -1] / v0 for h in (1e-4, 5e-5)}
    _, _, K, C, eps = _drop(zeta, v0, 1e-4)
    assert abs(e[1e-4] - e[5e-5]) < 0.05 * onset_bound(v0, K, eps)
    e_closed = restitution(zeta)
    # A 4x wider onset: the error grows about 16x (second order), not 4x.
    wide = _drop(zeta, v0, 5e-5, gear=dict(delta_eps=4 * eps))[0][8, -1] / v0
    assert abs(wide - e_closed) > 8 * abs(e[5e-5] - e_closed)


@pytest.mark.parametrize("height", [0.05, 0.3])
def test_free_drop_bounces_to_the_height_of_the_oscillator_with_gravity(height):
    # Rotors off: a fall from ``height``, contact under gravity (the rebound then
    # depends on v0), a free flight to the apex.
    zeta, h = 0.3, 1e-4
    g = gear_defaults()
    K = N_FEET * g["k"]
    g["c"] = 2 * zeta * np.sqrt(K * M) / N_FEET
    p = params(gear=g)
    z0 = np.zeros(NZ)
    z0[2] = GEAR_HEIGHT + height
    v0 = np.sqrt(2 * G * height)
    Z = simulate(z0, p, h, np.sqrt(2 * height / G) + 0.25)
    d, d_dot, t_c = oscillator(v0, K, N_FEET * g["c"], G)
    apex = d_dot(t_c) ** 2 / (2 * G) - d(t_c)
    after = Z[2, np.argmin(Z[2]):]
    e_sim = np.sqrt(2 * G * (after.max() - GEAR_HEIGHT)) / v0
    assert e_sim == pytest.approx(np.sqrt(2 * G * apex) / v0,
                                  abs=onset_bound(v0, K, g["delta_eps"]))


# --- inclined deck: friction ------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("axis", [0, 1])
def test_above_the_friction_angle_the_body_slides_at_g_sin_minus_mu_cos(axis):
    mu, theta, h = 0.3, np.radians(25.0), 5e-4
    eta2 = np.array([0.0, 0.0, 0.7])
    eta2[axis] = theta
    p = params(gear=dict(mu=mu), deck=tilted(axis, theta))
    g = gear_defaults()
    Z = simulate(state_on_deck(eta2, M * G * np.cos(theta) / (N_FEET * g["k"]), psi2=0.7),
                 p, h, 1.5)
    n2 = np.array(rotation(ca.DM(eta2)))[:, 2]
    down = -(np.array([0, 0, 1.0]) - n2[2] * n2)
    down /= np.linalg.norm(down)
    t = np.arange(Z.shape[1]) * h
    v = np.array([np.array(rotation(ca.DM(Z[3:6, i]))) @ Z[6:9, i] for i in range(len(t))])
    window = t >= 0.5
    a_sim = np.polyfit(t[window], v[window] @ down, 1)[0]
    a_closed = G * (np.sin(theta) - mu * np.cos(theta))
    # Regularisation: the friction falls short of mu F_n by at most
    # mu F_n (1 - v / sqrt(v^2 + v_s^2)) <= mu F_n v_s^2 / (2 v^2), v_s at the whole load.
    v_s = np.hypot(g["v_eps"], mu * M * G * np.cos(theta) / g["b_slip"])
    v_min = a_closed * 0.5 * 0.9
    bound = mu * G * np.cos(theta) * v_s ** 2 / (2 * v_min ** 2)
    assert a_sim == pytest.approx(a_closed, abs=bound)


@pytest.mark.parametrize("axis", [0, 1])
def test_below_the_friction_angle_the_body_only_creeps_as_regularised(axis):
    mu, theta, h = 0.3, np.radians(10.0), 5e-4
    eta2 = np.zeros(3)
    eta2[axis] = theta
    p = params(gear=dict(mu=mu), deck=tilted(axis, theta))
    g = gear_defaults()
    Z = simulate(state_on_deck(eta2, M * G * np.cos(theta) / (N_FEET * g["k"])), p, h, 1.0)
    tail = slice(int(0.8 / h), None)
    speed = np.linalg.norm(Z[6:9, tail], axis=0)                   # body frame = deck frame
    F_n, F_t = M * G * np.cos(theta), M * G * np.sin(theta)
    args = (F_n, mu, g["v_eps"], g["b_slip"])
    least, most = creep_speed(F_t, *args, feet=N_FEET), creep_speed(F_t, *args, feet=1)
    assert np.tan(theta) < mu
    assert least * 0.99 <= speed.min() and speed.max() <= most
    assert np.ptp(speed) < 0.01 * least                        # steady
    assert np.abs(Z[9:12, tail]).max() < 1e-3                 # no spin, no rocking


# --- tipping ------------------------------------------------------------------------

@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("offset_deg", [-1.0, 1.0])
def test_tips_over_beyond_the_static_angle_and_stays_below_it(axis, offset_deg):
    # Friction enough not to slide (mu = 1.5 > tan 38 deg). Heavily damped feet
    # (c = 200 N s/m) settle without overshoot onto the static equilibrium: lightly
    # damped ones rock past it and tip below the static angle, a dynamic effect.
    h = 5e-4
    angle = np.array(tip_over_function()(GEAR.pack(gear_defaults()))[axis]).item()
    theta = angle + np.radians(offset_deg)
    eta2 = np.zeros(3)
    eta2[axis] = theta
    g = dict(mu=1.5, c=200.0)
    p = params(gear=g, deck=tilted(axis, theta))
    Z = simulate(state_on_deck(eta2, M * G * np.cos(theta) / (N_FEET * 5000.0)), p, h, 2.0)
    tilt = relative_tilt_deg(Z[:, ::20], np.array(rotation(ca.DM(eta2))))
    if offset_deg < 0:
        assert tilt.max() < 1.0                  # the gear's compliance only
    else:
        assert tilt.max() > 60.0                 # rolled over


def test_tip_over_angles_are_atan_half_track_over_height():
    roll, pitch = (np.array(a).item() for a in tip_over_function()(GEAR.pack(gear_defaults())))
    assert roll == pytest.approx(np.arctan(0.125 / 0.2), rel=1e-14)
    assert pitch == pytest.approx(np.arctan(0.15 / 0.2), rel=1e-14)
    g = gear_defaults()
    g["r_feet"] = [0.3, 0.2, -0.25, -0.1, 0.2, -0.25, -0.1, -0.05, -0.25, 0.3, -0.05, -0.25]
    a = np.array(tip_over_angles(ca.DM(GEAR.pack(g)))).ravel()
    np.testing.assert_allclose(a, np.arctan([0.05 / 0.25, 0.1 / 0.25]), rtol=1e-14)


# --- energy, continuity, a rolling deck, the lock ------------------------------------

def test_no_energy_is_created_without_damping_or_friction():
    # A still deck rolled 10 deg and pitched 0.1 rad; the body falls tilted and
    # spinning, so the feet strike one after another. Energy: kinetic, gravity and
    # the feet's softplus potential.
    eps = gear_defaults()["delta_eps"]
    eta2 = np.array([np.radians(10.0), 0.1, 0.3])
    deck = {"roll_amp": [eta2[0], 0, 0], "roll_phase": [_SIN, 0, 0],
            "pitch_amp": [eta2[1], 0, 0], "pitch_phase": [_SIN, 0, 0]}
    p = params(gear=dict(c=0.0, mu=0.0), deck=deck)
    z0 = state_on_deck(eta2, -0.05, psi2=0.3)
    z0[3:5] += [0.05, -0.03]
    z0[6:12] = [0.2, -0.1, -0.5, 0.5, -0.8, 1.0]
    drift = {}
    for h in (2e-4, 1e-4):
        Z = simulate(z0, p, h, 0.6)
        delta = signals(Z, p)[0][FOOT.slice("delta")]
        assert delta.max() > 100 * eps                         # a real bounce
        spring = softplus_potential(delta, 5000.0, eps).sum(axis=0)
        E = (0.5 * M * np.sum(Z[6:9] ** 2, axis=0) + 0.5 * INERTIA @ Z[9:12] ** 2
             + M * G * Z[2] + spring)
        drift[h] = np.abs(E - E[0]).max() / spring.max()       # of what the feet store
    assert drift[1e-4] < 1e-6
    assert drift[2e-4] > 8 * drift[1e-4]                       # RK4's error, not the model's


def test_forces_are_continuous_across_the_onset_and_the_clip():
    # At the first foot's onset (delta = 0), where the clip may also act: the wrench
    # moves by no more than a Lipschitz bound times the displacement.
    f = contact_function()
    p = params()
    g = gear_defaults()
    feet = np.reshape(g["r_feet"], (N_FEET, 3))
    rng = np.random.default_rng(18)
    dz = 1e-9
    for _ in range(20):
        z = np.zeros(QUAD6_STATE.size)
        z[3:6] = rng.normal(0, 0.05, 3)
        z[6:12] = rng.normal(0, 0.5, 6)
        R1 = np.array(rotation(ca.DM(z[3:6])))
        forces = []
        for shift in (-dz, 0.0, dz):
            z[2] = -min(R1[2] @ r for r in feet) + shift
            out = f(z, np.zeros(6), 0.0, np.inf, *(part(p, n) for n in
                                                   ("p_veh", "p_deck", "p_gear", "p_lock")))
            forces.append(np.concatenate([np.array(out[0]).ravel(), np.array(out[1]).ravel()]))
        # d F_n / d delta <= k + c |delta_dot| max(sigma') / eps, sigma' <= 1/4; friction
        # adds mu of it; arms below 0.3 m; four feet.
        rate = np.linalg.norm(z[6:9]) + 0.3 * np.linalg.norm(z[9:12])
        lipschitz = N_FEET * (1 + g["mu"]) * (g["k"] + g["c"] * rate / (4 * g["delta_eps"]))
        assert np.isfinite(forces).all()
        assert np.abs(np.diff(forces, axis=0)).max() <= lipschitz * dz


def _rolling_deck(roll_amp):
    """A deck rolling ``roll_amp`` at 0.25 Hz, pitching and heaving, on a vehicle at
    3 m/s; the pad 1 m forward and 0.3 m above the roll centre."""
    deck = {"roll_amp": [roll_amp, 0, 0], "roll_freq": [2 * np.pi / 4, 0, 0],
            "pitch_amp": [np.radians(3.0), 0, 0], "pitch_freq": [1.3, 0, 0],
            "pitch_phase": [0.4, 0, 0], "heave_amp": [0.3, 0, 0], "heave_freq": [0.9, 0, 0],
            "pad_offset": [1.0, 0.0, 0.3], "deck_height": 2.0}
    veh = dict(tau=[150.0 * 3.0, 0.0, 0.0])
    xv = np.zeros(VEHICLE_STATE.size)
    xv[VEHICLE_STATE.index("u2")] = 3.0
    return deck, veh, xv


def _on_moving_deck(p, xv, depth):
    """The body on the pad at t = 0, moving with the deck's material point."""
    pv, pd = (part(p, n) for n in ("p_veh", "p_deck"))
    deck = [np.array(v) for v in deck_function()(xv, 0.0, pv, pd)]
    p2, eta2, R, v2E, w2E = deck[0].ravel(), deck[1].ravel(), deck[2], deck[3].ravel(), \
        deck[5].ravel()
    z = state_on_deck(eta2, depth, p2=p2, psi2=eta2[2], xv=xv.copy())
    r = z[0:3] - p2
    z[6:9] = R.T @ (v2E + np.cross(w2E, r))
    z[9:12] = R.T @ w2E
    return z, deck_function(), pv, pd


def _deck_bounds(pv, pd, xv, T, r_body):
    """Largest acceleration of the deck point at the body's centre and the deck's tilt."""
    a, tilt = [], []
    for t in np.linspace(0.0, T, 401):
        xv_t = xv.copy()
        xv_t[VEHICLE_STATE.index("x2")] = 3.0 * t
        _, eta2, R, _, a2E, w2E, w2E_dot = (np.array(v) for v in deck_function()(xv_t, t, pv, pd))
        r = R @ r_body
        a.append(np.linalg.norm(a2E.ravel() + np.cross(w2E_dot.ravel(), r)
                                + np.cross(w2E.ravel(), np.cross(w2E.ravel(), r))))
        tilt.append(np.arccos(R[2, 2]))
    return max(a), max(tilt)


@pytest.mark.slow
def test_rolling_deck_forces_stay_finite_and_bounded_and_the_body_stays():
    h, T = 2.5e-4, 2.0
    deck, veh, xv = _rolling_deck(np.radians(8.0))
    p = params(deck=deck, veh=veh)
    z0, _, pv, pd = _on_moving_deck(p, xv, M * G / (N_FEET * 5000.0))
    Z = simulate(z0, p, h, T)
    foot, _ = signals(Z, p)
    assert np.isfinite(Z).all() and np.isfinite(foot).all()
    a_max, tilt_max = _deck_bounds(pv, pd, xv, T, np.array([0.0, 0.0, GEAR_HEIGHT]))
    # A suddenly applied load on an undamped spring peaks at twice its static value.
    assert foot[FOOT.slice("F_n")].sum(axis=0).max() < 2 * M * (G + a_max)
    assert foot[FOOT.slice("in_contact")].min() == 1.0        # all four feet, all along
    # Below the friction and tip-over angles: the feet creep at most as regularised.
    g = gear_defaults()
    F_t, F_n = M * (G * np.sin(tilt_max) + a_max), M * (G * np.cos(tilt_max) - a_max)
    v_most = creep_speed(F_t, F_n, g["mu"], g["v_eps"], g["b_slip"], feet=1)
    assert foot[FOOT.slice("slip")].max() < v_most
    # Halving the step changes the force history by far less than the weight.
    Z2 = simulate(z0, p, h / 2, T)
    diff = total_normal(Z, p) - total_normal(Z2[:, ::2], p)
    assert np.abs(diff).max() < 1e-3 * M * G


@pytest.mark.slow
@pytest.mark.parametrize("locked", [False, True])
def test_lock_down_holds_the_body_on_a_deck_rolling_beyond_the_tip_over_angle(locked):
    h, T, roll = 5e-4, 2.0, np.radians(40.0)
    lk = lock_defaults()
    deck, veh, xv = _rolling_deck(roll)
    p = params(deck=deck, veh=veh, t_signal=-3.0 if locked else np.inf)   # long engaged
    depth = (M * G + (lk["F_hold"] if locked else 0.0)) / (N_FEET * 5000.0)
    z0, _, pv, pd = _on_moving_deck(p, xv, depth)
    Z = simulate(z0, p, h, T)
    foot, hold = signals(Z, p)
    a_max, tilt_max = _deck_bounds(pv, pd, xv, T, np.array([0.0, 0.0, GEAR_HEIGHT]))
    assert tilt_max > np.array(tip_over_function()(GEAR.pack(gear_defaults()))[0]).item()
    # The gear centre's motion in the deck frame, from its first place.
    R = [np.array(v) for v in deck_function().map(Z.shape[1])(
        Z[QUAD6_STATE.size:NZ - 1], Z[NZ - 1], pv, pd)]
    p2, R_deck = R[0], R[2].reshape(3, 3, -1, order="F")
    centre = np.array([Z[0:3, i] + np.array(rotation(ca.DM(Z[3:6, i]))) @ [0, 0, -GEAR_HEIGHT]
                       for i in range(Z.shape[1])]).T
    rel = np.einsum("jin,jn->in", R_deck, centre - p2)
    moved = np.linalg.norm(rel - rel[:, :1], axis=0).max()
    R1 = [np.array(rotation(ca.DM(Z[3:6, i]))) for i in range(0, Z.shape[1], 20)]
    tilt = np.degrees([np.arccos(np.clip(R1[j][:, 2] @ R_deck[:, 2, 20 * j], -1, 1))
                       for j in range(len(R1))])
    if not locked:
        assert tilt.max() > 30.0 or moved > 0.3                # tips or slides away
        return
    assert hold[HOLD.slice("engaged")].min() > 1 - 1e-6
    g = gear_defaults()
    F_t = M * (G * np.sin(tilt_max) + a_max)
    F_n = M * (G * np.cos(tilt_max) - a_max) + lk["F_hold"] / (1 + 0.0) ** 2
    v_most = creep_speed(F_t, F_n, g["mu"], g["v_eps"], g["b_slip"], feet=1)
    assert moved < v_most * T
    # The gear's compliance: the tangential load F_t at the centre's height moves
    # F_t h / (2 a) from the uphill to the downhill pair of feet (a the half-track),
    # rolling the body by F_t h / (4 a^2 k); twice that for a suddenly applied load.
    a = 0.125
    assert tilt.max() < np.degrees(2 * F_t * GEAR_HEIGHT / (4 * a ** 2 * g["k"]))


def test_lock_engages_after_its_delay_with_a_first_order_rise():
    f = contact_function()
    lk = lock_defaults()
    p = params()
    pv, pd, pg, pl = (part(p, n) for n in ("p_veh", "p_deck", "p_gear", "p_lock"))
    z = np.zeros(QUAD6_STATE.size)
    gap = 5e-3                                                 # 50 eps: feet clear
    z[2] = GEAR_HEIGHT + gap
    for t_signal, t in ((np.inf, 5.0), (np.nan, 5.0), (1.0, 1.2), (1.0, 1.25), (1.0, 1.6)):
        out = f(z, np.zeros(6), t, t_signal, pv, pd, pg, pl)
        hold = HOLD.unpack(np.array(out[3]).ravel())
        age = max(t - t_signal - lk["lock_delay"], 0.0) if np.isfinite(t_signal) else 0.0
        s = 1 - np.exp(-age / lk["lock_rise_time"])
        assert hold["engaged"].item() == pytest.approx(s, abs=1e-15)
        assert hold["F_lock"].item() == pytest.approx(
            lk["F_hold"] * s / (1 + gap / lk["lock_gap_scale"]) ** 2, rel=1e-12, abs=1e-15)
        np.testing.assert_allclose(np.array(out[0]).ravel(), [0, 0, -hold["F_lock"].item()],
                                   atol=1e-12)
        np.testing.assert_allclose(np.array(out[1]).ravel(), 0.0, atol=1e-12)


# --- Jacobian, judging functions -------------------------------------------------

def test_jacobian_matches_central_differences_where_the_model_is_smooth():
    f = contact_function()
    deck, veh, xv = _rolling_deck(np.radians(8.0))
    p = params(deck=deck, veh=veh, t_signal=-0.3)
    z, _, pv, pd = _on_moving_deck(p, xv, 2e-3)
    z[6:12] += [0.05, -0.04, 0.01, 0.2, -0.1, 0.3]            # slipping, rocking
    pg, pl = (part(p, n) for n in ("p_gear", "p_lock"))
    x1q, xvs, t = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), ca.SX.sym("t")
    keep = [i for i in range(FOOT.size) if not FOOT.element_names()[i].startswith("in_")]
    d_F, d_M, foot, hold = f(x1q, xvs, t, -0.3, pv, pd, pg, pl)
    y = ca.vertcat(d_F, d_M, foot[keep], hold)
    x = ca.vertcat(x1q, xvs, t)
    fn = ca.Function("y", [x], [y, ca.jacobian(y, x)])
    x0 = np.concatenate([z[:QUAD6_STATE.size], z[QUAD6_STATE.size:NZ - 1], [0.0]])
    foot0 = FOOT.unpack(np.array(f(x0[:16], x0[16:22], 0.0, -0.3, pv, pd, pg, pl)[2]).ravel())
    assert foot0["in_contact"].min() == 1.0 and foot0["slip"].min() > 0.01
    J = np.array(fn(x0)[1])
    # At rest on a still deck (zero slip, exactly) the wrench's Jacobian is finite too.
    still = params()
    wrench = ca.vertcat(*f(x1q, xvs, t, np.inf, *(part(still, n) for n in
                                                 ("p_veh", "p_deck", "p_gear", "p_lock")))[:2])
    rest = state_on_deck(np.zeros(3), 2e-3)
    assert np.isfinite(np.array(ca.Function("rest", [x], [ca.jacobian(wrench, x)])(rest))).all()
    step = 1e-6
    J_fd = np.column_stack([(np.array(fn(x0 + step * e)[0]) - np.array(fn(x0 - step * e)[0]))
                            .ravel() / (2 * step) for e in np.eye(x0.size)])
    scale = np.abs(J).max(axis=1, keepdims=True) + 1.0
    assert (np.abs(J - J_fd) / scale).max() < 1e-6


@pytest.mark.parametrize("theta_deg", [5.0, 20.0])
def test_friction_margin_on_a_still_tilted_deck(theta_deg):
    theta = np.radians(theta_deg)
    p = params(deck=tilted(0, theta))
    pq, pv, pd, pg = (part(p, n) for n in ("p_quad", "p_veh", "p_deck", "p_gear"))
    mu = gear_defaults()["mu"]
    z = state_on_deck(np.array([theta, 0, 0]), 0.0)
    f = friction_margin_function()
    n2 = np.array([0.0, -np.sin(theta), np.cos(theta)])

    def margin(F_other):
        return float(f(z[:16], z[16:22], 0.0, F_other, pq, pv, pd, pg))

    assert margin(np.zeros(3)) == pytest.approx(np.tan(theta) / mu, rel=1e-12)
    F_lock, T = 50.0, 8.0
    assert margin(-F_lock * n2) == pytest.approx(
        M * G * np.sin(theta) / (mu * (M * G * np.cos(theta) + F_lock)), rel=1e-12)
    assert margin(T * n2) == pytest.approx(
        M * G * np.sin(theta) / (mu * (M * G * np.cos(theta) - T)), rel=1e-12)
    assert margin(np.array([0, 0, 2 * M * G])) == np.inf     # lifting off


def test_friction_margin_on_an_accelerating_level_deck():
    tau_x, m11 = 3000.0, 1500.0
    p = params(veh=dict(tau=[tau_x, 0.0, 0.0], m11=m11))
    pq, pv, pd, pg = (part(p, n) for n in ("p_quad", "p_veh", "p_deck", "p_gear"))
    z = state_on_deck(np.zeros(3), 0.0)
    m = float(friction_margin_function()(z[:16], z[16:22], 0.0, np.zeros(3), pq, pv, pd, pg))
    assert m == pytest.approx(tau_x / m11 / (gear_defaults()["mu"] * G), rel=1e-12)


def test_stiffest_rate_sets_rk4s_largest_stable_step():
    # Resting on a level deck with the lock on, every foot's friction slope is at its
    # cap b_slip: the rate is the largest eigenvalue of the numerical Jacobian, and RK4
    # settles just below RK4_REAL_STABILITY / rate and chatters just above it.
    p = params(t_signal=-10.0)
    rate = float(stiffest_rate(ca.DM(part(p, "p_quad")), ca.DM(part(p, "p_gear"))))
    z0 = state_on_deck(np.zeros(3), (M * G + lock_defaults()["F_hold"]) / (N_FEET * 5000.0))
    z0[6] = 0.05
    Z = simulate(z0, p, 1e-4, 1.0)
    z = ca.SX.sym("z", NZ)
    jac = ca.Function("rhs_jacobian", [z], [ca.jacobian(_model()[1](z, p), z)])
    eig = np.linalg.eigvals(np.array(jac(Z[:, -1]))[:12, :12])
    assert np.abs(eig).max() == pytest.approx(rate, rel=0.05)
    h_max = RK4_REAL_STABILITY / np.abs(eig.real).max()
    residual = {f: np.abs(simulate(z0, p, f * h_max, 1.5)[6:12, -1]).max() for f in (0.9, 1.2)}
    assert residual[0.9] < 1e-6 and residual[1.2] > 1e-3


def test_defaults_and_layouts():
    assert GEAR.pack(gear_defaults("car_roof")).size == GEAR.size
    assert LOCK.pack(lock_defaults("magnet")).size == LOCK.size
    for bad, fn in (("ice", gear_defaults), ("rope", lock_defaults)):
        with pytest.raises(ValueError, match="must be one of"):
            fn(bad)
    g = gear_defaults()
    zeta = N_FEET * g["c"] / (2 * np.sqrt(N_FEET * g["k"] * M))
    assert zeta == pytest.approx(0.3, rel=0.01)               # the documented damping ratio
    f = contact_function()
    assert f.name_in() == ["x1q", "xv", "t", "t_signal", "p_veh", "p_deck", "p_gear", "p_lock"]
    assert f.name_out() == ["d_F", "d_M", "foot", "hold"]
    assert f.size1_out(2) == FOOT.size and f.size1_out(3) == HOLD.size


# --- the report's gear signals: what holds a body resting on a moving roof ------------

def _resting_on_a_car(V, Kt, Kq, lock, wind=(0.0, 0.0, 0.0)):
    """``gear_signals`` (quadland_symbolic.landing.gear) of the body resting level, at
    its static deflection, on a level roof driving straight at a steady ``V`` m/s
    (``d11 V`` holds it) through the ``wind`` (E, m/s; still air by default), rotors
    off, long after the contact switch closed (lock fully engaged if there is one)."""
    from quadland_symbolic.landing.gear import GEAR_SIGNALS, GEAR_STATE, gear_signals_function
    veh = dict(tau=[150.0 * V, 0.0, 0.0])
    p = params(gear=dict(mu=0.5), lock=lock, veh=veh)
    xv = np.zeros(VEHICLE_STATE.size)
    xv[VEHICLE_STATE.index("u2")] = V
    z = state_on_deck(np.zeros(3), M * G / (N_FEET * gear_defaults()["k"]), xv=xv)
    z[6] = V                                                    # V1: moving with the roof
    quad = dict(m1=M, I=INERTIA, Kt=[Kt] * 3, Kr=[0.0] * 3, g=G, arm=0.25, c=0.05)
    act = dict(motor_time_constant=0.02, F_max=20.0, gear_height=GEAR_HEIGHT,
               drag_quadratic=[Kq] * 3, rotor_radius=0.0, air_density=1.225,
               rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3)
    t = 100.0
    xg = GEAR_STATE.pack(dict(impulse=t, t_contact=t, F_peak=M * G))
    s = gear_signals_function()(z[:QUAD6_STATE.size], xv, xg, t, np.asarray(wind, dtype=float),
                                QUADROTOR.pack(quad),
                                ACTUATOR.pack(act), part(p, "p_veh"), part(p, "p_deck"),
                                part(p, "p_gear"), part(p, "p_lock"))
    return GEAR_SIGNALS.unpack(np.array(s).ravel())


def test_the_friction_margin_of_a_body_on_a_car_roof_carries_the_drag():
    # Resting level on the roof at 100 km/h, the still air's drag Kt V + Kq V^2 (the
    # shipped 0.3 and 0.01225: 17.8 N) is all the feet must hold against mu m g: the
    # margin is (Kt V + Kq V^2) / (mu m g) = 1.82, not 0 (the drag left out, a body
    # sliding off the roof was "resting with a friction margin").
    V, Kt, Kq, mu = 100 / 3.6, 0.3, 0.01225, 0.5
    s = _resting_on_a_car(V, Kt, Kq, dict(F_hold=0.0))
    drag = Kt * V + Kq * V ** 2
    assert s["friction_margin"] == pytest.approx(drag / (mu * M * G), rel=1e-12)
    assert s["friction_margin"] > 1
    # no device: nothing is engaged, however long the switch has been closed
    assert s["engaged"] == 0.0 and s["F_lock"] == 0.0
    # a magnet engaged at the deck: its pull F_lock joins the weight on the feet
    held = _resting_on_a_car(V, Kt, Kq, dict(F_hold=100.0))
    assert held["engaged"] == pytest.approx(1.0, abs=1e-12)
    assert held["friction_margin"] == pytest.approx(
        drag / (mu * (M * G + held["F_lock"])), rel=1e-12)
    # in still air on a still roof the margin is 0
    assert _resting_on_a_car(0.0, Kt, Kq, dict(F_hold=0.0))["friction_margin"] == \
        pytest.approx(0.0, abs=1e-9)


def test_the_friction_margin_carries_the_wind_s_force_on_the_resting_body():
    # issue 18's review: the wind, a disturbance input, was left out of the margin. The
    # plant's drag acts on the airspeed V1 - R1^T v_wind, per body axis -Kt V - Kq V |V|:
    # resting level (R1 = I), the feet must hold Kt w + Kq w^2 per axis of wind w.
    Kt, Kq, mu = 0.3, 0.01225, 0.5
    none = dict(F_hold=0.0)

    def force(v):                                   # one axis's drag magnitude, N
        return Kt * abs(v) + Kq * v ** 2

    # a still deck in a 10 m/s wind along x: 3 + 1.225 = 4.225 N of mu m g = 9.8 N
    s = _resting_on_a_car(0.0, Kt, Kq, none, wind=(10.0, 0.0, 0.0))
    assert s["friction_margin"] == pytest.approx(force(10.0) / (mu * M * G), rel=1e-12)
    # 20 m/s: 6 + 4.9 = 10.9 N, more than mu m g: a body with no lock is not held (the
    # still air's margin, before, was 0 and read it secured)
    gale = _resting_on_a_car(0.0, Kt, Kq, none, wind=(20.0, 0.0, 0.0))
    assert gale["friction_margin"] == pytest.approx(force(20.0) / (mu * M * G), rel=1e-12)
    assert gale["friction_margin"] > 1
    # on the roof at 100 km/h with a tailwind of the car's speed the airspeed is zero
    V = 100 / 3.6
    assert _resting_on_a_car(V, Kt, Kq, none, wind=(V, 0.0, 0.0))["friction_margin"] == \
        pytest.approx(0.0, abs=1e-9)
    # and in a 5 m/s crosswind (+y) the airspeed is (V, -5): the two axes' drags add as
    # a vector, hypot(Kt V + Kq V^2, Kt 5 + Kq 25)
    cross = _resting_on_a_car(V, Kt, Kq, none, wind=(0.0, 5.0, 0.0))
    assert cross["friction_margin"] == pytest.approx(
        np.hypot(force(V), force(5.0)) / (mu * M * G), rel=1e-12)


def test_the_farthest_foot_s_offset_from_the_pad_centre():
    # the body resting level with its centre at (0.3, 0.1) from the pad centre: the feet
    # at (+-0.15, +-0.125) put the farthest at (0.45, 0.225), hypot 0.5031 m, past a
    # 0.5 m pad that the centre (0.316 m) is well inside
    from quadland_symbolic.landing.gear import GEAR_SIGNALS, GEAR_STATE, gear_signals_function
    g = gear_defaults()
    feet = np.asarray(g["r_feet"], dtype=float).reshape(-1, 3)
    assert np.allclose(np.abs(feet[:, :2]), [0.15, 0.125])
    p = params()
    for centre, yaw, want in (((0.3, 0.1), 0.0, np.hypot(0.45, 0.225)),
                              ((0.3, 0.1), np.pi / 2, np.hypot(0.425, 0.25)),
                              ((0.0, 0.0), 0.3, np.hypot(0.15, 0.125))):
        z = state_on_deck(np.zeros(3), 0.001, p2=(*centre, 0.0))
        z[5] = yaw
        s = gear_signals_function()(z[:QUAD6_STATE.size], z[QUAD6_STATE.size:NZ - 1],
                                    GEAR_STATE.zeros(), 0.0, np.zeros(3), part(p, "p_quad"),
                                    part(p, "p_act"), part(p, "p_veh"), part(p, "p_deck"),
                                    part(p, "p_gear"), part(p, "p_lock"))
        off = GEAR_SIGNALS.unpack(np.array(s).ravel())["foot_offset"]
        assert off == pytest.approx(want, rel=1e-12), (centre, yaw)


@pytest.mark.parametrize("pitch_deg,tips", [(32.0, False), (33.5, True)])
def test_a_body_on_its_corner_tips_where_its_centre_leaves_the_support_rectangle(pitch_deg,
                                                                                 tips):
    # At rest on its lowest foot on a still level deck, rotors off, roll 30 deg and pitch
    # (ZYX) as given: the centre's projection along the deck normal onto the feet's plane
    # is at x = h_cg tan(pitch) / cos(roll), y = h_cg tan(roll) = 0.115 m (within 0.125):
    # 0.144 m at 32 deg, within the feet's 0.15 m, and it falls back onto its feet; 0.153 m
    # at 33.5 deg, past them, and it goes over (the boundary, 33.0 deg, below the pure
    # pitch's 36.87 deg). Friction enough not to slide, feet damped as in the tip test.
    ph, th = np.radians(30.0), np.radians(pitch_deg)
    x = GEAR_HEIGHT * np.tan(th) / np.cos(ph)
    assert bool(x > 0.15) is tips and GEAR_HEIGHT * np.tan(ph) < 0.125
    R = np.array(rotation(ca.DM([ph, th, 0.0])))
    feet = np.asarray(gear_defaults()["r_feet"], dtype=float).reshape(-1, 3).T
    z = np.zeros(NZ)
    z[3:5] = ph, th
    z[2] = -(R @ feet)[2].min() - 0.0005
    Z = simulate(z, params(gear=dict(mu=1.5, c=200.0)), 5e-4, 1.5)
    tilt = relative_tilt_deg(Z[:, ::20], np.eye(3))
    assert bool(tilt[-1] > 90.0) is tips and bool(tilt[-1] < 1.0) is not tips

def _tip_margin_on_a_still_deck(roll: float, pitch: float) -> float:
    """The gear signals' ``tip_margin`` of the body 1 mm above a still level deck at
    ``roll``, ``pitch`` (rad, ZYX), rotors and wind at zero."""
    from quadland_symbolic.landing.gear import GEAR_SIGNALS, GEAR_STATE, gear_signals_function
    p = params()
    z = state_on_deck(np.zeros(3), 0.001)
    z[3:5] = roll, pitch
    s = gear_signals_function()(z[:QUAD6_STATE.size], z[QUAD6_STATE.size:NZ - 1],
                                GEAR_STATE.zeros(), 0.0, np.zeros(3), part(p, "p_quad"),
                                part(p, "p_act"), part(p, "p_veh"), part(p, "p_deck"),
                                part(p, "p_gear"), part(p, "p_lock"))
    return float(np.ravel(GEAR_SIGNALS.unpack(np.array(s).ravel())["tip_margin"])[0])


def test_tip_margin_passes_1_where_the_centre_leaves_the_support_rectangle():
    # The body on a still level deck at roll 30 deg, pitch 34 deg (ZYX): the deck normal in
    # body axes is n = (-sin th, sin ph cos th, cos ph cos th), and the centre's projection
    # along it onto the feet's plane, h_cg (-n_x, -n_y) / n_z, is at x = 0.2 tan 34 / cos 30
    # = 0.1557 m, past the feet's 0.15 m (y = 0.2 tan 30 = 0.1155 m, within 0.125 m): with
    # no thrust, lock or friction limit nothing holds it. By the edges' angles alone (30 of
    # 32.0 deg, 34 of 36.87 deg) it would be within.
    ph, th = np.radians(30.0), np.radians(34.0)
    x = GEAR_HEIGHT * np.tan(th) / np.cos(ph)
    assert x > 0.15 and GEAR_HEIGHT * np.tan(ph) < 0.125
    margin = _tip_margin_on_a_still_deck(ph, th)
    assert margin > 1
    assert margin == pytest.approx(max(x / 0.15, GEAR_HEIGHT * np.tan(ph) / 0.125), rel=1e-12)


@pytest.mark.parametrize("roll_deg", [180.0, 100.0])
def test_a_body_on_its_side_or_upside_down_is_outside_its_support(roll_deg):
    # Upside down the deck normal in body axes is (0, ~1e-16, -1): the projection's ratio
    # would divide rounding noise by the clamped n_z and read "inside" (1.96e-7 at 180 deg,
    # issue 18's second review); past 90 deg the body has no support at all.
    assert _tip_margin_on_a_still_deck(np.radians(roll_deg), 0.0) == 1e9

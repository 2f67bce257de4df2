"""The navigation filter's model: prediction, measurement blocks, gates, outputs.

Against SciPy's matrix exponential and Van Loan's method, the chi-square and
binomial quantiles, central finite differences, the textbook Joseph update
(tests/nav_reference.py), the relative state of quadland_symbolic.landing.relative
(differentiated symbolically along both bodies' motion) and the exact attitude
of a deck turning at a constant rate.
"""

import casadi as ca
import numpy as np
import pytest
from nav_reference import (
    PARAMS,
    N,
    block_data,
    col,
    discrete,
    h_rows,
    joseph_reference,
    params,
    random_spd,
    sl,
)
from reference import NO_AERO, rotation
from scipy.linalg import expm
from scipy.optimize import newton
from scipy.stats import binom, chi2

from quadland_symbolic.landing.deck import deck_pose, pack_deck
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    NAV,
    RANGE,
    covariance_pattern,
    deck_at,
    measurement_model_function,
    nav_transition_function,
    nav_update_function,
    relative_output,
)
from quadland_symbolic.landing.quadrotor import ACTUATOR, QUAD6_STATE
from quadland_symbolic.landing.relative import relative6
from quadland_symbolic.parameters import VEHICLE

# ---------------------------------------------------------------- prediction

def test_prediction_equals_the_matrix_exponential_and_van_loan(rng):
    """Phi, Gamma and Q of (E3)-(E5) against expm and Van Loan's method."""
    f = nav_transition_function()
    for dt in (0.004, 0.1, 1.3):
        q = {**ESTIMATOR_DEFAULTS, "q_acc": rng.uniform(0.01, 1, 3),
             "q_at": rng.uniform(0.01, 1, 3), "q_b": rng.uniform(1e-4, 0.1, 3),
             "q_ab": rng.uniform(1e-4, 0.1, 3)}
        Phi, Gamma, Q = (np.array(v) for v in f(dt, PARAMS.pack(q)))
        Phi_r, Gamma_r, Q_r = discrete(dt, q)
        scale = np.abs(Q_r).max()
        np.testing.assert_allclose(Phi, Phi_r, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(Gamma, Gamma_r, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(Q, Q_r, rtol=1e-10, atol=1e-12 * scale)
        np.testing.assert_array_equal(Q, Q.T)
        assert np.linalg.eigvalsh(Q).min() > -1e-15 * scale

#: The range fused wherever its beam points (E12a off): the reference has no deck extent.
ANYWHERE = {"range_deck_radius": 1e30, "range_deck_sigmas": 0.0}


def test_gates_default_to_the_chi_square_99_percent_quantile():
    for b in BLOCKS:
        assert ESTIMATOR_DEFAULTS[f"gate_{b.name}"] == pytest.approx(chi2.ppf(0.99, b.dim),
                                                                      rel=1e-6)

# ---------------------------------------------------------------- gating

@pytest.mark.parametrize("name", ["vision", "range", "gnss_rel"])
def test_gate_rejects_clean_data_at_the_chi_square_rate(name):
    """Measurements drawn from N(h(x), S): rejected at 1 %, within a binomial bound."""
    rng = np.random.default_rng([4, len(name)])
    f, model = nav_update_function(name), measurement_model_function(name)
    layout, x, P, vals, n2 = block_data(rng, name)
    block = next(b for b in BLOCKS if b.name == name)
    p = params(vision_k_range=0.0, **ANYWHERE)  # R not a function of the draw
    _, h, H, r, _ = model(x, layout.pack(vals), n2, p)
    h, H, r = col(h), np.array(H), col(r)
    L = np.linalg.cholesky(H @ P @ H.T + np.diag(r))
    n, rejected = 2000, 0
    for _ in range(n):
        z = h + L @ rng.normal(size=block.dim)
        vals[block.field] = z if block.dim > 1 else z[0]
        out = f(x, P, layout.pack(vals), n2, p, 1.0)
        rejected += 1 - int(out[4])
    lo, hi = binom.interval(0.999, n, 0.01)
    assert lo <= rejected <= hi


@pytest.mark.parametrize("name", [b.name for b in BLOCKS])
def test_ten_sigma_outliers_are_rejected_and_change_nothing(name):
    rng = np.random.default_rng([41, len(name)])
    f, model = nav_update_function(name), measurement_model_function(name)
    layout, x, P, vals, n2 = block_data(rng, name)
    block = next(b for b in BLOCKS if b.name == name)
    p = params(vision_k_range=0.0, **ANYWHERE)  # sigma not a function of the outlier; the
    #                                              range's beam on the deck: gated, not held
    for _ in range(20):
        # 10.5 sigma along a random direction of the innovation's covariance; the vision's
        # h and H read the packet's own r_z (E10), the range's its own s (E12b): that value
        # is the root of a scalar equation
        u = rng.normal(size=block.dim)
        u /= np.linalg.norm(u)

        def outlier(z_z, u=u):
            pkt = dict(vals, **{block.field: np.r_[0.0, 0.0, z_z] if block.dim > 1 else z_z})
            _, h, H, r, _ = model(x, layout.pack(pkt), n2, p)
            h, H = col(h), np.array(H)
            return h + 10.5 * np.linalg.cholesky(H @ P @ H.T + np.diag(col(r))) @ u

        z = outlier(0.0)
        if name in ("vision", "range"):
            k = 2 if name == "vision" else 0
            z = outlier(newton(lambda c, k=k: outlier(c)[k] - c, z[k], tol=1e-14, maxiter=100))
        vals[block.field] = z if block.dim > 1 else z[0]
        x_next, P_next, _, nis, fused, held = f(x, P, layout.pack(vals), n2, p, 1.0)
        assert float(fused) == 0 and float(held) == 0
        assert float(nis) == pytest.approx(10.5**2, rel=1e-9)
        np.testing.assert_array_equal(col(x_next), x)
        np.testing.assert_array_equal(np.array(P_next), P)

# ---------------------------------------------------------------- Jacobians

@pytest.mark.parametrize("name", [b.name for b in BLOCKS])
def test_measurement_jacobians_equal_finite_differences(name):
    rng = np.random.default_rng([5, len(name)])
    model = measurement_model_function(name)
    layout, x, _, vals, n2 = block_data(rng, name)
    pkt, p = layout.pack(vals), params()
    H = np.array(model(x, pkt, n2, p)[2])
    eps = 1e-6
    fd = np.column_stack([(col(model(x + eps * e, pkt, n2, p)[1])
                           - col(model(x - eps * e, pkt, n2, p)[1])) / (2 * eps)
                          for e in np.eye(N)])
    np.testing.assert_allclose(H, fd, rtol=1e-8, atol=1e-9)
    if name == "range":                              # the model itself, written out (E12b)
        b3, s = vals["b3_E"], vals["s"]
        c, w = n2 @ b3, np.cross(b3, n2)
        a = x[sl("a_tilt")]
        np.testing.assert_allclose(col(model(x, pkt, n2, p)[1]),
                                   n2 @ x[sl("p_r")] / c
                                   + s / (c * 9.8) * (a[0] * w[1] - a[1] * w[0]), rtol=1e-14)

# ---------------------------------------------------------------- the controller's v_e

@pytest.mark.parametrize("seed", range(4))
def test_output_is_the_relative_state_of_symbolic_landing_relative(values, seed):
    """(E15): p_e, v_e from p1 - p2, p1' - p2', eta2 and w2E equal relative6's p_e and
    its symbolic time derivative, on a rolling, pitching, heaving, turning deck."""
    rng = np.random.default_rng([7, seed])
    deg = np.pi / 180
    p_deck = pack_deck(dict(
        heave_amp=rng.uniform(0, 0.7, 3), heave_freq=rng.uniform(0.2, 1.5, 3),
        heave_phase=rng.uniform(-3, 3, 3), roll_amp=rng.uniform(0, 10 * deg, 3),
        roll_freq=rng.uniform(0.3, 2, 3), roll_phase=rng.uniform(-3, 3, 3),
        pitch_amp=rng.uniform(0, 8 * deg, 3), pitch_freq=rng.uniform(0.3, 2, 3),
        pitch_phase=rng.uniform(-3, 3, 3), pad_offset=rng.normal(size=3),
        deck_height=rng.uniform(0.5, 3)))
    p_veh = values.p_veh.copy()
    p_veh[VEHICLE.slice("tau")] = rng.normal(size=3) * [50, 30, 20]
    p_act = ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=10.0, gear_height=0.2,
                               rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3, **NO_AERO))
    x1q = np.concatenate([rng.normal(size=3) + [0, 0, 4], rng.uniform(-0.5, 0.5, 3),
                          rng.normal(size=3), rng.normal(size=3), rng.uniform(0, 10, 4)])
    xv = np.concatenate([rng.normal(size=2) * 5, rng.uniform(-3, 3, 1), rng.normal(size=2) * 2,
                         rng.normal(size=1) * 0.3])
    t = rng.uniform(0, 30)
    p_e, v_e = (col(v) for v in relative6(x1q, xv, t, values.p_quad, p_act, p_veh,
                                           p_deck)[:2])
    deck = deck_pose(xv, t, p_veh, p_deck)
    q = QUAD6_STATE.unpack(x1q)
    v1 = rotation(q["eta1"]) @ q["V1"]
    out = relative_output(ca.DM(q["p1"] - col(deck.p2)), ca.DM(v1 - col(deck.v2E)),
                          deck.eta2, deck.w2E)
    np.testing.assert_allclose(col(out[0]), p_e, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(col(out[1]), v_e, rtol=1e-12, atol=1e-12)


def test_deck_extrapolation_is_second_order(rng):
    """(E7) against the exact attitude of a deck turning at a constant rate in E:
    the error falls as the cube of the age."""
    eta2, w2E = np.array([0.1, -0.05, 0.8]), np.array([0.2, -0.3, 0.4])
    R0 = rotation(eta2)
    errors = []
    for age in (0.2, 0.1):
        S = np.array([[0, -w2E[2], w2E[1]], [w2E[2], 0, -w2E[0]], [-w2E[1], w2E[0], 0]])
        R = expm(S * age) @ R0
        exact = np.array([np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(R[2, 0]),
                          np.arctan2(R[1, 0], R[0, 0])])
        eta, w = deck_at(ca.DM(eta2), ca.DM(w2E), ca.DM.zeros(3), age, 1.0)
        np.testing.assert_array_equal(col(w), w2E)
        errors.append(np.abs(col(eta) - exact).max())
    assert 6 < errors[0] / errors[1] < 10
    eta_clipped, _ = deck_at(ca.DM(eta2), ca.DM(w2E), ca.DM.zeros(3), 5.0, 0.2)
    eta_max, _ = deck_at(ca.DM(eta2), ca.DM(w2E), ca.DM.zeros(3), 0.2, 0.2)
    np.testing.assert_array_equal(col(eta_clipped), col(eta_max))


# ---------------------------------------------------------------- unchanged when not fused

@pytest.mark.parametrize("name", [b.name for b in BLOCKS])
def test_a_block_not_due_or_rejected_leaves_x_and_P_bit_exact(name):
    rng = np.random.default_rng([8, len(name)])
    f = nav_update_function(name)
    layout, x, P, vals, n2 = block_data(rng, name)
    p = params(**ANYWHERE)                      # the random state's beam may miss the deck
    nan_vals = {k: np.full(np.shape(v), np.nan) if k not in ("fresh", "tau") else v
                for k, v in vals.items()}
    # (packet, due, held): a NaN range has no valid beam (n2 . b3 is NaN), so it is held
    # back before the gate; a NaN of another block reaches the gate and fails it
    rng_ = float(name == "range")
    cases = [(layout.pack(vals), 0.0, 0.0),             # not due
             (layout.pack(nan_vals), 1.0, rng_),        # due, NaN: rejected or held
             (layout.pack(nan_vals), 0.0, 0.0),
             (np.zeros(layout.size), rng_, rng_)]       # an empty slot: b3 = 0, held
    for pkt, due, want_held in cases:
        x_next, P_next, nu, nis, fused, held = f(x, P, pkt, n2, p, due)
        assert float(fused) == 0 and float(held) == want_held
        np.testing.assert_array_equal(col(x_next), x)
        np.testing.assert_array_equal(np.array(P_next), P)
    x_next, P_next, *_, fused, held = f(x, P, layout.pack(vals), n2, p, 1.0)
    assert float(fused) == 1 and float(held) == 0
    assert not np.array_equal(np.array(P_next), P)

# ---------------------------------------------------------------- decoupled axes

@pytest.mark.parametrize("scale", [1.0, 1e-6])
def test_axes_fuse_a_tilted_range_on_z_with_the_rest_as_noise(rng, scale):
    """(E9a), (E9b): the decoupled range update against its formula written out. With a
    covariance of 1e-6 the height's variance ``h_z^T P h_z`` is below the range's ``r``
    and the dropped part's variance counts ``r / h_z^T P h_z`` times in the update, once
    in the NIS."""
    f = nav_update_function("range", "axes")
    pattern = covariance_pattern("axes")
    x = rng.normal(size=N)
    P = pattern.unpack_numeric(pattern.pack_numeric(random_spd(rng, N))) * scale
    n2 = rotation([0.1, -0.08, 0.3])[:, 2]
    b3 = np.array([0.1, 0.05, 1.0]) / np.linalg.norm([0.1, 0.05, 1.0])
    s = n2 @ x[sl("p_r")] / (n2 @ b3) + 0.2 * scale      # inside the gate
    pkt = RANGE.pack(dict(fresh=1.0, tau=0.0, s=s, b3_E=b3))
    h = h_rows("range", n2, b3, [s], 9.8)[0]
    iz = NAV.slice("p_r").start + 2
    h_z, h_d = np.zeros(N), h.copy()
    h_z[iz], h_d[iz] = h[iz], 0.0
    r0 = ESTIMATOR_DEFAULTS["range_sigma"] ** 2
    memory = max(1.0, r0 / (h_z @ P @ h_z))
    assert (memory > 1) == (scale < 1)
    r = r0 + memory * h_d @ P @ h_d
    nu = s - h @ x
    x_ref, P_ref, _, _ = joseph_reference(x, P, h_z[None, :], np.array([nu + h_z @ x]),
                                 np.array([[r]]))
    x_next, P_next, _, nis, *_ = f(x, P, pkt, n2, params(**ANYWHERE), 1.0)
    assert float(nis) == pytest.approx(nu ** 2 / (h_z @ P @ h_z + r0 + h_d @ P @ h_d),
                                       rel=1e-12)
    np.testing.assert_allclose(col(x_next), x_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.array(P_next), P_ref, rtol=1e-12, atol=1e-14)


def test_a_range_whose_beam_misses_the_deck_is_not_fused():
    """(E12a): the beam's predicted deck point ``p_r - h b3_E`` (a level deck, a vertical
    beam: ``(x, y, 0)`` of ``p_r``) must lie within ``range_deck_radius`` of the pad by
    ``range_deck_sigmas`` horizontal standard deviations, else the range is not fused
    (it may measure the ground) but held back, before its gate; within it, it is fused."""
    f = nav_update_function("range")
    n2 = np.array([0.0, 0.0, 1.0])
    pkt = RANGE.pack(dict(fresh=1.0, tau=0.0, s=2.0, b3_E=n2))
    # |(x_off, 0.4)| + 2 sqrt(2 var): 0.5 + 0.028 = 0.528, 0.566 + 0.028, 0.5 + 2.83
    for x_off, var, fused in ((0.3, 1e-4, 1.0), (0.4, 1e-4, 0.0), (0.3, 1.0, 0.0)):
        x, P = np.zeros(N), np.eye(N) * var
        x[sl("p_r")] = [x_off, 0.4, 2.0]
        p = params(range_deck_radius=0.55, range_deck_sigmas=2.0)
        x_next, P_next, _, _, ok, held = f(x, P, pkt, n2, p, 1.0)
        assert float(ok) == fused and float(held) == 1.0 - fused
        assert np.array_equal(np.array(P_next), P) == (fused == 0.0)


@pytest.mark.parametrize("name", ["vision", "gnss_rel", "gnss_v1"])
def test_a_locked_out_block_is_readmitted_with_its_covariance_inflated(name):
    """(E8a): a 10.5-sigma packet is refused with fewer than gate_lockout refusals before
    it; from gate_lockout on it is fused, exactly as the ordinary update fuses it from
    the covariance inflated by NIS / gate with the gate opened (no gate: the same Joseph
    updates, from alpha P)."""
    from quadland_symbolic.landing.navigation import block_update, estimator_params

    rng = np.random.default_rng([43, len(name)])
    layout, x, P, vals, n2 = block_data(rng, name)
    block = next(b for b in BLOCKS if b.name == name)
    pattern = covariance_pattern("full")
    p = params(vision_k_range=0.0, **ANYWHERE)
    model = measurement_model_function(name)
    _, h, H, r, _ = model(x, layout.pack(vals), n2, p)
    h, H = col(h), np.array(H)
    u = rng.normal(size=block.dim)
    z = h + 10.5 * np.linalg.cholesky(H @ P @ H.T + np.diag(col(r))) @ (u / np.linalg.norm(u))
    vals[block.field] = z if block.dim > 1 else z[0]
    pkt = layout.pack(vals)
    xs, Ps, ks = NAV.sym("x"), ca.SX.sym("P", N, N), ca.SX.sym("streak")
    ps = estimator_params().sym()
    out = block_update(name, xs, pattern.unpack(pattern.pack(Ps)), pkt, n2, ps, 1.0, pattern,
                       ks)
    f = ca.Function("f", [xs, Ps, ps, ks], [out[0], ca.densify(out[1]), out[3], out[4]])
    gate = estimator_params().unpack(p)[f"gate_{name}"]
    lockout = estimator_params().unpack(p)["gate_lockout"]
    assert lockout == 10
    x9, P9, nis, fused9 = f(x, P, p, lockout - 1)
    assert float(fused9) == 0 and float(nis) > gate
    np.testing.assert_array_equal(col(x9), x)
    x10, P10, nis10, fused10 = f(x, P, p, lockout)
    assert float(fused10) == 1 and float(nis10) == float(nis)
    alpha = float(nis) / gate
    open_gate = params(vision_k_range=0.0, **ANYWHERE, **{f"gate_{name}": 1e300})
    x_ref, P_ref, _, _, fused_ref, _ = nav_update_function(name)(x, alpha * P, pkt, n2,
                                                                 open_gate, 1.0)
    assert float(fused_ref) == 1
    np.testing.assert_allclose(col(x10), col(x_ref), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.array(P10), np.array(P_ref), rtol=1e-10, atol=1e-14)
    # the innovation shrinks: the fused state explains the packet better
    _, h10, _, _, _ = model(col(x10), pkt, n2, p)
    assert np.linalg.norm(z - col(h10)) < np.linalg.norm(z - h)

"""The navigation filter against a textbook Kalman filter written here in NumPy.

The references: the model's matrices written from the state equations (E2)
index by index, SciPy's matrix exponential for ``Phi`` and Van Loan's method
for ``Q``, the full-matrix Joseph update ``(I - K H) P (I - K H)^T + K R K^T``
with ``K = P H^T S^-1``, SciPy's chi-square and binomial quantiles, central
finite differences, the relative state of :mod:`symbolic.landing.relative`
(differentiated symbolically along both bodies' motion) and a seeded Monte
Carlo on truth drawn from the filter's own process model.
"""

import casadi as ca
import numpy as np
import pytest
from reference import rotation
from scipy.linalg import expm
from scipy.stats import binom, chi2

from symbolic.kalman import CovariancePattern, joseph_update, scalar_update
from symbolic.landing.controller import MEASUREMENT
from symbolic.landing.deck import DECK_PARAMS, deck_pose
from symbolic.landing.estimator import (
    estimator_diagnostics,
    estimator_init_function,
    estimator_memory,
    estimator_step_function,
    output_predictor_function,
)
from symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    GNSS,
    IMU,
    NAV,
    PACKETS,
    RANGE,
    VISION,
    covariance_pattern,
    deck_at,
    estimator_params,
    measurement_model_function,
    nav_transition_function,
    nav_update_function,
    relative_output,
)
from symbolic.landing.quadrotor import ACTUATOR
from symbolic.landing.quadrotor import STATE as QUAD6
from symbolic.landing.relative import relative6
from symbolic.parameters import VEHICLE

N = NAV.size
PARAMS = estimator_params()
DIAG = estimator_diagnostics()
OPEN_GATES = {f"gate_{b.name}": 1e30 for b in BLOCKS}


def _sl(name):
    return NAV.slice(name)


def _col(v):
    return np.array(v, dtype=float).ravel()


def _params(**over):
    return PARAMS.pack({**ESTIMATOR_DEFAULTS, **over})


# ---------------------------------------------------------------- the NumPy reference

def _model_matrices(q):
    """A, B, W of (E2), entry by entry from the state equations."""
    A, B, W = np.zeros((N, N)), np.zeros((N, 3)), np.zeros((N, N))
    I3 = np.eye(3)
    A[_sl("p_r"), _sl("v1")] = I3                     # p_r' = v1 - v_t
    A[_sl("p_r"), _sl("v_t")] = -I3
    A[_sl("v1"), _sl("a_b")] = -I3                    # v1' = a_in - a_b
    B[_sl("v1"), :] = I3
    A[_sl("v_t"), _sl("a_t")] = I3                    # v_t' = a_t
    for name, key in (("v1", "q_acc"), ("a_t", "q_at"), ("b", "q_b"), ("a_b", "q_ab")):
        W[_sl(name), _sl(name)] = q[key] * I3
    return A, B, W


_DISCRETE = {}


def _discrete(dt, q):
    """Phi and Gamma by the exponential of [[A, B], [0, 0]], Q by Van Loan."""
    key = (dt, q["q_acc"], q["q_at"], q["q_b"], q["q_ab"])
    if key not in _DISCRETE:
        _DISCRETE[key] = _discrete_uncached(dt, q)
    return _DISCRETE[key]


def _discrete_uncached(dt, q):
    A, B, W = _model_matrices(q)
    M = np.zeros((N + 3, N + 3))
    M[:N, :N], M[:N, N:] = A, B
    E = expm(M * dt)
    V = expm(np.block([[-A, W], [np.zeros((N, N)), A.T]]) * dt)
    Phi = V[N:, N:].T
    return E[:N, :N], E[:N, N:], Phi @ V[:N, N:]


def _h_rows(name, n2=None, b3=None):
    """H of each block from (E10)-(E14), with the range's rows n2^T / (n2 . b3)."""
    H = np.zeros((3, N))
    I3 = np.eye(3)
    if name == "vision":
        H[:, _sl("p_r")] = -I3
    elif name == "gnss_rel":
        H[:, _sl("p_r")], H[:, _sl("b")] = -I3, I3
    elif name == "gnss_v1":
        H[:, _sl("v1")] = I3
    elif name in ("gnss_vt", "datalink_v"):
        H[:, _sl("v_t")] = I3
    elif name == "datalink_a":
        H[:, _sl("a_t")] = I3
    else:
        H = np.zeros((1, N))
        H[0, _sl("p_r")] = n2 / (n2 @ b3)
    return H


def _variances(name, z, q):
    if name == "vision":
        return np.full(3, (q["vision_sigma0"] + q["vision_k_range"] * np.linalg.norm(z)) ** 2)
    if name == "range":
        return np.array([q["range_sigma"] ** 2])
    key = {"gnss_rel": "gnss_rel_sigma", "gnss_v1": "gnss_v1_sigma", "gnss_vt": "gnss_vt_sigma",
           "datalink_v": "datalink_v_sigma", "datalink_a": "datalink_a_sigma"}[name]
    return np.asarray(q[key], dtype=float) ** 2


def _joseph(x, P, H, z, R):
    """The textbook update: K = P H^T S^-1, full-matrix Joseph form."""
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    nu = z - H @ x
    I_KH = np.eye(N) - K @ H
    return x + K @ nu, I_KH @ P @ I_KH.T + K @ R @ K.T, nu, nu @ np.linalg.solve(S, nu)


class ReferenceKF:
    """A textbook KF on (E2), fusing packets at their own time, in fusion order."""

    def __init__(self, x0, P0, q):
        self.x, self.P, self.q = np.array(x0, float), np.array(P0, float), q

    def fuse(self, packets, n2):
        """``packets``: sensor -> dict of values (fresh ones only). Returns NIS per block."""
        nis = {}
        for b in BLOCKS:
            pk = packets.get(b.sensor)
            if pk is None:
                continue
            z = np.atleast_1d(pk[b.field])
            H = _h_rows(b.name, n2, pk.get("b3_E"))
            R = np.diag(_variances(b.name, z, self.q))
            self.x, self.P, _, nis[b.name] = _joseph(self.x, self.P, H, z, R)
        return nis

    def predict(self, a_in, dt):
        Phi, Gamma, Q = _discrete(dt, self.q)
        self.x = Phi @ self.x + Gamma @ a_in
        self.P = Phi @ self.P @ Phi.T + Q


# ---------------------------------------------------------------- helpers

def _random_spd(rng, n, scale=1.0):
    L = rng.normal(size=(n, n))
    return scale * (L @ L.T / n + 0.1 * np.eye(n))


def _imu(rng):
    eta = rng.normal(size=3) * [0.2, 0.2, 1.0]
    return IMU.pack(dict(eta_hat=eta, f_b=rng.normal(size=3) + [0, 0, 9.8],
                         omega=rng.normal(size=3) * 0.3))


def _a_in(imu, g):
    v = IMU.unpack(imu)
    return rotation(v["eta_hat"]) @ v["f_b"] - np.array([0, 0, g])


def _packet_values(rng, sensor, x, tau, eta2, n2):
    """A packet near the measurement the state predicts (noise of order 0.3)."""
    e = rng.normal(size=3) * 0.3
    if sensor == "vision":
        return dict(fresh=1.0, tau=tau, r_E=-x[_sl("p_r")] + e)
    if sensor == "gnss":
        return dict(fresh=1.0, tau=tau, rel=-x[_sl("p_r")] + x[_sl("b")] + e,
                    v1=x[_sl("v1")] + e[::-1], vt=x[_sl("v_t")] - e)
    if sensor == "range":
        b3 = np.array([0.1, -0.05, 1.0]) + rng.normal(size=3) * 0.05
        b3 /= np.linalg.norm(b3)
        return dict(fresh=1.0, tau=tau, s=n2 @ x[_sl("p_r")] / (n2 @ b3) + e[0], b3_E=b3)
    return dict(fresh=1.0, tau=tau, eta2=eta2, v2E=x[_sl("v_t")] + e,
                a2E=x[_sl("a_t")] + e[::-1], w2E=np.zeros(3), w2E_dot=np.zeros(3))


def _empty(layout):
    return np.zeros(layout.size)


def _init(n_hist, depth, coupling, x0, P0_diag, eta2=(0, 0, 0), t0=0.0):
    deck0 = np.concatenate([eta2, np.zeros(6)])
    return _col(estimator_init_function(n_hist, depth, coupling)(x0, P0_diag, deck0, t0))


def _x0_P0(rng):
    x0 = rng.normal(size=N) * 0.5
    x0[_sl("p_r")] += [1.0, -2.0, 4.0]
    return x0, rng.uniform(0.05, 1.0, N)


def _unpack_P(mem_layout, coupling, mem):
    return covariance_pattern(coupling).unpack_numeric(mem_layout.unpack(mem)["P_h"])


# ---------------------------------------------------------------- 1. the textbook KF

def _run_undelayed(rng, coupling="full", steps=30, p_fresh=0.6, n_hist=0, depth=1):
    """Steps of the filter with packets taken at ``t`` and arriving at once, and the
    reference KF on the same data; yields both after each step."""
    step = estimator_step_function(n_hist, depth, coupling)
    lay = estimator_memory(n_hist, depth, coupling)
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": 0.3, "q_at": 0.5, "q_b": 0.01,
         "q_ab": 0.02}
    p = PARAMS.pack(q)
    x0, P0 = _x0_P0(rng)
    eta2 = np.array([0.05, -0.03, 0.7])
    mem = _init(n_hist, depth, coupling, x0, P0, eta2)
    ref = ReferenceKF(x0, np.diag(P0), q)
    dt = 0.01
    for k in range(steps):
        t = k * dt
        imu = _imu(rng)
        if rng.uniform() < p_fresh:
            eta2 = eta2 + rng.normal(size=3) * 0.01
        n2 = rotation(eta2)[:, 2]
        packets = {s: _packet_values(rng, s, ref.x, t, eta2, n2)
                   for s in ("vision", "gnss", "range", "datalink") if rng.uniform() < p_fresh}
        if "datalink" not in packets:
            eta2 = lay.unpack(mem)["deck_eta2"]
            n2 = rotation(eta2)[:, 2]
        vecs = [layout.pack(packets[layout.name]) if layout.name in packets else _empty(layout)
                for layout in PACKETS]
        mem, y, diag = (_col(v) for v in step(mem, imu, *vecs, p, dt, t))
        nis = ref.fuse(packets, n2)
        fused = dict(x=ref.x.copy(), P=ref.P.copy())
        ref.predict(_a_in(imu, q["g"]), dt)
        yield dict(diag=DIAG.unpack(diag), y=y, mem=mem, lay=lay, ref=ref, nis=nis, t=t,
                   packets=packets, fused=fused, imu=imu, p=p)


@pytest.mark.parametrize("seed", range(3))
def test_equals_a_textbook_kalman_filter_without_delay(seed):
    """(E2)-(E14) with every block fused at its time: x, P, NIS as the NumPy KF's."""
    rng = np.random.default_rng([17, seed])
    fused = 0
    for r in _run_undelayed(rng):
        d, ref, m = r["diag"], r["ref"], r["lay"].unpack(r["mem"])
        np.testing.assert_allclose(d["x_h"], r["fused"]["x"], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(d["P_diag"], np.diag(r["fused"]["P"]), rtol=1e-10,
                                   atol=1e-12)
        for k, b in enumerate(BLOCKS):
            if b.name in r["nis"]:
                fused += 1
                assert d["fused"][k] == 1
                np.testing.assert_allclose(d["nis"][k], r["nis"][b.name], rtol=1e-9)
            else:
                assert d["fused"][k] == 0 and d["nis"][k] == 0
        # after the step's prediction over dt
        np.testing.assert_allclose(m["x_h"], ref.x, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(_unpack_P(r["lay"], "full", r["mem"]), ref.P, rtol=1e-10,
                                   atol=1e-12)
    assert fused > 50


def test_prediction_equals_the_matrix_exponential_and_van_loan(rng):
    """Phi, Gamma and Q of (E3)-(E5) against expm and Van Loan's method."""
    f = nav_transition_function()
    for dt in (0.004, 0.1, 1.3):
        q = {**ESTIMATOR_DEFAULTS, "q_acc": rng.uniform(0.01, 1), "q_at": rng.uniform(0.01, 1),
             "q_b": rng.uniform(1e-4, 0.1), "q_ab": rng.uniform(1e-4, 0.1)}
        Phi, Gamma, Q = (np.array(v) for v in f(dt, PARAMS.pack(q)))
        Phi_r, Gamma_r, Q_r = _discrete(dt, q)
        scale = np.abs(Q_r).max()
        np.testing.assert_allclose(Phi, Phi_r, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(Gamma, Gamma_r, rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(Q, Q_r, rtol=1e-10, atol=1e-12 * scale)
        np.testing.assert_array_equal(Q, Q.T)
        assert np.linalg.eigvalsh(Q).min() > -1e-15 * scale


def test_gates_default_to_the_chi_square_99_percent_quantile():
    for b in BLOCKS:
        assert ESTIMATOR_DEFAULTS[f"gate_{b.name}"] == pytest.approx(chi2.ppf(0.99, b.dim),
                                                                      rel=1e-6)


# ---------------------------------------------------------------- 2. the delayed horizon

#: Latency of each sensor in periods (all below the horizon's 6) and its period.
LATENCY = dict(vision=2, gnss=5, range=0, datalink=3)
EVERY = dict(vision=3, gnss=7, range=2, datalink=4)


def test_delayed_fusion_is_the_undelayed_filter_shifted_by_the_horizon():
    """Packets L < D late: the horizon holds, exactly, the KF that fused each at its time,
    n_hist periods ago; the output is that estimate carried through the buffered inputs."""
    rng = np.random.default_rng(2017)
    n_hist, depth, dt, steps = 6, 3, 0.01, 60
    step = estimator_step_function(n_hist, depth)
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": 0.3, "q_at": 0.5}
    p = PARAMS.pack(q)
    x0, P0 = _x0_P0(rng)
    eta2 = np.array([0.04, -0.02, 0.3])                # one deck attitude: n2 is the same
    n2, R2 = rotation(eta2)[:, 2], rotation(eta2)
    mem = _init(n_hist, depth, "full", x0, P0, eta2)
    ref = ReferenceKF(x0, np.diag(P0), q)
    history, inputs, arrivals = [], [], {}
    for k in range(steps):
        t = k * dt
        imu = _imu(rng)
        packets = {s: _packet_values(rng, s, ref.x, t, eta2, n2)
                   for s in LATENCY if k % EVERY[s] == 0}
        ref.fuse(packets, n2)
        history.append((ref.x.copy(), ref.P.copy()))
        a_in = _a_in(imu, q["g"])
        inputs.append(a_in)
        ref.predict(a_in, dt)
        for s, pk in packets.items():
            arrivals[(k + LATENCY[s], s)] = pk
        vecs = [layout.pack(arrivals[(k, layout.name)]) if (k, layout.name) in arrivals
                else _empty(layout) for layout in PACKETS]
        mem, y, diag = (_col(v) for v in step(mem, imu, *vecs, p, dt, t))
        d = DIAG.unpack(diag)
        j = k - n_hist                                   # the horizon's sample
        if j < 0:
            assert d["t_h"] == 0.0
            continue
        assert d["t_h"] == pytest.approx(j * dt, abs=1e-12)
        x_ref, P_ref = history[j]
        np.testing.assert_allclose(d["x_h"], x_ref, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(d["P_diag"], np.diag(P_ref), rtol=1e-10, atol=1e-12)
        # the output predictor: x_ref carried through inputs j .. k-1 by expm
        x_now = x_ref.copy()
        for a in inputs[j:k]:
            Phi, Gamma, _ = _discrete(dt, q)
            x_now = Phi @ x_now + Gamma @ a
        ys = MEASUREMENT.unpack(y)
        np.testing.assert_allclose(ys["p_e"], R2.T @ x_now[_sl("p_r")], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["v_e"], R2.T @ (x_now[_sl("v1")] - x_now[_sl("v_t")]),
                                   rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["v2E"], x_now[_sl("v_t")], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["a2E"], x_now[_sl("a_t")], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ys["eta2"], eta2, atol=1e-15)
        np.testing.assert_array_equal(ys["eta1"], IMU.unpack(imu)["eta_hat"])
    assert d["n_fused"].sum() > 40 and d["n_discarded"].sum() == 0
    assert d["n_dropped"].sum() == 0 and d["n_rejected"].sum() == 0


def test_output_predictor_is_the_chained_prediction(rng):
    """(E17) in closed form against N steps of Phi, Gamma with varying periods."""
    n = 7
    f = output_predictor_function(n)
    q = dict(ESTIMATOR_DEFAULTS)
    x = rng.normal(size=N)
    hist = np.vstack([rng.normal(size=(3, n)) * 3, rng.uniform(0, 0.02, n)])
    hist[3, 2] = 0.0                                       # an empty period
    x_ref = x.copy()
    for k in range(n):
        Phi, Gamma, _ = _discrete(hist[3, k], q)
        x_ref = Phi @ x_ref + Gamma @ hist[:3, k]
    np.testing.assert_allclose(_col(f(x, hist)), x_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(_col(output_predictor_function(0)(x, np.zeros((4, 0)))), x)


# ---------------------------------------------------------------- 3. Joseph form

def _joseph_function():
    P, k, h, r = (ca.SX.sym("P", N, N), ca.SX.sym("k", N), ca.SX.sym("h", N), ca.SX.sym("r"))
    pat = CovariancePattern.full(N)
    return ca.Function("j", [P, k, h, r],
                       [ca.densify(joseph_update(pat.unpack(pat.pack(P)), k, h, r, pat))])


def _scalar_function():
    x, P, h = ca.SX.sym("x", N), ca.SX.sym("P", N, N), ca.SX.sym("h", N)
    nu, r, acc = ca.SX.sym("nu"), ca.SX.sym("r"), ca.SX.sym("accept")
    pat = CovariancePattern.full(N)
    out = scalar_update(x, pat.unpack(pat.pack(P)), h, nu, r, acc, pat)
    return ca.Function("s", [x, P, h, nu, r, acc], [out[0], ca.densify(out[1])])


def _ill_conditioned(rng, decades):
    Qm, _ = np.linalg.qr(rng.normal(size=(N, N)))
    P = (Qm * np.logspace(0, -decades, N)) @ Qm.T
    return np.triu(P) + np.triu(P, 1).T


def test_joseph_form_is_positive_for_any_gain_where_the_short_form_is_not(rng):
    """(E9) equals (I - k h^T) P (I - k h^T)^T + r k k^T for a gain that is not
    optimal, and stays positive semi-definite; P - s k k^T with that gain does not."""
    f = _joseph_function()
    naive_negative = 0
    for _ in range(50):
        P = _random_spd(rng, N)
        h, r = rng.normal(size=N), rng.uniform(0.01, 1)
        k_opt = P @ h / (h @ P @ h + r)
        k = k_opt * (1 + 0.3 * rng.normal(size=N))        # a gain with errors
        A = np.eye(N) - np.outer(k, h)
        expected = A @ P @ A.T + r * np.outer(k, k)
        got = np.array(f(P, k, h, r))
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-12)
        assert np.linalg.eigvalsh(got).min() > -1e-12
        naive = P - (h @ P @ h + r) * np.outer(k, k)
        naive_negative += np.linalg.eigvalsh(naive).min() < 0
    assert naive_negative >= 45


def test_joseph_updates_keep_an_ill_conditioned_covariance_positive(rng):
    """2000 optimal scalar updates with tiny r on P spanning 10 decades: P stays exactly
    symmetric with positive eigenvalues; the short form P - u u^T / s agrees to rounding."""
    f = _scalar_function()
    P = _ill_conditioned(rng, 10)
    x = np.zeros(N)
    worst = np.inf
    for it in range(2000):
        h = rng.normal(size=N)
        r = 1e-12 * (h @ P @ h)
        x, P_next = (np.array(v) for v in f(x, P, h, 1.0, r, 1.0))
        u = P @ h
        short = P - np.outer(u, u) / (h @ u + r)
        np.testing.assert_allclose(P_next, short, atol=1e-9 * np.abs(P).max())
        np.testing.assert_array_equal(P_next, P_next.T)
        P = P_next
        if it % 10 == 9:                                  # process noise, as a prediction adds
            P = P + np.diag(rng.uniform(0, 1e-6, N))
        ev = np.linalg.eigvalsh(P)
        worst = min(worst, ev.min() / ev.max())
    assert worst > 0


# ---------------------------------------------------------------- 4. gating

def _block_data(rng, name):
    layout = next(p for p in PACKETS if p.name == next(b.sensor for b in BLOCKS
                                                         if b.name == name))
    x, P = rng.normal(size=N), _random_spd(rng, N, 0.5)
    eta2 = np.array([0.05, 0.02, 0.4])
    n2 = rotation(eta2)[:, 2]
    vals = _packet_values(rng, layout.name, x, 0.0, eta2, n2)
    return layout, x, P, vals, n2


@pytest.mark.parametrize("name", ["vision", "range", "gnss_rel"])
def test_gate_rejects_clean_data_at_the_chi_square_rate(name):
    """Measurements drawn from N(h(x), S): rejected at 1 %, within a binomial bound."""
    rng = np.random.default_rng([4, len(name)])
    f, model = nav_update_function(name), measurement_model_function(name)
    layout, x, P, vals, n2 = _block_data(rng, name)
    block = next(b for b in BLOCKS if b.name == name)
    p = _params(vision_k_range=0.0)             # R not a function of the draw
    _, h, H, r, _ = model(x, layout.pack(vals), n2, p)
    h, H, r = _col(h), np.array(H), _col(r)
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
    layout, x, P, vals, n2 = _block_data(rng, name)
    block = next(b for b in BLOCKS if b.name == name)
    p = _params(vision_k_range=0.0)             # sigma not a function of the outlier
    _, h, H, r, _ = model(x, layout.pack(vals), n2, p)
    h, H = _col(h), np.array(H)
    for _ in range(20):
        # 10 sigma along a random direction of the innovation's covariance
        u = rng.normal(size=block.dim)
        u /= np.linalg.norm(u)
        S = H @ P @ H.T + np.diag(_col(r))
        z = h + 10.5 * np.linalg.cholesky(S) @ u
        vals[block.field] = z if block.dim > 1 else z[0]
        x_next, P_next, _, nis, fused = f(x, P, layout.pack(vals), n2, p, 1.0)
        assert float(fused) == 0 and float(nis) > 100
        np.testing.assert_array_equal(_col(x_next), x)
        np.testing.assert_array_equal(np.array(P_next), P)


# ---------------------------------------------------------------- 5. Jacobians

@pytest.mark.parametrize("name", [b.name for b in BLOCKS])
def test_measurement_jacobians_equal_finite_differences(name):
    rng = np.random.default_rng([5, len(name)])
    model = measurement_model_function(name)
    layout, x, _, vals, n2 = _block_data(rng, name)
    pkt, p = layout.pack(vals), _params()
    H = np.array(model(x, pkt, n2, p)[2])
    eps = 1e-6
    fd = np.column_stack([(_col(model(x + eps * e, pkt, n2, p)[1])
                           - _col(model(x - eps * e, pkt, n2, p)[1])) / (2 * eps)
                          for e in np.eye(N)])
    np.testing.assert_allclose(H, fd, rtol=1e-8, atol=1e-9)
    if name == "range":                              # the model itself, written out
        b3 = vals["b3_E"]
        np.testing.assert_allclose(_col(model(x, pkt, n2, p)[1]),
                                   n2 @ x[_sl("p_r")] / (n2 @ b3), rtol=1e-14)


# ---------------------------------------------------------------- 6. consistency

MC_RUNS, MC_STEPS, MC_DT = 100, 150, 0.01
MC_LATENCY = dict(vision=2, gnss=3, range=1, datalink=2)
MC_EVERY = dict(vision=3, gnss=10, range=2, datalink=5)


def _mc_truth(rng, q, x0, P0, Phi, Gamma, Q):
    """Truth from the filter's own model: x0 ~ N(x0_hat, P0), x+ = Phi x + Gamma a + w."""
    L = np.linalg.cholesky(Q + 1e-18 * np.eye(N))
    xs = np.empty((MC_STEPS + 1, MC_RUNS, N))
    xs[0] = x0 + rng.normal(size=(MC_RUNS, N)) * np.sqrt(P0)
    imus = np.empty((MC_STEPS, MC_RUNS, IMU.size))
    for k in range(MC_STEPS):
        for r in range(MC_RUNS):
            imus[k, r] = _imu(rng)
        a = np.array([_a_in(imu, q["g"]) for imu in imus[k]])
        xs[k + 1] = xs[k] @ Phi.T + a @ Gamma.T + rng.normal(size=(MC_RUNS, N)) @ L.T
    return xs, imus


def _mc_packet(rng, sensor, x, tau, eta2, n2, b3, q):
    """A packet drawn from (E10)-(E14) at the true state with the filter's noise."""
    def noise(sigma):
        return rng.normal(size=3) * sigma
    if sensor == "vision":
        return dict(fresh=1.0, tau=tau, r_E=-x[_sl("p_r")] + noise(q["vision_sigma0"]))
    if sensor == "gnss":
        return dict(fresh=1.0, tau=tau,
                    rel=-x[_sl("p_r")] + x[_sl("b")] + noise(np.array(q["gnss_rel_sigma"])),
                    v1=x[_sl("v1")] + noise(np.array(q["gnss_v1_sigma"])),
                    vt=x[_sl("v_t")] + noise(np.array(q["gnss_vt_sigma"])))
    if sensor == "range":
        return dict(fresh=1.0, tau=tau, s=n2 @ x[_sl("p_r")] / (n2 @ b3)
                    + rng.normal() * q["range_sigma"], b3_E=b3)
    return dict(fresh=1.0, tau=tau, eta2=eta2,
                v2E=x[_sl("v_t")] + noise(np.array(q["datalink_v_sigma"])),
                a2E=x[_sl("a_t")] + noise(np.array(q["datalink_a_sigma"])),
                w2E=np.zeros(3), w2E_dot=np.zeros(3))


def test_monte_carlo_nees_and_nis_lie_in_their_chi_square_bounds():
    """100 runs on truth from the process model, every sensor late by less than the
    horizon: the average NEES of the 18 states at the end and each block's average NIS
    (innovations of a consistent filter are white, so all fusions pool) lie inside their
    two-sided 95 % chi-square bounds. Gates open and the vision noise range-free: both
    make R or the accepted set depend on the draw, which (E8) tests apart."""
    rng = np.random.default_rng(20171)
    n_hist, depth = 4, 4
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": 0.05, "q_at": 0.2, "q_b": 0.01,
         "q_ab": 0.01, "vision_k_range": 0.0}
    p = PARAMS.pack(q)
    x0 = np.zeros(N)
    x0[_sl("p_r")] = [0.5, -0.5, 4.0]
    P0 = np.concatenate([[1.0] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.01] * 3])
    Phi, Gamma, Q = _discrete(MC_DT, q)
    xs, imus = _mc_truth(rng, q, x0, P0, Phi, Gamma, Q)
    eta2 = np.array([0.03, -0.02, 0.5])
    n2, b3 = rotation(eta2)[:, 2], np.array([0.05, 0.03, 1.0]) / np.linalg.norm([0.05, 0.03, 1])
    step = estimator_step_function(n_hist, depth).map(MC_RUNS)
    lay = estimator_memory(n_hist, depth)
    mem = np.tile(_init(n_hist, depth, "full", x0, P0, eta2)[:, None], (1, MC_RUNS))
    arrivals, nis = {}, {b.name: [] for b in BLOCKS}
    for k in range(MC_STEPS):
        for s in MC_LATENCY:
            if k % MC_EVERY[s] == 0:
                arrivals[(k + MC_LATENCY[s], s)] = [
                    _mc_packet(rng, s, xs[k, r], k * MC_DT, eta2, n2, b3, q)
                    for r in range(MC_RUNS)]
        vecs = [np.column_stack([layout.pack(v) for v in arrivals[(k, layout.name)]])
                if (k, layout.name) in arrivals else np.zeros((layout.size, MC_RUNS))
                for layout in PACKETS]
        mem, _, diag = step(mem, imus[k].T, *vecs, p, MC_DT, k * MC_DT)
        mem, d = np.array(mem), DIAG.unpack(np.array(diag))
        for i, b in enumerate(BLOCKS):
            nis[b.name] += list(d["nis"][i][d["fused"][i] == 1])
    j = int(round(lay.unpack(mem[:, 0])["t_h"][0] / MC_DT))
    nees = []
    for r in range(MC_RUNS):
        m = lay.unpack(mem[:, r])
        e = m["x_h"] - xs[j, r]
        nees.append(e @ np.linalg.solve(_unpack_P(lay, "full", mem[:, r]), e))
    lo, hi = chi2.ppf([0.025, 0.975], MC_RUNS * N) / MC_RUNS
    assert lo <= np.mean(nees) <= hi, (np.mean(nees), lo, hi)
    for b in BLOCKS:
        n = len(nis[b.name])
        assert n >= 10 * MC_RUNS
        lo, hi = chi2.ppf([0.025, 0.975], n * b.dim) / n
        assert lo <= np.mean(nis[b.name]) <= hi, (b.name, np.mean(nis[b.name]), lo, hi)


# ---------------------------------------------------------------- 7. the controller's v_e

@pytest.mark.parametrize("seed", range(4))
def test_output_is_the_relative_state_of_symbolic_landing_relative(values, seed):
    """(E15): p_e, v_e from p1 - p2, p1' - p2', eta2 and w2E equal relative6's p_e and
    its symbolic time derivative, on a rolling, pitching, heaving, turning deck."""
    rng = np.random.default_rng([7, seed])
    deg = np.pi / 180
    p_deck = DECK_PARAMS.pack(dict(
        heave_amp=rng.uniform(0, 0.7, 3), heave_freq=rng.uniform(0.2, 1.5, 3),
        heave_phase=rng.uniform(-3, 3, 3), roll_amp=rng.uniform(0, 10 * deg, 3),
        roll_freq=rng.uniform(0.3, 2, 3), roll_phase=rng.uniform(-3, 3, 3),
        pitch_amp=rng.uniform(0, 8 * deg, 3), pitch_freq=rng.uniform(0.3, 2, 3),
        pitch_phase=rng.uniform(-3, 3, 3), pad_offset=rng.normal(size=3),
        deck_height=rng.uniform(0.5, 3)))
    p_veh = values.p_veh.copy()
    p_veh[VEHICLE.slice("tau")] = rng.normal(size=3) * [50, 30, 20]
    p_act = ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=10.0, gear_height=0.2))
    x1q = np.concatenate([rng.normal(size=3) + [0, 0, 4], rng.uniform(-0.5, 0.5, 3),
                          rng.normal(size=3), rng.normal(size=3), rng.uniform(0, 10, 4)])
    xv = np.concatenate([rng.normal(size=2) * 5, rng.uniform(-3, 3, 1), rng.normal(size=2) * 2,
                         rng.normal(size=1) * 0.3])
    t = rng.uniform(0, 30)
    p_e, v_e = (_col(v) for v in relative6(x1q, xv, t, values.p_quad, p_act, p_veh,
                                           p_deck)[:2])
    deck = deck_pose(xv, t, p_veh, p_deck)
    q = QUAD6.unpack(x1q)
    v1 = rotation(q["eta1"]) @ q["V1"]
    out = relative_output(ca.DM(q["p1"] - _col(deck.p2)), ca.DM(v1 - _col(deck.v2E)),
                          deck.eta2, deck.w2E)
    np.testing.assert_allclose(_col(out[0]), p_e, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(_col(out[1]), v_e, rtol=1e-12, atol=1e-12)


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
        np.testing.assert_array_equal(_col(w), w2E)
        errors.append(np.abs(_col(eta) - exact).max())
    assert 6 < errors[0] / errors[1] < 10
    eta_clipped, _ = deck_at(ca.DM(eta2), ca.DM(w2E), ca.DM.zeros(3), 5.0, 0.2)
    eta_max, _ = deck_at(ca.DM(eta2), ca.DM(w2E), ca.DM.zeros(3), 0.2, 0.2)
    np.testing.assert_array_equal(_col(eta_clipped), _col(eta_max))


# ---------------------------------------------------------------- 8. unchanged when not fused

@pytest.mark.parametrize("name", [b.name for b in BLOCKS])
def test_a_block_not_due_or_rejected_leaves_x_and_P_bit_exact(name):
    rng = np.random.default_rng([8, len(name)])
    f = nav_update_function(name)
    layout, x, P, vals, n2 = _block_data(rng, name)
    p = _params()
    nan_vals = {k: np.full(np.shape(v), np.nan) if k not in ("fresh", "tau") else v
                for k, v in vals.items()}
    cases = [(layout.pack(vals), 0.0),                 # not due
             (layout.pack(nan_vals), 1.0),             # due, NaN: rejected
             (layout.pack(nan_vals), 0.0),
             (np.zeros(layout.size), float(name == "range"))]   # an empty slot: b3 = 0
    for pkt, due in cases:
        x_next, P_next, nu, nis, fused = f(x, P, pkt, n2, p, due)
        assert float(fused) == 0
        np.testing.assert_array_equal(_col(x_next), x)
        np.testing.assert_array_equal(np.array(P_next), P)
    x_next, P_next, *_, fused = f(x, P, layout.pack(vals), n2, p, 1.0)
    assert float(fused) == 1 and not np.array_equal(np.array(P_next), P)


def test_rejected_and_not_due_packets_leave_the_step_bit_exact(rng):
    """Through the step: a rejected vision outlier and a non-finite GNSS packet (not
    queued) give the same state and covariance as no packet at all, and are counted."""
    n_hist, depth = 3, 4
    step, lay = estimator_step_function(n_hist, depth), estimator_memory(n_hist, depth)
    p = _params()
    x0, P0 = _x0_P0(rng)
    mem = _init(n_hist, depth, "full", x0, P0)
    mem_a = mem_b = mem
    imu = _imu(rng)
    for k in range(8):
        t = k * 0.01
        vis = VISION.pack(dict(fresh=1.0, tau=t, r_E=[50.0, 0, 0]))
        gnss = GNSS.pack(dict(fresh=1.0, tau=t, rel=[np.nan] * 3, v1=[np.inf] * 3,
                              vt=[1e300, np.nan, 0.0]))
        empty = [_empty(layout) for layout in PACKETS]
        mem_a = _col(step(mem_a, imu, vis, gnss, *empty[2:], p, 0.01, t)[0])
        mem_b = _col(step(mem_b, imu, *empty, p, 0.01, t)[0])
        a, b = lay.unpack(mem_a), lay.unpack(mem_b)
        np.testing.assert_array_equal(a["x_h"], b["x_h"])
        np.testing.assert_array_equal(a["P_h"], b["P_h"])
        assert np.all(np.isfinite(mem_a))
    assert a["n_rejected"][[bk.name for bk in BLOCKS].index("vision")] == 8 - n_hist
    assert a["n_rejected"].sum() == 8 - n_hist and a["n_fused"].sum() == 0
    assert list(a["n_dropped"]) == [0, 8, 0, 0]      # the non-finite GNSS packets
    assert b["n_rejected"].sum() == 0 and b["n_dropped"].sum() == 0


# ---------------------------------------------------------------- FIFOs and time

def _vision_run(n_hist, depth, taus_by_step, steps, **over):
    """Vision packets at the given steps with the given sample times; diagnostics."""
    step = estimator_step_function(n_hist, depth)
    lay = estimator_memory(n_hist, depth)
    p = _params(**OPEN_GATES, **over)
    x0 = np.zeros(N)
    x0[_sl("p_r")] = [0, 0, 3.0]
    mem = _init(n_hist, depth, "full", x0, np.ones(N))
    imu = IMU.pack(dict(eta_hat=np.zeros(3), f_b=[0, 0, 9.8], omega=np.zeros(3)))
    out = []
    for k in range(steps):
        tau = taus_by_step.get(k)
        vis = (VISION.pack(dict(fresh=1.0, tau=tau, r_E=[0, 0, -3.0])) if tau is not None
               else _empty(VISION))
        mem, _, d = step(mem, imu, vis, *[_empty(layout) for layout in PACKETS[1:]], p, 0.01,
                         k * 0.01)
        mem = _col(mem)
        out.append((DIAG.unpack(_col(d)), lay.unpack(mem)))
    return out


def test_one_packet_per_sensor_and_period_then_late_or_discarded():
    """Two packets due in the same period: one fused, the next a period late, or
    discarded when that is beyond max_age; a packet from the future is not queued."""
    taus = {1: 0.003, 2: 0.006, 3: 0.009, 6: 0.5}        # t = 0.01 k, horizon 3 behind
    out = _vision_run(3, 4, taus, 8)
    assert [int(d["fused"][0]) for d, _ in out] == [0, 1, 0, 0, 1, 1, 0, 0]
    assert [int(d["dropped"][0]) for d, _ in out] == [0, 0, 0, 0, 0, 0, 1, 0]
    out = _vision_run(3, 4, taus, 8, max_age_vision=0.005)
    assert [int(d["fused"][0]) for d, _ in out] == [0, 1, 0, 0, 1, 0, 0, 0]
    assert [int(d["discarded"][0]) for d, _ in out] == [0, 0, 0, 0, 0, 1, 0, 0]
    assert out[-1][1]["count_vision"][0] == 0


def test_a_full_fifo_drops_the_newest_and_counts_it():
    taus = {k: k * 0.01 for k in range(12)}
    out = _vision_run(6, 3, taus, 12)
    counts = [int(m["count_vision"][0]) for _, m in out]
    assert max(counts) == 3
    dropped = [int(d["dropped"][0]) for d, _ in out]
    # one packet a period, each waiting 6 periods for the horizon, into 3 slots: 4, 5, 6
    # find it full; 7, 8, 9 replace 1, 2, 3 as those are fused; 10, 11 find it full again
    assert dropped == [0, 0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 1]
    assert [k for k, (d, _) in enumerate(out) if d["fused"][0]] == [0, 7, 8, 9]
    assert out[-1][0]["n_dropped"][0] == 5


def test_init_is_the_handover_estimate():
    """At t0 the horizon is t0 and the output is x0 in the deck frame; a level deck,
    not rotating, before the first broadcast."""
    rng = np.random.default_rng(9)
    x0, P0 = _x0_P0(rng)
    eta2 = np.array([0.02, 0.01, 1.2])
    mem = _init(3, 4, "axes", x0, P0, eta2, t0=3.0)
    lay = estimator_memory(3, 4, "axes")
    m = lay.unpack(mem)
    np.testing.assert_array_equal(m["x_h"], x0)
    np.testing.assert_array_equal(np.diag(_unpack_P(lay, "axes", mem)), P0)
    assert m["t_h"][0] == 3.0 and m["deck_tau"][0] == 3.0
    assert not np.any(m["hist"]) and not np.any(m["n_fused"])
    imu = IMU.pack(dict(eta_hat=[0.1, 0, 0], f_b=[0, 0, 9.8], omega=[0.1, 0.2, 0.3]))
    y = MEASUREMENT.unpack(_col(estimator_step_function(3, 4, "axes")(
        mem, imu, *[_empty(layout) for layout in PACKETS], _params(), 0.004, 3.0)[1]))
    R2 = rotation(eta2)
    np.testing.assert_allclose(y["p_e"], R2.T @ x0[_sl("p_r")], rtol=1e-14)
    np.testing.assert_allclose(y["v_e"], R2.T @ (x0[_sl("v1")] - x0[_sl("v_t")]), rtol=1e-14)
    np.testing.assert_array_equal(y["eta2"], eta2)
    np.testing.assert_array_equal(y["Omega1"], [0.1, 0.2, 0.3])


# ---------------------------------------------------------------- decoupled axes

def test_axes_equal_full_when_no_measurement_couples_the_axes():
    """A level deck and a vertical range: every block is separable, so the decoupled
    filter is the full one and the full one's cross-axis covariances stay zero."""
    rng = np.random.default_rng(31)
    n_hist, depth = 3, 4
    full, axes = (estimator_step_function(n_hist, depth, c) for c in ("full", "axes"))
    lay_f, lay_a = (estimator_memory(n_hist, depth, c) for c in ("full", "axes"))
    x0, P0 = _x0_P0(rng)
    mem_f, mem_a = (_init(n_hist, depth, c, x0, P0) for c in ("full", "axes"))
    p = _params(**OPEN_GATES)
    zero, up = np.zeros(3), np.array([0, 0, 1.0])
    for k in range(20):
        t = k * 0.01
        x = lay_f.unpack(mem_f)["x_h"]
        pk = {s: _packet_values(rng, s, x, t, zero, up) for s in ("vision", "gnss", "range",
                                                                  "datalink")}
        pk["range"]["b3_E"] = up
        vecs = [layout.pack(pk[layout.name]) for layout in PACKETS]
        imu = _imu(rng)
        mem_f = _col(full(mem_f, imu, *vecs, p, 0.01, t)[0])
        mem_a = _col(axes(mem_a, imu, *vecs, p, 0.01, t)[0])
    P_f, P_a = _unpack_P(lay_f, "full", mem_f), _unpack_P(lay_a, "axes", mem_a)
    np.testing.assert_allclose(lay_a.unpack(mem_a)["x_h"], lay_f.unpack(mem_f)["x_h"],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(P_a, P_f, rtol=1e-12, atol=1e-15)
    assert lay_f.unpack(mem_f)["n_fused"].sum() > 100


def test_axes_fuse_a_tilted_range_on_z_with_the_rest_as_noise(rng):
    """(E9a): the decoupled range update against its formula written out."""
    f = nav_update_function("range", "axes")
    pattern = covariance_pattern("axes")
    x = rng.normal(size=N)
    P = pattern.unpack_numeric(pattern.pack_numeric(_random_spd(rng, N)))
    n2 = rotation([0.1, -0.08, 0.3])[:, 2]
    b3 = np.array([0.1, 0.05, 1.0]) / np.linalg.norm([0.1, 0.05, 1.0])
    s = n2 @ x[_sl("p_r")] / (n2 @ b3) + 0.2
    pkt = RANGE.pack(dict(fresh=1.0, tau=0.0, s=s, b3_E=b3))
    h = np.zeros(N)
    h[_sl("p_r")] = n2 / (n2 @ b3)
    iz = NAV.slice("p_r").start + 2
    h_z, h_d = np.zeros(N), h.copy()
    h_z[iz], h_d[iz] = h[iz], 0.0
    r = ESTIMATOR_DEFAULTS["range_sigma"] ** 2 + h_d @ P @ h_d
    x_ref, P_ref, _, _ = _joseph(x, P, h_z[None, :], np.array([s - h @ x + h_z @ x]),
                                 np.array([[r]]))
    x_next, P_next, *_ = f(x, P, pkt, n2, _params(), 1.0)
    np.testing.assert_allclose(_col(x_next), x_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.array(P_next), P_ref, rtol=1e-12, atol=1e-14)

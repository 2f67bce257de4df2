"""The navigation filter's step against a textbook Kalman filter written in NumPy.

The references (tests/nav_reference.py): the model's matrices written from the
state equations (E2) index by index, SciPy's matrix exponential and Van Loan's
method, the full-matrix Joseph update; a seeded Monte Carlo on truth drawn
from the filter's own process model against chi-square bounds (SciPy).
"""

import numpy as np
import pytest
from nav_reference import (
    DIAG,
    OPEN_GATES,
    PARAMS,
    N,
    ReferenceKF,
    acceleration,
    body_turn,
    col,
    discrete,
    empty,
    init_memory,
    packet_values,
    params,
    random_imu,
    sl,
    unpack_P,
    vision_vector,
    x0_P0,
)
from reference import rotation
from scipy.stats import chi2

from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.estimator import (
    estimator_memory,
    estimator_step_function,
    output_predictor_function,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    ESTIMATOR_DEFAULTS,
    GNSS,
    IMU,
    NAV_PACKETS,
    VISION,
)

# ---------------------------------------------------------------- the textbook KF

def _run_undelayed(rng, coupling="full", steps=30, p_fresh=0.6, n_hist=0, depth=1):
    """Steps of the filter with packets taken at ``t`` and arriving at once, and the
    reference KF on the same data; yields both after each step."""
    step = estimator_step_function(n_hist, depth, coupling)
    lay = estimator_memory(n_hist, depth, coupling)
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": [0.3, 0.2, 0.4], "q_at": [0.5] * 3,
         "q_b": [0.01, 0.01, 0.03], "q_ab": [0.02, 0.01, 0.03]}
    p = PARAMS.pack(q)
    x0, P0 = x0_P0(rng)
    eta2 = np.array([0.05, -0.03, 0.7])
    mem = init_memory(n_hist, depth, coupling, x0, P0, eta2)
    ref = ReferenceKF(x0, np.diag(P0), q)
    dt = 0.01
    for k in range(steps):
        t = k * dt
        imu = random_imu(rng)
        if rng.uniform() < p_fresh:
            eta2 = eta2 + rng.normal(size=3) * 0.01
        n2 = rotation(eta2)[:, 2]
        packets = {s: packet_values(rng, s, ref.x, t, eta2, n2)
                   for s in ("vision", "gnss", "range", "datalink") if rng.uniform() < p_fresh}
        if "datalink" not in packets:
            eta2 = lay.unpack(mem)["deck_eta2"]
            n2 = rotation(eta2)[:, 2]
        vecs = [layout.pack(packets[layout.name]) if layout.name in packets else empty(layout)
                for layout in NAV_PACKETS]
        mem, y, diag = (col(v) for v in step(mem, imu, *vecs, p, dt, t))
        nis = ref.fuse(packets, n2)
        fused = dict(x=ref.x.copy(), P=ref.P.copy())
        ref.predict(acceleration(imu, q["g"]), dt, body_turn(imu, dt))
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
        np.testing.assert_allclose(unpack_P(r["lay"], "full", r["mem"]), ref.P, rtol=1e-10,
                                   atol=1e-12)
    assert fused > 50

# ---------------------------------------------------------------- the delayed horizon

#: Latency of each sensor in periods (all below the horizon's 6) and its period.
LATENCY = dict(vision=2, gnss=5, range=0, datalink=3)
EVERY = dict(vision=3, gnss=7, range=2, datalink=4)


def test_delayed_fusion_is_the_undelayed_filter_shifted_by_the_horizon():
    """Packets L < D late: the horizon holds, exactly, the KF that fused each at its time,
    n_hist periods ago; the output is that estimate carried through the buffered inputs."""
    rng = np.random.default_rng(2017)
    n_hist, depth, dt, steps = 6, 3, 0.01, 60
    step = estimator_step_function(n_hist, depth)
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": [0.3] * 3, "q_at": [0.5] * 3}
    p = PARAMS.pack(q)
    x0, P0 = x0_P0(rng)
    eta2 = np.array([0.04, -0.02, 0.3])                # one deck attitude: n2 is the same
    n2, R2 = rotation(eta2)[:, 2], rotation(eta2)
    mem = init_memory(n_hist, depth, "full", x0, P0, eta2)
    ref = ReferenceKF(x0, np.diag(P0), q)
    history, inputs, arrivals = [], [], {}
    for k in range(steps):
        t = k * dt
        imu = random_imu(rng)
        packets = {s: packet_values(rng, s, ref.x, t, eta2, n2)
                   for s in LATENCY if k % EVERY[s] == 0}
        ref.fuse(packets, n2)
        history.append((ref.x.copy(), ref.P.copy()))
        a_in = acceleration(imu, q["g"])
        inputs.append(a_in)
        ref.predict(a_in, dt, body_turn(imu, dt))
        for s, pk in packets.items():
            arrivals[(k + LATENCY[s], s)] = pk
        vecs = [layout.pack(arrivals[(k, layout.name)]) if (k, layout.name) in arrivals
                else empty(layout) for layout in NAV_PACKETS]
        mem, y, diag = (col(v) for v in step(mem, imu, *vecs, p, dt, t))
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
            Phi, Gamma, _ = discrete(dt, q, held=True)
            x_now = Phi @ x_now + Gamma @ a
        ys = LANDING_MEASUREMENT.unpack(y)
        np.testing.assert_allclose(ys["p_e"], R2.T @ x_now[sl("p_r")], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["v_e"], R2.T @ (x_now[sl("v1")] - x_now[sl("v_t")]),
                                   rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["v2E"], x_now[sl("v_t")], rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(ys["a2E"], x_now[sl("a_t")], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ys["eta2"], eta2, atol=1e-15)
        np.testing.assert_array_equal(ys["eta1"], IMU.unpack(imu)["eta_hat"])
    assert d["n_fused"].sum() > 40 and d["n_discarded"].sum() == 0
    assert d["n_dropped"].sum() == 0 and d["n_rejected"].sum() == 0


def test_output_predictor_is_the_chained_prediction(rng):
    """(E17) in closed form against N steps of Phi, Gamma with varying periods (the tilt
    bias held, as (E17) carries it)."""
    n = 7
    f = output_predictor_function(n)
    q = dict(ESTIMATOR_DEFAULTS)
    x = rng.normal(size=N)
    hist = np.vstack([rng.normal(size=(3, n)) * 3, rng.uniform(0, 0.02, n)])
    hist[3, 2] = 0.0                                       # an empty period
    x_ref = x.copy()
    for k in range(n):
        Phi, Gamma, _ = discrete(hist[3, k], q, held=True)
        x_ref = Phi @ x_ref + Gamma @ hist[:3, k]
    np.testing.assert_allclose(col(f(x, hist, 0.0)), x_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(col(output_predictor_function(0)(x, np.zeros((4, 0)), 0.0)),
                                  x)

# ---------------------------------------------------------------- consistency

MC_RUNS, MC_STEPS, MC_DT = 100, 150, 0.01
MC_LATENCY = dict(vision=2, gnss=3, range=1, datalink=2)
MC_EVERY = dict(vision=3, gnss=10, range=2, datalink=5)


def _mc_truth(rng, q, x0, P0, Phi, Gamma, Q):
    """Truth from the filter's own model: x0 ~ N(x0_hat, P0), x+ = Phi x + Gamma a + w,
    the accelerometer's bias turned with the body (E6a)."""
    L = np.linalg.cholesky(Q + 1e-18 * np.eye(N))
    xs = np.empty((MC_STEPS + 1, MC_RUNS, N))
    xs[0] = x0 + rng.normal(size=(MC_RUNS, N)) * np.sqrt(P0)
    imus = np.empty((MC_STEPS, MC_RUNS, IMU.size))
    for k in range(MC_STEPS):
        for r in range(MC_RUNS):
            imus[k, r] = random_imu(rng)
        a = np.array([acceleration(imu, q["g"]) for imu in imus[k]])
        xs[k + 1] = xs[k] @ Phi.T + a @ Gamma.T + rng.normal(size=(MC_RUNS, N)) @ L.T
        turn = np.array([body_turn(imu, MC_DT) for imu in imus[k]])
        xs[k + 1][:, sl("a_b")] += np.cross(turn, xs[k][:, sl("a_b")])
    return xs, imus


def _mc_packet(rng, sensor, x, tau, eta2, n2, b3, q):
    """A packet drawn from (E10)-(E14) at the true state with the filter's noise."""
    def noise(sigma):
        return rng.normal(size=3) * sigma
    if sensor == "vision":
        return dict(fresh=1.0, tau=tau, r_E=vision_vector(x, noise(q["vision_sigma0"]),
                                                          q["g"]))
    if sensor == "gnss":
        return dict(fresh=1.0, tau=tau,
                    rel=-x[sl("p_r")] + x[sl("b")] + noise(np.array(q["gnss_rel_sigma"])),
                    v1=x[sl("v1")] + noise(np.array(q["gnss_v1_sigma"])),
                    vt=x[sl("v_t")] + noise(np.array(q["gnss_vt_sigma"])))
    if sensor == "range":
        return dict(fresh=1.0, tau=tau, s=n2 @ x[sl("p_r")] / (n2 @ b3)
                    + rng.normal() * q["range_sigma"], b3_E=b3)
    return dict(fresh=1.0, tau=tau, eta2=eta2,
                v2E=x[sl("v_t")] + noise(np.array(q["datalink_v_sigma"])),
                a2E=x[sl("a_t")] + noise(np.array(q["datalink_a_sigma"])),
                w2E=np.zeros(3), w2E_dot=np.zeros(3))


@pytest.mark.slow
def test_monte_carlo_nees_and_nis_lie_in_their_chi_square_bounds():
    """100 runs on truth from the process model, every sensor late by less than the
    horizon: the average NEES of the 21 states at the end and each block's average NIS
    (innovations of a consistent filter are white, so all fusions pool) lie inside their
    two-sided 95 % chi-square bounds. Gates open and the vision noise range-free: both
    make R or the accepted set depend on the draw, which (E8) tests apart."""
    rng = np.random.default_rng(20171)
    n_hist, depth = 4, 4
    q = {**ESTIMATOR_DEFAULTS, **OPEN_GATES, "q_acc": [0.05] * 3, "q_at": [0.2] * 3,
         "q_b": [0.01] * 3, "q_ab": [0.01] * 3, "tilt_sigma": [0.1] * 3, "tilt_tau": 2.0,
         "vision_k_range": 0.0}
    p = PARAMS.pack(q)
    x0 = np.zeros(N)
    x0[sl("p_r")] = [0.5, -0.5, 4.0]
    P0 = np.concatenate([[1.0] * 3, [0.25] * 6, [0.1] * 3, [1.0] * 3, [0.01] * 6])
    Phi, Gamma, Q = discrete(MC_DT, q)
    xs, imus = _mc_truth(rng, q, x0, P0, Phi, Gamma, Q)
    eta2 = np.array([0.03, -0.02, 0.5])
    n2, b3 = rotation(eta2)[:, 2], np.array([0.05, 0.03, 1.0]) / np.linalg.norm([0.05, 0.03, 1])
    step = estimator_step_function(n_hist, depth).map(MC_RUNS)
    lay = estimator_memory(n_hist, depth)
    mem = np.tile(init_memory(n_hist, depth, "full", x0, P0, eta2)[:, None], (1, MC_RUNS))
    arrivals, nis = {}, {b.name: [] for b in BLOCKS}
    for k in range(MC_STEPS):
        for s in MC_LATENCY:
            if k % MC_EVERY[s] == 0:
                arrivals[(k + MC_LATENCY[s], s)] = [
                    _mc_packet(rng, s, xs[k, r], k * MC_DT, eta2, n2, b3, q)
                    for r in range(MC_RUNS)]
        vecs = [np.column_stack([layout.pack(v) for v in arrivals[(k, layout.name)]])
                if (k, layout.name) in arrivals else np.zeros((layout.size, MC_RUNS))
                for layout in NAV_PACKETS]
        mem, _, diag = step(mem, imus[k].T, *vecs, p, MC_DT, k * MC_DT)
        mem, d = np.array(mem), DIAG.unpack(np.array(diag))
        for i, b in enumerate(BLOCKS):
            nis[b.name] += list(d["nis"][i][d["fused"][i] == 1])
    j = int(round(lay.unpack(mem[:, 0])["t_h"][0] / MC_DT))
    nees = []
    for r in range(MC_RUNS):
        m = lay.unpack(mem[:, r])
        e = m["x_h"] - xs[j, r]
        nees.append(e @ np.linalg.solve(unpack_P(lay, "full", mem[:, r]), e))
    lo, hi = chi2.ppf([0.025, 0.975], MC_RUNS * N) / MC_RUNS
    assert lo <= np.mean(nees) <= hi, (np.mean(nees), lo, hi)
    for b in BLOCKS:
        n = len(nis[b.name])
        assert n >= 10 * MC_RUNS
        lo, hi = chi2.ppf([0.025, 0.975], n * b.dim) / n
        assert lo <= np.mean(nis[b.name]) <= hi, (b.name, np.mean(nis[b.name]), lo, hi)

# ---------------------------------------------------------------- unchanged when not fused

def test_rejected_and_not_due_packets_leave_the_step_bit_exact(rng):
    """Through the step: a rejected vision outlier and a non-finite GNSS packet (not
    queued) give the same state and covariance as no packet at all, and are counted."""
    n_hist, depth = 3, 4
    step, lay = estimator_step_function(n_hist, depth), estimator_memory(n_hist, depth)
    p = params()
    x0, P0 = x0_P0(rng)
    mem = init_memory(n_hist, depth, "full", x0, P0)
    mem_a = mem_b = mem
    imu = random_imu(rng)
    for k in range(8):
        t = k * 0.01
        vis = VISION.pack(dict(fresh=1.0, tau=t, r_E=[50.0, 0, 0]))
        gnss = GNSS.pack(dict(fresh=1.0, tau=t, rel=[np.nan] * 3, v1=[np.inf] * 3,
                              vt=[1e300, np.nan, 0.0]))
        none = [empty(layout) for layout in NAV_PACKETS]
        mem_a = col(step(mem_a, imu, vis, gnss, *none[2:], p, 0.01, t)[0])
        mem_b = col(step(mem_b, imu, *none, p, 0.01, t)[0])
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
    p = params(**OPEN_GATES, **over)
    x0 = np.zeros(N)
    x0[sl("p_r")] = [0, 0, 3.0]
    mem = init_memory(n_hist, depth, "full", x0, np.ones(N))
    imu = IMU.pack(dict(eta_hat=np.zeros(3), f_b=[0, 0, 9.8], omega=np.zeros(3)))
    out = []
    for k in range(steps):
        tau = taus_by_step.get(k)
        vis = (VISION.pack(dict(fresh=1.0, tau=tau, r_E=[0, 0, -3.0])) if tau is not None
               else empty(VISION))
        mem, _, d = step(mem, imu, vis, *[empty(layout) for layout in NAV_PACKETS[1:]], p, 0.01,
                         k * 0.01)
        mem = col(mem)
        out.append((DIAG.unpack(col(d)), lay.unpack(mem)))
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
    x0, P0 = x0_P0(rng)
    eta2 = np.array([0.02, 0.01, 1.2])
    mem = init_memory(3, 4, "axes", x0, P0, eta2, t0=3.0)
    lay = estimator_memory(3, 4, "axes")
    m = lay.unpack(mem)
    np.testing.assert_array_equal(m["x_h"], x0)
    np.testing.assert_array_equal(np.diag(unpack_P(lay, "axes", mem)), P0)
    assert m["t_h"][0] == 3.0 and m["deck_tau"][0] == 3.0
    assert not np.any(m["hist"]) and not np.any(m["n_fused"])
    imu = IMU.pack(dict(eta_hat=[0.1, 0, 0], f_b=[0, 0, 9.8], omega=[0.1, 0.2, 0.3]))
    y = LANDING_MEASUREMENT.unpack(col(estimator_step_function(3, 4, "axes")(
        mem, imu, *[empty(layout) for layout in NAV_PACKETS], params(), 0.004, 3.0)[1]))
    R2 = rotation(eta2)
    np.testing.assert_allclose(y["p_e"], R2.T @ x0[sl("p_r")], rtol=1e-14)
    np.testing.assert_allclose(y["v_e"], R2.T @ (x0[sl("v1")] - x0[sl("v_t")]), rtol=1e-14)
    np.testing.assert_array_equal(y["eta2"], eta2)
    np.testing.assert_array_equal(y["Omega1"], [0.1, 0.2, 0.3])

# ---------------------------------------------------------------- decoupled axes

def test_axes_equal_full_when_no_measurement_couples_the_axes():
    """A level deck, a vertical range and a body that does not turn (the bias' turn
    (E6a) couples the axes): every block is separable, so the decoupled filter is the
    full one and the full one's cross-axis covariances stay zero."""
    rng = np.random.default_rng(31)
    n_hist, depth = 3, 4
    full, axes = (estimator_step_function(n_hist, depth, c) for c in ("full", "axes"))
    lay_f, lay_a = (estimator_memory(n_hist, depth, c) for c in ("full", "axes"))
    x0, P0 = x0_P0(rng)
    mem_f, mem_a = (init_memory(n_hist, depth, c, x0, P0) for c in ("full", "axes"))
    p = params(**OPEN_GATES)
    zero, up = np.zeros(3), np.array([0, 0, 1.0])
    for k in range(20):
        t = k * 0.01
        x = lay_f.unpack(mem_f)["x_h"]
        pk = {s: packet_values(rng, s, x, t, zero, up) for s in ("vision", "gnss", "range",
                                                                  "datalink")}
        pk["range"]["b3_E"] = up
        vecs = [layout.pack(pk[layout.name]) for layout in NAV_PACKETS]
        imu = IMU.pack(IMU.unpack(random_imu(rng)) | dict(omega=zero))
        mem_f = col(full(mem_f, imu, *vecs, p, 0.01, t)[0])
        mem_a = col(axes(mem_a, imu, *vecs, p, 0.01, t)[0])
    P_f, P_a = unpack_P(lay_f, "full", mem_f), unpack_P(lay_a, "axes", mem_a)
    np.testing.assert_allclose(lay_a.unpack(mem_a)["x_h"], lay_f.unpack(mem_f)["x_h"],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(P_a, P_f, rtol=1e-12, atol=1e-15)
    assert lay_f.unpack(mem_f)["n_fused"].sum() > 100

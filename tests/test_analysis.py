"""Margins of textbook loops against closed-form values."""

import math

import control
import numpy as np
import pytest
import scipy.optimize

from quadland.analysis import (
    allmargin,
    closed_loop_poles,
    disk_gain_margin,
    disk_phase_margin,
    diskmargin,
    freqresp,
)


def _third_order():
    """L = 1/(s(s+1)(s+2)): |L(j sqrt2)| = 1/6, gain crossover w^6 + 5 w^4 + 4 w^2 = 1."""
    wc = math.sqrt(max(r.real for r in np.roots([1, 5, 4, -1]) if abs(r.imag) < 1e-12))
    pm = 90 - math.degrees(math.atan(wc) + math.atan(wc / 2))
    return control.tf([1], [1, 3, 2, 0]), dict(gm=[6.0], wg=[math.sqrt(2)], pm=[pm], wc=[wc])


def _cubic_lag():
    """L = 2/(s+1)^3: phase -180 at w = tan(60 deg), |L| = 2/8; |L| = 1 at (1+w^2) = 2^(2/3)."""
    wc = math.sqrt(2 ** (2 / 3) - 1)
    return (control.tf([2], [1, 3, 3, 1]),
            dict(gm=[4.0], wg=[math.sqrt(3)], pm=[180 - 3 * math.degrees(math.atan(wc))],
                 wc=[wc]))


def _conditionally_stable():
    """L = (s+1)^2/s^3: phase -180 at w = 1 with |L| = 2 (gain-reduction margin 1/2);
    |L| = 1 where w^3 - w^2 - 1 = 0, PM = 2 atan(wc) - 90 deg."""
    wc = max(r.real for r in np.roots([1, -1, 0, -1]) if abs(r.imag) < 1e-12)
    return (control.tf([1, 2, 1], [1, 0, 0, 0]),
            dict(gm=[0.5], wg=[1.0], pm=[2 * math.degrees(math.atan(wc)) - 90], wc=[wc]))


def _integrator():
    """L = 4/s: no phase crossing, PM = 90 deg at w = 4."""
    return control.tf([4], [1, 0]), dict(gm=[], wg=[], pm=[90.0], wc=[4.0])


def _discrete_integrator():
    """L(z) = k T/(z - 1), T = 0.1, k = 1: L(-1) = -kT/2, so GM = 20 at pi/T;
    |e^{jwT} - 1| = 2 sin(wT/2) = kT at crossover, PM = 90 - wT/2 (deg)."""
    T, k = 0.1, 1.0
    wc = 2 / T * math.asin(k * T / 2)
    return (control.tf([k * T], [1, -1], T),
            dict(gm=[2 / (k * T)], wg=[math.pi / T], pm=[90 - math.degrees(wc * T / 2)], wc=[wc]))


CASES = [_third_order, _cubic_lag, _conditionally_stable, _integrator, _discrete_integrator]


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.__name__.strip("_"))
def test_allmargin_siso_closed_form(case):
    L, ref = case()
    m, = allmargin(L)
    assert m.stable
    np.testing.assert_allclose(m.gain_margin, ref["gm"], rtol=1e-8)
    np.testing.assert_allclose(m.gm_frequency, ref["wg"], rtol=1e-8)
    np.testing.assert_allclose(m.phase_margin, ref["pm"], rtol=1e-8)
    np.testing.assert_allclose(m.pm_frequency, ref["wc"], rtol=1e-8)
    # a delay tau adds phase -w tau: the margin is PM (rad) / wc
    np.testing.assert_allclose(m.delay_margin, np.radians(ref["pm"]) / np.array(ref["wc"]),
                               rtol=1e-8)


def _double_integrator_lead():
    """L = K (T s + 1)/s^2, K = 2, T = 1: the phase -180 + atan(wT) never reaches -180
    again; |L| = 1 where w^4 = K^2 (1 + w^2 T^2), PM = atan(wc T)."""
    K, T = 2.0, 1.0
    x = max(r.real for r in np.roots([1, -K * K * T * T, -K * K]) if abs(r.imag) < 1e-12)
    wc = math.sqrt(x)
    return (control.tf([K * T, K], [1, 0, 0]),
            dict(gm=[], wg=[], pm=[math.degrees(math.atan(wc * T))], wc=[wc]))


def _quadruple_integrator():
    """L = 2 (s+1)^3/s^4: phase -360 + 3 atan(w) is -180 at w = sqrt 3 with |L| = 16/9
    (gain-reduction margin 9/16); |L| = 1 where 4 (1 + x)^3 = x^4, x = w^2; the closed
    loop s^4 + 2 (s+1)^3 is stable (Routh: k = 2 > 9/8)."""
    x = max(r.real for r in np.roots([1, -4, -12, -12, -4]) if abs(r.imag) < 1e-12)
    wc = math.sqrt(x)
    return (control.tf([2, 6, 6, 2], [1, 0, 0, 0, 0]),
            dict(gm=[9 / 16], wg=[math.sqrt(3)], pm=[3 * math.degrees(math.atan(wc)) - 180],
                 wc=[wc]))


def _slow_cubic_lag():
    """L = 2 a^3/(s + a)^3, a = 1e-4: the cubic lag 1e4 times slower, a genuine slow
    triple pole that must not be mistaken for roundoff."""
    a = 1e-4
    wc = a * math.sqrt(2 ** (2 / 3) - 1)
    return (control.tf([2 * a ** 3], [1, 3 * a, 3 * a * a, a ** 3]),
            dict(gm=[4.0], wg=[a * math.sqrt(3)], pm=[180 - 3 * math.degrees(math.atan(wc / a))],
                 wc=[wc]))


def _near_cancelled_lead():
    """L = 6.28 (s + 3.6) / (s^2 (s + 3.8)): the phase -180 + atan(w/3.6) - atan(w/3.8) stays
    within 0.6 deg above -180 and never reaches it (no gain margin); |L| = 1 where
    x^3 + 3.8^2 x^2 - 6.28^2 x - 6.28^2 3.6^2 = 0, x = w^2, PM = atan(wc/3.6) - atan(wc/3.8).
    The closed loop s^3 + 3.8 s^2 + 6.28 s + 22.6 is stable (Routh: 3.8 * 6.28 > 22.6)."""
    k, a, b = 6.28, 3.6, 3.8
    x = max(r.real for r in np.roots([1, b * b, -k * k, -k * k * a * a]) if abs(r.imag) < 1e-12)
    wc = math.sqrt(x)
    return (control.tf([k, k * a], [1, b, 0, 0]),
            dict(gm=[], wg=[], pm=[math.degrees(math.atan(wc / a) - math.atan(wc / b))],
                 wc=[wc]))


INTEGRATOR_CASES = [_conditionally_stable, _double_integrator_lead, _quadruple_integrator,
                    _integrator, _near_cancelled_lead]


def _companion(L):
    """An exact controllable-canonical realization (integer entries, exact zeros)."""
    import scipy.signal

    num, den = (np.asarray(v, dtype=float).ravel() for v in control.tfdata(L)[:2])
    A, B, C, D = scipy.signal.tf2ss(num, den)
    return control.ss(A, B, C, D)


def _assert_margins(m, ref):
    assert m.stable
    np.testing.assert_allclose(m.gain_margin, ref["gm"], rtol=1e-7)
    np.testing.assert_allclose(m.gm_frequency, ref["wg"], rtol=1e-7)
    np.testing.assert_allclose(m.phase_margin, ref["pm"], rtol=1e-7)
    np.testing.assert_allclose(m.pm_frequency, ref["wc"], rtol=1e-7)


@pytest.mark.parametrize("realize", [control.ss, _companion], ids=["control.ss", "companion"])
@pytest.mark.parametrize("case", INTEGRATOR_CASES, ids=lambda c: c.__name__.strip("_"))
def test_allmargin_repeated_integrators_both_realizations(case, realize):
    """control.ss goes through slycot when it is installed and leaves ~1e-16 in the
    entries of A, which splits a k-fold integrator into k poles of ~eps^(1/k); the
    companion form keeps them exactly at zero. Both must give the closed form."""
    L, ref = case()
    m, = allmargin(realize(L))
    _assert_margins(m, ref)


def _perturbed(base, rng):
    """Random similarity transforms (condition number up to ~1e2) and entry noise of
    1e-14 ||A||."""
    A, B, C, D = (np.asarray(v, dtype=float) for v in (base.A, base.B, base.C, base.D))
    n = A.shape[0]
    for _ in range(10):
        T = np.eye(n) + 0.5 * rng.standard_normal((n, n))
        Ti = np.linalg.inv(T)
        noise = 1e-14 * np.linalg.norm(A, 2) * rng.standard_normal((n, n))
        yield control.ss(Ti @ A @ T + noise, Ti @ B, C @ T, D)


@pytest.mark.parametrize("case", INTEGRATOR_CASES, ids=lambda c: c.__name__.strip("_"))
def test_allmargin_perturbed_realizations(case):
    """Perturbations scatter repeated integrators further; the margins must not move."""
    L, ref = case()
    for sys in _perturbed(_companion(L), np.random.default_rng(7)):
        m, = allmargin(sys)
        _assert_margins(m, ref)


def test_allmargin_orthogonal_changes_of_coordinates():
    """Random orthogonal similarity transforms (condition number 1): the phase of the
    near-cancelled lead sits within roundoff of -180 deg near w = 0, where the sign of
    Im L is not fixed by the data; no crossing may be reported there."""
    L, ref = _near_cancelled_lead()
    base = _companion(L)
    A, B, C, D = (np.asarray(v, dtype=float) for v in (base.A, base.B, base.C, base.D))
    rng = np.random.default_rng(5)
    for _ in range(50):
        Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        m, = allmargin(control.ss(Q.T @ A @ Q, Q.T @ B, C @ Q, D))
        _assert_margins(m, ref)


def test_allmargin_keeps_a_genuine_slow_triple_pole():
    """A well-scaled realization of a triple pole at -1e-4 (control.ss balances it), and
    perturbations of it: its crossings near 1e-4 rad/s are the loop's own. (The
    companion form of the same loop puts a^3 = 1e-12 beside unit entries; roundoff of
    1e-14 there moves the gain margin by 1e-3, and allmargin's error bound says so.)"""
    L, ref = _slow_cubic_lag()
    base = control.ss(L)
    m, = allmargin(base)
    _assert_margins(m, ref)
    for sys in _perturbed(base, np.random.default_rng(8)):
        m, = allmargin(sys)
        _assert_margins(m, ref)


def test_allmargin_agrees_with_python_control_on_small_loops():
    for case in (_third_order, _cubic_lag):
        L, _ = case()
        gm, pm, _, wg, wc, _ = control.stability_margins(L)
        m, = allmargin(L)
        assert m.gain_margin[0] == pytest.approx(gm, rel=1e-7)
        assert m.phase_margin[0] == pytest.approx(pm, rel=1e-7)
        assert m.gm_frequency[0] == pytest.approx(wg, rel=1e-7)
        assert m.pm_frequency[0] == pytest.approx(wc, rel=1e-7)


def _padded(L, n_extra, rng):
    """A realization of L with n_extra more states that the output never sees.

    Like the adaptive states of the flight loop: driven by the loop, many
    of them, and absent from its transfer function.
    """
    s = control.ss(L)
    n = s.nstates
    A1 = np.diag(-rng.uniform(0.01, 50.0, n_extra))
    X = rng.standard_normal((n_extra, n))
    A = np.block([[s.A, np.zeros((n, n_extra))], [X, A1]])
    B = np.vstack([s.B, rng.standard_normal((n_extra, 1))])
    C = np.hstack([s.C, np.zeros((1, n_extra))])
    return control.ss(A, B, C, s.D)


def test_margins_of_a_400_state_realization(rng):
    L, ref = _third_order()
    big = _padded(L, 400, rng)
    m, = allmargin(big)
    assert m.stable
    np.testing.assert_allclose(m.gain_margin, ref["gm"], rtol=1e-7)
    np.testing.assert_allclose(m.phase_margin, ref["pm"], rtol=1e-7)
    (dm,), _ = diskmargin(big)
    (dm3,), _ = diskmargin(L)
    assert dm.disk_margin == pytest.approx(dm3.disk_margin, rel=1e-6)


def test_freqresp_matches_the_transfer_function():
    L, _ = _cubic_lag()
    w = np.logspace(-2, 2, 7)
    s = 1j * w
    np.testing.assert_allclose(freqresp(L, w)[:, 0, 0], 2 / (s + 1) ** 3, rtol=1e-10)


def _siso_disk_reference(num, den):
    """alpha = 1/max_w |S - 1/2| by brute force on the polynomials."""
    def f(w):
        L = np.polyval(num, 1j * w) / np.polyval(den, 1j * w)
        return abs(1 / (1 + L) - 0.5)
    w = np.logspace(-3, 3, 200001)
    k = int(np.argmax(f(w)))
    res = scipy.optimize.minimize_scalar(lambda x: -f(x), bounds=(w[k - 1], w[k + 1]),
                                         method="bounded", options=dict(xatol=1e-12))
    return 1 / -res.fun, res.x


@pytest.mark.parametrize("num,den", [([1], [1, 3, 2, 0]), ([25], [1, 10, 10, 10]),
                                     ([2], [1, 3, 3, 1])])
def test_diskmargin_siso(num, den):
    alpha, w = _siso_disk_reference(num, den)
    (dm,), multi = diskmargin(control.tf(num, den))
    assert dm.disk_margin == pytest.approx(alpha, rel=1e-7)
    assert dm.frequency == pytest.approx(w, rel=1e-3)
    assert multi == dm
    lo, hi = dm.gain_margin
    assert lo == pytest.approx((1 - alpha / 2) / (1 + alpha / 2), rel=1e-7)
    assert hi == pytest.approx(1 / lo, rel=1e-9)
    assert dm.phase_margin == pytest.approx(math.degrees(2 * math.atan(alpha / 2)), rel=1e-7)
    # the disk is inside the classical margins: a gain of hi or a pure phase shift of
    # phase_margin cannot reach -1 before the classical margins do
    m, = allmargin(control.tf(num, den))
    if m.gain_margin:
        assert hi <= min(g for g in m.gain_margin if g > 1) + 1e-9
    assert dm.phase_margin <= min(m.phase_margin) + 1e-9


def test_disk_of_an_integrator_is_the_whole_half_plane():
    # L = k/s: S - T = (s - k)/(s + k) is all-pass, so alpha = 2: gain (0, inf), phase 90 deg
    (dm,), _ = diskmargin(control.tf([3], [1, 0]))
    assert dm.disk_margin == pytest.approx(2.0, rel=1e-9)
    assert dm.gain_margin == (0.0, math.inf)
    assert dm.phase_margin == pytest.approx(90.0, rel=1e-7)


def test_disk_formulas():
    # a balanced disk of alpha = 2 (1 - g)/(1 + g) has the real-axis intercepts g and 1/g
    for g in (0.1, 0.5, 0.9):
        alpha = 2 * (1 - g) / (1 + g)
        lo, hi = disk_gain_margin(alpha)
        assert lo == pytest.approx(g) and hi == pytest.approx(1 / g)
    assert disk_phase_margin(2.0) == pytest.approx(90.0)


def _satellite(a=10.0):
    """Spinning satellite (Doyle; Skogestad and Postlethwaite, Zhou, Doyle and Glover):
    G = 1/(s^2 + a^2) [[s - a^2, a (s + 1)], [-a (s + 1), s - a^2]], K = I."""
    return control.ss([[0, a], [-a, 0]], np.eye(2), [[1, a], [-a, 1]], np.zeros((2, 2)))


def test_satellite_loop_at_a_time_looks_perfect():
    # with either loop closed, the other sees 1/s: no phase crossing, PM 90 deg at 1 rad/s
    L = _satellite()
    margins = allmargin(L)
    assert len(margins) == 2
    for m in margins:
        assert m.stable
        assert m.gain_margin == ()
        np.testing.assert_allclose(m.phase_margin, [90.0], rtol=1e-8)
        np.testing.assert_allclose(m.pm_frequency, [1.0], rtol=1e-8)
        np.testing.assert_allclose(m.delay_margin, [math.pi / 2], rtol=1e-8)
    per_loop, _ = diskmargin(L)
    for dm in per_loop:  # S_i = s/(s+1): |S_i - 1/2| = 1/2 at every frequency
        assert dm.disk_margin == pytest.approx(2.0, rel=1e-6)


@pytest.mark.slow
def test_satellite_multiloop_disk_margin_is_poor():
    # T = 1/(s+1) [[1, a], [-a, 1]]; S - I/2 = 1/(s+1) ((s-1)/2 I + a J) with J skew, a
    # normal matrix, so mu = its spectral radius: max over w of
    # sqrt((1/4 + (w/2 + a)^2) / (1 + w^2)), reached at w = sqrt(a^2 + 1) - a.
    a = 10.0
    w = math.sqrt(a * a + 1) - a
    alpha = 1 / math.sqrt((0.25 + (w / 2 + a) ** 2) / (1 + w * w))
    _, multi = diskmargin(_satellite(a))
    assert multi.disk_margin == pytest.approx(alpha, rel=1e-6)
    assert multi.frequency == pytest.approx(w, rel=1e-2)
    assert multi.gain_margin[1] < 1.11 and multi.phase_margin < 6.0


def test_unstable_loop_has_no_margin():
    L = control.tf([1], [1, -1])           # closed loop s = 0: not stable
    m, = allmargin(L)
    assert not m.stable
    (dm,), multi = diskmargin(control.tf([0.5], [1, -1]))
    assert dm.disk_margin == 0.0 and multi.disk_margin == 0.0


def test_closed_loop_poles():
    np.testing.assert_allclose(sorted(closed_loop_poles(control.tf([2], [1, 1])).real), [-3.0])


def _max_real_pole(L, gains):
    """Largest real part of the poles of the loop closed through diag(gains)."""
    A, B, C = (np.asarray(m) for m in (L.A, L.B, L.C))
    return np.linalg.eigvals(A - B @ np.diag(gains) @ C).real.max()


@pytest.mark.slow
def test_flight_loop_margins_are_where_its_poles_cross():
    """Independent check on the 4 x 4, 40-state flight loop (l = 5): scale one loop's
    gain across each reported gain margin and watch the closed-loop eigenvalues; any
    diagonal gain inside the multiloop disk interval keeps the loop stable."""
    from quadland.linearization import equilibrium, linear_models
    from quadland.scenario import load_scenario

    sc = load_scenario("paper", ["rbf.nodes=5"])
    L = linear_models(sc, equilibrium(sc)).loop_input
    assert np.allclose(L.D, 0)
    assert _max_real_pole(L, np.ones(4)) < 0
    margins = allmargin(L)
    assert sum(len(m.gain_margin) for m in margins) >= 2
    for i, m in enumerate(margins):
        for gm in m.gain_margin:
            g = np.ones(4)
            g[i] = gm
            # the closed loop has a pole on the imaginary axis at the crossing frequency
            p = np.linalg.eigvals(np.asarray(L.A) - np.asarray(L.B) @ np.diag(g)
                                  @ np.asarray(L.C))
            assert np.min(np.abs(p.real)) < 1e-6 * max(1.0, gm ** -1)
            w = m.gm_frequency[m.gain_margin.index(gm)]
            k = np.argmin(np.abs(p.real))
            assert abs(abs(p[k].imag) - w) < 1e-5 * max(w, 1e-3)
    _, multi = diskmargin(L)
    lo, hi = multi.gain_margin
    rng = np.random.default_rng(1)
    for _ in range(20):
        g = np.exp(rng.uniform(np.log(lo) + 1e-3, np.log(hi) - 1e-3, 4))
        assert _max_real_pole(L, g) < 0


# ---------------------------------------------------------------- python-control's disk_margins
#
# Both libraries bound the multiloop (balanced, skew 0) disk margin through
# M(w) = S - I/2 = (S - T)/2 and a diagonal perturbation of independent complex
# scalars: alpha = 1 / max_w nu(M(w)), where nu is an upper bound of mu.
#
# * quadland: nu_q = sigma_max(D M D^-1) at the D its minimization over log D ends
#   at (convex, Nelder-Mead to 1e-8 in log D);
# * python-control 0.10.2 (``control.disk_margins(L, omega, skew=0.0)``): slycot's
#   ``ab13md`` with every block complex (itype 2). Its bound is Fan, Tits and Doyle's
#   (1991); their G-scalings act on real blocks only, so for complex blocks it is the
#   same D-scaled bound, to AB13MD's internal threshold TOL = 100 sqrt(eps) = 1.5e-6.
#
# Each is an achieved value of sigma_max(D M D^-1), so both are >= the infimum
# nu* >= mu: per frequency nu* <= nu_q, nu_pc, hence on the same frequencies
# alpha_pc <= alpha_q (up to quadland's own slack, ~1e-10) and alpha_q <= alpha_pc
# (1 + TOL), quadland's alpha being the larger where ab13md stops early. Both are
# lower bounds of the true margin 1 / max mu; where the D-scaled bound equals mu
# (one channel; up to three complex scalar blocks, Packard and Doyle 1993; normal M,
# with D = I) both are the true margin. python-control takes the maximum over the
# frequencies it is given and quadland refines its peak, so on any other set of
# frequencies python-control's alpha can only be larger (it may miss the peak).
# python-control does not check stability: it is compared on stable loops only.

#: AB13MD's convergence threshold, 100 sqrt(eps) (SLICOT AB13MD, "Set tolerances").
_AB13MD_TOL = 100 * math.sqrt(np.finfo(float).eps)

#: The runtime needs python-control >= 0.10.1; disk_margins came in 0.10.2.
needs_disk_margins = pytest.mark.skipif(not hasattr(control, "disk_margins"),
                                        reason="control.disk_margins needs python-control "
                                               ">= 0.10.2")


def _control_disk_margin(L, omega):
    """python-control's multiloop disk margin alpha on the frequencies omega."""
    dm, _, _ = control.disk_margins(L, np.asarray(omega, dtype=float), skew=0.0)
    return float(dm)


def _quadland_frequencies(L, multi):
    """quadland's search grid and its refined peak."""
    from quadland.analysis import FrequencyResponse, frequency_grid

    grid = frequency_grid(FrequencyResponse(L), extra_poles=closed_loop_poles(L))
    return np.unique(np.r_[grid, multi.frequency])


def _mu_lower(M, starts=6):
    """A lower bound of mu for independent complex scalars: max over diagonal unitary Q
    of the spectral radius of Q M (equal to mu, Doyle 1982; any Q gives a bound)."""
    m = M.shape[0]
    rng = np.random.default_rng(0)

    def neg_rho(theta):
        return -np.max(np.abs(np.linalg.eigvals(np.diag(np.exp(1j * np.r_[0.0, theta])) @ M)))

    best = -neg_rho(np.zeros(m - 1))
    for _ in range(starts):
        res = scipy.optimize.minimize(neg_rho, rng.uniform(0, 2 * np.pi, m - 1),
                                      method="Nelder-Mead",
                                      options=dict(xatol=1e-9, fatol=1e-13, maxiter=3000))
        best = max(best, -res.fun)
    return best


def _sensitivity_at(L, w):
    from quadland.analysis import FrequencyResponse

    resp = FrequencyResponse(L)
    G = resp.at(resp.point(w))
    return np.linalg.inv(np.eye(G.shape[0]) + G) - 0.5 * np.eye(G.shape[0])


def _three_channel():
    """A stable 3 x 3 loop with non-normal coupling: L = K / (s (s + 2)) with K
    upper triangular, so that S - I/2 is far from normal."""
    K = np.array([[3.0, 4.0, -2.0], [0.0, 2.0, 5.0], [0.0, 0.0, 4.0]])
    A = np.block([[np.zeros((3, 3)), np.eye(3)], [np.zeros((3, 3)), -2 * np.eye(3)]])
    return control.ss(A, np.vstack([np.zeros((3, 3)), K]), np.hstack([np.eye(3),
                                                                      np.zeros((3, 3))]), 0)


@needs_disk_margins
@pytest.mark.parametrize("case", [_third_order, _cubic_lag], ids=["third_order", "cubic_lag"])
def test_disk_margin_matches_python_control_siso(case):
    """One channel: mu = |S - 1/2| and both libraries are exact."""
    L, _ = case()
    (per,), multi = diskmargin(L)
    assert per == multi
    alpha_pc = _control_disk_margin(L, _quadland_frequencies(control.ss(L), multi))
    assert multi.disk_margin == pytest.approx(alpha_pc, rel=1e-12)


@pytest.mark.slow
@needs_disk_margins
def test_disk_margin_matches_python_control_satellite():
    """Normal M (D = I is optimal): both equal the closed form of
    test_satellite_multiloop_disk_margin_is_poor; ab13md to its TOL."""
    a = 10.0
    w = math.sqrt(a * a + 1) - a
    exact = 1 / math.sqrt((0.25 + (w / 2 + a) ** 2) / (1 + w * w))
    L = _satellite(a)
    _, multi = diskmargin(L)
    alpha_pc = _control_disk_margin(L, np.unique(np.r_[_quadland_frequencies(L, multi), w]))
    assert multi.disk_margin == pytest.approx(exact, rel=1e-9)
    assert alpha_pc == pytest.approx(exact, rel=_AB13MD_TOL)


@pytest.mark.slow
@needs_disk_margins
def test_disk_margin_matches_python_control_three_channels():
    """Three complex scalars: the D-scaled bound is mu (Packard and Doyle 1993), so at
    the peak quadland's bound meets an independent lower bound of mu; python-control
    agrees within ab13md's TOL, never above quadland's alpha."""
    L = _three_channel()
    assert np.all(closed_loop_poles(L).real < 0)
    _, multi = diskmargin(L)
    M = _sensitivity_at(L, multi.frequency)
    assert np.linalg.norm(M @ M.conj().T - M.conj().T @ M) > 0.1      # far from normal
    assert 1 / multi.disk_margin == pytest.approx(_mu_lower(M), rel=1e-8)
    alpha_pc = _control_disk_margin(L, _quadland_frequencies(L, multi))
    assert alpha_pc <= multi.disk_margin * (1 + 1e-9)
    assert multi.disk_margin <= alpha_pc * (1 + _AB13MD_TOL)


@pytest.fixture(scope="module")
def landing_loops():
    """The highway landing loop at hover (shipped l = 10): continuous-time limit and
    sampled at 250 Hz with one period of computation delay."""
    from threadpoolctl import threadpool_limits

    from quadland.linearization import equilibrium, linear_models, sampled_models
    from quadland.scenario import load_scenario

    with threadpool_limits(1):
        sc = load_scenario("highway")
        point = equilibrium(sc)
        return {"continuous": linear_models(sc, point).loop_input,
                "sampled": sampled_models(sc, point, 250.0).loop_input}


@pytest.mark.slow
@needs_disk_margins
@pytest.mark.parametrize("which", ["continuous", "sampled"])
def test_disk_margin_matches_python_control_landing_loop(landing_loops, which):
    """Four channels: the D-scaled bound may exceed mu in general. On the same
    frequencies python-control's alpha is quadland's within ab13md's TOL, never above it;
    on a coarse grid it can only be larger (it misses the peak). At this loop's peak the
    bound is tight: an independent lower bound of mu meets it (observed, 3e-15)."""
    L = landing_loops[which]
    _, multi = diskmargin(L)
    assert 0 < multi.disk_margin < 2
    alpha_pc = _control_disk_margin(L, _quadland_frequencies(L, multi))
    assert alpha_pc <= multi.disk_margin * (1 + 1e-9)
    assert multi.disk_margin <= alpha_pc * (1 + _AB13MD_TOL)
    coarse = np.logspace(-2, math.log10(0.99 * math.pi / L.dt) if L.dt else 3, 40)
    assert _control_disk_margin(L, coarse) >= multi.disk_margin * (1 - 1e-9)
    mu_low = _mu_lower(_sensitivity_at(L, multi.frequency))
    assert multi.disk_margin <= 1 / mu_low * (1 + 1e-9)                # guaranteed
    assert multi.disk_margin == pytest.approx(1 / mu_low, rel=1e-6)    # tight here


def test_the_triangular_solves_reuse_a_copy_of_the_schur_factor_per_thread():
    """Each point's solve rewrites only the diagonal of one kept copy of ``-T``: the same
    bits as a new ``-T`` per point with ``point`` added to its diagonal, the resolvent of
    a dense solve, and a copy of its own for each thread."""
    import threading

    import scipy.linalg

    from quadland.analysis import FrequencyResponse

    rng = np.random.default_rng(3)
    n = 40
    A = rng.normal(size=(n, n)) - 6 * np.eye(n)
    B, C, D = rng.normal(size=(n, 3)), rng.normal(size=(2, n)), rng.normal(size=(2, 3))
    resp = FrequencyResponse(control.ss(A, B, C, D))
    points = [1j * w for w in (0.01, 0.7, 3.0, 250.0)] + [0.3 + 2j]
    for p in points:
        fresh = -resp._T
        fresh.flat[::n + 1] += p
        old_way = resp._C @ scipy.linalg.solve_triangular(fresh, resp._B,
                                                          check_finite=False) + resp._D
        got = resp._solve(p)
        assert np.array_equal(got, old_way)
        dense = C @ np.linalg.solve(p * np.eye(n) - A, B) + D
        assert np.allclose(got, dense, rtol=1e-10, atol=1e-12)
    assert len(resp._negated) == 1
    results = {}

    def other():
        results["other"] = [resp._solve(p) for p in points]

    worker = threading.Thread(target=other)
    worker.start()
    worker.join()
    assert len(resp._negated) == 2
    again = [resp._solve(p) for p in points]
    assert all(np.array_equal(a, b) for a, b in zip(results["other"], again, strict=True))

"""The hover loop with the navigation filter in it (quadland.kinds.landing.filter_loop)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import quadland
from quadland.kinds.landing import filter_loop, linearize
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.estimator import FLIGHT_COUPLING
from quadland_symbolic.landing.filter_linearization import hover_law_function
from quadland_symbolic.landing.linearization import HOVER_OUTPUT
from quadland_symbolic.landing.navigation import (
    NAV,
    NAV_PACKETS,
    covariance_pattern,
    estimator_params,
    nav_transition_function,
)

RATE = 250.0


@pytest.fixture(scope="module")
def highway():
    sc = quadland.load_scenario("highway")
    point = linearize.hover_equilibrium(sc)
    h = filter_loop._hover_filter(sc, point, 1 / RATE)
    schedule = filter_loop.filter_schedule(sc, h["valid"], h["p_est"])
    return sc, point, h, schedule


def test_the_law_reads_the_quadrotor_as_the_perfect_sensing_jacobians_say(highway):
    """The step's Jacobians in its whole measurement, restricted to the quadrotor's part,
    are the perfect-sensing model's (a different composition of the same law)."""
    sc, point, _, _ = highway
    y0 = filter_loop.truth_measurement(sc, point)
    Phi, Gam, C, D, _ = filter_loop._law(sc, point, y0, 1 / RATE)
    J = linearize.hover_jacobians(sc, point, 1 / RATE)
    q = HOVER_OUTPUT.size
    assert LANDING_MEASUREMENT.element_names()[:q] == HOVER_OUTPUT.element_names()
    np.testing.assert_allclose(Phi, J["Phi_c"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(Gam[:, :q], J["Gamma_c"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(C, J["C_c"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(D[:, :q], J["D_c"], rtol=1e-9, atol=1e-9)
    hv = linearize.hover_values(sc)
    u = np.asarray(hover_law_function(hv.l)(y0, point.xc, hv.p_ctrl, hv.pm, hv.ref,
                                            1 / RATE)[0]).ravel()
    np.testing.assert_allclose(u, point.u, rtol=1e-9)       # the hover's own wrench


def _x_axis_dare(h, schedule):
    """The x axis' prior covariance from scipy's DARE, with the measurement rows of
    docs/estimator.md (E10), (E11), (E13) written by hand and the rate-equivalent
    variances."""
    p = estimator_params().unpack(h["p_est"])
    Phi, _, Q = (np.asarray(m, dtype=float) for m in nav_transition_function()(
        1 / RATE, h["p_est"]))
    ix = [3 * f for f in range(len(NAV.fields))]            # x of each field (field-major)
    Phi, Q = Phi[np.ix_(ix, ix)], Q[np.ix_(ix, ix)]
    # x-axis state: [p_r, v1, v_t, a_t, b, a_b, a_tilt]
    r_E = h["packets"][0]
    lever = r_E[2] / float(p["g"][0])
    s = schedule.variance_scale
    rows = [([-1, 0, 0, 0, 0, 0, lever],
             (p["vision_sigma0"][0] + p["vision_k_range"][0] * np.linalg.norm(r_E)) ** 2
             * s["vision"]),
            ([-1, 0, 0, 0, 1, 0, 0], p["gnss_rel_sigma"][0] ** 2 * s["gnss"]),
            ([0, 1, 0, 0, 0, 0, 0], p["gnss_v1_sigma"][0] ** 2 * s["gnss"]),
            ([0, 0, 1, 0, 0, 0, 0], p["gnss_vt_sigma"][0] ** 2 * s["gnss"]),
            ([0, 0, 1, 0, 0, 0, 0], p["datalink_v_sigma"][0] ** 2 * s["datalink"]),
            ([0, 0, 0, 1, 0, 0, 0], p["datalink_a_sigma"][0] ** 2 * s["datalink"])]
    H = np.array([r for r, _ in rows], dtype=float)
    R = np.diag([v for _, v in rows])
    return scipy.linalg.solve_discrete_are(Phi.T, H.T, Q, R), ix


def test_the_rate_equivalent_covariance_is_the_dare_on_the_x_axis(highway):
    """On x the flight recursion is a plain Kalman filter (the range finder measures z
    only, its x, y part projected as noise: E9a): its fixed point is the DARE's."""
    _, _, h, schedule = highway
    assert all(schedule.period[p.name] for p in NAV_PACKETS)
    P, steps = filter_loop.steady_covariance(h, schedule)
    assert steps < 60
    Pm = covariance_pattern(FLIGHT_COUPLING).unpack_numeric(P)
    X, ix = _x_axis_dare(h, schedule)
    np.testing.assert_allclose(Pm[np.ix_(ix, ix)], X, rtol=1e-7, atol=1e-14)

"""(E10c): the attitude estimate's heading error in the vision's noise.

The camera's vector is rotated into E with the attitude estimate, whose heading is off by
``eps_z`` (2 deg, correlated over 10 s): ``R(eta1 + e_att) d_b = r + eps_z e_z x r + ...``,
a horizontal error ``eps_z (-r_y, r_x, 0)`` that grows with the horizontal offset. Checked
against the variance written out by hand, and the update against the textbook Joseph
update (tests/nav_reference.py) with the share counted ``max(1, r_white / h^T P h)``
times, once in the NIS, as docs/estimator.md (E10c) states.
"""

import numpy as np
import pytest
from nav_reference import N, col, joseph_reference, params, random_spd, sl

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.navigation import (
    VISION,
    covariance_pattern,
    measurement_model_function,
    nav_update_function,
)

SIGMA_PSI = np.radians(2.0)


def test_heading_error_of_a_rotated_vector_has_the_variance_of_its_share():
    """A vector turned by a small heading error moves by ``eps_z (-r_y, r_x, 0)``: its
    variance over draws of ``eps_z`` (exact rotations, 20,000 of them) against the
    model's ``r`` less its white part, ``sigma_psi^2 (r_y^2, r_x^2, 0)``."""
    r_E = np.array([0.3, -0.12, -3.0])
    p = params(vision_sigma0=0.02, vision_k_range=0.01, vision_heading_sigma=SIGMA_PSI)
    _, _, H, r, _ = measurement_model_function("vision")(
        np.zeros(N), VISION.pack(dict(fresh=1.0, tau=0.0, r_E=r_E)), [0, 0, 1.0], p)
    white = (0.02 + 0.01 * np.linalg.norm(r_E)) ** 2
    share = col(r) - white
    np.testing.assert_allclose(share, SIGMA_PSI ** 2 * np.array([0.12 ** 2, 0.3 ** 2, 0.0]),
                               rtol=1e-12, atol=1e-18)
    rng = np.random.default_rng(10)
    moved = np.array([np.array(rotation([0.0, 0.0, e])) @ r_E - r_E
                      for e in rng.normal(0, SIGMA_PSI, 20_000)])
    np.testing.assert_allclose(moved.var(axis=0)[:2], share[:2], rtol=0.03)
    # the rows are the model's without it (E10)
    _, _, H0, _, _ = measurement_model_function("vision")(
        np.zeros(N), VISION.pack(dict(fresh=1.0, tau=0.0, r_E=r_E)), [0, 0, 1.0],
        params(vision_sigma0=0.02, vision_k_range=0.01))
    np.testing.assert_array_equal(np.array(H), np.array(H0))


@pytest.mark.parametrize("coupling", ["full", "axes"])
@pytest.mark.parametrize("scale", [1.0, 1e-4])
def test_the_update_counts_the_heading_share_over_the_packets_the_state_remembers(
        coupling, scale):
    """The heading's share is the same in every packet for seconds: the update counts it
    ``m = max(1, r_white / h^T P h)`` times (``m`` 1 for a loose covariance, more than 1
    once the position is known better than one packet), the gate's ``S`` and the NIS
    once."""
    rng = np.random.default_rng([17, int(scale < 1)])
    pattern = covariance_pattern(coupling)
    P = pattern.unpack_numeric(pattern.pack_numeric(random_spd(rng, N, scale)))
    x = rng.normal(size=N) * np.sqrt(scale)
    r_E = -x[sl("p_r")] + np.array([0.5, -0.4, 0.0])
    r_E[2] = -3.0
    p_kw = dict(vision_sigma0=0.02, vision_k_range=0.01, vision_heading_sigma=SIGMA_PSI,
                gate_vision=1e30)
    pkt = VISION.pack(dict(fresh=1.0, tau=0.0, r_E=r_E))
    _, h, H, r, _ = measurement_model_function("vision")(x, pkt, [0, 0, 1.0], params(**p_kw))
    H, h, r = np.array(H), col(h), col(r)
    share = SIGMA_PSI ** 2 * np.array([r_E[1] ** 2, r_E[0] ** 2, 0.0])
    white = r - share
    m = np.maximum(white / np.einsum("ij,jk,ik->i", H, P, H), 1.0)
    assert np.all(m[:2] > 1) == (scale < 1) and np.all(m[:2] >= 1)
    x_ref, P_ref, _, _ = joseph_reference(x, P, H, r_E - h + H @ x,
                                          np.diag(white + m * share))
    x_next, P_next, nu, nis, fused, _ = nav_update_function("vision", coupling)(
        x, P, pkt, [0, 0, 1.0], params(**p_kw), 1.0)
    S = H @ P @ H.T + np.diag(r)
    assert float(fused) == 1
    assert float(nis) == pytest.approx((r_E - h) @ np.linalg.solve(S, r_E - h), rel=1e-10)
    np.testing.assert_allclose(col(x_next), x_ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(np.array(P_next), P_ref, rtol=1e-9, atol=1e-14 * scale)

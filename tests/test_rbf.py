"""RBF network (eq. 8)."""

import numpy as np

from quadland_symbolic.rbf import default_centers, rbf_function


def test_gaussian_values():
    l = 3
    f = rbf_function(l)
    centers = np.zeros((10, l))
    centers[:, 1] = 1.0
    centers[0, 2] = 2.0
    widths = np.array([1.0, 2.0, 0.5])
    x = np.zeros(10)
    psi = np.array(f(x, centers, widths)).ravel()
    # ||x - mu||^2 = 0, 10, 4
    np.testing.assert_allclose(psi, [1.0, np.exp(-10 / 4), np.exp(-4 / 0.25)], rtol=1e-15)


def test_default_centers_on_diagonal():
    c = default_centers(5)
    assert c.shape == (10, 5)
    np.testing.assert_allclose(c[0], [-2, -1, 0, 1, 2])
    np.testing.assert_allclose(c, np.tile(c[0], (10, 1)))
    np.testing.assert_allclose(default_centers(1), np.zeros((10, 1)))

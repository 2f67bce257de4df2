"""gauss_markov's recursion, in C (quadland.engine.recursion) or without a compiler
column by column over Python floats (issue 20): the same numbers, bit for bit, as the
recursion written out row by row on NumPy's arrays."""

from __future__ import annotations

import numpy as np
import pytest

from quadland.engine import noise
from quadland.engine.noise import gauss_markov
from quadland.engine.recursion import compiled_recursion


def _by_rows(times, sigma, tau, normals):
    """x_0 = sigma n_0, x_(k+1) = a_k x_k + b_k n_(k+1), a_k = exp(-dt_k / tau), b_k =
    sigma sqrt(1 - a_k^2): the definition, one NumPy row at a time."""
    n, m = normals.shape
    x = np.empty((n, m))
    x[0] = sigma * normals[0]
    for k in range(n - 1):
        dt = times[k + 1] - times[k]
        a = np.array([np.exp(-dt / s) if 0 < s < np.inf else (1.0 if s == np.inf else 0.0)
                      for s in tau])
        b = sigma * np.sqrt(np.clip(1.0 - a * a, 0.0, None))
        x[k + 1] = a * x[k] + b * normals[k + 1]
    return x


@pytest.mark.parametrize("tau", [[0.0, np.inf, 0.3, 4.0], [1e-3, 0.3, 4.0, 1100.0]])
@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("n", [1, 2, 500, 10_000])
def test_gauss_markov_is_its_row_recursion_bit_for_bit(monkeypatch, n, compiled, tau):
    """In C and over Python floats: the row recursion's bits (signs of zero too), with
    the limits ``tau = 0`` and ``inf`` among the columns and with every ``tau`` positive
    and finite (the decay's path without them, the GNSS's)."""
    if compiled:
        assert compiled_recursion() is not None          # this machine has a compiler
    else:
        monkeypatch.setattr(noise, "recursion", lambda *args: None)
    rng = np.random.default_rng(20)
    times = np.cumsum(rng.uniform(1e-3, 1e-2, n))
    sigma, tau = np.array([0.5, 1.5, 2.0, 0.1]), np.array(tau)
    normals = rng.standard_normal((n, 4))
    got, want = gauss_markov(times, sigma, tau, normals), _by_rows(times, sigma, tau, normals)
    assert got.shape == want.shape == (n, 4)
    assert np.array_equal(got.view(np.int64), want.view(np.int64))

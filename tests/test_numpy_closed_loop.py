"""The NumPy closed loop (``numpy_closed_loop``) against ``closed_loop_function``.

``tests/numpy_closed_loop.py`` derives the closed loop again from the
paper, with alpha_dot (eq. 18) written out by hand; agreement at random
states checks both derivations against each other. The SciPy baseline of
``benchmarks/bench_simulate.py`` runs on the same right-hand side.
"""

import numpy as np
import pytest
from numpy_closed_loop import numpy_rhs, random_states

import quadland
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import closed_loop_function


@pytest.mark.parametrize("overrides", [
    [],
    ["controller.nominal_model=true", "reference.e1d=[0.1, 0.2, -0.1, 0.3]"],
    ["rbf.nodes=7", "rbf.width=0.7"],
], ids=["paper", "nominal-model-and-reference", "seven-nodes"])
def test_numpy_rhs_matches_casadi(overrides):
    mv = model_values(quadland.load_scenario("paper", overrides))
    f = closed_loop_function(mv.l)
    rhs = numpy_rhs(mv.p, mv.l)
    X, W = random_states(mv, 5, seed=1)
    for k in range(X.shape[1]):
        expected = np.asarray(f(X[:, k], W[:, k], mv.p)).ravel()
        np.testing.assert_allclose(rhs(0.0, X[:, k], W[:, k]), expected,
                                   rtol=1e-10, atol=1e-10)

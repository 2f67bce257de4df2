"""The benchmark's NumPy closed loop against ``closed_loop_function``.

``benchmarks/bench_simulate.py`` derives the closed loop again from the
paper, with alpha_dot (eq. 18) written out by hand; agreement at random
states checks both derivations against each other.
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import quadland
from quadland.model import model_values
from symbolic.closed_loop import closed_loop_function

_BENCH = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_simulate.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_simulate", _BENCH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("overrides", [
    [],
    ["controller.nominal_model=true", "reference.e1d=[0.1, 0.2, -0.1, 0.3]"],
    ["rbf.nodes=7", "rbf.width=0.7"],
], ids=["paper", "nominal-model-and-reference", "seven-nodes"])
def test_numpy_rhs_matches_casadi(bench, overrides):
    mv = model_values(quadland.load_scenario("paper", overrides))
    f = closed_loop_function(mv.l)
    rhs = bench.numpy_rhs(mv.p, mv.l)
    X, W = bench.random_states(mv, 5, seed=1)
    for k in range(X.shape[1]):
        expected = np.asarray(f(X[:, k], W[:, k], mv.p)).ravel()
        np.testing.assert_allclose(rhs(0.0, X[:, k], W[:, k]), expected,
                                   rtol=1e-10, atol=1e-10)

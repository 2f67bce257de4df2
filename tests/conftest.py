"""Shared fixtures: the paper's parameters as numeric vectors."""

import numpy as np
import pytest

from quadland.kinds.paper.values import model_values
from quadland.scenario import load_scenario


@pytest.fixture(scope="session")
def paper():
    """The paper scenario, validated."""
    return load_scenario("paper")


@pytest.fixture(scope="session")
def values(paper):
    """Numeric parameter vectors of the paper scenario."""
    return model_values(paper)


@pytest.fixture
def rng():
    """A seeded generator, one per test."""
    return np.random.default_rng(20191121)

"""Shared fixtures: the paper's parameters as numeric vectors; Ctrl-C as a user's shell
gives it."""

import signal

import numpy as np
import pytest

from quadland.kinds.paper.values import model_values
from quadland.scenario import load_scenario


def pytest_configure(config):
    """Give the tests a Ctrl-C as an interactive shell does. A non-interactive shell starts
    a background job with SIGINT ignored, an ignored signal is inherited across ``exec``,
    and Python raises no ``KeyboardInterrupt`` in a process that starts with it ignored:
    the interrupt tests' commands would never see the Ctrl-C they are sent."""
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)


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

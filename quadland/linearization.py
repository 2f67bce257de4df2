"""Operating points and linear models of any scenario's loop, its kind's way.

The loop kinds (:mod:`quadland.kinds`) find their operating points and form
their linear models (the paper's loop broken at the virtual input u of
eq. (6); a landing's at the wrench into the mixer, hovering over the pad);
these functions ask the scenario's kind. The types are
:mod:`quadland.linear`'s; the models are ``control.StateSpace`` objects
with named signals.
"""

from __future__ import annotations

from quadland.kinds import kind_of
from quadland.linear import LinearModels, OperatingPoint
from quadland.scenario import Scenario

__all__ = ["operating_point", "equilibrium", "frozen_point", "linear_models", "sampled_models"]


def operating_point(scenario: Scenario, at: float | None = None) -> OperatingPoint:
    """The loop's equilibrium, or its simulated state at time ``at`` (s) frozen."""
    return kind_of(scenario).operating_point(scenario, at)


def equilibrium(scenario: Scenario) -> OperatingPoint:
    """The loop's steady motion under the constant disturbance (a landing's: the hover)."""
    return kind_of(scenario).operating_point(scenario)


def frozen_point(scenario: Scenario, t: float) -> OperatingPoint:
    """The simulated state at time ``t`` (s), frozen (the paper's loop)."""
    return kind_of(scenario).operating_point(scenario, t)


def linear_models(scenario: Scenario, point: OperatingPoint) -> LinearModels:
    """Continuous-time plant, controller, broken loops and closed loop at a point."""
    return kind_of(scenario).linear_models(scenario, point)


def sampled_models(scenario: Scenario, point: OperatingPoint, rate_hz: float,
                   delay_periods: int = 1) -> LinearModels:
    """Sampled-data models at ``rate_hz`` with ``delay_periods`` of computation delay."""
    return kind_of(scenario).sampled_models(scenario, point, rate_hz, delay_periods)

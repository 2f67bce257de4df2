"""A landing scenario's sea state as the deck's wave components.

``[deck]``'s ``sea_state`` (1 to 6) names a WMO sea state
(:data:`quadland.schema.sea_state.SEA_STATES`); its significant wave height
and peak period are the most probable ones unless ``significant_wave_height``
or ``peak_period`` are given (not 0). The waves pass under the vessel of
``vessel_length``, ``vessel_beam``, ``roll_period`` and ``roll_damping``,
travelling at ``wave_heading_deg`` from its bow, at its initial surge speed
``initial.velocity2[0]``; :func:`quadland.engine.sea.sea_components` makes
:data:`~quadland_symbolic.landing.deck.N_SEA` components of them.

The phases are drawn from their own generator, derived from
``simulation.seed`` by the spawn key ``(SEA_STREAM,)``
(:func:`sea_seed`): the sea of a seed does not change with the sensors' or
the turbulence's settings, and a campaign's ``simulation.seed`` dispersion
draws a new sea for each run.
"""

from __future__ import annotations

import math

import numpy as np

from quadland.engine.sea import DeckComponents, Vessel, sea_components
from quadland.scenario import Scenario
from quadland.schema.sea_state import SEA_STATES
from quadland_symbolic.landing.deck import N_SEA

__all__ = ["SEA_STREAM", "sea_seed", "sea_of", "deck_components"]

#: The spawn key of the sea's phases: keeps them apart from the run's other
#: children of the same seed (the sensors' is "SENS").
SEA_STREAM = 0x53454153              # "SEAS"


def sea_seed(seed) -> np.random.SeedSequence:
    """The seed of the sea's phases: ``seed``'s entropy, spawn key ``(..., SEA_STREAM)``."""
    base = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    return np.random.SeedSequence(base.entropy,
                                  spawn_key=tuple(base.spawn_key) + (SEA_STREAM,))


def sea_of(scenario: Scenario) -> tuple[float, float, float, Vessel] | None:
    """``(Hs, Tp, gamma, vessel)`` of the scenario's sea, None at ``sea_state = 0``."""
    d = scenario.data
    dk = d["deck"]
    if dk["sea_state"] == 0:
        return None
    preset = SEA_STATES[dk["sea_state"]]
    hs = dk["significant_wave_height"] or preset.hs
    tp = dk["peak_period"] or preset.tp
    vessel = Vessel(length=dk["vessel_length"], beam=dk["vessel_beam"],
                    roll_period=dk["roll_period"], roll_damping=dk["roll_damping"],
                    speed=d["initial"]["velocity2"][0],
                    heading=math.radians(dk["wave_heading_deg"]))
    return hs, tp, dk["peak_enhancement"], vessel


def deck_components(scenario: Scenario) -> DeckComponents | None:
    """The sea's :data:`N_SEA` components (seeded), None at ``sea_state = 0``."""
    sea = sea_of(scenario)
    if sea is None:
        return None
    hs, tp, gamma, vessel = sea
    rng = np.random.default_rng(sea_seed(scenario.data["simulation"]["seed"]))
    return sea_components(hs, tp, gamma, vessel, N_SEA, rng,
                          scenario.data["quadrotor"]["gravity"])

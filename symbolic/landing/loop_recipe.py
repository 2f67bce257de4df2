"""The landing loops as recipes: their layouts without building their CasADi functions.

A landing loop model (:func:`~quadland_symbolic.landing.loop.landing_loop`,
:func:`~quadland_symbolic.landing.sensed_loop.landing_sensed_loop`, either on a flat
deck, :func:`~quadland_symbolic.landing.flat_deck.flat_deck_loop`) takes about 0.7 s
of CPU to build (the sensed one, ``l = 10``), in every process that flies one: a
campaign's own and each of its workers. A compiled simulator found in the cache needs
only the layouts of its arguments; :func:`landing_loop_recipe` gives them, and builds
the model (:func:`landing_loop_model`) only when a function is asked for (a build, the
VM, the welded ride's ``assemble``). ``tests/test_landing_loop_recipe.py`` checks each
recipe's layouts, flags and absent functions against the model it builds.
"""

from __future__ import annotations

import functools

from quadland_symbolic.landing.flat_deck import flat_deck_loop
from quadland_symbolic.landing.loop import (
    LANDING_ENVELOPE,
    LANDING_RECORDED,
    landing_loop,
    landing_loop_memory,
    landing_loop_params,
    landing_loop_state,
)
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.quadrotor import COMMAND
from quadland_symbolic.landing.sensed_loop import (
    SENSED_RECORDED,
    SENSED_TICK,
    landing_sensed_loop,
    sensed_loop_memory,
    sensed_loop_params,
)
from quadland_symbolic.landing.signals import LANDING_SIGNALS
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.loop_recipe import LoopRecipe

__all__ = ["landing_loop_model", "landing_loop_recipe"]


def landing_loop_model(l: int, sensed: bool, welded: bool, flat: bool) -> LoopModel:
    """The landing loop for ``l`` nodes: on ``sensed`` sensors and the filter or on the
    true state, ``welded`` to the deck at touchdown or on the gear, on a ``flat`` deck
    (its sinusoids' sums left out) or any."""
    model = landing_sensed_loop(l, welded) if sensed else landing_loop(l, welded)
    return flat_deck_loop(model) if flat else model


@functools.cache
def landing_loop_recipe(l: int, sensed: bool, welded: bool, flat: bool) -> LoopRecipe:
    """:func:`landing_loop_model` as a :class:`LoopRecipe`: the layouts, name, flags and
    absent functions given here, the model built when a function is first asked for."""
    name = ("landing_sensed" if sensed else "landing") + ("_welded" if welded else "") + \
        ("_flat" if flat else "")
    layouts = dict(state=landing_loop_state(l), disturbance=LANDING_DISTURBANCE,
                   params=LANDING_PLANT_PARAMS, outputs=LANDING_SIGNALS,
                   plant_state=LANDING_PLANT_STATE, held=COMMAND,
                   controller_state=(sensed_loop_memory if sensed else landing_loop_memory)(l),
                   plant_params=LANDING_PLANT_PARAMS,
                   controller_params=(sensed_loop_params if sensed else landing_loop_params)(l),
                   recorded=SENSED_RECORDED if sensed else LANDING_RECORDED,
                   envelope_layout=LANDING_ENVELOPE,
                   tick_inputs=SENSED_TICK if sensed else None)
    absent = {"rhs"} | ({"free_plant"} if welded else {"ride_rhs", "ride_row"})
    if not sensed:
        absent.add("controller_stages")
    flight = ("landing_sensed_flight_controller.c.jinja" if sensed else
              "landing_flight_controller.c.jinja")
    return LoopRecipe(landing_loop_model, (l, sensed, welded, flat), name, layouts,
                      frozenset(absent), dict(flight=flight, event_continues=not welded))

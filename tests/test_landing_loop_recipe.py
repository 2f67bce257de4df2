"""The landing loops as recipes: described without building, found in the cache unbuilt."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys

import pytest

from quadland.engine.build import have_compiler

needs_cc = pytest.mark.skipif(not have_compiler(), reason="needs a C compiler")


@pytest.mark.parametrize("sensed, welded, flat", list(itertools.product((False, True),
                                                                          repeat=3)))
def test_the_landing_recipe_describes_the_model_it_builds(sensed, welded, flat):
    """Every layout, flag and absent function the recipe gives without building is the
    model's that the loop's own builders make (``landing_loop`` or
    ``landing_sensed_loop``, through ``flat_deck_loop``), and so is its name."""
    from quadland.engine.compiled import built_model
    from quadland.engine.recall import model_digest
    from quadland_symbolic.landing.flat_deck import flat_deck_loop
    from quadland_symbolic.landing.loop import landing_loop
    from quadland_symbolic.landing.loop_recipe import landing_loop_recipe
    from quadland_symbolic.landing.sensed_loop import landing_sensed_loop

    l = 2
    recipe = landing_loop_recipe.__wrapped__(l, sensed, welded, flat)
    model = landing_sensed_loop(l, welded) if sensed else landing_loop(l, welded)
    model = flat_deck_loop(model) if flat else model
    known = recipe.known()
    for name, value in known.items():
        assert getattr(model, name) == value, name
    # every layout and flag of the model is given, and every function it leaves None
    for name in ("state", "controller_state", "controller_params", "recorded",
                 "tick_inputs", "envelope_layout", "flight", "event_continues"):
        assert name in known, name
    for name in ("rhs", "ride_rhs", "ride_row", "free_plant", "controller_stages"):
        assert (name in known) == (getattr(model, name) is None), name
    assert recipe.name == model.name
    built = built_model(recipe)               # built, and checked against the description
    assert built is recipe.model and model_digest(built) == model_digest(model)


_WARM = """
from quadland.campaign.fly import warm_up
from quadland.scenario import load_scenario
from quadland_symbolic.landing import flat_deck, loop, sensed_loop
warm_up(load_scenario("highway"))
print(sensed_loop.landing_sensed_loop.cache_info().misses,
      loop.landing_loop.cache_info().misses, flat_deck.flat_deck_loop.cache_info().misses)
"""


@pytest.mark.slow
@needs_cc
def test_a_landing_with_its_simulator_cached_builds_no_loop_model():
    """A fresh process whose sensed highway simulator is in the cache (the first process
    puts it there, if it was not) flies without building the loop: no call of
    ``landing_sensed_loop``, ``landing_loop`` or ``flat_deck_loop``; what a campaign's
    worker does at its start."""
    def misses():
        out = subprocess.run([sys.executable, "-c", _WARM], check=True, capture_output=True,
                             text=True, env=dict(os.environ))
        return [int(v) for v in out.stdout.split()]

    misses()
    assert misses() == [0, 0, 0]


@needs_cc
def test_each_landing_loop_and_each_generator_has_its_own_key(monkeypatch):
    """The eight landing loops (sensed or not, welded or not, flat deck or not) and two
    sizes never share a simulator's cache key, and every key changes with the code of
    ``quadland_symbolic`` (its digest): a library built for one loop, or before a change
    of the symbolic code, is never found for another."""
    from quadland.engine import recall
    from quadland_symbolic.landing.loop_recipe import landing_loop_recipe

    def keys():
        return {(l, *flags): recall.recall_key(landing_loop_recipe(l, *flags), "sampled", None,
                                               (), "qlsim_x", "-O2", False)
                for l in (2, 10) for flags in itertools.product((False, True), repeat=3)}

    before = keys()
    assert len(set(before.values())) == 16
    monkeypatch.setattr(recall, "generator_digest", lambda: "a changed symbolic source")
    after = keys()
    assert all(after[k] != before[k] for k in before)

"""A campaign run's scenario checked as far as its draws change it (issue 20).

:func:`quadland.campaign.dispersed.dispersed` must give what
:meth:`Scenario.replace` (every key validated again) gives: the same values, types and
order for every run's draws of the shipped campaigns, and the same one-line refusal
for a draw the schema refuses. The draws themselves: a chunk's numeric dispersions go
through their inverse CDFs at once, each run's values those of its own point alone.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from quadland.campaign.dispersed import dispersed
from quadland.campaign.draws import apply_mode
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.exceptions import ScenarioError
from quadland.scenario import load_scenario


def _same(a, b) -> bool:
    """The same scenario: name, values by repr (types, signs of zero) and key order."""
    return (a.name == b.name and a.source == b.source and a.overrides == b.overrides
            and a.campaign_table == b.campaign_table
            and repr(a.data) == repr(b.data))


@pytest.mark.parametrize("name", ["highway", "ship", "paper"])
def test_each_runs_scenario_is_the_replaced_one(name):
    base = load_scenario(name)
    for draw in draws(campaign_spec_of(base), range(12)):
        assert _same(dispersed(base, draw.values), base.replace(**draw.values)), draw.index


@pytest.mark.parametrize("changes", [
    {"vehicle.m11": -1.0},                                 # a field's range
    {"controller.rate_hz": "fast"},                        # a field's type
    {"vehicle.m11": -1.0, "quadrotor.mass": "x"},          # two: the schema's first
    {"quadrotor.mass": "x", "vehicle.m11": -1.0},          # in either order
    {"sensors.vision.rate_hz": 33.0},                      # a cross-key check
    {"vehicle.nonsense": 1.0},                             # not in the schema
    {"scenario.model": "paper"},                           # the model: full validation
    {"nosection": 1.0},                                    # not section.key
])
def test_a_refused_draw_is_refused_alike(changes):
    base = load_scenario("highway")
    with pytest.raises(ScenarioError) as full:
        base.replace(**changes)
    with pytest.raises(ScenarioError) as fast:
        dispersed(base, changes)
    assert str(fast.value) == str(full.value)
    assert "\n" not in str(fast.value)


@pytest.mark.parametrize("name", ["highway", "ship", "paper", "turning"])
@pytest.mark.parametrize("sampling", ["random", "lhs"])
def test_a_chunks_draws_are_each_runs_own(name, sampling):
    """The numeric dispersions' inverse CDFs computed once for a chunk's runs (an array
    of them) give each run's values as its own point alone (a vector of one run's
    dimensions, the former per-run computation), bit for bit: 150 runs of each shipped
    campaign (uniform, normal and truncated normal dispersions, relative and absolute,
    common and per element)."""
    from quadland.campaign.sampling import _numeric, unit_samples

    spec = dataclasses.replace(campaign_spec_of(load_scenario(name)), sampling=sampling)
    runs = list(range(150))
    U = unit_samples(spec, runs, 150)
    kinds = set()
    for i, draw in zip(runs, draws(spec, runs, 150), strict=True):
        col = 0
        for disp in spec.dispersions:
            u = U[i, col:col + disp.dims]
            col += disp.dims
            if disp.distribution in ("seed", "choice"):
                continue
            kinds.add(disp.distribution)
            alone = _numeric(disp, np.array(u))             # one run's point alone
            for t, target in enumerate(disp.targets):
                per = [apply_mode(disp.mode, nom, float(alone[0 if (t or len(alone) == 1)
                                                             else e]))
                       for e, nom in enumerate(target.nominal)]
                got = draw.values[target.key]
                got = [got] if target.scalar else got
                assert np.array_equal(np.array(got).view(np.uint64),
                                      np.array(per).view(np.uint64)), (i, target.key)
    assert kinds >= {"uniform"} and (name == "paper" or "truncnorm" in kinds)

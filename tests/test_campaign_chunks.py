"""Local workers fly chunks of runs per message (issue 20): the same outcomes as one run
per message, every run once."""

from __future__ import annotations

from quadland.campaign.local import AHEAD, CHUNK, chunk_size, pool_runs
from quadland.campaign.sampling import iter_draws
from quadland.campaign.spec import campaign_spec_of
from quadland.scenario import load_scenario


def _outcomes(base, spec, runs, chunk):
    got = [o for batch in pool_runs(base, iter_draws(spec, range(runs), runs), 2, spec.limits,
                                    chunk) for o in batch]
    return sorted(got, key=lambda o: o.index)


def test_chunks_of_runs_give_the_outcomes_of_single_runs():
    base = load_scenario("paper", ["simulation.duration=0.5"])
    spec = campaign_spec_of(base)
    single, chunked = (_outcomes(base, spec, 11, c) for c in (1, 3))
    assert [o.index for o in chunked] == list(range(11))      # each once, 3 + 3 + ... + 2
    assert chunked == single                                   # metrics equal, bit for bit


def test_chunk_size_keeps_every_worker_busy_to_the_end():
    """CHUNK runs a message while each worker still gets AHEAD messages' worth."""
    assert chunk_size(300, 2) == CHUNK
    assert chunk_size(2 * AHEAD * 3, 2) == 3
    assert chunk_size(5, 2) == 1 and chunk_size(0, 4) == 1

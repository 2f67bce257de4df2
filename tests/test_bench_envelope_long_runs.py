"""The queue model of ``benchmarks/bench_envelope_long_runs.py`` (issue 20): two workers fed
as :func:`quadland.campaign.local.pool_runs` feeds them, against schedules worked out by
hand."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

PATH = Path(__file__).resolve().parent.parent / "benchmarks" / "bench_envelope_long_runs.py"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("bench_envelope_long_runs", PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_one_run_a_chunk_goes_to_the_worker_that_finished_first(bench):
    # worker 0 takes the 3 s run; worker 1 the three 1 s runs, one after the other
    assert bench.finishing_times([3.0, 1.0, 1.0, 1.0], 2, 1, 1) == [3.0, 3.0]
    # the long run last: the 1 s runs alternate, worker 0 gets the 3 s run at t = 1
    assert bench.finishing_times([1.0, 1.0, 3.0, 1.0], 2, 1, 1) == [4.0, 2.0]


def test_chunks_queued_ahead_are_flown_by_the_worker_they_were_sent_to(bench):
    # chunks of 2 runs: (1+1), (1+1), (5+1), (1+1); two queued on each worker at the
    # start, worker by worker as pool_runs sends them: worker 0 holds chunks 0 and 1
    # (2 s, 2 s), worker 1 chunks 2 and 3 (6 s, 2 s)
    costs = [1.0, 1.0, 1.0, 1.0, 5.0, 1.0, 1.0, 1.0]
    assert bench.finishing_times(costs, 2, 2, 2) == [4.0, 8.0]
    # one queued each: chunk 2 goes to worker 0 (both finish at 2 s, the first popped)
    # and chunk 3 to worker 1
    assert bench.finishing_times(costs, 2, 2, 1) == [8.0, 4.0]
    # every run is flown once: the ends add up to the work when nothing waits
    assert sum(bench.finishing_times([1.0] * 9, 3, 2, 4)) == pytest.approx(9.0)


def test_a_worker_sent_nothing_ends_at_zero_and_late_chunks_follow_the_first_free(bench):
    # fewer chunks than the first sends: worker 0 holds both (1 s, 2 s), worker 1 none
    assert bench.finishing_times([1.0, 2.0], 2, 1, 2) == [3.0, 0.0]
    # chunks of 3 (the last one short): 3 s and 6 s sent first, one each; worker 0 is
    # free at 3 s and takes the 1 s rest: both end at 4 s and 6 s
    assert bench.finishing_times([1.0] * 3 + [2.0] * 3 + [1.0], 2, 3, 1) == [4.0, 6.0]

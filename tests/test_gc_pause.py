"""quadland.plots.gc_pause: no collection within the context, none of its objects
scanned right after it, nothing kept from a later full collection, the collector's state
restored."""

from __future__ import annotations

import gc
import weakref

from quadland.plots.gc_pause import collection_paused


class _Node:
    pass


def _collections_during(action) -> list[int]:
    generations: list[int] = []

    def count(phase, info):
        if phase == "start":
            generations.append(info["generation"])
    gc.callbacks.append(count)
    try:
        action()
    finally:
        gc.callbacks.remove(count)
    return generations


def _cycles(n: int) -> list:
    out = []
    for _ in range(n):
        a, b = _Node(), _Node()
        a.other, b.other = b, a
        out.append(a)
    return out


def test_no_collection_within_and_the_objects_left_unscanned_after():
    assert gc.isenabled()
    gc.collect()
    kept: list = []

    def make():
        with collection_paused():
            assert not gc.isenabled()
            kept.append(_cycles(50_000))          # 100,000 objects: 140 collections' worth
    assert _collections_during(make) == []
    assert gc.isenabled()
    # the objects made within are in the oldest generation now, not the youngest
    assert gc.get_count()[0] < 700
    assert _collections_during(lambda: _cycles(2_000)).count(2) == 0


def test_the_cycles_made_within_are_freed_by_a_later_collection():
    refs = []

    def make():
        with collection_paused():
            for node in _cycles(100):
                refs.append(weakref.ref(node))
    make()                                        # every cycle unreachable on return
    assert all(r() is not None for r in refs)     # nothing collected them yet
    gc.collect()
    assert all(r() is None for r in refs)


def test_a_disabled_collector_stays_disabled():
    gc.disable()
    try:
        with collection_paused():
            pass
        assert not gc.isenabled()
    finally:
        gc.enable()
    with collection_paused():
        pass
    assert gc.isenabled()


def test_a_hosts_frozen_objects_stay_frozen():
    """A host that froze its objects (``gc.freeze`` before a fork) keeps them frozen: the
    context does not ``gc.unfreeze`` the process."""
    gc.collect()
    gc.freeze()
    try:
        frozen = gc.get_freeze_count()
        assert frozen > 0
        with collection_paused():
            _cycles(10)
        assert gc.get_freeze_count() == frozen
        assert gc.isenabled()
    finally:
        gc.unfreeze()

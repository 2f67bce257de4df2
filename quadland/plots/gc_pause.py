"""The cyclic garbage collector kept off figures being made (:func:`collection_paused`).

matplotlib allocates tens of thousands of objects for a figure (every tick is six
artists, every text, path and transform several more), and each 700 allocations
start a collection of the youngest generation, every tenth of those the middle one,
and as the survivors pile up the oldest: the whole heap, which in a command that has
just linearized a loop (CasADi's functions, the scenario, the review) holds several
hundred thousand objects. Those collections find almost nothing (the figures are alive
until they are written); merely pausing the collector would not save them either: the
first collections after the pause would scan every object the figures made, twice.

:func:`collection_paused` turns the collector off for the context, and at its end moves
every object alive into the oldest generation without scanning it (``gc.freeze`` then
``gc.unfreeze``): the next full collection, when the oldest generation has grown by a
quarter, frees the figures' cycles as usual. For the margin figures of ``quadland
margins`` that is 0.07 to 0.1 s of CPU (the collections during and after the figures
0.10 to 0.17 s before, 0.01 to 0.03 s now; 3 runs each).
"""

from __future__ import annotations

import contextlib
import gc

__all__ = ["collection_paused"]


@contextlib.contextmanager
def collection_paused():
    """No automatic garbage collection within the context; at its end every object alive
    moves to the oldest generation unscanned, and the collector is as it was (enabled
    again only if it was enabled). In a process that has frozen objects itself (a host
    application's ``gc.freeze`` before a fork) the move is skipped: ``gc.unfreeze`` would
    release its objects too."""
    was_enabled = gc.isenabled()
    host_frozen = gc.get_freeze_count() > 0
    gc.disable()
    try:
        yield
    finally:
        if not host_frozen:
            gc.freeze()     # everything alive to the permanent generation...
            gc.unfreeze()   # ...and back into the oldest one, unscanned
        if was_enabled:
            gc.enable()

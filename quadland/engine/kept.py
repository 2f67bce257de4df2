"""Draws kept between the runs of one process, by what they are drawn from (issue 20).

An envelope flies each replicate of its scenario's campaign in every cell: run ``r``
of every cell has run ``r``'s seed and drawn values, the axes' values in place of what
it drew for those keys. Whatever a run draws from its seed and from keys the axes do
not set (a landing's sensors' table, its force and moment noise, its turbulence's normals
and its gust) is then the same in every cell. :data:`KEPT` keeps such draws in the
process that flies the runs, under a key that holds everything they are drawn from (the
seed, the settings, the sizes), so that equal keys mean equal draws: a key the axes
change (a ``sensors.*`` axis) is another key in every cell, and nothing is reused.

Nothing is kept unless a caller asks, for its own calls, with :func:`keeping` (the
envelope's :func:`quadland.campaign.fly.fly`); then at most that many bytes are kept,
the least recently used given up first. Two kinds of entry:

* :meth:`KeptDraws.take` and :meth:`KeptDraws.give`: an object a run changes as it
  flies it (a table drawn as far as the flight goes, and further by the next run),
  held by one run at a time: ``take`` removes it, ``give`` puts it back. Two threads
  flying the same replicate each hold a copy of their own;
* :meth:`KeptDraws.shared`: a read-only array, handed to every run of its key.

A run flown on what was kept computes what it computes on fresh draws, bit for bit:
the keys hold every input of the draws, and the draws are the same bits however far
ahead they were drawn (``tests/test_kept_draws.py``).
"""

from __future__ import annotations

import contextlib
import contextvars
import itertools
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterator
from typing import Any

import numpy as np

__all__ = ["KeptDraws", "KEPT", "keeping", "kept_bytes", "forget"]

#: Bytes this context's calls may keep (0: nothing kept, nothing looked up).
_LIMIT: contextvars.ContextVar[int] = contextvars.ContextVar("quadland_kept_bytes", default=0)


def kept_bytes() -> int:
    """Bytes the calls of this context may keep (0 unless within :func:`keeping`)."""
    return _LIMIT.get()


@contextlib.contextmanager
def keeping(limit: int) -> Iterator[None]:
    """Within, this thread's calls keep draws in :data:`KEPT`, at most ``limit`` bytes
    (0: none). What is kept stays after the block, for the next run's; :meth:`~KeptDraws.
    clear` gives it up."""
    token = _LIMIT.set(max(int(limit), 0))
    try:
        yield
    finally:
        _LIMIT.reset(token)


class KeptDraws:
    """Draws by their inputs' key, at most :func:`kept_bytes` bytes, least recently used
    given up first. Thread-safe."""

    def __init__(self):
        self._lock = threading.Lock()
        # (key, serial) -> (value, bytes, shared): in the order of their last use
        self._entries: OrderedDict[tuple, tuple[Any, int, bool]] = OrderedDict()
        self._serial = itertools.count()
        self.bytes = 0

    def __len__(self) -> int:
        return len(self._entries)

    def take(self, key: Hashable) -> Any | None:
        """A kept object of ``key``, removed from the store (None: none kept)."""
        with self._lock:
            for entry in reversed(self._entries):
                if entry[0] == key and not self._entries[entry][2]:
                    value, size, _ = self._entries.pop(entry)
                    self.bytes -= size
                    return value
        return None

    def give(self, key: Hashable, value: Any, size: int) -> None:
        """Keep ``value`` (``size`` bytes, and its key's ``bytes``) under ``key`` for a later
        :meth:`take`; not when keeping nothing, nor when it alone is over the limit."""
        self._put(key, value, size, False)

    def shared(self, key: Hashable, make: Callable[[], np.ndarray]) -> np.ndarray:
        """The read-only array of ``key``: the one kept, else ``make()`` (made read-only,
        and kept when keeping)."""
        if not kept_bytes():
            return make()
        with self._lock:
            for entry in reversed(self._entries):
                if entry[0] == key and self._entries[entry][2]:
                    self._entries.move_to_end(entry)
                    return self._entries[entry][0]
        value = make()
        value.flags.writeable = False
        self._put(key, value, value.nbytes, True)
        return value

    def _put(self, key, value, size: int, shared: bool) -> None:
        size += _key_bytes(key)                 # a key's arrays (a run's times) held too
        limit = kept_bytes()
        if not limit or size > limit:
            return
        with self._lock:
            self._entries[(key, next(self._serial))] = (value, size, shared)
            self.bytes += size
            while self.bytes > limit:
                _, (_, old, _) = self._entries.popitem(last=False)
                self.bytes -= old

    def clear(self) -> None:
        """Give up everything kept."""
        with self._lock:
            self._entries.clear()
            self.bytes = 0


def _key_bytes(key) -> int:
    """Bytes of the ``bytes`` parts of ``key`` (an array's, kept with its entry)."""
    parts = key if isinstance(key, tuple) else (key,)
    return sum(len(p) for p in parts if isinstance(p, bytes))


#: The process's kept draws.
KEPT = KeptDraws()


def forget() -> None:
    """Give up everything this process keeps (:data:`KEPT`; a module function, so that a
    cluster's workers can be asked to run it)."""
    KEPT.clear()

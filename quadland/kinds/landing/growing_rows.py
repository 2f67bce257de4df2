"""Arrays of rows filled in order, with room to grow (the sensors' draws, issue 20).

A sensor's draws (:mod:`quadland.kinds.landing.sensing`) are extended as a flight
needs them; each extension's rows are written once into arrays with room to spare,
of which the sensor keeps views, instead of concatenating all the rows drawn before.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["GrowingRows"]


class GrowingRows:
    """Arrays of rows filled in order, with room to grow: ``{name: (dtype, row shape)}``.

    :meth:`reserve` makes room for a row count (at least doubling the room when it
    grows, the rows so far copied once), :meth:`put` writes rows from an offset,
    :meth:`views` gives each array's first rows (views: a write into one is kept)."""

    def __init__(self, columns: Mapping[str, tuple]):
        self.columns = dict(columns)
        self.arrays = [np.zeros((0, *shape), dtype=dt) for dt, shape in self.columns.values()]

    def reserve(self, rows: int) -> None:
        """Room for ``rows`` rows at least."""
        room = self.arrays[0].shape[0]
        if rows <= room:
            return
        room = max(rows, 2 * room)
        grown = []
        for a, (dt, shape) in zip(self.arrays, self.columns.values(), strict=True):
            b = np.empty((room, *shape), dtype=dt)     # rows past those put are never read
            b[:a.shape[0]] = a
            grown.append(b)
        self.arrays = grown

    def put(self, k0: int, values) -> None:
        """Write each array's ``values`` (in the order of ``columns``) from row ``k0``."""
        for a, v in zip(self.arrays, values, strict=True):
            a[k0:k0 + len(v)] = v

    def views(self, rows: int) -> tuple[np.ndarray, ...]:
        """Each array's first ``rows`` rows, views in the order of ``columns``."""
        return tuple(a[:rows] for a in self.arrays)

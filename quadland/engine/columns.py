"""A run's rows as columns: the transposed copy, in blocks of rows.

A simulator returns its rows (one per output instant, the signals side by side); a
result holds each signal as a contiguous column. NumPy's transposed copy of a whole
``(rows, width)`` array writes each of its ``rows``-long output rows one element per
input row: for a 40 s landing's 4,001 rows of 175 recorded signals (5.6 MB) every write
lands on another page, 1.6 ms where the same copy in blocks of :data:`BLOCK_ROWS` rows
takes 0.8 ms (medians of 41, in one process; issue 20, docs/performance.md). The values
are copied, never computed: the same bits.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BLOCK_ROWS", "columns_of"]

#: Rows of the source one block of the transposed copy takes (4 KiB of each output row).
BLOCK_ROWS = 512


def _copy_transposed(dst: np.ndarray, src: np.ndarray) -> None:
    """``dst[...] = src.T`` in blocks of :data:`BLOCK_ROWS` rows of ``src``."""
    for i in range(0, src.shape[0], BLOCK_ROWS):
        dst[:, i:i + BLOCK_ROWS] = src[i:i + BLOCK_ROWS].T


def columns_of(rows, at: int | None = None, row=None) -> np.ndarray:
    """The columns of ``rows`` (``(n, width)`` doubles) as the rows of a C-contiguous
    ``(width, n)`` array: ``rows.T`` itself when it is one, else a copy; with ``at``,
    ``row`` inserted before row ``at`` (the columns of ``numpy.insert(rows, at, row,
    axis=0)``, ``(width, n + 1)``) in the same one copy.

    Examples
    --------
    >>> a = np.arange(6.0).reshape(3, 2)
    >>> columns_of(a).tolist(), columns_of(a, 1, [-1, -2]).tolist()
    ([[0.0, 2.0, 4.0], [1.0, 3.0, 5.0]], [[0.0, -1.0, 2.0, 4.0], [1.0, -2.0, 3.0, 5.0]])
    >>> b = columns_of(a)
    >>> columns_of(b.T).base is b
    True
    """
    rows = np.asarray(rows, dtype=np.float64)
    if at is None and rows.T.flags.c_contiguous:
        return rows.T
    n, width = rows.shape
    if at is None:
        out = np.empty((width, n))
        _copy_transposed(out, rows)
        return out
    out = np.empty((width, n + 1))
    _copy_transposed(out[:, :at], rows[:at])
    out[:, at] = row
    _copy_transposed(out[:, at + 1:], rows[at:])
    return out

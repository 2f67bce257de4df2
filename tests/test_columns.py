"""columns_of against NumPy's own transpose and insert, across the copy's blocks."""

import numpy as np
import pytest

from quadland.engine.columns import BLOCK_ROWS, columns_of


def _layouts(a):
    """The same rows C-ordered, Fortran-ordered and as a strided view."""
    return a, np.asfortranarray(a), np.repeat(a, 2, axis=0)[::2]


@pytest.mark.parametrize("n", [0, 1, BLOCK_ROWS - 1, BLOCK_ROWS, BLOCK_ROWS + 1,
                               3 * BLOCK_ROWS + 7])
def test_the_columns_are_the_transpose_and_the_insert_of_numpy(n):
    """Every row count around a block's edge, every insertion point at an edge, three
    memory layouts: ``rows.T`` and ``numpy.insert(rows, at, row, axis=0).T``, bit for
    bit, C-contiguous, without touching the caller's rows."""
    rng = np.random.default_rng(n)
    a = rng.normal(size=(n, 7))
    a[rng.random(a.shape) < 0.1] = -0.0
    for rows in _layouts(a):
        before = rows.copy()
        got = columns_of(rows)
        assert got.shape == (7, n) and got.flags.c_contiguous
        assert got.tobytes() == np.ascontiguousarray(rows.T).tobytes()
        for at in sorted({0, 1, BLOCK_ROWS - 1, BLOCK_ROWS, BLOCK_ROWS + 1, n // 2, n}):
            if at > n:
                continue
            row = rng.normal(size=7)
            got = columns_of(rows, at, row)
            want = np.ascontiguousarray(np.insert(rows, at, row, axis=0).T)
            assert got.flags.c_contiguous and got.shape == want.shape
            assert got.tobytes() == want.tobytes(), (n, at)
        assert rows.tobytes() == before.tobytes()

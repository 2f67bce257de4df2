"""The heap of a process that flies many runs: the memory a run frees kept for the next.

One function, :func:`keep_freed_memory`, for the processes quadland owns (a campaign's
local workers, the ``campaign`` and ``envelope`` commands); docs/performance.md, "A
campaign's process".
"""

from __future__ import annotations

import ctypes

__all__ = ["MMAP_THRESHOLD", "TRIM_THRESHOLD", "keep_freed_memory"]

#: glibc's ``mallopt`` parameters (``malloc.h``) and the values a campaign sets.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: Blocks below this come from the heap, not a mapping of their own (glibc's largest).
MMAP_THRESHOLD = 32 * 2**20
#: Free memory at the heap's top kept, not given back to the kernel.
TRIM_THRESHOLD = 256 * 2**20


def keep_freed_memory() -> bool:
    """Let this process reuse the memory its runs free instead of faulting in fresh pages.

    A landing allocates and frees some 10 MiB of arrays (rows, columns, copies). glibc
    gives a large block its own mapping, or trims the heap's free top, and the next
    run's arrays then fault in fresh pages, each zeroed by the kernel: measured in a
    one-worker ``highway`` campaign, about 4 ms of a 38 ms landing, and more where the
    process had not grown its heap first (building a loop model did). Blocks under
    :data:`MMAP_THRESHOLD` come from the heap and up to :data:`TRIM_THRESHOLD` of free
    memory at its top is kept: the process holds the memory of its largest run, as it
    did at that run's peak. For the processes quadland owns that fly many runs: a local
    worker, and the process of the ``campaign`` and ``envelope`` commands (not a
    caller's of :func:`quadland.run_campaign`, whose heap stays as it set it); no result
    changes. Returns whether the C library took both settings (False without glibc:
    its parameters' numbers are glibc's own; on macOS, musl or Windows nothing is set).
    """
    try:
        libc = ctypes.CDLL(None)                # Windows: CDLL(None) is a TypeError
        mallopt = libc.mallopt
    except (OSError, AttributeError, TypeError):
        return False
    if not hasattr(libc, "gnu_get_libc_version"):   # glibc's alone: not macOS's, musl's
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and \
        bool(mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))

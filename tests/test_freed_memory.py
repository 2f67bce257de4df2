"""A campaign's process reuses the memory its runs free (``keep_freed_memory``)."""

from __future__ import annotations

import subprocess
import sys

import pytest

#: In a fresh process: two 12 MiB arrays made and freed together, in turn, the page
#: faults of the last eight rounds counted (the kernel's ``ru_minflt``), with or without
#: the setting.
_FAULTS = """
import resource, sys
import numpy as np
from quadland.engine.runs import keep_freed_memory
kept = keep_freed_memory() if sys.argv[1] == "keep" else None
def one():                                      # two arrays live at once, written whole
    a, b = np.ones((12 * 2**20) // 8), np.ones((12 * 2**20) // 8)
    return float(a[-1] + b[-1])
for _ in range(2):
    one()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(8):
    one()
print(kept, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> tuple[str, int]:
    out = subprocess.run([sys.executable, "-c", _FAULTS, mode], check=True,
                         capture_output=True, text=True).stdout.split()
    return out[0], int(out[1])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt, Linux's "
                    "fault count")
def test_freed_arrays_are_reused_without_faulting_in_fresh_pages():
    """Without the setting glibc gives the heap's freed top (24 MiB, past its trim
    threshold of twice the largest block freed) back to the kernel, and each round faults
    in its 24 MiB anew (at least 12 faults a round: its 2 MiB huge pages, 6,144 in 4 KiB
    pages); with it, the heap keeps them and the eight rounds fault in under a tenth of
    that."""
    kept, faults = _faults("keep")
    if kept != "True":
        pytest.skip("the C library has no glibc mallopt")
    _, plain = _faults("plain")
    assert plain >= 8 * 12
    assert faults < plain / 10

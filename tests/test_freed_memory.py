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
from quadland.engine.heap import keep_freed_memory
kept = keep_freed_memory() if sys.argv[1] == "keep" else None
if sys.argv[1] == "serial":                     # a caller's process: no run, no setting
    from quadland.campaign.local import serial_runs
    list(serial_runs(None, [], {}))
if sys.argv[1] == "command":                    # the command's own process, stopped early
    import quadland.campaign.execute as execute
    from quadland.cli import main
    def stop(*args, **kwargs):
        raise SystemExit(0)
    execute.run_campaign = stop
    try:
        main(["campaign", "--scenario", "highway", "--runs", "1", "--no-plots"])
    except SystemExit:
        pass
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


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt, Linux's "
                    "fault count")
def test_a_one_worker_campaign_called_from_python_leaves_the_caller_s_heap_as_it_was():
    """``run_campaign`` flies a one-worker campaign in its caller's process (its serial
    runs): the caller's heap keeps glibc's behaviour (the rounds fault as in a plain
    process); the command's process, which quadland owns, takes the setting."""
    kept, faults = _faults("keep")
    if kept != "True":
        pytest.skip("the C library has no glibc mallopt")
    _, serial = _faults("serial")
    assert serial >= 8 * 12
    _, command = _faults("command")
    assert command < serial / 10


class _NoGlibc:
    """The symbols of a process without glibc (macOS, musl): no ``gnu_get_libc_version``."""

    def __init__(self, name):
        self.mallopt = lambda *args: 1


def _refused(name):
    raise TypeError("LoadLibrary() argument 1 must be str, not None")   # Windows


@pytest.mark.parametrize("cdll", [_NoGlibc, _refused])
def test_without_glibc_nothing_is_set_and_nothing_raised(monkeypatch, cdll):
    """Without glibc (``mallopt``'s parameter numbers are glibc's own) or where
    ``ctypes.CDLL(None)`` is refused (Windows), the setting is left alone: False."""
    from quadland.engine import heap

    monkeypatch.setattr(heap.ctypes, "CDLL", cdll)
    assert heap.keep_freed_memory() is False

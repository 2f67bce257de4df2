"""A campaign reports a run (progress, counts, the interrupted line) only once synced.

The journal writes each finished run's line at once and makes it durable with an
``fsync`` shared by the runs of :data:`quadland.campaign.journal.SYNC_INTERVAL`
(tests/test_journal_sync.py). What the campaign reports must follow the ``fsync``,
not the ``write``: here every ``fsync`` of ``runs.csv`` (with the lines the file
held when it was called) and every update of the progress bar are recorded in one
sequence, on a clock that moves 0.3 s per reading, so that with the interval of
0.5 s the journal syncs after every second run: runs 0 and 1 written, synced,
reported; runs 2 and 3 the same; and so on.
"""

from __future__ import annotations

import errno
import os
import types
from pathlib import Path

import pytest
from campaign_stubs import ctrl_c_at_run

from quadland.campaign import execute, journal
from quadland.campaign.execute import CampaignInterrupted, run_campaign
from quadland.exceptions import CampaignStopped

RUNS = 6
SHORT = ["simulation.duration=1.0"]


class _Log:
    """One sequence of the journal's fsyncs and the progress bar's updates.

    ``("fsync", n)``: an ``fsync`` of runs.csv that returned, the file holding ``n``
    runs; ``("fsync failed", n)``: one that raised; ``("report", k)``: the bar
    counted ``k`` more runs.
    """

    def __init__(self, monkeypatch, out: Path, fail_at: int | None = None):
        self.events: list[tuple[str, int]] = []
        real_fsync = os.fsync
        calls = []

        def fsync(fd):
            if os.readlink(f"/proc/self/fd/{fd}") != str(out / "runs.csv"):
                return real_fsync(fd)
            held = len((out / "runs.csv").read_bytes().splitlines()) - 1
            calls.append(fd)
            if len(calls) == fail_at:
                self.events.append(("fsync failed", held))
                raise OSError(errno.EIO, os.strerror(errno.EIO))
            real_fsync(fd)
            self.events.append(("fsync", held))
            return None

        log = self

        class Bar:
            def update(self, n):
                log.events.append(("report", n))

            def close(self):
                pass

        ticks = iter(range(1, 10**6))
        monkeypatch.setattr(journal, "SYNC_INTERVAL", 0.5)
        monkeypatch.setattr(journal, "time", types.SimpleNamespace(
            monotonic=lambda: 0.3 * next(ticks)))
        monkeypatch.setattr(journal.os, "fsync", fsync)
        monkeypatch.setattr(execute, "_progress_bar", lambda show, total, done: Bar())

    def reported(self) -> int:
        return sum(n for kind, n in self.events if kind == "report")

    def check_reports_follow_syncs(self) -> None:
        """Every report comes right after an fsync that returned, and the runs reported
        so far are never more than the runs the last such fsync made durable."""
        synced, reported = 0, 0
        for k, (kind, n) in enumerate(self.events):
            if kind == "fsync":
                synced = n
            elif kind == "report":
                assert k > 0 and self.events[k - 1][0] == "fsync", self.events
                reported += n
                assert reported <= synced, self.events


def test_the_progress_counts_each_run_once_its_line_is_synced(tmp_path, monkeypatch):
    out = tmp_path / "c"
    log = _Log(monkeypatch, out)
    result = run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False,
                          progress=True)
    # the clock's derivation in the module docstring: synced after runs 1, 3 and 5
    assert log.events == [("fsync", 2), ("report", 2), ("fsync", 4), ("report", 2),
                          ("fsync", 6), ("report", 2)]
    log.check_reports_follow_syncs()
    assert result.recorded == RUNS == log.reported()


def test_the_interrupted_line_counts_the_runs_synced(tmp_path, monkeypatch):
    """Ctrl-C in run 3: runs 0 and 1 were synced and reported, run 2 written only; the
    interruption syncs it, then reports it, and the interrupted line says 3."""
    out = tmp_path / "c"
    log = _Log(monkeypatch, out)
    ctrl_c_at_run(monkeypatch, 3)
    with pytest.raises(CampaignInterrupted) as stopped:
        run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False,
                     progress=True)
    assert log.events == [("fsync", 2), ("report", 2), ("fsync", 3), ("report", 1)]
    log.check_reports_follow_syncs()
    assert stopped.value.recorded == 3 == log.reported()
    assert str(stopped.value).startswith("3 of 6 runs recorded")


def test_runs_whose_fsync_failed_are_never_reported(tmp_path, monkeypatch):
    """The second fsync fails (EIO): runs 0 and 1, synced by the first, are reported;
    runs 2 and 3, written before the failed one, are not, and the campaign stops."""
    out = tmp_path / "c"
    log = _Log(monkeypatch, out, fail_at=2)
    with pytest.raises(CampaignStopped) as stopped:
        run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False,
                     progress=True)
    assert log.events == [("fsync", 2), ("report", 2), ("fsync failed", 4)]
    log.check_reports_follow_syncs()
    assert log.reported() == 2
    assert "runs.csv" in str(stopped.value) and "Input/output error" in str(stopped.value)

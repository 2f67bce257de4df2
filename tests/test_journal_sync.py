"""The journal's fsync shared by the runs written within ``SYNC_INTERVAL`` (issue 20).

Each finished run is still one ``write`` of its line; the ``fsync`` that makes it
durable comes with the first run written ``SYNC_INTERVAL`` or more after the last
``fsync``, shared with the runs written meanwhile, or at the campaign's end or
interruption. A run is reported recorded
(the counts, the progress, the interrupted line) only once synced: nothing
reported is lost, and the resume flies exactly the runs not recorded.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from campaign_stubs import ctrl_c_at_run

from quadland.campaign import journal, local
from quadland.campaign.execute import CampaignInterrupted, run_campaign

RUNS = 6
SHORT = ["simulation.duration=1.0"]


class _Disk:
    """Every write to and fsync of the journal (``runs.csv`` in ``out``), in order."""

    def __init__(self, monkeypatch, out: Path):
        self.events: list[tuple[str, int]] = []
        self.out = out
        real_write, real_fsync = journal._write_all, os.fsync

        def write(fd, data):
            real_write(fd, data)
            if self._journal(fd):
                self.events.append(("write", data.count(b"\n")))

        def fsync(fd):
            real_fsync(fd)
            if self._journal(fd):
                self.events.append(("fsync", 0))

        monkeypatch.setattr(journal, "_write_all", write)
        monkeypatch.setattr(journal.os, "fsync", fsync)

    def _journal(self, fd: int) -> bool:
        return os.readlink(f"/proc/self/fd/{fd}") == str(self.out / "runs.csv")

    def count(self, kind: str) -> int:
        return sum(e[0] == kind for e in self.events)


def _lines(out: Path) -> list[bytes]:
    return (out / "runs.csv").read_bytes().splitlines()


@pytest.mark.parametrize("interval, fsyncs", [(0.0, RUNS), (1e9, 1)])
def test_runs_written_one_by_one_share_the_fsyncs_of_their_interval(tmp_path, monkeypatch,
                                                                     interval, fsyncs):
    """One worker: six runs, six writes of one line each; an interval of 0 s syncs each,
    one longer than the campaign syncs once, after the last write; the same runs.csv."""
    monkeypatch.setattr(journal, "SYNC_INTERVAL", interval)
    reference = tmp_path / "reference"
    run_campaign("paper", SHORT, runs=RUNS, out=reference, workers=1, plots=False)
    out = tmp_path / "c"
    disk = _Disk(monkeypatch, out)
    result = run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False)
    assert result.recorded == RUNS and result.complete
    assert [e for e in disk.events if e[0] == "write"] == [("write", 1)] * RUNS
    assert disk.count("fsync") == fsyncs and disk.events[-1] == ("fsync", 0)
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()


def test_an_interrupted_campaign_syncs_and_reports_every_run_written(tmp_path, monkeypatch):
    """Ctrl-C during the fourth run, no fsync due yet: the three runs written are synced
    before the campaign reports them recorded (3 of 6, the lines in runs.csv); the
    same command flies the other three, and runs.csv is the uninterrupted one's."""
    monkeypatch.setattr(journal, "SYNC_INTERVAL", 1e9)
    reference = tmp_path / "reference"
    run_campaign("paper", SHORT, runs=RUNS, out=reference, workers=1, plots=False)
    out = tmp_path / "c"
    disk = _Disk(monkeypatch, out)
    real_fly = ctrl_c_at_run(monkeypatch, 3)
    with pytest.raises(CampaignInterrupted) as stopped:
        run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False)
    assert stopped.value.recorded == 3 == len(_lines(out)) - 1
    assert disk.events == [("write", 1)] * 3 + [("fsync", 0)]
    monkeypatch.setattr(local, "fly", real_fly)
    result = run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False)
    assert result.flown == RUNS - 3 and result.complete
    assert (out / "runs.csv").read_bytes() == (reference / "runs.csv").read_bytes()


def test_a_failed_fsync_stops_the_campaign_and_is_not_retried(tmp_path, monkeypatch):
    """The journal's first fsync fails (EIO, as a disk's write-back error reports it): the
    campaign stops with one line naming runs.csv and the error, and the journal's
    descriptor is not synced again at the campaign's end (a second fsync can report
    success with the failed pages dropped)."""
    import errno

    from quadland.exceptions import CampaignStopped

    monkeypatch.setattr(journal, "SYNC_INTERVAL", 0.0)
    out = tmp_path / "c"
    calls: list[int] = []
    real_fsync = os.fsync

    def fsync(fd):
        if os.readlink(f"/proc/self/fd/{fd}") == str(out / "runs.csv"):
            calls.append(fd)
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real_fsync(fd)

    monkeypatch.setattr(journal.os, "fsync", fsync)
    with pytest.raises(CampaignStopped) as stopped:
        run_campaign("paper", SHORT, runs=RUNS, out=out, workers=1, plots=False)
    message = str(stopped.value)
    assert "runs.csv" in message and "Input/output error" in message and "\n" not in message
    assert len(calls) == 1                  # the end's sync did not try again

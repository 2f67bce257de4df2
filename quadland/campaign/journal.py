"""A campaign folder: claimed, identified, and written one finished run at a time.

Unlike the output sets of ``quadland simulate`` (written whole at the end,
:class:`quadland.output.OutputFolder`), a campaign's folder fills while it
runs, so that a stop loses only the runs in flight:

- ``campaign.json`` (the manifest: what must not change for the folder to be
  resumed) and ``scenario.toml`` are written first, each atomically;
- ``runs.csv`` is the journal: its header is written atomically with the
  manifest, then each finished run is one line appended with a single
  ``write`` on a file opened ``O_APPEND`` and made durable with ``fsync``
  before the run counts as recorded (the runs written within
  :data:`SYNC_INTERVAL` of the last ``fsync`` share the next one, and the
  campaign's end or interruption makes every run written durable: a run is
  reported recorded, in the progress and the counts, only once synced). Lines
  are in the order the runs finished;
- when every run is recorded, ``runs.csv`` is rewritten sorted by index and
  ``summary.json`` and the figures are written, each atomically (temporary
  file, ``fsync``, rename).

A killed campaign can leave a last line cut short (power loss; a killed
process completes its ``write``, a full disk may not): reading the journal
sets it aside and :meth:`CampaignFolder.start` removes it, so the run is
flown again. The folder is locked against a second campaign (or
simulation) by the same lock file as ``OutputFolder`` uses.

Everything is read and checked before anything is written: the manifest and
the journal must be regular files (not a link, a folder, a pipe or a
device) of bounded size, and every recorded run must be a run of this
campaign, recorded once. A folder refused is left byte for byte as it was.
A disk that fills while runs are recorded or the summary written stops the
campaign (:class:`~quadland.exceptions.CampaignStopped`): the runs recorded
before stay, and the same command resumes once there is space.
"""

from __future__ import annotations

import csv
import errno
import io
import json
import os
import stat
import time
from collections.abc import Iterable, Sequence
from pathlib import Path

from quadland.exceptions import CampaignError, CampaignStopped
from quadland.output import fsync_dir, lock_folder, strict_json, unlock_folder, write_bytes_atomic

__all__ = ["CampaignFolder", "new_folder", "MANIFEST", "RUNS", "SYNC_INTERVAL",
           "MAX_MANIFEST_BYTES", "MAX_ROW_BYTES", "format_row", "damaged_manifest",
           "json_kind", "read_regular"]

#: The manifest: the campaign's identity.
MANIFEST = "campaign.json"
#: The journal of finished runs, then the sorted table.
RUNS = "runs.csv"

#: Seconds from one ``fsync`` of the journal to the next at least: the runs written
#: meanwhile are made durable together, with the first run written after it (a 55 ms
#: landing's own ``fsync`` cost 7 to 20 ms on this machine's virtual disk).
SYNC_INTERVAL = 0.5
#: The files a campaign replaces whole (atomically) besides its journal.
WRITTEN = ("scenario.toml", "summary.json")
#: Largest manifest read, bytes (one holds a scenario, itself at most 1 MiB of TOML).
MAX_MANIFEST_BYTES = 16 * 2**20
#: Longest line of the journal read, bytes (a run's row is a few hundred).
MAX_ROW_BYTES = 2**20
#: What a file that is not a regular one is, in words.
_FILE_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"),
               (stat.S_ISCHR, "a device"), (stat.S_ISBLK, "a device"),
               (stat.S_ISSOCK, "a socket"))


def damaged_manifest(path: Path, why: str) -> CampaignError:
    """The error of a manifest that is not what quadland writes."""
    return CampaignError(f"out: {path} is damaged ({why}); it cannot be resumed: choose a new "
                         "folder")


def _refused(path: Path, why: str) -> CampaignError:
    return CampaignError(f"out: {path} {why}; it cannot be resumed: choose a new folder")


def _open_regular(path: Path):
    """``path`` opened for reading in binary, or None when absent.

    Never through a symbolic link, and never blocking on a named pipe; a
    path that is not a regular file is refused (:class:`CampaignError`).
    """
    flags = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(path, flags)
    except FileNotFoundError:
        return None
    except OSError as exc:
        if exc.errno == errno.ELOOP or path.is_symlink():
            raise _refused(path, "is a symbolic link") from None
        raise CampaignError(f"out: {path} cannot be read ({exc.strerror or exc}); choose a "
                            "new folder") from None
    mode = os.fstat(fd).st_mode
    if not stat.S_ISREG(mode):
        os.close(fd)
        what = next((name for test, name in _FILE_KINDS if test(mode)), "not a file")
        raise _refused(path, f"is not a regular file ({what})")
    os.set_blocking(fd, True)
    return os.fdopen(fd, "rb")


def read_regular(path: Path, limit: int) -> bytes | None:
    """The bytes of the regular file ``path`` (None when absent), refused over ``limit``.

    Raises
    ------
    CampaignError
        ``out: ...``: a link, a folder, a pipe, a device, or a file over ``limit`` bytes.
    """
    fh = _open_regular(path)
    if fh is None:
        return None
    try:
        with fh:
            data = fh.read(limit + 1)
    except OSError as exc:
        raise CampaignError(f"out: {path} cannot be read ({exc.strerror or exc}); choose a "
                            "new folder") from None
    if len(data) > limit:
        raise _refused(path, f"is larger than {limit / 2**20:g} MiB, more than a campaign "
                             "writes")
    return data


def _stopped(path: Path, exc: OSError, what: str) -> CampaignStopped:
    """The stop of a campaign that cannot write ``path``: resumable once it can."""
    full = exc.errno in (errno.ENOSPC, errno.EDQUOT)
    return CampaignStopped(f"out: cannot write {path}: {exc.strerror or exc}; {what}: "
                           + ("free some space and " if full else "")
                           + "run the same command to resume")


def json_kind(value) -> str:
    """What a parsed JSON value is, in JSON's words (``null``, ``an array``, ...)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    kinds = {str: "a string", int: "a number", float: "a number", list: "an array",
             dict: "an object"}
    return kinds.get(type(value), type(value).__name__)


def format_row(values: Sequence[str]) -> bytes:
    """One CSV line (``\\n``-terminated) of texts."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow(values)
    return buf.getvalue().encode("utf-8")


class CampaignFolder:
    """The folder of one campaign: a new or empty folder, or an earlier run of it.

    Parameters
    ----------
    path : path-like
    """

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path).absolute()
        self._lock_fd: int | None = None
        self._runs_fd: int | None = None
        self._journal_end: int | None = None    # bytes of whole lines read, when cut short
        self._unsynced: list[Sequence[str]] = []   # rows written since the last fsync
        self._synced_at = time.monotonic()

    def __enter__(self) -> CampaignFolder:
        return self if self._lock_fd is not None else self.claim()

    def __exit__(self, *exc) -> None:
        self.release()

    def check(self) -> None:
        """Refuse a path that is not a folder, or a folder of other files (creates nothing)."""
        path = self.path
        try:
            if path.exists() and not path.is_dir():
                raise CampaignError(f"out: {path} exists and is not a folder")
            if path.is_dir() and not os.path.lexists(path / MANIFEST) and any(path.iterdir()):
                raise CampaignError(f"out: {path} holds files that are not a quadland "
                                    "campaign; choose a new or empty folder")
            for name in WRITTEN:                 # replaced whole later: a file, or nothing
                mode = os.lstat(path / name).st_mode if os.path.lexists(path / name) else None
                if mode is not None and not stat.S_ISREG(mode):
                    what = next((n for test, n in _FILE_KINDS if test(mode)), "not a file")
                    raise _refused(path / name, f"is not a regular file ({what})")
        except OSError as exc:
            raise CampaignError(f"out: cannot read {path}: {exc.strerror or exc}") from None

    def claim(self) -> CampaignFolder:
        """Check the folder and lock it; raise :class:`CampaignError` (``out: ...``)."""
        self.check()
        self._lock_fd = lock_folder(self.path, CampaignError)
        return self

    def release(self) -> None:
        """Close the journal and drop the lock."""
        if self._runs_fd is not None:
            os.close(self._runs_fd)
            self._runs_fd = None
        if self._lock_fd is not None:
            fd, self._lock_fd = self._lock_fd, None
            unlock_folder(self.path, fd)

    def manifest(self) -> dict | None:
        """The manifest of an earlier run into this folder (a JSON object), or None."""
        path = self.path / MANIFEST
        raw = read_regular(path, MAX_MANIFEST_BYTES)
        if raw is None:
            return None
        try:
            data = json.loads(raw.decode("utf-8"))
        except (ValueError, RecursionError) as exc:
            why = " ".join(str(exc).split())[:120] or type(exc).__name__
            raise CampaignError(f"out: {path} cannot be read ({why}); choose a new "
                                "folder") from None
        if not isinstance(data, dict):
            raise damaged_manifest(path, f"{json_kind(data)}, not a JSON object")
        return data

    def start(self, manifest: dict, header: Sequence[str], files: dict[str, bytes]) -> None:
        """Write the manifest and ``files`` (atomically; a file that holds them already is
        left alone), the journal's header if new, and drop a last line cut short.

        Call it after :meth:`manifest` and :meth:`read_runs` have accepted the folder.
        """
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            for name, data in {MANIFEST: strict_json(manifest), **files}.items():
                if _holds(self.path / name, data):
                    continue
                write_bytes_atomic(self.path / name, data)
            if not os.path.lexists(self.path / RUNS):
                write_bytes_atomic(self.path / RUNS, format_row(header))
            elif self._journal_end is not None:
                os.truncate(self.path / RUNS, self._journal_end)
                self._journal_end = None
            fsync_dir(self.path)
        except OSError as exc:
            raise CampaignError(f"out: cannot write {self.path}: {exc.strerror or exc}") \
                from None

    def read_runs(self, header: Sequence[str], runs: int) -> dict[int, list[str]]:
        """The recorded runs by index, checked; nothing is written.

        A last line cut short is set aside (:meth:`start` removes it). Every
        line must hold a run of the campaign's ``runs`` (an index in
        ``[0, runs)``), each run once, with this campaign's columns.

        Raises
        ------
        CampaignError
            ``out: ...``: naming the file and the line at fault.
        """
        path = self.path / RUNS
        fh = _open_regular(path)
        if fh is None:
            return {}
        out: dict[int, list[str]] = {}
        lines: dict[int, int] = {}
        try:
            with fh:
                data = fh.readline(MAX_ROW_BYTES + 1)
                if data.endswith(b"\n") and _parse_line(data) == list(header):
                    end, n = len(data), 1
                else:
                    raise CampaignError(f"out: {path} does not have this campaign's columns; "
                                        "choose a new folder")
                while data := fh.readline(MAX_ROW_BYTES + 1):
                    n += 1
                    if not data.endswith(b"\n"):
                        if len(data) > MAX_ROW_BYTES:
                            raise _refused(path, f"line {n} is longer than "
                                                 f"{MAX_ROW_BYTES / 2**20:g} MiB")
                        self._journal_end = end       # cut short: flown again
                        break
                    end += len(data)
                    row = _parse_line(data)
                    index = _run_index(row, header)
                    if index is None:
                        raise CampaignError(f"out: {path} line {n} is damaged; choose a new "
                                            "folder")
                    if not 0 <= index < runs:
                        raise _refused(path, f"line {n} holds run {index}, not one of this "
                                             f"campaign's {runs} (0 to {runs - 1})")
                    if index in out:
                        raise _refused(path, f"line {n} holds run {index} again (line "
                                             f"{lines[index]})")
                    out[index], lines[index] = row, n
        except OSError as exc:
            raise CampaignError(f"out: {path} cannot be read ({exc.strerror or exc}); choose a "
                                "new folder") from None
        return out

    def append(self, rows: Iterable[Sequence[str]]) -> list[Sequence[str]]:
        """Write finished runs (one write); ``fsync`` once :data:`SYNC_INTERVAL` has passed
        since the last. Returns the rows this made durable (these and the ones written
        before them since the last ``fsync``), or none."""
        rows = list(rows)
        data = b"".join(format_row(r) for r in rows)
        if not data:
            return []
        try:
            if self._runs_fd is None:
                self._runs_fd = os.open(self.path / RUNS,
                                        os.O_WRONLY | os.O_APPEND | os.O_NOFOLLOW)
            _write_all(self._runs_fd, data)
        except OSError as exc:
            raise _stopped(self.path / RUNS, exc, "the runs recorded before are kept") \
                from None
        self._unsynced += rows
        if time.monotonic() - self._synced_at < SYNC_INTERVAL:
            return []
        return self.sync()

    def sync(self) -> list[Sequence[str]]:
        """``fsync`` the runs written since the last; returns them (recorded now)."""
        if not self._unsynced:
            return []
        try:
            os.fsync(self._runs_fd)
        except OSError as exc:
            # a failed fsync may have dropped the pages it reported: those runs are never
            # counted, and the descriptor is not synced again (a second fsync can succeed
            # with the data lost)
            self._unsynced = []
            raise _stopped(self.path / RUNS, exc, "the runs recorded before are kept") \
                from None
        done, self._unsynced = self._unsynced, []
        self._synced_at = time.monotonic()
        return done

    def finish(self, header: Sequence[str], rows: Iterable[Sequence[str]],
               files: dict[str, bytes]) -> None:
        """Rewrite the journal sorted (``rows``, in order) and write ``files``, each atomically."""
        if self._runs_fd is not None:
            os.close(self._runs_fd)
            self._runs_fd = None
        name = RUNS
        try:
            write_bytes_atomic(self.path / RUNS,
                               format_row(header) + b"".join(format_row(r) for r in rows))
            for name, data in files.items():
                write_bytes_atomic(self.path / name, data)
            fsync_dir(self.path)
        except OSError as exc:
            raise _stopped(self.path / name, exc, "every run is recorded") from None


def _write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to ``fd`` (``os.write`` may write part of it)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _holds(path: Path, data: bytes) -> bool:
    """Whether ``path`` is a regular file that holds exactly ``data``."""
    try:
        st = os.lstat(path)
        if not stat.S_ISREG(st.st_mode) or st.st_size != len(data):
            return False
        with open(path, "rb") as fh:
            return fh.read(len(data) + 1) == data
    except OSError:
        return False


def _parse_line(data: bytes) -> list[str] | None:
    """One CSV line's fields (None when it does not parse as one line)."""
    try:
        rows = list(csv.reader(io.StringIO(data.decode("utf-8", errors="replace"))))
    except csv.Error:
        return None
    return rows[0] if len(rows) == 1 else None


def _run_index(row: list[str] | None, header: Sequence[str]) -> int | None:
    """The run index of a journal row with the header's columns, or None."""
    if row is None or len(row) != len(header):
        return None
    try:
        return int(row[0])
    except ValueError:
        return None


def new_folder(name: str, kind: str) -> CampaignFolder:
    """A new folder ``<name>-<kind>-<YYYYmmdd-HHMMSS>[-N]`` in the current folder, claimed
    (``kind``: ``"campaign"`` or ``"envelope"``); a name taken meanwhile by a command
    started in the same second is passed over for the next."""
    import datetime

    stem = f"{name}-{kind}-{datetime.datetime.now().strftime('%Y%m%d-%H%M%S')}"
    for n in range(1, 1000):
        path = Path.cwd() / (stem if n == 1 else f"{stem}-{n}")
        if path.exists():
            continue
        try:
            return CampaignFolder(path).claim()
        except CampaignError:               # taken meanwhile by a command started with it
            if not path.parent.is_dir() or not os.access(path.parent, os.W_OK):
                raise
    raise CampaignError(f"out: no free folder name {stem}-N in {Path.cwd()}")

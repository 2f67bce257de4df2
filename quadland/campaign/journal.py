"""A campaign folder: claimed, identified, and written one finished run at a time.

Unlike the output sets of ``quadland simulate`` (written whole at the end,
:class:`quadland.output.OutputFolder`), a campaign's folder fills while it
runs, so that a stop loses only the runs in flight:

- ``campaign.json`` (the manifest: what must not change for the folder to be
  resumed) and ``scenario.toml`` are written first, each atomically;
- ``runs.csv`` is the journal: its header is written atomically with the
  manifest, then each finished run is one line appended with a single
  ``write`` on a file opened ``O_APPEND`` and made durable with ``fsync``
  before the run counts as recorded (runs finishing together share one
  ``fsync``). Lines are in the order the runs finished;
- when every run is recorded, ``runs.csv`` is rewritten sorted by index and
  ``summary.json`` and the figures are written, each atomically (temporary
  file, ``fsync``, rename).

A killed campaign can leave a last line cut short (power loss; a killed
process completes its ``write``): reading the journal drops it, and the run
is flown again. The folder is locked against a second campaign (or
simulation) by the same lock file as ``OutputFolder`` uses.
"""

from __future__ import annotations

import csv
import io
import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path

from quadland.exceptions import CampaignError
from quadland.output import fsync_dir, lock_folder, strict_json, unlock_folder, write_bytes_atomic

__all__ = ["CampaignFolder", "MANIFEST", "RUNS", "format_row", "damaged_manifest",
           "json_kind"]

#: The manifest: the campaign's identity.
MANIFEST = "campaign.json"
#: The journal of finished runs, then the sorted table.
RUNS = "runs.csv"


def damaged_manifest(path: Path, why: str) -> CampaignError:
    """The error of a manifest that is not what quadland writes."""
    return CampaignError(f"out: {path} is damaged ({why}); it cannot be resumed: choose a new "
                         "folder")


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
            if path.is_dir() and not (path / MANIFEST).is_file() and any(path.iterdir()):
                raise CampaignError(f"out: {path} holds files that are not a quadland "
                                    "campaign; choose a new or empty folder")
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
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, ValueError, RecursionError) as exc:
            why = " ".join(str(exc).split())[:120] or type(exc).__name__
            raise CampaignError(f"out: {path} cannot be read ({why}); choose a new "
                                "folder") from None
        if not isinstance(data, dict):
            raise damaged_manifest(path, f"{json_kind(data)}, not a JSON object")
        return data

    def start(self, manifest: dict, header: Sequence[str], files: dict[str, bytes]) -> None:
        """Write the manifest and ``files`` (atomically), and the journal's header if new."""
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(self.path / MANIFEST, strict_json(manifest))
            for name, data in files.items():
                write_bytes_atomic(self.path / name, data)
            if not (self.path / RUNS).exists():
                write_bytes_atomic(self.path / RUNS, format_row(header))
            fsync_dir(self.path)
        except OSError as exc:
            raise CampaignError(f"out: cannot write {self.path}: {exc.strerror or exc}") \
                from None

    def read_runs(self, header: Sequence[str]) -> dict[int, list[str]]:
        """The recorded runs by index; a last line cut short is removed from the file."""
        path = self.path / RUNS
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            return {}
        if data and not data.endswith(b"\n"):
            keep = data.rfind(b"\n") + 1
            os.truncate(path, keep)
            data = data[:keep]
        rows = list(csv.reader(io.StringIO(data.decode("utf-8", errors="replace"))))
        if not rows or rows[0] != list(header):
            raise CampaignError(f"out: {path} does not have this campaign's columns; choose a "
                                "new folder")
        out: dict[int, list[str]] = {}
        for n, row in enumerate(rows[1:], start=2):
            try:
                index = int(row[0])
            except (ValueError, IndexError):
                index = -1
            if len(row) != len(header) or index < 0 or index in out:
                raise CampaignError(f"out: {path} line {n} is damaged; choose a new folder")
            out[index] = row
        return out

    def append(self, rows: Iterable[Sequence[str]]) -> None:
        """Record finished runs: one write, then ``fsync``."""
        data = b"".join(format_row(r) for r in rows)
        if not data:
            return
        try:
            if self._runs_fd is None:
                self._runs_fd = os.open(self.path / RUNS, os.O_WRONLY | os.O_APPEND)
            view = memoryview(data)
            while view:
                view = view[os.write(self._runs_fd, view):]
            os.fsync(self._runs_fd)
        except OSError as exc:
            raise CampaignError(f"out: cannot write {self.path / RUNS}: "
                                f"{exc.strerror or exc}") from None

    def finish(self, header: Sequence[str], rows: Iterable[Sequence[str]],
               files: dict[str, bytes]) -> None:
        """Rewrite the journal sorted (``rows``, in order) and write ``files``, each atomically."""
        if self._runs_fd is not None:
            os.close(self._runs_fd)
            self._runs_fd = None
        try:
            write_bytes_atomic(self.path / RUNS,
                               format_row(header) + b"".join(format_row(r) for r in rows))
            for name, data in files.items():
                write_bytes_atomic(self.path / name, data)
            fsync_dir(self.path)
        except OSError as exc:
            raise CampaignError(f"out: cannot write {self.path}: {exc.strerror or exc}") \
                from None


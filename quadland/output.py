"""Writing run outputs: a claimed folder written whole, deterministic PNGs.

Both ``quadland simulate`` and ``quadland margins`` go through the same
steps. :func:`output_folder` names the target and returns an
:class:`OutputFolder`; claiming it (``with folder:``) checks it before any
work: it must be a new folder, an empty one or an earlier quadland output,
its parent must be writable, and no other run may be writing there (a lock
beside it). :meth:`OutputFolder.write` then writes the whole set of files
into a hidden folder beside the target and swaps it in, so that the set
appears together or not at all and replaces any earlier set whole; a run
interrupted at any point leaves either the old set or the new one.
:func:`figure_png` turns a figure into the bytes written.
"""

from __future__ import annotations

import ctypes
import datetime
import errno
import fcntl
import io
import json
import math
import os
import shutil
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from quadland.exceptions import OutputError

__all__ = ["PNG_DPI", "MARKER", "OutputFolder", "output_folder", "write_files", "figure_png",
           "json_ready", "strict_json", "write_bytes_atomic", "write_text_atomic"]

#: Resolution of the figures written, dots per inch.
PNG_DPI = 110
#: File that marks a folder as a quadland output (so that it may be replaced).
MARKER = ".quadland-output"


class OutputFolder:
    """A run's output folder: claimed before any work, written whole at the end.

    Use as a context manager around the run (``with folder: ...``), or call
    :meth:`claim` and :meth:`release`. Errors are :class:`OutputError`
    with messages starting with ``"out: "``.

    Parameters
    ----------
    path : path-like
        The target folder.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path).absolute()
        self._lock_fd: int | None = None

    def __repr__(self) -> str:
        return f"OutputFolder({str(self.path)!r})"

    def __fspath__(self) -> str:
        return str(self.path)

    @property
    def _lock_path(self) -> Path:
        return self.path.parent / f".{self.path.name}.lock"

    def claim(self) -> OutputFolder:
        """Check the target and lock it against other runs; nothing is written yet."""
        if self._lock_fd is not None:
            return self
        path = self.path
        if path.exists() and not path.is_dir():
            raise OutputError(f"out: {path} exists and is not a folder")
        if path.is_dir() and not _replaceable(path):
            raise OutputError(f"out: {path} holds files that are not a quadland output; "
                              "choose a new or empty folder")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(self._lock_path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise OutputError(f"out: cannot write to {path.parent}: "
                              f"{exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise OutputError(f"out: {path} is in use by another quadland run") from None
        self._lock_fd = fd
        for stale in path.parent.glob(f".{path.name}.tmp-*"):
            shutil.rmtree(stale, ignore_errors=True)      # left by a killed run
        return self

    def release(self) -> None:
        """Drop the lock (and its file)."""
        if self._lock_fd is None:
            return
        try:
            self._lock_path.unlink(missing_ok=True)
        finally:
            os.close(self._lock_fd)
            self._lock_fd = None

    def __enter__(self) -> OutputFolder:
        return self.claim()

    def __exit__(self, *exc) -> None:
        self.release()

    def write(self, files: Mapping[str, bytes]) -> Path:
        """Write ``files`` as the folder's whole content, replacing any earlier set.

        Parameters
        ----------
        files : mapping of str to bytes
            File name (no folder part) to content.

        Returns
        -------
        Path
            The folder.
        """
        for name in files:
            if Path(name).name != name or name in ("", ".", "..", MARKER):
                raise ValueError(f"files: {name!r} is not a plain file name")
        claimed_here = self._lock_fd is None
        self.claim()
        tmp = None
        try:
            tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.tmp-", dir=self.path.parent))
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o777 & ~umask)
            for name, data in {**files, MARKER: b"quadland output folder\n"}.items():
                _write_synced(tmp / name, data, 0o666 & ~umask)
            _fsync_dir(tmp)
            _swap_in(tmp, self.path)
            tmp = None
            _fsync_dir(self.path.parent)
        except OSError as exc:
            raise OutputError(f"out: cannot write {self.path}: {exc.strerror or exc}") from None
        finally:
            if tmp is not None:
                shutil.rmtree(tmp, ignore_errors=True)
            if claimed_here:
                self.release()
        return self.path


def _replaceable(path: Path) -> bool:
    """An empty folder or an earlier quadland output."""
    try:
        return (path / MARKER).is_file() or not any(path.iterdir())
    except OSError:
        return False


def _write_synced(path: Path, data: bytes, mode: int) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def _fsync_dir(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


_RENAME_EXCHANGE = 2
_AT_FDCWD = -100


def _swap_in(new: Path, target: Path) -> None:
    """Put the folder ``new`` at ``target``: one atomic rename where possible."""
    if not target.exists():
        os.rename(new, target)
        return
    renameat2 = getattr(ctypes.CDLL(None, use_errno=True), "renameat2", None)
    if renameat2 is not None:
        if renameat2(_AT_FDCWD, os.fsencode(new), _AT_FDCWD, os.fsencode(target),
                     _RENAME_EXCHANGE) == 0:
            shutil.rmtree(new, ignore_errors=True)      # now holds the old set
            return
        if ctypes.get_errno() not in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
    # No atomic exchange (another OS or file system): two renames, the old set
    # kept aside until the new one is in place.
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
    os.rename(target, old / "set")
    os.rename(new, target)
    shutil.rmtree(old, ignore_errors=True)


def output_folder(out: str | os.PathLike | None, name: str, kind: str = "") -> OutputFolder:
    """The folder a run will write to (not claimed yet).

    Parameters
    ----------
    out : path-like, optional
        The folder asked for. If None, a new folder
        ``<name>[-<kind>]-<YYYYmmdd-HHMMSS>`` in the current folder, made
        unique with a suffix ``-2``, ``-3``, ... when that name is taken.
    name : str
        Stem of the default folder name (the scenario's name).
    kind : str, optional
        What the run produces (``"margins"``); empty for a simulation.

    Returns
    -------
    OutputFolder

    Raises
    ------
    OutputError
        ``out`` exists and is not a folder. The message starts with
        ``"out: "``, the parameter's name.
    """
    if out is not None:
        path = Path(out)
        if path.exists() and not path.is_dir():
            raise OutputError(f"out: {path} exists and is not a folder")
        return OutputFolder(path)
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    stem = "-".join(s for s in (name, kind, stamp) if s)
    path, n = Path.cwd() / stem, 1
    while path.exists():
        n += 1
        path = Path.cwd() / f"{stem}-{n}"
    return OutputFolder(path)


def write_files(folder: str | os.PathLike | OutputFolder, files: Mapping[str, bytes]) -> Path:
    """Write ``files`` as the whole content of ``folder`` (see :meth:`OutputFolder.write`)."""
    target = folder if isinstance(folder, OutputFolder) else OutputFolder(folder)
    return target.write(files)


def json_ready(x):
    """``x`` with NumPy scalars as Python ones and every NaN or infinity as None.

    ``None`` (``null``) stands for an undefined or unbounded value: a
    settling time never reached, a margin without a crossing.
    """
    if isinstance(x, dict):
        return {k: json_ready(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [json_ready(v) for v in x]
    if isinstance(x, float | np.floating):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def strict_json(data) -> bytes:
    """``data`` as strict JSON (RFC 8259): no NaN or Infinity tokens (see :func:`json_ready`)."""
    return (json.dumps(json_ready(data), indent=2, allow_nan=False) + "\n").encode("utf-8")


def figure_png(fig) -> bytes:
    """PNG bytes of a matplotlib figure, the same for the same figure.

    Drawn at :data:`PNG_DPI` without the "Software" metadata entry (which
    carries matplotlib's version). A figure that pyplot manages is closed
    afterwards, so that a batch of figures does not accumulate.

    Parameters
    ----------
    fig : matplotlib.figure.Figure

    Returns
    -------
    bytes
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=PNG_DPI, metadata={"Software": None})
    if getattr(fig.canvas, "manager", None) is not None:
        import matplotlib.pyplot as plt

        plt.close(fig)
    return buf.getvalue()


def write_bytes_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename.

    A reader never sees a half-written file, and an existing file is
    replaced only once the new content is complete on disk.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text_atomic(path, text: str) -> None:
    """Write UTF-8 ``text`` to ``path`` atomically (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))

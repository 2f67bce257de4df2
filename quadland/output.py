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
:func:`figure_png` (:mod:`quadland.png`) turns a figure into the bytes written.
"""

from __future__ import annotations

import ctypes
import datetime
import errno
import fcntl
import glob
import json
import math
import os
import shutil
import stat
import tempfile
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from quadland.exceptions import OutputError
from quadland.png import PNG_COMPRESS_LEVEL, PNG_DPI, figure_png

__all__ = ["PNG_DPI", "PNG_COMPRESS_LEVEL", "MARKER", "OutputFolder", "output_folder",
           "write_files", "figure_png", "json_ready", "strict_json", "write_bytes_atomic",
           "write_text_atomic", "lock_folder", "unlock_folder", "fsync_dir", "WorkFolder",
           "remove_abandoned"]

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
        self.path = Path(os.path.normpath(Path(path).absolute()))
        self._lock_fd: int | None = None

    def __repr__(self) -> str:
        return f"OutputFolder({str(self.path)!r})"

    def __fspath__(self) -> str:
        return str(self.path)

    def _check(self) -> None:
        path = self.path
        if path.is_symlink():
            raise OutputError(f"out: {path} is a symbolic link; give the folder itself")
        if path.exists() and not path.is_dir():
            raise OutputError(f"out: {path} exists and is not a folder")
        cwd = Path.cwd().resolve()
        if path.exists() and (cwd == path.resolve() or path.resolve() in cwd.parents):
            raise OutputError(f"out: {path} is the current folder or holds it; choose "
                              "another (a set replaces its folder whole)")
        if len(os.fsencode(path.name)) > _NAME_MAX - _TEMP_SUFFIX:
            raise OutputError(f"out: the folder name {path.name[:40]}... is too long")
        if path.is_dir() and not _replaceable(path):
            raise OutputError(f"out: {path} holds files that are not a quadland output; "
                              "choose a new or empty folder")

    def claim(self) -> OutputFolder:
        """Check the target and lock it against other runs; nothing is written yet."""
        if self._lock_fd is not None:
            return self
        self._check()
        path = self.path
        self._lock_fd = lock_folder(path, OutputError)
        stem = glob.escape(f".{path.name}")
        for stale in (*path.parent.glob(f"{stem}.tmp-*"), *path.parent.glob(f"{stem}.old-*")):
            _remove(stale)                                   # left by a killed run
        return self

    def release(self) -> None:
        """Drop the lock (and its file)."""
        if self._lock_fd is not None:
            fd, self._lock_fd = self._lock_fd, None
            unlock_folder(self.path, fd)

    def __enter__(self) -> OutputFolder:
        return self.claim()

    def __exit__(self, *exc) -> None:
        self.release()

    def write(self, files: Mapping[str, bytes]) -> Path:
        """Write ``files`` as the folder's whole content, replacing any earlier set.

        An earlier set is replaced only if the folder still holds nothing but
        the files its manifest (:data:`MARKER`) names: files that appeared in
        it meanwhile make the write fail, and they stay.

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
            manifest = json.dumps({"quadland_output": sorted(files)}, indent=1) + "\n"
            for name, data in {**files, MARKER: manifest.encode("utf-8")}.items():
                _write_synced(tmp / name, data, 0o666 & ~umask)
            fsync_dir(tmp)
            if self.path.exists() and not _replaceable(self.path):
                raise OutputError(f"out: {self.path} gained files that are not a quadland "
                                  "output during the run; nothing was replaced")
            _swap_in(tmp, self.path)
            tmp = None
            fsync_dir(self.path.parent)
        except OSError as exc:
            if isinstance(exc, OutputError):
                raise
            raise OutputError(f"out: cannot write {self.path}: {exc.strerror or exc}") from None
        finally:
            if tmp is not None:
                _remove(tmp)
            if claimed_here:
                self.release()
        return self.path


#: Longest file name most file systems take, and what the temporary names add.
_NAME_MAX, _TEMP_SUFFIX = 255, 24


def _lock_path(path: Path) -> Path:
    return path.parent / f".{path.name}.lock"


def lock_folder(path: Path, error: type[Exception]) -> int:
    """Lock the folder ``path`` against other quadland runs; return the lock's descriptor.

    The lock is an exclusive ``flock`` on ``.<name>.lock`` beside the folder,
    shared by :class:`OutputFolder` and campaign folders. Raises ``error``
    (``"out: ..."``) when the parent cannot be written or the lock is held.
    """
    for _ in range(8):
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(_lock_path(path), os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise error(f"out: cannot write to {path.parent}: "
                        f"{exc.strerror or exc}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise error(f"out: {path} is in use by another quadland run") from None
        try:
            same = os.fstat(fd).st_ino == os.stat(_lock_path(path)).st_ino
        except OSError:
            same = False
        if same:                 # not a lock file that its holder unlinked meanwhile
            return fd
        os.close(fd)
    raise error(f"out: {path} is in use by another quadland run")


def unlock_folder(path: Path, fd: int) -> None:
    """Drop a lock taken by :func:`lock_folder` (and its file)."""
    try:
        _lock_path(path).unlink(missing_ok=True)
    finally:
        os.close(fd)


def _remove(path: Path) -> None:
    """Remove a file, a symbolic link or a folder, quietly."""
    try:
        if path.is_symlink() or not path.is_dir():
            path.unlink(missing_ok=True)
        else:
            shutil.rmtree(path, ignore_errors=True)
    except OSError:
        pass


def _replaceable(path: Path) -> bool:
    """An empty folder, or one that holds exactly the files its manifest names."""
    try:
        entries = list(path.iterdir())
        if not entries:
            return True
        listed = set(json.loads((path / MARKER).read_text())["quadland_output"])
    except (OSError, ValueError, KeyError, TypeError):
        return False
    return all((e.name == MARKER or e.name in listed) and e.is_file() and not e.is_symlink()
               for e in entries)


def _write_synced(path: Path, data: bytes, mode: int) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())


def fsync_dir(path: Path) -> None:
    """``fsync`` a folder, so that renames and new files in it are durable."""
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
            _remove(new)                                 # now holds the old set
            return
        if ctypes.get_errno() not in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
    # No atomic exchange (another OS or file system): two renames, the old set
    # kept aside until the new one is in place.
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
    os.rename(target, old / "set")
    os.rename(new, target)
    _remove(old)


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
        Claimed already when the name is the default one (so that two runs
        started in the same second take different names).

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
    for n in range(1, 1000):
        path = Path.cwd() / (stem if n == 1 else f"{stem}-{n}")
        if path.exists():
            continue
        folder = OutputFolder(path)
        try:
            return folder.claim()              # claimed now: a run started in the same
        except OutputError:                    # second takes the next name
            continue
    raise OutputError(f"out: no free folder name {stem}-N in {Path.cwd()}")


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


class WorkFolder:
    """A private temporary folder that its process holds while it lives.

    ``mkdtemp`` under ``parent`` (mode 0700), with an exclusive ``flock`` on
    the folder itself for as long as it is open: :func:`remove_abandoned`
    removes such folders only when no live process holds them (a process
    killed by SIGKILL drops its locks with it). Use as a context manager;
    leaving it removes the folder.

    Parameters
    ----------
    parent : path-like
        Where to make it (on the file system of what it will be moved to).
    prefix : str
        Start of its name, e.g. ``".build-"``.
    """

    def __init__(self, parent: str | os.PathLike, prefix: str):
        self.path = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
        try:
            self._fd: int | None = os.open(self.path, os.O_RDONLY | os.O_DIRECTORY)
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            self.close()
            raise

    def close(self) -> None:
        """Remove the folder (whatever it still holds) and drop the lock."""
        _remove(self.path)
        if self._fd is not None:
            fd, self._fd = self._fd, None
            os.close(fd)

    def __enter__(self) -> WorkFolder:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def remove_abandoned(parent: str | os.PathLike, pattern: str, min_age_s: float = 60.0) -> int:
    """Remove the folders ``parent/pattern`` that no live process holds; return how many.

    A folder is abandoned when it is older than ``min_age_s`` (by its
    modification time: a folder just made is not locked yet) and its
    :class:`WorkFolder` lock can be taken. Symbolic links and files that
    match are left alone. Nothing is raised: what cannot be removed stays.
    """
    import time

    removed, now = 0, time.time()
    for path in Path(parent).glob(pattern):
        try:
            st = os.lstat(path)
            if not stat.S_ISDIR(st.st_mode) or now - st.st_mtime < min_age_s:
                continue
            fd = os.open(path, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue                                         # held by a live process
        try:
            shutil.rmtree(path)
            removed += 1
        except OSError:
            pass
        finally:
            os.close(fd)
    return removed

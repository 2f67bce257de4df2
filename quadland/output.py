"""Writing run outputs: a checked folder, whole files, deterministic PNGs.

Both ``quadland simulate`` and ``quadland margins`` go through the same
three steps: :func:`output_folder` names and checks the target before any
work, :func:`write_files` creates it and writes the whole set of files in
one call, and :func:`figure_png` turns a figure into the bytes written.
Handing over the set in one call leaves room to make it transactional
(all files or none) without changing a caller.
"""

from __future__ import annotations

import datetime
import io
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

from quadland.exceptions import QuadlandError

__all__ = ["PNG_DPI", "output_folder", "write_files", "figure_png", "write_bytes_atomic",
           "write_text_atomic"]

#: Resolution of the figures written, dots per inch.
PNG_DPI = 110


def output_folder(out: str | os.PathLike | None, name: str, kind: str = "") -> Path:
    """The folder a run will write to, checked before any work.

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
    Path
        The folder, not created yet (see :func:`write_files`).

    Raises
    ------
    QuadlandError
        ``out`` exists and is not a folder. The message starts with
        ``"out: "``, the parameter's name.
    """
    if out is not None:
        path = Path(out)
        _check_folder(path)
        return path
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    stem = "-".join(s for s in (name, kind, stamp) if s)
    path, n = Path.cwd() / stem, 1
    while path.exists():
        n += 1
        path = Path.cwd() / f"{stem}-{n}"
    return path


def _check_folder(path: Path) -> None:
    if path.exists() and not path.is_dir():
        raise QuadlandError(f"out: {path} exists and is not a folder")


def write_files(folder: str | os.PathLike, files: Mapping[str, bytes]) -> Path:
    """Create ``folder`` and write every file of ``files`` into it.

    Parameters
    ----------
    folder : path-like
        Usually the result of :func:`output_folder`; created with its
        parents if missing.
    files : mapping of str to bytes
        File name (no folder part) to content.

    Returns
    -------
    Path
        The folder.

    Raises
    ------
    QuadlandError
        The folder cannot be created (message starting with ``"out: "``).
    ValueError
        A name of ``files`` is not a plain file name.

    Notes
    -----
    Each file is written whole or not at all (:func:`write_bytes_atomic`);
    files of the folder that are not in ``files`` are left alone.
    """
    folder = Path(folder)
    for name in files:
        if Path(name).name != name or name in ("", ".", ".."):
            raise ValueError(f"files: {name!r} is not a plain file name")
    _check_folder(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise QuadlandError(f"out: cannot create {folder}: {exc.strerror}") from None
    for name, data in files.items():
        write_bytes_atomic(folder / name, data)
    return folder


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

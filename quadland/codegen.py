"""Regenerate, or check, the generated C code for a scenario.

``generated/`` in a source checkout is one tree with both flight steps: the
paper's control step with the paper scenario's values (``quadland.h``) and
the landing step and guidance with the ``highway`` scenario's
(``quadland_landing.h``); the double-precision build at its top, the
single-precision build in ``float/`` and the pure-C example in
``example/`` (``fly``: the paper's flight, ``land``: highway's landing, and
``bench``). Every file comes from :func:`quadland_symbolic.codegen.generate_tree`. A
landing scenario replaces the landing half's values and the paper's half
keeps its own, any other scenario the reverse; such a tree, or one from an
installed (non-editable) quadland, is written into a folder given with
``--out``.
"""

from __future__ import annotations

import difflib
import glob
import os
import stat
import sys
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from quadland.exceptions import CodegenError
from quadland.kinds import KINDS, kind_of
from quadland.output import WorkFolder, fsync_dir, remove_abandoned
from quadland.scenario import Scenario, load_scenario
from quadland_symbolic.codegen import TREE_PARTS, generate_tree

__all__ = ["DEFAULT_SCENARIO", "checkout_root", "generated_dir", "tree_defaults",
           "generated_files", "stale", "write", "check_target", "diff", "main"]

#: The scenario ``quadland codegen`` writes without ``--scenario``.
DEFAULT_SCENARIO = "paper"


def _package_parent() -> Path:
    """The folder that holds the ``quadland`` package."""
    return Path(__file__).resolve().parents[1]


def checkout_root() -> Path | None:
    """The source checkout quadland runs from, or None when it is installed.

    A checkout is the folder above the ``quadland`` package when it holds
    ``pyproject.toml``, ``symbolic/`` and ``generated/`` (an installed
    package sits in ``site-packages``, beside an installed ``quadland_symbolic``
    but without the other two).
    """
    root = _package_parent()
    if ((root / "pyproject.toml").is_file() and (root / "symbolic").is_dir()
            and (root / "generated").is_dir()):
        return root
    return None


def generated_dir() -> Path:
    """The checkout's ``generated/``.

    Raises
    ------
    CodegenError
        When quadland is not run from a source checkout.
    """
    root = checkout_root()
    if root is None:
        raise CodegenError(f"quadland is installed in {_package_parent()}, not run from a "
                           f"source checkout: there is no generated/ to write; pass --out DIR")
    return root / "generated"


#: The generated tree's own list of its files: a later generation removes only
#: files named there, never anything else under the target.
MANIFEST = ".quadland-generated"


def tree_defaults(scenario: Scenario | None = None) -> dict[str, Any]:
    """The C defaults of each part of the generated tree, by part name.

    Each loop kind's part carries its default scenario's values
    (:attr:`quadland.kinds.LoopKind.default_scenario`), the part of
    ``scenario``'s kind that scenario's.
    """
    parts_of = [k.codegen_part for k in KINDS.values() if k.codegen_part is not None]
    if len(parts_of) != len(set(parts_of)):
        raise CodegenError(f"the loop kinds share a part of the generated tree "
                           f"({', '.join(sorted(parts_of))}): each part is one kind's")
    if scenario is not None and kind_of(scenario).codegen_part not in TREE_PARTS:
        raise CodegenError(f"--scenario: the loop kind {scenario.model!r} has no part in the "
                           f"generated tree (its parts: {', '.join(TREE_PARTS)})")
    parts = {k.codegen_part: k.codegen_defaults(load_scenario(k.default_scenario))
             for k in KINDS.values()
             if k.codegen_part in TREE_PARTS and (scenario is None or k.name != scenario.model)}
    if scenario is not None:
        kind = kind_of(scenario)
        parts[kind.codegen_part] = kind.codegen_defaults(scenario)
    return parts


def generated_files(scenario: Scenario | None = None) -> dict[str, str]:
    """Every file of the generated tree by relative path (POSIX separators).

    Each part carries its kind's default scenario's values, the part of
    ``scenario``'s kind that scenario's (:func:`tree_defaults`). The tree
    includes :data:`MANIFEST`, the list of its other files.
    """
    d = tree_defaults(scenario)
    files = generate_tree(d)
    files[MANIFEST] = "".join(f"{rel}\n" for rel in sorted(files))
    return files


#: Every generated file says this; a file under the target that says it but is
#: no longer generated is stale.
_MARK = "Do not edit: regenerate with `quadland codegen`"


def stale(out: Path, files: dict[str, str]) -> list[str]:
    """Files a former generation wrote under ``out`` and this one does not.

    Only files that the former generation's :data:`MANIFEST` lists, that are
    regular files inside ``out`` and that still carry the generated marker:
    nothing else under ``out`` is ever touched.
    """
    manifest = out / MANIFEST
    if not manifest.is_file() or manifest.is_symlink():
        return []
    try:
        listed = manifest.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError):
        return []
    found = []
    for rel in listed:
        parts = Path(rel).parts
        if not rel or rel in files or Path(rel).is_absolute() or ".." in parts:
            continue
        path = out / rel
        if not path.is_file() or any((out / Path(*parts[:k])).is_symlink()
                                     for k in range(1, len(parts) + 1)):
            continue                       # never through a symbolic link
        try:
            head = path.read_text(encoding="utf-8")[:1000]
        except (OSError, UnicodeDecodeError):
            continue
        if _MARK in head:
            found.append(rel)
    return found


def write(out: Path, files: dict[str, str]) -> list[str]:
    """Write ``files`` under ``out`` and remove stale ones; return the paths that changed.

    Every path is checked before anything is written, and nothing of the
    user's is ever replaced: a file in the way that the former generation's
    :data:`MANIFEST` does not list (unless it already holds exactly the
    generated text), a folder or anything else where a file goes, a file
    where a folder goes, and a symbolic link anywhere under ``out`` on a
    written path are refused, naming the path. The changed files are then
    written whole into a hidden folder inside ``out`` (a new ``out``: beside
    it) and renamed into place, the manifest last; a new ``out`` appears
    whole or not at all.

    Raises
    ------
    CodegenError
        ``"out: ..."``, naming what is in the way or cannot be written;
        nothing under ``out`` has changed then.
    """
    out = Path(out)
    _check_tree(out, files)
    old = stale(out, files)                  # from the former manifest, before it goes
    changed = [rel for rel, text in sorted(files.items())
               if not _holds(out / rel, text.encode("utf-8"))]
    if not changed and not old:
        return []
    try:
        if not out.exists():
            out.parent.mkdir(parents=True, exist_ok=True)
            remove_abandoned(out.parent, f".{glob.escape(out.name)}.codegen-*")
            with WorkFolder(out.parent, f".{out.name}.codegen-") as work:
                _stage(work.path, files, files)
                os.chmod(work.path, 0o777 & ~_umask())
                os.rename(work.path, out)
            fsync_dir(out.parent)
            return changed
        remove_abandoned(out, f"{MANIFEST}.tmp-*")           # left by a killed generation
        with WorkFolder(out, f"{MANIFEST}.tmp-") as work:
            _stage(work.path, files, changed)
            _check_tree(out, files)          # nothing moved in meanwhile
            for rel in sorted(changed, key=lambda r: r == MANIFEST):     # the manifest last
                (out / rel).parent.mkdir(parents=True, exist_ok=True)
                os.replace(work.path / rel, out / rel)
            for rel in old:
                (out / rel).unlink()
            for folder in {(out / rel).parent for rel in (*changed, *old)}:
                fsync_dir(folder)
    except OSError as exc:
        raise CodegenError(f"out: cannot write {out}: {exc.strerror or exc}") from None
    return changed + old


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


def _holds(path: Path, data: bytes) -> bool:
    """Whether ``path`` is a regular file (not a link) holding exactly ``data``."""
    try:
        if not stat.S_ISREG(os.lstat(path).st_mode):
            return False
        return path.stat().st_size == len(data) and path.read_bytes() == data
    except OSError:
        return False


def _stage(folder: Path, files: dict[str, str], names: Iterable[str]) -> None:
    """Write ``names`` of ``files`` under ``folder``, each synced to disk."""
    mode = 0o666 & ~_umask()
    for rel in names:
        path = folder / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(files[rel].encode("utf-8"))
            fh.flush()
            os.fsync(fh.fileno())
    for path in sorted({(folder / rel).parent for rel in names}, key=lambda q: -len(q.parts)):
        fsync_dir(path)


def _listed(out: Path) -> set[str]:
    """The files the former generation's manifest lists (none without a regular one)."""
    manifest = out / MANIFEST
    try:
        if not stat.S_ISREG(os.lstat(manifest).st_mode):
            return set()
        return set(manifest.read_text(encoding="utf-8").splitlines())
    except (OSError, UnicodeDecodeError):
        return set()


def _check_tree(out: Path, files: dict[str, str]) -> None:
    """Refuse, naming it, anything under ``out`` that a write of ``files`` would replace
    and that is not the former generation's own."""
    try:
        st = os.lstat(out)
    except FileNotFoundError:
        return                                     # a new folder: nothing in the way
    except OSError as exc:
        raise CodegenError(f"out: cannot write {out}: {exc.strerror or exc}") from None
    if stat.S_ISLNK(st.st_mode):
        raise CodegenError(f"out: {out} is a symbolic link; give the folder itself")
    if not stat.S_ISDIR(st.st_mode):
        raise CodegenError(f"out: {out} exists and is not a folder")
    listed, seen = _listed(out), {}
    for rel, text in sorted(files.items()):
        parts = Path(rel).parts
        for depth in range(1, len(parts) + 1):
            sub = Path(*parts[:depth])
            if sub in seen:
                continue
            path = out / sub
            try:
                mode = os.lstat(path).st_mode
            except FileNotFoundError:
                seen[sub] = None
                break                              # nothing below it exists either
            except OSError as exc:
                raise CodegenError(f"out: cannot write {path}: {exc.strerror or exc}") from None
            seen[sub] = mode
            last = depth == len(parts)
            if stat.S_ISLNK(mode):
                raise CodegenError(f"out: {path} is a symbolic link; quadland codegen writes "
                                   "no file through one (remove it or choose another folder)")
            if not last and not stat.S_ISDIR(mode):
                raise CodegenError(f"out: {path} is in the way (the generated tree needs a "
                                   "folder there); move it or choose another folder")
            if last and not stat.S_ISREG(mode):
                raise CodegenError(f"out: {path} is in the way (the generated tree writes a "
                                   "file there); move it or choose another folder")
            if last and rel != MANIFEST and rel not in listed \
                    and not _holds(path, text.encode("utf-8")):
                raise CodegenError(f"out: {path} was not written by quadland codegen (the "
                                   f"folder's {MANIFEST} does not list it); move it or "
                                   "choose another folder")
    for folder in [out, *(out / sub for sub, mode in seen.items()
                          if mode is not None and stat.S_ISDIR(mode))]:
        if not os.access(folder, os.W_OK | os.X_OK):
            raise CodegenError(f"out: cannot write {folder}: permission denied")
    if not stat.S_ISREG(seen.get(Path(MANIFEST)) or 0):
        _check_foreign(out, files)


def _check_foreign(out: Path, files: dict[str, str]) -> None:
    """Refuse a folder without a :data:`MANIFEST` that holds anything but the tree's own.

    A folder no generation has written into may be empty, or hold only files
    of the tree with the generated text already (taken over) and the tree's
    folders; anything else there is the user's, and a generated tree is not
    mixed into it.
    """
    folders = {Path(rel).parents[k] for rel in files for k in range(len(Path(rel).parts) - 1)}
    pending = [Path()]
    while pending:
        sub = pending.pop()
        try:
            with os.scandir(out / sub) as entries:
                names = sorted(e.name for e in entries)
        except OSError as exc:
            raise CodegenError(f"out: cannot read {out / sub}: {exc.strerror or exc}") from None
        for name in names:
            rel = sub / name
            if sub == Path() and name.startswith(f"{MANIFEST}.tmp-"):
                continue                           # a generation's staging folder
            if rel in folders and (out / rel).is_dir() and not (out / rel).is_symlink():
                pending.append(rel)
                continue
            if rel.as_posix() in files and _holds(out / rel, files[rel.as_posix()].encode()):
                continue
            raise CodegenError(f"out: {out} holds {rel.as_posix()}, which quadland codegen "
                               f"did not write (there is no {MANIFEST}); choose a new or "
                               "empty folder")


def check_target(out: Path) -> None:
    """Refuse an ``--out`` that a generated tree must not be written into.

    The current folder or one that holds it, the ``quadland`` and
    ``symbolic`` packages (of the install and of the checkout), a folder
    inside them or holding them, and the checkout's root are refused; the
    checkout's ``generated/`` is allowed.

    Raises
    ------
    CodegenError
        ``"out: ..."``, naming the folder.
    """
    target = Path(os.path.abspath(out))
    real = target.resolve()
    cwd = Path.cwd().resolve()
    if real == cwd or real in cwd.parents:
        raise CodegenError(f"out: {out} is the current folder or holds it; give the generated "
                           "tree a folder of its own (e.g. --out generated-c)")
    import quadland
    import quadland_symbolic

    packages = {Path(quadland.__file__).resolve().parent,
                Path(quadland_symbolic.__file__).resolve().parent,
                _package_parent() / "quadland", _package_parent() / "symbolic"}
    root = checkout_root()
    if root is not None and real == root.resolve():
        raise CodegenError(f"out: {out} is the source checkout's root; choose a folder of its "
                           "own (the checkout's code goes to generated/)")
    for package in sorted(packages):
        where = ("is" if real == package else "lies in" if package in real.parents
                 else "holds" if real in package.parents else None)
        if where:
            raise CodegenError(f"out: {out} {where} the package folder {package}; choose a "
                               "folder of its own")


def diff(out: Path, files: dict[str, str]) -> str:
    """Unified diff from the files in ``out`` to ``files`` (empty when equal).

    Stale generated files show as deletions.
    """
    chunks = []
    for rel, text in sorted(files.items()):
        path = out / rel
        old = path.read_text(encoding="utf-8") if path.exists() else ""
        if old != text:
            chunks.extend(difflib.unified_diff(
                old.splitlines(keepends=True), text.splitlines(keepends=True),
                fromfile=f"a/{rel}" if path.exists() else "/dev/null", tofile=f"b/{rel}"))
    for rel in stale(out, files):
        old = (out / rel).read_text(encoding="utf-8")
        chunks.extend(difflib.unified_diff(old.splitlines(keepends=True), [],
                                           fromfile=f"a/{rel}", tofile="/dev/null"))
    return "".join(chunks)


def _command(scenario, overrides, out: Path | None) -> str:
    words = ["quadland", "codegen"]
    if str(scenario) != DEFAULT_SCENARIO:
        words += ["--scenario", str(scenario)]
    words += [w for o in overrides for w in ("--set", o)]
    if out is not None:
        words += ["--out", str(out)]
    return " ".join(words)


def main(out: Path | None = None, check: bool = False, scenario: str | Path = "paper",
         overrides: Iterable[str] = ()) -> int:
    """The ``quadland codegen`` command.

    Parameters
    ----------
    out : Path, optional
        Target folder; by default the checkout's ``generated/``, which holds
        the shipped scenarios' code only (each kind's default scenario).
    check : bool
        Regenerate into a temporary folder and compare instead of writing:
        print a unified diff and return 1 where ``out`` differs.
    scenario : str or Path
        A shipped scenario's name or a TOML file. It sets the defaults of its
        kind's part of the tree (a landing scenario: the landing step and the
        example ``land``; a paper scenario: the paper's step and the example
        ``fly``); the other part keeps its kind's default scenario's.
    overrides : iterable of str
        ``section.key=value`` overrides of the scenario.

    Returns
    -------
    int
        Exit status: 0, or 1 when ``check`` found differences.

    Raises
    ------
    CodegenError
        Without ``out`` outside a source checkout, or for another scenario
        than the shipped two or with overrides; nothing is written then.
    ScenarioError
        For an unknown or invalid scenario.
    """
    overrides = list(overrides)
    given = out
    if out is None:
        out = generated_dir()
        shipped = [k.default_scenario for k in KINDS.values()]
        if str(scenario) not in shipped or overrides:
            raise CodegenError(f"generated/ holds the {' and '.join(shipped)} scenarios' code; "
                               "write another scenario's with --out DIR")
    out = Path(out)
    if out.is_symlink():
        raise CodegenError(f"out: {out} is a symbolic link; give the folder itself")
    if out.exists() and not out.is_dir():
        raise CodegenError(f"out: {out} exists and is not a folder")
    if given is not None:
        check_target(out)
    files = generated_files(load_scenario(scenario, overrides))
    if check:
        with tempfile.TemporaryDirectory() as tmp:
            write(Path(tmp), files)
            fresh = {rel: (Path(tmp) / rel).read_text(encoding="utf-8") for rel in files}
        text = diff(out, fresh)
        if text:
            sys.stdout.write(text)
            print(f"quadland: {out} is out of date; run `{_command(scenario, overrides, given)}`",
                  file=sys.stderr)
            return 1
        print(f"quadland: {out} is up to date ({len(files)} files)")
        return 0
    changed = write(out, files)
    removed = sum(not (out / rel).exists() for rel in changed)
    print(f"quadland: wrote {len(changed) - removed} of {len(files)} files in {out}"
          + (f", removed {removed} stale" if removed else ""))
    return 0

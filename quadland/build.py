"""Compiling generated C into shared libraries, cached on disk.

The runtime never reads the source tree's ``generated/``: it compiles the
text that ``symbolic`` generates for it, into a per-user cache folder
(``$XDG_CACHE_HOME/quadland`` or ``~/.cache/quadland``), under a key made
of the sources, the CasADi version, the compiler (path and ``--version``)
and the flags. A library is built once and reused by every later process;
a build happens in a temporary folder beside its target and is moved into
place whole, so concurrent processes never load a half-written library.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

from quadland.exceptions import CompileError, CompilerNotFoundError

__all__ = ["STRICT_CFLAGS", "RUNTIME_CFLAGS", "SHARED_CFLAGS", "find_compiler", "have_compiler",
           "compiler_version", "cache_dir",
           "build_library"]

#: Flags every generated flight file compiles under, alone.
STRICT_CFLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror")
#: Flags of runtime-only code (the simulators), which need not be warning-free:
#: CasADi's raw output leaves unused parameters.
RUNTIME_CFLAGS = ("-std=c99", "-w")
#: Flags of a shared library. ``-fPIC`` alone lets every call between the
#: library's own functions go through the PLT (interposition), which costs
#: 1.8x on the closed loop's right-hand side here; the second flag removes it.
SHARED_CFLAGS = ("-fPIC", "-fno-semantic-interposition", "-shared")


def find_compiler() -> str:
    """Path of the C compiler: ``$CC``, else ``cc``, ``gcc`` or ``clang``.

    Raises
    ------
    CompilerNotFoundError
        When none is found.
    """
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        path = shutil.which(name) if name else None
        if path:
            return path
    raise CompilerNotFoundError(
        "no C compiler found (set CC or install cc, gcc or clang)")


def have_compiler() -> bool:
    """Whether :func:`find_compiler` finds one."""
    try:
        find_compiler()
    except CompilerNotFoundError:
        return False
    return True


@functools.lru_cache(maxsize=4)
def _compiler_identity(cc: str) -> str:
    try:
        proc = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError) as exc:
        raise CompilerNotFoundError(f"{cc}: cannot run the C compiler: {exc}") from None
    return f"{cc}\n{proc.stdout}"


def compiler_version() -> str | None:
    """First line of the C compiler's ``--version``, or None without one."""
    try:
        cc = find_compiler()
        return _compiler_identity(cc).splitlines()[1].strip() or Path(cc).name
    except (CompilerNotFoundError, IndexError):
        return None


def cache_dir() -> Path:
    """Folder of the compiled libraries.

    ``$XDG_CACHE_HOME/quadland`` (``~/.cache/quadland``); where that cannot
    be made (a read-only home, as in some CI and containers), a folder of the
    user's own in the system's temporary folder, after one warning.
    """
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    preferred = Path(root) / "quadland"
    try:
        preferred.mkdir(parents=True, exist_ok=True)
        if os.access(preferred, os.W_OK | os.X_OK):
            return preferred
    except OSError:
        pass
    fallback = Path(tempfile.gettempdir()) / f"quadland-cache-{os.getuid()}"
    _warn_cache(str(preferred), str(fallback))
    return fallback


@functools.cache
def _warn_cache(preferred: str, fallback: str) -> None:
    import warnings

    warnings.warn(f"cannot write the build cache {preferred}; using {fallback}",
                  RuntimeWarning, stacklevel=4)


def build_library(files: dict[str, str], compile_: tuple[str, ...], opt: str = "-O2",
                  name: str = "libquadland", strict: bool = True) -> Path:
    """Compile ``compile_`` (names in ``files``) into a cached shared library.

    Each translation unit compiles in its own process, as many at a time as
    there are cores, then they are linked.

    Parameters
    ----------
    files : dict of str to str
        Every source and header by file name.
    compile_ : tuple of str
        The ``.c`` files to compile and link.
    opt : str
        Optimization flag.
    name : str
        Stem of the library's file name.
    strict : bool
        Compile with :data:`STRICT_CFLAGS` (flight code) rather than
        :data:`RUNTIME_CFLAGS`.

    Returns
    -------
    Path
        The library; rebuilt only when sources, CasADi, compiler or flags change.

    Raises
    ------
    CompilerNotFoundError
        When no C compiler is found.
    CompileError
        When the compiler rejects the sources.
    """
    cc = find_compiler()
    cflags = (*(STRICT_CFLAGS if strict else RUNTIME_CFLAGS), opt, *SHARED_CFLAGS[:-1])
    digest = hashlib.sha256()
    for part in (_compiler_identity(cc), ca.__version__, *cflags, *compile_):
        digest.update(part.encode() + b"\0")
    for fname, text in sorted(files.items()):
        digest.update(fname.encode() + b"\0" + text.encode() + b"\0")
    target = cache_dir() / digest.hexdigest()[:24] / f"{name}.so"
    if target.exists():
        return target
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CompileError(f"{target.parent}: cannot create the build cache: "
                           f"{exc.strerror or exc}") from None
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".build-") as tmp:
        for fname, text in files.items():
            Path(tmp, fname).write_text(text)
        objects = [str(Path(c).with_suffix(".o")) for c in compile_]
        _run_parallel([[cc, *cflags, "-c", c, "-o", o]
                       for c, o in zip(compile_, objects, strict=True)], tmp, cc)
        out = Path(tmp, f"{name}.so")
        _run_parallel([[cc, SHARED_CFLAGS[-1], "-o", str(out), *objects, "-lm"]], tmp, cc)
        os.replace(out, target)
    return target


def _run_parallel(commands: list[list[str]], cwd: str, cc: str) -> None:
    """Run compiler commands, at most one per core at a time; raise on the first failure."""
    pending, running = list(commands), []
    jobs = max(1, os.cpu_count() or 1)
    try:
        while pending or running:
            while pending and len(running) < jobs:
                cmd = pending.pop(0)
                running.append(subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.DEVNULL,
                                                stderr=subprocess.PIPE, text=True))
            proc = running.pop(0)
            _, err = proc.communicate()
            if proc.returncode != 0:
                first = next((ln for ln in err.splitlines() if "error" in ln),
                             err.strip().splitlines()[0] if err.strip() else "")
                raise CompileError(f"{Path(cc).name} failed on the generated C: "
                                   f"{first or f'exit status {proc.returncode}'}")
    finally:
        for proc in running:
            proc.kill()
            proc.wait()

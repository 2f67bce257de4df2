"""Compiling generated C into shared libraries, cached on disk.

The runtime never reads the source tree's ``generated/``: it compiles the
text that ``symbolic`` generates for it, into a per-user cache folder
(``$XDG_CACHE_HOME/quadland`` or ``~/.cache/quadland``; :func:`cache_dir`), under
a key made of the sources, the CasADi version, the compiler (path and
``--version``) and the flags. A library is built once and reused by every
later process; a build happens in a temporary folder beside its target and
is moved into place whole, so concurrent processes never load a
half-written library.

What can go wrong is bounded or caught before a library is loaded:

* **Cost.** Generated C grows with the RBF network (``rbf.nodes``), and an
  optimizing compiler's memory and time grow about as the square of a
  function's size (CasADi writes one C function per symbolic function):
  the landing controller at ``l = 1000`` took 12.9 GB in ``cc1`` at -O2.
  :func:`plan_build` estimates each unit's cost (:data:`COMPILE_FIT`) and
  compiles a unit over :data:`COMPILE_MEMORY_BUDGET` or
  :data:`COMPILE_TIME_BUDGET` at -O0 (one warning); the compilers run
  together only within the memory budget.
* **Corruption.** Each library's SHA-256 is recorded beside it at its
  build; a library whose bytes differ (truncated, empty, damaged) or that
  does not load is rebuilt once, and a compiler that writes no output, or a
  disk that fills, is a :class:`~quadland.exceptions.CompileError`.
* **Other users.** Libraries are only built into and loaded from folders of
  the user's own that others cannot write; the fallback in the system's
  temporary folder is checked, not trusted (:func:`cache_dir`).
* **Killed builds.** A build folder is held with ``flock`` while it is in
  use; one left by a killed process is removed by a later build.
* **Hung compilers.** Each compiler process (``--version`` too) runs in a
  process group of its own, killed whole after
  :func:`~quadland.engine.compiler.compile_timeout` seconds: a
  :class:`~quadland.exceptions.CompileError`, so the simulators fall back
  to CasADi's virtual machine with one warning (:mod:`quadland.engine.compiler`).
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import hashlib
import os
import shutil
import stat
import tempfile
from pathlib import Path

import casadi as ca

from quadland.engine.compiler import (
    COMPILE_TIMEOUT,
    TIMEOUT_ENV,
    VERSION_TIMEOUT,
    compile_timeout,
    compiler_identity,
    compiler_problem,
    compiler_version,
    find_compiler,
    have_compiler,
    run_compilers,
)
from quadland.engine.machine import machine_flags, machine_rejected
from quadland.exceptions import CompileError
from quadland.output import WorkFolder, remove_abandoned, write_text_atomic

__all__ = ["STRICT_CFLAGS", "RUNTIME_CFLAGS", "SHARED_CFLAGS", "COMPILE_MEMORY_BUDGET",
           "COMPILE_TIME_BUDGET", "OPT_LEVELS", "LEVEL_FLAGS", "level_flags", "COMPILE_FIT",
           "STALE_BUILD_AGE",
           "CompileBudgetError", "compile_cost", "BuildPlan", "plan_build", "find_compiler",
           "have_compiler", "compiler_problem", "compiler_version", "cache_dir",
           "build_library", "COMPILE_TIMEOUT", "VERSION_TIMEOUT", "TIMEOUT_ENV",
           "compile_timeout", "compiler_identity", "verified_library", "language_flags"]

#: Flags every generated flight file compiles under, alone.
STRICT_CFLAGS = ("-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror")
#: Flags of runtime-only code (the simulators), which need not be warning-free:
#: CasADi's raw output leaves unused parameters.
RUNTIME_CFLAGS = ("-std=c99", "-w")
#: Flags of a shared library. ``-fPIC`` alone lets every call between the
#: library's own functions go through the PLT (interposition), which costs
#: 1.8x on the closed loop's right-hand side here; the second flag removes it.
SHARED_CFLAGS = ("-fPIC", "-fno-semantic-interposition", "-shared")


#: Most memory one build may take, bytes: the compiler processes running at once
#: together, by :func:`compile_cost`'s estimate (the run's own arrays have their
#: own 2 GiB, ``quadland.engine.plan.MEMORY_BUDGET``).
COMPILE_MEMORY_BUDGET = 2 * 2**30
#: Longest one translation unit may take to compile, s, by the estimate.
COMPILE_TIME_BUDGET = 120.0
#: Optimization levels tried, best first: a unit compiles at the first whose
#: estimated cost is within both budgets. -Os has no fit of its own and is costed
#: as -O2 (it took 60 % of -O2's CPU time on the paper's simulator), so a unit over
#: the budget at -O2 still goes to -O0.
OPT_LEVELS = ("-O2", "-Os", "-O0")
#: The flags a level compiles with, where they are more than the level itself. At -Os
#: the passes that merge computations partly redundant across branches (GCSE, tree
#: PRE, code hoisting) and the second scheduling pass find next to nothing to do in
#: CasADi's straight-line C and cost a quarter of its compile time (the paper's
#: right-hand side, 198 KB of C: 1.12 against 1.46 s of CPU). None of them changes
#: a floating-point operation; the simulator flies the same states, bit for bit.
LEVEL_FLAGS = {"-Os": ("-Os", "-fno-gcse", "-fno-tree-pre", "-fno-code-hoisting",
                       "-fno-schedule-insns2")}


def language_flags(strict: bool, cc: str) -> tuple[str, ...]:
    """The flags of a library's language: :data:`STRICT_CFLAGS` (flight code), or
    :data:`RUNTIME_CFLAGS` and the machine's own instructions
    (:func:`quadland.engine.machine.machine_flags`, the same bits)."""
    return STRICT_CFLAGS if strict else (*RUNTIME_CFLAGS, *machine_flags(cc))


def level_flags(level: str, cc: str) -> tuple[str, ...]:
    """The flags ``level`` compiles with on compiler ``cc``: :data:`LEVEL_FLAGS`'s on GCC
    (the passes they turn off are GCC's; clang rejects ``-fno-code-hoisting``), the level
    alone on any other compiler."""
    identity = compiler_identity(cc)
    gcc = "Free Software Foundation" in identity and "clang" not in identity.lower()
    return LEVEL_FLAGS.get(level, (level,)) if gcc else (level,)

#: Fit of gcc 12's peak memory (bytes) and time (s) to compile one generated
#: translation unit of ``S`` MB of C: ``a * S**b`` per optimization level.
#: Fitted to gcc 12 on CasADi's output for the landing controller (l = 200 to
#: 1000) and the paper's right-hand side (l = 300 and 1000), one ``cc1`` at a
#: time on a loaded 2-core x86-64 (the table is ``MEASURED`` in
#: tests/test_build.py). At -O2: 0.49 MB of C 649 MiB and 26 s, 0.69 MB 1150 MiB
#: and 51 s, 1.1 MB 3.5 GiB and 163 s; at -O0 2.1 MB 1.7 GiB and 23 s.
COMPILE_FIT = {"-O2": ((2574 * 2**20, 2.26), (120.0, 2.36)),
               "-O0": ((518 * 2**20, 1.56), (6.5, 1.19))}
#: Version of the cache's layout (a library and its ``.sha256``), in every key:
#: a quadland that writes libraries without checksums never shares a folder.
_CACHE_FORMAT = "checksummed-1"
#: Age, s, after which a build folder that no live process holds is removed.
STALE_BUILD_AGE = 900.0


class CompileBudgetError(CompileError):
    """Compiling the generated C would take more memory or time than allowed."""


def compile_cost(size: int, opt: str = "-O2") -> tuple[float, float]:
    """Estimated peak memory (bytes) and time (s) to compile ``size`` bytes of C.

    From :data:`COMPILE_FIT`; a level without a fit is costed as -O2. Within
    -20 % to +45 % of the measured values from 0.45 to 2.1 MB.

    Examples
    --------
    >>> mem, t = compile_cost(2_124_805)        # the landing controller, l = 1000
    >>> round(mem / 2**30), round(t)
    (14, 711)
    """
    (m, bm), (t, bt) = COMPILE_FIT.get(opt, COMPILE_FIT["-O2"])
    mb = size / 1e6
    return m * mb ** bm, t * mb ** bt


@dataclasses.dataclass(frozen=True)
class BuildPlan:
    """How each translation unit of a build is compiled, and what it is estimated to cost.

    Attributes
    ----------
    opts : tuple of (str, str)
        Each ``.c`` file and its optimization level.
    memory : dict of str to float
        Each file's estimated peak memory, bytes.
    lowered : tuple of str
        The files compiled below the level asked for (over the budget there).
    """

    opts: tuple[tuple[str, str], ...]
    memory: dict
    lowered: tuple[str, ...]


def plan_build(files: dict[str, str], compile_: tuple[str, ...], opt: str = "-O2") -> BuildPlan:
    """Each unit's optimization level: ``opt``, or a cheaper one where ``opt`` is over budget.

    Raises
    ------
    CompileBudgetError
        When a unit is over :data:`COMPILE_MEMORY_BUDGET` or
        :data:`COMPILE_TIME_BUDGET` even at the cheapest level; the message
        names ``rbf.nodes``, which the generated C grows with.
    """
    levels = (opt, *(o for o in OPT_LEVELS if o != opt and opt in OPT_LEVELS
                     and OPT_LEVELS.index(o) > OPT_LEVELS.index(opt)))
    opts, memory, lowered = [], {}, []
    for name in compile_:
        size = len(files[name].encode("utf-8"))
        for level in levels:
            mem, secs = compile_cost(size, level)
            if mem <= COMPILE_MEMORY_BUDGET and secs <= COMPILE_TIME_BUDGET:
                break
        else:
            mem, secs = compile_cost(size, levels[-1])
            raise CompileBudgetError(
                f"rbf.nodes: the generated {name} ({size / 1e6:.1f} MB of C) would need about "
                f"{_gib(mem)} and {secs:.0f} s to compile even at {levels[-1]}, over the "
                f"budget of {_gib(COMPILE_MEMORY_BUDGET)} and {COMPILE_TIME_BUDGET:g} s; "
                "lower rbf.nodes")
        opts.append((name, level))
        memory[name] = mem
        if level != opt:
            lowered.append(name)
    return BuildPlan(tuple(opts), memory, tuple(lowered))


def _gib(n: float) -> str:
    return f"{n / 2**30:.1f} GiB"


def cache_dir() -> Path:
    """Folder of the compiled libraries: one of the user's own that others cannot write.

    ``$XDG_CACHE_HOME/quadland`` (``~/.cache/quadland``). Where that cannot
    be made or is not safe (see below; a read-only home, as in some CI and
    containers), ``quadland-cache-<uid>`` in the system's temporary folder,
    after one warning; where that one is not safe either (another user made
    it, it is a symbolic link, others can write it), a new private folder
    for this process only (``mkdtemp``), removed at exit.

    A folder is safe when it is a real folder (not a link), owned by the
    user, not writable by group or others (a looser one of the user's own is
    set to 0700), and no folder above it is writable by others without the
    sticky bit: no one else can put a library where quadland loads one.
    """
    root = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    preferred = Path(root) / "quadland"
    why = _make_private(preferred)
    if why is None:
        return preferred
    fallback = Path(tempfile.gettempdir()) / f"quadland-cache-{os.getuid()}"
    why_not = _make_private(fallback, parents=False)
    if why_not is None:
        _warn_cache(f"cannot use the build cache {preferred} ({why}); using {fallback}")
        return fallback
    private = _private_cache()
    _warn_cache(f"cannot use the build cache {preferred} ({why}) nor {fallback} ({why_not}); "
                f"using {private} for this run")
    return private


def _make_private(path: Path, parents: bool = True) -> str | None:
    """Make ``path`` a folder only the user can write; None, or why it cannot be used."""
    try:
        if parents:
            path.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            pass
        return _unsafe(path)
    except OSError as exc:
        return exc.strerror or str(exc)


def _unsafe(path: Path) -> str | None:
    """Why a folder may not hold libraries to load (None: it may); a loose own mode is fixed."""
    st = os.lstat(path)
    if stat.S_ISLNK(st.st_mode):
        return "it is a symbolic link"
    if not stat.S_ISDIR(st.st_mode):
        return "it is not a folder"
    if st.st_uid != os.geteuid():
        return f"it belongs to user {st.st_uid}, not to {os.geteuid()}"
    if st.st_mode & 0o022:
        os.chmod(path, stat.S_IMODE(st.st_mode) & ~0o077)
    if not os.access(path, os.W_OK | os.X_OK):
        return "it is not writable"
    for above in path.resolve().parents:
        mode = os.stat(above).st_mode
        if mode & stat.S_IWOTH and not mode & stat.S_ISVTX:
            return f"{above} above it is writable by others"
    return None


@functools.cache
def _private_cache() -> Path:
    import atexit

    path = Path(tempfile.mkdtemp(prefix=f"quadland-cache-{os.getuid()}-"))
    atexit.register(shutil.rmtree, path, ignore_errors=True)
    return path


@functools.cache
def _warn_cache(message: str) -> None:
    import warnings

    warnings.warn(message, RuntimeWarning, stacklevel=4)


@functools.cache
def _warn_lowered(names: tuple[str, ...], detail: str) -> None:
    import warnings

    warnings.warn(f"rbf.nodes: {detail}; built at -O0 instead, so the run is slower (a smaller "
                  "rbf.nodes compiles optimized)", RuntimeWarning, stacklevel=4)


def build_library(files: dict[str, str], compile_: tuple[str, ...], opt: str = "-O2",
                  name: str = "libquadland", strict: bool = True) -> Path:
    """Compile ``compile_`` (names in ``files``) into a cached shared library.

    Each translation unit compiles in its own process, as many at a time as
    there are cores and :data:`COMPILE_MEMORY_BUDGET` allow, then they are
    linked. A unit whose compilation at ``opt`` is estimated over the budgets
    (:func:`plan_build`) compiles at -O0, after one warning. The library is
    checked before it is returned: its SHA-256 against the one recorded at its
    build (a corrupt or truncated file is rebuilt once), and it must load; it
    lies in a folder of the user's own that others cannot write (:func:`cache_dir`).

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
        When the compiler rejects the sources or produces no loadable library,
        when the cache cannot be written (a full disk), or
        (:class:`CompileBudgetError`) when a unit is over the budgets even at -O0.
    """
    timeout = compile_timeout()
    cc = find_compiler()
    plan = plan_build(files, compile_, opt)
    lang = language_flags(strict, cc)
    digest = hashlib.sha256()
    for part in (_CACHE_FORMAT, compiler_identity(cc), ca.__version__, *lang,
                 *level_flags(opt, cc), *SHARED_CFLAGS[:-1], *compile_):
        digest.update(part.encode() + b"\0")
    if plan.lowered:                         # the key of a build without them is unchanged
        for c, level in plan.opts:
            digest.update(f"{c}={' '.join(level_flags(level, cc))}".encode()
                          + b"\0")
    for fname, text in sorted(files.items()):
        digest.update(fname.encode() + b"\0" + text.encode() + b"\0")
    if plan.lowered:
        detail = ", ".join(
            f"{c} ({len(files[c].encode()) / 1e6:.1f} MB of C) would need about "
            f"{_gib(compile_cost(len(files[c].encode()), opt)[0])} and "
            f"{compile_cost(len(files[c].encode()), opt)[1]:.0f} s at {opt}"
            for c in plan.lowered)
        _warn_lowered(plan.lowered, f"{detail}, over the budget of "
                      f"{_gib(COMPILE_MEMORY_BUDGET)} and {COMPILE_TIME_BUDGET:g} s")
    cache = cache_dir()
    target = cache / digest.hexdigest()[:24] / f"{name}.so"
    for attempt in range(2):
        if not verified_library(target):
            _build_or_baseline(cc, lang, plan, files, compile_, target, cache, timeout)
        try:
            ctypes.CDLL(str(target))
            return target
        except OSError as exc:
            _discard(target)
            if attempt:
                first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise CompileError(f"{Path(cc).name} built a library that does not load: "
                                   f"{first}") from None
    raise AssertionError("unreachable")


def _checksum(path: Path) -> Path:
    return path.with_name(path.name + ".sha256")


def _sha256(path: Path) -> str:
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


def verified_library(target: Path) -> bool:
    """Whether ``target`` is a library of the user's own, in a safe folder, whose content
    is what its build recorded; a corrupt or unchecked one is removed."""
    try:
        why = _unsafe(target.parent)
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise CompileError(f"{target.parent}: cannot use the build cache: "
                           f"{exc.strerror or exc}") from None
    if why is not None:
        raise CompileError(f"{target.parent}: will not load a library from it: {why}")
    try:
        st = os.lstat(target)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid() or st.st_mode & 0o022:
            _discard(target)
            return False
        recorded = _checksum(target).read_text(encoding="ascii").strip()
        if recorded == _sha256(target):
            return True
    except (OSError, ValueError):
        pass
    _discard(target)
    return False


def _discard(target: Path) -> None:
    for path in (target, _checksum(target)):
        try:
            path.unlink(missing_ok=True)
        except OSError:
            pass


def _build_or_baseline(cc: str, lang: tuple[str, ...], *args) -> None:
    """:func:`_build`; again without the machine's flags where the compiler refused them
    (a compiler for another target: :func:`quadland.engine.machine.machine_rejected`)."""
    try:
        _build(cc, lang, *args)
    except CompileError as exc:
        n = len(RUNTIME_CFLAGS)
        extra = lang[n:] if lang[:n] == RUNTIME_CFLAGS else ()
        if not machine_rejected(str(exc), extra):
            raise
        _build(cc, RUNTIME_CFLAGS, *args)


def _build(cc: str, lang: tuple[str, ...], plan: BuildPlan, files: dict[str, str],
           compile_: tuple[str, ...], target: Path, cache: Path, timeout: float) -> None:
    """Compile and link into ``target`` (with its checksum), through a held work folder."""
    try:
        try:
            os.mkdir(target.parent, 0o700)
        except FileExistsError:
            pass
        why = _unsafe(target.parent)
        if why is not None:
            raise CompileError(f"{target.parent}: will not build a library into it: {why}")
        _clean_cache(cache)
        with WorkFolder(target.parent, ".build-") as work:
            tmp = str(work.path)
            for fname, text in files.items():
                Path(tmp, fname).write_text(text)
            objects = [str(Path(c).with_suffix(".o")) for c in compile_]
            opts = dict(plan.opts)
            run_compilers([[cc, *lang, *level_flags(opts[c], cc), *SHARED_CFLAGS[:-1],
                            "-c", c, "-o", o]
                           for c, o in zip(compile_, objects, strict=True)], tmp, cc,
                          [plan.memory[c] for c in compile_], objects, timeout,
                          COMPILE_MEMORY_BUDGET)
            out = Path(tmp, target.name)
            run_compilers([[cc, SHARED_CFLAGS[-1], "-o", str(out), *objects, "-lm"]], tmp, cc,
                          [0.0], [out.name], timeout, COMPILE_MEMORY_BUDGET)
            os.chmod(out, 0o755)                     # others may not write it, whatever the umask
            digest = _sha256(out)
            os.replace(out, target)
            write_text_atomic(_checksum(target), digest + "\n")
    except OSError as exc:
        raise CompileError(f"{target.parent}: cannot build in the cache: "
                           f"{exc.strerror or exc}") from None


@functools.cache
def _clean_cache(cache: Path) -> None:
    """Remove, once per process, the build folders that killed builds left in the cache."""
    for key in cache.iterdir():
        if key.is_dir() and not key.is_symlink():
            remove_abandoned(key, ".build-*", STALE_BUILD_AGE)

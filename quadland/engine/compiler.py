"""The C compiler: found, identified and run, each process bounded in time.

:func:`find_compiler` takes ``$CC`` (a ``$CC`` that names no program is an
error, not a cue to use another compiler), else ``cc``, ``gcc`` or
``clang``. Every compiler process, ``--version`` included, runs in a process
group of its own and is killed with its whole group (``cc1``, ``as``, a
wrapper's children) once it runs over its time: :func:`compile_timeout`
(``$QUADLAND_COMPILE_TIMEOUT``, else :data:`COMPILE_TIMEOUT`), and at most
:data:`VERSION_TIMEOUT` for ``--version``. A compiler that hangs is a
:class:`~quadland.exceptions.CompileError`; :mod:`quadland.engine.build`
turns the sources into a cached library with it.
"""

from __future__ import annotations

import functools
import math
import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

from quadland.exceptions import CompileError, CompilerNotFoundError, SettingError

__all__ = ["find_compiler", "have_compiler", "compiler_problem", "compiler_identity",
           "compiler_version", "compile_timeout", "run_compilers", "COMPILE_TIMEOUT",
           "VERSION_TIMEOUT", "TIMEOUT_ENV"]

#: Longest a compiler process may run before its process group is killed, s: four
#: times ``quadland.engine.build.COMPILE_TIME_BUDGET`` (the estimate is within +45 %,
#: and a loaded machine is slower).
COMPILE_TIMEOUT = 480.0


def find_compiler() -> str:
    """Path of the C compiler: ``$CC``, else ``cc``, ``gcc`` or ``clang``.

    Raises
    ------
    CompilerNotFoundError
        When none is found, or ``$CC`` names no program (it is not replaced
        by another compiler unasked).
    """
    given = os.environ.get("CC")
    if given:
        path = shutil.which(given)
        if path:
            return path
        raise CompilerNotFoundError(f"CC={' '.join(given.split())[:80]!r} is not a program "
                                    "(unset CC to use cc, gcc or clang)")
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return path
    raise CompilerNotFoundError(
        "no C compiler found (set CC or install cc, gcc or clang)")


def have_compiler() -> bool:
    """Whether :func:`find_compiler` finds one."""
    return compiler_problem() is None


def compiler_problem() -> str | None:
    """Why :func:`find_compiler` finds no compiler, or None when it finds one."""
    try:
        find_compiler()
    except CompilerNotFoundError as exc:
        return str(exc)
    return None


#: Variable of the environment that sets :func:`compile_timeout`, s.
TIMEOUT_ENV = "QUADLAND_COMPILE_TIMEOUT"
#: Longest ``CC --version`` may take, s (or the compile timeout, if shorter).
VERSION_TIMEOUT = 10.0


def compile_timeout() -> float:
    """Longest one compiler process may run, s: ``$QUADLAND_COMPILE_TIMEOUT`` or
    :data:`COMPILE_TIMEOUT`.

    Raises
    ------
    SettingError
        ``QUADLAND_COMPILE_TIMEOUT: ...`` when it is not a number of seconds > 0.
    """
    text = os.environ.get(TIMEOUT_ENV, "")
    if not text.strip():
        return COMPILE_TIMEOUT
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        shown = " ".join(text.split())[:40]
        raise SettingError(f"{TIMEOUT_ENV}: must be a number of seconds > 0, got {shown!r}")
    return value


def _start(cmd: list[str], cwd: str | None = None) -> subprocess.Popen:
    """A compiler process, in a process group of its own (killed whole on a timeout)."""
    return subprocess.Popen(cmd, cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, errors="replace",
                            process_group=0)


def _kill(proc: subprocess.Popen) -> None:
    """Kill a process started by :func:`_start` and every process of its group."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        proc.kill()
    proc.communicate()


@functools.lru_cache(maxsize=4)
def _probe(cc: str, timeout: float) -> tuple[str | None, str | None]:
    """``(identity, None)`` of a compiler (its path and ``--version``), or ``(None, why)``."""
    try:
        proc = _start([cc, "--version"])
    except OSError as exc:
        return None, f"{cc}: cannot run the C compiler: {exc.strerror or exc}"
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        _kill(proc)
        return None, (f"{cc} --version did not answer within {timeout:g} s (is it a C "
                      "compiler?)")
    except BaseException:
        _kill(proc)
        raise
    return f"{cc}\n{out}", None


def compiler_identity(cc: str) -> str:
    """The compiler's path and ``--version``, for the cache key.

    Raises
    ------
    CompileError
        When ``--version`` cannot run or does not answer in time.
    """
    identity, why = _probe(cc, min(VERSION_TIMEOUT, compile_timeout()))
    if why is not None:
        raise CompileError(why)
    return identity


def compiler_version() -> str | None:
    """First line of the C compiler's ``--version``, or None without one (or an answer)."""
    try:
        cc = find_compiler()
        return compiler_identity(cc).splitlines()[1].strip() or Path(cc).name
    except (CompilerNotFoundError, CompileError, IndexError):
        return None


def run_compilers(commands: list[list[str]], cwd: str, cc: str, memory: list[float],
                  outputs: list[str], timeout: float, budget: float) -> None:
    """Run compiler commands, at most one per core and ``budget`` bytes of estimated
    ``memory`` at a time; raise :class:`CompileError` on the first failure, a command
    that did not write its output, or one that ran over ``timeout`` seconds (its
    process group is killed)."""
    pending = list(zip(commands, memory, outputs, strict=True))
    running: list[tuple[subprocess.Popen, float, str, float]] = []
    jobs = max(1, os.cpu_count() or 1)
    try:
        while pending or running:
            while pending and len(running) < jobs and (
                    not running or sum(r[1] for r in running) + pending[0][1]
                    <= budget):
                cmd, mem, output = pending.pop(0)
                running.append((_start(cmd, cwd), mem, output, time.monotonic() + timeout))
            proc, _, output, deadline = running.pop(0)
            try:
                _, err = proc.communicate(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                _kill(proc)
                raise CompileError(f"{Path(cc).name} ran over {timeout:g} s making {output} "
                                   f"and was stopped ({TIMEOUT_ENV} sets the "
                                   "limit)") from None
            if proc.returncode != 0:
                first = next((ln for ln in err.splitlines() if "error" in ln),
                             err.strip().splitlines()[0] if err.strip() else "")
                raise CompileError(f"{Path(cc).name} failed on the generated C: "
                                   f"{first or f'exit status {proc.returncode}'}")
            if not Path(cwd, output).is_file() or Path(cwd, output).stat().st_size == 0:
                raise CompileError(f"{cc} wrote no {Path(output).suffix or output} file "
                                   "(is it a C compiler?)")
    finally:
        for proc, _, _, _ in running:
            _kill(proc)

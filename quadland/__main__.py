"""``python -m quadland`` and the ``quadland`` console script: the command line.

Ctrl-C must give one line ``quadland: interrupted`` and exit status 130 from
the first instant, also while the command's modules import (NumPy, CasADi,
matplotlib: most of a second): :func:`main` installs its SIGINT handler
before it imports anything of quadland's beyond this module, and the
package itself imports nothing on import (``quadland/__init__.py``). Once
the command's modules are loaded, Python's own handler is back and
:func:`quadland.cli.main` handles ``KeyboardInterrupt`` (a campaign keeps
its recorded runs).

Before NumPy loads, :func:`main` also asks BLAS for one thread (unless the
environment already says how many): quadland's matrices have at most a few
hundred rows, where OpenBLAS's thread pool costs more than it brings. Each
OpenBLAS library (NumPy and SciPy load one each) starts its pool on import,
and its threads spin on the second core after every call; a process pool's
workers inherit the setting. ``threadpoolctl`` limits only the libraries
already loaded, which SciPy's is not until ``scipy.linalg`` is imported.

The process itself (the console script, ``python -m quadland``) runs :func:`run`:
matplotlib's figure module, if a command draws, imported without the artists' ``set``
docstrings (:mod:`quadland.mpl_import`), :func:`main`, then, once the command is done,
its heap left to the operating system (:func:`leave_heap`) rather than collected object
by object at exit. A reader that closes the pipe early (``| head -1``) ends the command
quietly with status 141, as SIGPIPE ends a Unix tool.
"""

import gc
import os
import signal
import sys

#: Exit status of an interrupted command (128 + SIGINT).
INTERRUPTED = 130
#: Exit status when the reader of the standard output went away (128 + SIGPIPE).
BROKEN_PIPE = 141
#: The BLAS libraries' thread counts set to one unless given (OpenBLAS, MKL, OpenMP builds).
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS")


def _interrupted(signum, frame) -> None:
    os.write(2, b"quadland: interrupted\n")
    os._exit(INTERRUPTED)


def main(argv: list[str] | None = None, process: bool = False) -> int:
    """The command line: run the command of ``argv`` (``sys.argv[1:]`` if None) and return
    its exit status; ``process``: this is the command line's own process (:func:`run`), whose
    matplotlib is imported without the artists' ``set`` docstrings
    (:func:`quadland.mpl_import.for_the_command_line`)."""
    previous = signal.getsignal(signal.SIGINT)
    if previous is signal.default_int_handler:              # not where SIGINT is ignored
        signal.signal(signal.SIGINT, _interrupted)          # before any heavy import
    for name in BLAS_THREADS:                               # before NumPy is imported
        os.environ.setdefault(name, "1")
    if process:
        from quadland.mpl_import import for_the_command_line

        for_the_command_line()
    try:
        from quadland.cli import main as cli_main

        if previous is signal.default_int_handler:
            signal.signal(signal.SIGINT, previous)
        return cli_main(argv)
    except KeyboardInterrupt:                               # between the two
        print("quadland: interrupted", file=sys.stderr)
        return INTERRUPTED
    except ImportError as exc:
        # an extension module whose initialization a Ctrl-C cut short raises
        # ImportError from the KeyboardInterrupt
        if not isinstance(exc.__cause__ or exc.__context__, KeyboardInterrupt):
            raise
        print("quadland: interrupted", file=sys.stderr)
        return INTERRUPTED


def leave_heap() -> None:
    """Keep the objects alive now out of the collections at the interpreter's exit.

    At exit Python runs a last full collection, which walks every object alive
    (CasADi's functions, the review, and after a command with figures the hundreds of
    thousands of objects of its matplotlib figures, unreachable cycles until then)
    and frees the unreachable ones one by one: 0.4 s of CPU after ``quadland margins
    --scenario highway`` with its figures, 0.17 s without (a loaded machine). The
    process is ending and the operating system takes its memory back whole, so every
    object the collector tracks at this point (garbage cycles included) moves to the
    permanent generation (``gc.freeze``), which no collection walks. The exit handlers
    (``atexit``, ``weakref.finalize``) still run; the commands write through raw
    descriptors or files closed before they return, so no buffer is left unflushed.
    """
    gc.freeze()


def run() -> None:
    """The process's entry (console script and ``python -m quadland``): marked as the
    command line's (:func:`quadland.mpl_import.for_the_command_line`), :func:`main`, then
    :func:`leave_heap`, and exit with the command's status."""
    try:
        status = main(process=True)
        sys.stdout.flush()
    except BrokenPipeError:
        # the reader stopped reading (``quadland ... | head -1``): end quietly, as a Unix
        # tool killed by SIGPIPE would, the rest of the output sent nowhere
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        status = BROKEN_PIPE
    leave_heap()
    sys.exit(status)


if __name__ == "__main__":
    run()

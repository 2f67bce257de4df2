"""A Ctrl-C that no library can swallow.

Python raises ``KeyboardInterrupt`` in whatever Python code runs when SIGINT
arrives. Code that catches every exception there discards it, and the
command runs on to its end: CasADi's SWIG wrappers do (an overload's type
check that calls back into Python clears any error), and so does
``hasattr`` in C on Python 3.11. A campaign interrupted while it built its
symbolic loop flew all its runs and exited 0.

While a command runs under :func:`catching`, its SIGINT handler notes the
interrupt before it raises, and :func:`check` raises again one that was
noted but never reached the command. The command calls :func:`check` where
a lost interrupt would cost the most: after a symbolic build, between a
campaign's batches, and before it reports success.
"""

from __future__ import annotations

import contextlib
import re
import signal
import sys
import threading
from collections.abc import Iterator

_noted = False


def _note_and_raise(signum, frame) -> None:
    global _noted
    _noted = True
    raise KeyboardInterrupt


@contextlib.contextmanager
def catching() -> Iterator[None]:
    """Note every SIGINT while the block runs (in the main thread, where Python's
    own handler is installed; elsewhere nothing changes)."""
    global _noted
    own = (threading.current_thread() is threading.main_thread()
           and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    _noted = False
    if own:
        signal.signal(signal.SIGINT, _note_and_raise)
    try:
        yield
    finally:
        if own:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        _noted = False


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a SIGINT was noted since the last call.

    Call it where the interrupt, if it had been raised and handled, would
    have ended the work; an interrupt that did reach the command is noted
    too, so call it only on the way that did not see one.
    """
    global _noted
    if _noted:
        _noted = False
        raise KeyboardInterrupt


def wrapped_by_ctypes(exc: BaseException) -> bool:
    """Whether ``exc`` is a Ctrl-C that arrived while ctypes converted a call's
    arguments (NumPy's ``ndpointer`` checks them in Python): ctypes raises
    ``ArgumentError("argument 6: KeyboardInterrupt: ")`` instead, with neither
    cause nor context, its text all that is left of the interrupt."""
    ctypes = sys.modules.get("ctypes")
    return (ctypes is not None and isinstance(exc, ctypes.ArgumentError)
            and re.fullmatch(r"argument \d+: KeyboardInterrupt: ?", str(exc)) is not None)

"""A Ctrl-C as ctypes wraps it, from a real call of the C library (shared by the tests of the
commands' interrupts: tests/test_cli.py, tests/test_campaign_execute.py,
tests/test_campaign_grid.py)."""

import ctypes


class _Interrupted:
    """An argument type whose check meets a Ctrl-C, as NumPy's ``ndpointer`` (a check in
    Python) does when SIGINT arrives during it."""

    @classmethod
    def from_param(cls, obj):
        raise KeyboardInterrupt


def ctrl_c_wrapped_by_ctypes():
    """Call the C library's ``labs`` with an argument whose check meets a Ctrl-C: raises
    what ctypes makes of it, ``ArgumentError("argument 1: KeyboardInterrupt: ")``, with
    neither cause nor context."""
    labs = ctypes.CDLL(None).labs
    labs.restype, labs.argtypes = ctypes.c_long, [_Interrupted]
    labs(-3)


def labs_of_a_long():
    """The C library's ``labs`` declared on a ``long``: a wrong argument is ctypes'
    ``ArgumentError`` of a TypeError, not an interrupt."""
    labs = ctypes.CDLL(None).labs
    labs.restype, labs.argtypes = ctypes.c_long, [ctypes.c_long]
    return labs

"""Imported by a campaign's forkserver only (its preload): a quiet end for a worker whose
start the campaign's Ctrl-C cut short.

When Ctrl-C stops the campaign's process while it sends a new worker its process object,
the forkserver's child reads a truncated pickle and ends on ``EOFError``; multiprocessing
then prints that child's traceback through ``sys.excepthook``, under the campaign's one
line ``quadland: interrupted ...``. This hook ends such a child silently (its exit status
stays 1) and leaves every other exception to the default hook. The campaign's own process
never imports this module.
"""

from __future__ import annotations

import sys

__all__ = ["quiet_truncated_start"]


def quiet_truncated_start(kind, value, traceback) -> None:
    """``sys.excepthook`` of the forkserver and its children: silent on ``EOFError``."""
    if issubclass(kind, EOFError):
        return
    sys.__excepthook__(kind, value, traceback)


sys.excepthook = quiet_truncated_start

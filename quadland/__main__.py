"""``python -m quadland`` and the ``quadland`` console script: the command line.

Ctrl-C must give one line ``quadland: interrupted`` and exit status 130 from
the first instant, also while the command's modules import (NumPy, CasADi,
matplotlib: most of a second): :func:`main` installs its SIGINT handler
before it imports anything of quadland's beyond this module, and the
package itself imports nothing on import (``quadland/__init__.py``). Once
the command's modules are loaded, Python's own handler is back and
:func:`quadland.cli.main` handles ``KeyboardInterrupt`` (a campaign keeps
its recorded runs).
"""

import os
import signal
import sys

#: Exit status of an interrupted command (128 + SIGINT).
INTERRUPTED = 130


def _interrupted(signum, frame) -> None:
    os.write(2, b"quadland: interrupted\n")
    os._exit(INTERRUPTED)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``quadland`` console script and of ``python -m quadland``."""
    previous = signal.getsignal(signal.SIGINT)
    if previous is signal.default_int_handler:              # not where SIGINT is ignored
        signal.signal(signal.SIGINT, _interrupted)          # before any heavy import
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


if __name__ == "__main__":
    sys.exit(main())

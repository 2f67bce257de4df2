"""``python -m quadland``: the command line."""

import sys

from quadland.cli import main

if __name__ == "__main__":
    sys.exit(main())

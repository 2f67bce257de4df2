"""``python -m quadland``: the command line."""

import sys

from quadland.cli import main

sys.exit(main())

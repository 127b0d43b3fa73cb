"""``python -m sflm``: the command line (:func:`sflm.cli.main`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())

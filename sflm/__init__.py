"""sflm: the command line and reports on top of :mod:`modelgen` and :mod:`inversion`."""

import time as _time

#: When the process reached this package, before its imports: the command line's progress counts its seconds from here
#: (a busy machine took up to 11 s to import what a command needs, which the first line's "(2 s)" did not count).
STARTED = _time.monotonic()

from modelgen import __version__  # noqa: E402  # pyproject.toml's, through the installed metadata: what pip installed

__all__ = ["__version__"]

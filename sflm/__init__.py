"""sflm: the command line and reports on top of :mod:`modelgen` and :mod:`inversion`."""

from modelgen import __version__  # pyproject.toml's, through the installed metadata: what pip installed

__all__ = ["__version__"]

"""sflm: the command line and reports on top of :mod:`modelgen` and :mod:`inversion`."""

from importlib.metadata import PackageNotFoundError, version as _version

try:  # the installed package's metadata (pyproject.toml), so that `sflm --version` says what pip installed
    __version__ = _version("sflm")
except PackageNotFoundError:  # run from a source tree that was not installed
    __version__ = "0.1.0"

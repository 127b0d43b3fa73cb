"""sflm: the command line and reports on top of :mod:`modelgen` and :mod:`inversion`."""

__version__ = "0.1.0"

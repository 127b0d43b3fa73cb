"""Typed exceptions of the sflm toolkit.

Every error a user can cause derives from :class:`SflmError`; the command line prints
its message on one line and exits with status 2. Numerical failures carry the figures
that show the failure (a residual, a condition number) rather than returning a result.
"""

from __future__ import annotations

from typing import Any

__all__ = ["SflmError", "GeometryError", "ModelError", "CodegenError"]


class SflmError(Exception):
    """Base class of every error raised by sflm on purpose."""


class GeometryError(SflmError, ValueError):
    """A geometry file or geometry value is invalid.

    Parameters
    ----------
    key : str
        Dotted key of the offending entry (``"link.length"``), or the file for
        file-level problems.
    value : Any
        The rejected value (``None`` when the key is missing).
    accepted : str
        What would have been accepted.
    source : str, optional
        Where the geometry came from (file name or preset), for the message.
    """

    def __init__(self, key: str, value: Any, accepted: str, source: str | None = None):
        self.key = key
        self.value = value
        self.accepted = accepted
        self.source = source
        where = f"geometry {source!r}: " if source else "geometry: "
        if value is None:
            what = f"{key} is missing"
        else:
            what = f"{key} = {value!r} is not accepted"
        super().__init__(f"{where}{what}; expected {accepted}")


class ModelError(SflmError):
    """The model could not be built (a numerical check failed); the message has the figures."""


class CodegenError(SflmError):
    """Code generation, compilation or loading of generated code failed."""

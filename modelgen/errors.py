"""Typed exceptions of the sflm toolkit.

Every error a user can cause derives from :class:`SflmError`; the command line prints
its message on one line and exits with status 2. Numerical failures carry the figures
that show the failure (a residual, a condition number) rather than returning a result.
"""

from __future__ import annotations

import sys
import warnings
from typing import Any

__all__ = ["SflmError", "GeometryError", "SettingsError", "ModelError", "CodegenError", "SflmWarning", "warn"]


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
            what = f"{key} = {_shown(value)} is not accepted"
        super().__init__(f"{where}{what}; expected {accepted}")


class SettingsError(SflmError, ValueError):
    """A setting of the inversion, simulation or CLI is out of range.

    A setting of the inversion, the simulation or the command line is out of range.

    It lives here, below every layer that validates settings, so that each raises the same
    type (``inversion.errors`` hands it on under its former home).

    Parameters
    ----------
    parameter : str
        The setting, named as the library's keyword (``"cdec"``, ``"segments"``, ``"rate"`` ...); the command line shows it as its flag.
    value : Any
        The rejected value.
    accepted : str
        What would be accepted.
    """

    def __init__(self, parameter: str, value: Any, accepted: str):
        self.parameter = parameter
        self.value = value
        self.accepted = accepted
        super().__init__(f"{parameter} = {_shown(value)} is not accepted; expected {accepted}")


#: A rejected value's ``repr`` longer than this is shown by its start and its length (a 400-digit number filled the screen).
SHOWN_CHARACTERS = 200


def _shown(value: Any) -> str:
    """``repr`` of a rejected value, with NumPy scalars shown as the plain numbers they are (inside tuples and lists too);
    one longer than :data:`SHOWN_CHARACTERS` by its first 60 characters and its length."""
    text = repr(_plain(value))
    return text if len(text) <= SHOWN_CHARACTERS else f"{text[:60]}... ({len(text)} characters)"


def _plain(value: Any) -> Any:
    """``value`` with its NumPy scalars as Python numbers."""
    if isinstance(value, (tuple, list)):
        return type(value)(_plain(v) for v in value)
    item = getattr(value, "item", None)
    if callable(item) and type(value).__module__ == "numpy" and getattr(value, "ndim", 1) == 0:
        return item()
    return value


class ModelError(SflmError):
    """The model could not be built (a numerical check failed).

    The model could not be built (a numerical check failed); the message has the figures.
    """


class CodegenError(SflmError):
    """Generating, compiling or loading generated code failed."""


class SflmWarning(UserWarning):
    """Something worked, but not the best way.

    Something worked, but not the best way (e.g. no C compiler: slower in-process functions).
    """


#: Packages of the project: a warning is attributed to the first frame outside them.
_OWN_PACKAGES = ("modelgen", "inversion", "simulation", "sflm")


def _caller_stacklevel() -> int:
    """``stacklevel`` of the first frame outside the project (the user's call), for :func:`warnings.warn`."""
    frame = sys._getframe(2)
    level = 2
    while frame is not None and frame.f_globals.get("__name__", "").split(".")[0] in _OWN_PACKAGES:
        frame = frame.f_back  # type: ignore[assignment]
        level += 1
    return level


def warn(message: str) -> None:
    """A one-line :class:`SflmWarning` attributed to the caller.

    A one-line :class:`SflmWarning` attributed to the caller's code, not to the library.

    What the user's environment or model causes is not a defect of the library: the warning
    names the line of user code that led to it (so that a test suite turning the library's
    own warnings into errors still runs).

    Parameters
    ----------
    message : str
        The warning's one line.
    """
    warnings.warn(message, SflmWarning, stacklevel=_caller_stacklevel())

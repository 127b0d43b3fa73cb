"""Errors of the inversion layer."""

from __future__ import annotations

from typing import Any

from modelgen.errors import SflmError

__all__ = ["InversionError", "SettingsError", "TrajectoryError"]


class SettingsError(SflmError, ValueError):
    """An inversion or simulation setting is out of range.

    Parameters
    ----------
    parameter : str
        The setting (``"cdec"``, ``"segments"``, ``"--rate"`` ...).
    value : Any
        The rejected value.
    accepted : str
        What would be accepted.
    """

    def __init__(self, parameter: str, value: Any, accepted: str):
        self.parameter = parameter
        self.value = value
        self.accepted = accepted
        super().__init__(f"{parameter} = {value!r} is not accepted; expected {accepted}")


class TrajectoryError(SettingsError):
    """A desired trajectory is invalid (non-finite values, unreadable CSV, too few derivatives)."""


class InversionError(SflmError):
    """The inversion failed numerically; carries the figures that show it.

    Attributes
    ----------
    segment : int or None
        Index of the failing segment.
    residual : float
        Relative constraint residual of its linear system.
    condition : float
        Condition number of its (scaled) matrix.
    """

    def __init__(self, message: str, segment: int | None = None, residual: float = float("nan"), condition: float = float("nan")):
        self.segment = segment
        self.residual = residual
        self.condition = condition
        super().__init__(message)

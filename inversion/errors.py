"""Errors of the inversion layer (:class:`SettingsError` is shared with the other layers, from :mod:`modelgen.errors`)."""

from __future__ import annotations

from modelgen.errors import SettingsError, SflmError

__all__ = ["InversionError", "SettingsError", "TrajectoryError"]


class TrajectoryError(SettingsError):
    """A desired trajectory is invalid.

    A desired trajectory is invalid (non-finite values, unreadable CSV, too few derivatives).
    """


class InversionError(SflmError):
    """The inversion failed numerically; carries the figures.

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

"""inversion: piece-wise causal inversion by output redefinition (the numeric layer).

Consumes a loaded :class:`modelgen.Model` (compiled functions) and never imports SymPy.

>>> import modelgen, inversion
>>> result = inversion.invert(modelgen.load("paper-sim"), inversion.smoothstep(1.57, 5.5))
"""

from __future__ import annotations

from .api import invert
from .errors import InversionError, SettingsError, TrajectoryError
from .family.explore import Exploration, explore
from .realtime.feedforward_c import export_c, export_table
from .result import CSV_COLUMNS, InversionResult, InversionSummary
from .settings import InversionSettings
from .signals.trajectory import (
    CallableTrajectory,
    PolynomialTrajectory,
    Trajectory,
    experiment_trajectory,
    from_csv,
    smoothstep,
    trajectory_from_spec,
)

__all__ = [
    "CSV_COLUMNS",
    "CallableTrajectory",
    "Exploration",
    "InversionError",
    "InversionResult",
    "InversionSummary",
    "InversionSettings",
    "PolynomialTrajectory",
    "SettingsError",
    "Trajectory",
    "TrajectoryError",
    "experiment_trajectory",
    "explore",
    "export_c",
    "export_table",
    "from_csv",
    "invert",
    "smoothstep",
    "trajectory_from_spec",
]

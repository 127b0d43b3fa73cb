"""inversion: piece-wise causal inversion by output redefinition (the numeric layer).

Consumes a loaded :class:`modelgen.Model` (compiled functions) and never imports SymPy.

>>> import modelgen, inversion
>>> result = inversion.invert(modelgen.load("paper-sim"), inversion.smoothstep(1.57, 5.5))
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the names are imported when first used (PEP 562): `import inversion.config` stays light
    from .errors import InversionError, SettingsError, TrajectoryError
    from .explore import Exploration, explore
    from .methods import invert
    from .result import CSV_COLUMNS, InversionResult, InversionSummary
    from .settings import InversionSettings
    from .trajectory import (
        CallableTrajectory,
        PolynomialTrajectory,
        Trajectory,
        experiment_trajectory,
        from_csv,
        smoothstep,
        trajectory_from_spec,
    )

#: Where each public name lives.
_HOMES = {
    "InversionError": "errors", "SettingsError": "errors", "TrajectoryError": "errors",
    "Exploration": "explore", "explore": "explore", "invert": "methods",
    "CSV_COLUMNS": "result", "InversionResult": "result", "InversionSummary": "result",
    "InversionSettings": "settings",
    "CallableTrajectory": "trajectory", "PolynomialTrajectory": "trajectory", "Trajectory": "trajectory",
    "experiment_trajectory": "trajectory", "from_csv": "trajectory", "smoothstep": "trajectory",
    "trajectory_from_spec": "trajectory",
}


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'inversion' has no attribute {name!r}")
    value = getattr(import_module(f".{home}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_HOMES))


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
    "from_csv",
    "invert",
    "smoothstep",
    "trajectory_from_spec",
]

"""modelgen: derive, generate and load single-flexible-link-manipulator models.

Data flows geometry -> symbolic model (SymPy) -> generated C (CasADi) -> loaded model.
Importing this package is cheap: SymPy is imported only when a model has to be derived.
"""

from __future__ import annotations

from .errors import CodegenError, GeometryError, ModelError, SflmError
from .geometry import MODE_FAMILIES, PRESETS, Geometry, load_geometry, parse_geometry
from .loader import load
from .model import Model

__all__ = [
    "CodegenError",
    "Geometry",
    "GeometryError",
    "MODE_FAMILIES",
    "Model",
    "ModelError",
    "PRESETS",
    "SflmError",
    "load",
    "load_geometry",
    "parse_geometry",
]

__version__ = "0.1.0"

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



def _version() -> str:
    """sflm's version, from one source: ``pyproject.toml`` (through the installed package's metadata, or read from the
    source tree when it was not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("sflm")
    except PackageNotFoundError:
        import tomllib
        from pathlib import Path

        try:
            return tomllib.loads((Path(__file__).resolve().parent.parent / "pyproject.toml").read_text())["project"]["version"]
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "0+unknown"


__version__ = _version()

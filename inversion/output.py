"""The result writers under their former home: :mod:`modelgen.files` holds them, below every layer that writes."""

from __future__ import annotations

from modelgen.files import write_columns, write_json

__all__ = ["write_columns", "write_json"]

"""Writing results: CSV tables and JSON summaries (shared by the inversion and the simulation)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["write_columns", "write_json"]


def write_columns(path: str | Path, names: Sequence[str], columns: Sequence[ArrayLike]) -> None:
    """Write equal-length columns as a CSV table with a header (full double precision)."""
    arrays = [np.asarray(c, dtype=float) for c in columns]
    with open(path, "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(list(names))
        for row in zip(*arrays):
            writer.writerow([repr(float(v)) for v in row])


def write_json(path: str | Path, data: Any) -> None:
    """Write a JSON document (indented, newline-terminated)."""
    Path(path).write_text(json.dumps(data, indent=1) + "\n")

"""Writing results: CSV tables and JSON summaries (shared by the inversion, the simulation and the command line)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["write_columns", "write_json"]

_ROWS = 100_000  # rows formatted at once


def write_columns(
    path: str | Path,
    names: Sequence[str],
    columns: Sequence[ArrayLike],
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write equal-length columns as a CSV table with a header.

    Every value is written as the shortest decimal that reads back to the same double
    (``repr``), in blocks of ``_ROWS`` rows.

    Parameters
    ----------
    path : str or Path
        The file.
    names : sequence of str
        Column names (the header).
    columns : sequence of array_like
        The columns, of equal length.
    progress : callable, optional
        Called as ``progress(rows_written, rows)`` after each block.
    """
    table = np.column_stack([np.asarray(c, dtype=float).reshape(-1) for c in columns]) if columns else np.zeros((0, 0))
    rows = int(table.shape[0])
    with open(path, "w", newline="") as handle:
        handle.write(",".join(names) + "\n")
        for lo in range(0, rows, _ROWS):
            block = table[lo : lo + _ROWS].tolist()
            handle.write("\n".join(",".join(map(repr, row)) for row in block) + "\n")
            if progress is not None:
                progress(min(lo + _ROWS, rows), rows)


def write_json(path: str | Path, data: Any) -> None:
    """Write a JSON document (indented, newline-terminated)."""
    Path(path).write_text(json.dumps(data, indent=1) + "\n")

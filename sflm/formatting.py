"""Plain-text rendering of models and results for the command line."""

from __future__ import annotations

from typing import Any, Iterable, Sequence

import numpy as np

from modelgen.zeros import IMAGINARY_TOL

__all__ = ["zero_pairs", "table", "fmt", "printable"]


def fmt(value: float, digits: int = 5) -> str:
    """A number with ``digits`` significant digits.

    Parameters
    ----------
    value : float
        The number.
    digits : int, optional
        Significant digits.
    """
    return f"{value:.{digits}g}"


def zero_pairs(zeros: Iterable[complex], digits: int = 3, limit: int | None = None) -> list[str]:
    """Zeros as readable pairs.

    Zeros as readable pairs: ``±65.261``, ``±56.314i``, ``-0.753±55.935i``, ``77.800``.

    Symmetric real pairs and conjugate pairs are shown once.

    Parameters
    ----------
    zeros : Iterable[complex]
        The zeros.
    digits : int, optional
        Decimals shown.
    limit : int | None, optional
        Most pairs shown (``None``: all).
    """
    remaining = [complex(z) for z in zeros]
    out: list[str] = []
    while remaining and (limit is None or len(out) < limit):
        z = remaining.pop(0)
        tol = 1e-7 * max(abs(z), 1.0)
        real = abs(z.imag) <= IMAGINARY_TOL * abs(z)
        if real:
            mirror = next((w for w in remaining if abs(w + z.real) <= tol), None)
            if mirror is not None:
                remaining.remove(mirror)
                out.append(f"±{abs(z.real):.{digits}f}")
            else:
                out.append(f"{z.real:.{digits}f}")
            continue
        conj = next((w for w in remaining if abs(w - z.conjugate()) <= tol), None)
        if conj is not None:
            remaining.remove(conj)
        im = abs(z.imag)
        if abs(z.real) <= IMAGINARY_TOL * abs(z):
            mirror_text = "±" if conj is not None else ("" if z.imag > 0 else "-")
            out.append(f"{mirror_text}{im:.{digits}f}i")
        else:
            sign = "±" if conj is not None else ("+" if z.imag > 0 else "-")
            out.append(f"{z.real:.{digits}f}{sign}{im:.{digits}f}i")
    return out


def table(header: Sequence[str], rows: Sequence[Sequence[Any]]) -> str:
    """A left-aligned text table.

    Parameters
    ----------
    header : Sequence[str]
        The columns' titles.
    rows : Sequence[Sequence[Any]]
        The rows.
    """
    cells = [[str(c) for c in header]] + [[str(c) for c in row] for row in rows]
    widths = [max(len(r[i]) if i < len(r) else 0 for r in cells) for i in range(len(header))]
    lines = []
    for k, row in enumerate(cells):
        lines.append("  ".join(c.ljust(widths[i]) for i, c in enumerate(row)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def array_text(a: np.ndarray, digits: int = 6) -> str:
    """A small matrix, one row per line."""
    a = np.atleast_2d(np.asarray(a, dtype=float))
    return "\n".join("  ".join(f"{v: .{digits}g}" for v in row) for row in a)


def printable(text: str) -> str:
    """``text`` with its control characters written as escapes.

    An escape sequence in a file's name, a carriage return: written as ``\\x1b``, ``\\r``, so that a message cannot
    drive the terminal it is printed on; tabs and new lines are kept.

    Parameters
    ----------
    text : str
        A message.
    """
    return "".join(c if c.isprintable() or c in "\n\t" else c.encode("unicode_escape").decode("ascii") for c in str(text))

"""Writing results: CSV tables and JSON summaries (shared by the inversion, the simulation and the command line)."""

from __future__ import annotations

import json
import os
import uuid
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["write_columns", "write_json", "replaced", "read_document", "DocumentError", "MAX_DOCUMENT_BYTES", "MAX_DEPTH"]

_ROWS = 100_000  # rows formatted at once
#: Largest JSON or TOML document read (bytes): geometry files, systems, settings and summaries are a few kB.
MAX_DOCUMENT_BYTES = 16 * 2**20
#: Deepest nesting of arrays and tables accepted in a document (ours nest three deep).
MAX_DEPTH = 32


class DocumentError(ValueError):
    """A JSON or TOML document that cannot be read.

    A JSON or TOML document that cannot be read: malformed, too large or nested too deeply (the message says which).
    """


@contextmanager
def replaced(path: str | Path) -> Iterator[Path]:
    """A temporary name beside ``path``, renamed onto it at the end.

    Renamed onto ``path`` when the block ends, removed if it raises.

    Whatever writes the file writes it whole or not at all: a reader never sees half a file, and a command killed while
    writing leaves the file it had (``os.replace`` is atomic on one file system).

    Parameters
    ----------
    path : str or Path
        The file to write.
    """
    path = Path(path)
    _sweep(path)
    temporary = path.with_name(f".{path.name}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        yield temporary
        os.replace(temporary, path)
    finally:
        if temporary.exists():
            temporary.unlink()


#: The folders this process has swept (:func:`_sweep`): once each, at its first write there.
_SWEPT: set[Path] = set()


def _sweep(path: Path) -> None:
    """Remove the temporaries :func:`replaced` left in ``path``'s folder by processes that no longer run (a writer killed by
    ``kill -9`` cannot remove its own: 36 kills left 23 files, 14.7 MB, issue 59 item 14). A temporary of a process that
    still runs, or of another user's, is left alone. Once per folder and process: a folder of thousands of files (the
    model cache's roots) read at every write slowed a calibration's thousands of writes to minutes."""
    folder = path.parent
    if os.name != "posix" or folder in _SWEPT:  # os.kill(pid, 0) asks whether a process runs only on POSIX
        return
    _SWEPT.add(folder)
    try:
        candidates = [entry.name for entry in os.scandir(folder) if entry.name.startswith(".") and entry.name.endswith(".tmp")]
    except OSError:
        return
    for name in candidates:
        parts = name[: -len(".tmp")].rsplit(".", 2)  # [".NAME", PID, 8 hex digits], as replaced() names them
        if len(parts) != 3 or not parts[1].isdigit() or len(parts[2]) != 8 or int(parts[1]) == os.getpid():
            continue
        candidate = folder / name
        try:
            os.kill(int(parts[1]), 0)
        except ProcessLookupError:  # its writer is gone
            with suppress(OSError):
                candidate.unlink()
        except (PermissionError, OverflowError, OSError):  # another user's process, or not a process id: left alone
            continue


def write_columns(
    path: str | Path,
    names: Sequence[str],
    columns: Sequence[ArrayLike],
    progress: Callable[[int, int], None] | None = None,
) -> None:
    """Write equal-length columns as a CSV table with a header.

    Every value is written as the shortest decimal that reads back to the same double
    (``repr``), in blocks of ``_ROWS`` rows, under a temporary name renamed at the end (:func:`replaced`).

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
    with replaced(path) as temporary, open(temporary, "w", newline="") as handle:
        handle.write(",".join(names) + "\n")
        for lo in range(0, rows, _ROWS):
            block = table[lo : lo + _ROWS].tolist()
            handle.write("\n".join(",".join(map(repr, row)) for row in block) + "\n")
            if progress is not None:
                progress(min(lo + _ROWS, rows), rows)


def write_json(path: str | Path, data: Any) -> None:
    """Write a JSON document (indented, newline-terminated).

    Parameters
    ----------
    path : str | Path
        The file to write.
    data : Any
        A JSON-serialisable value.
    """
    with replaced(path) as temporary:
        temporary.write_text(json.dumps(data, indent=1) + "\n")


def read_document(path: str | Path, kind: str | None = None) -> Any:
    """A JSON or TOML document read safely (bounded size and depth).

    A JSON or TOML document read safely: at most :data:`MAX_DOCUMENT_BYTES`, nested at most :data:`MAX_DEPTH` deep.

    Python's readers recurse once per level of nesting: a file of ``[[[[...`` exhausts the
    interpreter's stack (a ``RecursionError``) before any check of its contents. Here the
    nesting is measured before the document is parsed, without recursion.

    Parameters
    ----------
    path : str or Path
        The file.
    kind : {"json", "toml"}, optional
        The format (default: from the suffix; ``.json`` is JSON, anything else TOML).

    Raises
    ------
    DocumentError
        For a document that is not a regular file, too large, too deep, not UTF-8 (a byte-order mark is accepted) or not
        valid JSON or TOML.
    OSError
        When the file cannot be read.
    """
    path = Path(path)
    kind = kind or ("json" if path.suffix.lower() == ".json" else "toml")
    if path.exists() and not path.is_file():  # a FIFO or a device would block the read, a folder fail it
        raise DocumentError("not a regular file (a folder, a pipe or a device)")
    with open(path, "rb") as handle:
        raw = handle.read(MAX_DOCUMENT_BYTES + 1)
    if len(raw) > MAX_DOCUMENT_BYTES:
        raise DocumentError(f"larger than {MAX_DOCUMENT_BYTES // 2**20} MB")
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark, as some editors write, is not the document's
    except UnicodeDecodeError as exc:
        raise DocumentError(f"not UTF-8 text ({exc.reason} at byte {exc.start})") from None
    depth = _nesting(text) if text.count("[") + text.count("{") > MAX_DEPTH else 0
    if depth > MAX_DEPTH:
        raise DocumentError(f"nested {depth} deep (at most {MAX_DEPTH})")
    try:
        if kind == "json":
            return json.loads(text)
        import tomllib

        return tomllib.loads(text)
    except (ValueError, RecursionError) as exc:
        raise DocumentError(f"not valid {kind.upper()} ({exc.__class__.__name__}: {exc})") from None


def _nesting(text: str) -> int:
    """The deepest nesting of ``[``/``{`` outside strings (JSON's and TOML's quotes; an upper bound where a TOML
    comment holds brackets)."""
    depth = deepest = 0
    quote = ""
    escaped = False
    for ch in text:
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\" and quote == '"':
                escaped = True
            elif ch == quote or (ch == "\n" and quote == "'"):
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(depth - 1, 0)
    return deepest


def cache_root() -> Path:
    """``$SFLM_CACHE_DIR`` or the user cache directory for ``sflm`` (the compiled models, and what is derived with them).

    Returns
    -------
    Path
        The folder (not created here).
    """
    env = os.environ.get("SFLM_CACHE_DIR")
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("sflm"))

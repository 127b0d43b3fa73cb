"""What is derived from a link's values and costs time, kept beside its compiled models: computed once, read back.

The compiled models are kept per number of modes (:mod:`modelgen.cache`); some quantities depend on a link's values
instead and take a noticeable share of an everyday command: the continuum reference of :mod:`modelgen.continuum` (two
finite-element meshes and their generalised eigenproblems, 0.3 s of every ``sflm info``). They are kept in the same
cache root, under ``derived/``, one NumPy ``.npz`` file (read with ``allow_pickle=False``) per kind and key, the key's
digest naming it. The key holds everything the values depend on: the inputs given (a link's every value, the mesh),
the source files that compute them (a change of the code is a new key), the versions of NumPy and SciPy (their LAPACK
decides the last bits) and :data:`FORMAT`.

Nothing here can fail a command: a cache root that cannot be written, a file another process is writing or a damaged
one, and the values are computed as if none were kept (and a damaged file replaced). A file is written under a name of
its own and renamed into place, so a reader sees a whole file or none.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import zipfile
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from .errors import SflmError

__all__ = ["kept", "FORMAT", "FOLDER"]

#: The layout of a kept file; a change makes every key new.
FORMAT = 1
#: The folder of the cache root that holds them.
FOLDER = "derived"


def _versions() -> dict[str, str]:
    import scipy

    return {"numpy": np.__version__, "scipy": scipy.__version__, "python": ".".join(map(str, sys.version_info[:3]))}


def _path(kind: str, key: Mapping[str, Any], sources: Sequence[str]) -> Path | None:
    """Where the values of ``key`` are kept (``None``: no cache root that can be used)."""
    from .cache import prepare_root, sources_digest
    from .files import cache_root

    text = json.dumps({"kind": kind, "key": key, "sources": sources_digest(sources), "versions": _versions(),
                       "format": FORMAT}, sort_keys=True, allow_nan=True, default=repr)
    digest = hashlib.sha256(text.encode()).hexdigest()
    try:
        root = prepare_root(cache_root())
    except (SflmError, OSError):  # an insecure or unwritable root: the compiled models say why where they need it
        return None
    return root / FOLDER / f"{kind}-{digest[:32]}.npz"


def kept(kind: str, key: Mapping[str, Any], compute: Callable[[], Mapping[str, NDArray[Any]]],
         sources: Sequence[str]) -> dict[str, NDArray[Any]]:
    """Arrays derived from ``key``: read back if kept, else computed.

    The arrays ``compute`` returns for ``key``: read back where kept, else computed and kept.

    Parameters
    ----------
    kind : str
        What they are (a file name's stem: letters, digits and hyphens).
    key : mapping
        Everything the values depend on besides the code, JSON-serialisable (floats are kept to the last bit).
    compute : callable
        Computes them: a mapping of names to arrays of numbers.
    sources : sequence of str
        The files of :mod:`modelgen` whose code computes them.

    Returns
    -------
    dict
        The arrays, bit for bit what ``compute`` returned when they were kept.
    """
    path = _path(kind, key, sources)
    if path is not None and path.is_file():
        try:
            with np.load(path, allow_pickle=False) as data:
                return {name: np.array(data[name]) for name in data.files}
        except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile):
            pass  # damaged (or written by another process under this name by hand): computed again and replaced
    values = {name: np.asarray(value) for name, value in compute().items()}
    if path is not None:
        tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
        try:
            path.parent.mkdir(mode=0o700, exist_ok=True)
            with open(tmp, "wb") as handle:
                savez: Any = np.savez  # (its stubs type a keyword array as the allow_pickle flag)
                savez(handle, **values)
            os.replace(tmp, path)
        except OSError:  # (a full disk, a root made read-only under us: nothing kept)
            try:
                tmp.unlink(missing_ok=True)
            except OSError:
                pass
    return values

"""Cache of generated and compiled models, keyed by a content hash.

Everything that shapes the generated code — the number of modes, the roles, the
compiler and its flags, the SymPy and CasADi versions and the source of the derivation
modules themselves — goes into a sorted-key JSON whose SHA-256 names the cache entry
``sflm_n<N>-<hash16>/``. The entry holds the C source and header, the compiled library,
the serialised CasADi functions (the no-compiler fallback) and ``manifest.json``.

* A hit (manifest present, hashes of the key and of every file match, library loads)
  imports neither SymPy nor the derivation.
* A miss builds into a temporary folder renamed into place: an interrupted or concurrent
  build never leaves a half-written entry; the loser of a race uses the winner's entry.
* A corrupted or stale entry is moved aside and rebuilt, never used; the manifest carries a
  checksum of its own content, so an edited manifest is a stale entry too.
* A build killed mid-way leaves its ``.build-*`` folder; the next build removes every such
  folder whose owner process (recorded in its name and its owner file) is gone, or that names
  no owner and is an hour old.
* Disk and permission errors are :class:`CodegenError` naming the cache folder and
  ``SFLM_CACHE_DIR``.
* The root is created private (``0700``, whatever the umask); a root that another user owns,
  or that others may write, is refused: the cache holds compiled code that sflm loads and
  runs, and its checksums certify themselves (whoever can write an entry can rewrite its
  manifest), so the cache is exactly as trusted as its folder.
* Without a C compiler, or when compilation fails, the in-process CasADi functions are
  used, with a one-line :class:`SflmWarning`.

The cache lives in ``$SFLM_CACHE_DIR`` or the user cache directory.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import sys
import tempfile
import uuid
from importlib import metadata
from pathlib import Path
from typing import Any, Sequence

from .abi import BATCH_CHUNK, COMPILE_FLAGS, ROLES, compiler_command, compiler_version
from .compiled import ModelFunctions, load_external, load_serialized
from .errors import CodegenError, SflmWarning, warn
from .files import cache_root

__all__ = [
    "SflmWarning",
    "cache_root",
    "prepare_root",
    "sweep_builds",
    "build_folder",
    "release",
    "file_digest",
    "cache_key",
    "ensure_model_functions",
    "build_entry",
    "MANIFEST",
    "FORMAT",
]

MANIFEST = "manifest.json"
#: Version of the manifest/cache layout.
FORMAT = 1
#: Modules whose source shapes the generated code (part of the cache key).
_DERIVATION_SOURCES = ("lagrange.py", "codegen.py", "sympy_casadi.py", "parameters.py", "abi.py")


def _version(dist: str) -> str:
    try:
        return metadata.version(dist)
    except metadata.PackageNotFoundError:
        return "unknown"


def versions() -> dict[str, str]:
    """Versions of the tools that shape the generated code."""
    return {
        "sflm": _version("sflm"),
        "sympy": _version("sympy"),
        "casadi": _version("casadi"),
        "python": ".".join(map(str, sys.version_info[:3])),
    }


def sources_digest(names: Sequence[str]) -> str:
    """The SHA-256 of some of :mod:`modelgen`'s source files.

    The SHA-256 of :mod:`modelgen`'s source files ``names`` (each name and its bytes, in turn): a change of the code that
    computes what a cache keeps is a new key (the compiled models', :mod:`modelgen.derived`'s).

    Parameters
    ----------
    names : sequence of str
        File names in the package's folder.
    """
    here = Path(__file__).parent
    digest = hashlib.sha256()
    for name in names:
        digest.update(name.encode())
        digest.update((here / name).read_bytes())
    return digest.hexdigest()


def cache_key(n: int, compiler: str | None) -> dict[str, Any]:
    """Everything that shapes an ``n``-mode model's code (hashed).

    Parameters
    ----------
    n : int
        Number of assumed modes.
    compiler : str | None
        The C compiler's command (its version enters the key), or ``None``.
    """
    v = versions()
    return {
        "format": FORMAT,
        "modes": n,
        "roles": {role: [list(ins), list(outs)] for role, (ins, outs) in ROLES.items()},
        "batch_chunk": BATCH_CHUNK,
        "compiler": compiler_version(compiler),
        "flags": list(COMPILE_FLAGS) if compiler else [],
        "sympy": v["sympy"],
        "casadi": v["casadi"],
        "derivation": sources_digest(_DERIVATION_SOURCES),
    }


def key_hash(key: dict[str, Any]) -> str:
    """SHA-256 of the sorted-key JSON of ``key``."""
    return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()


def file_digest(path: Path) -> str:
    """SHA-256 of a file's bytes (manifest and FMU checksums).

    Parameters
    ----------
    path : Path
        The file to hash.
    """
    return hashlib.sha256(path.read_bytes()).hexdigest()


def prepare_root(root: Path) -> Path:
    """The cache root, created private and checked to be this user's.

    The cache root, created private (``0700``, whatever the umask) and checked to be this user's alone.

    Parameters
    ----------
    root : Path
        The cache root to create or check.

    Raises
    ------
    CodegenError
        For a root owned by another user or writable by others (group or world), naming it and ``SFLM_CACHE_DIR``; or
        one that cannot be created.
    """
    import stat

    try:
        root.mkdir(parents=True, exist_ok=True, mode=0o700)
        info = root.stat()
    except OSError as exc:
        raise _cache_error(root, exc, "create the cache folder") from None
    if hasattr(os, "getuid") and info.st_uid != os.getuid():
        raise CodegenError(f"the model cache {root} belongs to another user (uid {info.st_uid}): sflm loads and runs the compiled "
                           "code it holds, so it must be yours alone; set SFLM_CACHE_DIR to a folder of your own")
    if info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        raise CodegenError(f"the model cache {root} is writable by others (mode {stat.S_IMODE(info.st_mode):o}): sflm loads and runs "
                           f"the compiled code it holds, so it must be yours alone; chmod 700 {root}, or set SFLM_CACHE_DIR to a "
                           "private folder")
    return root


def basename(n: int) -> str:
    """Base name of the generated files of an ``n``-mode model (``sflm_n2``)."""
    return f"sflm_n{n}"


def build_entry(n: int, folder: Path, compiler: str | None, key: dict[str, Any]) -> dict[str, Any]:
    """Derive, generate, serialise and compile into ``folder``.

    Returns the manifest (also written to ``folder/manifest.json``, last). Imports SymPy.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    folder : Path
        The build folder written into.
    compiler : str | None
        The C compiler's command, or ``None`` to serialise only.
    key : dict[str, Any]
        The cache key (:func:`cache_key`), recorded in the manifest.

    Raises
    ------
    CodegenError
        If compilation fails (the sources and serialised functions are written first).
    """
    import casadi as ca

    from .codegen import build_functions, compile_library, function_signatures, generate_sources, source_header
    from .lagrange import derive
    from .parameters import parameter_names

    folder = Path(folder)
    base = basename(n)
    functions = build_functions(derive(n))
    v = versions()
    source, header = generate_sources(functions, folder, base, source_header(n, v))
    serialized = folder / f"{base}.casadi"
    ser = ca.FileSerializer(str(serialized))
    ser.pack([functions[role] for role in ROLES])
    del ser
    library = folder / f"lib{base}.so"
    manifest: dict[str, Any] = {
        "format": FORMAT,
        "generator": f"sflm {v['sflm']} (modelgen.codegen)",
        "model": base,
        "modes": n,
        "hash": key_hash(key),
        "key": key,
        "versions": {**v, "compiler": compiler_version(compiler)},
        "compiler": {"command": Path(compiler).name if compiler else None, "flags": list(COMPILE_FLAGS)},
        "library": None,
        "sources": [source.name],
        "header": header.name,
        "serialized": serialized.name,
        "functions": function_signatures(functions),
        "parameters": {"names": parameter_names(n)},
        "batch_chunk": BATCH_CHUNK,
    }
    error: CodegenError | None = None
    if compiler is not None:
        try:
            compile_library(source, library, compiler)
            manifest["library"] = library.name
        except CodegenError as exc:
            error = exc
    manifest["checksums"] = {
        name: file_digest(folder / name)
        for name in [source.name, header.name, serialized.name] + ([library.name] if manifest["library"] else [])
    }
    manifest["manifest_checksum"] = _manifest_checksum(manifest)
    (folder / MANIFEST).write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    if error is not None:
        raise error
    return manifest


def _manifest_checksum(manifest: dict[str, Any]) -> str:
    """SHA-256 of the manifest's sorted-key JSON without its own checksum: an edited manifest is a stale entry."""
    return key_hash({k: v for k, v in manifest.items() if k != "manifest_checksum"})


def _read_manifest(folder: Path, expected_hash: str) -> dict[str, Any] | None:
    """The manifest if the entry is complete and intact, else ``None``."""
    try:
        manifest = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(manifest, dict) or manifest.get("hash") != expected_hash:
        return None
    if manifest.get("manifest_checksum") != _manifest_checksum(manifest):
        return None  # edited (or written by a layout without the checksum): rebuilt
    checks = manifest.get("checksums")
    if not isinstance(checks, dict):
        return None
    for name, digest in checks.items():
        path = folder / name
        if not path.is_file() or file_digest(path) != digest:
            return None
    return manifest


def _load_entry(folder: Path, manifest: dict[str, Any]) -> ModelFunctions:
    n = int(manifest["modes"])
    if manifest.get("library"):
        return load_external(folder / manifest["library"], n, manifest, folder)
    return load_serialized(folder / manifest["serialized"], n, manifest, folder)


def _discard(folder: Path) -> None:
    """Move a broken entry aside (atomically) and delete it."""
    trash = folder.with_name(f".trash-{folder.name}-{uuid.uuid4().hex[:8]}")
    try:
        os.replace(folder, trash)
    except OSError:
        return
    shutil.rmtree(trash, ignore_errors=True)


#: Name of the file a build folder holds its owner in (``pid host``).
_OWNER = ".owner"
#: A build or trash folder without a readable owner is stale after this many seconds.
_STALE_SECONDS = 3600.0


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except OSError:
        return False
    return True


def sweep_builds(root: Path) -> None:
    """Remove the build folders that no live build owns.

    Remove the ``.build-*`` and ``.trash-*`` folders no live build owns (a build killed mid-way, kill -9 while the compiler
    ran, leaves its folder): its owner's process gone on this host, or no owner and older than :data:`_STALE_SECONDS`.

    Parameters
    ----------
    root : Path
        The cache root whose build folders are swept.
    """
    import time

    host = _hostname()
    try:
        folders = [p for p in root.iterdir() if p.is_dir() and p.name.startswith((".build-", ".trash-"))]
    except OSError:
        return
    for folder in folders:
        owner = _owner(folder)
        if owner is not None:
            stale = owner[1] == host and not _alive(owner[0])
        else:
            try:
                stale = time.time() - folder.stat().st_mtime > _STALE_SECONDS
            except OSError:
                continue
        if stale:
            shutil.rmtree(folder, ignore_errors=True)


#: A build folder's name carries its owner (``.build-<entry>-p<pid>@<host>-<random>``): a build killed between creating
#: the folder and writing its owner file leaves a folder whose owner is still known.
_OWNED = re.compile(r"^\.build-.+?-p(?P<pid>\d+)@(?P<host>.+)-[a-z0-9_]+$")


def _owner(folder: Path) -> tuple[int, str] | None:
    """The ``(pid, host)`` that owns a build folder: from its owner file, else from its name; ``None`` if neither says."""
    try:
        pid, host = (folder / _OWNER).read_text().split()
        return int(pid), host
    except (OSError, ValueError):
        pass
    match = _OWNED.match(folder.name)
    return (int(match["pid"]), match["host"]) if match else None


def _hostname() -> str:
    """This host's name, as build folders and their owner files record it."""
    import socket

    return socket.gethostname()


def _claim(folder: Path) -> None:
    """Mark a build folder as this process's (for :func:`sweep_builds`)."""
    (folder / _OWNER).write_text(f"{os.getpid()} {_hostname()}\n")


def build_folder(root: Path, stem: str) -> Path:
    """A new build folder in ``root``, owned by this process.

    A new build folder in ``root`` owned by this process (``.build-<stem>-p<pid>@<host>-<random>``): what a build
    writes before renaming it into place, swept by :func:`sweep_builds` if the build is killed.

    Parameters
    ----------
    root : Path
        The cache root the folder is made in.
    stem : str
        The basename of the entry being built (part of the folder's name).
    """
    folder = Path(tempfile.mkdtemp(prefix=f".build-{stem}-p{os.getpid()}@{_hostname()}-", dir=root))
    _claim(folder)
    return folder


def release(folder: Path) -> None:
    """Drop a build folder's owner file before it is renamed.

    Parameters
    ----------
    folder : Path
        The build folder about to be renamed into place.
    """
    (folder / _OWNER).unlink(missing_ok=True)


def _cache_error(root: Path, exc: OSError, doing: str) -> CodegenError:
    """A disk or permission error while ``doing``, naming the cache folder and how to move it."""
    reason = exc.strerror or exc.__class__.__name__
    return CodegenError(f"cannot {doing} in the model cache {root} ({reason}); free space there or set SFLM_CACHE_DIR to a "
                        "writable folder with room")


def _warn_fallback(reason: str) -> None:
    """The compiler is missing or failed: a warning attributed to the caller's code, not to the library.

    An environment without a compiler is not a defect of the library: the warning names
    the line of user code that loaded the model (so a test suite that turns the library's
    own warnings into errors still runs without a compiler).
    """
    warn(f"{reason}; using in-process CasADi functions (same results, slower)")


def ensure_model_functions(n: int, root: Path | None = None) -> ModelFunctions:
    """An ``n``-mode model's functions: cached, or generated now.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    root : Path, optional
        Cache directory (default :func:`cache_root`).

    Returns
    -------
    ModelFunctions
    """
    root = prepare_root(cache_root() if root is None else Path(root))
    compiler = compiler_command()
    key = cache_key(n, compiler)
    digest = key_hash(key)
    entry = root / f"{basename(n)}-{digest[:16]}"

    if entry.exists():
        manifest = _read_manifest(entry, digest)
        if manifest is not None:
            try:
                functions = _load_entry(entry, manifest)
            except CodegenError:
                functions = None
            if functions is not None:
                if compiler is None:
                    _warn_fallback("no C compiler found (set CC or SFLM_CC)")
                functions.cache_hit = True
                return functions
        _discard(entry)

    try:
        sweep_builds(root)
        tmp = build_folder(root, basename(n))
    except OSError as exc:
        raise _cache_error(root, exc, "create a build folder") from None
    try:
        try:
            manifest = build_entry(n, tmp, compiler, key)
        except OSError as exc:  # a full disk, a folder made read-only under us
            raise _cache_error(root, exc, "write the generated model") from None
        except CodegenError as exc:
            # compilation failed: serve the in-process functions, cache nothing
            manifest = json.loads((tmp / MANIFEST).read_text())
            functions = load_serialized(tmp / manifest["serialized"], n, manifest, None)
            _warn_fallback(str(exc))
            return functions
        try:
            release(tmp)
            os.rename(tmp, entry)
        except OSError:
            # a concurrent build won the race: use its entry if it is intact
            winner = _read_manifest(entry, digest)
            if winner is None:
                raise CodegenError(f"cache entry {entry} is being written by another process and is not valid") from None
            manifest = winner
        if compiler is None:
            _warn_fallback("no C compiler found (set CC or SFLM_CC)")
        return _load_entry(entry, manifest)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)

"""``sflm generate``: write a model's generated C, header, library and manifest to a folder."""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .errors import CodegenError
from .geometry import Geometry
from .model import Model

__all__ = ["ExportResult", "default_folder", "export_model", "export_manifest"]


@dataclass(frozen=True)
class ExportResult:
    """What :func:`export_model` wrote.

    Attributes
    ----------
    folder : Path
        Where the files were written.
    files : list[str]
        The files written, relative to ``folder``.
    manifest : dict[str, Any]
        The manifest written.
    cache_hit : bool
        Whether the model came from the cache.
    seconds : float
        Time taken.
    """

    folder: Path
    files: list[str]
    manifest: dict[str, Any]
    cache_hit: bool
    seconds: float


def default_folder(geometry: Geometry) -> Path:
    """``generated/<name>-n<N>-<family>`` below the current directory.

    Parameters
    ----------
    geometry : Geometry
        The geometry whose folder is named.
    """
    return Path("generated") / f"{geometry.name}-n{geometry.modes}-{geometry.mode_shapes}"


def export_manifest(model: Model) -> dict[str, Any]:
    """The cache manifest plus this geometry's values.

    Keys: ``library``, ``sources``, ``header`` (relative paths), ``functions`` (role ->
    ``{"symbol", "inputs", "outputs"}``), ``parameters`` (``{"names", "values"}``),
    ``hash``, ``versions``, ``geometry``, ``natural_frequencies_hz``, ``zeros``,
    ``n_unstable``, ``internal_dynamics``, ``CAB``.

    Parameters
    ----------
    model : Model
        A loaded model.
    """
    fn = model.compiled_functions
    base = dict(fn.manifest)
    out: dict[str, Any] = {
        key: base[key]
        for key in ("format", "generator", "model", "modes", "hash", "versions", "compiler", "sources", "header",
                    "functions", "batch_chunk")
    }
    out["library"] = base.get("library")
    out["parameters"] = {"names": list(model.parameter_names), "values": model.parameters.tolist()}
    out["geometry"] = model.geometry.as_dict()
    out["mode_shapes"] = model.mode_family
    out["natural_frequencies_hz"] = model.natural_frequencies_hz.tolist()
    out["zeros"] = [[float(z.real), float(z.imag)] for z in model.zeros]
    out["n_unstable"] = model.n_unstable
    out["internal_dynamics"] = model.internal_dynamics
    out["CAB"] = float(model.CAB)
    return out


def export_model(model: Model, folder: Path, cache_hit: bool, started: float) -> ExportResult:
    """Copy a model's generated files into ``folder`` with a manifest.

    Copy the model's generated files from its cache entry into ``folder`` and write the manifest.

    Parameters
    ----------
    model : Model
        A loaded model (its functions come from a cache entry).
    folder : Path
        Destination (created).
    cache_hit : bool
        Whether loading the model reused a cache entry (reported).
    started : float
        ``time.perf_counter()`` when the work started (for the reported duration).
    """
    fn = model.compiled_functions
    if fn.folder is None:
        raise CodegenError("the model's generated files are not in the cache (compilation failed); nothing to export")
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):  # an existing read-only folder fails here
            pass
    except OSError as exc:
        raise CodegenError(f"cannot create and write {folder}: {exc.strerror}") from None
    manifest = export_manifest(model)
    names = list(manifest["sources"]) + [manifest["header"]]
    if manifest["library"]:
        names.append(manifest["library"])
    for name in names:
        # copy then rename: a library already loaded from `folder` keeps its (old) inode
        partial = folder / f".{name}.partial"
        shutil.copy2(fn.folder / name, partial)
        os.replace(partial, folder / name)
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return ExportResult(folder, names + ["manifest.json"], manifest, cache_hit, time.perf_counter() - started)

"""A run of ``sflm invert``, read back as it was judged: the table a controller holds, whatever the method.

``sflm invert --out RUN`` writes ``RUN/inversion.csv`` (the samples), ``RUN/summary.json`` (the figures, the settings,
the acceptance's record) and, in the summary, :func:`run_record`: one run id and the SHA-256 of every file the run
wrote. Every file is written under a temporary name and renamed (:func:`modelgen.files.replaced`), the summary last: its
rename is the moment the new run replaces the old. Until then the old summary stays in place, and the old run's files
are kept, linked, in ``RUN/.sflm-previous`` (:func:`keep_previous`), where :func:`read_run` finds them by their
checksums: a run killed at any moment leaves the old run or the new one, never a mix, and a folder whose files match
no summary is refused.

:func:`read_run` takes RUN as the folder, its ``summary.json`` or its ``inversion.csv`` and gives an
:class:`~inversion.result.InversionResult` whose feedforward is **the table the acceptance judged**: one row a period of
the controller (the summary's ``sampled`` period and hold), held over the period -- the rows of ``inversion.csv`` (a
point hold's values at the period's starts, a zero-order hold's means, an optimal-control table's values), bit for bit.
``simulation.simulate``, the exported C (:func:`~inversion.realtime.feedforward_c.export_c`) and the FMU take it as
they take any result, so that what ``invert`` judged is what each of them applies.
"""

from __future__ import annotations

import csv
import hashlib
import math
import os
import re
import shutil
import uuid
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np
from numpy.typing import NDArray

from modelgen.files import DocumentError, read_document
from modelgen.model import Model

from ..errors import SettingsError
from ..options import Hold
from ..options import values as choices
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form
from ..result import CSV_COLUMNS, SYSTEM_CSV_COLUMNS, InversionResult
from ..problem import paper_case
from ..signals.chebyshev import LINK_SIGNALS, SYSTEM_SIGNALS, held_values
from ..signals.trajectory import trajectory_from_spec

__all__ = ["read_run", "write_run", "run_record", "model_identity", "check_folder", "file_digest", "keep_previous", "forget_previous", "RUN_FILES", "PREVIOUS"]

FloatArray = NDArray[np.float64]
#: The files a run is read from.
RUN_FILES = ("summary.json", "inversion.csv")
#: The folder, inside a run's, where the files of the run being replaced are kept until the new summary lands.
PREVIOUS = ".sflm-previous"


#: The longest header line read from a table (a file of one long line is not read whole to find it is not a table).
MAX_HEADER = 65_536

def file_digest(path: str | Path) -> str:
    """The SHA-256 of a file's bytes (hex).

    Parameters
    ----------
    path : str or Path
        The file.
    """
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def model_identity(model: Any) -> dict[str, Any]:
    """What a run was computed for: the model and its digest.

    Its name, modes, output point and a digest of its linear model's values.

    The digest is the SHA-256 of the linear model's matrices (a link's ``A``, ``B``, ``C_out``; a system's ``A``, ``B``,
    ``C``): another link's values -- half the Young's modulus under the same name, a geometry file named like a preset --,
    another output point or another number of modes give another digest.

    Parameters
    ----------
    model : Model or LinearSystem
        The model.
    """
    digest = hashlib.sha256()
    for name in ("A", "B", "C_out" if isinstance(model, Model) else "C"):
        matrix = np.ascontiguousarray(np.asarray(getattr(model, name), dtype=float))
        digest.update(str(matrix.shape).encode())
        digest.update(matrix.tobytes())
    out: dict[str, Any] = {"name": str(getattr(model, "name", "")), "digest": digest.hexdigest()}
    if isinstance(model, Model):
        out.update(modes=int(model.n), output_at=float(model.output_at))
    return out


def run_record(files: list[Path], model: Any = None, command: str | None = None, trajectory: Any = None) -> dict[str, Any]:
    """The summary's ``run`` block: an id, its files, what it is of.

    A new run id, the SHA-256 of each file the run wrote (by name), the command that wrote it, the model it was computed
    for (:func:`model_identity`) and the SHA-256 of a move read from a file (its path: the summary's ``trajectory_spec``).

    Parameters
    ----------
    files : list of Path
        The files written before the summary.
    model : Model or LinearSystem, optional
        The model.
    command : str, optional
        The command (``invert``, ``simulate``, ...).
    trajectory : Trajectory, optional
        The move (a CSV file's is recorded by its digest).
    """
    record: dict[str, Any] = {"id": uuid.uuid4().hex, "files": {Path(p).name: file_digest(p) for p in files}}
    if command is not None:
        record["command"] = command
    if model is not None:
        record["model"] = model_identity(model)
    move = _move_file(getattr(trajectory, "spec", None))
    if move is not None and move.is_file():
        record["move"] = {"file": str(move), "sha256": file_digest(move)}
    return record


def _move_file(spec: Any) -> Path | None:
    """The CSV file a trajectory's spec reads (``FILE.csv[:smoothing=S]``), or ``None``."""
    if not isinstance(spec, str) or spec in ("paper-sim", "paper-exp") or spec.startswith("smoothstep:"):
        return None
    return Path(spec.rpartition(":smoothing=")[0] if ":smoothing=" in spec else spec)


def check_folder(folder: str | Path, command: str) -> None:
    """Refuse to write a run into a folder of another command's run.

    ``command``'s summary would replace the other's, and a reader of that run would find this one.

    Parameters
    ----------
    folder : str or Path
        The folder.
    command : str
        The command about to write there.

    Raises
    ------
    SettingsError
        Naming the command whose run is there.
    """
    try:
        document = read_document(Path(folder) / "summary.json", "json")
    except (DocumentError, OSError):
        return
    record = document.get("run") if isinstance(document, dict) else None
    there = record.get("command") if isinstance(record, dict) else None
    if isinstance(document, dict) and (document.get("status") == "refused" or there is None):
        there = document.get("command", there)  # a refusal's record, or a summary without a run's (sflm explore's)
    if isinstance(there, str) and there != command:
        raise SettingsError("out", str(folder), f"a folder for sflm {command}'s run: this one holds sflm {there}'s (its summary "
                                                "would be replaced); name another --out")


def _recorded(summary: Path) -> dict[str, str] | None:
    """The files (name: SHA-256) a summary.json records, or None (no summary, unreadable, or without a record)."""
    try:
        document = read_document(summary, "json")
    except (DocumentError, OSError):
        return None
    record = document.get("run") if isinstance(document, dict) else None
    files = record.get("files") if isinstance(record, dict) else None
    return {str(k): str(v) for k, v in files.items()} if isinstance(files, dict) else None


def keep_previous(folder: str | Path) -> None:
    """Keep the run in place, if whole, while a new one replaces it.

    Before a run's files are replaced: the run in place, if it is whole, kept in ``folder/.sflm-previous``.

    Its files are hard-linked there (copied where links are refused), so that a reader of the summary still in place
    finds them, by their checksums, while the new files replace them; :func:`forget_previous` drops them once the new
    summary is in place. A folder left half-replaced by a killed run keeps the copy it has (the whole run its summary
    names).

    Parameters
    ----------
    folder : str or Path
        The run's folder.
    """
    folder = Path(folder)
    files = _recorded(folder / "summary.json")
    if not files:
        return
    if not all((folder / name).is_file() and file_digest(folder / name) == digest for name, digest in files.items()):
        return  # not whole in place: what .sflm-previous holds is the run its summary names
    kept = folder / PREVIOUS
    shutil.rmtree(kept, ignore_errors=True)
    kept.mkdir()
    for name in files:
        try:
            os.link(folder / name, kept / name)
        except OSError:
            shutil.copy2(folder / name, kept / name)


def forget_previous(folder: str | Path) -> None:
    """Drop what :func:`keep_previous` kept.

    The new summary is in place.

    Parameters
    ----------
    folder : str or Path
        The run's folder.
    """
    shutil.rmtree(Path(folder) / PREVIOUS, ignore_errors=True)


def write_run(result: Any, folder: str | Path, *, table: str = "inversion.csv", progress: Callable[[int, int], None] | None = None,
              more: Callable[[Path], Iterable[Path]] | None = None, command: str = "invert") -> list[Path]:
    """Write a run: its table, then its summary with its record.

    Write a run: its table, what ``more`` writes beside it, then ``summary.json`` with the run's record.

    What ``sflm invert --out RUN`` writes and ``sflm simulate --feedforward RUN`` (:func:`read_run`) reads back. Each
    file is written under a temporary name and renamed, the summary last, the run it replaces kept meanwhile
    (:func:`keep_previous`): a run killed at any moment leaves the old run or the new one to a reader, never a mix. The
    summary's ``run`` block (:func:`run_record`) holds one id and each file's SHA-256.

    Parameters
    ----------
    result : InversionResult (or any result with ``write_csv``, ``write_summary`` and ``summary``)
        What to write.
    folder : str or Path
        The run's folder (created).
    table : str, optional
        The table's name (``inversion.csv``; a simulation's ``simulation.csv``).
    progress : callable, optional
        ``progress(rows_written, rows)`` while the table is written.
    more : callable, optional
        ``more(folder)`` writes further files of the run (figures) and returns their paths: recorded too.
    command : str, optional
        What wrote it (``invert``; a simulation's ``simulate``): recorded, and a folder holding another command's run is
        refused (:func:`check_folder`).

    Returns
    -------
    list of Path
        The table, ``summary.json`` and what ``more`` wrote.

    Examples
    --------
    >>> import modelgen, inversion, tempfile
    >>> result = inversion.invert(modelgen.load("paper-sim"), inversion.trajectory_from_spec("paper-sim"))
    >>> folder = tempfile.mkdtemp()
    >>> [p.name for p in inversion.write_run(result, folder)]
    ['inversion.csv', 'summary.json']
    >>> inversion.read_run(folder, result.model).summary["peak_torque"] == result.summary["peak_torque"]
    True
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    check_folder(folder, command)
    written = [folder / table]
    keep_previous(folder)
    result.write_csv(folder / table, progress)
    move = _write_move(result, folder)
    if move is not None:
        written.append(move)
    if more is not None:
        written += list(more(folder))
    result.summary["run"] = run_record(written, getattr(result, "model", None), command, getattr(result, "trajectory", None))
    result.write_summary(folder / "summary.json")
    forget_previous(folder)
    return [written[0], folder / "summary.json", *written[1:]]


#: The move's samples in a run whose move has no specification of its own (the fastest move's path).
MOVE_FILE = "move.csv"


def _write_move(result: Any, folder: Path) -> Path | None:
    """A move given by its samples (:func:`inversion.signals.trajectory.from_samples`), written into the run as
    ``move.csv`` (every digit: read back, the same spline), its specification (this file) the summary's
    ``trajectory_spec``; ``None`` for another move."""
    trajectory = getattr(result, "trajectory", None)
    samples = getattr(trajectory, "samples", None)
    if trajectory is None or samples is None:
        return None
    from modelgen.files import replaced

    path = folder / MOVE_FILE
    with replaced(path) as temporary:
        with open(temporary, "w", encoding="utf-8") as handle:
            handle.write("t,y\n")
            handle.writelines(f"{float(t)!r},{float(y)!r}\n" for t, y in zip(*samples))
    trajectory.spec = f"{path.resolve()}:smoothing=0.0"
    result.summary["trajectory_spec"] = trajectory.spec
    return path


def _whole(folder: Path, name: str, digest: str) -> Path | None:
    """The file ``name`` of the run whose summary records ``digest``: in place, or kept while a new run replaced it."""
    for path in (folder / name, folder / PREVIOUS / name):
        if path.is_file() and file_digest(path) == digest:
            return path
    return None


def _locate(run: str | Path) -> tuple[Path, Path]:
    """The summary and the samples of RUN (a folder, its ``summary.json`` or its ``inversion.csv``)."""
    path = Path(run)
    folder = path if path.is_dir() else path.parent
    if not path.is_dir() and path.name not in RUN_FILES:
        raise SettingsError("feedforward", str(run), "a folder sflm invert wrote (--out), its summary.json or its inversion.csv")
    summary, samples = folder / "summary.json", folder / "inversion.csv"
    for needed in (summary, samples):
        if not needed.is_file():
            raise SettingsError("feedforward", str(run), f"a run of sflm invert: {needed} is missing")
    return summary, samples


def read_run(run: str | Path, model: Model | LinearSystem) -> InversionResult:
    """The result a run of ``sflm invert`` wrote, as it was judged.

    Its feedforward is the table the acceptance judged.

    Parameters
    ----------
    run : str or Path
        The folder, its ``summary.json`` or its ``inversion.csv``.
    model : Model or LinearSystem
        The model it is of (its name must be the summary's).

    Returns
    -------
    InversionResult
        The samples held over the controller's period (``settings["hold"]`` ``"zoh"``: a held table), the summary as
        written (its ``run`` block included).

    Raises
    ------
    SettingsError
        For a run that is not whole (a file its summary does not name, or one changed since), of another model, or
        without a move to read back.
    """
    summary_path, samples_path = _locate(run)
    try:
        summary = read_document(summary_path, "json")
    except (DocumentError, OSError) as exc:
        raise SettingsError("feedforward", str(run), f"a readable summary.json ({exc})") from None
    if not isinstance(summary, dict):
        raise SettingsError("feedforward", str(run), "a summary.json of sflm invert")
    if summary.get("status") == "refused":
        raise SettingsError("feedforward", str(run), f"a run that returned a table (this one was refused: {summary.get('message', '')})")
    samples_path = _checked_record(run, summary, summary_path, samples_path, model)
    spec = summary.get("trajectory_spec")
    if not isinstance(spec, str):
        raise SettingsError("feedforward", str(run), "a summary that records its move (trajectory_spec)")
    _check_move(run, summary.get("run"), spec)
    trajectory = trajectory_from_spec(spec)
    link = isinstance(model, Model)
    columns = CSV_COLUMNS if link else SYSTEM_CSV_COLUMNS
    table = _read_table(samples_path, columns)
    sampled, settings = _block(run, summary, "sampled"), dict(_block(run, summary, "settings"))
    period = _recorded_period(run, sampled, settings)
    t = table["t"]
    if t.size < 2:
        raise SettingsError("feedforward", str(run), "an inversion.csv of two rows at least")
    spacing = float(np.median(np.diff(t)))
    every = int(round(period / spacing))
    if every < 1 or abs(every * spacing - period) > 1e-6 * period:
        raise SettingsError("feedforward", str(run), f"samples every controller's period ({period:g} s) or a whole fraction of it "
                            f"(inversion.csv's are {spacing:g} s apart)")
    keep = np.arange(0, t.size, every)
    # the rows the acceptance judged: its count where the summary records it, else one a period until the move ends
    count = sampled.get("samples")
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        count = max(1, math.ceil((max(trajectory.tf, float(t[0])) - float(t[0])) / period - 1e-9))
    if count > keep.size:
        raise SettingsError("feedforward", str(run), f"an inversion.csv of the {count} rows its summary judged ({keep.size} at "
                            f"{period:g} s)")
    keep = keep[:count]
    rows = {k: v[keep] for k, v in table.items()}
    _check_desired(run, trajectory, spec, rows)
    names = LINK_SIGNALS if link else SYSTEM_SIGNALS
    values = np.column_stack([rows[n] for n in (("tau", "theta_d", "thetadot_d") if link else ("u",))])
    signals = held_values(names, float(rows["t"][0]), period, values)
    form = normal_form(model)
    held_from = sampled.get("hold", settings.get("hold", "point"))
    if held_from not in choices(Hold):
        raise SettingsError("feedforward", str(run), f"a summary whose hold is one of {' or '.join(map(repr, choices(Hold)))} (this one "
                                                     f"records {str(held_from)[:40]!r})")
    settings.update(period=period, hold="zoh", rate=1.0 / period, held_from=held_from)
    # what the run is of, from the model its digest matched (a summary's own words for it are not trusted: issue 59, item 6)
    identity: dict[str, Any] = ({"model": model.name, "modes": model.n, "mode_shapes": model.mode_family, "output_at": model.output_at}
                                if link else {"model": getattr(model, "name", summary.get("model")), "system": model.report()})
    summary = {**summary, **identity, "settings": settings}
    X = np.zeros((rows["t"].size, form.n_states))
    if link:
        n1 = form.n_states // 2
        X[:, 0], X[:, n1] = rows["theta_d"], rows["thetadot_d"]
    result = InversionResult(t=rows["t"], y_d=rows["y_d"], y=rows["y_redef"], ydot=rows["ydot_redef"], yddot=rows["yddot_redef"],
                             X=X, tau=values[:, 0], theta_d=rows.get("theta_d"), thetadot_d=rows.get("thetadot_d"),
                             summary=summary,  # type: ignore[arg-type]
                             model=model, trajectory=trajectory, modal=form.modal(0.0), signals=signals)
    return replace(result, case=paper_case(model, trajectory) if link else None)


def _block(run: str | Path, summary: dict[str, Any], key: str) -> dict[str, Any]:
    """The summary's ``key`` block (``sampled``, ``settings``): a mapping, or empty when absent; else refused."""
    block = summary.get(key)
    if block is None:
        return {}
    if not isinstance(block, dict):
        raise SettingsError("feedforward", str(run), f"a summary.json of sflm invert (its {key!r} is a {type(block).__name__}, "
                                                     "not a mapping): run sflm invert again")
    return block


def _recorded_period(run: str | Path, sampled: dict[str, Any], settings: dict[str, Any]) -> float:
    """The controller's period the run was judged at: ``sampled.period``, else ``settings.period``, else ``1/settings.rate``
    (1 kHz when none is recorded); each a finite number > 0, else refused naming the key."""
    for where, block, key in (("sampled", sampled, "period"), ("settings", settings, "period"), ("settings", settings, "rate")):
        value = block.get(key)
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value < math.inf:
            raise SettingsError("feedforward", str(run), f"a summary whose {where}.{key} is a finite number > 0 (this one records "
                                                         f"{str(value)[:40]!r}): run sflm invert again")
        return float(value) if key == "period" else 1.0 / float(value)
    return 1.0 / 1000.0


def _checked_record(run: str | Path, summary: dict[str, Any], summary_path: Path, samples_path: Path, model: Any) -> Path:
    """The run's record checked (its files whole, its command, its model): the samples' path (in place, or kept while a
    new run replaced them)."""
    record = summary.get("run")
    files = record.get("files") if isinstance(record, dict) else None
    if not isinstance(files, dict) or samples_path.name not in files:
        raise SettingsError("feedforward", str(run), "a run whose summary.json records its files (the 'run' block with "
                            "inversion.csv's SHA-256): this one records none (written before sflm kept the record, or edited): "
                            "run sflm invert again")
    for name, digest in files.items():
        if not (isinstance(name, str) and name == Path(name).name and name not in ("", ".", "..")
                and isinstance(digest, str) and re.fullmatch(r"[0-9a-f]{64}", digest)):
            raise SettingsError("feedforward", str(run), f"a run record of the run's own file names and their SHA-256 ({name!r} "
                                f"is not): run sflm invert again")
        found = _whole(summary_path.parent, name, digest)
        if found is None:
            raise SettingsError("feedforward", str(run), f"a whole run: {name} is not the one its summary.json records (a file "
                                "changed or removed since): run sflm invert again")
        if name == samples_path.name:
            samples_path = found
    command = record.get("command")  # type: ignore[union-attr]
    if command is not None and command != "invert":
        raise SettingsError("feedforward", str(run), f"a run of sflm invert (this one is sflm {command}'s)")
    name = getattr(model, "name", None)
    if isinstance(summary.get("model"), str) and name is not None and summary["model"] != name:
        raise SettingsError("feedforward", str(run), f"a run of {name}'s (this summary is of model {summary['model']})")
    _check_identity(run, record.get("model"), model)  # type: ignore[union-attr]
    return samples_path


def _check_move(run: str | Path, record: Any, spec: str) -> None:
    """Refuse a run whose move's CSV changed since (its record keeps the file's SHA-256)."""
    move = _move_file(spec)
    if move is not None:
        kept = record.get("move") if isinstance(record, dict) else None
        if not (isinstance(kept, dict) and kept.get("file") == str(move) and move.is_file() and kept.get("sha256") == file_digest(move)):
            raise SettingsError("feedforward", str(run), f"a run whose move is the one it was computed for: {move} is not the file "
                                "its summary records (changed or removed since): run sflm invert again")


#: The table's ``y_d`` and the summary's move agree to this share of the move (the table keeps every digit; a spline
#: read again from its file, or a move evaluated on another machine, differs by rounding).
_DESIRED_TOLERANCE = 1e-9


def _check_desired(run: str | Path, trajectory: Any, spec: str, rows: dict[str, FloatArray]) -> None:
    """Refuse a run whose summary's move (``trajectory_spec``) is not the one its table was computed for: the table's
    ``y_d`` column (the table's SHA-256 is recorded) against the move the summary names, at the table's times (the
    summary itself is not checksummed: an edited move would be judged against a table it was never planned for)."""
    t, recorded = rows["t"], rows["y_d"]
    expected = np.asarray(trajectory.derivative(np.clip(t, trajectory.t0, trajectory.tf), 0), dtype=float)
    scale = max(abs(float(trajectory.move())), float(np.abs(recorded).max(initial=0.0)), 1e-300)
    worst = float(np.abs(expected - recorded).max(initial=0.0)) / scale
    if not worst <= _DESIRED_TOLERANCE:
        raise SettingsError("feedforward", str(run), f"a run whose summary names the move its table was computed for: "
                            f"{spec[:80]!r} differs from the table's y_d by {worst:.3g} of the move (the summary edited, or "
                            "another run's): run sflm invert again")


def _check_identity(run: str | Path, kept: Any, model: Any) -> None:
    """Refuse a run computed for another model than ``model``: another output point, other modes, other values."""
    if not (isinstance(kept, dict) and isinstance(kept.get("digest"), str)):
        raise SettingsError("feedforward", str(run), "a run that records the model it was computed for (the 'run' block's "
                                                     "'model': its name, modes, output point and digest): this one does not "
                                                     "(written before sflm kept it, or edited): run sflm invert again")
    now = model_identity(model)
    for key, words in (("output_at", "the output at {} m"), ("modes", "{} modes")):
        if key in kept and key in now and kept[key] != now[key]:
            raise SettingsError("feedforward", str(run), f"a run of this model: it was computed for {words.format(kept[key])}, "
                                                         f"the model has {words.format(now[key])}")
    if kept.get("digest") != now["digest"]:
        raise SettingsError("feedforward", str(run), "a run of this model: it was computed for a model of other values (its "
                                                     "linear model's digest differs: another geometry under the same name, or the "
                                                     "file changed since): run sflm invert again")


def _read_table(path: Path, columns: tuple[str, ...]) -> dict[str, FloatArray]:
    """The columns of ``inversion.csv`` (its header must name them)."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:
            header = [h.strip() for h in next(csv.reader([handle.readline(MAX_HEADER)]), [])]
            missing = [c for c in columns if c not in header]
            if missing:
                raise SettingsError("feedforward", str(path), f"an inversion.csv with the columns {', '.join(columns)} "
                                    f"({', '.join(missing)} missing)")
            index = [header.index(c) for c in columns]
            # NumPy's parser (issue 59, item 10: rows parsed into Python lists took 5.6 GB and 82 CPU-s for a 1.8 GB run)
            data = np.loadtxt(handle, delimiter=",", usecols=index, ndmin=2, dtype=float, comments=None)
    except UnicodeDecodeError:
        raise SettingsError("feedforward", str(path), "an inversion.csv of text (UTF-8), as sflm invert writes it") from None
    except (ValueError, IndexError):
        raise SettingsError("feedforward", str(path), "an inversion.csv of numbers, a row for every time") from None
    if data.ndim != 2 or data.shape[1] != len(columns) or not np.all(np.isfinite(data)):
        raise SettingsError("feedforward", str(path), "an inversion.csv of finite numbers")
    return {c: data[:, k] for k, c in enumerate(columns)}

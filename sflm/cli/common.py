"""What the commands share besides their arguments: the model and move they name, the folder they write, the run they
read, the Dask client, a refusal as JSON."""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, Sequence
from .flags import FLAGS


def load_model(args: argparse.Namespace, system: bool = True) -> Any:
    """The model the command's MODEL, --modes, --mode-shapes and --output-at describe: a link, or (where ``system``) a
    transfer function in ``s`` or a file of one (:mod:`sflm.systems`)."""
    import modelgen

    from ..systems import looks_like_transfer_function, system_from_model_argument, transfer_function_file

    if looks_like_transfer_function(args.model) or transfer_function_file(args.model):
        from modelgen.errors import SettingsError

        if not system:
            raise SettingsError("MODEL", args.model, f"a preset or a geometry file for sflm {args.command} (it is about a link's "
                                "model; a transfer function goes to invert, explore, compare and info)")
        for option, value in (("--modes", args.modes), ("--mode-shapes", args.mode_shapes), ("--output-at", args.output_at)):
            if value is not None:
                raise SettingsError(option, value, "nothing for a transfer function (it is about a link's assumed modes)")
        return system_from_model_argument(args.model)
    if hasattr(args, "reporter"):
        args.reporter(f"loading {args.model} (derived, generated and compiled the first time, then cached)")
    model = modelgen.load(args.model, modes=args.modes, mode_shapes=args.mode_shapes, output_at=args.output_at)
    if hasattr(args, "reporter"):  # the line no longer says "loading" once the work after it starts (issue 59, item 12)
        args.reporter(f"{args.model} loaded; sflm {args.command} at work")
    return model






def inputs_of(args: argparse.Namespace) -> list[Path]:
    """The files and folders a command reads: its model's file, ``--data``, ``--feedforward`` (a run's folder), a move's
    CSV, ``--settings`` -- each resolved (symbolic links followed)."""
    out = []
    for name in ("model", "data", "feedforward", "trajectory", "settings"):
        value = getattr(args, name, None)
        if not isinstance(value, str) or not value:
            continue
        path = Path(value.rpartition(":smoothing=")[0] if ":smoothing=" in value else value)
        try:
            if not path.exists():
                continue
            resolved = path.resolve()
        except (OSError, ValueError):
            continue
        out.append(resolved.parent if name == "feedforward" and resolved.is_file() else resolved)
    return out


def check_out(args: argparse.Namespace, path: Path) -> None:
    """Refuse an ``--out`` that is, or resolves to, what the command reads (a measurement, a run, the model's file), or
    that is a symbolic link (written through, it replaced the file it points to).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    path : Path
        The file or folder ``--out`` names.
    """
    from modelgen.errors import SettingsError

    if path.is_symlink():
        raise SettingsError("--out", str(path), f"a path that is not a symbolic link (it points to {os.readlink(path)}: "
                            "writing through it replaces that file)")
    try:
        target = path.resolve()
    except (OSError, ValueError):
        return
    for read in inputs_of(args):
        if target == read or (read.is_dir() and target.is_relative_to(read) and target.name in ("summary.json", "inversion.csv")):
            raise SettingsError("--out", str(path), f"a place other than what the command reads ({read}: it would be replaced)")


def _out_path(args: argparse.Namespace, name: str, what: str) -> Path:
    """The folder ``--out`` names, or the default ``sflm-out/NAME/WHAT``."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name).strip("._") or "system"  # '(2-s)/(s+1)^3' too
    return Path(args.out) if args.out else Path("sflm-out") / safe / what


def _writable(folder: Path, flag: str = "--out", accepted: str = "a folder that can be created and written") -> None:
    """Refuse a folder that cannot be written (a file is created in it and removed), naming ``flag``."""
    try:
        with tempfile.TemporaryFile(dir=folder):  # an existing read-only folder fails here, before any work is lost
            pass
    except OSError as exc:
        from modelgen.errors import SettingsError

        raise SettingsError(flag, str(folder), f"{accepted} ({exc.strerror})") from None


def output_folder(args: argparse.Namespace, name: str, what: str) -> Path:
    """The run's folder (:func:`_out_path`), checked (:func:`check_out`), created and written to once.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    name : str
        The model's name (the default folder's).
    what : str
        The command (the default folder's last part).
    """
    folder = _out_path(args, name, what)
    check_out(args, folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        from modelgen.errors import SettingsError

        raise SettingsError("--out", str(folder), f"a folder that can be created and written ({exc.strerror})") from None
    _writable(folder)
    return folder


def check_out_before_work(args: argparse.Namespace, name: str, what: str) -> None:
    """Refuse, before the command's work, an ``--out`` it would refuse after it.

    What :func:`output_folder` and the run's writer (:func:`inversion.realtime.runs.write_run`) refuse once the work is
    done, asked before it and nothing created: a place the command reads (:func:`check_out`), a folder holding another
    command's run (:func:`inversion.realtime.runs.check_folder`), a file, an existing folder that cannot be written. ``sflm
    simulate --feedforward RUN --out RUN`` simulated for 3-5 s before refusing; now it refuses at once.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    name : str
        The model's name (the default folder's).
    what : str
        The command (the default folder's last part).
    """
    from inversion.realtime.runs import check_folder
    from modelgen.errors import SettingsError

    folder = _out_path(args, name, what)
    check_out(args, folder)
    try:
        check_folder(folder, args.command)
    except SettingsError as exc:
        raise SettingsError("--out", exc.value, exc.accepted) from None
    if folder.exists() and not folder.is_dir():
        raise SettingsError("--out", str(folder), "a folder that can be created and written (a file is there)")
    if folder.is_dir():
        _writable(folder)


def check_exports_before_work(args: argparse.Namespace) -> None:
    """Refuse, before the inversion, an ``--export-c`` or ``--export-table`` its writer would refuse after it.

    ``--export-c`` names a folder (a file there is refused, an existing folder must be writable); ``--export-table`` a
    file (a folder there is refused, an existing parent folder must be writable). The writers
    (:func:`inversion.realtime.feedforward_c.export_c`, :func:`~inversion.realtime.feedforward_c.export_table`) refuse
    the same after the work: a 5 s inversion of the aluminium link was lost to a misspelt path.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from modelgen.errors import SettingsError

    if args.export_c:
        folder = Path(args.export_c)
        if folder.exists() and not folder.is_dir():
            raise SettingsError("--export-c", args.export_c, "a folder that can be created and written (a file is there)")
        if folder.is_dir():
            _writable(folder, "--export-c")
    if args.export_table:
        path = Path(args.export_table)
        if path.is_dir():
            raise SettingsError("--export-table", args.export_table, "a file that can be written (a folder is there)")
        if path.parent.is_dir():
            _writable(path.parent, "--export-table", "a file that can be written")


def uncertainty_of(args: argparse.Namespace, model: Any = None) -> Any:
    """``--uncertainty SPEC`` (and ``--samples``) parsed and checked against ``model``, or ``None``."""
    from inversion.studies.robustness import parse_uncertainty
    from modelgen.errors import SettingsError

    if args.uncertainty is None:
        if args.samples:
            raise SettingsError("--samples", args.samples, "0 without --uncertainty (the samples are of its ranges)")
        return None
    parsed = parse_uncertainty(args.uncertainty, args.samples)
    if model is not None:
        parsed.check(model)  # before the work: a transfer function, or a key that is zero in the geometry
    return parsed


def dask_client(address: str) -> Any:
    """A client of the Dask scheduler at ``address`` (one line and exit 2 if there is none)."""
    from modelgen.errors import SettingsError

    try:
        from distributed import Client
    except ImportError:
        raise SettingsError("--scheduler", address, "an installed Dask distributed (pip install 'sflm[dask]')") from None
    fault = scheduler_fault(address)  # Dask retries a refused address for its whole timeout, and trusts what a stranger sends
    if fault is not None:
        raise SettingsError("--scheduler", address, f"the address of a running Dask scheduler ({fault})")
    try:
        return Client(address, timeout=10)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SettingsError("--scheduler", address, f"the address of a running Dask scheduler ({exc.__class__.__name__})") from None


#: Seconds a TCP peer has to send its first bytes: a Dask scheduler writes its handshake as soon as it accepts.
SCHEDULER_GREETING = 5.0


#: Largest first message a Dask scheduler sends (its handshake is a few hundred bytes).
_GREETING_BYTES = 1 << 20


def scheduler_fault(address: str, timeout: float = SCHEDULER_GREETING) -> str | None:
    """Why the TCP address ``address`` (``tcp://host:port`` or ``host:port``) is not a Dask scheduler, or ``None``.

    A Dask scheduler answers a connection at once with its handshake, framed as Dask's TCP
    comm frames it: eight bytes giving the length of what follows. A closed port refuses; a
    web server sends nothing until asked (Dask would wait for it without end) or answers
    ``HTTP/1.1 ...`` (whose first eight bytes Dask would read as a length of exbibytes and
    try to allocate). Other schemes, and addresses this machine cannot reach now, are left to
    Dask's own timeout.
    """
    import socket
    import struct
    from urllib.parse import urlsplit

    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:  # a port that is not a number: Dask names the fault
        return None
    if parts.scheme != "tcp" or host is None or port is None:
        return None
    try:
        connection = socket.create_connection((host, port), timeout=2)
    except ConnectionRefusedError:
        return "the connection was refused"
    except OSError:  # unreachable or slow: Dask's timeout decides
        return None
    with connection:
        connection.settimeout(timeout)
        received = b""
        try:
            while len(received) < 8:
                chunk = connection.recv(8 - len(received))
                if not chunk:
                    break
                received += chunk
        except (TimeoutError, OSError):
            pass
    if not received:
        return f"the service there sent nothing in {timeout:g} s: not a Dask scheduler"
    length = struct.unpack("Q", received)[0] if len(received) == 8 else 0
    if not 0 < length <= _GREETING_BYTES:
        shown = received.decode("ascii", "replace")
        return f"the service there answered {shown!r}, not a Dask handshake"
    return None


def emit(args: argparse.Namespace, result: Any, folder: Path, csv_name: str, plot: str, text: Any,
          extra: Sequence[str] = ()) -> int:
    """Write the run (:func:`inversion.realtime.runs.write_run`: ``csv_name``, the figures of :mod:`sflm.plots`'s ``plot``
    with ``--plot``, then ``summary.json`` with the run's record); print the summary.

    Each file is written under a temporary name and renamed, the summary last, the run it replaces kept meanwhile: a run
    killed at any moment leaves the old run or the new one to a reader (:func:`inversion.realtime.runs.read_run`), never
    a mix; a folder holding another command's run is refused before anything is written there."""
    from inversion.realtime.runs import write_run
    from modelgen.errors import SettingsError

    def figures(where: Path) -> list[Path]:
        if not args.plot:
            return []
        args.reporter("drawing the figures")
        from .. import plots  # matplotlib only when plotting (0.35 s to import)

        return list(getattr(plots, plot)(result, where))

    try:
        with args.reporter.stage(f"writing {csv_name}", unit="rows") as bar:
            written = write_run(result, folder, table=csv_name, progress=bar, more=figures, command=args.command)
    except SettingsError as exc:
        if exc.parameter == "out":
            raise SettingsError("--out", exc.value, exc.accepted) from None
        raise
    except OSError as exc:  # a full disk, a folder gone read-only: the folder the user chose is named, not a bare errno
        raise SettingsError("--out", str(folder), f"a folder with room for {csv_name} and summary.json "
                            f"({exc.strerror or exc})") from None
    files = [str(written[0]), str(written[1]), *extra, *(str(p) for p in written[2:])]
    print(json.dumps(result.summary, indent=1) if args.json else text(result, files))
    return 0


def is_run(path: str) -> bool:
    """Whether ``path`` names a run of ``sflm invert``: its folder, or its ``summary.json`` or ``inversion.csv`` beside the
    other."""
    run = Path(path)
    if run.is_dir():
        return True
    return run.name in ("summary.json", "inversion.csv") and (run.parent / "summary.json").is_file() and (
        run.parent / "inversion.csv").is_file()


def read_feedforward(args: argparse.Namespace, model: Any) -> Any:
    """The result ``--feedforward RUN`` names (:func:`inversion.realtime.runs.read_run`), refusing the inversion's own
    arguments beside it (the run holds its move and its settings)."""
    from inversion.realtime.runs import read_run
    from modelgen.errors import SettingsError

    given = [flag for flag, name in (("--trajectory", "trajectory"), ("--segments", "segments"), ("--h", "h"), ("--cdec", "cdec"),
                                     ("--settings", "settings"), ("--method", "method"), ("--max-error", "max_error"),
                                     ("--period", "period"), ("--hold", "hold"), ("--auto", "auto"), ("--end", "end"))
             if getattr(args, name, None) not in (None, False)]
    if given:
        raise SettingsError(given[0], getattr(args, given[0].lstrip("-").replace("-", "_")), "nothing with --feedforward RUN "
                            "(the run holds its move, its settings and the table it was judged with)")
    args.reporter(f"reading the run {args.feedforward}")
    try:
        return read_run(args.feedforward, model)
    except SettingsError as exc:
        if exc.parameter == "feedforward":
            raise SettingsError("--feedforward", exc.value, exc.accepted) from None
        raise


def refusal_record(command: str | None, error: str, message: str) -> dict[str, Any]:
    """The keys every ``--json`` refusal starts with (scripts read them: ``status``, ``command``, ``message``,
    ``error``)."""
    return {"status": "refused", "command": command, "message": message, "error": error}


def refusal_json(args: argparse.Namespace, exc: Exception, message: str) -> None:
    """A refusal as a result (``--json``): one JSON object on stdout, and the same as ``summary.json`` in the folder the
    command would have written (where it names one and can write it)."""
    from inversion.realtime.runs import forget_previous, run_record

    record = refusal_record(args.command, type(exc).__name__, message)
    parameter = getattr(exc, "parameter", None)
    if parameter is not None:
        record["parameter"] = FLAGS.get(parameter, parameter)
    for key in ("status", "causal_limit", "bounded_limit", "stages", "record"):
        value = getattr(exc, key, None)
        if value is not None:
            record["reason" if key == "status" else "search" if key == "record" else key] = value
    search = record.get("search")
    if isinstance(search, dict):
        record.setdefault("reason", "no-member")  # the family's search: no member passed
        if search.get("alternatives"):
            record["nearest"] = search["alternatives"]
    text = json.dumps(record, indent=1, default=str)
    print(text)
    out = getattr(args, "out", None)
    if out and args.command in ("invert", "simulate", "compare", "explore"):
        folder = Path(out)
        if _holds_a_run(folder) or folder.is_symlink() or any(folder.resolve() == read for read in inputs_of(args)):
            return  # a refusal does not replace a good run (nor anything the command reads): stdout has the record
        try:
            folder.mkdir(parents=True, exist_ok=True)
            from modelgen.files import write_json

            write_json(folder / "summary.json", {**json.loads(text), "run": run_record([], command=args.command)})
            forget_previous(folder)
        except OSError:
            pass  # the folder cannot be written: stdout has the record


def _holds_a_run(folder: Path) -> bool:
    """Whether ``folder`` holds a run that returned a result (its summary not a refusal's)."""
    try:
        document = json.loads((folder / "summary.json").read_text())
    except (OSError, ValueError):
        return False
    return isinstance(document, dict) and document.get("status") != "refused"


def silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass

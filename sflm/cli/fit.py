"""``sflm fit``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any
from .common import check_out, output_folder
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm fit tests/data/glass-fibre-rod.toml --data tests/data/bench-doublet.csv --plot"


def add(sub: Any) -> None:
    """Add ``sflm fit``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    fit = sub.add_parser("fit", help="calibrate a geometry file to what was measured on the bench: natural frequencies, a "
                                     "frequency response or a time series")
    fit.add_argument("model", metavar="GEOMETRY", help="the nominal geometry .toml file (or a preset)")
    fit.add_argument("--data", required=True, metavar="FILE", help="frequencies (.toml: frequencies_hz = [...], boundary = "
                     "'hub-free' or 'hub-clamped'), a frequency response (.csv: f,magnitude,phase in Hz, absolute, degrees) or "
                     "a time series (.csv: t,tau,theta[,y], open loop from rest)")
    fit.add_argument("--params", metavar="LIST", help="the dotted names to fit, comma-separated (default: link.flexural_rigidity, "
                     "payload.mass, payload.inertia, hub.inertia, damping.ratio -- with [damping] modal, damping.modal_K for "
                     "each mode K the data reaches -- less those zero in the geometry or that the data's noise hides)")
    fit.add_argument("--held-spread", metavar="SPEC", help="how far a parameter held at its nominal value may be from the link's "
                     "(relative, 95 %%), e.g. payload.mass=1%%,hub.inertia=10%% (0 for a value known exactly; default: each "
                     "assumed within 30 %%, said so in the report); its part enters every fitted interval")
    fit.add_argument("--output", choices=("theta", "y"), help="a frequency response's output: the hub angle (default) or the tip")
    fit.add_argument("--kp", type=float, metavar="KP", help="a closed-loop record's (t,tau_ff,theta_d,theta[,y]) joint PD gain k_P")
    fit.add_argument("--kd", type=float, metavar="KD", help="a closed-loop record's joint PD gain k_D")
    fit.add_argument("--modes", type=int, metavar="N", help="number of assumed modes (default: the geometry's)")
    fit.add_argument("--out", metavar="FILE", help="the calibrated geometry file to write (default sflm-out/<name>/fit/<name>-calibrated.toml)")
    fit.add_argument("--json", action="store_true", help="print the fit's figures as JSON")
    fit.add_argument("--plot", action="store_true", help="write fit.png beside the calibrated file: measured, nominal and fitted")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm fit``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from modelgen.fit import calibrated_toml, fit_file, held_spreads
    from modelgen.geometry import load_geometry

    from ..summaries import fit_text

    from modelgen.errors import SettingsError
    from modelgen.files import replaced

    nominal = load_geometry(args.model).with_model(args.modes)
    if args.out:  # before the fit: a measurement or a model replaced by the calibration would be lost
        check_out(args, Path(args.out))
        if Path(args.out).is_dir():
            raise SettingsError("--out", args.out, "a file to write (the calibrated geometry .toml), not a folder")
        _writable(Path(args.out))  # and a place it can be written, before the fit's seconds (issue 59, item 13)
    params = None if args.params is None else [p.strip() for p in args.params.split(",") if p.strip()]
    law = None if args.kp is None and args.kd is None else (args.kp, args.kd)
    spreads = None if args.held_spread is None else held_spreads(args.held_spread)
    args.reporter(f"fitting {nominal.name} to {Path(args.data).name} (least squares over the model's response)")
    result = fit_file(nominal, args.data, params, args.output, law, spreads)
    path = Path(args.out) if args.out else output_folder(args, nominal.name, "fit") / f"{nominal.name}-calibrated.toml"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        if args.plot:  # the figure beside it is the previous calibration's: gone before the new file (a kill between the
            (path.parent / "fit.png").unlink(missing_ok=True)  # two left the new calibration beside the old figure)
        with replaced(path) as temporary:  # written whole under another name, then renamed: never half a file
            temporary.write_text(calibrated_toml(result, Path(args.data).name))
    except OSError as exc:
        raise SettingsError("--out", str(path), f"a file that can be written ({exc.strerror or exc})") from None
    files = [str(path)]
    if args.plot:
        from ..plots import fit_figure

        files.append(str(fit_figure(result, args.data, args.output, path.parent / "fit.png", law)))
    if args.json:
        print(json.dumps({**result.summary(), "files": files}, indent=1))
    else:
        print(fit_text(result, files))
    return 0


def _writable(path: Path) -> None:
    """Refuse (``--out``) a file whose folder cannot be made or written: the folder made, a file tried in it."""
    import tempfile

    from modelgen.errors import SettingsError

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".sflm-fit-", suffix=".probe"):
            pass
    except OSError as exc:
        raise SettingsError("--out", str(path), f"a file that can be written ({exc.strerror or exc})") from None

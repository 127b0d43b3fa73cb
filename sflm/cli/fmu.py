"""``sflm fmu``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any
from .arguments import TRAJECTORY_HELP_SHORT, add_model_arguments, trajectory_of
from .common import check_out, is_run, load_model, output_folder, read_feedforward
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm fmu tests/data/own-aluminium.toml --feedforward run --out link.fmu"


def add(sub: Any) -> None:
    """Add ``sflm fmu``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    fmu = sub.add_parser("fmu", help="the model as an FMI 2.0 model-exchange FMU (input tau; outputs y, theta, thetadot, the "
                                     "deflections), or with --feedforward the feedforward of a summary.json")
    add_model_arguments(fmu)
    fmu.add_argument("--plant", choices=("linear", "nonlinear"), default="nonlinear",
                     help="the right-hand side the FMU integrates: linear (P8) or nonlinear (default): P4 with the geometric stiffening")
    fmu.add_argument("--feedforward", metavar="RUN", help="an FMU of the feedforward itself (time in; tau, theta_d, thetadot_d "
                     "out): the table a run of sflm invert judged (its --out folder, summary.json or inversion.csv: any method), "
                     "or the member of an explore best.json, inverted again for MODEL")
    fmu.add_argument("--trajectory", metavar="SPEC", help="with --feedforward: " + TRAJECTORY_HELP_SHORT)
    fmu.add_argument("--out", metavar="FILE", help="the .fmu to write (default sflm-out/<name>/fmu/<name>.fmu, or <name>-feedforward.fmu)")
    fmu.add_argument("--json", action="store_true", help="print what the FMU holds as JSON")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm fmu``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from modelgen.errors import SettingsError

    model = load_model(args, system=False)
    if args.trajectory is not None and args.feedforward is None:
        raise SettingsError("--trajectory", args.trajectory, "nothing without --feedforward (the plant's FMU takes tau as its input)")
    stem = model.name + ("-feedforward" if args.feedforward else "")
    path = Path(args.out) if args.out else output_folder(args, model.name, "fmu") / f"{stem}.fmu"
    check_out(args, path)
    args.reporter(f"building the FMU of {model.name}")
    if args.feedforward is None:
        from modelgen.fmu import build_fmu

        written = build_fmu(model, path, args.plant)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "modes": model.n,
                "plant": args.plant, "parameters": len(model.parameters), "states": 2 * (model.n + 1), "inputs": ["tau"],
                "outputs": ["y", "theta", "thetadot", *[f"delta_{j}" for j in range(1, model.n + 1)]]}
    elif is_run(args.feedforward):
        from inversion.realtime.feedforward_fmu import build_feedforward_fmu

        result = read_feedforward(args, model)
        written = build_feedforward_fmu(result, path)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "feedforward": True,
                "run": result.summary.get("run", {}).get("id"), "method": result.summary.get("method", "ssef"),
                "period": result.summary["settings"]["period"], "hold": result.summary["settings"]["held_from"],
                "span": [float(result.signals.bounds[0]), float(result.signals.bounds[-1])] if result.signals is not None else None,
                "peak_torque": result.summary["peak_torque"], "inputs": [], "outputs": ["tau", "theta_d", "thetadot_d"]}
    else:
        from inversion import Family, Problem, invert
        from inversion.realtime.feedforward_fmu import build_feedforward_fmu
        from modelgen.files import DocumentError, read_document

        try:
            summary = read_document(args.feedforward, "json")
        except OSError as exc:
            raise SettingsError("--feedforward", args.feedforward, f"a readable file ({exc.strerror})") from None
        except DocumentError as exc:
            raise SettingsError("--feedforward", args.feedforward, f"a summary.json of sflm invert (or a best.json of explore); "
                                f"this one is {exc}") from None
        if not isinstance(summary, dict):
            raise SettingsError("--feedforward", args.feedforward, "a summary.json of sflm invert (or a best.json of explore)")
        if isinstance(summary.get("run"), dict):  # a run's summary without its table: never another table in its name
            table = Path(args.feedforward).parent / "inversion.csv"
            raise SettingsError("--feedforward", args.feedforward, f"a run of sflm invert with its table ({table} is missing: "
                                "the summary vouches for the table it records, and inverting again would give another)")
        of = summary.get("model")
        if isinstance(of, str) and of != model.name:  # another model's: said before anything is inverted with it
            raise SettingsError("--feedforward", args.feedforward, f"a summary of {model.name}'s (this summary is of model {of})")
        if args.trajectory is None and isinstance(summary.get("trajectory_spec"), str):
            args.trajectory = summary["trajectory_spec"]  # the summary says what it inverted
        args.reporter(f"inverting the member of {args.feedforward} again for {model.name} (the file holds its settings, not a table)")
        try:
            result = invert(Problem(model, trajectory_of(args, model.name)), method=Family(settings=args.feedforward))
        except SettingsError as exc:  # the settings are the file given as --feedforward
            if exc.parameter == "settings":
                raise SettingsError("--feedforward", args.feedforward, exc.accepted) from None
            raise
        expected = summary.get("peak_torque")
        if isinstance(expected, (int, float)) and abs(result.summary["peak_torque"] - expected) > 1e-9 * max(abs(expected), 1e-300):
            raise SettingsError("--feedforward", args.feedforward, f"the summary of a member of {model.name} on this trajectory (inverted "
                                f"again its peak torque is {result.summary['peak_torque']:.9g} N m, the file's {expected:.9g})")
        written = build_feedforward_fmu(result, path)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "feedforward": True,
                "inverted_again": True,
                "span": [float(result.signals.bounds[0]), float(result.signals.bounds[-1])] if result.signals is not None else None,
                "peak_torque": result.summary["peak_torque"], "inputs": [], "outputs": ["tau", "theta_d", "thetadot_d"]}
    if args.json:
        print(json.dumps(held, indent=1))
    else:
        what = ("the feedforward (outputs tau, theta_d, thetadot_d; peak {:.4g} N m{})".format(
                    held["peak_torque"], "; the member of the file given, inverted again" if held.get("inverted_again") else "")
                if args.feedforward
                else f"{held['modes']} modes, {held['plant']} plant: {held['states']} states, {held['parameters']} parameters, input tau, "
                     f"outputs {', '.join(held['outputs'])}")
        print(f"{model.name}: FMI 2.0 model-exchange FMU of {what}\n\nwrote {written}")
    return 0

"""``sflm invert``."""

from __future__ import annotations

import argparse
import math
from typing import Any
from inversion.config import DEFAULTS
from inversion.options import method_names, registered
from inversion.realtime.feedforward_c import export_c, export_table

from .arguments import add_inversion_arguments, add_model_arguments, add_uncertainty_arguments, request, trajectory_of
from .common import check_exports_before_work, check_out_before_work, dask_client, emit, load_model, output_folder, uncertainty_of
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm invert tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --plot --out run"


def add(sub: Any) -> None:
    """Add ``sflm invert``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    inv = sub.add_parser("invert", help="piece-wise causal inversion of a desired tip trajectory")
    add_model_arguments(inv)
    add_inversion_arguments(inv)
    add_uncertainty_arguments(inv)
    inv.add_argument("--workers", type=int, metavar="N", help="with --objective robust: local processes for the explorer and the "
                     "judging (default: all cores; 1 runs in this process)")
    inv.add_argument("--scheduler", metavar="ADDRESS", help="with --objective robust: run them on an existing Dask distributed "
                     "cluster (pip install 'sflm[dask]')")
    inv.add_argument("--controller", choices=("none", "pd"), default=None,
                     help="the loop the table is judged in: pd (the default for a link), the feedforward alone and with the "
                          "joint PD of Eq. (40) closed (the paper's experiment, the loop sflm simulate closes by default): every "
                          "candidate must hold the tip within --max-error in both, during the move and after it, and the summary "
                          "reports both; none, the feedforward alone")
    inv.add_argument("--kp", type=float, metavar="KP", help="with --controller pd: the joint PD gain k_P (default: the paper's for "
                     "its cases, else the documented rule, as sflm simulate)")
    inv.add_argument("--kd", type=float, metavar="KD", help="with --controller pd: the joint PD gain k_D (default as --kp)")
    inv.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/invert)")
    inv.add_argument("--json", action="store_true", help="print summary.json")
    inv.add_argument("--plot", action="store_true", help="write output.png, redefinition_error.png, torque.png")
    inv.add_argument("--method", choices=method_names(), default=None,
                     help="default: the paper's member for the paper's case as shipped or a member given, else the automatic "
                          "choice across methods (the family first; the optimal-control feedforward at the controller's period "
                          "only when no member passes; with --preview, stable inversion truncated to it competes); "
                          + methods_help())
    inv.add_argument("--preview", type=float, metavar="S", help="seconds of torque allowed before the move starts: stable "
                     "inversion truncated to S competes in the automatic choice (or bounds --method stable's pre-actuation)")
    inv.add_argument("--export-c", metavar="DIR", help="write DIR/feedforward.c and feedforward.h: the feedforward's closed form in C99 (freestanding: no library, not even libm)")
    inv.add_argument("--export-table", metavar="FILE", help="write t, tau, theta_d, thetadot_d at --rate as C arrays in FILE (a .h)")
    inv.add_argument("--c-prefix", default=DEFAULTS.c_prefix, metavar="NAME",
                     help="prefix of the exported C symbols (default %(default)s: %(default)s_eval)")


def robust_choice_of(args: argparse.Namespace, model: Any, uncertainty: Any) -> Any:
    """``--objective robust``: the member of least worst-case error on the perturbed links (:func:`inversion.studies.robustness.robust_choice`)."""
    from inversion.studies.robustness import robust_choice
    from modelgen.errors import SettingsError

    if uncertainty is None:
        raise SettingsError("--objective", "robust", "robust together with --uncertainty SPEC (the links it is robust to)")
    given = [name for name in ("segments", "h", "cdec", "joining", "settings", "end") if getattr(args, name, None) is not None]
    if given or args.method not in (None, "ssef") or getattr(args, "preview", None) is not None or args.command != "invert":
        raise SettingsError("--objective", "robust", "invert of the family (no --method, member settings or --end: it explores them)")
    executor = dask_client(args.scheduler) if args.scheduler else None
    try:
        with args.reporter.stage("robust choice", unit="members") as bar:
            return robust_choice(model, trajectory_of(args, model.name), uncertainty, max_error=args.max_error, max_torque=args.max_torque,
                                 progress=bar, workers=args.workers, executor=executor)
    finally:
        if executor is not None:
            executor.close()


def methods_help() -> str:
    """Each registered method's help, ``NAME: what it is`` (methods of one help text share it: ``zv, zvd: ...``)."""
    entries: list[tuple[list[str], str]] = []
    for kind in registered():
        if entries and entries[-1][1] == kind.help:
            entries[-1][0].append(kind.name)
        else:
            entries.append(([kind.name], kind.help or kind.label))
    return "; ".join(f"{', '.join(names)}: {text}" for names, text in entries)


def inverted(args: argparse.Namespace, model: Any, uncertainty: Any = None) -> Any:
    """:func:`inversion.invert` of the command line's request (:func:`sflm.cli.arguments.request`; progress on stderr).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    model : Model or LinearSystem
        The model.
    uncertainty : Uncertainty, optional
        The parameter spread the table is planned for.
    """
    from inversion.api import resolve
    from inversion.problem import Loop

    # the loop the table is judged in: invert's --controller (a link's default: both loops); simulate's own
    gains = (args.kp, args.kd) if args.kp is not None or args.kd is not None else None
    controller = args.controller if args.controller in ("none", None) else "pd"  # simulate's two-stage: the PD during the move
    if controller == "none" and gains is not None:
        from modelgen.errors import SettingsError

        raise SettingsError("--kp" if args.kp is not None else "--kd", args.kp if args.kp is not None else args.kd,
                            "a gain without --controller none (the joint PD the table is judged in)")
    loop = Loop(controller=controller, gains=gains)
    shortest = shortest_profile(args.trajectory)
    if shortest is not None:  # smoothstep:D:shortest[:ORDER]: the duration is the answer
        from inversion.methods.shortest import shortest_move
        from inversion.signals.trajectory import smoothstep

        distance, order = shortest
        args.trajectory = f"smoothstep:{distance!r}:1.0:{order}"  # a member of the profile: the problem's template
        problem, method = request(args, model, loop, uncertainty)  # the method only where one is asked: else optimal control
        return shortest_move(problem, lambda duration: smoothstep(distance, duration, order),
                             None if getattr(args, "method", None) is None else method, args.reporter,
                             curve=6 if getattr(args, "plot", False) else 0)  # the plot draws the curve
    fastest = fastest_distance(args.trajectory)
    if fastest is not None:  # shortest:DISTANCE: the profile is free too
        from inversion.methods.fastest import fastest_move

        args.trajectory = f"smoothstep:{fastest!r}:1.0"  # the start and the distance: the problem's template
        problem, method = request(args, model, loop, uncertainty)
        return fastest_move(problem, fastest, None if getattr(args, "method", None) is None else method, args.reporter)
    problem, method = request(args, model, loop, uncertainty)
    return resolve(problem, method, args.reporter)


def fastest_distance(spec: Any) -> float | None:
    """``DISTANCE`` of ``shortest:DISTANCE`` (the fastest move of any profile), or ``None``.

    Parameters
    ----------
    spec : str or None
        ``--trajectory``'s value.
    """
    if not isinstance(spec, str) or not spec.startswith("shortest:"):
        return None
    from modelgen.errors import SettingsError

    try:
        distance = float(spec.split(":", 1)[1])
    except ValueError:
        distance = math.nan
    if not (math.isfinite(distance) and distance != 0):
        raise SettingsError("--trajectory", spec, "shortest:DISTANCE with a finite non-zero number DISTANCE (the tip's move, m)")
    return distance


def shortest_profile(spec: Any) -> tuple[float, int] | None:
    """``(distance, order)`` of ``smoothstep:DISTANCE:shortest[:ORDER]`` (the shortest move of that profile), or ``None``.

    Parameters
    ----------
    spec : str or None
        ``--trajectory``'s value.
    """
    if not isinstance(spec, str) or not spec.startswith("smoothstep:"):
        return None
    parts = spec.split(":")[1:]
    if len(parts) not in (2, 3) or parts[1] != "shortest":
        return None
    from modelgen.errors import SettingsError

    try:
        distance, order = float(parts[0]), int(parts[2]) if len(parts) == 3 else 5
    except ValueError:
        raise SettingsError("--trajectory", spec, "smoothstep:DISTANCE:shortest[:ORDER] with a number DISTANCE and an integer "
                            "ORDER") from None
    return distance, order


def run(args: argparse.Namespace) -> int:
    """Run ``sflm invert``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """

    from ..summaries import inversion_text

    if args.export_c or args.export_table:
        from inversion.realtime.feedforward_c import check_prefix

        check_prefix(args.c_prefix)  # before the work
        check_exports_before_work(args)
    model = load_model(args)
    uncertainty = uncertainty_of(args, model)  # checked before the work
    check_out_before_work(args, model.name, "invert")  # as --out, before the work
    for option, value in (("--workers", args.workers), ("--scheduler", args.scheduler)):
        if value is not None and args.objective != "robust":
            from modelgen.errors import SettingsError

            raise SettingsError(option, value, "nothing without --objective robust (the one search invert spreads over processes)")
    if args.objective == "robust":
        result = robust_choice_of(args, model, uncertainty)
    else:  # the optimal-control programme holds the corners at once
        result = inverted(args, model, uncertainty)
    if uncertainty is not None and args.objective != "robust":
        from inversion.studies.robustness import judge_robustness

        judge_robustness(result, uncertainty)
    extra: list[str] = []
    from modelgen.errors import SettingsError

    try:
        if args.export_c:
            extra += [str(p) for p in export_c(result, args.export_c, args.c_prefix)]
        if args.export_table:
            extra.append(str(export_table(result, args.export_table, args.c_prefix)))
    except SettingsError as exc:
        if exc.parameter in ("folder", "path"):  # the file or folder the flag named
            raise SettingsError("--export-c" if exc.parameter == "folder" else "--export-table", exc.value, exc.accepted) from None
        raise
    return emit(args, result, output_folder(args, model.name, "invert"), "inversion.csv", "plot_inversion", inversion_text, extra)

"""``sflm explore``."""

from __future__ import annotations

import argparse
import json
from typing import Any
from inversion.config import DEFAULTS

from .arguments import TRAJECTORY_HELP, add_model_arguments, add_smooth_argument, add_uncertainty_arguments, float_list, int_list, list_text, percent, str_list, trajectory_of
from .common import check_out_before_work, dask_client, load_model, output_folder, uncertainty_of
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm explore paper-sim --segments 5,10,20 --h 1,2 --plot"


def add(sub: Any) -> None:
    """Add ``sflm explore``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    grid = DEFAULTS.grid
    exp = sub.add_parser("explore", help="the family of redefinitions on a grid: errors, torques, the Pareto front, the best member")
    add_model_arguments(exp)
    exp.add_argument("--trajectory", metavar="SPEC", help=TRAJECTORY_HELP)
    add_smooth_argument(exp)
    exp.add_argument("--segments", type=int_list, metavar="LIST", help=f"segment counts, comma-separated (default {list_text(grid.segments)})")
    exp.add_argument("--h", type=int_list, metavar="LIST", help=f"orders of smooth joining (default {list_text(grid.h)})")
    exp.add_argument("--cdec-fast", type=float_list, metavar="LIST", help=f"fastest decays Cdec_f (default {list_text(grid.cdec_fast)})")
    exp.add_argument("--cdec-slow", type=float_list, metavar="LIST", help=f"slowest decays Cdec_s (default {list_text(grid.cdec_slow)}; "
                     "pairs with Cdec_f >= Cdec_s are skipped)")
    exp.add_argument("--joining", type=str_list, metavar="LIST", help=f"joinings: paper, position, anchored (default {list_text(grid.joining)})")
    exp.add_argument("--eps", type=float, default=None, metavar="E", help=f"zeros with Re >= -E count as unstable (default {DEFAULTS.eps:g})")
    exp.add_argument("--end", type=str_list, metavar="LIST", help="how the members end: free, settle (anchored only), rest "
                     "(default free, the paper's)")
    exp.add_argument("--objective", choices=("torque", "error"), default=None,
                     help=f"the automatic choice's objective, which marks the chosen member (default {DEFAULTS.objective})")
    exp.add_argument("--period", type=float, metavar="DT", help="the controller's period the chosen member is judged at "
                     f"(s; default {1 / DEFAULTS.rate:g}); with --plot, of the optimal-control front (default {DEFAULTS.ocp_period:g})")
    exp.add_argument("--hold", choices=("point", "zoh"), default=None, help=f"how the chosen member's samples are held (default {DEFAULTS.hold})")
    exp.add_argument("--max-torque", type=float, metavar="T", help="members with a larger peak torque (N m) are not chosen")
    exp.add_argument("--max-error", type=float, metavar="E", help=f"in m: the members' quality gate (default {percent(DEFAULTS.quality_gate)} of "
                     f"the move) and the chosen member's tip bound (default {percent(DEFAULTS.bound)}); inf accepts any")
    exp.add_argument("--workers", type=int, metavar="N", help="local processes (default: all cores; 1 runs in this process)")
    exp.add_argument("--scheduler", metavar="ADDRESS", help="run on an existing Dask distributed cluster (pip install 'sflm[dask]')")
    exp.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/explore)")
    add_uncertainty_arguments(exp, "judge the members within the bounds (at most 16, spread over their peak torques) on perturbed "
                                    "links in the closed loop with the joint PD: geometry keys with relative ranges, e.g. "
                                    "link.flexural_rigidity=10%%,payload.mass=20%%; explore.csv gains worst_case_error, pareto.png "
                                    "colours by it")
    exp.add_argument("--json", action="store_true", help="print summary.json")
    exp.add_argument("--plot", action="store_true", help="write pareto.png")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm explore``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from inversion.family.explore import explore

    from ..summaries import exploration_text

    model = load_model(args)
    trajectory = trajectory_of(args, model.name)
    check_out_before_work(args, model.name, "explore")  # a folder of another command's run: its summary.json is replaced
    folder = output_folder(args, model.name, "explore")
    uncertainty = uncertainty_of(args, model)  # checked before the work
    executor = dask_client(args.scheduler) if args.scheduler else None
    try:
        with args.reporter.stage("explore", unit="members") as bar:
            result = explore(
                model, trajectory, segments=args.segments, h=args.h, cdec_fast=args.cdec_fast, cdec_slow=args.cdec_slow,
                joining=args.joining, eps=args.eps, end=args.end, max_error=args.max_error, max_torque=args.max_torque,
                workers=args.workers, executor=executor, progress=bar, objective=args.objective, period=args.period, hold=args.hold,
            )
        if uncertainty is not None:
            from inversion.studies.robustness import judge_family

            with args.reporter.stage("perturbed links", unit="members") as bar:
                judge_family(result, model, trajectory, uncertainty, max_error=args.max_error, progress=bar, workers=args.workers,
                             executor=executor)
    finally:
        if executor is not None:
            executor.close()
    files = [str(f) for f in result.write(folder)]
    if args.plot:
        from inversion.methods.ocp import ocp_front, write_front

        from ..plots import pareto_figure

        period = args.period if args.period is not None else DEFAULTS.ocp_period
        with args.reporter.stage("optimal-control front", unit="bounds") as bar:
            front = ocp_front(model, trajectory, period=period, progress=bar)
        files.append(str(write_front(front, folder / "ocp_front.csv")))
        files.append(str(pareto_figure(result, folder / "pareto.png", ocp=(front, period))))
    print(json.dumps(result.summary, indent=1) if args.json else exploration_text(result, files))
    return 0

"""``sflm compare``."""

from __future__ import annotations

import argparse
import json
from typing import Any
from .arguments import (add_inversion_arguments, add_model_arguments, add_uncertainty_arguments, bounds_of, member_of, sampling_of,
                        trajectory_of)
from .common import load_model, output_folder, uncertainty_of
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm compare tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --plot"


def add(sub: Any) -> None:
    """Add ``sflm compare``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    cmp = sub.add_parser("compare", help="the causal inversion beside its baselines (SSEF, SSEF with a rest end, polynomial, stable "
                                            "inversion) and the alternatives (optimal control, ZV, ZVD)")
    add_model_arguments(cmp)
    add_inversion_arguments(cmp)
    add_uncertainty_arguments(cmp)
    cmp.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/compare)")
    cmp.add_argument("--json", action="store_true", help="print the rows as JSON")
    cmp.add_argument("--plot", action="store_true", help="write compare.png: the torques on one time axis and the tip errors")
    cmp.add_argument("--shortest", action="store_true", help="also the shortest move of the same profile and the fastest of any "
                     "profile, certified, each with its duration (absolute --max-torque and --max-torque-rate, or the geometry's "
                     "[drive])")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm compare``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from inversion.studies.compare import compare

    from ..summaries import comparison_text

    from inversion.family.method import Family
    from inversion.problem import Problem
    from inversion.studies.compare import check_objective

    model = load_model(args)
    trajectory = trajectory_of(args, model.name)
    folder = output_folder(args, model.name, "compare")
    uncertainty = uncertainty_of(args, model)
    problem = Problem(model, trajectory, bounds=bounds_of(args), sampling=sampling_of(args), uncertainty=uncertainty, margin=args.margin)
    member = {k: v for k, v in member_of(args).items() if k != "end" and v is not None}  # each row takes its own end
    check_objective(member.get("objective"))
    family = Family(**member)
    result = compare(problem, family=family, progress=args.reporter, shortest=args.shortest)
    files = [str(result.write_csv(folder / "compare.csv"))]
    if args.plot:
        from ..plots import comparison_figure

        files.append(str(comparison_figure(result, folder / "compare.png", f"{model.name}: {trajectory.name}")))
    print(json.dumps(result.rows, indent=1) if args.json else comparison_text(result, files))
    return 0

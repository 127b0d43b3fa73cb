"""``sflm reproduce``."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm reproduce paper-sim --out paper"


def add(sub: Any) -> None:
    """Add ``sflm reproduce``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    rep = sub.add_parser("reproduce", help="the paper's simulation or experiment end to end: figures and report.md")
    rep.add_argument("case", metavar="CASE", choices=("paper-sim", "paper-exp"), help="paper-sim (section 7) or paper-exp (section 8)")
    rep.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<case>)")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm reproduce``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from ..reproduce import reproduce

    folder = Path(args.out) if args.out else Path("sflm-out") / args.case
    result = reproduce(args.case, folder, progress=args.reporter)
    print(result.report.read_text())
    figures = [f for f in result.files if f.suffix == ".png"]
    print(f"wrote {len(result.files)} files to {result.folder}/ ({len(figures)} figures, report.md) "
          f"in {result.numbers['seconds']:.1f} s")
    return 0

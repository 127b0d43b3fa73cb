"""``sflm generate``."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any
from .arguments import add_model_arguments
from .common import load_model
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm generate paper-sim --modes 2 --out generated-c"


def add(sub: Any) -> None:
    """Add ``sflm generate``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    gen = sub.add_parser("generate", help="generate, compile and write the model's C code and manifest")
    add_model_arguments(gen)
    gen.add_argument("--out", metavar="DIR", help="output folder (default generated/<name>-n<N>-<family>/)")
    gen.add_argument("--json", action="store_true", help="print the manifest as JSON")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm generate``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    import time

    from modelgen.export import default_folder, export_model

    started = time.perf_counter()
    args.reporter("deriving, generating and compiling the model (cached after the first time)")
    model = load_model(args, system=False)
    folder = Path(args.out) if args.out else default_folder(model.geometry)
    result = export_model(model, folder, model.functions.cache_hit, started)
    if args.json:
        print(json.dumps(result.manifest, indent=1, sort_keys=True))
    else:
        how = "cache hit" if result.cache_hit else "derived, generated and compiled"
        kind = "compiled C" if result.manifest["library"] else "no library: in-process CasADi fallback"
        print(f"{result.folder}/: {', '.join(result.files)}")
        print(f"  {model.name}, {model.n} {model.mode_family} mode{'s' if model.n != 1 else ''}; {how} in {result.seconds:.2f} s ({kind})")
        print(f"  {len(result.manifest['functions'])} functions sflm_<role>(p, ...); p has {len(model.parameter_names)} entries (manifest.json)")
    return 0

"""The ``sflm`` command line: a module per command, the argument groups they share defined once.

Subcommands: ``info``, ``generate``, ``invert``, ``explore``, ``compare``, ``simulate``, ``reproduce``, ``fmu``, ``fit``
(:data:`COMMANDS`: each module adds its parser, ``add(sub)``, and runs it, ``run(args)``). The shared groups -- the
model, the move, the family's member, the bounds, the sampling, the parameter spread -- are in
:mod:`sflm.cli.arguments`, mapped onto :class:`inversion.Problem` and a method object there. User errors print one line
on stderr and exit with status 2; warnings print one line on stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import warnings
from types import ModuleType
from typing import Sequence

from modelgen.errors import SflmError
from ..formatting import printable

from .. import __version__
from . import compare, explore, fit, fmu, generate, info, invert, reproduce, simulate
from .arguments import Parser
from .common import SCHEDULER_GREETING, refusal_json, refusal_record, scheduler_fault, silence_stdout
from .flags import FLAGS, in_flags, one_line_warning

__all__ = ["main", "parser", "COMMANDS", "FLAGS", "in_flags", "scheduler_fault", "SCHEDULER_GREETING"]

#: The commands, in the order ``sflm --help`` lists them: each module's ``add(sub)`` and ``run(args)``.
COMMANDS: dict[str, ModuleType] = {"info": info, "generate": generate, "invert": invert, "explore": explore, "compare": compare,
                                   "simulate": simulate, "reproduce": reproduce, "fmu": fmu, "fit": fit}
#: The order the parsers are added in (``sflm --help``'s).
_ORDER = ("info", "generate", "invert", "explore", "compare", "simulate", "reproduce", "fmu", "fit")


def parser() -> argparse.ArgumentParser:
    """The command line's parser.

    The command line's parser (built again at each call: ``--method`` lists the methods registered now)."""
    top = Parser(prog="sflm", description="Single flexible link manipulator: models, generated code, causal inversion.")
    top.add_argument("--version", action="version", version=f"sflm {__version__}")
    sub = top.add_subparsers(dest="command", required=True, parser_class=Parser)
    for name in _ORDER:
        COMMANDS[name].add(sub)
        # its example (the module's EXAMPLE) under --help, as written: the command reference shows the same
        sub.choices[name].epilog = f"example:\n  {COMMANDS[name].EXAMPLE}"
        sub.choices[name].formatter_class = argparse.RawDescriptionHelpFormatter
    for command in sub.choices.values():  # every command: past 2 s its stage on stderr at least every 5 s, unless asked not to
        command.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr (past 2 s a command reports its "
                             "stage there at least every 5 s: a bar on a terminal, lines otherwise)")
    return top


#: :func:`parser` under its earlier name (the documentation's build and the tests read it).
_parser = parser


def _parsed(built: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """``built.parse_args(argv)``; with ``--json``, a usage error is also a JSON refusal on stdout (as every other
    refusal is: a script reading stdout found nothing, issue 59 item 14), its line on stderr as argparse prints it."""
    if "--json" not in argv:
        return built.parse_args(argv)
    said = io.StringIO()
    try:
        with contextlib.redirect_stderr(said):
            return built.parse_args(argv)
    except SystemExit as exc:
        text = said.getvalue()
        sys.stderr.write(text)
        if exc.code:
            command = next((a for a in argv if a in COMMANDS), None)
            message = text.strip().splitlines()[-1].partition("error: ")[2] if text.strip() else "usage error"
            print(json.dumps(refusal_record(command, "UsageError", message), indent=1))
        raise


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sflm`` console script; the exit status.

    Parameters
    ----------
    argv : Sequence[str] | None, optional
        The arguments (``None``: ``sys.argv[1:]``).
    """
    warnings.formatwarning = one_line_warning
    built = parser()
    if not (sys.argv[1:] if argv is None else list(argv)):
        built.print_help(sys.stderr)
        return 2
    args = _parsed(built, list(sys.argv[1:] if argv is None else argv))
    from .. import STARTED
    from ..progress import Reporter

    args.reporter = Reporter(args.command, enabled=not args.quiet, start=STARTED)
    try:
        return int(COMMANDS[args.command].run(args))
    except SflmError as exc:
        args.reporter.close()
        message = in_flags(str(exc), getattr(exc, "parameter", getattr(exc, "key", None)))
        print(f"sflm {args.command}: error: {printable(message)}", file=sys.stderr)
        if getattr(args, "json", False):
            refusal_json(args, exc, message)
        return 2
    except BrokenPipeError:
        # the reader went away (`sflm ... | head -1`): say nothing more, as a killed writer would
        silence_stdout()
        return 128 + 13  # SIGPIPE
    except OSError as exc:  # the system refused (a full disk, a folder gone read-only, a file removed)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"sflm {args.command}: error: {printable(f'{where}{exc.strerror or exc}')}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        args.reporter.close()
        print("sflm: interrupted", file=sys.stderr)
        return 130
    finally:
        args.reporter.close()

"""The command line's reference, generated from its parser: every subcommand and flag, its default and its choices.

``docs/build.py`` writes it into the documentation (``cli.md``), so it cannot drift from ``sflm --help``.
"""

from __future__ import annotations

import argparse

__all__ = ["reference_markdown"]


def _default(action: argparse.Action) -> str:
    if action.default in (None, argparse.SUPPRESS) or isinstance(action, (argparse._StoreTrueAction, argparse._HelpAction)):
        return ""
    return f"`{action.default}`"


def _usage(action: argparse.Action) -> str:
    if not action.option_strings:
        return f"`{action.metavar or action.dest.upper()}`"
    name = ", ".join(action.option_strings)
    if action.nargs == 0:
        return f"`{name}`"
    if action.choices:  # a table cell: its pipes escaped (inside the code span too), or they end the cell; a line
        # may break after each (a zero-width space: a long list of choices fits the column at a desk)
        return "`" + name + " {" + "\\|\u200b".join(str(c) for c in action.choices) + "}`"
    metavar = action.metavar if isinstance(action.metavar, str) else " ".join(action.metavar or (action.dest.upper(),))
    return f"`{name} {metavar}`"


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """The help ``--help`` prints for ``action``: its ``%`` formats expanded by argparse itself (``%(default)s``,
    ``%%``), word for word."""
    return parser._get_formatter()._expand_help(action) if action.help else ""


def _cell(text: str | None) -> str:
    """Text for a table cell: its pipes escaped (they would end the cell), its angle brackets as entities (``<name>``
    would be read as an HTML tag and vanish), on one line."""
    return " ".join((text or "").replace("|", "\\|").replace("<", "&lt;").replace(">", "&gt;").split())


def reference_markdown(parser: argparse.ArgumentParser) -> str:
    """The reference of ``sflm``'s parser as a Markdown page.

    The reference of ``parser`` (``sflm``'s) as a Markdown page: a section per subcommand, a table of its arguments.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command line's parser.

    Examples
    --------
    >>> from sflm.cli import _parser
    >>> "--preview S" in reference_markdown(_parser())
    True
    """
    lines = ["# Command-line reference", "",
             f"Generated from the parser of `{parser.prog}` (`{parser.prog} COMMAND --help` prints the same). "
             "Errors in what you give print one line and exit with status 2.", ""]
    subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {choice.dest: choice.help for choice in subparsers._choices_actions}
    for name, sub in subparsers.choices.items():
        lines += [f"## `{parser.prog} {name}`", "", _cell(helps.get(name)) + ".", ""]
        if sub.epilog:  # the command's example, as its --help prints it
            head, _, example = sub.epilog.partition("\n")
            lines += [f"{head.strip().capitalize()}", "", "```sh", *(line.strip() for line in example.splitlines()), "```", ""]
        lines += ["| argument | default | what it does |", "|---|---|---|"]
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            lines.append(f"| {_usage(action)} | {_default(action)} | {_cell(_help(sub, action))} |")
        lines.append("")
    return "\n".join(lines)

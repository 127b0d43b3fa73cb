"""Every command's options as the command line had them before its commands moved into modules of their own (issue 55).

The reference (``tests/data/reference-runs/parsers.json``) holds each option of each command: its flags, destination,
choices, default, number of values, metavar and help text. A rearrangement of the command line keeps them all; an option
added later is listed here with ``--update-references`` (an option removed or changed fails: scripts rely on them).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import pytest

from sflm.cli import main  # noqa: F401  (the entry point the console script names)

REFERENCE = Path(__file__).resolve().parents[1] / "data" / "reference-runs" / "parsers.json"


def parser_options() -> dict[str, list[dict[str, Any]]]:
    """Each command's options, as argparse holds them."""
    from sflm.cli import _parser

    sub = next(a for a in _parser()._actions if isinstance(a, argparse._SubParsersAction))
    out: dict[str, list[dict[str, Any]]] = {}
    for name, command in sub.choices.items():
        out[name] = [{"flags": list(a.option_strings), "dest": a.dest, "choices": None if a.choices is None else list(a.choices),
                      "default": a.default if isinstance(a.default, (str, int, float, bool, type(None))) else repr(a.default),
                      "nargs": a.nargs, "metavar": list(a.metavar) if isinstance(a.metavar, tuple) else a.metavar,
                      "help": a.help, "type": getattr(a.type, "__name__", None)}
                     for a in command._actions if not isinstance(a, argparse._HelpAction)]
    return out


def test_every_option_is_kept(request: pytest.FixtureRequest) -> None:
    found = json.loads(json.dumps(parser_options()))
    if request.config.getoption("--update-references"):
        REFERENCE.write_text(json.dumps(found, indent=1) + "\n")
        return
    reference = json.loads(REFERENCE.read_text())
    assert sorted(found) == sorted(reference), "a command was added or removed"
    for command, options in reference.items():
        now = {tuple(o["flags"]) or (o["dest"],): o for o in found[command]}
        for option in options:
            key = tuple(option["flags"]) or (option["dest"],)
            assert key in now, f"sflm {command}: {key} is gone"
            assert now[key] == option, f"sflm {command} {key}: was {option}, now {now[key]}"

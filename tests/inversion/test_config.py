"""Each default of the inversion layer lives once: in ``inversion/config.py``, read through its three resolvers.

The literal defaults of ``eps``, ``rate``, ``solver``, ``tol``, ``max_error``, ``period`` and ``window`` (and the
others of :class:`inversion.config.Defaults`) appear nowhere else in the source, and a ``None`` becomes a default only
in :func:`inversion.config.default`, :func:`~inversion.config.tip_bound` and :func:`~inversion.config.held_period`.
"""

from __future__ import annotations

import ast
import dataclasses
from pathlib import Path

import pytest

from inversion.config import DEFAULTS, default, held_period, tip_bound

ROOT = Path(__file__).resolve().parents[2]
SOURCES = sorted(p for package in ("inversion", "simulation", "sflm") for p in (ROOT / package).rglob("*.py")
                 if p != ROOT / "inversion" / "config.py")
#: The keywords whose defaults the issue named (and ``hold``).
NAMED = ("eps", "rate", "solver", "tol", "max_error", "period", "window", "hold")


def _literal_defaults(path: Path, root: Path = ROOT) -> list[str]:
    """``name=<constant>`` in a signature of ``path`` for a named keyword (a default written a second time)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            args = node.args
            pairs = list(zip(args.args[len(args.args) - len(args.defaults):], args.defaults))
            pairs += [(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults) if d is not None]
            for arg, value in pairs:
                if arg.arg in NAMED and isinstance(value, ast.Constant) and value.value is not None:
                    found.append(f"{path.relative_to(root)}:{value.lineno} {arg.arg}={value.value!r}")
    return found


def _none_to_default(path: Path, root: Path = ROOT) -> list[str]:
    """``DEFAULTS.x if x is None else x`` and ``... if max_error is None ...``: a default resolved outside config.py."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.IfExp) and isinstance(node.test, ast.Compare) and isinstance(node.test.ops[0], ast.Is):
            text = ast.unparse(node)
            subject = ast.unparse(node.test.left)
            named = subject.split(".")[-1].strip("'\"]").removeprefix("options['").removeprefix("options.get('").rstrip("')")
            if ast.unparse(node.body).startswith("DEFAULTS.") or named in NAMED:
                found.append(f"{path.relative_to(root)}:{node.lineno} {text}")
    return found


def test_no_named_default_is_written_twice() -> None:
    found = [line for path in SOURCES for line in _literal_defaults(path)]
    assert not found, found


def test_none_becomes_a_default_only_in_config() -> None:
    found = [line for path in SOURCES for line in _none_to_default(path)]
    assert not found, found


def test_the_search_finds_a_second_home_when_there_is_one(tmp_path: Path) -> None:
    # the checks above can fail: a planted second home is found by each
    planted = tmp_path / "planted.py"
    planted.write_text("from inversion.config import DEFAULTS\n\ndef f(rate=1000.0, tol=None):\n"
                       "    return DEFAULTS.tol if tol is None else tol, 0.01 if max_error is None else max_error\n")
    assert len(_literal_defaults(planted, tmp_path)) == 1
    assert len(_none_to_default(planted, tmp_path)) == 2


@pytest.mark.parametrize("name", [f.name for f in dataclasses.fields(DEFAULTS) if f.name != "grid"])
def test_default_reads_the_one_home(name: str) -> None:
    assert default(name, None) == getattr(DEFAULTS, name)
    assert default(name, "given") == "given"


def test_tip_bound_and_held_period() -> None:
    # the judged bound is DEFAULTS.bound of the move, a fixed member's gate DEFAULTS.quality_gate of it (config.py)
    assert tip_bound(None, 0.5) == pytest.approx(DEFAULTS.bound * 0.5)
    assert tip_bound(None, 0.5, judged=False) == pytest.approx(DEFAULTS.quality_gate * 0.5)
    assert tip_bound(2e-3, 0.5) == 2e-3 and tip_bound(2e-3, 0.5, judged=False) == 2e-3
    assert held_period(None) == pytest.approx(1.0 / DEFAULTS.rate)
    assert held_period(None, 200.0) == pytest.approx(5e-3)
    assert held_period(0.02, 200.0) == 0.02

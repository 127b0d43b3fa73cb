"""Typed contracts between the layers: the compiled functions, and the summaries scripts read."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path
from typing import get_type_hints

import pytest

import modelgen
from inversion import InversionSummary, invert, trajectory_from_spec
from modelgen.errors import ModelError
from modelgen.interface import CompiledFunctions
from simulation import SimulationSummary, simulate


def test_model_functions_meet_the_contract() -> None:
    model = modelgen.load("paper-sim")
    assert isinstance(model.functions, CompiledFunctions)
    assert model.compiled_functions is model.functions
    bare = dataclasses.replace(model, functions=None)
    with pytest.raises(ModelError, match="no generated functions"):
        bare.compiled_functions


def test_interface_imports_no_casadi() -> None:
    code = "import sys, modelgen.interface; print('casadi' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def _keys(typed: type) -> tuple[set[str], set[str]]:
    """Required and optional keys of a TypedDict."""
    return set(typed.__required_keys__), set(typed.__optional_keys__)  # type: ignore[attr-defined]


def test_inversion_summary_has_exactly_the_typed_keys(tmp_path: Path) -> None:
    required, optional = _keys(InversionSummary)
    model = modelgen.load("paper-sim")
    result = invert(model, trajectory_from_spec("paper-sim"))
    assert set(result.summary) == required | {"loop"}  # the paper's member: no automatic search; judged in both loops
    assert optional == {"auto", "zero_dynamics", "pre_actuation_time", "post_actuation_time", "loop"}
    assert result.summary["method"] == "ssef"  # every summary names its method
    # the CLI's --json prints the same keys
    proc = subprocess.run([sys.executable, "-m", "sflm.cli", "invert", "paper-sim", "--json", "--out", str(tmp_path)],
                          capture_output=True, text=True, check=True)
    printed = json.loads(proc.stdout)
    assert set(printed) == required | {"run", "loop"}  # the CLI's record of the files it wrote (issue 47)
    assert set(printed["run"]) == {"id", "files", "command", "model"} and set(printed["run"]["files"]) == {"inversion.csv"}
    hints = get_type_hints(InversionSummary)
    for key in ("max_redefinition_error", "peak_torque", "torque_at_end"):
        assert hints[key] is float and isinstance(result.summary[key], float)  # type: ignore[literal-required]


def test_simulation_summary_has_exactly_the_typed_keys() -> None:
    model = modelgen.load("paper-sim")
    sim = simulate(model, invert(model, trajectory_from_spec("paper-sim")), t_end=7.0)
    required, optional = _keys(SimulationSummary)
    assert required <= set(sim.summary) <= required | optional


def test_the_command_line_help_reads_the_defaults(monkeypatch: pytest.MonkeyPatch) -> None:
    # each default is stated once (inversion/config.py): the help is built from DEFAULTS, not retyped (it once listed an
    # explorer grid of 1..30 segments and Cdec_s 0.2 the explorer did not use)
    import sflm.cli as cli
    import sflm.cli.arguments
    import sflm.cli.explore
    import sflm.cli.invert
    from inversion.config import DEFAULTS, SearchGrid

    changed = dataclasses.replace(DEFAULTS, rate=512.0, tol=3e-7, eps=0.25, quality_gate=0.07, bound=0.02, torque_ratio=2.5,
                                  c_prefix="ff", grid=SearchGrid(segments=(7, 9), cdec_slow=(0.75,)))
    for module in (sflm.cli.arguments, sflm.cli.explore, sflm.cli.invert):  # each reads inversion.config's, at the parser's build
        monkeypatch.setattr(module, "DEFAULTS", changed)
    parser = cli._parser()
    commands = parser._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    explore, invert = commands["explore"].format_help(), commands["invert"].format_help()
    squeeze = lambda text: " ".join(text.split())  # noqa: E731 -- argparse wraps the lines
    assert "(default 7,9)" in squeeze(explore) and "(default 0.75;" in squeeze(explore)
    for text in ("(default 512;", "(default 3e-07)", "(default 0.25)", "(default 7 % of the move, 2 % for the automatic choice",
                 "(default 2.5 x what a rigid link needs)", "(default ff: ff_eval)"):
        assert text in squeeze(invert), text
    namespace = parser.parse_args(["invert", "paper-sim"])
    assert namespace.rate is None and namespace.tol is None and namespace.eps is None  # None: the API's default

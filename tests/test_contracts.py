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
    assert set(result.summary) == required  # the paper's member: no automatic search
    assert optional == {"auto", "zero_dynamics", "method", "pre_actuation_time", "post_actuation_time"}
    # the CLI's --json prints the same keys
    proc = subprocess.run([sys.executable, "-m", "sflm.cli", "invert", "paper-sim", "--json", "--out", str(tmp_path)],
                          capture_output=True, text=True, check=True)
    assert set(json.loads(proc.stdout)) == required
    hints = get_type_hints(InversionSummary)
    for key in ("max_redefinition_error", "peak_torque", "torque_at_end"):
        assert hints[key] is float and isinstance(result.summary[key], float)  # type: ignore[literal-required]


def test_simulation_summary_has_exactly_the_typed_keys() -> None:
    model = modelgen.load("paper-sim")
    sim = simulate(model, invert(model, trajectory_from_spec("paper-sim")), t_end=7.0)
    required, optional = _keys(SimulationSummary)
    assert required <= set(sim.summary) <= required | optional

"""Without a C compiler (``SFLM_CC`` empty) sflm runs its generated functions in process (CasADi's virtual machine):
every role is the compiled one, and what a user gets from them -- the inversion, the closed loop on each plant, the
command line -- is what the compiled model gives. CI also runs the modules whose tests depend on a compiler this way
(``.ci/run``)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import modelgen
from _helpers import run_cli
from inversion import invert, trajectory_from_spec
from modelgen.abi import ROLES, compiler_command
from modelgen.cache import SflmWarning, ensure_model_functions
from simulation import simulate

needs_cc = pytest.mark.skipif(compiler_command() is None, reason="compares with the compiled functions")


@pytest.fixture(scope="module")
def nocc_cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A cache folder of its own for the in-process entries."""
    return tmp_path_factory.mktemp("nocc")


def _interpreted(monkeypatch: pytest.MonkeyPatch, cache: Path) -> None:
    monkeypatch.setenv("SFLM_CC", "")
    monkeypatch.setenv("SFLM_CACHE_DIR", str(cache))


def _inputs(manifest: dict, role: str, rng: np.random.Generator) -> list[np.ndarray]:
    """Random values of a role's inputs: parameters in [0.5, 2] (lengths, masses, rigidities), states and inputs N(0, 1)."""
    out = []
    for name, (rows, cols) in manifest["functions"][role]["inputs"]:
        out.append(rng.uniform(0.5, 2.0, (rows, cols)) if name == "p" else rng.normal(size=(rows, cols)))
    return out


@needs_cc
@pytest.mark.parametrize("n", [1, 3])
def test_every_in_process_role_is_the_compiled_one(n: int, nocc_cache: Path, monkeypatch: pytest.MonkeyPatch,
                                                   rng: np.random.Generator) -> None:
    compiled = ensure_model_functions(n)
    _interpreted(monkeypatch, nocc_cache)
    with pytest.warns(SflmWarning, match="no C compiler"):
        interpreted = ensure_model_functions(n)
    assert compiled.compiled and not interpreted.compiled and interpreted.manifest["library"] is None
    assert set(interpreted.functions) == set(compiled.functions) == set(ROLES)
    for role in ROLES:
        for _ in range(3):
            args = _inputs(compiled.manifest, role, rng)
            for a, b in zip(interpreted.call(role, *args), compiled.call(role, *args)):
                scale = max(float(np.abs(b).max()), 1e-300)
                assert np.abs(a - b).max() <= 1e-12 * scale, (role, np.abs(a - b).max() / scale)


@needs_cc
def test_the_inversion_and_the_closed_loop_are_the_compiled_ones(nocc_cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # paper-exp: the paper's member inverted, then its closed loop with friction on the stiffened and the paper's plant
    # (the in-process plant has no compiled Jacobian: CasADi differentiates it itself)
    compiled_model = modelgen.load("paper-exp")
    _interpreted(monkeypatch, nocc_cache)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SflmWarning)
        model = modelgen.load("paper-exp")
    assert not model.compiled_functions.compiled and compiled_model.compiled_functions.compiled
    trajectory = trajectory_from_spec("paper-exp")
    mine, theirs = invert(model, trajectory), invert(compiled_model, trajectory)
    for key in ("max_redefinition_error", "peak_torque", "torque_at_end"):
        assert mine.summary[key] == pytest.approx(theirs.summary[key], rel=1e-10, abs=1e-15), key
    np.testing.assert_allclose(mine.tau, theirs.tau, rtol=0, atol=1e-10 * np.abs(theirs.tau).max())
    move = theirs.summary["move"]
    for plant in ("nonlinear", "nonlinear-paper"):
        a = simulate(model, mine, plant=plant, t_end=3.0)
        b = simulate(compiled_model, theirs, plant=plant, t_end=3.0)
        assert a.t.size == b.t.size and np.abs(a.y - b.y).max() <= 1e-7 * move, plant  # the integrators' tolerance
        assert a.summary["steady_tip_error"] == pytest.approx(b.summary["steady_tip_error"], rel=1e-4, abs=1e-9 * move)


def test_the_command_line_says_once_that_there_is_no_compiler(tmp_path: Path, nocc_cache: Path,
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    _interpreted(monkeypatch, nocc_cache)
    proc = run_cli("invert", "paper-sim", "--out", str(tmp_path), "--json")
    assert proc.returncode == 0, proc.stderr
    warned = [line for line in proc.stderr.splitlines() if "no C compiler" in line]
    assert len(warned) == 1 and warned[0].startswith("sflm: warning:"), proc.stderr
    assert (tmp_path / "inversion.csv").is_file()
    refused = run_cli("fmu", "paper-sim", "--out", str(tmp_path / "plant.fmu"))
    assert refused.returncode == 2 and "C compiler" in refused.stderr and not (tmp_path / "plant.fmu").exists()

"""Golden files: the committed generated sources of the shipped presets are what sflm generates.

Regenerates each preset into a temporary folder and fails with a unified diff when a
committed source differs. ``pytest tests/test_golden.py --update-golden`` rewrites them.
"""

from __future__ import annotations

import difflib
import json
import shutil
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

from sflm.cli import main

GENERATED = Path(__file__).resolve().parent.parent / "generated"
GOLDEN = {"paper-sim": "paper-sim-n2-clamped-mass", "paper-exp": "paper-exp-n1-clamped-mass"}
EXACT_KEYS = (
    "format", "model", "modes", "sources", "header", "library", "functions", "batch_chunk",
    "geometry", "mode_shapes", "internal_dynamics", "n_unstable",
)
NUMERIC_KEYS = ("natural_frequencies_hz", "zeros", "CAB")


def _diff(committed: Path, fresh: Path) -> str:
    return "".join(
        difflib.unified_diff(
            committed.read_text().splitlines(keepends=True),
            fresh.read_text().splitlines(keepends=True),
            fromfile=f"committed/{committed.name}",
            tofile=f"regenerated/{fresh.name}",
            n=2,
        )
    )


@pytest.mark.parametrize("preset", sorted(GOLDEN))
def test_committed_sources_are_regenerated_identically(preset: str, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    committed = GENERATED / GOLDEN[preset]
    fresh = tmp_path / GOLDEN[preset]
    assert main(["generate", preset, "--out", str(fresh)]) == 0
    new_manifest = json.loads((fresh / "manifest.json").read_text())
    if request.config.getoption("--update-golden"):
        committed.mkdir(parents=True, exist_ok=True)
        for name in [*new_manifest["sources"], new_manifest["header"], "manifest.json"]:
            shutil.copy2(fresh / name, committed / name)
        return
    old_manifest = json.loads((committed / "manifest.json").read_text())
    tools = ("sflm", "sympy", "casadi")
    if any(old_manifest["versions"][t] != metadata.version(t) for t in tools):
        pytest.skip(
            "golden files were generated with "
            + ", ".join(f"{t} {old_manifest['versions'][t]}" for t in tools)
            + "; installed: " + ", ".join(f"{t} {metadata.version(t)}" for t in tools)
            + " (rerun with --update-golden after checking the change)"
        )
    for name in [*new_manifest["sources"], new_manifest["header"]]:
        diff = _diff(committed / name, fresh / name)
        assert not diff, f"{name} differs from the committed golden file:\n{diff[:4000]}"
    for key in EXACT_KEYS:
        assert old_manifest[key] == new_manifest[key], key
    assert old_manifest["parameters"]["names"] == new_manifest["parameters"]["names"]
    # numbers: the same up to the last digits LAPACK may change between machines. Off-diagonal
    # modal integrals vanish by orthogonality and come out as round-off (~1e-13 of the diagonal):
    # they are compared on the scale of the largest parameter, not relatively.
    values = np.asarray(old_manifest["parameters"]["values"])
    np.testing.assert_allclose(new_manifest["parameters"]["values"], values, rtol=1e-10, atol=1e-12 * np.abs(values).max())
    for key in NUMERIC_KEYS:
        np.testing.assert_allclose(np.asarray(new_manifest[key]), np.asarray(old_manifest[key]), rtol=1e-9, atol=1e-9, err_msg=key)


def test_no_binaries_committed() -> None:
    import subprocess

    tracked = subprocess.run(["git", "ls-files", "generated"], cwd=GENERATED.parent, capture_output=True, text=True)
    if tracked.returncode != 0:
        pytest.skip("not a git checkout")
    assert not [f for f in tracked.stdout.split() if f.endswith((".so", ".dylib", ".dll", ".o", ".casadi"))]

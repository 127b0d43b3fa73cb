"""Golden files: the committed generated sources of the shipped presets are what sflm generates.

Regenerates each preset into a temporary folder. With the generator versions recorded in
the committed manifest, a committed source that differs fails with a unified diff; with
any versions, the committed sources, compiled, must compute what the regenerated ones
compute (so a version drift in CI fails on a real change instead of skipping), and the
folders hold exactly the manifest's files. ``pytest tests/modelgen/test_golden.py --update-golden``
rewrites them and removes stale files.
"""

from __future__ import annotations

import difflib
import json
import shutil
from importlib import metadata
from pathlib import Path

import numpy as np
import pytest

from modelgen.abi import compiler_command
from sflm.cli import main

GENERATED = Path(__file__).resolve().parents[2] / "generated"
GOLDEN = {"paper-sim": "paper-sim-n2-clamped-mass", "paper-exp": "paper-exp-n1-clamped-mass"}
EXACT_KEYS = (  # not "library": whether one is built depends on the machine's compiler
    "format", "model", "modes", "sources", "header", "functions", "batch_chunk",
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


def _files(manifest: dict[str, object]) -> set[str]:
    """The files a golden folder holds: the sources, the header, the manifest."""
    return {*manifest["sources"], manifest["header"], "manifest.json"}  # type: ignore[misc]


def _library(folder: Path, manifest: dict[str, object], out: Path) -> Path:
    """The golden sources of ``folder`` compiled into ``out`` (skips without a C compiler)."""
    from modelgen.abi import compiler_command
    from modelgen.codegen import compile_library

    command = compiler_command()
    if command is None:
        pytest.skip("comparing sources of different generator versions needs a C compiler")
    out.mkdir(parents=True, exist_ok=True)
    library = out / f"lib{folder.name}.so"
    compile_library(folder / manifest["sources"][0], library, command)  # type: ignore[index]
    return library


def _same_functions(committed: Path, fresh: Path, manifest: dict[str, object], tmp_path: Path) -> None:
    """Every generated function of the committed sources equals the regenerated one at random inputs."""
    import casadi as ca

    from modelgen.abi import symbol

    rng = np.random.default_rng(20090402)
    old_lib = _library(committed, manifest, tmp_path)
    new_lib = _library(fresh, manifest, tmp_path / "fresh")
    p = np.asarray(manifest["parameters"]["values"])  # type: ignore[index]
    for role in manifest["functions"]:  # type: ignore[attr-defined]
        old, new = ca.external(symbol(role), str(old_lib)), ca.external(symbol(role), str(new_lib))
        args = [p if old.name_in(i) == "p" else 0.1 * rng.normal(size=old.size_in(i)) for i in range(old.n_in())]
        for a, b in zip(old(*args) if old.n_out() > 1 else [old(*args)], new(*args) if new.n_out() > 1 else [new(*args)]):
            a, b = np.asarray(a), np.asarray(b)
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * max(np.abs(a).max(initial=0), 1.0), err_msg=role)


@pytest.mark.parametrize("preset", sorted(GOLDEN))
def test_committed_sources_are_regenerated_identically(preset: str, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    committed = GENERATED / GOLDEN[preset]
    fresh = tmp_path / GOLDEN[preset]
    assert main(["generate", preset, "--out", str(fresh)]) == 0
    new_manifest = json.loads((fresh / "manifest.json").read_text())
    if request.config.getoption("--update-golden"):
        committed.mkdir(parents=True, exist_ok=True)
        for stale in {p.name for p in committed.iterdir()} - _files(new_manifest):
            (committed / stale).unlink()
        for name in _files(new_manifest):
            shutil.copy2(fresh / name, committed / name)
        return
    old_manifest = json.loads((committed / "manifest.json").read_text())
    assert {p.name for p in committed.iterdir()} == _files(old_manifest) == _files(new_manifest)
    for key in EXACT_KEYS:
        assert old_manifest[key] == new_manifest[key], key
    assert old_manifest["parameters"]["names"] == new_manifest["parameters"]["names"]
    tools = ("sflm", "sympy", "casadi")
    same_generators = all(old_manifest["versions"][t] == metadata.version(t) for t in tools)
    if same_generators:
        # the same generators: the same text, to the byte
        for name in [*new_manifest["sources"], new_manifest["header"]]:
            diff = _diff(committed / name, fresh / name)
            assert not diff, f"{name} differs from the committed golden file:\n{diff[:4000]}"
    # other generator versions may print the same functions differently: the committed
    # sources, compiled, must still compute what the regenerated ones compute
    if compiler_command() is not None or not same_generators:
        _same_functions(committed, fresh, new_manifest, tmp_path)
    # numbers: the same up to the last digits LAPACK may change between machines. Off-diagonal
    # modal integrals vanish by orthogonality and come out as round-off (~1e-13 of the diagonal):
    # they are compared on the scale of the largest parameter, not relatively.
    values = np.asarray(old_manifest["parameters"]["values"])
    np.testing.assert_allclose(new_manifest["parameters"]["values"], values, rtol=1e-10, atol=1e-12 * np.abs(values).max())
    for key in NUMERIC_KEYS:
        np.testing.assert_allclose(np.asarray(new_manifest[key]), np.asarray(old_manifest[key]), rtol=1e-9, atol=1e-9, err_msg=key)


def test_golden_folders_are_the_shipped_presets() -> None:
    assert {p.name for p in GENERATED.iterdir() if p.is_dir()} == set(GOLDEN.values())


def test_regenerated_functions_are_compared_across_versions(tmp_path: Path) -> None:
    # the path taken on a generator version drift must be able to fail: a committed source
    # with one constant changed computes something else
    committed = GENERATED / GOLDEN["paper-sim"]
    manifest = json.loads((committed / "manifest.json").read_text())
    altered = tmp_path / "altered"
    shutil.copytree(committed, altered)
    source = altered / manifest["sources"][0]
    text = source.read_text()
    assert "a0=(a0+a1);" in text  # the first sum of the shared mass-matrix function (I_h + I_t)
    source.write_text(text.replace("a0=(a0+a1);", "a0=(a0-a1);", 1))
    with pytest.raises(AssertionError):
        _same_functions(committed, altered, manifest, tmp_path)


def test_no_binaries_committed() -> None:
    import subprocess

    tracked = subprocess.run(["git", "ls-files", "generated"], cwd=GENERATED.parent, capture_output=True, text=True)
    if tracked.returncode != 0:
        pytest.skip("not a git checkout")
    assert not [f for f in tracked.stdout.split() if f.endswith((".so", ".dylib", ".dll", ".o", ".casadi"))]

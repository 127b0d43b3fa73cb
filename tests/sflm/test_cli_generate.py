"""``sflm generate``: the manifest contract, cache hits, unseen geometries."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

import modelgen
from modelgen.abi import ROLES, compiler_command
from sflm.cli import main
from _helpers import error_lines, run_cli

MANIFEST_KEYS = {"library", "sources", "header", "functions", "parameters", "hash", "versions", "natural_frequencies_hz", "zeros"}


@pytest.mark.skipif(compiler_command() is None, reason="needs a C compiler")
def test_generate_unseen_geometry(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    geo = tmp_path / "steel.toml"
    geo.write_text(
        'name = "steel-strip"\n[link]\nlength = 0.45\nyoungs_modulus = 200e9\ndensity = 7900\nwidth = 0.025\n'
        "thickness = 0.0015\n[hub]\ninertia = 0.01\nviscous_damping = 0.05\n[payload]\nmass = 0.08\n"
        "[damping]\nratio = 0.005\n[model]\nmodes = 3\n"
    )
    out = tmp_path / "out"
    assert main(["generate", str(geo), "--out", str(out)]) == 0
    manifest = json.loads((out / "manifest.json").read_text())
    assert MANIFEST_KEYS <= set(manifest)
    assert set(manifest["functions"]) == set(ROLES)
    assert manifest["functions"]["A"] == {"symbol": "sflm_A", "inputs": [["p", [len(manifest["parameters"]["names"]), 1]]], "outputs": [["A", [8, 8]]]}
    for rel in [manifest["library"], manifest["header"], *manifest["sources"]]:
        assert (out / rel).is_file()
    model = modelgen.load(geo)
    assert manifest["parameters"]["values"] == pytest.approx(model.parameters.tolist(), rel=1e-15)
    # the written library, loaded with casadi.external, gives the model's numbers
    A = np.array(ca.external("sflm_A", str(out / manifest["library"]))(manifest["parameters"]["values"]))
    np.testing.assert_array_equal(A, model.A)
    np.testing.assert_allclose(manifest["natural_frequencies_hz"], model.natural_frequencies_hz, rtol=1e-15)
    # info and the compiled functions agree
    capsys.readouterr()
    assert main(["info", str(geo), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(info["zeros"], manifest["zeros"], rtol=1e-15)


def test_second_generate_is_a_cache_hit(tmp_path: Path) -> None:
    cmd = [sys.executable, "-m", "sflm.cli", "generate", "paper-exp", "--out", str(tmp_path / "g")]
    subprocess.run(cmd, capture_output=True, text=True, check=True)
    second = subprocess.run(cmd, capture_output=True, text=True, check=True)
    assert "cache hit" in second.stdout


def test_generate_default_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["generate", "paper-exp", "--modes", "2", "--mode-shapes", "polynomial"]) == 0
    assert (tmp_path / "generated" / "paper-exp-n2-polynomial" / "manifest.json").is_file()


def test_generate_user_error(tmp_path: Path) -> None:
    proc = run_cli("generate", "paper-sim", "--modes", "-3")
    assert proc.returncode == 2 and len(error_lines(proc.stderr)) == 1 and "--modes" in proc.stderr

"""``sflm info``: readable output, the --json contract, one-line errors with status 2."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sflm.cli import main
from _helpers import error_lines, run_cli

JSON_KEYS = {
    "natural_frequencies_hz", "zeros", "internal_dynamics", "n_unstable", "CAB",
    "M", "K", "C", "D", "H", "A", "B", "C_out", "AI", "BI", "T",
}


def test_info_paper_sim_text(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", "paper-sim"]) == 0
    out = capsys.readouterr().out
    assert "±65.261" in out and "±56.314i" in out
    assert "3 unstable zeros" in out and "non-hyperbolic" in out
    assert "±61.25" in out  # the paper's values are shown beside ours


def test_info_json_contract(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", "paper-sim", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert JSON_KEYS <= set(data)
    assert data["n_unstable"] == 3
    assert data["natural_frequencies_hz"] == sorted(data["natural_frequencies_hz"])
    assert len(data["zeros"]) == 4 and all(len(z) == 2 for z in data["zeros"])
    assert len(data["A"]) == 6 and len(data["A"][0]) == 6
    assert len(data["T"]) == 6


def test_info_convergence_json(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", "paper-exp", "--modes", "3", "--convergence", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rows = data["convergence"]["rows"]
    assert [r["n"] for r in rows] == [1, 2, 3]
    assert data["convergence"]["continuum"]["natural_frequencies_hz"][1] == pytest.approx(52.94, abs=0.005)


def test_info_convergence_text(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["info", "paper-sim", "--modes", "3", "--convergence"]) == 0
    out = capsys.readouterr().out
    assert "FE" in out and "differ from FE" in out


@pytest.mark.parametrize(
    "args,needle",
    [
        (["info", "no-such-model"], "MODEL"),
        (["info", "paper-sim", "--modes", "0"], "--modes"),
        (["info", "paper-sim", "--mode-shapes", "bessel"], "--mode-shapes"),
        (["info", "paper-sim", "--modes", "two"], "--modes"),
    ],
)
def test_info_user_errors(args: list[str], needle: str) -> None:
    proc = run_cli(*args)
    assert proc.returncode == 2
    lines = error_lines(proc.stderr)
    assert len(lines) == 1 and needle in lines[0]
    assert "Traceback" not in proc.stderr


def test_info_bad_geometry_file(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\n[link]\nlength = -1\nflexural_rigidity = 1\nlinear_density = 1\n[hub]\ninertia = 1\n')
    proc = run_cli("info", str(bad))
    assert proc.returncode == 2
    assert len(error_lines(proc.stderr)) == 1 and "link.length" in proc.stderr


def test_convergence_plot(tmp_path: Path) -> None:
    proc = run_cli("info", "hyperbolic", "--convergence", "--max-modes", "3", "--plot", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "convergence.png").stat().st_size > 10_000 and str(tmp_path / "convergence.png") in proc.stdout
    alone = run_cli("info", "hyperbolic", "--plot", "--out", str(tmp_path))
    lines = error_lines(alone.stderr)
    assert alone.returncode == 2 and len(lines) == 1 and "--convergence" in lines[0]

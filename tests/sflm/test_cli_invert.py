"""``sflm invert``: the CSV and summary contracts, presets' defaults, plots, errors."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from sflm.cli import main
from _helpers import error_lines, run_cli

SUMMARY_KEYS = {
    "max_redefinition_error", "peak_torque", "max_torque_jump", "max_constraint_residual",
    "max_condition_number", "zeros", "n_unstable", "settings",
}
CSV_COLUMNS = ["t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "tau", "theta_d", "thetadot_d"]


def test_invert_paper_sim_writes_csv_summary_and_plots(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["invert", "paper-sim", "--out", str(tmp_path), "--plot", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert SUMMARY_KEYS <= set(summary)
    assert summary["settings"]["h"] == 2 and summary["settings"]["cdec"] == [1e-4, 1.0]
    assert len(summary["segments"]) == 5
    assert summary["max_redefinition_error"] == pytest.approx(5.73e-3, abs=5e-6)  # docs/method.md section 7
    assert json.loads((tmp_path / "summary.json").read_text()) == summary
    with open(tmp_path / "inversion.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == CSV_COLUMNS
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (5501, 8)
    assert np.abs(data[:, 5]).max() == pytest.approx(summary["peak_torque"])
    for name in ("output.png", "redefinition_error.png", "torque.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_invert_paper_exp_defaults(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["invert", "paper-exp", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "6 segments" in out and "r = 7" in out and "1 unstable zero" in out
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["settings"]["cdec"] == [0.01, 1.0]


def test_invert_unseen_geometry_and_settings(tmp_path: Path) -> None:
    geo = tmp_path / "alu.toml"
    geo.write_text('name = "alu"\n[link]\nlength = 0.6\nyoungs_modulus = 69e9\ndensity = 2700\nwidth = 0.03\n'
                   'thickness = 0.002\n[hub]\ninertia = 0.002\n[payload]\nmass = 0.05\ninertia = 2e-5\n')
    out = tmp_path / "out"
    code = main(["invert", str(geo), "--trajectory", "smoothstep:0.3:1.5:4", "--segments", "4", "--h", "1",
                 "--cdec", "0.001", "0.8", "--rate", "500", "--out", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["settings"]["segments"] == pytest.approx([0, 0.375, 0.75, 1.125, 1.5])
    assert summary["samples"] == 751 and summary["max_torque_jump"] < 1e-9


@pytest.mark.parametrize(
    "args,needle",
    [
        (["invert", "paper-sim", "--cdec", "0", "1"], "cdec"),
        (["invert", "paper-sim", "--cdec", "0.5", "0.1"], "cdec"),
        (["invert", "paper-sim", "--segments", "0"], "segments"),
        (["invert", "paper-sim", "--h", "0"], "h = 0"),
        (["invert", "paper-sim", "--rate", "-1"], "rate"),
        (["invert", "paper-sim", "--trajectory", "zigzag"], "--trajectory"),
        (["invert", "paper-sim", "--cdec", "0.9999", "1"], "residual"),
        (["invert", "modelgen/presets/paper-sim.toml"], "--trajectory"),
    ],
)
def test_invert_errors_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    proc = run_cli(*args, "--out", str(tmp_path), cwd=Path(__file__).resolve().parents[2])
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert len(error_lines(proc.stderr)) == 1 and needle in proc.stderr and "Traceback" not in proc.stderr


OWN = str(Path(__file__).resolve().parents[1] / "data" / "own-aluminium.toml")


def test_own_link_with_the_paper_settings_exits_2() -> None:
    # the issue: 1.38 m (here 1.17 m) off a 0.5 m move used to exit 0
    proc = run_cli("invert", OWN, "--trajectory", "smoothstep:0.5:2:2", "--segments", "5", "--h", "2", "--cdec", "1e-4", "1",
                   "--joining", "paper", "--out", "/dev/null/x")
    assert proc.returncode == 2
    assert len(error_lines(proc.stderr)) == 1 and "from the desired one" in proc.stderr and "--auto" in proc.stderr


def test_own_link_chooses_automatically(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["invert", OWN, "--trajectory", "smoothstep:0.5:2:2", "--max-torque", "0.2", "--objective", "error",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr()
    assert "automatic choice" in out.out and "less torque" not in out.out.split("automatic choice")[0]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["auto"]["members"] > 100 and summary["peak_torque"] <= 0.2
    assert summary["relative_redefinition_error"] < 1e-3
    # progress on stderr only past 2 s, as lines when stderr is not a terminal (sflm.progress.Reporter)
    assert all(line.startswith("sflm invert: ") for line in out.err.splitlines())


def test_max_error_and_joining_options(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["invert", "paper-sim", "--joining", "anchored", "--max-error", "1e-3", "--out", str(tmp_path), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["settings"]["joining"] == "anchored" and summary["max_error"] == 1e-3
    assert summary["settings"]["h"] == 2 and len(summary["segments"]) == 5  # the rest from the paper's member
    assert main(["invert", "paper-sim", "--max-error", "inf", "--segments", "1", "--out", str(tmp_path)]) == 0


@pytest.mark.parametrize(
    "args,needle",
    [
        (["invert", "paper-sim", "--max-error", "0"], "--max-error"),  # the command line's words, not Python's
        (["invert", "paper-sim", "--max-torque", "-1"], "--max-torque"),
        (["invert", "paper-sim", "--settings", "nowhere.json"], "--settings"),
        (["invert", "paper-sim", "--auto", "--settings", "x.json"], "settings"),
        (["invert", "paper-sim", "--joining", "welded"], "joining"),
    ],
)
def test_new_options_errors_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    proc = run_cli(*args, "--out", str(tmp_path), cwd=Path(__file__).resolve().parents[2])
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert len(error_lines(proc.stderr)) == 1 and needle in proc.stderr and "Traceback" not in proc.stderr

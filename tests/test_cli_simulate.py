"""``sflm simulate`` and ``sflm reproduce``: file contracts, the paper's defaults, errors."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from sflm.cli import main

SUMMARY_KEYS = {"final_tip_error", "max_tracking_error", "peak_torque", "settling_time"}


def test_simulate_paper_sim(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-sim", "--plant", "linear", "--t-end", "8", "--out", str(tmp_path), "--plot", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert SUMMARY_KEYS <= set(summary)
    assert summary["kp"] == 15.0 and summary["kd"] == 30.0 and summary["plant"] == "linear"
    with open(tmp_path / "simulation.csv") as handle:
        header = next(csv.reader(handle))
    assert header[:6] == ["t", "y", "y_d", "y_redef", "theta", "tau"]
    assert header[-2:] == ["delta_1", "delta_2"]
    for name in ("torque.png", "tip.png", "tip_error.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_simulate_paper_exp_controllers(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-exp", "--controller", "two-stage", "--t-end", "4", "--out", str(tmp_path / "a")]) == 0
    out = capsys.readouterr().out
    assert "pulses (stage 2)" in out and "0.55 N m sliding" in out
    two = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert main(["simulate", "paper-exp", "--controller", "pd", "--t-end", "4", "--out", str(tmp_path / "b")]) == 0
    pd = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert two["steady_tip_error"] < 1e-3 < 5e-3 < pd["steady_tip_error"]
    # the plant's friction can be set back to the compensated average
    assert main(["simulate", "paper-exp", "--controller", "pd", "--t-end", "2", "--coulomb-friction", "0.45",
                 "--breakaway-friction", "0.45", "--out", str(tmp_path / "c")]) == 0
    assert json.loads((tmp_path / "c" / "summary.json").read_text())["steady_tip_error"] < 1e-3


@pytest.mark.parametrize(
    "args,needle",
    [
        (["simulate", "paper-exp", "--kp", "-1"], "kp"),
        (["simulate", "paper-exp", "--t-end", "0.1"], "t_end"),
        (["simulate", "paper-exp", "--coulomb-friction", "0.7", "--breakaway-friction", "0.5"], "breakaway"),
        (["simulate", "paper-exp", "--plant-damping", "-0.1"], "zeta"),
        (["simulate", "paper-exp", "--controller", "lqr"], "--controller"),
        (["reproduce", "paper-xyz"], "CASE"),
    ],
)
def test_simulate_errors_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    proc = subprocess.run([sys.executable, "-m", "sflm.cli", *args, "--out", str(tmp_path)], capture_output=True, text=True)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stderr.count("\n") == 1 and needle in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.parametrize(
    "case,figures,needles",
    [
        ("paper-sim", [3, 4, 5, 6], ["±61.25", "±65.261", "5.733 mm", "1.56427 m"]),
        ("paper-exp", [8, 9, 10, 11, 12, 14, 15, 16], ["±212.00", "±232.054", "about 10 mm / about 1 mm", "Assumptions"]),
    ],
)
def test_reproduce(case: str, figures: list[int], needles: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["reproduce", case, "--out", str(tmp_path)]) == 0
    report = (tmp_path / "report.md").read_text()
    for needle in needles:
        assert needle in report
    for number in figures:
        assert list(tmp_path.glob(f"fig{number}_*.png")), number
    assert (tmp_path / "generated" / "manifest.json").is_file()
    numbers = json.loads((tmp_path / "numbers.json").read_text())
    if case == "paper-exp":
        sims = numbers["simulations"]
        assert sims["two-stage"]["steady_tip_error"] < 1e-3 < sims["pd"]["steady_tip_error"]

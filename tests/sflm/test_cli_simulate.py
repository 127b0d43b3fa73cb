"""``sflm simulate`` and ``sflm reproduce``: file contracts, defaults shared with the API, the report's honesty, errors."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

import modelgen
from inversion import invert, trajectory_from_spec
from modelgen.paper import CASES
from sflm.cli import main
from simulation import simulate
from simulation.cases import fitted_plant
from _helpers import assert_figures_inside_the_canvas, error_lines, kept_figures, run_cli

SUMMARY_KEYS = {"final_tip_error", "max_tracking_error", "peak_torque", "settling_time", "steady_tip_error",
                "residual_vibration", "settled", "plant"}
DATA = Path(__file__).resolve().parents[1] / "data"


def test_simulate_paper_sim(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-sim", "--plant", "linear", "--t-end", "8", "--out", str(tmp_path), "--plot", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert SUMMARY_KEYS <= set(summary)
    assert summary["kp"] == 15.0 and summary["kd"] == 30.0 and summary["plant"]["kind"] == "linear"
    assert summary["gains_source"].startswith("the paper")
    with open(tmp_path / "simulation.csv") as handle:
        header = next(csv.reader(handle))
        rows = sum(1 for _ in handle)
    assert header[:6] == ["t", "y", "y_d", "y_redef", "theta", "tau"]
    assert header[-2:] == ["delta_1", "delta_2"]
    assert rows == summary["samples"] == 8001
    for name in ("torque.png", "tip.png", "tip_error.png"):
        assert (tmp_path / name).stat().st_size > 10_000


def test_cli_and_api_defaults_agree(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The same defaults in Python and on the command line: plant, controller, gains, friction.
    assert main(["simulate", "paper-exp", "--t-end", "2", "--out", str(tmp_path), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    model = modelgen.load("paper-exp")
    api = simulate(model, invert(model, trajectory_from_spec("paper-exp")), t_end=2.0).summary
    for key in ("plant", "controller", "kp", "kd", "gains_source", "friction_compensation", "coulomb_friction",
                "breakaway_friction", "t_end"):
        assert cli[key] == api[key], key
    assert cli["final_tip_error"] == pytest.approx(api["final_tip_error"], rel=1e-9)
    assert cli["plant"]["differs_from_model"] == {}  # the model itself unless asked otherwise


def test_paper_plant_is_recorded(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-exp", "--controller", "two-stage", "--t-end", "3", "--paper-plant", "--json",
                 "--out", str(tmp_path / "a")]) == 0
    two = json.loads(capsys.readouterr().out)
    diffs = two["plant"]["differs_from_model"]
    assert {k: d["value"] for k, d in diffs.items()} == {"coulomb_friction": 0.55, "breakaway_friction": 0.6, "zeta": 0.01}
    assert all(d["source"] == CASES["paper-exp"].plant[k].source for k, d in diffs.items())
    assert json.loads((tmp_path / "a" / "summary.json").read_text()) == two
    # an option beats the fitted value, and says so
    assert main(["simulate", "paper-exp", "--t-end", "2", "--paper-plant", "--coulomb-friction", "0.5", "--json",
                 "--out", str(tmp_path / "b")]) == 0
    diffs = json.loads(capsys.readouterr().out)["plant"]["differs_from_model"]
    assert diffs["coulomb_friction"] == {"value": 0.5, "model": 0.45, "unit": "N m", "source": "command line (--coulomb-friction)"}


def test_text_report_lists_the_pulses(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-exp", "--controller", "two-stage", "--t-end", "3", "--paper-plant",
                 "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    summary = json.loads((tmp_path / "summary.json").read_text())
    line = next(l for l in out.splitlines() if l.strip().startswith("pulses (stage 2)"))
    widths = re.search(r"widths (.*) ms", line).group(1).split(", ")  # type: ignore[union-attr]
    assert len(widths) == len(summary["pulses"]) >= 2
    assert [float(w) for w in widths] == [round(p["width"] * 1e3, 1) for p in summary["pulses"]]
    assert "instead of the model's 0.45" in out  # each fitted value is named with the model's


def test_pulse_options_reach_the_law(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", "paper-exp", "--controller", "two-stage", "--t-end", "2", "--pulse-amplitude", "1.2",
                 "--pulse-period", "0.3", "--pulse-tolerance", "5e-4", "--json", "--out", str(tmp_path)]) == 0
    law = json.loads(capsys.readouterr().out)["pulse_law"]
    assert (law["amplitude"], law["period"], law["tolerance"], law["gain"]) == (1.2, 0.3, 5e-4, 0.8)


def test_own_geometry_gets_the_rule_gains(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["simulate", str(DATA / "own-aluminium.toml"), "--trajectory", "smoothstep:0.5:2", "--plant", "linear",
                 "--json", "--out", str(tmp_path)]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["gains_source"].startswith("rule") and s["kp"] > 0 and s["kd"] > 0
    assert s["settled"] and s["final_tip_error"] < 1e-3


@pytest.mark.parametrize(
    "args,needle",
    [
        (["simulate", "paper-exp", "--kp", "-1"], "kp"),
        (["simulate", "paper-exp", "--t-end", "0.1"], "--t-end"),
        (["simulate", "paper-exp", "--coulomb-friction", "0.7", "--breakaway-friction", "0.5"], "breakaway"),
        (["simulate", "paper-exp", "--plant-damping", "-0.1"], "zeta"),
        (["simulate", "paper-exp", "--controller", "lqr"], "--controller"),
        (["simulate", "paper-exp", "--controller", "two-stage", "--pulse-gain", "2"], "pulse_gain"),
        (["simulate", "paper-sim", "--controller", "two-stage"], "controller"),
        (["simulate", "paper-sim", "--paper-plant"], "--paper-plant"),
        (["simulate", "paper-sim", "--rate", "1e9"], "rate"),
        (["reproduce", "paper-xyz"], "CASE"),
    ],
)
def test_simulate_errors_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    proc = run_cli(*args, "--out", str(tmp_path))
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert len(error_lines(proc.stderr)) == 1 and needle in proc.stderr and "Traceback" not in proc.stderr


def _cells(report: str, first: str) -> list[str]:
    """The cells of the table row that starts with ``first``."""
    line = next(l for l in report.splitlines() if l.startswith(f"| {first} |"))
    return [c.strip() for c in line.strip("|").split("|")]


def test_reproduce_paper_sim(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    figures = kept_figures(monkeypatch)
    assert main(["reproduce", "paper-sim", "--out", str(tmp_path)]) == 0
    assert_figures_inside_the_canvas(figures)  # issue 25: every figure's text inside its canvas
    report = (tmp_path / "report.md").read_text()
    numbers = json.loads((tmp_path / "numbers.json").read_text())
    for number in (3, 4, 5, 6):
        assert list(tmp_path.glob(f"fig{number}_*.png")), number
    assert (tmp_path / "generated" / "manifest.json").is_file()
    inv = numbers["inversion"]
    assert _cells(report, "max abs(y~ - y_d)")[1] == f"{inv['max_redefinition_error'] * 1e3:.4g} mm" == "5.733 mm"
    assert _cells(report, "y~(t_f)")[1] == f"{inv['final_redefined_output']:.6g} m" == "1.56427 m"
    end = _cells(report, "end of the run")[1]
    pd = numbers["simulations"]["pd"]
    assert end.startswith(f"{pd['final_tip_error'] * 1e3:.3g} mm at 15 s")
    assert f"vibration {pd['residual_vibration'] * 1e3:.3g} mm p-p" in end
    # every assumption of the case is listed with its source
    for key, value in CASES["paper-sim"].assumptions().items():
        assert _cells(report, key)[2] == value.source


@pytest.mark.slow
def test_reproduce_paper_exp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    figures = kept_figures(monkeypatch)
    assert main(["reproduce", "paper-exp", "--out", str(tmp_path)]) == 0
    assert_figures_inside_the_canvas(figures)  # the sensitivity, acceleration and velocity figures too
    report = (tmp_path / "report.md").read_text()
    numbers = json.loads((tmp_path / "numbers.json").read_text())
    for number in (8, 9, 10, 11, 12, 14, 15, 16):
        assert list(tmp_path.glob(f"fig{number}_*.png")), number
    assert (tmp_path / "sensitivity.png").stat().st_size > 10_000
    sims = numbers["simulations"]
    # the fitted plant is the assumption, recorded in each run's summary
    fitted = fitted_plant(CASES["paper-exp"])
    diffs = sims["pd"]["plant"]["differs_from_model"]
    assert diffs["coulomb_friction"]["value"] == fitted["coulomb_friction"] and diffs["zeta"]["source"].startswith("assumed")
    assert sims["pd-model-plant"]["plant"]["differs_from_model"] == {}
    # what the paper observed, with the fitted plant: PD about a centimetre short; with the model as the plant, not
    assert 5e-3 < sims["pd"]["steady_tip_error"] < 2e-2
    assert sims["pd-model-plant"]["steady_tip_error"] < 1e-3
    # the sensitivity: the PD error grows with the mismatch; no damping leaves the two-stage run ringing
    friction = [r for r in numbers["sensitivity"]["friction"] if r["controller"] == "pd"]
    errors = [r["steady_tip_error"] for r in sorted(friction, key=lambda r: r["coulomb_friction"])]
    assert errors == sorted(errors) and errors[0] < 1e-3 < 5e-3 < errors[-1]
    undamped = next(r for r in numbers["sensitivity"]["damping"] if r["controller"] == "two-stage" and r["zeta"] == 0.0)
    assert undamped["residual_vibration"] > 5e-3 and not undamped["settled"]
    # the report prints these numbers, not a mean alone
    row = _cells(report, "0.55 / 0.6")
    pd55 = next(r for r in friction if r["coulomb_friction"] == 0.55)
    assert row[1] == (f"{pd55['steady_tip_error'] * 1e3:.3g} mm / {pd55['residual_vibration'] * 1e3:.3g} mm / "
                      f"{pd55['final_tip_error'] * 1e3:.3g} mm")
    end = _cells(report, "end of the run")
    assert "vibration" in end[2] and f"{sims['two-stage']['residual_vibration'] * 1e3:.3g} mm p-p" in end[2]
    for key, value in CASES["paper-exp"].assumptions().items():
        assert _cells(report, key)[2] == value.source
    assert "steady" not in "".join(l for l in report.splitlines() if l.startswith("| end of the run"))

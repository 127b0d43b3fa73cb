"""`sflm compare`: the causal inversion beside the baselines the paper argues against."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from _helpers import run_cli
from inversion.studies.compare import COMPARE_COLUMNS, METHODS

ROOT = Path(__file__).resolve().parents[3]


def _compare(preset: str, out: Path, *extra: str) -> list[dict[str, str]]:
    proc = run_cli("compare", preset, "--out", str(out), *extra, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    with open(out / "compare.csv", newline="") as handle:
        reader = csv.DictReader(handle)
        assert tuple(reader.fieldnames or ()) == COMPARE_COLUMNS
        return list(reader)


def test_paper_sim_side_by_side(tmp_path: Path) -> None:
    rows = {r["method"]: r for r in _compare("paper-sim", tmp_path, "--plot")}
    assert tuple(rows) == METHODS
    assert (tmp_path / "compare.png").stat().st_size > 10_000
    move = 1.57
    ssef, rest = rows["ssef"], rows["ssef-rest"]
    assert ssef["status"] == rest["status"] == "ok"
    assert float(ssef["max_redefinition_error"]) == pytest.approx(5.733e-3, rel=1e-3)  # the paper's member
    assert float(ssef["residual_vibration"]) > 1e-4 * move  # the free end leaves the link ringing
    assert float(rest["residual_vibration"]) <= 1e-9 * move and abs(float(rest["torque_at_end"])) <= 1e-9 * float(rest["peak_torque"])
    # the paper's argument, shown: the imaginary zeros leave no stable inverse
    assert rows["stable"]["status"] == "not-exist" and "purely imaginary" in rows["stable"]["message"]
    assert rows["stable"]["peak_torque"] == ""


def test_hyperbolic_side_by_side(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    from _helpers import assert_figures_inside_the_canvas, kept_figures
    from sflm.cli import main

    figures = kept_figures(monkeypatch)
    assert main(["compare", "hyperbolic", "--out", str(tmp_path), "--json", "--plot"]) == 0
    rows = {r["method"]: r for r in json.loads(capsys.readouterr().out)}
    assert_figures_inside_the_canvas(figures)  # issue 25: the torques on a log axis and the failed methods' legend inside
    assert all(rows[m]["status"] == "ok" for m in ("ssef", "ssef-rest", "polynomial", "stable", "ocp", "zv")), rows
    # the optimal-control feedforward, the limit at its period (10 ms) and bound (1 %): below every causal member's peak
    assert rows["ocp"]["peak_torque"] < min(rows[m]["peak_torque"] for m in ("ssef", "ssef-rest", "polynomial"))
    # judged where invert judges it (issue 47): the controller's period, 1 ms by default, each row saying its period and hold
    assert "at every 0.001 s sample" in rows["ocp"]["settings"]
    assert (rows["ocp"]["period"], rows["ocp"]["hold"]) == (0.001, "zoh") and (rows["ssef"]["period"], rows["ssef"]["hold"]) == (0.001, "point")
    assert rows["ocp"]["pre_actuation_time"] == 0.0 and rows["ocp"]["max_redefinition_error"] <= 0.01 * 1.57 * (1 + 1e-6)
    # ZVD lags the move by twice ZV's shaper: measured 8.0 % of the move from y_d, beyond the 5 % gate, and said so
    assert rows["zvd"]["status"] == "failed" and "does not shape the deflection" in rows["zvd"]["message"]
    assert all(r["seconds"] >= 0 for r in rows.values())
    assert rows["stable"]["pre_actuation_time"] > 0 and rows["stable"]["max_redefinition_error"] == 0.0
    assert rows["ssef"]["pre_actuation_time"] == 0.0  # causal: nothing before t0
    assert rows["polynomial"]["max_redefinition_error"] > rows["ssef-rest"]["max_redefinition_error"]


def test_a_system_s_residual_vibration_holds_its_static_input() -> None:
    # (s - 1)/((s + 1)(s + 2)), 1 in 3 s: stable inversion is y_d exactly and ends on u = y_d(t_f) / G(0) = -2. After its
    # last sample the plant is held there, as the acceptance's window holds it, and does not move; left without an input
    # it fell back towards 0, reported as 0.847 of vibration
    import scipy.signal as sg

    from inversion import invert, smoothstep
    from inversion.studies.compare import residual_vibration

    result = invert(sg.TransferFunction([1.0, -1.0], [1.0, 3.0, 2.0]), smoothstep(1.0, 3.0, 3), method="stable")
    assert float(result.tau[-1]) == pytest.approx(-2.0, rel=1e-9)
    assert residual_vibration(result) <= 1e-9


def test_a_system_without_zeros_is_compared_without_a_traceback() -> None:
    # 100/(s^2 + 2 s + 100): no internal dynamics. The polynomial redefinition's ranking raised an IndexError (every
    # compare of such a system ended in a traceback); it is refused by name, and optimal control holds the move
    from inversion.studies.compare import compare
    from inversion import trajectory_from_spec
    from sflm.systems import system_from_model_argument

    rows = {row["method"]: row for row in compare(system_from_model_argument("100/(s^2 + 2 s + 100)"),
                                                  trajectory_from_spec("smoothstep:1:10:3")).rows}
    assert rows["polynomial"]["status"] == "failed" and "a system with zeros" in rows["polynomial"]["message"]
    assert rows["ocp"]["status"] == "ok"


def test_the_family_s_rows_share_the_batches_they_both_solve(monkeypatch: pytest.MonkeyPatch) -> None:
    # (2 - s)/((s + 1)(s + 3)), 1 in 10 s (benchmarks/bench_chain.py's compare): the rest end's row searches the rest end's
    # part of the grid the first row searched too. Within compare each batch is solved once (measured: the rest row's
    # 0.54 s became 0.26 s), and each row is the row its method gives computed alone, bit for bit
    import inversion.family.auto as auto
    from inversion import trajectory_from_spec
    from inversion.api import resolve
    from inversion.family.method import Family
    from inversion.problem import Problem
    from inversion.studies.compare import _row, compare, compare_rows
    from sflm.systems import system_from_model_argument

    problem = Problem(system_from_model_argument("(2 - s)/((s + 1)(s + 3))"), trajectory_from_spec("smoothstep:1:10:3"))
    solved: list[int] = []
    original = auto.evaluate_members
    monkeypatch.setattr(auto, "evaluate_members", lambda *a, **k: solved.append(len(a[2])) or original(*a, **k))
    family_rows = [(name, method) for name, method in compare_rows() if isinstance(method, Family)]
    assert [name for name, _ in family_rows] == ["ssef", "ssef-rest"]
    alone = {name: _row(name, method, *method.compared(problem, resolve)[:1], None) for name, method in family_rows}
    batches_alone = len(solved)
    solved.clear()
    rows = {row["method"]: row for row in compare(problem).rows}
    assert len(solved) <= batches_alone - 30, (len(solved), batches_alone)  # measured: 132 batches alone, 96 within compare
    for name, row in alone.items():
        assert row["status"] == "ok"
        assert {k: v for k, v in rows[name].items() if k in row} == row, name

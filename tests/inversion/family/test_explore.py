"""The family explorer: its rows are what ``invert`` reports, its Pareto flag is right, and Dask gives the same table."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

import modelgen
from inversion import InversionError, experiment_trajectory, invert, smoothstep
from inversion.family.explore import EXPLORE_COLUMNS, explore, pareto_front
from sflm.cli import main
from _helpers import error_lines, run_cli

ROOT = Path(__file__).resolve().parents[3]
# a small grid around the paper's experiment member (6 segments, h = 2, Cdec (0.01, 1), paper)
GRID = dict(segments=[3, 6, 12], h=[1, 2], cdec_fast=[1e-2, 1e-6, 1e-10], cdec_slow=[1.0, 0.5], joining=["paper", "anchored"])


@pytest.fixture(scope="module")
def family():  # type: ignore[no-untyped-def]
    model = modelgen.load("paper-exp")
    return model, explore(model, experiment_trajectory(), **GRID, workers=1)


def test_rows_equal_invert_with_the_same_settings(family) -> None:  # type: ignore[no-untyped-def]
    model, ex = family
    assert len(ex.rows) == 3 * 2 * 3 * 2 * 2
    paper = [r for r in ex.rows if r["paper"]]
    assert len(paper) == 1 and paper[0]["max_redefinition_error"] == pytest.approx(1.3548e-3, abs=5e-8)  # docs/method.md
    picks = paper + [ex.best] + [r for r in ex.rows if r["status"] not in ("ok",)][:3] + ex.succeeded[::7]
    for row in picks:
        settings = dict(segments=row["segments"], h=row["h"], cdec=(row["cdec_fast"], row["cdec_slow"]), joining=row["joining"])
        try:
            # the row's figures are the member's own: no torque bound, as the explorer's rows (its choice has them)
            result = invert(model, experiment_trajectory(), **settings, max_torque=math.inf, max_torque_rate=math.inf)
        except InversionError as exc:
            assert row["status"] == exc.status, (row, str(exc))  # type: ignore[attr-defined]
            assert row["max_redefinition_error"] is None
            continue
        assert row["status"] == "ok", row
        s = result.summary
        assert row["max_redefinition_error"] == pytest.approx(s["max_redefinition_error"], rel=1e-12)
        assert row["peak_torque"] == pytest.approx(s["peak_torque"], rel=1e-12)
        assert row["max_condition_number"] == pytest.approx(s["max_condition_number"], rel=1e-9)


def test_pareto_flag(family) -> None:  # type: ignore[no-untyped-def]
    _, ex = family
    ok = ex.succeeded
    assert ok and all(r["pareto"] == 0 for r in ex.rows if r["status"] != "ok")
    for r in ok:
        dominated = any(
            o["max_redefinition_error"] <= r["max_redefinition_error"] and o["peak_torque"] <= r["peak_torque"]
            and (o["max_redefinition_error"] < r["max_redefinition_error"] or o["peak_torque"] < r["peak_torque"])
            for o in ok
        )
        assert r["pareto"] == int(not dominated), r
    assert ex.best["chosen"] == 1 and sum(r["chosen"] for r in ex.rows) == 1
    # the automatic choice's rule (issue 20): the least peak torque among the members within 1 % of the
    # move during the move and after it, at most 3 x the rigid need -- and its whole acceptance passed
    bound, limit = ex.summary["max_error"], ex.summary["max_torque"]
    assert bound == pytest.approx(0.01 * 0.1) and limit == pytest.approx(3 * ex.summary["rigid_torque"])
    within = [r for r in ok if r["max_redefinition_error"] <= bound and r["after_end_excursion"] <= bound and r["peak_torque"] <= limit]
    least = min(r["peak_torque"] for r in within)  # members within 2 % of it count as equal: the smallest error wins
    ties = [r for r in within if r["peak_torque"] <= 1.02 * least]
    assert ex.best["max_redefinition_error"] == min(r["max_redefinition_error"] for r in ties)
    assert ex.summary["acceptance"]["torque_ratio"] <= 3


def test_pareto_front_of_ties_and_duplicates() -> None:
    assert pareto_front([(1.0, 2.0), (1.0, 2.0), (2.0, 1.0), (2.0, 2.0), (0.5, 3.0)]) == [True, False, True, False, True]
    assert pareto_front([]) == []


def test_local_processes_give_the_same_table(family) -> None:  # type: ignore[no-untyped-def]
    model, serial = family
    parallel = explore(model, experiment_trajectory(), **GRID, workers=2)
    assert parallel.workers == "2 local processes"
    assert parallel.rows == serial.rows


@pytest.mark.slow
def test_a_dask_cluster_gives_the_same_table(family) -> None:  # type: ignore[no-untyped-def]
    distributed = pytest.importorskip("distributed")
    model, serial = family
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = explore(model, experiment_trajectory(), **GRID, executor=client)
    assert remote.workers.startswith("Dask scheduler tcp://")
    assert remote.rows == serial.rows


def test_files_and_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "explore"
    code = main(["explore", "paper-exp", "--segments", "3,6", "--h", "2", "--cdec-fast", "0.01,1e-6", "--cdec-slow", "1",
                 "--joining", "paper,anchored", "--workers", "1", "--out", str(out), "--plot", "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["members"] == 8 and summary["paper_member"]["segments"] == 6
    # whose summary.json it is: sflm invert and simulate refuse to write their runs over it
    assert summary["command"] == json.loads((out / "summary.json").read_text())["command"] == "explore"
    with open(out / "explore.csv") as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == EXPLORE_COLUMNS and len(rows) == 9
    assert (out / "pareto.png").stat().st_size > 10_000
    # the optimal-control front beside the family (issue 21): the least peak torque falls as the bound widens (an optimum
    # over a larger feasible set cannot be higher)
    from inversion.methods.ocp import FRONT_BOUNDS, FRONT_COLUMNS

    with open(out / "ocp_front.csv") as handle:
        front = list(csv.DictReader(handle))
    assert tuple(front[0]) == FRONT_COLUMNS and [float(r["relative_error"]) for r in front] == list(FRONT_BOUNDS)
    peaks = [float(r["peak_torque"]) for r in front if r["status"] == "ok"]
    assert len(peaks) >= 4 and all(b <= a * (1 + 1e-6) for a, b in zip(peaks, peaks[1:]))
    best = json.loads((out / "best.json").read_text())
    assert best["settings"]["segments"] in (3, 6) and best["max_redefinition_error"] == summary["best"]["max_redefinition_error"]
    # best.json is a member invert can reuse: the same figures
    code = main(["invert", "paper-exp", "--settings", str(out / "best.json"), "--out", str(tmp_path / "invert"), "--json"])
    assert code == 0
    again = json.loads(capsys.readouterr().out)
    assert again["max_redefinition_error"] == pytest.approx(best["max_redefinition_error"], rel=1e-12)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["explore", "paper-exp", "--segments", "3,x"], "--segments"),
        (["explore", "paper-exp", "--joining", "glued", "--segments", "3"], "joining"),
        (["explore", "paper-exp", "--h", "0", "--segments", "3"], "h = 0"),
        (["explore", "paper-exp", "--segments", "3", "--scheduler", "tcp://127.0.0.1:9"], "refused"),  # at once, not in 10 s
        (["explore", "modelgen/presets/paper-exp.toml"], "--trajectory"),
    ],
)
def test_explore_errors_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    proc = run_cli(*args, "--out", str(tmp_path), cwd=ROOT)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert len(error_lines(proc.stderr)) == 1 and needle in proc.stderr and "Traceback" not in proc.stderr


def test_members_with_too_much_torque_keep_their_figures() -> None:
    model = modelgen.load("paper-sim")
    ex = explore(model, smoothstep(1.57, 5.5, 5), segments=[5], h=[2], cdec_fast=[1e-4], cdec_slow=[1.0], joining=["paper"],
                 max_torque=0.1, workers=1)
    (row,) = ex.rows
    assert row["status"] == "max-torque" and row["peak_torque"] == pytest.approx(0.43096, abs=1e-5) and row["pareto"] == 0
    assert ex.best is None and not math.isnan(row["max_redefinition_error"])
    assert np.isfinite(row["max_condition_number"])


def test_a_refused_scheduler_address_is_told_at_once() -> None:
    # Dask retries a refused TCP address for its whole timeout (10 s); the CLI asks the socket first
    import socket

    from sflm.cli import scheduler_fault

    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        port = server.getsockname()[1]
        # something listens but says nothing: not a scheduler (a Dask scheduler greets at once)
        assert "sent nothing" in str(scheduler_fault(f"tcp://127.0.0.1:{port}", timeout=0.2))
    assert "refused" in str(scheduler_fault(f"tcp://127.0.0.1:{port}"))  # closed: refused
    assert scheduler_fault("inproc://x") is None and scheduler_fault("tcp://127.0.0.1:port") is None  # Dask's to judge
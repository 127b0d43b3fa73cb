"""A run of ``sflm invert`` consumed as it was judged (issue 47): ``simulate`` and ``fmu`` take ``--feedforward RUN``,
refusals are results with ``--json``, and a run killed at any moment leaves the old run or the new one, never a mix."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import modelgen
from inversion.errors import SettingsError
from inversion.realtime import runs
from inversion.realtime.runs import PREVIOUS, read_run
from sflm.cli import main
from simulation import simulate
from _helpers import error_lines, run_cli

DATA = Path(__file__).resolve().parents[1] / "data"
SHORT = str(DATA / "short-steel.toml")
#: On the short steel link the family and the re-plan fail these moves and the automatic choice is optimal control.
MOVE_A, MOVE_B = "smoothstep:0.2:0.08:2", "smoothstep:0.05:0.08:2"


@pytest.fixture(scope="module")
def short() -> modelgen.Model:
    return modelgen.load(SHORT)


@pytest.fixture(scope="module")
def run_a(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("run") / "a"
    assert main(["invert", SHORT, "--trajectory", MOVE_A, "--controller", "none", "--out", str(folder), "-q"]) == 0
    return folder


def _tau(folder: Path, model: modelgen.Model) -> np.ndarray:
    return np.asarray(read_run(folder, model).tau)


def test_a_run_of_optimal_control_is_read_as_judged(run_a: Path, short: modelgen.Model) -> None:
    summary = json.loads((run_a / "summary.json").read_text())
    assert summary["method"] == "ocp", "the link this test stands on must be one whose automatic choice is optimal control"
    rows = np.loadtxt(run_a / "inversion.csv", delimiter=",", skiprows=1)
    result = read_run(run_a, short)
    count = summary["sampled"]["samples"]
    # the table the acceptance judged, bit for bit: its rows, its period, held
    assert result.tau.size == count and np.array_equal(result.tau, rows[:count, 5])
    assert result.summary["settings"]["hold"] == "zoh" and result.summary["settings"]["period"] == summary["sampled"]["period"]
    assert result.signals is not None and result.signals.bounds[-1] == pytest.approx(0.08, abs=1e-15)
    for named in (run_a / "summary.json", run_a / "inversion.csv"):
        assert np.array_equal(read_run(named, short).tau, result.tau)


def test_the_plant_driven_by_a_read_run_gives_what_the_acceptance_judged(run_a: Path, short: modelgen.Model) -> None:
    # the linear plant driven by the table alone (CVODES) against the acceptance's exactly discretised plant at the rows
    result = read_run(run_a, short)
    sampled = result.summary["sampled"]
    sim = simulate(short, result, plant="linear", controller="none", t_end=1.0)
    on_rows = np.interp(result.t, sim.t, np.abs(sim.y - sim.y_d))
    assert on_rows.max() == pytest.approx(sampled["max_tip_error"], rel=1e-5)
    assert sim.summary["peak_torque"] == pytest.approx(float(np.abs(result.tau).max()), rel=1e-12)
    assert sim.summary["final_tip_error"] < 1e-6  # the window after the move, as judged


def test_simulate_feedforward_on_the_nonlinear_plant_with_the_pd(run_a: Path, tmp_path: Path) -> None:
    done = run_cli("simulate", SHORT, "--feedforward", str(run_a), "--controller", "pd", "--plant", "nonlinear",
                   "--out", str(tmp_path), "--json", "-q")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["controller"] == "pd" and summary["plant"]["kind"] == "nonlinear"
    assert summary["settled"] and summary["final_tip_error"] < 1e-4
    # the feedforward simulated is the run's: the PD adds to it, the table's own peak is the run's
    judged = json.loads((run_a / "summary.json").read_text())["peak_torque"]
    assert summary["peak_torque"] >= judged * (1 - 1e-12)


def test_a_run_refuses_the_inversion_arguments_beside_it(run_a: Path, tmp_path: Path) -> None:
    done = run_cli("simulate", SHORT, "--feedforward", str(run_a), "--trajectory", MOVE_B, "--out", str(tmp_path))
    assert done.returncode == 2 and len(error_lines(done.stderr)) == 1
    assert "--trajectory" in done.stderr and "--feedforward RUN" in done.stderr


@pytest.mark.parametrize("what", ["missing", "no-csv", "other-model", "not-a-run-file", "changed", "refused"])
def test_hostile_runs_are_refused(what: str, run_a: Path, tmp_path: Path) -> None:
    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    model = SHORT
    if what == "missing":
        folder = tmp_path / "nowhere"
    elif what == "no-csv":
        (folder / "inversion.csv").unlink()
    elif what == "other-model":
        model = str(DATA / "steel-strip.toml")
    elif what == "not-a-run-file":
        folder = folder / "other.txt"
        folder.write_text("t,tau\n0,1\n")
    elif what == "changed":
        text = (folder / "inversion.csv").read_text().splitlines()
        text[3] = text[3].replace(",", ",1", 1)
        (folder / "inversion.csv").write_text("\n".join(text) + "\n")
    elif what == "refused":
        summary = json.loads((folder / "summary.json").read_text())
        (folder / "summary.json").write_text(json.dumps({"status": "refused", "message": "no", "model": summary["model"]}))
    done = run_cli("simulate", model, "--feedforward", str(folder), "--out", str(tmp_path / "out"), "-q")
    assert done.returncode == 2, done.stdout
    lines = error_lines(done.stderr)
    assert len(lines) == 1 and "--feedforward" in lines[0], lines
    fmu = run_cli("fmu", model, "--feedforward", str(folder), "--out", str(tmp_path / "ff.fmu"), "-q")
    assert fmu.returncode == 2 and "--feedforward" in fmu.stderr
    assert not (tmp_path / "ff.fmu").exists()


def test_fmu_feedforward_takes_a_run(run_a: Path, tmp_path: Path) -> None:
    done = run_cli("fmu", SHORT, "--feedforward", str(run_a), "--out", str(tmp_path / "ff.fmu"), "--json", "-q")
    assert done.returncode == 0, done.stderr
    held = json.loads(done.stdout)
    summary = json.loads((run_a / "summary.json").read_text())
    assert held["run"] == summary["run"]["id"] and held["method"] == "ocp" and held["hold"] == "zoh"
    assert held["peak_torque"] == pytest.approx(summary["peak_torque"], rel=1e-12)
    assert (tmp_path / "ff.fmu").stat().st_size > 1000


def test_a_refusal_with_json_is_a_result(tmp_path: Path) -> None:
    # 0.2 m in 0.08 s on the 1 m steel strip: below its causal limit (issue 47's example)
    out = tmp_path / "refused"
    done = run_cli("invert", str(DATA / "steel-strip.toml"), "--trajectory", "smoothstep:0.2:0.08", "--out", str(out), "--json")
    assert done.returncode == 2 and len(error_lines(done.stderr)) == 1
    record = json.loads(done.stdout)
    assert record["status"] == "refused" and record["command"] == "invert" and record["error"] == "InversionError"
    assert record["reason"] == "causal-limit" and record["message"] in done.stderr
    limit = record["causal_limit"]
    assert limit["error"] > 0.002 and limit["shortest_duration"] > 0.08 and limit["bound"] == pytest.approx(0.002)
    written = json.loads((out / "summary.json").read_text())
    assert {k: v for k, v in written.items() if k != "run"} == record
    with pytest.raises(SettingsError, match="refused"):
        read_run(out, modelgen.load(str(DATA / "steel-strip.toml")))


def test_a_family_refusal_names_the_test_its_nearest_member_failed(tmp_path: Path) -> None:
    done = run_cli("invert", SHORT, "--trajectory", MOVE_A, "--method", "ssef", "--json", "-q")
    assert done.returncode == 2
    record = json.loads(done.stdout)
    assert record["reason"] == "no-member" and record["causal_limit"]["error"] < 0.002 and record["nearest"]
    for member in record["nearest"]:
        assert member["failed"] and all(isinstance(f, str) and f for f in member["failed"])


class _Killed(BaseException):
    """The process killed at a file-system step (nothing catches it, as nothing catches SIGKILL)."""


@pytest.mark.parametrize("step", range(9))
def test_killed_at_any_step_leaves_the_old_run_or_the_new(step: int, run_a: Path, short: modelgen.Model, tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    old = _tau(folder, short)
    calls = {"n": 0}
    real = {"replace": os.replace, "link": os.link}

    def counted(name: str):  # type: ignore[no-untyped-def]
        def step_(*args, **kwargs):  # type: ignore[no-untyped-def]
            if calls["n"] == step:
                raise _Killed()
            calls["n"] += 1
            return real[name](*args, **kwargs)
        return step_

    monkeypatch.setattr(os, "replace", counted("replace"))
    monkeypatch.setattr(os, "link", counted("link"))
    try:
        main(["invert", SHORT, "--trajectory", MOVE_B, "--out", str(folder), "--plot", "-q"])
        killed = False
    except _Killed:
        killed = True
    monkeypatch.undo()
    now = _tau(folder, short)
    if killed:
        assert np.array_equal(now, old), f"killed at step {step}: the old run must read back whole"
    else:
        assert not np.array_equal(now, old) and not (folder / PREVIOUS).exists()


def test_killed_by_a_signal_leaves_the_old_run_or_the_new(run_a: Path, short: modelgen.Model, tmp_path: Path) -> None:
    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    old = _tau(folder, short)
    new_folder = tmp_path / "new"
    assert main(["invert", SHORT, "--trajectory", MOVE_B, "--out", str(new_folder), "-q"]) == 0
    new = _tau(new_folder, short)
    seen = set()
    for delay in (0.3, 1.0, 1.6, 2.0, 2.4, 3.0):
        process = subprocess.Popen([sys.executable, "-m", "sflm.cli", "invert", SHORT, "--trajectory", MOVE_B, "--out", str(folder), "--plot", "-q"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(delay)
        process.send_signal(signal.SIGKILL)
        process.wait()
        tau = _tau(folder, short)
        assert np.array_equal(tau, old) or np.array_equal(tau, new)
        seen.add("old" if np.array_equal(tau, old) else "new")
        shutil.rmtree(folder)
        shutil.copytree(run_a, folder)
    assert "old" in seen


def test_keep_previous_keeps_only_a_whole_run(run_a: Path, tmp_path: Path) -> None:
    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    runs.keep_previous(folder)
    assert sorted(p.name for p in (folder / PREVIOUS).iterdir()) == ["inversion.csv"]
    (tmp_path / "new.csv").write_text("t\n")
    os.replace(tmp_path / "new.csv", folder / "inversion.csv")  # half replaced, as a writer replaces: what is kept is the run its summary names
    runs.keep_previous(folder)
    assert runs.file_digest(folder / PREVIOUS / "inversion.csv") == runs.file_digest(run_a / "inversion.csv")
    runs.forget_previous(folder)
    assert not (folder / PREVIOUS).exists()

"""A run of ``sflm invert`` consumed as it was judged (issue 47): ``simulate`` and ``fmu`` take ``--feedforward RUN``,
refusals are results with ``--json``, and a run killed at any moment leaves the old run or the new one, never a mix."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

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


@pytest.fixture(scope="module")
def inverted_b() -> list[Any]:
    """MOVE_B's inversion, computed by the first kill-at-a-step test that runs and served to the rest: the steps killed
    are the file system's, after the inversion (which each test would otherwise compute again, 4 s each)."""
    return []


@pytest.mark.parametrize("step", range(9))
def test_killed_at_any_step_leaves_the_old_run_or_the_new(step: int, run_a: Path, short: modelgen.Model, tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch, inverted_b: list[Any]) -> None:
    import copy
    import dataclasses

    import sflm.cli.invert as command

    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    old = _tau(folder, short)
    real_inverted = command.inverted

    def served(*args: Any, **kwargs: Any) -> Any:
        if not inverted_b:
            inverted_b.append(real_inverted(*args, **kwargs))
        # what the writing adds to the summary (the run's record) is not kept for the next test
        return dataclasses.replace(inverted_b[0], summary=copy.deepcopy(inverted_b[0].summary))

    monkeypatch.setattr(command, "inverted", served)
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


@pytest.mark.slow  # six real processes killed at times (12 s); every step's kill is the deterministic test above
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


def _tampered(run_a: Path, tmp_path: Path, edit: Any, csv: bytes | None = None) -> Path:
    """A copy of ``run_a`` whose summary ``edit(summary)`` changed (and whose table is ``csv``, its checksum recorded)."""
    folder = tmp_path / "run"
    shutil.copytree(run_a, folder)
    summary = json.loads((folder / "summary.json").read_text())
    if csv is not None:
        (folder / "inversion.csv").write_bytes(csv)
        summary["run"]["files"]["inversion.csv"] = hashlib.sha256(csv).hexdigest()
    edit(summary)
    (folder / "summary.json").write_text(json.dumps(summary))  # NaN and Infinity as Python's json writes them
    return folder


#: issue 59, item 6: 22 tracebacks from summary.json's types; each a refusal naming what is wrong
WRONG_TYPES: dict[str, tuple[Any, str]] = {
    "period-abc": (lambda s: s["sampled"].update(period="abc"), "sampled.period is a finite number > 0"),
    "period-nan": (lambda s: s["sampled"].update(period=float("nan")), "sampled.period is a finite number > 0"),
    "period-inf": (lambda s: s["sampled"].update(period=float("inf")), "sampled.period is a finite number > 0"),
    "period-list": (lambda s: s["sampled"].update(period=[0.001]), "sampled.period is a finite number > 0"),
    "period-true": (lambda s: s["sampled"].update(period=True), "sampled.period is a finite number > 0"),
    "rate-0": (lambda s: (s["sampled"].pop("period"), s["settings"].pop("period"), s["settings"].update(rate=0)),
               "settings.rate is a finite number > 0"),
    "sampled-list": (lambda s: s.update(sampled=[1, 2]), "its 'sampled' is a list, not a mapping"),
    "settings-str": (lambda s: s.update(settings="x"), "its 'settings' is a str, not a mapping"),
    "hold-5": (lambda s: s["sampled"].update(hold=5), "hold is one of 'point' or 'zoh'"),
    "run-null": (lambda s: s.update(run=None), "records its files"),
    "run-model-str": (lambda s: s["run"].update(model="x"), "records the model it was computed for"),
    "run-model-none": (lambda s: s["run"].pop("model"), "records the model it was computed for"),
}


@pytest.mark.parametrize("what", list(WRONG_TYPES))
def test_a_summary_of_the_wrong_types_is_refused_in_words(what: str, run_a: Path, short: modelgen.Model, tmp_path: Path) -> None:
    edit, words = WRONG_TYPES[what]
    folder = _tampered(run_a, tmp_path, edit)
    with pytest.raises(SettingsError, match="feedforward") as caught:
        read_run(folder, short)
    assert words in str(caught.value)


@pytest.mark.parametrize("csv", [b"\xff\xfe\x00\x01garbage\x80\x81", b"", b"t,y_d\n0,1\n", b"t,y_d,y_redef,ydot_redef,yddot_redef,tau,"
                                 b"theta_d,thetadot_d\n0,1,2\n"])
def test_a_table_that_is_not_the_run_s_is_refused_in_words(csv: bytes, run_a: Path, short: modelgen.Model, tmp_path: Path) -> None:
    # a binary inversion.csv whose checksum the summary records was a UnicodeDecodeError
    folder = _tampered(run_a, tmp_path, lambda s: None, csv)
    with pytest.raises(SettingsError, match="an inversion.csv"):
        read_run(folder, short)


def test_what_a_run_is_of_is_the_model_its_digest_matched(run_a: Path, short: modelgen.Model, tmp_path: Path) -> None:
    # the summary's own words for its model are not read back (a summary without "model" or with output_at = "x" was a
    # traceback in the C header's provenance); its figures that the C header quotes, edited, are a refusal in words
    def edit(summary: dict[str, Any]) -> None:
        del summary["model"]
        summary.update(output_at="x", modes="two")

    result = read_run(_tampered(run_a, tmp_path / "a", edit), short)
    assert (result.summary["model"], result.summary["modes"], result.summary["output_at"]) == (short.name, short.n, short.output_at)
    assert main(["fmu", SHORT, "--feedforward", str(tmp_path / "a" / "run"), "--out", str(tmp_path / "a.fmu"), "-q"]) == 0
    folder = _tampered(run_a, tmp_path / "b", lambda s: s.update(peak_torque="high"))
    assert main(["fmu", SHORT, "--feedforward", str(folder), "--out", str(tmp_path / "b.fmu"), "-q"]) == 2
    assert not (tmp_path / "b.fmu").exists()

"""What a hostile round met on the runs (issue 59, items 1-3): a run or a measurement replaced through ``--out``, another
link's or another output's run applied with exit 0, checksums the summary could switch off. Each case failed before."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from _helpers import error_lines, run_cli

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
OWN = DATA / "own-aluminium.toml"
MOVE = "smoothstep:0.5:2:2"


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A run of the aluminium link, and one of the same link's point at 0.5 m (``--output-at 0.5``)."""
    root = tmp_path_factory.mktemp("runs")
    for name, extra in (("run", []), ("r05", ["--output-at", "0.5"])):
        done = run_cli("invert", str(OWN), "--trajectory", MOVE, *extra, "--out", str(root / name), "-q")
        assert done.returncode == 0, done.stderr
    return {"run": root / "run", "r05": root / "r05"}


def _copy(run: Path, to: Path) -> Path:
    shutil.copytree(run, to)
    return to


def _refused(done, flag: str) -> None:  # type: ignore[no-untyped-def]
    assert done.returncode == 2 and len(error_lines(done.stderr)) == 1 and flag in done.stderr, done.stderr


def test_a_run_is_not_replaced_by_what_reads_it(runs: dict[str, Path], tmp_path: Path) -> None:
    run = _copy(runs["run"], tmp_path / "run")
    before = (run / "summary.json").read_bytes()
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(run), "--out", str(run), "-q"), "--out")
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(run / "summary.json"), "--out", str(run), "-q"), "--out")
    # another command into a run's folder: its summary would replace the run's
    _refused(run_cli("simulate", str(OWN), "--trajectory", MOVE, "--t-end", "3", "--out", str(run), "-q"), "sflm invert's")
    assert (run / "summary.json").read_bytes() == before


def test_a_place_it_would_refuse_is_refused_before_the_work(runs: dict[str, Path], tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    # the refusals above came after the work: simulate ran its 3-5 s simulation, invert its 8 s inversion, then refused
    # to write; now the work is never started (it would fail the test here)
    import inversion.family.explore as explore_module
    import simulation
    import sflm.cli.invert as invert_command

    def no_work(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise AssertionError("the work was started for a place to write that is refused")

    monkeypatch.setattr(simulation, "simulate", no_work)
    monkeypatch.setattr(invert_command, "inverted", no_work)
    monkeypatch.setattr(explore_module, "explore", no_work)
    run = _copy(runs["run"], tmp_path / "run")
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(run), "--out", str(run), "-q"), "--out")
    _refused(run_cli("simulate", str(OWN), "--trajectory", MOVE, "--t-end", "3", "--out", str(run), "-q"), "sflm invert's")
    simulated = tmp_path / "simulated"
    simulated.mkdir()
    (simulated / "summary.json").write_text(json.dumps({"run": {"command": "simulate"}}))
    _refused(run_cli("invert", str(OWN), "--trajectory", MOVE, "--out", str(simulated), "-q"), "sflm simulate's")
    assert [p.name for p in simulated.iterdir()] == ["summary.json"]
    _refused(run_cli("invert", str(OWN), "--trajectory", MOVE, "--out", str(run / "summary.json"), "-q"), "--out")
    # the C's folder is a file, the table's file a folder: refused before the inversion too, nothing written
    fresh = tmp_path / "fresh"
    _refused(run_cli("invert", str(OWN), "--trajectory", MOVE, "--export-c", str(run / "summary.json"), "--out", str(fresh), "-q"),
             "--export-c")
    _refused(run_cli("invert", str(OWN), "--trajectory", MOVE, "--export-table", str(run), "--out", str(fresh), "-q"),
             "--export-table")
    assert not fresh.exists()
    # sflm explore wrote its summary.json over a run's (the run then unreadable); and a run over explore's
    before = (run / "summary.json").read_bytes()
    _refused(run_cli("explore", str(OWN), "--trajectory", MOVE, "--out", str(run), "-q"), "sflm invert's")
    assert (run / "summary.json").read_bytes() == before
    explored = tmp_path / "explored"
    explored.mkdir()
    (explored / "summary.json").write_text(json.dumps({"model": "own-aluminium", "command": "explore"}))
    _refused(run_cli("invert", str(OWN), "--trajectory", MOVE, "--out", str(explored), "-q"), "sflm explore's")


def test_a_refusal_does_not_replace_a_good_run(runs: dict[str, Path], tmp_path: Path) -> None:
    run = _copy(runs["run"], tmp_path / "run")
    before = (run / "summary.json").read_bytes()
    done = run_cli("invert", str(OWN), "--trajectory", MOVE, "--max-error", "1e-9", "--json", "--out", str(run), "-q")
    assert done.returncode == 2 and json.loads(done.stdout)["status"] == "refused"  # the refusal on stdout, as before
    assert (run / "summary.json").read_bytes() == before
    done = run_cli("simulate", str(OWN), "--feedforward", str(run), "--kp", "-1", "--json", "--out", str(run), "-q")
    assert done.returncode == 2 and (run / "summary.json").read_bytes() == before


def test_a_measurement_is_not_replaced_by_the_calibration(tmp_path: Path) -> None:
    geometry = tmp_path / "arm.toml"
    shutil.copy(DATA / "bench-arm.toml", geometry)
    data = tmp_path / "f.toml"
    data.write_text("frequencies_hz = [3.0, 20.0]\nboundary = 'hub-free'\n")
    before = data.read_bytes(), geometry.read_bytes()
    _refused(run_cli("fit", str(geometry), "--data", str(data), "--out", str(data), "-q"), "--out")
    _refused(run_cli("fit", str(geometry), "--data", str(data), "--out", str(geometry), "-q"), "--out")
    link = tmp_path / "link.toml"
    link.symlink_to(data)
    _refused(run_cli("fit", str(geometry), "--data", str(data), "--out", str(link), "-q"), "symbolic link")
    assert (data.read_bytes(), geometry.read_bytes()) == before


def test_another_output_s_run_is_refused(runs: dict[str, Path]) -> None:
    # before: "max tracking error 1586 mm", exit 0 (a table for the point at 0.5 m judged at the tip)
    done = run_cli("simulate", str(OWN), "--feedforward", str(runs["r05"]), "-q", "--out", str(runs["r05"].parent / "sim"))
    _refused(done, "output at 0.5 m")
    _refused(run_cli("fmu", str(OWN), "--feedforward", str(runs["r05"]), "-q", "--out", str(runs["r05"].parent / "f.fmu")),
             "output at 0.5 m")


def test_another_link_s_run_under_the_same_name_is_refused(runs: dict[str, Path], tmp_path: Path) -> None:
    # before: exit 0 (half the Young's modulus, the same name)
    softer = tmp_path / "own-aluminium.toml"
    text = OWN.read_text()
    assert "youngs_modulus = 69e9" in text
    softer.write_text(text.replace("youngs_modulus = 69e9", "youngs_modulus = 34.5e9"))
    done = run_cli("simulate", str(softer), "--feedforward", str(runs["run"]), "-q", "--out", str(tmp_path / "sim"))
    _refused(done, "other values")


def test_the_paper_s_figures_are_shown_only_beside_the_paper_s_link(tmp_path: Path) -> None:
    # before: `sflm info` printed the paper's Table 1 for any geometry named paper-sim (EI 30 instead of 47.25 here)
    shipped = (ROOT / "modelgen" / "presets" / "paper-sim.toml").read_text()
    assert "flexural_rigidity = 47.25" in shipped
    (tmp_path / "other").mkdir()
    (tmp_path / "same").mkdir()
    (tmp_path / "other" / "paper-sim.toml").write_text(shipped.replace("flexural_rigidity = 47.25", "flexural_rigidity = 30.0"))
    (tmp_path / "same" / "paper-sim.toml").write_text(shipped)  # a copy of the shipped values: the paper's link still
    for folder, shown in (("other", False), ("same", True)):
        done = run_cli("info", str(tmp_path / folder / "paper-sim.toml"), "-q")
        assert done.returncode == 0, done.stderr
        assert ("Table 1" in done.stdout) is shown, (folder, done.stdout)
    done = run_cli("info", "paper-sim", "--modes", "3", "-q")  # the preset's link with another count: beside it, labelled
    assert done.returncode == 0 and "Table 1 (2 modes)" in done.stdout, done.stdout


@pytest.mark.parametrize("record", ["absent", None, {}, [], {"files": None}, {"files": {"../../x": "0" * 64}},
                                    {"files": {"/etc/hostname": "0" * 64}}])
def test_a_run_without_its_record_is_refused(runs: dict[str, Path], tmp_path: Path, record: object) -> None:
    run = _copy(runs["run"], tmp_path / "run")
    summary = json.loads((run / "summary.json").read_text())
    if record == "absent":
        del summary["run"]
    else:
        summary["run"] = record
    (run / "summary.json").write_text(json.dumps(summary))
    with open(run / "inversion.csv", "a") as handle:  # tampered: before, applied with exit 0
        handle.write("9.9,0,0,0,0,1e6,0,0\n")
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(run), "-q", "--out", str(tmp_path / "sim")), "--feedforward")


def test_a_move_changed_after_the_run_is_refused(tmp_path: Path) -> None:
    import numpy as np

    move = tmp_path / "move.csv"
    t = np.linspace(0, 2, 401)
    rows = [f"{float(a)!r},{float(0.25 * (1 - np.cos(np.pi * a / 2)))!r}" for a in t]
    move.write_text("t,y\n" + "\n".join(rows) + "\n")
    done = run_cli("invert", str(OWN), "--trajectory", str(move), "--out", str(tmp_path / "run"), "-q")
    assert done.returncode == 0, done.stderr
    move.write_text("t,y\n" + "\n".join(rows[:-1]) + "\n")  # changed since: its last sample gone
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(tmp_path / "run"), "-q", "--out", str(tmp_path / "sim")),
             "move.csv")


@pytest.mark.parametrize("spec", ["smoothstep:1:2:3", "smoothstep:0.5:2.2:2", "smoothstep:0.5:2:3"])
def test_a_summary_naming_another_move_than_its_table_s_is_refused(runs: dict[str, Path], tmp_path: Path, spec: str) -> None:
    # the summary itself is not checksummed: its move edited to another (or to the same distance in another time or
    # order), the table was judged against the move the summary now names, exit 0 ("max tracking error 862 mm" on the
    # paper's link); the table's y_d, whose file the record vouches for, must be the move the summary names
    run = _copy(runs["run"], tmp_path / "run")
    summary = json.loads((run / "summary.json").read_text())
    assert summary["trajectory_spec"] == "smoothstep:0.5:2.0:2"  # MOVE as the run spells it
    summary["trajectory_spec"] = spec
    (run / "summary.json").write_text(json.dumps(summary))
    _refused(run_cli("simulate", str(OWN), "--feedforward", str(run), "-q", "--out", str(tmp_path / "sim")), "y_d")
    _refused(run_cli("fmu", str(OWN), "--feedforward", str(run), "-q", "--out", str(tmp_path / "f.fmu")), "y_d")


def test_a_killed_writer_s_temporaries_are_swept_by_the_next_write(tmp_path: Path) -> None:
    # issue 59, item 14: a writer killed by kill -9 cannot remove its temporary (36 kills left 23 files, 14.7 MB); a
    # process's first write into a folder removes those of processes that no longer run, and leaves a running writer's
    # and what is not a temporary of ours alone
    import os
    import subprocess
    import sys

    from modelgen.files import write_json

    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True, check=True)
    dead = tmp_path / f".summary.json.{int(gone.stdout)}.0123abcd.tmp"
    alive = tmp_path / f".summary.json.{os.getppid()}.4567cdef.tmp"  # this test's parent runs: its file is not ours to take
    other = tmp_path / f".inversion.csv.{int(gone.stdout)}.89ab0123.tmp"  # another file's of the same dead writer
    mine = tmp_path / ".notes.tmp"  # not named as ours are
    for path in (dead, alive, other, mine):
        path.write_text("half a file")
    write_json(tmp_path / "summary.json", {"a": 1})
    assert json.loads((tmp_path / "summary.json").read_text()) == {"a": 1}
    assert not dead.exists() and not other.exists() and alive.exists() and mine.exists()


def test_fit_plot_never_leaves_the_old_figure_beside_a_new_calibration(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 59, item 14: `sflm fit --plot --out cal.toml` killed after the calibrated file and before its figure left the
    # new cal.toml beside the previous fit's fit.png; the figure is removed before the new file is written
    import sflm.plots
    from sflm.cli import main

    data = ROOT / "tests" / "data"
    out = tmp_path / "cal.toml"
    args = ["fit", str(data / "glass-fibre-rod.toml"), "--data", str(data / "bench-doublet.csv"), "--plot", "--out", str(out), "-q"]
    (tmp_path / "fit.png").write_bytes(b"the previous calibration's figure")

    def killed(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt  # stands for the kill between the two files

    monkeypatch.setattr(sflm.plots, "fit_figure", killed)
    assert main(args) != 0  # the command's own handling of an interrupt
    assert out.is_file() and not (tmp_path / "fit.png").exists()

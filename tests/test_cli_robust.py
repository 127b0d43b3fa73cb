"""The command line tried as a new user would: pipes, unwritable folders, version, usage, limits."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from _helpers import error_lines
from inversion.output import write_columns

ROOT = Path(__file__).resolve().parent.parent
OWN = str(ROOT / "tests" / "data" / "own-aluminium.toml")


def sflm(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sflm.cli", *args], capture_output=True, text=True, cwd=ROOT,
                          env={**os.environ, **(env or {})})


@pytest.mark.parametrize("args", [["invert", "paper-sim"], ["info", "paper-sim"], ["generate", "paper-exp"]])
def test_a_closed_pipe_is_no_traceback(args: list[str], tmp_path: Path) -> None:
    # `sflm ... | head -1`: the reader goes away; the writer stops quietly
    extra = ["--out", str(tmp_path / "out")] if args[0] != "info" else []
    reader = subprocess.Popen([sys.executable, "-c", "pass"], stdin=subprocess.PIPE)  # reads nothing, exits
    assert reader.stdin is not None
    reader.wait()  # the pipe has no reader left: the first write fails
    writer = subprocess.run([sys.executable, "-m", "sflm.cli", *args, *extra], stdout=reader.stdin, stderr=subprocess.PIPE,
                            text=True, cwd=ROOT)
    reader.stdin.close()
    assert "Traceback" not in writer.stderr and "BrokenPipe" not in writer.stderr, writer.stderr
    assert writer.returncode == 141  # 128 + SIGPIPE, as a writer killed by the signal


@pytest.mark.parametrize("command", ["invert", "simulate", "reproduce"])
@pytest.mark.parametrize("folder", ["/proc", "/proc/x", "afile/sub"])
def test_an_unwritable_out_folder_is_one_line(command: str, folder: str, tmp_path: Path) -> None:
    (tmp_path / "afile").write_text("")
    target = folder if folder.startswith("/") else str(tmp_path / folder)
    proc = sflm(command, "paper-sim", "--out", target)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    lines = error_lines(proc.stderr)
    assert len(lines) == 1 and "--out" in lines[0] and "written" in lines[0]


def test_generate_into_an_unwritable_folder_is_one_line() -> None:
    proc = sflm("generate", "paper-exp", "--out", "/proc")
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(error_lines(proc.stderr)) == 1


def test_an_unwritable_cache_is_one_line(tmp_path: Path) -> None:
    (tmp_path / "afile").write_text("")
    for cache in ("/proc", str(tmp_path / "afile" / "cache")):
        # nothing is cached there: the model must be built, and written, in it
        proc = sflm("info", OWN, "--modes", "3", env={"SFLM_CACHE_DIR": cache})
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        lines = error_lines(proc.stderr)
        assert len(lines) == 1 and "SFLM_CACHE_DIR" in lines[0] and cache in lines[0]


def test_version_and_usage() -> None:
    from sflm import __version__

    version = sflm("--version")
    assert version.returncode == 0 and version.stdout.strip() == f"sflm {__version__}"
    bare = sflm()
    assert bare.returncode == 2 and "usage: sflm" in bare.stderr and "invert" in bare.stderr


def test_convergence_names_max_modes() -> None:
    proc = sflm("info", "paper-sim", "--convergence", "--max-modes", "0")
    lines = error_lines(proc.stderr)
    assert proc.returncode == 2 and len(lines) == 1 and "--max-modes" in lines[0] and "1..20" in lines[0]


def test_the_sample_limit_is_stated() -> None:
    proc = sflm("invert", "paper-sim", "--rate", "1e7", "--out", "/dev/null/x")
    lines = error_lines(proc.stderr)
    assert proc.returncode == 2 and len(lines) == 1 and "rate" in lines[0] and "10000000 samples" in lines[0]


def test_csv_round_trips_and_reports_progress(tmp_path: Path, rng: np.random.Generator) -> None:
    columns = [rng.normal(size=250_001) * 10.0 ** rng.integers(-300, 300, size=250_001), np.arange(250_001.0)]
    columns[0][:3] = [0.0, -0.0, 1e-320]
    seen: list[tuple[int, int]] = []
    write_columns(tmp_path / "x.csv", ["a", "b"], columns, lambda done, total: seen.append((done, total)))
    back = np.loadtxt(tmp_path / "x.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(back, np.column_stack(columns))  # every double read back exactly
    assert (tmp_path / "x.csv").read_text().split("\n", 1)[0] == "a,b"
    assert seen[-1] == (250_001, 250_001) and len(seen) == 3

"""The command line tried as a new user would: pipes, unwritable folders, version, usage, limits."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from _helpers import error_lines, run_cli
from modelgen.files import write_columns

ROOT = Path(__file__).resolve().parents[2]
OWN = str(ROOT / "tests" / "data" / "own-aluminium.toml")


def sflm(*args: str) -> subprocess.CompletedProcess[str]:
    """``sflm ARGS`` in this process (the refusals below happen after start-up)."""
    return run_cli(*args, cwd=ROOT)


def sflm_process(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    """``python -m sflm.cli ARGS``: the entry point itself, or an environment read at start-up."""
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
        proc = sflm_process("info", OWN, "--modes", "3", env={"SFLM_CACHE_DIR": cache})
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        lines = error_lines(proc.stderr)
        assert len(lines) == 1 and "SFLM_CACHE_DIR" in lines[0] and cache in lines[0]


def test_version_and_usage() -> None:
    from sflm import __version__

    version = sflm_process("--version")
    assert version.returncode == 0 and version.stdout.strip() == f"sflm {__version__}"
    bare = sflm_process()
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


@pytest.mark.parametrize(
    "args,needle",
    [
        (["explore", "paper-exp", "--segments", "3", "--workers", "0"], "workers = 0"),
        (["explore", "paper-exp", "--segments", "3", "--workers", "-1"], "workers = -1"),
        (["invert", "paper-sim", "--trajectory", ""], "--trajectory = ''"),
        (["simulate", "paper-sim", "--kp", "1e12"], "1.17e+06 rad/s"),  # rang at 1.2e6 rad/s for minutes before
    ],
)
def test_inputs_once_accepted_silently_are_one_line(args: list[str], needle: str, tmp_path: Path) -> None:
    # issue 25: each of these ran (or ran for minutes) with exit 0
    proc = sflm(*args, "--out", str(tmp_path))
    assert proc.returncode == 2, proc.stdout
    (line,) = error_lines(proc.stderr)
    assert needle in line, line


def test_an_empty_settings_file_is_refused(tmp_path: Path) -> None:
    empty = tmp_path / "settings.json"
    empty.write_text("{}")
    proc = sflm("invert", "paper-sim", "--settings", str(empty), "--out", str(tmp_path))
    assert proc.returncode == 2
    (line,) = error_lines(proc.stderr)
    assert "--settings" in line and "a member" in line


def test_a_noisy_csv_says_so_and_takes_a_smoothing(tmp_path: Path, rng: np.random.Generator) -> None:
    # issue 25: a noisy CSV raised the peak torque 9x with no hint
    import warnings

    from inversion import smoothstep
    from inversion.signals.trajectory import from_csv, trajectory_from_spec
    from modelgen.errors import SflmWarning

    move = smoothstep(0.5, 2.0, 5)
    t = np.linspace(0.0, 2.0, 2001)
    path = tmp_path / "noisy.csv"
    write_columns(path, ["t", "y"], [t, move.derivative(t, 0) + 1e-6 * rng.normal(size=t.size)])
    with pytest.warns(SflmWarning, match=r"look noisy \(about (9\.\d|1\.0)e-0[67] rms.*noisy.csv:smoothing="):
        raw = from_csv(path)
    smoothed = trajectory_from_spec(f"{path}:smoothing=2e-9")
    peak = float(np.abs(move.derivative(t, 2)).max())
    assert float(np.abs(raw.derivative(t, 2)).max()) > 5 * peak  # what the interpolated noise does (measured 11x)
    assert float(np.abs(smoothed.derivative(t, 2)).max()) == pytest.approx(peak, rel=0.05)
    # the same smoothing from the command line: --smooth S (a CSV only)
    from sflm.cli import main

    assert main(["invert", "paper-sim", "--trajectory", str(path), "--smooth", "2e-9", "--segments", "4", "--h", "1", "--cdec",
                 "1e-4", "1", "--joining", "anchored", "--out", str(tmp_path / "inv"), "--json"]) == 0
    assert main(["invert", "paper-sim", "--smooth", "2e-9", "--out", str(tmp_path / "inv")]) == 2
    clean = tmp_path / "clean.csv"
    write_columns(clean, ["t", "y"], [t, move.derivative(t, 0)])
    with warnings.catch_warnings():
        warnings.simplefilter("error", SflmWarning)
        from_csv(clean)  # exact samples: no warning


def test_ctrl_c_inside_cvodes_is_an_interruption(monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 25: Ctrl-C during a long simulation reported a CVODES failure (exit 2) instead of "interrupted" (130)
    import simulation.integrate as integrate

    def interrupted(*_args):  # type: ignore[no-untyped-def]
        raise RuntimeError('CVode returned "CV_RHSFUNC_FAIL". rhs failed: KeyboardInterrupt')

    with pytest.raises(KeyboardInterrupt):
        integrate._call(interrupted, np.zeros(2), np.zeros(1), "in a test")


def test_rejected_values_show_plain_numbers() -> None:
    from modelgen.errors import SettingsError

    message = str(SettingsError("shaped mode", (np.float64(0.0), [np.float64(0.5)]), "a frequency > 0"))
    assert "np.float64" not in message and "(0.0, [0.5])" in message

"""The automatic choice against one command-line run of the paper's member, and its coarse first grid against the full one.

Run: ``python benchmarks/bench_auto.py [RUNS]``. Two parts, each a ratio against a baseline measured
in the same run (absolute times on shared machines are noisy):

1. ``sflm invert PRESET --modes N --auto`` against ``sflm invert paper-sim`` (the paper's member,
   the baseline), whole processes, run in turn (A B A B ...) and paired: the median of the
   pair-by-pair ratios for each case, and their median over the presets with 2 to 8 modes
   (issues 20 and 24: at most 3x);
2. in one process, the automatic choice from its coarse grid (:meth:`inversion.config.SearchGrid.coarse`)
   and from the explorer's full grid: the ratio of their times and of the peak torques they
   choose, on the presets and the own links of ``tests/data``.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import modelgen
import inversion.family.auto as auto
from inversion import InversionError, invert, trajectory_from_spec
from inversion.config import DEFAULTS

ROOT = Path(__file__).resolve().parent.parent
CLI_CASES = [("paper-sim", 2), ("paper-sim", 6), ("hyperbolic", 4), ("hyperbolic", 8), ("paper-exp", 2), ("near-non-hyperbolic", 5)]
GRID_CASES = [("paper-sim", 2, "paper-sim"), ("paper-sim", 6, "paper-sim"), ("hyperbolic", 4, "paper-sim"), ("paper-exp", 2, "paper-exp"),
              ("near-non-hyperbolic", 5, "paper-sim"), (str(ROOT / "tests/data/own-aluminium.toml"), 2, "smoothstep:0.5:2:2"),
              (str(ROOT / "tests/data/steel-strip.toml"), 2, "smoothstep:0.5:0.6:2"),
              (str(ROOT / "tests/data/steel-strip.toml"), 4, "smoothstep:0.5:1.0:2")]


def _seconds(command: list[str]) -> float:
    started = time.perf_counter()
    subprocess.run(command, check=True, capture_output=True)
    return time.perf_counter() - started


def cli_ratios(runs: int) -> None:
    with tempfile.TemporaryDirectory() as out:
        baseline = [sys.executable, "-m", "sflm.cli", "invert", "paper-sim", "--out", out, "--json"]
        _seconds(baseline)  # warm the model cache and the imports
        medians = []
        print(f"{'case':26s} {'auto (s)':>9s} {'paper (s)':>10s} {'ratio':>7s}")
        for name, n in CLI_CASES:
            command = [sys.executable, "-m", "sflm.cli", "invert", name, "--modes", str(n), "--auto", "--out", out, "--json"]
            _seconds(command)
            pairs = [(_seconds(command), _seconds(baseline)) for _ in range(runs)]
            ratio = statistics.median(a / b for a, b in pairs)
            medians.append(ratio)
            print(f"{name + ' n=' + str(n):26s} {statistics.median(a for a, _ in pairs):9.2f} "
                  f"{statistics.median(b for _, b in pairs):10.2f} {ratio:7.2f}", flush=True)
        print(f"median ratio over the presets with 2 to 8 modes: {statistics.median(medians):.2f} (target at most 3)")


def grid_ratios() -> None:
    coarse = dict(auto.GRID)
    full = DEFAULTS.grid.as_dict()
    print(f"\n{'case':44s} {'coarse (s)':>10s} {'full (s)':>9s} {'time ratio':>10s} {'torque ratio':>12s}")
    for name, n, spec in GRID_CASES:
        model = modelgen.load(name, modes=n)
        trajectory = trajectory_from_spec(spec)
        figures = []
        for grid in (coarse, full):
            auto.GRID.clear()
            auto.GRID.update(grid)
            started = time.perf_counter()
            try:
                peak = invert(model, trajectory, auto=True).summary["peak_torque"]
            except InversionError:
                peak = float("nan")
            figures.append((time.perf_counter() - started, peak))
        auto.GRID.clear()
        auto.GRID.update(coarse)
        (tc, pc), (tf, pf) = figures
        print(f"{Path(name).stem + ' n=' + str(n) + ' ' + spec:44s} {tc:10.2f} {tf:9.2f} {tc / tf:10.2f} {pc / pf:12.4f}", flush=True)


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    cli_ratios(runs)
    grid_ratios()


if __name__ == "__main__":
    main()

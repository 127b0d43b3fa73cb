"""Answers in seconds: the chain programmes' commands against one run of the paper's member (issue 46).

Run: ``python benchmarks/bench_chain.py [RUNS]``. The baseline is one run of the paper's member, ``sflm invert
paper-sim`` (a whole process: imports, the compiled model loaded, the inversion, its files), timed in turn with each
case (A B A B ...) after a warm-up of both; each case's figure is the median of the pair-by-pair ratios (absolute times
on these shared machines are noisy, a ratio measured in one run is not). The target printed is the tightest an issue
asks: issue 56's -- ``sflm info --period`` and a refusal at most 1x, the 6-mode optimal-control table 2x, the 4-corner
table 5x, ``compare`` on the transfer function 3x, the automatic choice's median over the presets 1.5x (each preset 2x)
-- where it is tighter than issue 46's:

* the bounded causal limit of the 3 mm strip's 0.5 m in 0.6 s at 1 ms, with 2 and with 4 modes: at most 1x -- the
  limit itself (:func:`inversion.methods.bounded_limit.bounded_limit`, in this process) against the baseline's
  process; ``sflm info --period``, which prints it beside the model's frequencies, zeros and continuum check (1.3 s of
  its own) and the shortest duration within the bounds, is shown too;
* an optimal-control table of a 0.4 s move of a glass-fibre rod with 6 modes at 1 ms (``--method ocp``): at most 5x;
* a refusal by the bounded limit (the automatic choice on the 3 mm strip's 0.6 s move, with the shortest duration within
  the bounds): at most 3x;
* ``sflm compare`` on a 10 s move of a transfer function: at most 20x (issue 46), 3x (issue 56);
* issue 60, item 3: the automatic choice on a transfer function with complex zeros to the right (its optimal-control
  table): at most 3x;
* issue 47: one optimal-control table for the heavy payload and its four corners (EI +-5 %, payload +-0.5 %; five
  plants, 30 states, three chain programmes: the least tube, the least peak, the smoothest): at most 25x (measured
  22x: 15 s); the automatic choice judged in the PD loop on its 0.343 s move (the tube tightened): at most 5x;
* the automatic choice (``--auto``) on the presets with 2 to 8 modes, the median of their ratios: at most 3x;
* issue 60, item 6: the automatic choice on the 3 mm strip's 0.5 m in 1.5 s within 2.5 mm, where the family's member
  is judged by the least peak any causal table can have (optimal control screened out by the member's own robustness
  radius): shown, no target (measured by farm-bench 2.48x; 10.9x while optimal control was asked; about 2x before);
* issue 57: the shortest smoothstep of the 3 mm strip within its drive (``steel-strip-3mm-drive.toml``), certified, with
  its table: at most 3x (the feedforward alone, and in both loops); the fastest move of any profile (``shortest:0.5`` at
  2 ms, certified to the row, the ZV-shaped bang-bang and the shortest smoothstep beside it): at most 5x;
* issue 60, item 4: the stiff aluminium bar's 0.3 m in 0.1 s (8 modes, an 11.4 s window), the default path, and with its
  EI within 5 %: shown, no target.

Each case's figures are printed after its ratio (``--json``'s), so that a run beside two CPU burners can be compared with
one on a free machine: the chain programme stops on its iteration limit alone, so they must agree to 1e-6.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
SFLM = [sys.executable, "-m", "sflm.cli"]
STRIP = str(DATA / "steel-strip-3mm.toml")
PRESETS = [("paper-sim", 2), ("paper-sim", 6), ("hyperbolic", 4), ("hyperbolic", 8), ("paper-exp", 2), ("near-non-hyperbolic", 5)]


def _run(command: list[str]) -> tuple[float, str]:
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    return time.perf_counter() - started, done.stdout if done.returncode == 0 else done.stderr.strip().splitlines()[-1]


def _figures(output: str) -> str:
    """The figures a case printed, in a line."""
    try:
        data = json.loads(output)
    except json.JSONDecodeError:
        return output[:160]
    if isinstance(data, dict) and "bounded_limit" in data:
        b = data["bounded_limit"]
        return f"E* = {b['error']!r}, shortest {b['shortest_duration']!r} s"
    if isinstance(data, dict) and "shortest" in data:
        b = data["shortest"]
        return f"no table in {b['lower_bound']:.5g} s, this one {b['duration']:.5g} s ({100 * b['gap']:.2g} % longer)"
    if isinstance(data, dict) and "peak_torque" in data:
        return f"{data['method']}: peak {data['peak_torque']!r}, held error {data['sampled']['max_tip_error']!r}"
    rows = data.get("rows", data) if isinstance(data, dict) else data
    return ", ".join(f"{r['method']} {r['status']} {r.get('peak_torque')!r}" for r in rows)[:200]


def _in_process_limit(modes: int, runs: int) -> tuple[float, float]:
    """The bounded limit's median seconds in this process, and its figure."""
    import modelgen
    from inversion import smoothstep
    from inversion.acceptance import Criteria
    from inversion.methods.bounded_limit import bounded_limit

    model, move = modelgen.load(STRIP, modes=modes), smoothstep(0.5, 0.6, 2)
    bounded_limit(model, move, Criteria(max_error=0.005, period=1e-3), shortest=False)
    times, error = [], 0.0
    for _ in range(runs):
        started = time.perf_counter()
        error = bounded_limit(model, move, Criteria(max_error=0.005, period=1e-3), shortest=False).error
        times.append(time.perf_counter() - started)
    return statistics.median(times), error


def main(runs: int) -> None:
    with tempfile.TemporaryDirectory() as out:
        baseline = [*SFLM, "invert", "paper-sim", "--out", out, "--json", "-q"]
        _run(baseline)
        paper = statistics.median(_run(baseline)[0] for _ in range(runs))
        print(f"baseline: the paper's member, sflm invert paper-sim: {paper:.2f} s (median of {runs})\n")
        print(f"{'case':44s} {'case (s)':>9s} {'ratio':>7s} {'target':>7s}  figures")
        for modes in (2, 4):
            seconds, error = _in_process_limit(modes, runs)
            print(f"{f'bounded limit, 3 mm strip, {modes} modes (itself)':44s} {seconds:9.3f} {seconds / paper:7.2f} {1:7.0f}  "
                  f"E* = {error!r}", flush=True)
        cases: list[tuple[str, list[str], float | None]] = [
            ("sflm info --period, 3 mm strip, 2 modes", [*SFLM, "info", STRIP, "--trajectory", "smoothstep:0.5:0.6:2", "--period",
                                                          "0.001", "--json", "-q"], 1.0),
            ("sflm info --period, 3 mm strip, 4 modes", [*SFLM, "info", STRIP, "--modes", "4", "--trajectory", "smoothstep:0.5:0.6:2",
                                                          "--period", "0.001", "--json", "-q"], 1.0),
            ("ocp table, glass-fibre rod, 6 modes, 0.4 s", [*SFLM, "invert", str(DATA / "glass-fibre-rod.toml"), "--modes", "6",
                                                             "--trajectory", "smoothstep:0.3:0.4:2", "--method", "ocp", "--out", out,
                                                             "--json", "-q"], 2.0),
            ("refusal by the bounded limit, 3 mm strip", [*SFLM, "invert", STRIP, "--trajectory", "smoothstep:0.5:0.6:2", "--out", out,
                                                          "-q"], 1.0),
            ("ocp table, heavy payload, 4 corner plants", [*SFLM, "invert", str(DATA / "heavy-payload.toml"), "--trajectory",
                                                          "smoothstep:0.5:0.6:2", "--method", "ocp", "--uncertainty",
                                                          "link.flexural_rigidity=5%,payload.mass=0.5%", "--out", out, "--json",
                                                          "-q"], 5.0),
            ("auto in the PD loop, heavy payload, 0.343 s", [*SFLM, "invert", str(DATA / "heavy-payload.toml"), "--trajectory",
                                                             "smoothstep:0.5:0.343:2", "--controller", "pd", "--out", out,
                                                             "--json", "-q"], 5.0),
            ("compare, (2 - s)/((s + 1)(s + 3)), 10 s", [*SFLM, "compare", "(2 - s)/((s + 1)(s + 3))", "--trajectory",
                                                         "smoothstep:1:10:3", "--out", out, "--json", "-q"], 3.0),
            # issue 60, item 3: complex zeros to the right (0.6 +- 2.94i); the family and the re-plan fail, optimal control's
            # table is returned; the family's first grid is solved while HPIPM solves the bounded limit
            ("complex zeros to the right, 4.4 s", [*SFLM, "invert", "(s^2 - 1.2 s + 9)/((s + 1)(s + 2)(s^2 + 0.8 s + 4))",
                                                    "--trajectory", "smoothstep:1:4.4:3", "--out", out, "--json", "-q"], 3.0),
            # issue 60, item 6: the automatic choice judging the family's member by the least peak (optimal control screened
            # out by the member's radius: the member kept); no target yet, the everyday cost of the judgement
            ("least peak's judgement, 3 mm strip, 1.5 s", [*SFLM, "invert", STRIP, "--trajectory", "smoothstep:0.5:1.5",
                                                            "--max-error", "0.0025", "--out", out, "--json", "-q"], None),
            # issue 57: the shortest smoothstep of the 3 mm strip with its drive, certified, and its table (alone; both loops)
            ("shortest smoothstep, 3 mm strip, alone", [*SFLM, "invert", str(DATA / "steel-strip-3mm-drive.toml"), "--trajectory",
                                                        "smoothstep:0.5:shortest:2", "--max-error", "0.005", "--controller", "none",
                                                        "--out", out, "--json", "-q"], 3.0),
            ("shortest smoothstep, 3 mm strip, both loops", [*SFLM, "invert", str(DATA / "steel-strip-3mm-drive.toml"), "--trajectory",
                                                             "smoothstep:0.5:shortest:2", "--max-error", "0.005", "--out", out,
                                                             "--json", "-q"], 3.0),
            # issue 57, item 3: the fastest move of any profile, certified to the row, with its table (alone; both loops)
            ("fastest move, any profile, 3 mm strip, alone", [*SFLM, "invert", str(DATA / "steel-strip-3mm-drive.toml"), "--trajectory",
                                                             "shortest:0.5", "--max-error", "0.005", "--period", "0.002",
                                                             "--controller", "none", "--out", out, "--json", "-q"], 5.0),
            ("fastest move, any profile, both loops", [*SFLM, "invert", str(DATA / "steel-strip-3mm-drive.toml"), "--trajectory",
                                                      "shortest:0.5", "--max-error", "0.005", "--period", "0.002", "--out", out,
                                                      "--json", "-q"], 5.0),
            # issue 60, item 4: a ringing link (8 modes, 0.1 % damping, an 11.4 s window after its 0.1 s move) -- the
            # default path (the family, the re-plan, optimal control planned for both loops) and with EI +-5 % (each
            # corner alone and in its loop); no target: refused after 124 s and 263 s before the window was condensed
            ("ringing bar, 11.4 s window, both loops", [*SFLM, "invert", str(DATA / "aluminium-bar.toml"), "--trajectory",
                                                        "smoothstep:0.3:0.1:2", "--out", out, "--json", "-q"], None),
            ("ringing bar, EI +-5 %, both loops", [*SFLM, "invert", str(DATA / "aluminium-bar.toml"), "--trajectory",
                                                   "smoothstep:0.3:0.1:2", "--uncertainty", "link.flexural_rigidity=5%", "--out",
                                                   out, "--json", "-q"], None),
        ] + [(f"auto, {name} n={n}", [*SFLM, "invert", name, "--modes", str(n), "--auto", "--out", out, "--json", "-q"], 2.0)
             for name, n in PRESETS]
        autos = []
        for label, command, target in cases:
            _, output = _run(command)  # warm-up: the model compiled and cached
            pairs = [(_run(command)[0], _run(baseline)[0]) for _ in range(runs)]
            ratio = statistics.median(a / b for a, b in pairs)
            if label.startswith("auto"):
                autos.append(ratio)
            shown = "" if target is None else f"{target:.0f}"
            print(f"{label:44s} {statistics.median(a for a, _ in pairs):9.2f} {ratio:7.2f} {shown:>7s}  {_figures(output)}", flush=True)
        print(f"{'the automatic choice, median over the presets':44s} {'':9s} {statistics.median(autos):7.2f} {1.5:7.1f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)

"""The causal limit's cost against one automatic choice on the presets (issue 33), and the held judgement's.

Run: ``python benchmarks/bench_causal_limit.py [RUNS]``. In one process, for each case (the presets with
their own trajectory and another, the own links): the median over ``RUNS`` of the time of
:func:`inversion.lti.causal_limit.causal_limit` (with its shortest duration for 1 % of the move) and of one
automatic choice (``invert(..., auto=True)``), each measured in turn, and their ratio; then the limit itself.
The limit should cost a small fraction of the choice it lets the command line skip.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import modelgen
from inversion import InversionError, invert, trajectory_from_spec
from inversion.lti.causal_limit import causal_limit
from inversion.threads import one_thread

ROOT = Path(__file__).resolve().parent.parent
CASES = [("paper-sim", "paper-sim"), ("paper-sim", "smoothstep:1.57:5.5:3"), ("paper-exp", "paper-exp"), ("hyperbolic", "paper-sim"),
         ("near-non-hyperbolic", "paper-sim"), (str(ROOT / "tests/data/own-aluminium.toml"), "smoothstep:0.5:2:3"),
         (str(ROOT / "tests/data/steel-strip.toml"), "smoothstep:0.5:0.6:2")]


def _seconds(call: object) -> float:
    started = time.perf_counter()
    try:
        call()  # type: ignore[operator]
    except InversionError:
        pass  # a refusal costs its search too
    return time.perf_counter() - started


def main(runs: int) -> None:
    print(f"{'case':48s} {'limit (ms)':>10s} {'auto (ms)':>10s} {'ratio':>8s}  limit")
    ratios = []
    for name, spec in CASES:
        model, trajectory = modelgen.load(name), trajectory_from_spec(spec)
        bound = 0.01 * trajectory.move()
        with one_thread():
            causal_limit(model, trajectory, bound)  # imports and caches warm
            pairs = [(_seconds(lambda: causal_limit(model, trajectory, bound)), _seconds(lambda: invert(model, trajectory, auto=True)))
                     for _ in range(runs)]
        limit = causal_limit(model, trajectory, bound)
        ratio = statistics.median(a / b for a, b in pairs)
        ratios.append(ratio)
        label = f"{Path(name).stem} {spec}"
        print(f"{label:48s} {1e3 * statistics.median(a for a, _ in pairs):10.1f} {1e3 * statistics.median(b for _, b in pairs):10.0f} "
              f"{ratio:8.4f}  {100 * limit.relative_error:.3g} % ({limit.method}), shortest for 1 %: {limit.shortest_duration:.3g} s",
              flush=True)
    print(f"median ratio, the limit over one automatic choice: {statistics.median(ratios):.4f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)

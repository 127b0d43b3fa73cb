"""The family explorer and the automatic choice: cost per member against one inversion, throughput.

Run: ``python benchmarks/bench_family.py``. Prints, in one run:

1. one in-process 1 kHz ``invert`` of paper-sim with the paper's member -- as shipped (solve,
   closed-form figures, solver and extended-precision checks, plant check, sampling) and its
   core alone (solve and 1 kHz sampling, what an unverified inversion costs) -- the baselines;
2. the explorer on its default grid for paper-sim (about 3 000 members) on all cores and on
   one: members per second, and the wall time per member as a ratio of each baseline
   (targets: ratio to one ``invert`` at most 0.25; more than 1000 members per second);
3. the automatic choice on the own aluminium link with the quintic (target: under 5 s).

Absolute times on shared machines are noisy: each figure is a median of repeats, and the
ratios compare measurements of the same run.
"""

from __future__ import annotations

import os
import statistics
import time
from pathlib import Path

import numpy as np

import modelgen
from inversion import explore, invert, smoothstep
from inversion.family.redefinition import Redefinition
from inversion.family.ssef import build_plan, solve_plan
from inversion.lti.system import NormalForm

ROOT = Path(__file__).resolve().parent.parent


def median_time(fn, repeat: int) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def core_inversion(model, traj) -> None:  # type: ignore[no-untyped-def]
    """Solve the paper's member and sample it at 1 kHz, without figures or checks."""
    form = NormalForm.of_model(model)
    modal = form.modal()
    plan = build_plan(modal, traj, np.linspace(0.0, 5.5, 6), 2, [(1e-4, 1.0)], "paper", np.zeros(modal.lam.size, complex))
    redef = Redefinition(solve_plan(plan), 0, form)
    t = np.arange(5501) / 1000.0
    values = redef.sample(t)
    X = form.state(values["y"], values["ydot"], values["XI"])
    model.functions.inverse_torque(model.parameters, X, values["yddot"])


def main() -> None:
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    model = modelgen.load("paper-sim")
    traj = smoothstep(1.57, 5.5, 5)
    full = lambda: invert(model, traj, rate=1000.0)  # noqa: E731  the paper's case: the paper's member
    full()
    core_inversion(model, traj)
    t_full = median_time(full, 15)
    t_core = median_time(lambda: core_inversion(model, traj), 15)
    print(f"baseline: one 1 kHz invert of paper-sim (the paper's member), median of 15: {t_full * 1e3:.1f} ms as shipped, "
          f"{t_core * 1e3:.1f} ms for its core (solve + sampling, no figures or checks)")

    explore(model, traj, segments=[5], workers=1)  # warm up the worker code paths
    runs = []
    for _ in range(3):
        family = explore(model, traj)
        runs.append(family.seconds)
    seconds = statistics.median(runs)
    members = len(family.rows)
    per_member = seconds / members
    serial = explore(model, traj, workers=1)
    print(f"explorer, default grid: {members} members ({len(family.succeeded)} ok) on {family.workers}: "
          f"{seconds:.2f} s (median of 3) = {members / seconds:.0f} members/s   target > 1000/s: "
          f"{'met' if members / seconds > 1000 else 'MISSED'}")
    print(f"  wall time per member {per_member * 1e3:.3f} ms = {per_member / t_full:.3f} x one invert as shipped "
          f"(target <= 0.25: {'met' if per_member / t_full <= 0.25 else 'MISSED'}), {per_member / t_core:.3f} x its core")
    print(f"  on one process: {serial.seconds:.2f} s = {members / serial.seconds:.0f} members/s, "
          f"{serial.seconds / members / t_full:.3f} x one invert, {serial.seconds / members / t_core:.3f} x its core "
          f"({cores} cores here)")

    own = modelgen.load(ROOT / "tests" / "data" / "own-aluminium.toml")
    quintic = smoothstep(0.5, 2.0, 2)
    invert(own, quintic)  # warm up
    t_auto = median_time(lambda: invert(own, quintic), 3)
    chosen = invert(own, quintic)
    s = chosen.summary
    print(f"auto on the own aluminium link, quintic: {t_auto:.2f} s (median of 3; {s['auto']['members']} members)   "
          f"target < 5 s: {'met' if t_auto < 5 else 'MISSED'}; chose {chosen.settings.segment_count} segments, "
          f"{chosen.settings.joining}: {s['max_redefinition_error'] * 1e3:.3f} mm, {s['peak_torque']:.4f} N m")


if __name__ == "__main__":
    main()

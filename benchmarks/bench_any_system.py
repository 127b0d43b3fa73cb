"""The link through the generic core against its compiled path (issue 10: at most 2x).

Run: ``python benchmarks/bench_any_system.py [--repeats 7]``.

For each preset the same member is inverted twice: from the loaded model (compiled
Eq. (12), the normal form of Eq. (14)) and from ``(A, B, C_out)`` as a generic system
(:mod:`inversion.lti.linear_system`: numerical normal form, NumPy Eq. (12)). Printed: the median
time of each over ``--repeats`` runs, their ratio (target <= 2), the one-off conversion
cost (normal form and the zeros' cross-check) as a ratio to the compiled inversion, and the
largest torque difference (of the peak). Then the automatic choice for three transfer
functions that are not links, for scale.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import modelgen
from bench_family import median_time
from inversion import invert, smoothstep, trajectory_from_spec
from inversion.lti.linear_system import as_linear_system
from inversion.threads import one_thread

MEMBER = {"segments": 5, "h": 1, "cdec": (1e-3, 1.0), "joining": "anchored"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(f"{'preset':22s} {'compiled s':>10s} {'generic s':>10s} {'ratio':>6s} {'convert':>8s} {'|du|/peak':>10s}")
    worst = 0.0
    for preset in ("paper-sim", "paper-exp", "hyperbolic", "near-non-hyperbolic"):
        model = modelgen.load(preset)
        trajectory = trajectory_from_spec(preset if preset.startswith("paper") else "paper-sim")
        matrices = (model.A, model.B, model.C_out)
        system = as_linear_system(matrices, name=preset)
        compiled = invert(model, trajectory, **MEMBER)  # warm caches on both paths
        generic = invert(system, trajectory, **MEMBER)
        t_compiled = median_time(lambda: invert(model, trajectory, **MEMBER), args.repeats)
        t_generic = median_time(lambda: invert(system, trajectory, **MEMBER), args.repeats)
        with one_thread():
            t_convert = median_time(lambda: as_linear_system(matrices, name=preset), args.repeats)
        ratio = t_generic / t_compiled
        worst = max(worst, ratio)
        du = float(np.abs(generic.u - compiled.tau).max() / np.abs(compiled.tau).max())
        print(f"{preset:22s} {t_compiled:10.4f} {t_generic:10.4f} {ratio:6.2f} {t_convert / t_compiled:8.3f} {du:10.1e}")
    print(f"largest ratio generic/compiled: {worst:.2f} (target <= 2) -- {'met' if worst <= 2 else 'MISSED'}")

    import control

    s = control.tf("s")
    systems = {
        "(2-s)/(s+1)^3": (2 - s) / (s + 1) ** 3,
        "(s^2+9)/((s+1)^2(s+2)^2)": (s**2 + 9) / ((s + 1) ** 2 * (s + 2) ** 2),
        "(2-s)(s^2+9)/(...)": (2 - s) * (s**2 + 9) / ((s + 1) ** 3 * (s**2 + 2 * s + 5)),
        "(2-s)/((s+1)(s+3))": (2 - s) / ((s + 1) * (s + 3)),  # relative degree 1
        "(2-s)/((s+1)^3(s+2))": (2 - s) / ((s + 1) ** 3 * (s + 2)),  # relative degree 3
    }
    print(f"\n{'transfer function':26s} {'rho':>4s} {'auto s':>8s} {'members':>8s} {'|y~-y_d|/move':>14s} {'peak |u|':>10s}")
    trajectory = smoothstep(1.0, 6.0, 5)
    for name, G in systems.items():
        start = time.perf_counter()
        result = invert(G, trajectory)
        elapsed = time.perf_counter() - start
        summary = result.summary
        print(f"{name:26s} {summary['system']['relative_degree']:4d} {elapsed:8.2f} {summary['auto']['members']:8d} "
              f"{summary['relative_redefinition_error']:14.2e} {summary['peak_torque']:10.3g}")


if __name__ == "__main__":
    main()

"""What leaving the untrusted zeros free costs and buys (``invert(..., zeros=...)``).

Run: ``python benchmarks/bench_zero_dynamics.py [--cases paper-sim:4,hyperbolic:6]``.

For each model (preset:n) the feedforward is chosen automatically three times -- all
unstable zeros constrained, the truncation artefacts left free (``physical``), only the
converged zeros constrained (``converged``) -- and printed with:

* the time of the automatic choice, as a ratio to the ``all`` run measured in the same run;
* the constrained unstable zeros and ``r`` (columns of every segment system);
* the peak torque, its largest jump (the free modes jump at the joints) and the full
  plant's distance from ``y~`` (the verification, on the full model);
* ``|tau - tau_all|``: the torque's largest difference from the ``all`` run's (of its peak);
* ``tip vs y_d on n+4``: the model with four more modes -- closer to the continuum -- driven
  by each torque from rest (exact first-order-hold discretisation at the sampling rate),
  its tip's largest distance from ``y_d`` over ``[t0, tf + 1 s]``, as a fraction of the move.
  The same figure for that model's own ``all`` torque is printed as the floor.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

import modelgen
from inversion import invert, smoothstep
from inversion.threads import one_thread

RATE = 4000.0


def _trajectory(name: str):  # type: ignore[no-untyped-def]
    return smoothstep(1.57, 5.5, 5) if name.startswith("paper") else smoothstep(0.5, 2.0, 5)


def _tip_error(model: modelgen.Model, t: np.ndarray, tau: np.ndarray, y_d: np.ndarray) -> float:
    """Largest ``|y - y_d|`` of ``model``'s linear plant driven by ``tau`` from rest (held 1 s at zero after t_f)."""
    import scipy.signal as sig

    dt = float(t[1] - t[0])
    extra = int(round(1.0 / dt))
    u = np.concatenate([tau, np.zeros(extra)])
    yd = np.concatenate([y_d, np.full(extra, y_d[-1])])
    A, B, C = np.asarray(model.A), np.asarray(model.B).reshape(-1, 1), np.asarray(model.C_out).reshape(1, -1)
    Ad, Bd, Cd, Dd, _ = sig.cont2discrete((A, B, C, np.zeros((1, 1))), dt, method="foh")
    _, y, _ = sig.dlsim((Ad, Bd, Cd, Dd, dt), u)
    return float(np.abs(y[:, 0] - yd).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default="paper-sim:4,paper-sim:6,hyperbolic:6", help="preset:n,... (default %(default)s)")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # fading CAB warnings of the larger models: not the subject here
    header = (f"{'model':14s} {'zeros':10s} {'time':>7s} {'ratio':>6s} {'n_u':>4s} {'r':>3s} {'peak N m':>9s} {'jump':>8s} "
              f"{'plant':>8s} {'|tau-tau_all|':>13s} {'tip vs y_d on n+4':>18s}")
    print(header)
    for case in args.cases.split(","):
        name, n = case.split(":")
        model = modelgen.load(name, modes=int(n))
        finer = modelgen.load(name, modes=int(n) + 4)
        trajectory = _trajectory(name)
        with one_thread():
            floor = invert(finer, trajectory, auto=True, rate=RATE)
        move = floor.summary["move"]
        reference = _tip_error(finer, floor.t, floor.tau, floor.y_d) / move
        base_time = base_tau = None
        for zeros in ("all", "physical", "converged"):
            start = time.perf_counter()
            try:
                with one_thread():
                    result = invert(model, trajectory, auto=True, rate=RATE, zeros=zeros)
            except Exception as exc:  # a failed choice is a result of the benchmark
                print(f"{case:14s} {zeros:10s} failed: {str(exc)[:120]}")
                continue
            seconds = time.perf_counter() - start
            s = result.summary
            if zeros == "all":
                base_time, base_tau = seconds, result.tau
            ratio = seconds / base_time if base_time else float("nan")
            diff = float(np.abs(result.tau - base_tau).max() / s["peak_torque"]) if base_tau is not None else float("nan")
            tip = _tip_error(finer, result.t, result.tau, result.y_d) / move
            print(f"{case:14s} {zeros:10s} {seconds:6.2f}s {ratio:6.2f} {s['n_unstable']:4d} {s['r']:3d} {s['peak_torque']:9.6f} "
                  f"{s['max_torque_jump']:8.1e} {s['verification']['plant_output_error']:8.1e} {diff:13.1e} {tip:18.2e}")
        print(f"{name + ':' + str(int(n) + 4):14s} {'all':10s} {'':7s} {'':6s} {floor.summary['n_unstable']:4d} {floor.summary['r']:3d} "
              f"{floor.summary['peak_torque']:9.6f} {'':8s} {'':8s} {'':13s} {reference:18.2e}  (floor: its own torque)")


if __name__ == "__main__":
    main()

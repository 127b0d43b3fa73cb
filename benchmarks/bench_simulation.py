"""Closed-loop simulation: the compiled loop against a plain ``solve_ivp`` loop, measured in one run.

Run: ``python benchmarks/bench_simulation.py [--repeat N]``.

paper-sim, the paper's member and gains, 15 s at 1 kHz, on the linear and the nonlinear
plant. Both sides do the whole job from an inversion to the sampled run:

* ours -- :func:`simulation.simulate` as shipped (``engine="cvodes"``): the reference
  spline, CVODES over the CasADi graph of plant, reference and PD law, the outputs;
* baseline -- the same reference spline (:class:`simulation.reference.Reference`, its
  SciPy B-spline) and ``scipy.integrate.solve_ivp`` (LSODA, the analytic Jacobian, the
  same tolerances) over a right-hand side in Python: ``A x + B tau`` in NumPy for the
  linear plant, the compiled ``nonlinear_rhs`` called through a reusable buffer for the
  nonlinear one; the tip computed from the states.

Printed: the best of ``N`` times of each, their ratio (target: at most 0.2), and the
largest difference of the final states (target: at most 1e-6 m). Also the time of
``simulate(engine="scipy")`` (the library's own cross-check, which calls the CasADi
closed loop from Python).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any, Callable

import numpy as np
from scipy.integrate import solve_ivp

import modelgen
from inversion import invert, trajectory_from_spec
from modelgen.compiled import FastCall
from simulation import simulate
from simulation.reference import Reference

TARGET_RATIO = 0.2
TARGET_STATE = 1e-6


def best_time(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    best, out = math.inf, None
    for _ in range(repeat):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def baseline(model: Any, inv: Any, plant: str, kp: float, kd: float, t_end: float, rate: float = 1000.0) -> np.ndarray:
    """The plain loop: reference spline, numpy right-hand side, LSODA; returns the final state."""
    ref = Reference(inv)
    n1 = model.n + 1
    A, B, p = model.A, model.B, model.parameters
    compiled = FastCall(model.functions.functions["nonlinear_rhs"])
    jacobian = FastCall(model.functions.functions["nonlinear_rhs_jacobian"])

    def plant_rhs(x: np.ndarray, u: float) -> np.ndarray:
        return A @ x + B * u if plant == "linear" else compiled(p, x, u)[0].reshape(-1)

    def plant_jac(x: np.ndarray, u: float) -> tuple[np.ndarray, np.ndarray]:
        if plant == "linear":
            return A, B
        J, Ju = jacobian(p, x, u)
        return J, Ju.reshape(-1)

    grad = np.zeros(2 * n1)
    grad[0], grad[n1] = -kp, -kd

    def during(t: float, x: np.ndarray) -> np.ndarray:
        tau_l, theta_d, thetadot_d, _ = ref.spline(t)
        return plant_rhs(x, tau_l + kp * (theta_d - x[0]) + kd * (thetadot_d - x[n1]))

    def during_jac(t: float, x: np.ndarray) -> np.ndarray:
        tau_l, theta_d, thetadot_d, _ = ref.spline(t)
        J, Ju = plant_jac(x, tau_l + kp * (theta_d - x[0]) + kd * (thetadot_d - x[n1]))
        return J + np.outer(Ju, grad)

    hold = ref.theta_final

    def after(t: float, x: np.ndarray) -> np.ndarray:
        return plant_rhs(x, kp * (hold - x[0]) - kd * x[n1])

    def after_jac(t: float, x: np.ndarray) -> np.ndarray:
        J, Ju = plant_jac(x, kp * (hold - x[0]) - kd * x[n1])
        return J + np.outer(Ju, grad)

    t0, tf = ref.t0, ref.tf
    s1 = t0 + np.arange(1, int(round((tf - t0) * rate)) + 1) / rate
    s2 = tf + np.arange(1, int(round((t_end - tf) * rate)) + 1) / rate
    kw = {"method": "LSODA", "rtol": 1e-9, "atol": 1e-12}
    a = solve_ivp(during, (t0, tf), inv.X[0], t_eval=s1, jac=during_jac, **kw)
    b = solve_ivp(after, (tf, t_end), a.y[:, -1], t_eval=s2, jac=after_jac, **kw)
    y = np.concatenate([a.y[:n1].T @ model.D, b.y[:n1].T @ model.D])
    assert y.size == s1.size + s2.size
    return np.asarray(b.y[:, -1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    model = modelgen.load("paper-sim")
    inv = invert(model, trajectory_from_spec("paper-sim"))
    ok = True
    print(f"paper-sim, 15 s at 1 kHz, best of {args.repeat}")
    print(f"{'plant':<10} {'ours (s)':>9} {'baseline (s)':>13} {'ratio':>7} {'max |dX(15 s)|':>15} {'scipy engine (s)':>17}")
    for plant in ("linear", "nonlinear"):
        simulate(model, inv, plant)  # warm CasADi's plugins
        ours_t, ours = best_time(lambda: simulate(model, inv, plant), args.repeat)
        base_t, final = best_time(lambda: baseline(model, inv, plant, 15.0, 30.0, 15.0), args.repeat)
        scipy_t, _ = best_time(lambda: simulate(model, inv, plant, engine="scipy"), 1)
        ratio = ours_t / base_t
        diff = float(np.abs(ours.X[-1] - final).max())
        ok &= ratio <= TARGET_RATIO and diff <= TARGET_STATE
        print(f"{plant:<10} {ours_t:9.3f} {base_t:13.3f} {ratio:7.3f} {diff:15.2e} {scipy_t:17.3f}")
    print(f"targets: ratio <= {TARGET_RATIO}, final state within {TARGET_STATE:g}: {'met' if ok else 'NOT met'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

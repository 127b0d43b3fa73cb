"""Inversion benchmarks: the closed form against numerical integration, and scaling.

Run: ``python benchmarks/bench_inversion.py``. Prints, in one run:

1. paper-sim at 1 kHz: the median time of :func:`inversion.invert` as shipped (solve, figures,
   verification, sampling) against its core (solve and sampling) measured in the same run;
2. the stable internal modes evaluated by the closed form (what ``invert`` does) and by
   the obvious alternative -- integrating ``zdot = lambda z + beta yddot~`` segment by
   segment with ``scipy.integrate.solve_ivp`` (DOP853) at the tightest tolerance that
   works -- with both times, both accuracies against a 40-digit evaluation of the exact
   solution, and the ratio (target: closed form >= 20 x faster at equal or better accuracy);
3. how the time grows with the number of samples and of segments, and 1e6 samples
   (target < 1 s);
4. 1e6 samples on one BLAS thread against the arithmetic floor measured in the same run:
   10 exponentials per sample and one ``(N x 12) @ (12 x 6)`` product (target: at most 2 x);
5. ``import inversion`` in a fresh interpreter (target < 0.3 s).
"""

from __future__ import annotations

import subprocess
import sys
import time

import mpmath
import numpy as np
from scipy.integrate import solve_ivp

import modelgen
from bench_family import core_inversion
from inversion import invert, smoothstep
from inversion.threads import one_thread


def median_time(fn, repeat: int = 30) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def stable_closed_form(result) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    modal = result.modal
    out = []
    for seg in result.segments:
        local = result.t[(result.t >= seg.t_start) & (result.t < seg.t_end)] - seg.t_start
        out.append(seg.evaluate(local, modal)[3][:, ~modal.unstable])
    return out


def stable_solve_ivp(result, rtol: float) -> list[np.ndarray]:  # type: ignore[no-untyped-def]
    modal = result.modal
    stable = np.flatnonzero(~modal.unstable)
    out = []
    for seg in result.segments:
        local = result.t[(result.t >= seg.t_start) & (result.t < seg.t_end)] - seg.t_start
        lam, beta = modal.lam[stable], modal.beta[stable]

        def rhs(s: float, x: np.ndarray) -> np.ndarray:
            z = x[: stable.size] + 1j * x[stable.size :]
            dz = lam * z + beta * float(np.exp(seg.mu * s) @ seg.c)
            return np.r_[dz.real, dz.imag]

        z0 = seg.z0[stable]
        sol = solve_ivp(rhs, (0.0, seg.duration), np.r_[z0.real, z0.imag], method="DOP853", t_eval=local,
                        rtol=rtol, atol=rtol * 1e-3)
        out.append((sol.y[: stable.size] + 1j * sol.y[stable.size :]).T)
    return out


def exact_reference(result, picks: int = 40) -> list[tuple[int, np.ndarray, np.ndarray]]:  # type: ignore[no-untyped-def]
    """40-digit evaluation of the stable modes at a few samples of every segment."""
    mpmath.mp.dps = 40
    modal = result.modal
    stable = np.flatnonzero(~modal.unstable)
    refs = []
    for k, seg in enumerate(result.segments):
        local = result.t[(result.t >= seg.t_start) & (result.t < seg.t_end)] - seg.t_start
        idx = np.linspace(0, local.size - 1, picks).astype(int)
        values = np.zeros((idx.size, stable.size), dtype=complex)
        for a, j in enumerate(idx):
            s = mpmath.mpf(float(local[j]))
            for b, i in enumerate(stable):
                lam, beta = mpmath.mpc(complex(modal.lam[i])), mpmath.mpc(complex(modal.beta[i]))
                z = mpmath.exp(lam * s) * mpmath.mpc(complex(seg.z0[i]))
                for mu, c in zip(seg.mu, seg.c):
                    mu = mpmath.mpf(float(mu))
                    z += beta * mpmath.mpf(float(c)) * (mpmath.exp(mu * s) - mpmath.exp(lam * s)) / (mu - lam)
                values[a, b] = complex(z)
        refs.append((k, idx, values))
    return refs


def error(parts: list[np.ndarray], refs) -> float:  # type: ignore[no-untyped-def]
    worst = 0.0
    for k, idx, values in refs:
        scale = np.abs(values).max() + 1e-300
        worst = max(worst, float(np.abs(parts[k][idx] - values).max() / scale))
    return worst


def main() -> None:
    model = modelgen.load("paper-sim")
    traj = smoothstep(1.57, 5.5, 5)
    run = lambda: invert(model, traj, segments=5, h=2, cdec=(1e-4, 1.0), rate=1000.0)  # noqa: E731
    result = run()
    median_time(run, 20)  # warm up (allocator, caches, CPU clock)
    t_invert = median_time(run, 100)
    t_core = median_time(lambda: core_inversion(model, traj), 100)
    print(f"invert paper-sim at 1 kHz ({result.t.size} samples): median {t_invert * 1e3:.2f} ms of 100 runs as shipped; "
          f"its core (solve and sample, no figures or checks) {t_core * 1e3:.2f} ms: the closed-form figures and the "
          f"verification (two re-solves, the plant check) cost {t_invert / t_core:.1f} x the core")

    refs = exact_reference(result)
    t_closed = median_time(lambda: stable_closed_form(result), 50)
    e_closed = error(stable_closed_form(result), refs)
    print("stable internal modes over the manoeuvre (relative error against 40 digits):")
    print(f"  closed form     {t_closed * 1e3:8.3f} ms   error {e_closed:.1e}")
    best = None
    for rtol in (1e-8, 1e-10, 1e-12, 1e-13):
        t_ivp = median_time(lambda: stable_solve_ivp(result, rtol), 3)
        e_ivp = error(stable_solve_ivp(result, rtol), refs)
        print(f"  solve_ivp {rtol:.0e} {t_ivp * 1e3:8.3f} ms   error {e_ivp:.1e}   ratio {t_ivp / t_closed:7.1f}")
        best = (rtol, t_ivp, e_ivp)
    assert best is not None
    rtol, t_ivp, e_ivp = best
    verdict = "met" if t_ivp / t_closed >= 20 and e_closed <= e_ivp else "MISSED"
    print(f"  at the tightest tolerance (rtol {rtol:.0e}): closed form {t_ivp / t_closed:.0f} x faster, "
          f"error {e_closed:.1e} vs {e_ivp:.1e}   target >= 20 x at equal or better accuracy: {verdict}")

    print("time against samples (5 segments):")
    base = None
    for rate in (100.0, 1000.0, 10_000.0, 100_000.0):
        t = median_time(lambda: invert(model, traj, rate=rate), 10)
        n = int(5.5 * rate) + 1
        base = base or t
        print(f"  {n:8d} samples  {t * 1e3:8.2f} ms   ratio to the first {t / base:6.1f}")
    print("time against segments (1 kHz):")
    base = None
    for k in (5, 10, 20, 40):  # anchored: the paper's joining diverges or fails the gate beyond ~20 segments
        t = median_time(lambda: invert(model, traj, segments=k, joining="anchored"), 10)
        base = base or t
        print(f"  {k:4d} segments  {t * 1e3:8.2f} ms   ratio to the first {t / base:6.1f}")
    rate = (1_000_000 - 1) / 5.5
    start = time.perf_counter()
    million = invert(model, traj, rate=rate)
    t_million = time.perf_counter() - start
    print(f"{million.t.size} samples: {t_million:.3f} s   target < 1 s: {'met' if t_million < 1 else 'MISSED'}")

    N = 1_000_000
    rng = np.random.default_rng(1)
    x, E, W = -rng.random((N, 10)), rng.random((N, 12)), rng.random((12, 6))

    def floor() -> None:
        np.exp(x)
        E @ W

    with one_thread():
        t_floor = median_time(floor, 10)
        t_ours = median_time(lambda: invert(model, traj, rate=rate), 5)
    ratio = t_ours / t_floor
    print(f"1e6 samples on one thread {t_ours:.3f} s, arithmetic floor {t_floor:.3f} s: {ratio:.1f} x   "
          f"target <= 2 x: {'met' if ratio <= 2 else 'MISSED'}")
    imports = []
    for _ in range(5):
        code = "import time; t = time.perf_counter(); import inversion; print(time.perf_counter() - t)"
        imports.append(float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout))
    print(f"import inversion: best {min(imports):.3f} s of 5   target < 0.3 s: {'met' if min(imports) < 0.3 else 'MISSED'}")


if __name__ == "__main__":
    main()

"""Generated-code benchmarks: cold and warm model builds, call overhead, batch throughput.

Run: ``python benchmarks/bench_codegen.py [N]`` (N = largest number of modes, default 12).
Every timing is printed beside a baseline measured in the same run, as a ratio:

* cold build (derive + generate + compile) and warm load (cache hit) for n = 1..N, in a
  fresh temporary cache; the warm/cold ratio;
* end-to-end ``sflm generate`` for paper-sim, cold and warm (separate processes);
* per-call overhead of one compiled ``linear_rhs`` evaluation against NumPy's ``A @ X``;
* ``inverse_torque`` over 1e6 samples in one batch against NumPy's ``(ydd - X @ CA2)/CAB``.

Targets (issue "compiled models"): cold n = 2 < 5 s; warm ``sflm generate`` < 1 s and
< 0.3 x cold; n = 10 cold < 60 s; 1e6-sample batch < 0.5 s; (issue 24) cold n = 12 at most
3 x cold n = 2.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from modelgen.cache import ensure_model_functions
from modelgen.lagrange import derive


def _verdict(ok: bool) -> str:
    return "met" if ok else "MISSED"


def builds(top: int) -> None:
    counts = sorted({1, 2, *range(4, top + 1, 2), top})
    print("n   cold build (s)   warm load (s)   warm/cold   cold / cold(n=2)")
    cold_of: dict[int, float] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in counts:
            derive.cache_clear()
            start = time.perf_counter()
            ensure_model_functions(n, root=Path(tmp))
            cold = cold_of[n] = time.perf_counter() - start
            start = time.perf_counter()
            fns = ensure_model_functions(n, root=Path(tmp))
            warm = time.perf_counter() - start
            assert fns.cache_hit
            note = ""
            if n == 2:
                note = f"   target cold < 5 s: {_verdict(cold < 5)}"
            if n == 10:
                note = f"   target cold < 60 s: {_verdict(cold < 60)}"
            if n == 12:  # issue 24: the derivation assembled from its structure, the code O(n^2) data
                note = f"   target <= 3x n=2: {_verdict(cold <= 3 * cold_of[2])}"
            ratio = cold / cold_of[2] if 2 in cold_of else float("nan")
            print(f"{n:<3d} {cold:14.2f}   {warm:13.4f}   {warm / cold:9.4f}   {ratio:16.2f}{note}", flush=True)


def cli_generate() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "SFLM_CACHE_DIR": str(Path(tmp) / "cache")}
        cmd = [sys.executable, "-m", "sflm.cli", "generate", "paper-sim", "--out", str(Path(tmp) / "out")]
        times = []
        for _ in range(2):
            start = time.perf_counter()
            subprocess.run(cmd, env=env, check=True, capture_output=True)
            times.append(time.perf_counter() - start)
    cold, warm = times
    print(
        f"sflm generate paper-sim: cold {cold:.2f} s, warm {warm:.2f} s, warm/cold {warm / cold:.2f}"
        f"   targets warm < 1 s: {_verdict(warm < 1)}, < 0.3 cold: {_verdict(warm < 0.3 * cold)}"
    )


def overhead() -> None:
    import modelgen

    model = modelgen.load("paper-sim")
    X = np.linspace(-0.1, 0.1, 6)
    reps = 20000
    call = model.functions.call
    call("linear_rhs", model.parameters, X, 0.1)
    start = time.perf_counter()
    for _ in range(reps):
        call("linear_rhs", model.parameters, X, 0.1)
    compiled = (time.perf_counter() - start) / reps
    A, B = model.A, model.B
    start = time.perf_counter()
    for _ in range(reps):
        A @ X + B * 0.1
    numpy = (time.perf_counter() - start) / reps
    print(f"one linear_rhs call: compiled {compiled * 1e6:.1f} us, NumPy A@X+B*tau {numpy * 1e6:.1f} us, ratio {compiled / numpy:.1f}")

    N = 1_000_000
    rng = np.random.default_rng(0)
    Xs = rng.normal(size=(N, 6))
    ydd = rng.normal(size=N)
    runs, bases = [], []
    for _ in range(5):
        start = time.perf_counter()
        tau = model.functions.inverse_torque(model.parameters, Xs, ydd)
        runs.append(time.perf_counter() - start)
        start = time.perf_counter()
        ref = (ydd - Xs @ model.CA2) / model.CAB
        bases.append(time.perf_counter() - start)
    assert np.allclose(tau, ref, rtol=1e-12, atol=1e-12)
    batch, base = float(np.median(runs)), float(np.median(bases))
    print(
        f"inverse_torque over 1e6 samples: first call {runs[0]:.3f} s (sets up the map), median {batch:.3f} s;"
        f" NumPy {base:.3f} s; ratio {batch / base:.1f}   target < 0.5 s: {_verdict(max(runs) < 0.5)}"
    )


if __name__ == "__main__":
    top = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    builds(top)
    cli_generate()
    overhead()

"""Derivation time of the symbolic model (SymPy) for n = 1..N modes.

Run: ``python benchmarks/bench_derivation.py [N]``. Prints each n's time and its ratio to
n = 1 measured in the same run (absolute times on shared machines are noisy), and checks
the targets of issue 2 (n = 2 under 2 s, n = 6 under 20 s).
"""

from __future__ import annotations

import sys
import time

from modelgen.lagrange import derive

TARGETS = {2: 2.0, 6: 20.0}


def main(top: int = 10) -> int:
    import sympy  # noqa: F401  (import time is not derivation time)

    times = {}
    for n in range(1, top + 1):
        derive.cache_clear()
        start = time.perf_counter()
        derive(n)
        times[n] = time.perf_counter() - start
        target = TARGETS.get(n)
        verdict = "" if target is None else f"  target < {target:.0f} s: {'met' if times[n] < target else 'MISSED'}"
        print(f"n = {n:2d}  {times[n]:7.2f} s  ratio to n=1 {times[n] / times[1]:6.1f}{verdict}", flush=True)
    return 0 if all(times[n] < t for n, t in TARGETS.items() if n in times) else 1


if __name__ == "__main__":
    sys.exit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 10))

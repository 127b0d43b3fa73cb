"""The automatic choice on every shipped preset with 1..6 modes and smoothstep orders 2..5.

Run: ``python benchmarks/sweep_auto.py [PRESETS] [MODES]`` (comma-separated; default all four
presets and 1..6 modes). One line per case: the chosen member, its redefinition error as a
fraction of the move, its peak torque, the plant check, the members tried and the time --
or the failure. The move: 1.57 m in 5.5 s for the simulation link and its variants, 0.1 m in
0.6 s for the experiment link (the paper's distances and durations).
"""

from __future__ import annotations

import sys
import time

import modelgen
from inversion import InversionError, invert, smoothstep

PRESETS = ("paper-sim", "paper-exp", "hyperbolic", "near-non-hyperbolic")


def main() -> None:
    presets = sys.argv[1].split(",") if len(sys.argv) > 1 else PRESETS
    modes = [int(n) for n in sys.argv[2].split(",")] if len(sys.argv) > 2 else range(1, 7)
    worst = 0.0
    failures = 0
    for preset in presets:
        distance, duration = (0.1, 0.6) if preset == "paper-exp" else (1.57, 5.5)
        for n in modes:
            model = modelgen.load(preset, modes=n)
            for order in (2, 3, 4, 5):
                started = time.perf_counter()
                try:
                    r = invert(model, smoothstep(distance, duration, order), auto=True)
                except InversionError as exc:
                    failures += 1
                    print(f"{preset:20s} n={n} order={order}  FAILED  {exc}  ({time.perf_counter() - started:.1f} s)", flush=True)
                    continue
                s = r.summary
                worst = max(worst, s["relative_redefinition_error"])
                st = r.settings
                print(f"{preset:20s} n={n} order={order}  {100 * s['relative_redefinition_error']:9.2e} % of the move, "
                      f"peak {s['peak_torque']:.3g} N m, plant {s['verification']['plant_output_error']:.1e}; "
                      f"{st.segment_count} segments, h = {st.h}, Cdec = ({st.cdec[0]:.3g}, {st.cdec[1]:.3g}), {st.joining}; "
                      f"{s['auto']['members']} members, {time.perf_counter() - started:.1f} s", flush=True)
    print(f"largest redefinition error {100 * worst:.3g} % of the move; {failures} failures")


if __name__ == "__main__":
    main()

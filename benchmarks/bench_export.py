"""Cost of one evaluation of the exported feedforward, as a multiple of one libm ``exp()``.

Run: ``python benchmarks/bench_export.py [--count N]``.

For each case the feedforward is exported (:func:`inversion.realtime.feedforward_c.export_c`) and compiled
with a C program (``-std=c99 -O2``) that times, in the same run, ``N`` evaluations at
random times of the span and ``N`` calls of ``exp`` on random arguments in ``[-5, 0]``
(each result summed into a ``volatile`` sink, so that nothing is optimised away). Printed:
both times per call and their ratio (target: at most 50 for the presets with their paper
settings and for the own link with the automatic choice; a 6-mode model is shown beyond it).
An evaluation is a segment and piece lookup and three Chebyshev series of degree 24
(:mod:`inversion.signals.chebyshev`), whatever the number of exponentials and modes.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import modelgen
from inversion import export_c, invert, smoothstep, trajectory_from_spec
from modelgen.abi import compiler_command

TARGET = 50.0
ROOT = Path(__file__).resolve().parent.parent

PROGRAM = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "feedforward.h"

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char **argv) {
    const long n = atol(argv[1]);
    double *t = malloc(n * sizeof *t), *x = malloc(n * sizeof *x);
    unsigned long long state = 88172645463325252ULL;
    for (long i = 0; i < n; ++i) { /* xorshift: reproducible random times and arguments */
        state ^= state << 13; state ^= state >> 7; state ^= state << 17;
        const double u = (state >> 11) * (1.0 / 9007199254740992.0);
        t[i] = SFLM_FEEDFORWARD_T0 + u * (SFLM_FEEDFORWARD_TF - SFLM_FEEDFORWARD_T0);
        x[i] = -5.0 * u;
    }
    volatile double sink = 0.0;
    double best_eval = 1e300, best_exp = 1e300;
    for (int repeat = 0; repeat < 5; ++repeat) {
        double start = now(), acc = 0.0;
        for (long i = 0; i < n; ++i) acc += exp(x[i]);
        sink = acc;
        double mid = now();
        acc = 0.0;
        for (long i = 0; i < n; ++i) {
            double tau, theta, thetadot;
            sflm_feedforward_eval(t[i], &tau, &theta, &thetadot);
            acc += tau + theta + thetadot;
        }
        sink = acc;
        double end = now();
        if (mid - start < best_exp) best_exp = mid - start;
        if (end - mid < best_eval) best_eval = end - mid;
    }
    (void)sink;
    printf("%.6e %.6e\n", best_eval / n, best_exp / n);
    free(t);
    free(x);
    return 0;
}
"""


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--count", type=int, default=200_000)
    args = parser.parse_args()
    cc = compiler_command()
    if cc is None:
        print("needs a C compiler")
        return 1
    cases = {
        "paper-sim, the paper's member": lambda: invert(modelgen.load("paper-sim"), trajectory_from_spec("paper-sim")),
        "paper-sim, anchored (series terms)": lambda: invert(modelgen.load("paper-sim"), trajectory_from_spec("paper-sim"), segments=5,
                                                             h=2, cdec=(1e-4, 1.0), joining="anchored"),
        "paper-exp, the paper's member": lambda: invert(modelgen.load("paper-exp"), trajectory_from_spec("paper-exp")),
        "hyperbolic": lambda: invert(modelgen.load("hyperbolic"), trajectory_from_spec("paper-sim")),
        "near-non-hyperbolic": lambda: invert(modelgen.load("near-non-hyperbolic"), trajectory_from_spec("paper-sim")),
        "own link, automatic choice": lambda: invert(modelgen.load(str(ROOT / "tests" / "data" / "own-aluminium.toml")),
                                                     smoothstep(0.5, 2.0, 2)),
    }
    # beyond the cases of the target: 6 modes, 13 exponentials and 12 complementary modes per segment
    extra = {"paper-sim, 6 modes, automatic choice": lambda: invert(modelgen.load("paper-sim", modes=6), smoothstep(1.57, 5.5, 2))}
    ok = True
    print(f"{'case':<38} {'r':>3} {'segments':>8} {'pieces':>6} {'eval (ns)':>10} {'exp (ns)':>9} {'ratio':>7}")
    with tempfile.TemporaryDirectory() as tmp:
        for label, make in {**cases, **extra}.items():
            result = make()
            folder = Path(tmp) / str(abs(hash(label)))
            export_c(result, folder)
            (folder / "bench.c").write_text(PROGRAM)
            exe = folder / "bench"
            subprocess.run([cc, "-std=c99", "-O2", f"-I{folder}", "-o", str(exe), str(folder / "bench.c"),
                            str(folder / "feedforward.c"), "-lm"], check=True)
            per_eval, per_exp = (float(v) for v in subprocess.run([str(exe), str(args.count)], capture_output=True, text=True,
                                                                   check=True).stdout.split())
            ratio = per_eval / per_exp
            if label in cases:
                ok &= ratio <= TARGET
            r = result.redefinition.plan.r if result.redefinition else 0
            pieces = result.signals.pieces if result.signals else 0
            print(f"{label:<38} {r:3d} {len(result.segments):8d} {pieces:6d} {per_eval * 1e9:10.1f} {per_exp * 1e9:9.2f} {ratio:7.1f}")
    print(f"target (the presets and the own link): one evaluation at most {TARGET:g} exp(): {'met' if ok else 'MISSED'}; "
          f"the last line is outside it")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

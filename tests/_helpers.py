"""Small assertions shared by tests."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
import scipy.linalg as sla
from scipy.optimize import linear_sum_assignment


def held(A, B, period: float):  # type: ignore[no-untyped-def]
    """``(A_d, B_d)`` of ``(A, B)`` with the input held over ``period``: the exponential of the augmented matrix."""
    A, B = np.asarray(A, float), np.asarray(B, float).reshape(-1)
    N = A.shape[0]
    augmented = np.zeros((N + 1, N + 1))
    augmented[:N, :N], augmented[:N, N] = A, B
    E = sla.expm(augmented * period)
    return E[:N, :N], E[:N, N]


def pd_loop(model, result, kp: float, kd: float):  # type: ignore[no-untyped-def]
    """A link's joint PD loop written apart, for a result's held rows: ``(C, K, rows, step, fine, references)`` --
    the output row, the gain row ``K`` (``k_P`` on the hub angle, ``k_D`` on its rate), the rows held, the exact map
    over a period and over a twentieth of one of ``[x; w]`` under ``x' = (A - B K) x + B w`` (``w = tau_k + K x_ref,k``,
    held), and ``references(k)``, the reference state ``x_ref,k`` of row ``k`` (the run's ``theta_d``, ``thetadot_d``)."""
    A, B, C = np.asarray(model.A, float), np.asarray(model.B, float).reshape(-1), np.asarray(model.C_out, float).reshape(-1)
    N, n1 = A.shape[0], A.shape[0] // 2
    K = np.zeros(N)
    K[0], K[n1] = kp, kd
    period = float(result.summary["sampled"]["period"])
    augmented = np.zeros((N + 1, N + 1))
    augmented[:N, :N], augmented[:N, N] = A - np.outer(B, K), B

    def references(k: int) -> np.ndarray:
        x = np.zeros(N)
        x[0], x[n1] = result.theta_d[k], result.thetadot_d[k]
        return x

    return (C, K, int(result.summary["sampled"]["samples"]), sla.expm(augmented * period), sla.expm(augmented * period / 20),
            references)


def assert_same_zeros(actual: ArrayLike, desired: ArrayLike, rtol: float) -> None:
    """Two sets of complex numbers agree, matched one-to-one (order-free), to ``rtol`` of the largest."""
    a = np.asarray(actual, dtype=complex)
    d = np.asarray(desired, dtype=complex)
    assert a.size == d.size, f"{a.size} values vs {d.size}"
    cost = np.abs(a[:, None] - d[None, :])
    rows, cols = linear_sum_assignment(cost)
    worst = cost[rows, cols].max(initial=0.0)
    scale = max(np.abs(d).max(initial=0.0), 1.0)
    assert worst <= rtol * scale, f"zeros differ by {worst:.3e} (> {rtol:g} x {scale:.3g}): {a} vs {d}"


def linear_plant_output(model, result, X0=None, rate: float = 20_000.0):  # type: ignore[no-untyped-def]
    """Drive the linear plant (P9) with the inverse torque and return y at ``result.t``.

    ``model`` is a link model or a generic system (:mod:`inversion.lti.linear_system`, whose
    ``A, B, C`` are the caller's realisation; ``result.evaluate`` gives its input there).

    Independent of the closed form: the torque is sampled at ``rate`` or finer (closed form, one
    batch) on a grid through every ``result.t``, interpolated by a cubic spline, and the plant
    driven by that spline exactly: on each interval the spline's third derivative is constant,
    so the state extended by the input and its three derivatives obeys a linear ODE, stepped by
    its matrix exponential (SciPy's ``expm``). The rounding of the steps adds up to about 1e-12
    of the state on a 5 s move (measured; DOP853 at rtol 1e-12 on a spline of the same rate: 1.4e-13,
    6x slower). Returns ``(y, X)``.
    """
    import math

    import scipy.linalg as sla
    from scipy.interpolate import CubicSpline

    t = np.asarray(result.t, dtype=float)
    gaps = np.diff(t)
    q = max(1, math.ceil(gaps.max() * rate - 1e-9))  # spline intervals per output interval
    fine = np.append((t[:-1, None] + gaps[:, None] * (np.arange(q)[None, :] / q)).ravel(), t[-1])
    tau = CubicSpline(fine, result.evaluate(fine)["tau"])
    # the input and its derivatives at each spline interval's start
    d = np.stack([tau(fine[:-1], nu) for nu in range(4)], axis=1).reshape(gaps.size, q, 4)
    A, B = np.asarray(model.A, dtype=float), np.asarray(model.B, dtype=float).reshape(-1)
    n = A.shape[0]
    F = np.zeros((n + 4, n + 4))
    F[:n, :n], F[:n, n] = A, B
    F[n, n + 1] = F[n + 1, n + 2] = F[n + 2, n + 3] = 1.0
    keys, which = np.unique(np.round(gaps / gaps.max(), 12), return_inverse=True)  # output intervals of one length
    jumps, carried = [], np.empty((gaps.size, n))
    for g, key in enumerate(keys):
        E = sla.expm(F * (key * gaps.max() / q))
        Phi, G = E[:n, :n], E[:n, n:]
        powers = [np.eye(n)]
        for _ in range(q - 1):
            powers.append(Phi @ powers[-1])
        W = np.stack([p @ G for p in powers[::-1]])  # Phi^(q-1-m) G: what the m-th spline piece adds at the interval's end
        rows = which == g
        carried[rows] = np.einsum("mab,jmb->ja", W, d[rows])
        jumps.append(Phi @ powers[-1])
    x = np.zeros(n) if X0 is None else np.asarray(X0, dtype=float).copy()
    X = np.empty((t.size, n))
    X[0] = x
    for j in range(gaps.size):
        x = jumps[which[j]] @ x + carried[j]
        X[j + 1] = x
    C = np.asarray(model.C_out if hasattr(model, "C_out") else model.C).reshape(-1)
    return X @ C, X


def run_cli(*args: str, cwd: Path | str | None = None) -> subprocess.CompletedProcess[str]:
    """``sflm ARGS`` run in this process (:func:`sflm.cli.main`): its exit status and what it printed.

    What ``python -m sflm.cli ARGS`` would give, without starting an interpreter (1.5 s each):
    argparse's exit becomes the status, warnings are printed to stderr as the command prints
    them, and an exception that escapes ``main`` fails the test (a traceback there). Entry points,
    pipes, signals and the environment read at start-up keep their subprocess tests.
    """
    import contextlib
    import io
    import warnings

    from sflm.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), contextlib.chdir(cwd or os.getcwd()), \
            warnings.catch_warnings():
        warnings.simplefilter("default")  # the interpreter's own filters: what a command's stderr would show
        for category in (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning):
            warnings.simplefilter("ignore", category)
        warnings.showwarning = lambda message, category, filename, lineno, file=None, line=None: err.write(  # noqa: ARG005
            warnings.formatwarning(message, category, filename, lineno, line))
        try:
            code = main(list(args))
        except SystemExit as exc:  # argparse refusing the arguments
            code = exc.code if isinstance(exc.code, int) else 2
    return subprocess.CompletedProcess(["sflm", *args], code, out.getvalue(), err.getvalue())


def error_lines(stderr: str) -> list[str]:
    """The lines of a command's stderr other than its one-line warnings (e.g. no C compiler) and its progress (past 2 s,
    ``sflm COMMAND: stage (N s)``: :class:`sflm.progress.Reporter`)."""
    import re

    progress = re.compile(r"^sflm \w+: (?!error:).* \(\d+ s\)$")
    return [line for line in stderr.splitlines()
            if line.strip() and not line.startswith("sflm: warning:") and not progress.match(line)]


def beyond_the_canvas(fig) -> list[str]:  # type: ignore[no-untyped-def]
    """Where matplotlib's tight bounding box of everything a figure draws (titles, labels, ticks, legends, colour bars,
    notes) leaves the figure, in inches (empty when it does not): issue 25's canvas test."""
    fig.canvas.draw()
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    width, height = fig.get_size_inches()
    slack = 1.0 / fig.dpi
    sides = {"left": -box.x0, "bottom": -box.y0, "right": box.x1 - width, "top": box.y1 - height}
    return [f"{side} by {excess:.3f} in" for side, excess in sides.items() if excess > slack]


class KeptFigures(list):  # type: ignore[type-arg]
    """Figures kept open for a test, with pyplot's own ``close`` to let them go afterwards."""

    close: Any = None


def kept_figures(monkeypatch) -> KeptFigures:  # type: ignore[no-untyped-def]
    """The figures :mod:`sflm.plots` closes from now on, kept open for a test to measure."""
    import matplotlib

    from sflm import plots

    kept = KeptFigures()
    kept.close = plots.plt.close
    monkeypatch.setattr(plots.plt, "close", lambda fig: kept.append(fig))
    monkeypatch.setitem(matplotlib.rcParams, "figure.max_open_warning", 0)  # they are kept on purpose
    return kept


def assert_figures_inside_the_canvas(figures: KeptFigures) -> None:
    """Every figure's text within its canvas (:func:`beyond_the_canvas`); the figures are closed afterwards."""
    try:
        problems = {(fig.axes[0].get_title()[:50] if fig.axes else str(fig)): beyond_the_canvas(fig) for fig in figures}
        assert figures and not {name: sides for name, sides in problems.items() if sides}
    finally:
        for fig in figures:
            figures.close(fig)

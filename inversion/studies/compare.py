"""The causal inversion beside the baselines the paper argues against, and the methods engineers pick instead.

:func:`compare` runs the paper's SSEF (as :func:`inversion.invert` chooses it), SSEF with a
rest end (the paper's Remark 2), the polynomial redefinition (the paper's Eq. (2)), the
non-causal stable inversion, the optimal-control feedforward (the limit of any causal one at
its period: :mod:`inversion.methods.ocp`) and input shaping (ZV, ZVD: :mod:`inversion.methods.shaping`), and
reports each one's figures and wall time -- or why it failed, with its figures.
``residual_vibration`` is the peak-to-peak tip motion, over the ``VIBRATION_WINDOW`` seconds
after ``t_f``, of the linear plant driven by the feedforward alone: the plant follows
the result's state (each method's defining property, tested) until the feedforward ends, then
moves under the input that holds ``y_d(t_f)`` -- zero torque for a link, ``y_d(t_f) / G(0)`` for a system (exact).
"""

from __future__ import annotations

import csv
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from modelgen.model import Model

from ..api import LEGACY, from_keywords, resolve
from ..acceptance import WINDOW
from ..errors import InversionError, SettingsError
from ..family.auto import shared_members
from ..family.method import Family
from ..options import InversionMethod, registered
from ..problem import Problem
from ..result import InversionResult

__all__ = ["compare", "compare_rows", "check_objective", "Comparison", "COMPARE_COLUMNS", "SHORTEST_ROWS", "VIBRATION_WINDOW"]
#: Columns of ``compare.csv`` (a contract relied on by scripts: extended, never renamed; ``held_tip_error`` since issue 60).
COMPARE_COLUMNS = ("method", "status", "max_redefinition_error", "relative_redefinition_error", "peak_torque", "torque_at_end",
                   "pre_actuation_time", "post_actuation_time", "residual_vibration", "settings", "message", "seconds",
                   "worst_case_error", "period", "hold", "held_tip_error", "duration", "certified_lower_bound")
#: The rows ``shortest=True`` adds (issue 57): the shortest move of the asked move's profile and the fastest of any.
SHORTEST_ROWS = ("shortest, same profile", "fastest, any profile")
#: Seconds after ``t_f`` over which ``residual_vibration`` is measured.
VIBRATION_WINDOW = WINDOW


@dataclass
class Comparison:
    """The rows of a comparison and the results behind them.

    Attributes
    ----------
    rows : list of dict
        One per row of :func:`compare_rows`, with the keys :data:`COMPARE_COLUMNS`.
    results : dict of str to InversionResult
        The methods that succeeded.
    """

    rows: list[dict[str, Any]]
    results: dict[str, InversionResult] = field(default_factory=dict)

    def write_csv(self, path: str | Path) -> Path:
        """Write ``compare.csv``.

        Write ``compare.csv`` (empty cells for figures a failed method does not have).

        Parameters
        ----------
        path : str | Path
            The folder written into.
        """
        path = Path(path)
        with open(path, "w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=list(COMPARE_COLUMNS))
            writer.writeheader()
            for row in self.rows:
                writer.writerow({k: ("" if row.get(k) is None else (repr(row[k]) if isinstance(row[k], float) else row[k]))
                                 for k in COMPARE_COLUMNS})
        return path


def residual_vibration(result: InversionResult, window: float = VIBRATION_WINDOW) -> float:
    """Peak-to-peak tip motion over ``window`` s after ``t_f`` of the linear plant driven by the feedforward alone (a held
    table's last row held until ``t_f``); after the feedforward's last sample, the input that holds the plant at rest at
    ``y_d(t_f)`` (:meth:`~inversion.lti.system.NormalForm.equilibrium_input`: zero torque for a link, ``y / G(0)`` for a
    system), as the acceptance's after-end window has it."""
    import scipy.linalg as sla

    model = result.model
    tf = result.trajectory.tf
    A, B = np.asarray(model.A, dtype=float), np.asarray(model.B, dtype=float).reshape(-1)
    held = np.zeros((A.shape[0] + 1, A.shape[0] + 1))  # the plant and a held input: expm of it steps both
    held[:-1, :-1], held[:-1, -1] = A, B
    inside = (result.t >= tf) & (result.t <= tf + window)
    tip = list(result.y[inside])  # the plant follows the result's output while the feedforward lasts
    x = np.asarray(result.X[-1], dtype=float)
    C = np.asarray(model.C_out if isinstance(model, Model) else model.C, dtype=float).reshape(-1)  # y = C X
    from ..lti.system import normal_form

    last = float(result.t[-1])
    if last < tf:  # a held table's last row holds its torque until t_f (the optimal-control feedforward's)
        x = (sla.expm(held * (tf - last)) @ np.append(x, float(result.tau[-1])))[:-1]
        tip.append(float(C @ x))
        last = tf
    rest = tf + window - last
    if rest > 0:
        steps = max(2, math.ceil(rest / 0.005))
        step = sla.expm(held * (rest / steps))
        z = np.append(x, normal_form(model).equilibrium_input(result.trajectory.y_final))
        for _ in range(steps + 1):
            tip.append(float(C @ z[:-1]))
            z = step @ z
    return float(np.ptp(tip)) if tip else 0.0


def _row(name: str, method: InversionMethod, result: InversionResult | None, error: Exception | None, note: str = "") -> dict[str, Any]:
    if result is None:
        status = "not-exist" if not method.causal and "does not exist" in str(error) else "failed"
        return {"method": name, "status": status, "message": str(error), "settings": ""}
    s: Any = result.summary  # a link's or a generic system's
    return {
        "method": name, "status": "ok", "message": note, "settings": method.settings_text(s),
        "max_redefinition_error": s["max_redefinition_error"], "relative_redefinition_error": s["relative_redefinition_error"],
        "peak_torque": s["peak_torque"], "torque_at_end": s["torque_at_end"],
        "pre_actuation_time": float(s.get("pre_actuation_time", 0.0)), "post_actuation_time": float(s.get("post_actuation_time", 0.0)),
        "residual_vibration": residual_vibration(result),
        # what the table held at the row's period does at the tip (the figures above are the method's own: a closed
        # form's error and peak for the family)
        "held_tip_error": (s.get("sampled") or {}).get("max_tip_error"),
    }


def compare_rows(family: Family | None = None) -> list[tuple[str, InversionMethod]]:
    """The rows of a comparison, in order.

    The rows of a comparison, in order: each registered method's variants (:meth:`InversionMethod.variants`; the
    family's options given to its rows, its member's parts to the polynomial's).

    Parameters
    ----------
    family : Family, optional
        The family's options.
    """
    family = family or Family()
    rows: list[tuple[str, InversionMethod]] = []
    for kind in registered():
        if kind is Family:
            method: InversionMethod = replace(family, end=None)
        elif kind.name == "polynomial":
            method = kind.from_options({k: getattr(family, k) for k in ("segments", "h", "joining")})
        else:
            method = kind()
        rows += method.variants()
    return rows


def compare(problem: Problem | Any, trajectory: Any = None, *, family: Family | None = None, progress: Callable[[str], None] | None = None,
            shortest: bool = False, **legacy: Any) -> Comparison:
    """Run the causal inversion and its baselines on one problem.

    Parameters
    ----------
    problem : Problem, or a model
        What is asked (a model with ``trajectory``: the problem of the defaults). Its ``uncertainty``: each row is also
        judged on the perturbed links in the closed loop (:func:`inversion.studies.robustness.judge_robustness`: the
        ``worst_case_error`` column); the rows themselves are computed for the nominal plant.
    trajectory : Trajectory, optional
        The move, with a model in place of a problem.
    family : Family, optional
        The family's options for its rows (``segments``, ``h``, ``joining`` also for the polynomial's).
    progress : callable, optional
        Called with a line before each row.
    shortest : bool
        Also the rows :data:`SHORTEST_ROWS`: the shortest move of the asked move's profile (stretched in time,
        :func:`inversion.methods.shortest.shortest_move`) and the fastest of any profile
        (:func:`inversion.methods.fastest.fastest_move`), each with its ``duration`` and ``certified_lower_bound`` (the
        problem's bounds absolute: given, or the model's ``[drive]``; else the rows fail with the reason).
    **legacy
        The last release's flat keywords (``max_error=``, ``segments=``, ...), with a DeprecationWarning.

    Returns
    -------
    Comparison
        A row per method variant (:func:`compare_rows`); a method that fails (or does not exist) has its message and no
        figures.
    """
    if not isinstance(problem, Problem):
        problem, family = _legacy(problem, trajectory, family, legacy)
    family = family or Family()
    check_objective(family.objective)
    uncertainty = problem.uncertainty
    if uncertainty is not None:
        from .robustness import Uncertainty, parse_uncertainty

        uncertainty = uncertainty if isinstance(uncertainty, Uncertainty) else parse_uncertainty(uncertainty)
        uncertainty.check(problem.system)
    nominal = problem.without_spread()
    say = progress or (lambda message: None)
    rows: list[dict[str, Any]] = []
    results: dict[str, InversionResult] = {}
    # every row is judged at the controller's period and hold, the one invert judges with; each row says which
    asked = {"period": problem.period, "hold": problem.hold}
    # the family's rows (as given, and with a rest end) search the same grid: each batch of members solved once
    with shared_members():
        for name, method in compare_rows(family):
            if progress is not None:
                progress(f"compare: {name}")
            start = time.perf_counter()
            try:
                result, note = method.compared(nominal, lambda p, m: resolve(p, m))
            except (InversionError, SettingsError) as exc:
                rows.append({**_row(name, method, None, exc), **asked, "seconds": time.perf_counter() - start})
                continue
            results[name] = result
            sampled = result.summary.get("sampled") or {}
            judged = {"period": float(sampled.get("period", asked["period"])), "hold": str(sampled.get("hold", asked["hold"]))}
            row = {**_row(name, method, result, None, note), **judged, "seconds": time.perf_counter() - start}
            if uncertainty is not None:
                from .robustness import judge_robustness

                row["worst_case_error"] = judge_robustness(result, uncertainty)["worst_case_error"]
            rows.append({**row, "duration": nominal.trajectory.duration})
    if shortest:
        for name, result, row in _shortest_rows(nominal, say):
            if result is not None:
                results[name] = result
            sampled = {} if result is None else (result.summary.get("sampled") or {})
            rows.append({**row, "period": float(sampled.get("period", asked["period"])), "hold": str(sampled.get("hold", asked["hold"]))})
    return Comparison(rows, results)


def _shortest_rows(problem: Problem, say: Callable[[str], None]) -> list[tuple[str, InversionResult | None, dict[str, Any]]]:
    """The rows :data:`SHORTEST_ROWS`: each move's result (``None`` where it failed) and its row."""
    from ..api import shortest
    from ..options import as_method

    runs: list[tuple[str, Callable[[], InversionResult]]] = [(SHORTEST_ROWS[0], lambda: shortest(problem, progress=say)),
                                                              (SHORTEST_ROWS[1], lambda: shortest(problem, "free", progress=say))]
    out: list[tuple[str, InversionResult | None, dict[str, Any]]] = []
    for name, run in runs:
        say(f"compare: {name}")
        start = time.perf_counter()
        try:
            result = run()
        except (InversionError, SettingsError) as exc:
            out.append((name, None, {"method": name, "status": "failed", "message": str(exc), "settings": "",
                                     "seconds": time.perf_counter() - start}))
            continue
        block = result.summary["shortest"]  # type: ignore[typeddict-item]
        method = as_method(str(result.summary["method"]))
        row = _row(name, method, result, None, f"no table in {block['lower_bound']:.4g} s, this one {block['duration']:.4g} s "
                                               f"({100 * block['gap']:.2g} % longer)")
        out.append((name, result, {**row, "duration": block["duration"], "certified_lower_bound": block["lower_bound"],
                                   "seconds": time.perf_counter() - start}))
    return out


def check_objective(objective: Any) -> None:
    """Refuse an objective a comparison has no use for.

    Refuse an objective a comparison has no use for (each method runs once; the robust choice is ``invert``'s).

    Parameters
    ----------
    objective : str or None
        The family's objective.
    """
    if objective not in (None, "torque", "error"):
        raise SettingsError("objective", objective, "'torque' or 'error' for a comparison (each method runs once; the "
                            "robust choice is invert's, with uncertainty)")


def _legacy(model: Any, trajectory: Any, family: Family | None, legacy: dict[str, Any]) -> tuple[Problem, Family]:
    """The problem and the family's options of the last release's ``compare(model, trajectory, **options)``."""
    unknown = sorted(set(legacy) - set(LEGACY) - {"method"})
    if unknown:
        raise SettingsError(unknown[0], legacy[unknown[0]], "a keyword of compare: problem, trajectory, family, progress")
    given = {k: v for k, v in legacy.items() if v is not None and k not in ("end", "method")}
    if given:
        warnings.warn("compare's flat keywords are deprecated (they go with the next release): pass an inversion.Problem and "
                      "family=inversion.Family(...)", DeprecationWarning, stacklevel=3)
    problem, method = from_keywords(model, trajectory, "ssef", {k: v for k, v in given.items() if k != "objective"})
    base = method if isinstance(method, Family) else Family()
    return problem, replace(base, objective=given.get("objective")) if family is None else family


def __getattr__(name: str) -> Any:
    """``METHODS``, the rows' names (now read from the registry: :func:`compare_rows`)."""
    if name == "METHODS":
        return tuple(row for row, _ in compare_rows())
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

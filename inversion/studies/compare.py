"""The causal inversion beside the baselines the paper argues against, and the methods engineers pick instead.

:func:`compare` runs the paper's SSEF (as :func:`inversion.invert` chooses it), SSEF with a
rest end (the paper's Remark 2), the polynomial redefinition (the paper's Eq. (2)), the
non-causal stable inversion, the optimal-control feedforward (the limit of any causal one at
its period: :mod:`inversion.baselines.ocp`) and input shaping (ZV, ZVD: :mod:`inversion.baselines.shaping`), and
reports each one's figures and wall time -- or why it failed, with its figures.
``residual_vibration`` is the peak-to-peak tip motion, over the ``VIBRATION_WINDOW`` seconds
after ``t_f``, of the linear plant driven by the feedforward alone: the plant follows
the result's state (each method's defining property, tested) until the feedforward ends, then
moves under the input that holds ``y_d(t_f)`` -- zero torque for a link, ``y_d(t_f) / G(0)`` for a system (exact).
"""

from __future__ import annotations

import csv
import itertools
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from modelgen.model import Model

from ..api import check_bounds, invert
from ..baselines.polynomial import polynomial_redefinition_error
from ..config import DEFAULTS, default, held_period, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.linear_system import as_linear_system
from ..lti.system import normal_form
from ..result import InversionResult
from ..signals.trajectory import Trajectory

__all__ = ["compare", "Comparison", "COMPARE_COLUMNS", "METHODS", "VIBRATION_WINDOW"]

#: The rows of a comparison, in order.
METHODS = ("ssef", "ssef-rest", "polynomial", "stable", "ocp", "zv", "zvd", "replan")
#: Columns of ``compare.csv`` (a contract relied on by scripts).
COMPARE_COLUMNS = ("method", "status", "max_redefinition_error", "relative_redefinition_error", "peak_torque", "torque_at_end",
                   "pre_actuation_time", "post_actuation_time", "residual_vibration", "settings", "message", "seconds",
                   "worst_case_error", "period", "hold")
#: Seconds after ``t_f`` over which ``residual_vibration`` is measured.
VIBRATION_WINDOW = DEFAULTS.vibration_window
#: The polynomial redefinition's members tried when none is given: the smallest error wins.
POLYNOMIAL_SEGMENTS = (1, 2, 3, 4, 5, 6)
POLYNOMIAL_H = (1, 2, 3)
POLYNOMIAL_JOININGS = ("paper", "position")


@dataclass
class Comparison:
    """The rows of a comparison and the results behind them.

    Attributes
    ----------
    rows : list of dict
        One per method of :data:`METHODS`, with the keys :data:`COMPARE_COLUMNS`.
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


def _row(method: str, result: InversionResult | None, error: Exception | None, note: str = "") -> dict[str, Any]:
    if result is None:
        status = "not-exist" if method == "stable" and "does not exist" in str(error) else "failed"
        return {"method": method, "status": status, "message": str(error), "settings": ""}
    s: Any = result.summary  # a link's or a generic system's
    settings = s["settings"]
    if method in ("ssef", "ssef-rest"):
        described = (f"{len(settings['segments']) - 1} segments, h = {settings['h']}, Cdec = ({settings['cdec'][0]:g}, "
                     f"{settings['cdec'][1]:g}), {settings['joining']}, {settings['end']} end")
    elif method == "polynomial":
        described = f"{len(settings['segments']) - 1} segments, h = {settings['h']}, {settings['joining']}"
    elif method == "ocp":
        described = (f"least peak torque within {settings['max_error']:.3g} m at every {settings['period']:g} s sample, held; "
                     f"{s['ocp'].get('solver', 'ipopt').upper()} {s['ocp']['status']}"
                     + ("" if s["ocp"]["iterations"] is None else f", {s['ocp']['iterations']} iterations"))
    elif method == "replan":
        described = (f"the move reshaped within {settings['max_error']:.3g} m ({s['replan']['splines']} splines of degree "
                     f"{s['replan']['degree']}), inverted exactly; {settings['end']} end")
    elif method in ("zv", "zvd"):
        modes = ", ".join(f"{m['frequency']:.4g} rad/s" for m in settings["modes"])
        described = (f"shaped for {modes} (shaper {s['shaping']['shaper_duration']:.3g} s), joint PD k_P {settings['kp']:.3g}, "
                     f"k_D {settings['kd']:.3g}; the shaped modes ring {s['shaping']['residual_vibration']:.2g} m after "
                     f"(unshaped {s['shaping']['unshaped_residual_vibration']:.2g} m)")
    else:
        described = f"tails cut at {settings['tail_tolerance']:g}"
    return {
        "method": method, "status": "ok", "message": note, "settings": described,
        "max_redefinition_error": s["max_redefinition_error"], "relative_redefinition_error": s["relative_redefinition_error"],
        "peak_torque": s["peak_torque"], "torque_at_end": s["torque_at_end"],
        "pre_actuation_time": float(s.get("pre_actuation_time", 0.0)), "post_actuation_time": float(s.get("post_actuation_time", 0.0)),
        "residual_vibration": residual_vibration(result),
    }


def _ocp(model: Any, trajectory: Trajectory, options: dict[str, Any]) -> tuple[InversionResult, str]:
    """The optimal-control feedforward at the controller's period, as ``invert`` judges it (its rows held at ``period``, or
    one a sample at ``rate``: 1 ms by default)."""
    period = held_period(options.get("period"), options.get("rate"))
    result = invert(model, trajectory, method="ocp", max_error=options.get("max_error"), period=period, window=options.get("window"),
                    max_torque=options.get("max_torque"), max_torque_rate=options.get("max_torque_rate"), margin=options.get("margin"))
    return result, ""


def _polynomial(model: Any, trajectory: Trajectory, options: dict[str, Any]) -> tuple[InversionResult, str]:
    """The polynomial redefinition with the member given, or the best of the grid (segments, h, joining) above."""
    given = {k: options[k] for k in ("segments", "h", "joining") if options.get(k) is not None}
    sampling = {k: options[k] for k in ("rate", "period", "hold", "window", "max_torque", "max_torque_rate", "margin") if k in options}
    if given:
        return invert(model, trajectory, method="polynomial", max_error=options.get("max_error"), **sampling, **given), ""
    members = [(k, h, joining) for k, h, joining in itertools.product(POLYNOMIAL_SEGMENTS, POLYNOMIAL_H, POLYNOMIAL_JOININGS)
               if trajectory.max_derivative is None or h + 2 <= trajectory.max_derivative]
    tried = len(members)
    # ranked by the redefinition's error alone (cheap); the full inversion -- samples, series, checks -- only for the best
    system = model if isinstance(model, Model) else as_linear_system(model)
    if normal_form(system).n_internal == 0:  # what no member changes: refused by name, as invert refuses it
        raise SettingsError("system", system.name, "a system with zeros for the polynomial redefinition (without zeros it has "
                            "no internal dynamics: its exact inverse is causal and bounded)")
    ranked: list[tuple[float, int]] = []
    for index, (k, h, joining) in enumerate(members):
        try:
            error = polynomial_redefinition_error(system, trajectory, segments=k, h=h, joining=joining)
        except (InversionError, SettingsError):
            continue
        if math.isfinite(error):
            ranked.append((error, index))
    best: InversionResult | None = None
    first: str | None = None  # why the member of least error was refused (the acceptance every method passes)
    for _error, index in sorted(ranked):
        k, h, joining = members[index]
        try:
            best = invert(model, trajectory, method="polynomial", segments=k, h=h, joining=joining, max_error=math.inf, **sampling)
        except (InversionError, SettingsError) as exc:
            first = first or str(exc)
            continue
        break
    grid = f"{tried} members (segments 1..6, h 1..3, paper or position)"
    if best is None:
        if first is not None:
            raise InversionError(f"none of the {grid} of the polynomial redefinition passes; the closest to y_d: {first}")
        raise InversionError(f"none of the {grid} of the polynomial redefinition has a finite solution")
    s = best.summary
    gate = tip_bound(options.get("max_error"), s["move"], judged=False)
    if not s["max_redefinition_error"] <= gate:
        settings = s["settings"]
        raise InversionError(
            f"the best of {grid} ({len(settings['segments']) - 1} segments, h = {settings['h']}, {settings['joining']}) is "
            f"{s['max_redefinition_error']:.4g} m from the desired output ({100 * s['relative_redefinition_error']:.3g} % of the "
            f"{s['move']:.4g} m move; accepted {gate:.3g} m)"
        )
    return best, f"the smallest error of {grid}"


def compare(model: Any, trajectory: Trajectory, progress: Callable[[str], None] | None = None, uncertainty: Any = None,
            **options: Any) -> Comparison:
    """Run the causal inversion and its baselines on one trajectory.

    Parameters
    ----------
    model : Model
    trajectory : Trajectory
    progress : callable, optional
        Called with a line before each method.
    uncertainty : Uncertainty or str, optional
        Each method's result is also judged on the perturbed links in the closed loop
        (:func:`inversion.studies.robustness.judge_robustness`): the ``worst_case_error`` column.
    **options
        :func:`inversion.invert`'s options for the SSEF rows (``segments``, ``h``, ``cdec``,
        ``joining``, ``settings``, ``auto``, ``max_error``, ``max_torque``, ``rate``, ...);
        ``segments``, ``h``, ``joining``, ``rate`` and ``max_error`` also for the polynomial.

    Returns
    -------
    Comparison
        A row per method; a method that fails (or does not exist) has its message and no figures.
    """
    options = {k: v for k, v in options.items() if v is not None}
    options.pop("end", None)
    options.pop("method", None)
    # what every method would refuse is refused once, before any runs (not a table of failed rows, exit 0)
    check_bounds(trajectory, **{k: options[k] for k in ("max_error", "max_torque", "max_torque_rate", "rate", "period", "hold", "window")
                                if k in options})
    if options.get("objective") not in (None, "torque", "error"):
        raise SettingsError("objective", options["objective"], "'torque' or 'error' for a comparison (each method runs once; the "
                            "robust choice is invert's, with uncertainty)")
    if uncertainty is not None:
        from .robustness import Uncertainty, parse_uncertainty

        uncertainty = uncertainty if isinstance(uncertainty, Uncertainty) else parse_uncertainty(uncertainty)
        uncertainty.check(model if isinstance(model, Model) else as_linear_system(model))
    rows: list[dict[str, Any]] = []
    results: dict[str, InversionResult] = {}
    # what every method is judged with (invert's acceptance: the held table through the window, the torque and its rate)
    sampling = {k: options[k] for k in ("rate", "period", "hold", "window", "max_torque", "max_torque_rate", "margin") if k in options}
    runs: dict[str, Callable[[], tuple[InversionResult, str]]] = {
        "ssef": lambda: (invert(model, trajectory, method="ssef", **options), ""),
        "ssef-rest": lambda: (invert(model, trajectory, method="ssef", end="rest", **options), ""),
        "polynomial": lambda: _polynomial(model, trajectory, options),
        "stable": lambda: (invert(model, trajectory, method="stable", **sampling), ""),
        "ocp": lambda: _ocp(model, trajectory, options),
        "zv": lambda: (invert(model, trajectory, method="zv", max_error=options.get("max_error"), **sampling), ""),
        "zvd": lambda: (invert(model, trajectory, method="zvd", max_error=options.get("max_error"), **sampling), ""),
        "replan": lambda: (invert(model, trajectory, method="replan", max_error=options.get("max_error"), **sampling), ""),
    }
    # every row is judged at the controller's period and hold, the one invert judges with; each row says which
    asked = {"period": held_period(options.get("period"), options.get("rate")), "hold": str(default("hold", options.get("hold")))}
    for method in METHODS:
        if progress is not None:
            progress(f"compare: {method}")
        start = time.perf_counter()
        try:
            result, note = runs[method]()
        except (InversionError, SettingsError) as exc:
            rows.append({**_row(method, None, exc), **asked, "seconds": time.perf_counter() - start})
            continue
        results[method] = result
        sampled = result.summary.get("sampled") or {}
        judged = {"period": float(sampled.get("period", asked["period"])), "hold": str(sampled.get("hold", asked["hold"]))}
        row = {**_row(method, result, None, note), **judged, "seconds": time.perf_counter() - start}
        if uncertainty is not None:
            from .robustness import judge_robustness

            row["worst_case_error"] = judge_robustness(result, uncertainty)["worst_case_error"]
        rows.append(row)
    return Comparison(rows, results)

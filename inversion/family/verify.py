"""Acceptance that matches correctness: is a member's torque what the numbers say it is?

A small constraint residual does not prove a result: an ill-conditioned segment system can
be solved "exactly" by two solvers into two different torques, and coefficients of 1e10
that sum to 1 lose the redefined output to cancellation. Three independent checks judge
what matters:

* **solver independence** -- the segment systems solved again with another
  factorisation (SVD least squares against LU); the torque and the redefined output at
  the check points must agree to :data:`TOLERANCE` of the peak torque (or of the request's
  torque scale ``max |yddot_d|/|CAB|`` if larger) and of the move;
* **extended precision** -- the segment systems assembled, solved (Gaussian elimination)
  and evaluated again in ``numpy.longdouble`` (64-bit mantissa on x86-64, 11 more bits
  than double); the same agreement is required. On a platform whose ``longdouble`` is
  plain double the check is reported as unavailable;
* **the plant** -- the linear plant ``Xdot = A X + B tau`` driven from the redefined
  initial state by the torque (exact discretisation of ``A`` with a quintic Hermite hold of
  the torque -- its value, slope and curvature at both ends of a step -- on a grid of
  0.2 rad of the fastest content per step, an error below ~2e-9 of the torque's scale)
  must reproduce ``y~``
  to :data:`PLANT_TOLERANCE` of the move: the inversion's defining property.

The check points are the segment ends, the locations of the figures and 6 points inside
every segment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from ..lti.discrete import run_smooth
from ..lti.system import NormalForm
from .figures import Figures
from .redefinition import Redefinition, evaluate_flat
from .ssef import PlanSolution, SegmentPlan, solve_plan

__all__ = ["Checks", "TOLERANCE", "PLANT_TOLERANCE", "check_member", "check_members", "plant_check", "EXTENDED_PRECISION"]

FloatArray = NDArray[np.float64]

#: Largest accepted disagreement of the torque (fraction of its peak) and of the redefined
#: output (fraction of the move) between two solvers or two precisions.
TOLERANCE = 1e-6
#: Largest accepted distance of the plant's tip from ``y~`` (fraction of the move).
PLANT_TOLERANCE = 1e-6
#: Whether ``longdouble`` carries more digits than double on this platform.
EXTENDED_PRECISION = bool(np.finfo(np.longdouble).eps < 1e-17)
#: Grid of the plant check: radians of the fastest content per step.
_PLANT_STEP = 0.2
_PLANT_MAX_STEPS = 400_000
_INTERIOR_POINTS = 6


@dataclass(frozen=True)
class Checks:
    """Outcome of one member's verification (relative differences).

    Attributes
    ----------
    solver_torque, solver_output : float
        Largest difference between the LU and the least-squares solutions (torque over
        its peak, output over the move).
    precision_torque, precision_output : float
        The same between double and extended precision (NaN when unavailable).
    precision : str
        ``"longdouble"`` or ``"unavailable"``.
    plant_output : float or None
        ``max |y_plant - y~| / move`` (``None`` when the plant check was not run).
    plant_state : float or None
        ``max |X_plant - X| / max |X|``.
    plant_steps : int
        Steps of the plant check.
    points : int
        Check points of the solver and precision checks.
    """

    solver_torque: float
    solver_output: float
    precision_torque: float
    precision_output: float
    precision: str
    plant_output: float | None = None
    plant_state: float | None = None
    plant_steps: int = 0
    points: int = 0

    def failure(self, tolerance: float = TOLERANCE, plant_tolerance: float = PLANT_TOLERANCE) -> tuple[str, str] | None:
        """``(status, message)`` of the first failed check, or ``None``.

        Parameters
        ----------
        tolerance : float, optional
            The largest relative difference accepted between solvers.
        plant_tolerance : float, optional
            The largest relative difference accepted from the plant.
        """
        if not (self.solver_torque <= tolerance and self.solver_output <= tolerance):
            return "solver", (
                f"the torque depends on the linear solver: LU and least squares differ by {self.solver_torque:.2e} of the "
                f"peak torque and {self.solver_output:.2e} of the move (accepted {tolerance:.0e})"
            )
        if self.precision == "longdouble" and not (self.precision_torque <= tolerance and self.precision_output <= tolerance):
            return "precision", (
                f"the result does not survive extended precision: it moves by {self.precision_torque:.2e} of the peak "
                f"torque and {self.precision_output:.2e} of the move (accepted {tolerance:.0e})"
            )
        if self.plant_output is not None and not self.plant_output <= plant_tolerance:
            return "plant", (
                f"the linear plant driven by the torque leaves the redefined output by {self.plant_output:.2e} of the "
                f"move (accepted {plant_tolerance:.0e})"
            )
        return None

    def as_dict(self) -> dict[str, float | int | str | None]:
        """JSON-ready values."""
        return {
            "solver_torque_difference": self.solver_torque,
            "solver_output_difference": self.solver_output,
            "precision_torque_difference": None if math.isnan(self.precision_torque) else self.precision_torque,
            "precision_output_difference": None if math.isnan(self.precision_output) else self.precision_output,
            "precision": self.precision,
            "plant_output_error": self.plant_output,
            "plant_state_error": self.plant_state,
            "plant_steps": self.plant_steps,
            "check_points": self.points,
        }


def _check_points(plan: SegmentPlan, figures: Sequence[Figures]) -> list[tuple[NDArray[np.intp], FloatArray, NDArray[np.intp]]]:
    """Check points of every member of ``plan``: blocks of points inside every segment, and the figures' locations.

    Returns ``(flat segments, local times, member)`` twice: blocks (times of shape (S, M))
    and single points.
    """
    K = plan.count
    B = plan.members
    flat = np.arange(B * K)
    blocks = (flat, plan.flat_durations[:, None] * np.linspace(0.0, 1.0, _INTERIOR_POINTS + 2)[None, :], flat // K)
    extra_t = np.array([[f.time_of_max_error, f.time_of_peak_torque] for f in figures]).ravel()
    extra_k = np.clip(np.searchsorted(plan.bounds, extra_t, side="right") - 1, 0, K - 1)
    extra_b = np.repeat(np.arange(B), 2)
    return [blocks, (extra_b * K + extra_k, extra_t - plan.bounds[extra_k], extra_b)]


def _differences(
    a: PlanSolution, b: PlanSolution | None, form: NormalForm,
    points: list[tuple[NDArray[np.intp], FloatArray, NDArray[np.intp]]], figures: Sequence[Figures],
) -> tuple[FloatArray, FloatArray]:
    """Largest torque and output differences of two solutions of a batch at the check points, per member (relative)."""
    B = len(figures)
    if b is None:
        return np.full(B, math.inf), np.full(B, math.inf)
    d_tau = np.zeros(B)
    d_y = np.zeros(B)
    for flat, s, member in points:
        va = evaluate_flat(a, form, flat, s, state=False)
        vb = evaluate_flat(b, form, flat, s.astype(b.c.dtype), state=False)
        for out, key in ((d_tau, "tau"), (d_y, "y")):
            diff = np.abs(np.asarray(va[key] - vb[key], dtype=float))
            diff = np.nan_to_num(diff, nan=np.inf).reshape(flat.size, -1).max(axis=1)
            np.maximum.at(out, member, diff)
    scale_tau = np.array([f.torque_scale for f in figures])
    scale_y = np.array([f.move if f.move > 0 else max(f.max_error, 1.0) for f in figures])
    return d_tau / scale_tau, d_y / scale_y


def _resolve(plan: SegmentPlan, solver: str, dtype: type) -> PlanSolution | None:
    """The same plan solved another way (``None`` if that fails outright)."""
    try:
        return solve_plan(plan, solver=solver, dtype=dtype)  # type: ignore[arg-type]
    except (np.linalg.LinAlgError, FloatingPointError, ValueError):
        return None


def check_members(
    solution: PlanSolution, form: NormalForm, figures: Sequence[Figures], members: Sequence[int], primary: str = "lu"
) -> list[Checks]:
    """Solver independence and extended precision of members.

    The members are those of one solved batch.

    Parameters
    ----------
    solution : PlanSolution
        The batch solved in double precision with ``primary``.
    form : NormalForm
        The model's matrices.
    figures : sequence of Figures
        The members' figures (scales of the comparison and extra check points).
    members : sequence of int
        The members checked (aligned with ``figures``).
    primary : {"lu", "lstsq"}
        The solver that produced ``solution``; the other one is the check.
    """
    members = list(members)
    if not members:
        return []
    mine = solution.subset(members)
    sub = mine.plan
    points = _check_points(sub, figures)
    other = _resolve(sub, "lstsq" if primary == "lu" else "lu", np.float64)
    solver = _differences(mine, other, form, points, figures)
    if EXTENDED_PRECISION:
        precision = _differences(mine, _resolve(sub, "ge", np.longdouble), form, points, figures)
        kind = "longdouble"
    else:
        precision, kind = (np.full(len(members), math.nan), np.full(len(members), math.nan)), "unavailable"
    count = int(sum(p[1].size for p in points) // max(len(members), 1))
    return [
        Checks(float(solver[0][i]), float(solver[1][i]), float(precision[0][i]), float(precision[1][i]), kind, points=count)
        for i in range(len(members))
    ]


def check_member(redef: Redefinition, figures: Figures, primary: str = "lu", plant: bool = False) -> Checks:
    """:func:`check_members` for one member, and its plant check.

    :func:`check_members` for one member, and (with ``plant``) :func:`plant_check`.

    Parameters
    ----------
    redef : Redefinition
        A solved member's redefinition.
    figures : Figures
        Its figures.
    primary : str, optional
        The solver it was solved with.
    plant : bool, optional
        Whether to drive the plant too.
    """
    checks = check_members(redef.solution, redef.form, [figures], [redef.member], primary)[0]
    if not plant:
        return checks
    output, state, steps = plant_check(redef, figures)
    return replace(checks, plant_output=output, plant_state=state, plant_steps=steps)


def plant_check(redef: Redefinition, figures: Figures) -> tuple[float, float, int]:
    """Drive the linear plant with the torque; compare with the output.

    Parameters
    ----------
    redef : Redefinition
        A solved member's redefinition.
    figures : Figures
        Its figures.

    Returns
    -------
    output_error : float
        ``max |C X_plant - y~| / move``.
    state_error : float
        ``max |X_plant - X| / max |X|``.
    steps : int
        Integration steps.
    """
    output, state, steps, _ = plant_run(redef, figures)
    return output, state, steps


def plant_run(redef: Redefinition, figures: Figures, step: float = _PLANT_STEP) -> tuple[float, float, int, FloatArray]:
    """:func:`plant_check`, and the plant's state at ``t_f``.

    When the output error comes out above a tenth of :data:`PLANT_TOLERANCE`, the run is
    repeated with steps four times shorter (the hold's error falls 4096-fold), so that a
    coarse grid cannot fail a member: what is reported then is the finer run's figure.

    The linear plant starts in the redefined state at ``t_0`` and is driven by the torque held
    as a quintic Hermite polynomial between points (values, slopes and curvatures of the
    closed form), exactly discretised with ``expm``: independent of the closed form's own
    internal dynamics. ``step``: the steps' length in units of the fastest rate (the hold's
    error falls as its sixth power). Modes left free (:mod:`inversion.lti.zero_dynamics`) start
    from the true initial state, not from their particular solution: the check measures
    what leaving them free costs.
    """
    run = _plant_run(redef, figures, step)
    if run[0] > 0.1 * PLANT_TOLERANCE:
        run = _plant_run(redef, figures, step / 4)
    return run


def _plant_run(redef: Redefinition, figures: Figures, step: float) -> tuple[float, float, int, FloatArray]:
    """One run of :func:`plant_run` at a given step."""
    form = redef.form
    A, B, C = form.A, form.B, form.C
    fastest_mode = float(np.abs(redef.plan.modal.lam).max(initial=0.0))
    rates = [max(float(np.abs(seg.mu).max(initial=0.0)), fastest_mode, 1e-12) for seg in redef.segments]
    counts = [max(8, math.ceil(seg.duration * rate / step)) for seg, rate in zip(redef.segments, rates)]
    total = sum(counts)
    if total > _PLANT_MAX_STEPS:
        counts = [max(8, math.ceil(c * _PLANT_MAX_STEPS / total)) for c in counts]
    start = redef.evaluate_local(0, [0.0])
    x = start["X"][0].astype(float)
    modal = redef.plan.modal
    if np.any(modal.free):  # free modes (zero_dynamics) start on their particular solution; the plant starts where it is
        XI = modal.to_physical(np.asarray(redef.plan.z_initial, dtype=complex)[None, :])
        x = np.asarray(form.state(np.asarray(start["y"], dtype=float), np.asarray(start["ydot"], dtype=float), XI)[0], dtype=float)
    worst_y = worst_x = peak_x = 0.0
    steps = 0
    for k, (seg, n) in enumerate(zip(redef.segments, counts)):
        s = np.linspace(0.0, seg.duration, n + 1)
        values = redef.evaluate_local(k, s)
        tau1, tau2 = redef.torque_rate(values)
        # the quintic Hermite hold of the torque (values, slopes and curvatures at both ends), exactly discretised
        states = run_smooth(A, B, x, s, values["tau"], tau1, tau2)[1:]
        x = states[-1]
        X = values["X"][1:]
        worst_y = max(worst_y, float(np.abs(states @ C - values["y"][1:]).max()))
        worst_x = max(worst_x, float(np.abs(states - X).max()))
        peak_x = max(peak_x, float(np.abs(X).max()))
        steps += n
    scale_y = figures.move if figures.move > 0 else 1.0
    return worst_y / scale_y, worst_x / (peak_x if peak_x > 0 else 1.0), steps, x

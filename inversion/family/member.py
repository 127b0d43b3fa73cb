"""Evaluate one member of the family: solve, measure, verify, judge.

:func:`evaluate_member` is shared by :func:`inversion.invert`, the automatic choice
(:mod:`inversion.family.auto`) and the explorer (:mod:`inversion.family.explore`), so a member's figures
and status are the same wherever it is computed. Its status is ``"ok"`` or names what
failed, in this order:

``settings``
    the settings do not fit the trajectory (e.g. ``h`` beyond its derivatives);
``singular``
    the internal dynamics cannot be diagonalised, or an exponent equals an unstable zero;
``residual``
    a segment system is not solved to ``tol``;
``max-error``
    the redefined output is further from ``y_d`` than ``max_error`` (the quality gate);
    judged before the checks below, since a redefinition metres away from the request is
    a failure however reproducibly it is computed;
``solver``, ``precision``, ``plant``
    a check of :mod:`inversion.family.verify` failed: the torque depends on the solver, does not
    survive extended precision, or does not drive the linear plant along ``y~``;
``rest``
    asked to end at rest (``end="rest"``), the torque at ``t_f`` is above ``REST_TOLERANCE``
    of its peak, or the linear plant left in the redefined state at ``t_f`` would move the
    tip by more than ``REST_TOLERANCE`` of the move in the following ``REST_WINDOW``
    seconds (the end conditions are met only to the member's rounding);
``max-torque``
    the peak torque exceeds ``max_torque``.

The figures of ``settings``, ``singular``, ``residual``, ``solver``, ``precision`` and
``plant`` are not trustworthy and are not reported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..acceptance import Acceptance, AfterEnd, Criteria, free_excursions, judge, window_length
from ..config import DEFAULTS, default, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.system import NormalForm
from ..options import End, Joining
from ..settings import InversionSettings, describe
from ..signals.chebyshev import PiecewiseChebyshev
from ..signals.trajectory import Trajectory
from .anchors import tracking_anchors
from .figures import Figures, figures_of
from .redefinition import Redefinition, evaluate_flat
from .series import member_signals
from .settle import SettleTail, settle_tail
from .ssef import SolverName, build_plan, solve_plan
from .verify import Checks, check_members, plant_run

__all__ = [
    "MemberResult", "evaluate_member", "evaluate_members", "member_acceptance", "FAILURES",
    "amplification",
]

#: The quality gate's default: the largest accepted redefinition error as a fraction of the move
#: (:data:`inversion.config.DEFAULTS`).
#: Statuses whose figures are not trustworthy.
FAILURES = ("settings", "singular", "residual", "solver", "precision", "plant", "rest")


@dataclass(frozen=True, eq=False)
class MemberResult:
    """A member of the family and what it achieves.

    Attributes
    ----------
    settings : InversionSettings
        The member.
    status : str
        ``"ok"`` or the failure (module docstring).
    message : str
        Why it failed ("" when ok).
    figures : Figures or None
        Its figures (``None`` for a numerical failure).
    checks : Checks or None
        The verification (``None`` if not reached or not run).
    redefinition : Redefinition or None
        The solved member.
    max_condition_number, max_constraint_residual : float
        Over the segment systems (NaN if not solved).
    amplification, max_spectral_radius : float or None
        Growth of the unstable state carried across the joints (``paper``/``position``).
    max_error : float
        The quality gate applied (m).
    tail : SettleTail or None
        The post-actuation of a settle end (:mod:`inversion.family.settle`).
    after : AfterEnd or None
        The linear plant left alone where the feedforward ends
        (:func:`~inversion.acceptance.after_end`, from the closed form's state there).
    """

    settings: InversionSettings
    status: str
    message: str = ""
    figures: Figures | None = None
    checks: Checks | None = None
    redefinition: Redefinition | None = None
    max_condition_number: float = math.nan
    max_constraint_residual: float = math.nan
    amplification: float | None = None
    max_spectral_radius: float | None = None
    max_error: float = math.nan
    tail: SettleTail | None = None
    after: AfterEnd | None = None

    @property
    def feed_end(self) -> float:
        """When the feedforward ends: ``t_f``, or the end of a settle tail (s)."""
        assert self.redefinition is not None
        return self.tail.end if self.tail is not None else float(self.redefinition.plan.bounds[-1])

    @property
    def ok(self) -> bool:
        """Whether the member passed every check."""
        return self.status == "ok"

    def error(self, hint: str = "") -> InversionError:
        """The :class:`InversionError` that reports this member's failure.

        The :class:`InversionError` that reports this member's failure (``hint`` appended).

        Parameters
        ----------
        hint : str, optional
            A sentence appended to the message.
        """
        exc = InversionError(f"{describe(self.settings)}: {self.message}{'; ' + hint if hint else ''}",
                             condition=self.max_condition_number)
        exc.residual = self.max_constraint_residual
        exc.status = self.status  # type: ignore[attr-defined]
        return exc


def amplification(propagation: NDArray[np.float64]) -> tuple[float, float] | None:
    """The growth of a member's propagation maps.

    Largest (Frobenius) norm of the partial products of a member's propagation maps, and the largest spectral radius.

    ``None`` when no unstable state is carried (``anchored`` joining, or no unstable zero).

    Parameters
    ----------
    propagation : NDArray[np.float64]
        The member's propagation maps, one a segment.
    """
    if propagation.size == 0:
        return None
    if not np.all(np.isfinite(propagation)):
        return math.inf, math.inf
    product = np.eye(propagation.shape[1])
    growth = 1.0
    for step in propagation:
        product = step @ product
        growth = max(growth, float(np.sqrt(np.sum(product * product))))
    radius = float(np.abs(np.linalg.eigvals(propagation)).max())
    return growth, radius


def _gate(figures: Figures, max_error: float | None) -> float:
    """The quality gate in metres: ``max_error``, or :attr:`~inversion.config.Defaults.quality_gate` of the move."""
    return tip_bound(max_error, max(figures.move, 0.0), judged=False)


def segment_anchors(form: NormalForm, trajectory: Trajectory, settings: InversionSettings) -> Any:
    """The exact-tracking anchors of an ``anchored`` member's segmentation, to share between the
    members of a batch (``None`` for another joining, or settings that do not fit; the members then
    report that themselves)."""
    if settings.joining != Joining.ANCHORED:
        return None
    try:
        return tracking_anchors(form.modal(settings.eps), trajectory, settings.boundaries(trajectory, form.rho))
    except (SettingsError, InversionError):
        return None


def initial_modal_state(form: NormalForm, eps: float, internal_state: ArrayLike | None,
                        trajectory: Trajectory | None = None) -> NDArray[np.complex128]:
    """``z(t0)`` from ``X_I(t0) = [delta; deltadot]`` (default: rest).

    For a system of relative degree other than 2 the internal coordinates driven by ``yddot``
    also depend on the output's derivatives at ``t0`` (:meth:`NormalForm.internal_start`),
    read from ``trajectory``.

    Raises
    ------
    SettingsError
        For a state of the wrong size or with non-finite values.
    """
    n2 = form.n_internal
    XI0 = np.zeros(n2)
    if internal_state is not None:
        XI0 = np.asarray(internal_state, dtype=float).reshape(-1)
        if XI0.size != n2 or not np.all(np.isfinite(XI0)):
            raise SettingsError("initial_internal_state", internal_state, f"{n2} finite numbers [delta; deltadot]")
    if trajectory is not None and form.shift.any():
        XI0 = form.internal_start(XI0, trajectory.values([trajectory.t0], form.shift.shape[1] - 1))
    if not XI0.any():
        return np.zeros(n2, dtype=complex)
    return form.modal(eps).to_modal(XI0)


def evaluate_members(
    form: NormalForm,
    trajectory: Trajectory,
    settings: Sequence[InversionSettings],
    *,
    initial_internal_state: ArrayLike | None = None,
    anchors: Any = None,
    solver: SolverName | None = None,
    tol: float | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    verify: bool = True,
    plant: bool = False,
    window: float | None = None,
) -> list[MemberResult]:
    """Solve, measure, verify and bound members differing in ``cdec``.

    Solve members that differ only in ``cdec``, compute their figures, verify them and apply the bounds.

    Parameters
    ----------
    form : NormalForm
        The model's matrices.
    trajectory : Trajectory
        The desired trajectory.
    settings : sequence of InversionSettings
        The members: the same segments, ``h``, joining and ``eps``, any ``cdec``.
    initial_internal_state : array_like, optional
        ``X_I(t0)`` (default: rest).
    anchors : ndarray, optional
        :func:`~inversion.family.anchors.tracking_anchors` for this segmentation (shared by the
        explorer between batches; computed when needed).
    solver : {"lu", "lstsq"}, optional
        The primary solver (the other one checks it; default :data:`inversion.config.DEFAULTS`).
    tol : float, optional
        Largest accepted relative constraint residual (default :data:`inversion.config.DEFAULTS`).
    max_error : float, optional
        Quality gate (m); default 5 % of the move; ``inf`` accepts anything.
    max_torque : float, optional
        Largest accepted peak torque (N m).
    verify : bool
        Run the solver and extended-precision checks (the automatic choice runs them on
        its candidates only).
    plant : bool
        Also run the plant check.
    window : float, optional
        The after-end window (s; default :func:`~inversion.acceptance.window_length`).

    Returns
    -------
    list of MemberResult
        Aligned with ``settings``. Never raises for a numerical failure: the status says
        what failed.
    """
    if not settings:
        return []
    solver = default("solver", solver)
    tol = default("tol", tol)
    base = settings[0]
    if any((s.segments, s.h, s.joining, s.eps, s.plan_end, s.edges) != (base.segments, base.h, base.joining, base.eps, base.plan_end, base.edges)
           for s in settings):
        raise ValueError("a batch of members must share segments, h, joining, eps and end (a settle end shares a free end's systems)")
    try:
        bounds = base.boundaries(trajectory, form.rho)
    except SettingsError as exc:
        return [MemberResult(s, "settings", str(exc)) for s in settings]
    try:
        modal = form.modal(base.eps)
        z0 = initial_modal_state(form, base.eps, initial_internal_state, trajectory)
        # h joins y^(rho) smoothly: the plan joins yddot~ to order h + rho - 2 (rho = 1: h - 1)
        plan = build_plan(modal, trajectory, bounds, base.h + form.rho - 2, [s.cdec for s in settings], base.joining, z0,
                          anchors if base.joining == Joining.ANCHORED else None, end=base.plan_end, edges=base.edges)
    except InversionError as exc:
        return [MemberResult(s, "singular", str(exc)) for s in settings]
    solution = solve_plan(plan, solver=solver)
    K = plan.count
    results: list[MemberResult | None] = [None] * len(settings)
    solved = []
    for b, s in enumerate(settings):
        failure = solution.failure(b, tol)
        if failure is None:
            solved.append(b)
        else:
            status = "singular" if plan.singular[b] else "residual"
            results[b] = MemberResult(s, status, str(failure), max_condition_number=failure.condition,
                                      max_constraint_residual=failure.residual)
    figures = figures_of(solution, form, trajectory, solved)
    finite = [b for b, f in zip(solved, figures) if math.isfinite(f.max_error) and math.isfinite(f.peak_torque)]
    by_member = dict(zip(solved, figures))
    ends = _feed_ends(solution, form, trajectory, settings, finite, by_member, window)
    checks: dict[int, Checks] = {}
    if verify or plant:
        checks = dict(zip(finite, check_members(solution, form, [by_member[b] for b in finite], finite, solver)))
    for b in solved:
        s = settings[b]
        redef = Redefinition(solution, b, form)
        growth = amplification(solution.propagation[b * K : (b + 1) * K]) if solution.propagation.size else None
        fig = by_member[b]
        common: dict[str, Any] = {
            "redefinition": redef,
            "max_condition_number": float(solution.conditions[b * K : (b + 1) * K].max()),
            "max_constraint_residual": float(solution.residuals[b * K : (b + 1) * K].max()),
            "amplification": None if growth is None else growth[0],
            "max_spectral_radius": None if growth is None else growth[1],
            "max_error": _gate(fig, max_error),
        }
        if b not in finite:
            results[b] = MemberResult(s, "residual", "the redefinition is not finite", **common)
        else:
            results[b] = _judged(s, redef, ends[b], checks.get(b), common, growth, max_torque, plant)
    return [r for r in results if r is not None]


def _judged(s: InversionSettings, redef: Redefinition, end: Any, check: Checks | None, common: dict[str, Any],
            growth: tuple[float, float] | None, max_torque: float | None, plant: bool) -> MemberResult:
    """A solved member with finite figures judged: its end, the quality gate, the checks (the plant's with ``plant``), the
    rest end's and the torque limit, in that order; the first that fails is its status."""
    common = {**common, "tail": end.tail, "after": end.after}
    fig = end.figures
    if end.failure:
        return MemberResult(s, "settle", end.failure, fig, **common)
    if not fig.max_error <= common["max_error"]:  # far from y_d: that is the failure, however it is computed
        return MemberResult(s, "max-error", _gate_message(fig, common["max_error"], growth), fig, check, **common)
    plant_end = None
    if check is not None and plant:
        # a rest end is judged on the plant itself: finer steps (a hold error of ~1e-12)
        output, state, steps, plant_end = plant_run(redef, fig, **({"step": REST_PLANT_STEP} if s.end == End.REST else {}))
        check = replace(check, plant_output=output, plant_state=state, plant_steps=steps)
    failed = check.failure() if check is not None else None
    if failed is None and s.end == End.REST and check is not None:
        failed = rest_failure(redef, fig, plant_end)
    if failed is not None:
        return MemberResult(s, failed[0], failed[1], checks=check, **common)
    if max_torque is not None and not fig.peak_torque <= max_torque:
        return MemberResult(s, "max-torque", f"the peak torque {fig.peak_torque:.4g} N m exceeds {max_torque:g} N m",
                            fig, check, **common)
    return MemberResult(s, "ok", "", fig, check, **common)


@dataclass(frozen=True)
class _FeedEnd:
    """How a member's feedforward ends: its settle tail, the plant left alone after it, its figures with the tail's torque."""

    figures: Figures
    tail: SettleTail | None
    after: AfterEnd | None
    failure: str = ""


def _feed_ends(solution: Any, form: NormalForm, trajectory: Trajectory, settings: Sequence[InversionSettings], members: list[int],
               figures: dict[int, Figures], window: float | None) -> dict[int, _FeedEnd]:
    """The end of every member's feedforward, in one batch: the closed form's state at ``t_f``, a settle tail
    (:mod:`inversion.family.settle`) where asked for, and the linear plant left alone from the state where the
    feedforward ends (:func:`~inversion.acceptance.free_excursions`)."""
    if not members:
        return {}
    plan = solution.plan
    K = plan.count
    flat = np.asarray(members, dtype=np.intp) * K + K - 1
    values = evaluate_flat(solution, form, flat, np.full(flat.size, plan.durations[-1]))
    X_end = np.asarray(values["X"], dtype=float)
    y_final = float(plan.position[-1, 0])
    hold = form.equilibrium_input(y_final)
    span = float(plan.bounds[-1] - plan.bounds[0])
    out: dict[int, _FeedEnd] = {}
    starts = X_end.copy()
    for row, b in enumerate(members):
        fig, tail, failure = figures[b], None, ""
        if settings[b].end == End.SETTLE:
            modal = plan.modal
            z = modal.to_modal(np.asarray(values["XI"][row], dtype=float))
            joint_range = fig.move / form.output_at if form.output_at else 0.0
            try:
                tail = settle_tail(form, modal, float(plan.bounds[-1]), y_final, z, (fig.torque_scale, joint_range),
                                   DEFAULTS.settle_tolerance, DEFAULTS.longest_tail * span)
            except InversionError as exc:
                failure = str(exc)
            if tail is not None:
                fig, starts[row] = _with_tail(fig, tail)
        out[b] = _FeedEnd(fig, tail, None, failure)
    length = window_length(form, window)
    excursion, drift = free_excursions(form, starts, y_final, hold, length)
    for row, b in enumerate(members):
        end = out[b]
        feed_end = end.tail.end if end.tail is not None else float(plan.bounds[-1])
        out[b] = replace(end, after=AfterEnd(length, feed_end, float(excursion[row]), float(drift[row])))
    return out


def _with_tail(fig: Figures, tail: SettleTail) -> tuple[Figures, NDArray[np.float64]]:
    """The member's figures with the tail's torque (its peak on a grid of four points a radian), and the state where the tail ends."""
    form = tail.form
    fastest = float(np.abs(tail.modal.lam[~(tail.modal.unstable | tail.modal.free)]).max(initial=0.0))
    count = int(min(200_000, max(64, math.ceil(tail.length * fastest * 4))))
    t = tail.start + np.linspace(0.0, tail.length, count + 1)
    values = tail.values(t)
    X = form.state_of(values)
    tau = np.abs(np.asarray(form.input_of(values, X), dtype=float))
    peak = int(np.argmax(tau))
    if tau[peak] > fig.peak_torque:
        fig = replace(fig, peak_torque=float(tau[peak]), time_of_peak_torque=float(t[peak]))
    return fig, np.asarray(X[-1], dtype=float)


def member_acceptance(
    member: MemberResult, form: NormalForm, trajectory: Trajectory, bounds: Criteria, *, link: bool,
    larger: tuple[int, dict[str, Any]] | None = None,
) -> tuple[Acceptance, PiecewiseChebyshev, MemberResult]:
    """What reaches the link from a solved member.

    What reaches the link from a solved member (:mod:`inversion.acceptance`), the signals it feeds forward, and the member
    (its settle tail started from the state summed in extended precision).

    Parameters
    ----------
    member : MemberResult
        A solved member (its after-end figure computed).
    form : NormalForm
        The model's matrices.
    trajectory : Trajectory
        The desired trajectory.
    bounds : Criteria
        The period and hold of the held table, the after-end window.
    link : bool
        Whether the form is a link's (its signals: the torque and the joint references).
    larger : (int, dict), optional
        The modes and matrices of the model with more modes (:func:`modelgen.linear.linear_model`):
        the truncation check, run only for a member that starts from rest.

    Returns
    -------
    Acceptance, PiecewiseChebyshev, MemberResult
    """
    redef, fig = member.redefinition, member.figures
    assert redef is not None and fig is not None and member.after is not None
    if member.tail is not None:  # started where the closed form summed in extended precision ends: continuous to rounding
        member = replace(member, tail=member.tail.starting_at(redef.end_state()))
    signals = member_signals(redef, link, member.tail)
    tf = float(redef.plan.bounds[-1])
    t0 = float(redef.plan.bounds[0])
    x0 = np.asarray(redef.evaluate([t0])["X"][0], dtype=float)
    if member.tail is not None:
        x_end = np.asarray(member.tail.form.state_of(member.tail.values([member.tail.end]))[0], dtype=float)
    else:
        x_end = np.asarray(redef.evaluate([tf])["X"][0], dtype=float)
    at_rest = not np.any(redef.plan.z_initial) and not float(redef.plan.position[0, 1])  # the larger model starts at rest

    def reference(t: NDArray[np.float64]) -> NDArray[np.float64]:
        # y~ through t_f; after it the output the feedforward holds (a settle tail's y_f = y~(t_f)), or ends on
        inside = np.clip(t, t0, tf)
        if inside.ndim == 1 and inside.size > 1 and np.all(np.diff(inside) >= 0):  # a grid: segment by segment, in blocks
            return np.asarray(redef.sample(inside)["y"], dtype=float)
        return np.asarray(redef.evaluate(inside)["y"], dtype=float)

    acceptance = judge(form, trajectory, signals, bounds, x0=x0, x_end=x_end, feed_start=t0, feed_end=member.feed_end, reference=reference,
                       peak=fig.peak_torque, error=fig.max_error, move=fig.move, larger=larger, at_rest=at_rest)
    return acceptance, signals, member


def point_table(member: MemberResult, period: float) -> tuple[NDArray[np.float64], float, float]:
    """A solved member's torque at the rows of a controller at ``period`` (``t_0 + k period`` until its feedforward ends,
    the settle tail's included), and the inputs held before and after the table: what :func:`inversion.acceptance.table_rate`
    judges, before the member's series are fitted (a cheap test of its rate for a search)."""
    redef = member.redefinition
    assert redef is not None
    form = redef.form
    plan = redef.plan
    t0, tf = float(plan.bounds[0]), float(plan.bounds[-1])
    count = max(1, math.ceil((member.feed_end - t0) / period - 1e-9))
    t = t0 + np.arange(count) * period
    inside = t <= tf
    values = redef.sample(t[inside])
    tau = np.asarray(form.input_of(values, form.state_of(values)), dtype=float)
    if member.tail is not None and not np.all(inside):
        later = member.tail.values(t[~inside])
        tau = np.concatenate([tau, np.asarray(form.input_of(later, form.state_of(later)), dtype=float)])
    at_rest = not np.any(plan.z_initial) and not float(plan.position[0, 1])  # else no input was held before the table
    before = form.equilibrium_input(float(plan.position[0, 0])) if at_rest else float(tau[0])
    after = form.equilibrium_input(float(plan.position[-1, 0]))
    return tau, before, after


#: A rest end must bring the torque and the free motion of the tip after ``t_f`` below this
#: fraction of the peak torque and of the move (:attr:`inversion.config.Defaults.rest_tolerance`).
REST_TOLERANCE = DEFAULTS.rest_tolerance
#: Seconds after ``t_f`` over which the free motion of the tip is measured.
REST_WINDOW = 2.0
#: Steps of the plant run that judges a rest end, in units of the fastest rate.
REST_PLANT_STEP = 0.05


def rest_failure(redef: Redefinition, fig: Figures, plant_end: NDArray[np.float64] | None = None) -> tuple[str, str] | None:
    """Whether a member asked to end at rest does (``None``), or why not.

    The torque at ``t_f`` (Eq. (12)) with its rounding against the input that holds the
    plant at rest there (:meth:`~inversion.lti.system.NormalForm.equilibrium_input`: zero for
    the link), and the output's motion over ``REST_WINDOW`` of the linear plant left with
    that input from ``t_f`` (exact: the matrix exponential of the plant with the input as a
    constant state) -- in ``plant_end``, the state of the plant driven by the torque
    (:func:`~inversion.family.verify.plant_run`), or else in the redefined state.
    """
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    form = redef.form
    last = redef.plan.count - 1
    end = redef.evaluate_local(last, [redef.plan.durations[last]])
    X = np.asarray(end["X"][0], dtype=float)
    # the torque at t_f as far as double precision can tell: its value plus the rounding of
    # the closed form there (the samples and any other evaluator see the value within it)
    hold = form.equilibrium_input(float(redef.plan.position[-1, 0]))
    tau = float(np.asarray(end["tau"], dtype=float)[0]) - hold
    tau = math.copysign(abs(tau) + float(redef.rounding([last], [redef.plan.durations[last]])["tau"][0]), tau)
    start = X if plant_end is None else np.asarray(plant_end, dtype=float)
    N = start.size
    augmented = np.zeros((N + 1, N + 1))
    augmented[:N, :N], augmented[:N, N] = form.A, form.B * hold
    step = sla.expm(augmented * (REST_WINDOW / 200))
    x = np.append(start, 1.0)
    tip = [float(form.C @ start)]
    for _ in range(200):
        x = step @ x
        tip.append(float(form.C @ x[:N]))
    drift = float(np.ptp(tip))
    move = fig.move if fig.move > 0 else 1.0
    if abs(tau) <= REST_TOLERANCE * fig.peak_torque and drift <= REST_TOLERANCE * move:
        return None
    held = f" - {hold:.6g} (the input at rest)" if hold else ""
    return "rest", (f"the feedforward does not end at rest to {REST_TOLERANCE:g}: |tau_l(t_f){held}| up to {abs(tau):.3g} "
                    f"with its rounding ({abs(tau) / fig.peak_torque:.2g} of the peak), and the output of the plant left with "
                    f"{'that input' if hold else 'zero torque'} moves {drift:.3g} ({drift / move:.2g} of the move) in the "
                    f"{REST_WINDOW:g} s after t_f")


def _gate_message(fig: Figures, gate: float, growth: tuple[float, float] | None) -> str:
    """Why a member fails the quality gate (with the growth of the carried unstable state when it explains it)."""
    message = (
        f"the redefined output is {fig.max_error:.4g} m from the desired one ({100 * fig.relative_error:.3g} % "
        f"of the {fig.move:.4g} m move; accepted {gate:.3g} m)"
    )
    if growth is not None and growth[0] > 1e3:
        message += (f"; the unstable internal state carried across the segments grows by {growth[0]:.3g} "
                    f"(largest spectral radius of a segment's propagation map {growth[1]:.3g})")
    return message


def evaluate_member(form: NormalForm, trajectory: Trajectory, settings: InversionSettings, **options: Any) -> MemberResult:
    """:func:`evaluate_members` for one member (same options).

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    trajectory : Trajectory
        The desired output.
    settings : InversionSettings
        The member.
    """
    return evaluate_members(form, trajectory, [settings], **options)[0]

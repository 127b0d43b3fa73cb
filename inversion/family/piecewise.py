"""Piece-wise causal inversion by output redefinition: the paper's method (its section 5, and beyond it).

:func:`ssef_inversion` picks a member of the family (the caller's settings, the paper's for its
own cases, or the automatic choice of :mod:`inversion.family.auto`), solves and verifies it
(:mod:`inversion.family.member`), and :func:`sample_member` samples the bounded, continuous, causal
feedforward torque ``tau_l = (yddot~ - C A^2 X) / CAB`` (Eq. (12)) with everything needed to
use it. :func:`inversion.invert` is the entry point that leads here.

>>> import modelgen
>>> from inversion import invert, smoothstep
>>> result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), segments=5, h=2, cdec=(1e-4, 1.0))
>>> round(result.summary["max_redefinition_error"], 5), len(result.segments)
(0.00573, 5)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.model import Model
from modelgen.paper import PaperCase

from ..acceptance import Acceptance, Criteria, held_table, larger_model, outside_values, summary_keys
from ..config import DEFAULTS, default, held_period, tip_bound
from ..errors import SettingsError
from ..lti.linear_system import LinearSystem
from ..lti.system import NormalForm
from ..lti.zero_dynamics import free_zeros, zero_dynamics_summary
from ..options import Hold, ZeroSet
from ..result import (
    CSV_COLUMNS,
    SYSTEM_CSV_COLUMNS,
    InversionResult,
    InversionSummary,
    SegmentSummary,
    SummaryFigures,
    SystemInversionSummary,
    inverse_input,
    segment_summaries,
    summarize,
)
from ..settings import DEFAULT_SETTINGS, InversionSettings, decide_auto, paper_settings
from ..signals.chebyshev import DEGREE, PiecewiseChebyshev
from ..signals.trajectory import Trajectory
from .figures import Figures
from .member import MemberResult, evaluate_member, member_acceptance
from .redefinition import Redefinition
from .settle import SettleTail
from .ssef import SegmentSolution, SolverName
from .verify import Checks

__all__ = ["ssef_inversion", "family_form", "sample_member", "MemberDetail", "resolve_settings", "sample_times", "InversionResult", "InversionSummary",
           "SystemInversionSummary", "SegmentSummary", "CSV_COLUMNS", "SYSTEM_CSV_COLUMNS"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MemberDetail:
    """What a result of the family keeps of its own.

    What a result of the family keeps of its own (:attr:`inversion.result.InversionResult.detail`).

    Attributes
    ----------
    segments : list of SegmentSolution
        Exponents, coefficients, residual and condition number of each segment (Eq. (29)).
    figures : Figures
        Largest redefinition error and peak torque, from the closed form.
    checks : Checks
        The verification (solver, extended precision, plant).
    redefinition : Redefinition
        The solved member: its closed form anywhere.
    tail : SettleTail or None
        A settle end's post-actuation after ``t_f`` (:mod:`inversion.family.settle`).
    """

    segments: list[SegmentSolution]
    figures: Figures
    checks: Checks
    redefinition: Redefinition
    tail: SettleTail | None = None

    def evaluate(self, t: ArrayLike) -> dict[str, Any]:
        """``y~``, its derivatives and ``X_I`` at times ``t``.

        ``y~``, its derivatives and ``X_I`` at times ``t`` (any order): the closed form through ``t_f``, the tail after.

        Parameters
        ----------
        t : array_like
            Times (s).

        Returns
        -------
        dict
            The output's values (``y``, ``ydot``, ``yddot``, ..., ``XI``), as :meth:`Redefinition.evaluate`.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        values = self.redefinition.evaluate(t)
        if self.tail is not None and np.any(t >= self.tail.start):  # from t_f on: the settle tail's closed form (as the series)
            after = t >= self.tail.start
            tail = self.tail.values(t[after])
            values = {k: np.array(v, dtype=float) for k, v in values.items() if k in tail}
            for k in values:
                values[k][after] = tail[k]
        return values


def resolve_settings(
    case: PaperCase | None,
    explicit: Mapping[str, Any],
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
) -> InversionSettings:
    """The member a manual inversion uses.

    The member a manual inversion uses: the paper's for its own cases, else the defaults, then the caller's.

    Parameters
    ----------
    case : PaperCase or None
        The paper's case of the inversion (:func:`inversion.problem.paper_case`).
    explicit : mapping
        Values the caller gave (``segments``, ``h``, ``cdec``, ``joining``, ``eps``).
    settings : InversionSettings, mapping or path, optional
        A stored member (``best.json``); ``explicit`` values override it.
    """
    base = paper_settings(case) if case is not None else DEFAULT_SETTINGS
    if isinstance(settings, InversionSettings):
        base = settings
    elif isinstance(settings, Mapping):
        base = InversionSettings.from_dict(settings, base)
    elif settings is not None:
        base = InversionSettings.from_json(settings, base)
    changes = {k: (tuple(v) if k == "segments" and not isinstance(v, (int, np.integer)) else v) for k, v in explicit.items()}
    return base.with_changes(**changes) if changes else base


def family_form(model: Any, zeros: str = "all") -> NormalForm:
    """The normal form the family inverts.

    A system's, or a link's with the unstable zeros ``zeros`` constrained (:func:`inversion.lti.zero_dynamics.free_zeros`).
    A system's and a link's with every zero constrained are cached per model: the same object each time.

    Parameters
    ----------
    model : Model or LinearSystem
        The plant.
    zeros : {"all", "physical", "converged"}
        A link's zeros constrained.
    """
    if isinstance(model, LinearSystem):
        return NormalForm.of_system(model)
    return free_zeros(model, NormalForm.of_model(model), zeros)


def ssef_inversion(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    explicit: Mapping[str, Any],
    *,
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
    auto: bool | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    max_torque_rate: float | None = None,
    objective: str | None = None,
    rate: float,
    period: float | None = None,
    hold: str | None = None,
    window: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: SolverName = DEFAULTS.solver,
    tol: float,
    progress: Callable[[str], None] | None = None,
    zeros: str = "all",
    case: PaperCase | None = None,
    loop: tuple[float, float] | None = None,
) -> InversionResult:
    """The SSEF inversion of :func:`inversion.invert`.

    ``explicit`` holds the member's values the caller gave (``segments``, ``h``, ``cdec``,
    ``joining``, ``eps``, ``end``). A member given, or the paper's for a paper case, is
    evaluated and verified, and what reaches the link is measured and reported; otherwise the
    family is searched for a member that meets the bounds there too (:func:`inversion.family.auto.choose`).

    Parameters
    ----------
    model : Model | LinearSystem
        The plant.
    trajectory : Trajectory
        The desired output.
    explicit : Mapping[str, Any]
        The member's values the caller gave.
    settings : InversionSettings | Mapping[str, Any] | str | Path | None, optional
        A member, its mapping or file, or ``None``.
    auto : bool | None, optional
        Whether to search the family (``None``: when no member is given).
    max_error : float | None, optional
        The tip's bound (m).
    max_torque : float | None, optional
        The peak torque's bound (N m).
    max_torque_rate : float | None, optional
        The bound on the held rows' change.
    objective : str | None, optional
        What the search minimises.
    rate : float
        The sampling rate (Hz).
    period : float | None, optional
        The controller's period (s).
    hold : str | None, optional
        How the controller holds the rows.
    window : float | None, optional
        The after-end window (s).
    initial_internal_state : ArrayLike | None, optional
        ``X_I(t_0)``, if not at rest.
    solver : SolverName, optional
        The segment systems' linear solver.
    tol : float
        The segment systems' residual tolerance.
    progress : Callable[[str], None] | None, optional
        The search's progress display.
    zeros : str, optional
        The unstable zeros constrained.
    case : PaperCase, optional
        The paper's case of ``model`` and ``trajectory`` (:func:`inversion.problem.paper_case`), decided once by
        :func:`inversion.invert`; ``None`` for any other.
    loop : (float, float), optional
        A link's joint PD gains: every member is judged with that loop closed too (:attr:`inversion.acceptance.Criteria.loop`).

    Raises
    ------
    SettingsError
        For settings that do not fit the trajectory.
    InversionError
        When the member fails (with its figures), or no member passes the search (with the
        alternatives).
    """
    form = family_form(model, zeros)
    auto = decide_auto(case, explicit, settings, auto)  # the paper's member ends free: with another end, chosen like any other
    move = trajectory.move()
    gate = tip_bound(max_error, move, judged=auto)
    bounds = Criteria(max_error=gate, max_torque=max_torque, torque_ratio=DEFAULTS.torque_ratio, window=window,
                    extra_modes=DEFAULTS.extra_modes, period=held_period(period, rate),
                    hold=default("hold", hold), max_torque_rate=max_torque_rate, loop=loop)
    larger = larger_model(model, bounds.extra_modes)
    search: dict[str, Any] | None = None
    if auto:
        if settings is not None:
            raise SettingsError("settings", settings, "no stored settings with auto=True (it searches the family itself)")
        from .auto import choose

        choice = choose(form, trajectory, fixed=explicit, bounds=bounds, objective=objective, initial_internal_state=initial_internal_state,
                        solver=solver, tol=tol, progress=progress, larger=larger)
        member, acceptance, signals, search = choice.member, choice.acceptance, choice.signals, choice.record
    else:
        if objective is not None:
            raise SettingsError("objective", objective, "None with a member given (an objective chooses the member: auto=True)")
        chosen = resolve_settings(case, explicit, settings)
        chosen.boundaries(trajectory, form.rho)  # a user error: SettingsError, not a failed member
        member = evaluate_member(form, trajectory, chosen, initial_internal_state=initial_internal_state, solver=solver,
                                 tol=tol, max_error=gate, max_torque=max_torque, verify=True, plant=True, window=window)
        if not member.ok:
            raise member.error("the automatic choice (auto=True) searches the family for a member that meets the bounds")
        acceptance, signals, member = member_acceptance(member, form, trajectory, bounds, link=isinstance(model, Model), larger=larger)
        failed = acceptance.failure(bounds)  # what it asked for is y_d, after the move too, as a controller holds it
        if failed is not None:
            hint = "end='settle' or end='rest' holds it there" if failed[0] == "after-end" else ""
            raise replace(member, status=failed[0], message=failed[1]).error(hint)
    judged = Judged(member, acceptance, signals, bounds)
    return sample_member(model, trajectory, judged, rate, solver, tol, initial_internal_state, search, zeros, case)


@dataclass(frozen=True)
class Judged:
    """A verified member with what reaches the link: its acceptance, its signals and the bounds it was judged by."""

    member: MemberResult
    acceptance: Acceptance
    signals: PiecewiseChebyshev
    bounds: Criteria


def sample_times(trajectory: Trajectory, rate: float, end: float | None = None) -> FloatArray:
    """The sample times ``t0 + k (1 / rate)`` through ``end``.

    ``t0 + k (1 / rate)`` through ``end`` (default ``tf``; itself appended when the grid misses it).

    Parameters
    ----------
    trajectory : Trajectory
        The desired output.
    rate : float
        The sampling rate (Hz).
    end : float | None, optional
        The last time (s; ``None``: ``t_f``).
    """
    stop = trajectory.tf if end is None else float(end)
    count = int(math.floor((stop - trajectory.t0) * rate + 1e-9)) + 1
    # k times the period, as the acceptance's held rows are (inversion.acceptance.held_table): k / rate differs from
    # k * period in the last bit for one k in seven, and so did 14 % of the rows the C serves from inversion.csv's
    t = trajectory.t0 + np.arange(count) * (1.0 / rate)
    if stop - t[-1] > 1e-9 / rate:
        t = np.append(t, stop)
    return np.asarray(t, dtype=float)


def sample_member(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    judged: Judged,
    rate: float,
    solver: str,
    tol: float,
    initial_internal_state: ArrayLike | None,
    search: dict[str, Any] | None,
    zeros: str = "all",
    case: PaperCase | None = None,
) -> InversionResult:
    """Sample a judged member and summarize it.

    With ``hold="zoh"`` the samples are the controller's: one a period, the torque the mean of
    the period it is held over (:func:`~inversion.acceptance.held_table`); otherwise the
    signals at ``rate``, through the end of the feedforward (a settle tail included).

    Parameters
    ----------
    model : Model | LinearSystem
        The plant.
    trajectory : Trajectory
        The desired output.
    judged : Judged
        The judged member.
    rate : float
        The sampling rate (Hz).
    solver : str
        The segment systems' linear solver.
    tol : float
        The segment systems' residual tolerance.
    initial_internal_state : ArrayLike | None
        ``X_I(t_0)``, if not at rest.
    search : dict[str, Any] | None
        The search's record, if a search chose the member.
    zeros : str, optional
        The unstable zeros constrained.
    case : PaperCase | None, optional
        The paper case, if any.
    """
    member, signals, bounds = judged.member, judged.signals, judged.bounds
    redef, figures, checks = member.redefinition, member.figures, member.checks
    assert redef is not None and figures is not None and checks is not None and member.after is not None
    plan = redef.plan
    link = not isinstance(model, LinearSystem)
    if bounds.hold == Hold.ZOH:
        y_start, y_final = float(plan.position[0, 0]), float(plan.position[-1, 0])
        outside = [outside_values(signals, t, redef.form.equilibrium_input(y)) for t, y in ((trajectory.t0, y_start), (member.feed_end, y_final))]
        t, fed = held_table(signals, trajectory.t0, member.feed_end, bounds.period, Hold.ZOH, *outside)
    else:
        t = sample_times(trajectory, rate, member.feed_end)
        fed = signals.evaluate(t)
    sampled = _redefined(redef, member.tail, t)
    X, tau_closed = inverse_input(model, redef.form, sampled)  # Eq. (12), one batch
    tau = fed[signals.names[0]]
    summary = _summary(model, trajectory, judged, t, sampled, X, tau, rate, solver, tol, initial_internal_state, search, zeros,
                       signals.evaluate(t)[signals.names[0]] if bounds.hold == Hold.ZOH else tau, tau_closed)
    return InversionResult(
        t=t,
        y_d=trajectory.derivative(np.clip(t, trajectory.t0, trajectory.tf), 0),
        y=sampled["y"],
        ydot=sampled["ydot"],
        yddot=sampled["yddot"],
        X=X,
        tau=tau,
        theta_d=fed["theta_d"] if link else None,
        thetadot_d=fed["thetadot_d"] if link else None,
        summary=summary,
        model=model,
        trajectory=trajectory,
        modal=plan.modal,
        settings=member.settings,
        signals=signals,
        case=case,
        detail=MemberDetail(segments=redef.segments, figures=figures, checks=checks, redefinition=redef, tail=member.tail),
        acceptance=judged.acceptance,
    )


def _redefined(redef: Redefinition, tail: SettleTail | None, t: FloatArray) -> dict[str, Any]:
    """``y~``, its derivatives and ``X_I`` at increasing times ``t``: the closed form through ``t_f``, the tail after."""
    tf = float(redef.plan.bounds[-1])
    inside = t <= tf
    values = redef.sample(t[inside])
    if tail is None or np.all(inside):
        return values
    after = tail.values(t[~inside])
    return {name: np.concatenate([np.asarray(v), np.asarray(after[name], dtype=np.asarray(v).dtype)]) for name, v in values.items()}


def _summary(
    model: Model | LinearSystem, trajectory: Trajectory, judged: Judged, t: FloatArray, sampled: dict[str, Any], X: FloatArray,
    tau: FloatArray, rate: float, solver: str, tol: float, initial_internal_state: ArrayLike | None, search: dict[str, Any] | None,
    zeros: str, tau_points: FloatArray, tau_closed: FloatArray,
) -> InversionSummary | SystemInversionSummary:
    """The summary of a judged member: the member's figures, its checks, what reaches the link."""
    member, acceptance, signals, bounds = judged.member, judged.acceptance, judged.signals, judged.bounds
    redef, figures, checks = member.redefinition, member.figures, member.checks
    assert redef is not None and figures is not None and checks is not None
    plan = redef.plan
    jumps = redef.joint_jumps()
    settings = member.settings
    XI0 = np.zeros(redef.form.n_internal) if initial_internal_state is None else np.asarray(initial_internal_state, dtype=float).reshape(-1)
    summary_figures = SummaryFigures.of(
        figures, member.max_error, plan.modal.n_unstable, max_torque_jump=jumps["torque"], max_output_jump=jumps["output"],
        max_constraint_residual=member.max_constraint_residual, max_condition_number=member.max_condition_number,
        amplification=member.amplification, max_spectral_radius=member.max_spectral_radius, r=plan.r,
        matched_exponentials=int(plan.matched.max(initial=0)),
    )
    settings_json = {**settings.to_dict(), "segments": [float(b) for b in plan.bounds], "rate": float(rate), "solver": solver,
                     "tol": float(tol), "initial_internal_state": XI0.tolist(), "period": bounds.period, "hold": str(bounds.hold)}
    top, checked_at_the_link = summary_keys(acceptance)
    verification = {**checks.as_dict(), "sampling": _sampling_record(signals, tau_closed, tau_points), **checked_at_the_link}
    segments = segment_summaries([(s.t_start, s.t_end, s.mu.tolist(), s.c.tolist(), s.residual, s.condition) for s in redef.segments])
    extra: dict[str, Any] = dict(top)
    if member.tail is not None:  # a post-actuation: the feedforward goes on after t_f
        extra.update(pre_actuation_time=0.0, post_actuation_time=member.tail.length)
    if search is not None:
        extra["auto"] = search
    if zeros != ZeroSet.ALL:
        extra["zero_dynamics"] = zero_dynamics_summary(redef.form, zeros, settings.eps)
    samples = {"t": t, "y": sampled["y"], "ydot": sampled["ydot"], "tau": tau, "X": X}
    return summarize(model, trajectory, summary_figures, samples, settings_json, verification=verification, segments=segments,
                     extra=extra)


def _sampling_record(signals: PiecewiseChebyshev, tau_closed: Any, tau: FloatArray) -> dict[str, Any]:
    """How the samples were formed: the series' pieces and how far the closed form summed in double is from them."""
    peak = float(np.abs(tau).max()) or 1.0
    return {"method": "piecewise Chebyshev series of the closed form, computed in extended precision",
            "pieces": signals.pieces, "degree": DEGREE, "largest_series_tail": signals.tail,
            "closed_form_in_double_difference": float(np.abs(np.asarray(tau_closed) - tau).max() / peak)}

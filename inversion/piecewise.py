"""Piece-wise causal inversion by output redefinition: the paper's method (its section 5, and beyond it).

:func:`ssef_inversion` picks a member of the family (the caller's settings, the paper's for its
own cases, or the automatic choice of :mod:`inversion.auto`), solves and verifies it
(:mod:`inversion.member`), and :func:`sample_member` samples the bounded, continuous, causal
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
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.model import Model
from modelgen.paper import PaperCase

from .chebyshev import DEGREE, PiecewiseChebyshev, member_signals
from .linear_system import LinearSystem
from .member import MemberResult, evaluate_member
from .options import End, ZeroSet
from .result import (
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
from .settings import DEFAULT_SETTINGS, InversionSettings, paper_case, paper_settings
from .ssef import Solver
from .system import NormalForm
from .trajectory import Trajectory
from .zero_dynamics import free_zeros, zero_dynamics_summary

__all__ = ["ssef_inversion", "sample_member", "resolve_settings", "sample_times", "InversionResult", "InversionSummary",
           "SystemInversionSummary", "SegmentSummary", "CSV_COLUMNS", "SYSTEM_CSV_COLUMNS"]

FloatArray = NDArray[np.float64]


def resolve_settings(
    case: PaperCase | None,
    explicit: Mapping[str, Any],
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
) -> InversionSettings:
    """The member a manual inversion uses: the paper's for its own cases, else the defaults, then the caller's.

    Parameters
    ----------
    case : PaperCase or None
        The paper's case of the inversion (:func:`inversion.settings.paper_case`).
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


def ssef_inversion(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    explicit: Mapping[str, Any],
    *,
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
    auto: bool | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    rate: float,
    initial_internal_state: ArrayLike | None = None,
    solver: Solver = "lu",
    tol: float,
    progress: Callable[[str], None] | None = None,
    zeros: str = "all",
) -> InversionResult:
    """The SSEF inversion of :func:`inversion.invert` (its arguments, validated there).

    ``explicit`` holds the member's values the caller gave (``segments``, ``h``, ``cdec``,
    ``joining``, ``eps``, ``end``). A member given, or the paper's for a paper case, is
    evaluated and verified; otherwise the family is searched (:func:`inversion.auto.choose`).

    Raises
    ------
    SettingsError
        For settings that do not fit the trajectory.
    InversionError
        When the member fails (with its figures), or no member passes the search.
    """
    if isinstance(model, LinearSystem):
        form = NormalForm.of_system(model)
    else:
        form = free_zeros(model, NormalForm.of_model(model), zeros)
    case = paper_case(model, trajectory)  # decided once; the result carries it
    if auto is None:
        # the paper's member ends free: with a rest end, a paper case is chosen like any other
        member_given = any(k != "end" for k in explicit) or settings is not None
        auto = not member_given and (case is None or explicit.get("end") == End.REST)
    search: dict[str, Any] | None = None
    if auto:
        from .errors import SettingsError

        if settings is not None:
            raise SettingsError("settings", settings, "no stored settings with auto=True (--auto searches the family itself)")
        from .auto import choose

        member, search = choose(form, trajectory, fixed=explicit, max_error=max_error, max_torque=max_torque,
                                initial_internal_state=initial_internal_state, solver=solver, tol=tol, progress=progress)
    else:
        chosen = resolve_settings(case, explicit, settings)
        chosen.boundaries(trajectory, form.rho)  # a user error: SettingsError, not a failed member
        member = evaluate_member(form, trajectory, chosen, initial_internal_state=initial_internal_state, solver=solver,
                                 tol=tol, max_error=max_error, max_torque=max_torque, verify=True, plant=True)
        if not member.ok:
            raise member.error("the automatic choice (auto=True, --auto) searches the family for a member that meets the bounds")
    return sample_member(model, trajectory, member, rate, solver, tol, initial_internal_state, search, zeros, case)


def sample_times(trajectory: Trajectory, rate: float) -> FloatArray:
    """``t0 + k / rate`` through ``tf`` (``tf`` itself appended when the grid misses it)."""
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    t = trajectory.t0 + np.arange(count) / rate
    if trajectory.tf - t[-1] > 1e-9 / rate:
        t = np.append(t, trajectory.tf)
    return np.asarray(t, dtype=float)


def sample_member(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    member: MemberResult,
    rate: float,
    solver: str,
    tol: float,
    initial_internal_state: ArrayLike | None,
    search: dict[str, Any] | None,
    zeros: str = "all",
    case: PaperCase | None = None,
) -> InversionResult:
    """Sample a verified member at ``rate`` and summarize it (:func:`inversion.result.summarize`)."""
    redef, figures, checks = member.redefinition, member.figures, member.checks
    assert redef is not None and figures is not None and checks is not None
    plan = redef.plan
    t = sample_times(trajectory, rate)
    sampled = redef.sample(t)
    X, tau_closed = inverse_input(model, redef.form, sampled)  # Eq. (12), one batch
    # the signals fed forward, from their well-conditioned re-expansion (inversion.chebyshev)
    link = not isinstance(model, LinearSystem)
    signals = member_signals(redef, link)
    fed = signals.evaluate(t)
    tau = fed[signals.names[0]]
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
                     "tol": float(tol), "initial_internal_state": XI0.tolist()}
    verification = {**checks.as_dict(), "sampling": _sampling_record(signals, tau_closed, tau)}
    segments = segment_summaries([(s.t_start, s.t_end, s.mu.tolist(), s.c.tolist(), s.residual, s.condition) for s in redef.segments])
    extra: dict[str, Any] = {}
    if search is not None:
        extra["auto"] = search
    if zeros != ZeroSet.ALL:
        extra["zero_dynamics"] = zero_dynamics_summary(redef.form, zeros, settings.eps)
    samples = {"t": t, "y": sampled["y"], "ydot": sampled["ydot"], "tau": tau, "X": X}
    summary = summarize(model, trajectory, summary_figures, samples, settings_json, verification=verification, segments=segments,
                        extra=extra)
    return InversionResult(
        t=t,
        y_d=trajectory.derivative(t, 0),
        y=sampled["y"],
        ydot=sampled["ydot"],
        yddot=sampled["yddot"],
        X=X,
        tau=tau,
        theta_d=fed["theta_d"] if link else None,
        thetadot_d=fed["thetadot_d"] if link else None,
        segments=redef.segments,
        summary=summary,
        model=model,
        trajectory=trajectory,
        modal=plan.modal,
        settings=settings,
        figures=figures,
        checks=checks,
        redefinition=redef,
        signals=signals,
        case=case,
    )


def _sampling_record(signals: PiecewiseChebyshev, tau_closed: Any, tau: FloatArray) -> dict[str, Any]:
    """How the samples were formed: the series' pieces and how far the closed form summed in double is from them."""
    peak = float(np.abs(tau).max()) or 1.0
    return {"method": "piecewise Chebyshev series of the closed form, computed in extended precision",
            "pieces": signals.pieces, "degree": DEGREE, "largest_series_tail": signals.tail,
            "closed_form_in_double_difference": float(np.abs(np.asarray(tau_closed) - tau).max() / peak)}

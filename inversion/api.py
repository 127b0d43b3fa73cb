"""The one entry point of every inversion method: :func:`invert`.

It validates what the caller gave, converts a generic system (:mod:`inversion.lti.linear_system`),
and hands the case to its method -- the paper's sums of stable exponentials
(:func:`inversion.family.piecewise.ssef_inversion`), the polynomial redefinition
(:func:`inversion.baselines.polynomial.polynomial_inversion`), stable inversion
(:func:`inversion.baselines.stable.stable_inversion`), the optimal-control feedforward
(:func:`inversion.baselines.ocp.ocp_inversion`) or input shaping (:func:`inversion.baselines.shaping.shaped_inversion`)
-- each returning an
:class:`~inversion.result.InversionResult`. Defaults come from :mod:`inversion.config`.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from numpy.typing import ArrayLike

from modelgen.model import Model

from .acceptance import Acceptance, Bounds, check_period, window_length
from .baselines.bounded_limit import BoundedLimit, bounded_limit
from .baselines.ocp import OBJECTIVES as OCP_OBJECTIVES
from .baselines.ocp import ocp_inversion
from .baselines.polynomial import polynomial_inversion
from .baselines.replan import replanned_inversion
from .chain.programme import MAX_WORK, work
from .baselines.shaping import shaped_inversion
from .baselines.stable import stable_inversion
from .config import DEFAULTS, default, held_period, tip_bound
from .errors import InversionError, SettingsError
from .family.piecewise import ssef_inversion
from .lti.causal_limit import CausalLimit, causal_limit
from .lti.linear_system import LinearSystem, as_linear_system
from .lti.system import normal_form
from .margin import margin_block
from .options import (
    SHARED_OPTIONS,
    End,
    FamilyOptions,
    Hold,
    Method,
    Objective,
    OcpOptions,
    PolynomialOptions,
    ReplanOptions,
    ShapingOptions,
    StableOptions,
    ZeroSet,
    checked,
    method_options,
    values,
)
from .result import InversionResult
from .settings import DEFAULT_SETTINGS, InversionSettings, decide_auto, describe, paper_case, paper_settings
from .signals.trajectory import PolynomialTrajectory, Trajectory
from .threads import one_thread

__all__ = ["invert", "beyond_limit", "check_bounds", "METHODS", "MAX_SAMPLES"]

#: Inversion methods: the paper's causal one (sums of stable exponentials), the polynomial
#: redefinition, the non-causal baseline.
METHODS = values(Method)
#: Largest number of samples one inversion may produce (:data:`inversion.config.DEFAULTS`).
MAX_SAMPLES = DEFAULTS.max_samples
#: With the joint PD closed (``controller="pd"``): the optimal-control programme solved at most this many times, its tubes
#: tightened each time by what the loop adds to the feedforward's error, plus this share of the bound a time, to at most
#: ``_LOOP_MOST`` of the bound kept free.
_LOOP_TRIES, _LOOP_INSIDE, _LOOP_MOST = 3, 0.02, 0.5


def invert(
    model: Model | LinearSystem | Any,
    trajectory: Trajectory,
    segments: int | Sequence[float] | None = None,
    h: int | None = None,
    cdec: tuple[float, float] | None = None,
    joining: str | None = None,
    *,
    end: str | None = None,
    edges: str | None = None,
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
    auto: bool | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    max_torque_rate: float | None = None,
    rate: float | None = None,
    eps: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: str | None = None,
    tol: float | None = None,
    progress: Callable[[str], None] | None = None,
    method: str | None = None,
    zeros: str = "all",
    objective: str | None = None,
    period: float | None = None,
    hold: str | None = None,
    window: float | None = None,
    preview: float | None = None,
    margin: float | None = None,
    controller: str | None = None,
    gains: tuple[float, float] | None = None,
    uncertainty: Any = None,
) -> InversionResult:
    """Causal inverse torque of the linear model for a tip trajectory.

    Parameters
    ----------
    model : Model, or any SISO linear system
        A loaded model (:func:`modelgen.load`); its compiled ``inverse_torque`` gives Eq. (12).
        Or a generic system: a python-control :class:`~control.StateSpace` or
        :class:`~control.TransferFunction`, a :class:`scipy.signal.lti` system, a tuple
        ``(A, B, C)`` or a
        :class:`~inversion.lti.linear_system.LinearSystem`, continuous-time, strictly proper; its
        normal form is computed numerically (:mod:`inversion.lti.linear_system`) and the result's
        ``u`` is its input. Any relative degree ``rho >= 1`` (detected); every method, from
        rest, all its zeros constrained.
    trajectory : Trajectory
        Desired tip trajectory on ``[t0, tf]``.
    segments : int or sequence of float, optional
        Number of equal segments, or their boundaries ``[t0, ..., tf]`` (Eq. (28)).
    h : int, optional
        Order of smooth joining, Eq. (30): ``yddot~`` and its first ``h`` derivatives join
        ``y_d``'s. For a generic system of relative degree ``rho`` it is ``y~^(rho)`` and its
        first ``h`` derivatives that are continuous (the input is ``h`` times continuously
        differentiable, as the link's torque).
    cdec : (float, float), optional
        ``(Cdec_f, Cdec_s)``, Eq. (35); ``0 < Cdec_f < Cdec_s <= 1``.
    joining : {"paper", "position", "anchored"}, optional
        The joining conditions (:mod:`inversion.family.ssef`): the paper's, plus position
        joining, plus the unstable state anchored at every joint.
    end : {"free", "rest", "settle"}, optional
        ``"free"`` (the paper's: the torque stops at ``t_f``), ``"rest"``: the last segment
        also ends on ``y_d(t_f)``, ``ydot_d(t_f)`` with zero deflections and rates, so that the
        torque ends at zero and the linear plant at rest (the paper's Remark 2), or
        ``"settle"`` (``anchored`` only): after ``t_f`` the output is held on ``y_d(t_f)`` while
        the internal modes decay (:mod:`inversion.family.settle`, a causal post-actuation). Default:
        free for a member given; the automatic choice tries all three.
    edges : {"match", "rest"}, optional
        How the redefined output meets ``y_d`` at ``t_0`` and ``t_f`` (:class:`~inversion.options.Edges`):
        ``"match"`` (the paper's) joins ``yddot_d`` and its first ``h`` derivatives; ``"rest"``
        joins ``yddot_d`` with those derivatives zero, so the torque leaves and reaches rest with
        zero slope even where the move's jerk jumps at its ends. Default: match for a member
        given; the automatic choice tries both where they differ.
    settings : InversionSettings, mapping or path, optional
        A member chosen before (``best.json`` of :func:`inversion.explore`); the arguments
        above override its values.
    auto : bool, optional
        Choose the member automatically (:func:`inversion.family.auto.choose`) by ``objective``
        among the members whose feedforward reaches the link within the bounds (error,
        torque, after the move, with more modes, held at ``period``). Default: automatic when
        nothing above is given and the case is not one of the paper's (whose member ends
        free: with another ``end`` a paper case is chosen automatically too) (a preset as
        shipped with its own trajectory keeps the paper's settings). Values given with
        ``auto=True`` fix those dimensions of the search.
    max_error : float, optional
        The bound on the tip (m): a member given is refused beyond it from ``y_d`` (the quality
        gate, default 5 % of the move; ``math.inf`` accepts anything); the automatic choice
        also keeps the tip within it after the move and with more modes (default 1 % of the
        move).
    max_torque : float, optional
        Largest accepted peak torque (N m); a result above it is refused (default: three times
        what a rigid body needs along ``y_d``; ``math.inf`` accepts any).
    max_torque_rate : float, optional
        Largest accepted change of the held table from one row to the next, the first row against
        the input before it (N m; default ten times the rigid body's largest change over one
        period along ``y_d``; ``math.inf`` accepts any): a step the drive and the unmodelled modes
        see (:mod:`inversion.acceptance`).
    objective : {"torque", "error"}, optional
        What the automatic choice minimises (default ``"torque"``): the peak torque within
        ``max_error``, or the error within the torque limit (:mod:`inversion.family.auto`).
    period : float, optional
        The controller's period (s; default ``1 / rate``): the held table the summary's
        ``sampled`` block judges, and with ``hold="zoh"`` the samples returned.
    hold : {"point", "zoh"}, optional
        ``"point"`` (default): samples at ``rate``, a controller holding each value for a
        period. ``"zoh"``: one sample a period, the torque the mean over the period it is held
        for (:func:`inversion.acceptance.held_table`: a held error of ``O(period^2)`` where the
        point value's is ``O(period)``).
    window : float, optional
        The after-end window (s; default 2 s, or five time constants of the slowest stable
        mode of the plant).
    rate : float, optional
        Sampling rate of the returned series (Hz; default :data:`inversion.config.DEFAULTS`).
    eps : float, optional
        Zeros with ``Re >= -eps`` are treated as unstable (default 0; purely imaginary
        ones always are).
    initial_internal_state : array_like, optional
        ``X_I(t0) = [delta; deltadot]`` (default: rest).
    solver : {"lu", "lstsq"}, optional
        Linear solver of the segment systems (the other one checks it; default ``"lu"``).
    tol : float, optional
        Largest accepted relative constraint residual of a segment system (default ``1e-8``).
    progress : callable, optional
        Receives one-line messages of the automatic choice.
    method : {None, "ssef", "polynomial", "stable", "ocp", "zv", "zvd", "replan"}
        ``None`` (default): the paper's member for the paper's case as shipped, or a member
        given (``settings``, ``segments``, ...); otherwise the automatic choice across methods
        -- the family first (its automatic choice), and only when none of its members passes,
        the re-planned output, then the optimal-control feedforward at the controller's period
        (``1 / rate`` or ``period``), each judged by the same acceptance; with ``preview``, stable inversion truncated
        to it competes too, and the least peak input of those that pass is returned. The
        summary's ``method`` names the result, ``auto["stages"]`` records what was tried and
        why each stage failed; a refusal quotes the causal limit.
        ``"ssef"``: the paper's causal inversion alone, a sum of stable exponential
        functions per segment. ``"replan"``: the move reshaped within ``max_error`` so that it is
        exactly and causally invertible (:func:`inversion.baselines.replan.replanned_inversion`: a
        linear programme over splines, the least peak input; relative degree 2, a piecewise
        polynomial move; ``end`` ``"settle"`` or ``"rest"``). ``"ocp"``: the optimal-control feedforward
        (:func:`inversion.baselines.ocp.ocp_inversion`: the least peak torque, or energy, that keeps the
        tip within ``max_error`` at every sample, on the model discretised at ``period``; the
        limit of any causal feedforward there). ``"polynomial"``: the same conditions met by a polynomial
        per segment (:func:`inversion.baselines.polynomial.polynomial_inversion`; ``segments``, ``h``
        and ``joining`` paper or position apply). ``"stable"``: the non-causal stable
        inversion baseline (:func:`inversion.baselines.stable.stable_inversion`: exact tracking,
        torque before ``t0``; no member settings apply). ``"zv"``, ``"zvd"``: input shaping
        (:func:`inversion.baselines.shaping.shaped_inversion`: the rigid joint reference shaped for the
        joint PD loop's ringing flexible modes, driven by that PD -- the paper's gains for its
        cases, else :func:`modelgen.joint_pd.rule_gains`, as the closed loop uses; it aims at
        the vibration after the move, not at the tip during it).
    margin : float, optional
        The fraction of the bound the table keeps free (:attr:`~inversion.config.Defaults.margin`, 0.1, when ``None``;
        in ``[0, 0.5]``): the automatic choice, the optimal-control and the re-planned methods aim within
        ``(1 - margin)`` of the bound, within half the room where the bounded causal limit leaves less, and at the bound
        where nothing else passes (:mod:`inversion.margin`). Every summary reports the margin it keeps
        (``summary["margin"]``: the held error, the window after the move and more modes against the bound, and the
        plant errors the table tolerates, its robustness radius). 0: the limit itself.
    controller : {None, "none", "pd"}, optional
        The loop the table is judged in: ``None`` or ``"none"`` (default), the feedforward alone; ``"pd"`` (a link), the
        joint PD of Eq. (40) closed around the plant as well (the paper's experiment, as ``sflm simulate`` runs it), the
        joint references held with the torque (:func:`inversion.acceptance.closed_loop`). Every candidate of every
        method must then hold the tip within the bound in both, during the move and through the window after it; the
        optimal-control stage tightens its tube by what the loop adds. ``summary["loop"]`` reports both.
    gains : (float, float), optional
        With ``controller="pd"``: ``(k_P, k_D)`` (default, or where one is ``None``: the paper's for its cases, else
        :func:`modelgen.joint_pd.rule_gains`, the gains ``sflm simulate`` uses).
    uncertainty : Uncertainty, optional
        A link's plant ranges (:func:`inversion.studies.robustness.parse_uncertainty` of a SPEC such as
        ``"link.flexural_rigidity=5%,payload.mass=1%"``): the optimal-control programme then holds the nominal plant and
        every corner of the ranges at once -- one table, each plant's tip within the tube during the move and through
        the window after it, the nominal plant at rest at a rest end (:func:`inversion.baselines.ocp.ocp_inversion`'s
        ``plants``);
        ``summary["ocp"]["plants"]`` has each corner's figures. The re-planned output's programme holds them too (its
        input's rows, a rest end; ``summary["replan"]["plants"]``). The family's members are judged on the nominal
        plant as before (``sflm invert --uncertainty`` reports every result on the corners in the PD loop; ``--objective
        robust`` searches the family for the least worst case).
    preview : float, optional
        Seconds of torque allowed before the move starts (pre-actuation): stable inversion,
        truncated to it (:func:`inversion.baselines.stable.stable_inversion`), with ``method="stable"``
        or in the automatic choice across methods. Default: none in the automatic choice, as
        long as the tails need with ``method="stable"``.
    zeros : {"all", "physical", "converged"}
        The unstable zeros the inversion constrains (:mod:`inversion.lti.zero_dynamics`): all
        (the default), all but the truncation artefacts, or only those converged to the
        continuum's; the others are left free (their particular solution, no continuity
        rows). The verification still drives the full model's plant, from its true initial
        state; the summary's ``zero_dynamics`` names the free zeros. SSEF only.

    Returns
    -------
    InversionResult
        Its ``summary`` holds ``max_redefinition_error`` (m), ``relative_redefinition_error``
        (of the move), ``peak_torque`` (N m) -- both from the closed form, whatever
        ``rate`` -- ``max_torque_jump``, ``max_constraint_residual``,
        ``max_condition_number``, ``verification`` (the checks of
        :mod:`inversion.family.verify`), ``zeros``, ``n_unstable``, ``r``, ``settings``, the
        segments' exponents and coefficients, and ``auto`` (the search) when chosen
        automatically.

    Raises
    ------
    SettingsError
        For settings out of range (named in the message with the accepted range).
    InversionError
        When the member fails: a segment system not solved to ``tol``, a torque that
        depends on the solver or on the precision, a plant that does not follow ``y~``,
        a redefinition beyond ``max_error`` or a torque beyond ``max_torque`` -- with its
        figures. Never a torque that is not what it claims.

    References
    ----------
    The paper, Eqs. (12), (14)-(17), (28)-(36); docs/method.md.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import invert, smoothstep
    >>> result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), segments=5, h=2, cdec=(1e-4, 1.0))
    >>> round(result.summary["max_redefinition_error"], 5)
    0.00573
    """
    rate = default("rate", rate)
    solver = default("solver", solver)
    tol = default("tol", tol)
    _validate_common(rate, solver, tol, max_error, max_torque)
    check_bounds(trajectory, max_torque_rate=max_torque_rate, period=period, hold=hold, window=window, objective=objective)
    if method is not None and method not in METHODS:
        raise SettingsError("method", method, "None (the automatic choice across methods) or " + " or ".join(repr(m) for m in METHODS))
    if preview is not None and (isinstance(preview, bool) or not isinstance(preview, (int, float)) or not 0 <= preview < math.inf):
        raise SettingsError("preview", preview, "a finite number >= 0 (s of torque allowed before the move starts)")
    if preview is not None and method not in (None, Method.STABLE):
        raise SettingsError("preview", preview, f"None with method={method!r} (pre-actuation is stable inversion's; "
                                                "method=None lets it compete with the causal methods)")
    if margin is not None and (isinstance(margin, bool) or not isinstance(margin, (int, float)) or not 0 <= margin <= 0.5):
        raise SettingsError("margin", margin, "a fraction of the bound in [0, 0.5] (the share of it the table keeps free)")
    if zeros not in values(ZeroSet):
        raise SettingsError("zeros", zeros, " or ".join(repr(z) for z in values(ZeroSet)))
    if not isinstance(model, Model):
        model = _generic(model, zeros, initial_internal_state)
        if method in (Method.SSEF, Method.POLYNOMIAL, Method.STABLE) and normal_form(model).n_internal == 0:
            raise SettingsError("system", model.name, "a system with zeros for method={!r}: without zeros it has no internal "
                                "dynamics, its exact inverse u = (y_d^(r) - C A^r x) / (C A^(r-1) B) is causal and bounded; "
                                "method='ocp' gives it held at a period".format(str(method)))
    if zeros != ZeroSet.ALL and method not in (None, Method.SSEF):
        raise SettingsError("zeros", zeros, f"'all' with method={method!r} (zeros are left free by the SSEF inversion only)")
    if zeros != ZeroSet.ALL and end == End.REST:
        raise SettingsError("zeros", zeros, "'all' with end='rest' (a rest end holds every internal mode at zero at t_f; "
                                           "a free mode ends on its particular solution)")
    case = paper_case(model, trajectory)  # decided once, here
    loop = _loop(model, controller, gains, case)
    corners = _corners(model, uncertainty)
    explicit = {k: v for k, v in (("segments", segments), ("h", h), ("cdec", cdec), ("joining", joining), ("eps", eps),
                                  ("end", end), ("edges", edges)) if v is not None}
    options = dict(settings=settings, auto=auto, max_error=max_error, max_torque=max_torque, max_torque_rate=max_torque_rate, rate=rate,
                   eps=eps, initial_internal_state=initial_internal_state, solver=solver, tol=tol, progress=progress, zeros=zeros,
                   objective=objective, period=period, hold=hold, window=window, end=end, segments=segments, h=h, cdec=cdec,
                   joining=joining, edges=edges, preview=preview, margin=float(default("margin", margin)), loop=loop, corners=corners)
    chosen = decide_auto(case, explicit, settings, auto)
    # across methods: anything but the paper's case as shipped or a member given, and wherever pre-actuation is allowed
    # (auto=True asks for the family's own automatic choice)
    across = method is None and auto is None and (chosen or preview is not None)
    method = None if across else Method.SSEF if method is None else method
    # the causal limit: no causal feedforward from rest holds the move closer (docs/method.md section 7); computed once,
    # with the shortest duration that meets the bound where it exceeds it
    bound = tip_bound(max_error, trajectory.move(), judged=across or bool(chosen) or method in (Method.OCP, Method.REPLAN))
    limit = causal_limit(model, trajectory, bound)
    if method is None:
        result = _across(model, trajectory, explicit, limit, case, options)
    else:
        result = _one(model, trajectory, method, explicit, limit, case, options, explain=True)
    if "margin" not in result.summary:
        aimed = (result.summary.get("ocp") or {}).get("aimed")
        result.summary["margin"] = margin_block(result, _judged_bound(result, bound), aimed=aimed,
                                                asked=options["margin"] if result.summary.get("method") in ("ocp", "replan") else None,
                                                gains=loop)
    if loop is not None:
        result.summary["loop"] = loop_block(result, loop, "given" if gains is not None else
                                            "the paper's" if case is not None else "the rule's (modelgen.joint_pd.rule_gains)")
    return result


def _corners(model: Model | LinearSystem, uncertainty: Any) -> tuple[list[str], list[tuple[Any, Any, Any]]] | None:
    """The corner plants of :func:`invert`'s ``uncertainty`` (their names and ``(A, B, C)``), or ``None``."""
    if uncertainty is None:
        return None
    if not callable(getattr(uncertainty, "corner_plants", None)):  # the studies' Uncertainty (a later room: duck-typed)
        raise SettingsError("uncertainty", uncertainty, "an Uncertainty, inversion.studies.robustness.parse_uncertainty('KEY=RANGE,...'), "
                            "e.g. of 'link.flexural_rigidity=5%,payload.mass=1%'")
    named = uncertainty.corner_plants(model)  # the corners (the samples are judged, not held)
    return [name for name, _ in named], [plant for _, plant in named]


def _loop(model: Model | LinearSystem, controller: Any, gains: Any, case: Any) -> tuple[float, float] | None:
    """The joint PD gains a table is judged with (:func:`invert`'s ``controller`` and ``gains``), or ``None``."""
    if controller not in (None, "none", "pd"):
        raise SettingsError("controller", controller, "None or 'none' (the feedforward alone) or 'pd' (the joint PD of Eq. (40) closed too)")
    if controller != "pd":
        if gains is not None:
            raise SettingsError("gains", gains, "None without controller='pd' (the gains are the joint PD's)")
        return None
    if not isinstance(model, Model):
        raise SettingsError("controller", controller, "None or 'none' for a generic system (it has no joint to close a PD around)")
    from modelgen.joint_pd import loop_gains

    if gains is None:
        return loop_gains(model, case)
    try:
        given = list(gains)
        if len(given) != 2:
            raise ValueError
        kp, kd = (float(d if g is None else g) for g, d in zip(given, loop_gains(model, case)))
    except (TypeError, ValueError):
        raise SettingsError("gains", gains, "(k_P, k_D), two finite numbers (None: the default's), k_P > 0 and k_D >= 0") from None
    if not (math.isfinite(kp) and math.isfinite(kd) and kp > 0 and kd >= 0):
        raise SettingsError("gains", gains, "(k_P, k_D), two finite numbers, k_P > 0 and k_D >= 0")
    return kp, kd


def loop_block(result: InversionResult, gains: tuple[float, float], source: str) -> dict[str, Any]:
    """The summary's ``loop`` block: the table judged with the feedforward alone and with the joint PD closed.

    Parameters
    ----------
    result : InversionResult
        A link's result judged in the loop (its ``sampled`` block).
    gains : (float, float)
        The joint PD's ``(k_P, k_D)``.
    source : str
        Where the gains come from, in words.
    """
    held = result.summary["sampled"]  # every method judges a link's table in the loop its bounds carry (Bounds.loop)
    return {"controller": "pd", "kp": float(gains[0]), "kd": float(gains[1]), "gains": source, "period": held.get("period"),
            "hold": held.get("hold"), "pd": {"during": float(held["loop_error"]), "after": float(held["loop_after"])},
            "feedforward": {"during": held.get("max_tip_error"), "after": held.get("after_end_excursion")},
            "bound": float(result.summary["max_error"])}


def _judged_bound(result: InversionResult, bound: float | None) -> float:
    """The bound a result's margin is measured against: the caller's (or the default's), else what it was judged with."""
    return float(bound) if bound is not None and math.isfinite(bound) else float(result.summary["max_error"])


def _one(model: Model | LinearSystem, trajectory: Trajectory, method: str, explicit: dict[str, Any], limit: CausalLimit,
         case: Any, options: dict[str, Any], explain: bool = False) -> InversionResult:
    """One method's result, judged on what reaches the link (:func:`invert`'s arguments, validated there; ``case``: the
    paper's case, or ``None``), or its refusal quoting the causal limit. ``explain``: where the optimal-control solvers
    return no table (unsolved, or proved infeasible at the programme's own margins), lead the refusal with the bounded
    causal limit when it rules every feedforward within the bounds out (the automatic choice computes that limit before
    its stage instead)."""
    if limit.exceeds and method != Method.STABLE:
        raise beyond_limit(limit)
    bounded = None
    if explain and method in (Method.OCP, Method.REPLAN):
        # cheap things first: the table these methods return is judged within the drive's bounds at the controller's
        # period; where no causal feedforward held there can meet the bound, neither can they (no solve)
        bounded = _bounded(model, trajectory, options, held_period(options["period"], options["rate"]), limit.bound,
                           options["progress"] or (lambda message: None))
        if bounded is not None and bounded.exceeds:
            raise _beyond_bounds(bounded, limit)
    try:
        with one_thread():  # skinny products and small solves: a BLAS pool would only spin
            result = _dispatch(model, trajectory, method, explicit, options, case=case)
        max_torque, max_torque_rate = options["max_torque"], options["max_torque_rate"]
        # what every method returns is judged by the same bounds, on what reaches the link (inversion.acceptance)
        judged = Bounds(max_error=float(result.summary["max_error"]), max_torque=max_torque, max_torque_rate=max_torque_rate,
                        extra_modes=DEFAULTS.extra_modes)
        acceptance = Acceptance.of_summary(result.summary)
        failure = acceptance.failure(judged)
        if failure is not None:
            exc = InversionError(f"{_described(result)}: {failure[1]}")
            exc.status = failure[0]  # type: ignore[attr-defined]
            raise exc
    except InversionError as exc:
        if explain and getattr(exc, "unsolved", False) and not limit.exceeds:
            if bounded is None:
                bounded = _bounded(model, trajectory, options, held_period(options["period"], options["rate"]), limit.bound,
                                   options["progress"] or (lambda message: None))
            if bounded is not None and bounded.exceeds:
                exc.args = (f"no causal feedforward within the bounds exists: {bounded.sentence()}, above the bound "
                            f"{bounded.bound:.4g}; {exc}" + ("" if limit.method == "none" else f"; {limit.sentence()}"),)
                exc.bounded_limit = bounded.as_dict()  # type: ignore[attr-defined]
        if limit.method != "none" and method != Method.STABLE and "no causal feedforward" not in str(exc):
            exc.args = (f"{exc}; {limit.sentence()}",)
        if getattr(exc, "causal_limit", None) is None:
            exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
        raise
    result.summary["method"] = str(result.summary.get("method", "ssef"))
    result.summary["causal_limit"] = limit.as_dict()
    result.summary["bounds"] = bounds_record(judged, acceptance)
    return result


def _across(model: Model | LinearSystem, trajectory: Trajectory, explicit: dict[str, Any], limit: CausalLimit, case: Any,
            options: dict[str, Any]) -> InversionResult:
    """The automatic choice across methods (:func:`invert` with ``method=None``): the family, then -- only when none of its
    members passes -- the re-planned output (:mod:`inversion.baselines.replan`), then -- only when that fails too -- the
    optimal-control feedforward at the controller's period; stable inversion truncated to ``preview`` competes when it
    is given. The least peak input of those that pass, with the record of every stage."""
    bound = limit.bound
    preview = options["preview"]
    if limit.exceeds and preview is None:
        raise beyond_limit(limit)
    # cheap things first: a move whose table no result can hold (one row a sample) is refused before any programme
    count = int(math.floor(trajectory.duration * options["rate"] + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise SettingsError("rate", options["rate"], f"at most {MAX_SAMPLES / trajectory.duration:.4g} Hz for this trajectory "
                            f"({MAX_SAMPLES} samples; its {trajectory.duration:g} s at this rate are {count})")
    say = options["progress"] or (lambda message: None)
    has_zeros = isinstance(model, Model) or normal_form(model).n_internal > 0
    stages: list[dict[str, Any]] = []
    baseline = {**options, "auto": None, "max_error": bound, "preview": None}

    def record(method: str, status: str, message: str, seconds: float, **more: Any) -> None:
        stages.append({"method": str(method), "name": _NAMES[method], "status": status, "message": message, "seconds": seconds,
                       **more})

    def attempt(method: str, given: dict[str, Any], why_not: str | None = None) -> InversionResult | None:
        if why_not is not None:
            record(method, "skipped", why_not, 0.0)
            return None
        start = time.perf_counter()
        try:
            result = _one(model, trajectory, method, explicit if method == Method.SSEF else {}, limit, case, given)
        except (InversionError, SettingsError) as exc:
            status = getattr(exc, "status", "too-large" if isinstance(exc, SettingsError) else "failed")
            record(method, status, str(exc), time.perf_counter() - start)
            say(f"{_NAMES[method]}: {status}")
            return None
        record(method, "passed", f"peak input {result.summary['peak_torque']:.4g}", time.perf_counter() - start,
               peak_torque=float(result.summary["peak_torque"]))
        return result

    beyond = f"beyond the causal limit ({limit.sentence()})" if limit.exceeds else None
    controller = held_period(options["period"], options["rate"])
    bounded = None
    if beyond is None and preview is None:
        # cheap things first: what any causal feedforward within the drive's bounds can reach (a chain programme, a
        # fraction of a second); beyond the bound, no method has a table to return, and none is searched
        bounded = _bounded(model, trajectory, options, controller, bound, say)
        if bounded is not None and bounded.exceeds:
            raise _beyond_bounds(bounded, limit)
    asked, room, kept, aim = _aim(float(options["margin"]), bound, bounded, say)
    aimed = {"max_error": aim, "margin": 0.0}
    baseline = {**baseline, **aimed}
    candidates = [attempt(Method.SSEF, {**options, **aimed, "preview": None}, beyond or (None if has_zeros else _NO_ZEROS))]
    if preview is not None:
        candidates.append(attempt(Method.STABLE, {**baseline, "end": None, "objective": None, "preview": preview},
                                  None if has_zeros else _NO_ZEROS))
    if not any(candidates):
        # the move reshaped within the bound and inverted exactly: near the optimal-control limit, in about a second
        replannable = None if normal_form(model).rho == 2 and isinstance(trajectory, PolynomialTrajectory) else (
            "it re-plans a piecewise polynomial move of a plant of relative degree 2")
        candidates.append(attempt(Method.REPLAN, {**baseline, "end": options["end"] if options["end"] in (End.REST, End.SETTLE) else None,
                                                  "objective": None}, beyond or (None if has_zeros else _NO_ZEROS) or replannable))
    if not any(candidates):
        rows = _ocp_rows(model, trajectory, controller, options)
        if beyond is None and bounded is None and preview is not None:  # with a preview the limit was not asked above
            bounded = _bounded(model, trajectory, options, controller, bound, say)
        say(f"neither a member of the family nor the re-planned output passes; the optimal-control feedforward at a "
            f"{1e3 * controller:.3g} ms period" + (f", its programme's rows {rows} periods apart" if rows > 1 else ""))
        ocp_objective = options["objective"] if options["objective"] in OCP_OBJECTIVES else None
        out_of_bounds = f"beyond the bounded causal limit ({bounded.sentence()})" if bounded is not None and bounded.exceeds else None
        # its own tube: `kept` of the bound free where its least peak stays within the torque bound, half that, or none
        result = attempt(Method.OCP, {**baseline, "max_error": bound, "margin": kept,
                                      "end": End.FREE if options["end"] == End.FREE else End.REST,
                                      "objective": ocp_objective, "period": controller, "ramp": rows if rows > 1 else None},
                         beyond or out_of_bounds)
        if rows > 1 and stages[-1]["status"] != "skipped":  # the table is the controller's, judged at its period
            stages[-1]["message"] += (f"; its programme's rows are {rows * controller:g} s apart ({rows} of the controller's "
                                      f"periods: every period would be more than one chain programme takes), the input linear "
                                      f"between them and held every {controller:g} s")
        candidates.append(result)
    passed = [c for c in candidates if c is not None]
    if not passed:
        raise _no_method(stages, limit, bounded)
    return _chosen(min(passed, key=lambda r: float(r.summary["peak_torque"])), stages, bounded, bound, asked, room, options["loop"])


def _chosen(best: InversionResult, stages: list[dict[str, Any]], bounded: BoundedLimit | None, bound: float, asked: float,
            room: float | None, gains: tuple[float, float] | None = None) -> InversionResult:
    """The automatic choice's result: its record of every stage, the caller's bound and the margin it keeps."""
    chosen = best.summary["method"]
    for stage in stages:
        stage["chosen"] = stage["method"] == chosen
    best.summary["auto"] = {**(best.summary.get("auto") or {}), "stages": stages,
                            **({} if bounded is None else {"bounded_limit": bounded.as_dict()})}
    judged_at = float(best.summary["max_error"])
    best.summary["max_error"] = bound  # the caller's bound; the table was judged within `judged_at`, inside it
    aimed = min(judged_at, float((best.summary.get("ocp") or {}).get("aimed", judged_at)))
    best.summary["margin"] = {**margin_block(best, bound, aimed=aimed, asked=asked, gains=gains), "room": room}
    return best


def _aim(asked: float, bound: float, bounded: BoundedLimit | None, say: Callable[[str], None]) -> tuple[float, float | None, float, float]:
    """The automatic choice's tube: margin by default.

    Every stage aims within ``(1 - margin)`` of the bound, within half the room the bounded causal limit leaves where it
    leaves less than twice that (docs/method.md, section 5j). Returns the margin asked, the room (``None``: not known), the
    margin kept and the tube."""
    room = None if bounded is None or not bound > 0 else max(0.0, 1.0 - float(bounded.error) / bound)
    kept = asked if room is None else min(asked, room / 2)
    aim = bound * (1 - kept)
    if kept > 0:
        say(f"aiming within {aim:.4g} ({100 * kept:.3g} % of the bound {bound:.4g} kept free)")
    return asked, room, kept, aim


def _beyond_bounds(bounded: BoundedLimit, limit: CausalLimit) -> InversionError:
    """The refusal of a move no causal feedforward within the bounds can follow (before any method is tried): the bounded
    causal limit, the shortest duration within the bounds, the causal limit, and what would change the verdict."""
    longer = bounded.duration_sentence()
    text = (f"no causal feedforward within the bounds exists: {bounded.sentence()}, above the bound {bounded.bound:.4g}"
            + (f"; {longer}" if longer else "") + f" ({limit.sentence()}); a larger max_error, max_torque or max_torque_rate, "
            "a longer move, or pre-actuation (preview=S seconds, or method='stable': torque before t0) may make one exist")
    exc = InversionError(text)
    exc.status = "bounded-limit"  # type: ignore[attr-defined]
    exc.stages = []  # type: ignore[attr-defined]
    exc.bounded_limit = bounded.as_dict()  # type: ignore[attr-defined]
    exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
    return exc


def _no_method(stages: list[dict[str, Any]], limit: CausalLimit, bounded: BoundedLimit | None) -> InversionError:
    """The automatic choice's refusal: the limits once (each method's own refusal quotes them too), the exact reason first
    where there is one -- the bounded causal limit beyond the bound -- then what each stage found."""
    tried = "; ".join(f"{st['name']}: {_without(st['message'], limit.sentence())}" for st in stages)
    if bounded is not None and bounded.exceeds:
        tried = tried.replace(f"beyond the bounded causal limit ({bounded.sentence()})", "beyond that limit")
        text = (f"no causal feedforward within the bounds exists: {bounded.sentence()}, above the bound {bounded.bound:.4g} ("
                f"{limit.sentence()}); what each method found: {tried}")
    else:
        unsolved = "" if bounded is None else (f" (the bounded causal limit does not rule one out: {bounded.sentence()}, within the "
                                               f"bound {bounded.bound:.4g}; a shorter period, other bounds or a longer move may help)")
        text = f"no causal method found a feedforward within the bounds{unsolved}: {tried}; {limit.sentence()}"
    exc = InversionError(text)
    exc.status = "no-method"  # type: ignore[attr-defined]
    exc.stages = stages  # type: ignore[attr-defined]
    exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
    exc.bounded_limit = None if bounded is None else bounded.as_dict()  # type: ignore[attr-defined]
    return exc


def _without(message: str, sentence: str) -> str:
    """A stage's refusal without the causal limit's sentence (quoted once at the end of the automatic choice's)."""
    return message.replace(f"; {sentence}", "").replace(sentence, "").rstrip("; ")


def _bounded(model: Model | LinearSystem, trajectory: Trajectory, options: dict[str, Any], period: float, bound: float | None,
             say: Callable[[str], None]) -> BoundedLimit | None:
    """The bounded causal limit at the controller's period and the judged bounds, or ``None`` where the programme is too
    large or not solved (the optimal-control feedforward is then tried all the same)."""
    if bound is None:  # no bound judged: nothing to rule out
        return None
    key = (period, bound, options["window"], options["max_torque"], options["max_torque_rate"])
    for kept_model, kept_trajectory, kept_key, kept in _BOUNDED:  # compare asks again for each method: computed once
        if kept_model is model and kept_trajectory is trajectory and kept_key == key:
            return kept
    say(f"the least error within the torque and rate bounds at {1e3 * period:.3g} ms (a chain programme)")
    try:
        found = bounded_limit(model, trajectory, Bounds(max_error=bound, period=period, hold="zoh", window=options["window"],
                                                        max_torque=options["max_torque"], max_torque_rate=options["max_torque_rate"]))
    except (InversionError, SettingsError) as exc:
        say(f"the bounded causal limit: not computed ({exc})")
        found = None
    _BOUNDED.insert(0, (model, trajectory, key, found))
    del _BOUNDED[4:]
    return found


#: The last bounded causal limits computed, with the model and move they are of (the same objects: compared by identity).
_BOUNDED: list[tuple[Any, Any, tuple[Any, ...], BoundedLimit | None]] = []


def _ocp_rows(model: Model | LinearSystem, trajectory: Trajectory, period: float, options: dict[str, Any]) -> int:
    """The optimal-control feedforward's rows in the automatic choice, in controller's periods: 1 (every period) where its
    chain programme fits one solve (:data:`inversion.chain.programme.MAX_WORK`), else the least whole number that does --
    the table then linear between the rows (the programme's ``ramp``)."""
    form = normal_form(model)
    span = trajectory.duration + window_length(form, options["window"])
    rows = 1
    while work(math.ceil(span / (rows * period)), form.n_states, True, 8 + 2 * (rows - 1)) > MAX_WORK and rows < _LONGEST_RAMP:
        rows += 1
    return rows


#: The most controller's periods between the optimal-control programme's rows in the automatic choice (beyond, the
#: programme's size refuses the stage with its figure).
_LONGEST_RAMP = 50


#: What each method is called in the automatic choice's record.
_NAMES = {"ssef": "the family", "ocp": "the optimal-control feedforward", "stable": "stable inversion",
          "replan": "the re-planned output",
          "polynomial": "the polynomial redefinition", "zv": "ZV input shaping", "zvd": "ZVD input shaping"}
_NO_ZEROS = ("a system without zeros has no internal dynamics: its exact inverse is causal, and the optimal-control "
             "feedforward gives it held at the period")


def bounds_record(bounds: Bounds, acceptance: Acceptance) -> dict[str, Any]:
    """The bounds a result was judged by, each with its rule (the summary's ``bounds`` block): the tip (during the move, after
    it, and with more modes), the peak torque and the change between the held rows."""
    held = acceptance.sampled
    rate, rate_rule = bounds.rate_limit(0.0 if held is None else held.rigid_torque_rate, acceptance.link)
    return {"max_error": bounds.max_error, "more_modes_error": bounds.truncation_factor * bounds.max_error,
            "more_modes_rule": f"{bounds.truncation_factor:g} x max_error",
            "max_torque": bounds.torque_limit(acceptance.rigid_torque), "max_torque_rule": bounds.torque_rule(acceptance.link),
            "max_torque_rate": rate, "max_torque_rate_rule": rate_rule}


def beyond_limit(limit: CausalLimit) -> InversionError:
    """The refusal of a move whose causal limit exceeds its bound.

    The refusal of a move whose causal limit exceeds its bound: the limit, the shortest duration that meets the bound,
    pre-actuation.

    Parameters
    ----------
    limit : CausalLimit
        The move's causal limit.
    """
    assert limit.bound is not None
    longer = ("" if limit.shortest_duration is None else
              f"; within {limit.bound:.4g} the same move needs at least {limit.shortest_duration:.4g} s (it lasts {limit.duration:g} s)")
    exc = InversionError(f"{limit.sentence()}: a bound of {limit.bound:.4g} ({100 * limit.bound / (limit.move or 1.0):.3g} % of the move) "
                         f"cannot be met{longer}, or with pre-actuation (preview=S seconds, or method='stable': torque before t0)")
    exc.status = "causal-limit"  # type: ignore[attr-defined]
    exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
    return exc


def _described(result: InversionResult) -> str:
    """What a result is, for a refusal: its method, or its member's settings."""
    method = result.summary.get("method", "ssef")
    if method == "ssef":
        return describe(result.settings)
    return _NAMES.get(str(method), str(method))


def _dispatch(model: Model | LinearSystem, trajectory: Trajectory, method: str, explicit: dict[str, Any], options: dict[str, Any],
              case: Any = None) -> InversionResult:
    """The method's own inversion (:func:`invert`'s arguments, validated there; ``case``: the paper's case it is, or
    ``None``), in the caller's one-thread BLAS context. The shared options (the bounds, the sampling, the progress display)
    go to every method; the rest build the method's options object (:func:`inversion.options.method_options`), which
    refuses an option the method does not take."""
    shared = {name: options[name] for name in SHARED_OPTIONS}
    own = {name: value for name, value in options.items() if name not in shared}
    if method != Method.SSEF:  # the segment systems' solver and tolerance are the family's (always resolved, never "given")
        own.pop("solver", None)
        own.pop("tol", None)
    if own.get("objective") == Objective.ENERGY and method != Method.OCP:
        raise SettingsError("objective", own["objective"], "'torque' or 'error' (the energy objective is the optimal-control method's)")
    if method not in (Method.OCP, Method.SSEF):
        own.pop("objective", None)  # the automatic choice's objective: nothing for a method without a choice to make
    chosen = method_options(method, own)
    max_error, rate, period, window, max_torque_rate = (shared[k] for k in ("max_error", "rate", "period", "window", "max_torque_rate"))

    loop, corners = shared["loop"], shared["corners"]

    def baseline_bounds() -> Bounds:
        return replace(_baseline_bounds(trajectory, max_error, rate, period, shared["hold"], window, max_torque_rate), loop=loop)

    if isinstance(chosen, StableOptions):
        return replace(stable_inversion(model, trajectory, rate, bounds=baseline_bounds(), preview=chosen.preview), case=case)
    if isinstance(chosen, OcpOptions):
        return replace(_ocp(model, trajectory, chosen, shared), case=case)
    if isinstance(chosen, ReplanOptions):
        bound = tip_bound(max_error, trajectory.move())
        judged = Bounds(max_error=bound, period=held_period(period, rate), hold=default("hold", shared["hold"]), window=window,
                        extra_modes=DEFAULTS.extra_modes, max_torque_rate=max_torque_rate, loop=loop)
        # the output re-planned within (1 - margin) of the bound, then within half that, then at the bound
        kept = float(default("margin", shared["margin"]))
        ladder = sorted({kept, kept / 2, 0.0}, reverse=True) if kept > 0 else [0.0]
        for share in ladder:
            try:
                result = replanned_inversion(model, trajectory, max_error=bound * (1 - share), rate=rate, end=chosen.end,
                                             bounds=replace(judged, max_error=bound * (1 - share)),
                                             plants=None if corners is None else corners[1],
                                             plant_names=None if corners is None else corners[0])
            except InversionError:
                if share == ladder[-1]:
                    raise
                continue
            if share == ladder[-1] or judged.torque_limit(float(result.summary["rigid_torque"])) >= float(result.summary["peak_torque"]):
                break
        result.summary["max_error"] = bound
        result.summary["settings"]["max_error"] = bound
        result.summary["margin"] = margin_block(result, bound, aimed=bound * (1 - share), asked=kept, gains=shared["loop"])
        return replace(result, case=case)
    if isinstance(chosen, ShapingOptions):
        # the paper's cases have their gains; the closed loop uses the same
        result = shaped_inversion(model, trajectory, method, rate=rate,
                                  gains=None if case is None else (float(case.kp.value), float(case.kd.value)), bounds=baseline_bounds())
        return replace(result, case=case)
    if isinstance(chosen, PolynomialOptions):
        base = paper_settings(case) if case is not None else DEFAULT_SETTINGS
        result = polynomial_inversion(model, trajectory, segments=base.segment_count if chosen.segments is None else chosen.segments,  # type: ignore[arg-type]
                                      h=base.h if chosen.h is None else chosen.h, joining=chosen.joining or "paper", rate=rate,
                                      max_error=max_error, acceptance_bounds=baseline_bounds())
        return replace(result, case=case)
    family: FamilyOptions = chosen
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise SettingsError("rate", rate, f"at most {MAX_SAMPLES / trajectory.duration:.4g} Hz for this trajectory ({MAX_SAMPLES} samples)")
    return ssef_inversion(model, trajectory, explicit, settings=family.settings, auto=family.auto, max_error=max_error,
                          max_torque=shared["max_torque"], max_torque_rate=max_torque_rate, objective=family.objective, rate=rate,
                          period=period, hold=shared["hold"], window=window, initial_internal_state=family.initial_internal_state,
                          solver=family.solver, tol=family.tol, progress=shared["progress"], zeros=family.zeros, case=case,  # type: ignore[arg-type]
                          loop=loop)


def _ocp(model: Model | LinearSystem, trajectory: Trajectory, chosen: OcpOptions, shared: dict[str, Any]) -> InversionResult:
    """The optimal-control method of :func:`_dispatch`: with the joint PD closed, solved again in tubes tightened by what
    the loop adds (at most ``_LOOP_TRIES`` times); with corner plants, all held by one table."""
    max_error, rate, period, window, max_torque_rate = (shared[k] for k in ("max_error", "rate", "period", "window", "max_torque_rate"))
    loop, corners = shared["loop"], shared["corners"]
    if chosen.objective is not None and chosen.objective not in OCP_OBJECTIVES:
        raise SettingsError("objective", chosen.objective, "'torque' or 'energy' for method='ocp'")
    step = held_period(period, rate)
    bound = tip_bound(max_error, trajectory.move())
    asked = float(default("margin", shared["margin"]))
    margins: list[float] | None = None
    for attempt in range(_LOOP_TRIES):
        result = ocp_inversion(model, trajectory, period=step, max_error=bound, objective=chosen.objective or "torque",
                               end=chosen.end or "rest", window=window,
                               progress=shared["progress"], ramp=chosen.ramp or 1,
                               bounds=Bounds(max_error=bound, period=step, hold="zoh", window=window, max_torque=shared["max_torque"],
                                             max_torque_rate=max_torque_rate, loop=loop),
                               margin=asked, smoothing=DEFAULTS.smoothing, margins=margins,
                               plants=None if corners is None else corners[1], plant_names=None if corners is None else corners[0])
        held = result.summary.get("sampled") or {}
        looped = max(float(held.get("loop_error", 0.0)), float(held.get("loop_after", 0.0)))
        if loop is None or looped <= bound or attempt == _LOOP_TRIES - 1:
            break
        # the loop drags the table off by what the feedforward alone does not show: the tubes tightened by that much,
        # from the margin asked for in the loop down to the least the loop can pass with
        drag = max(0.0, looped - float(held["max_tip_error"])) / bound + _LOOP_INSIDE * (attempt + 1)
        margins = sorted({min(asked + drag, _LOOP_MOST), min(asked / 2 + drag, _LOOP_MOST), min(drag, _LOOP_MOST)}, reverse=True)
        (shared["progress"] or (lambda message: None))(
            f"ocp: with the joint PD closed the tip is {looped / bound:.3f} of the bound; again within "
            + ", ".join(f"{100 * m:.3g} %" for m in margins) + " inside it")
    return result


def _baseline_bounds(trajectory: Trajectory, max_error: float | None, rate: float, period: float | None, hold: str | None,
                     window: float | None, max_torque_rate: float | None = None) -> Bounds:
    """What the baselines' acceptance is measured with: their quality gate, the period, hold and window asked for."""
    gate = tip_bound(max_error, trajectory.move(), judged=False)
    return Bounds(max_error=gate, period=held_period(period, rate), hold=default("hold", hold),
                  window=window, extra_modes=DEFAULTS.extra_modes, max_torque_rate=max_torque_rate)


def check_bounds(trajectory: Trajectory, *, max_error: Any = None, max_torque: Any = None, max_torque_rate: Any = None, rate: Any = None,
                 period: Any = None, hold: Any = None, window: Any = None, objective: Any = None) -> None:
    """Check the bounds and the sampling a result is judged with.

    As :func:`invert` checks them. :func:`inversion.studies.compare.compare` checks its options with it before running any method: a value every
    method would refuse is one refusal, not a table of failed rows.

    Parameters
    ----------
    trajectory : Trajectory
        The move (the period must fit it).
    max_error, max_torque, max_torque_rate, rate, period, hold, window, objective : optional
        As :func:`invert` takes them (``None``: the default).

    Raises
    ------
    SettingsError
        Naming the first value out of range and the accepted range.
    """
    if rate is not None or max_error is not None or max_torque is not None:
        _validate_common(default("rate", rate), default("solver", None), default("tol", None), max_error, max_torque)
    if max_torque_rate is not None and (isinstance(max_torque_rate, bool) or not isinstance(max_torque_rate, (int, float))
                                        or not max_torque_rate > 0):
        raise SettingsError("max_torque_rate", max_torque_rate, "a number > 0 (N m a row), inf to accept any")
    _validate_sampling(period, hold, window, objective)
    check_period(period, trajectory)


def _validate_sampling(period: Any, hold: Any, window: Any, objective: Any) -> None:
    """The sampling and acceptance options: a period and a window > 0 (s), a hold and an objective of their choices."""
    for name, value in (("period", period), ("window", window)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0):
            raise SettingsError(name, value, "a finite number > 0 (s)")
    if hold is not None:
        checked(Hold, "hold", hold)
    if objective is not None:
        checked(Objective, "objective", objective)


def _generic(system: Any, zeros: str, initial_internal_state: ArrayLike | None) -> LinearSystem:
    """A generic system as a :class:`LinearSystem` the core takes (refusing the options that are about a link)."""
    converted = as_linear_system(system)
    if zeros != ZeroSet.ALL:
        raise SettingsError("zeros", zeros, "'all' for a generic system (its zeros have no continuum to be judged against)")
    if initial_internal_state is not None:
        raise SettingsError("initial_internal_state", initial_internal_state, "None for a generic system: it starts from rest")
    return converted


def _validate_common(rate: Any, solver: Any, tol: Any, max_error: Any, max_torque: Any) -> None:
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
        raise SettingsError("rate", rate, "a finite number > 0 (Hz)")
    if solver not in ("lu", "lstsq"):
        raise SettingsError("solver", solver, "'lu' or 'lstsq'")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1:
        raise SettingsError("tol", tol, "a number in (0, 1)")
    if max_error is not None and (isinstance(max_error, bool) or not isinstance(max_error, (int, float)) or not max_error > 0):
        raise SettingsError("max_error", max_error, "a number > 0 (m), inf to accept any redefinition")
    if max_torque is not None and (
        isinstance(max_torque, bool) or not isinstance(max_torque, (int, float)) or not max_torque > 0 or math.isnan(max_torque)
    ):
        raise SettingsError("max_torque", max_torque, "a number > 0 (N m)")

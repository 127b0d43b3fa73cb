"""A method run on a problem and judged by what reaches the link: :func:`solve` (the door's work) and :func:`judged_run`.

Every method's result is judged by the same acceptance (:mod:`inversion.acceptance`) against the problem's bounds, or
refused with its figures and the causal limit (computed once, :mod:`inversion.lti.causal_limit`); the summary gains the
blocks every result carries: the ``bounds`` it was judged by, the ``causal_limit``, the ``margin`` it keeps (the share of
the bound free and the plant errors it tolerates, :mod:`inversion.methods.margin`) and, in the joint PD's loop, the
``loop``.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Callable

import numpy as np

from ..acceptance import Acceptance
from ..errors import InversionError, SettingsError
from ..lti.causal_limit import CausalLimit, causal_limit
from ..options import InversionMethod
from ..problem import Problem
from ..result import InversionResult
from ..threads import one_thread
from ..signals.trajectory import stretched
from .bounded_limit import BoundedLimit, bounded_at, bounded_limit, searchable
from .margin import margin_block

__all__ = ["solve", "check", "bending", "judged_run", "beyond_limit", "beyond_bounds", "bounds_record", "loop_block"]


def solve(problem: Problem, method: InversionMethod, say: Callable[[str], None]) -> InversionResult:
    """A method's result for a problem, judged where it is used.

    A method's result for a problem, judged where it is used (:func:`inversion.invert`'s work).

    The causal limit computed once (with the shortest duration that meets the bound where it exceeds it); the method run
    (or, for the automatic choice, its stages) and judged; the summary's ``margin`` and, in the loop, ``loop`` blocks.

    Parameters
    ----------
    problem : Problem
        What is asked.
    method : InversionMethod
        The method (an :class:`~inversion.methods.automatic.Automatic` runs its stages).
    say : callable
        The progress display.
    """
    # the whole door on one BLAS thread, not the methods' solves alone: the causal and bounded limits, the automatic
    # choice's stages and the margin's judgements are skinny products too (issue 60, item 10)
    with one_thread():
        return _solved(problem, method, say)


def _solved(problem: Problem, method: InversionMethod, say: Callable[[str], None]) -> InversionResult:
    """:func:`solve`'s work (module docstring of :mod:`inversion.api`)."""
    check(problem, method)
    choose = getattr(method, "choose", None)
    bound = problem.bound(judged=choose is not None or method.judged_at_bound(problem))
    limit = causal_limit(problem.system, problem.trajectory, bound)
    if choose is not None:
        result = choose(problem, limit, say)
    else:
        result = judged_run(problem, method, limit, say, explain=True)
    if "margin" not in result.summary:
        aimed = (result.summary.get("ocp") or {}).get("aimed")
        judged_bound = float(bound) if bound is not None and math.isfinite(bound) else float(result.summary["max_error"])
        result.summary["margin"] = margin_block(result, judged_bound, aimed=aimed, asked=problem.kept if method.plans else None,
                                                gains=problem.gains)
        if problem.margin is not None and not method.plans:
            _margin_held(result, method, float(problem.margin))
    if problem.gains is not None:
        result.summary["loop"] = loop_block(result, problem.gains, problem.gains_source, (problem.max_torque, problem.max_torque_rate))
    if problem.bounds.max_deflection is not None:
        _deflection_held(result, method, float(problem.bounds.max_deflection))
    return result


def _deflection_held(result: InversionResult, method: InversionMethod, bound: float) -> None:
    """The table bends the link within ``max_deflection`` at its rows (the summary's ``deflection`` block), or it is
    refused with the figure."""
    figures = bending(result)
    block = {"peak": figures["peak_deflection"], "relative": figures["relative_deflection"], "bound": bound}
    result.summary["deflection"] = block  # type: ignore[typeddict-unknown-key]
    if block["peak"] > bound * (1 + 1e-6):
        exc = InversionError(f"max_deflection: the {method.name} table bends the link {block['peak']:.4g} m at its output "
                             f"({100 * block['relative']:.3g} % of its distance from the hub), beyond the bound {bound:.4g} m; "
                             "method='ocp' plans its table within it, or a longer move or a larger max_deflection")
        exc.status = "deflection"  # type: ignore[attr-defined]
        raise exc


def _margin_held(result: InversionResult, method: InversionMethod, asked: float) -> None:
    """A margin asked of a method that does not plan its table (a given member, a shaper, a baseline): the table it
    returns keeps that share of the bound free at the rows, after the move and with more modes, or it is refused with
    its figures (issue 59, item 14: ``--margin`` with the paper's member was ignored without a word)."""
    block = result.summary["margin"]
    free = [block[key] for key in ("held", "after", "more_modes") if block.get(key) is not None]
    if free and min(free) < asked:
        raise InversionError(
            f"margin: the {method.name} table keeps {100 * min(free):.3g} % of the bound {block['bound']:.4g} m free at the "
            f"rows, after the move and with more modes (its tip within {100 * (1 - min(free)):.3g} % of it); {100 * asked:.3g} % "
            "was asked. This method does not plan its table: the automatic choice, method='ocp' or method='replan' keep a margin, "
            "or ask a smaller one")
    block["asked"] = asked


def check(problem: Problem, method: InversionMethod) -> None:
    """What the door refuses before any work.

    What the door refuses of a method and a problem before any work (each refusal names the key).

    Parameters
    ----------
    problem : Problem
        What is asked.
    method : InversionMethod
        The method.
    """
    if problem.bounds.max_deflection is not None and not problem.link:
        raise SettingsError("max_deflection", problem.bounds.max_deflection, "None for a system (a link's elastic deflection)")
    automatic = getattr(method, "choose", None) is not None
    if problem.preview is not None and not automatic and method.causal:
        raise SettingsError("preview", problem.preview, f"None with method={method.name!r} (pre-actuation is stable inversion's; "
                                                        "method=None lets it compete with the causal methods)")
    method.check_system(problem) if not automatic else getattr(method, "family").check_system(problem)
    if not automatic:
        method.check(problem)  # the method's own refusals, before the limits' programmes
    if (not problem.link and method.needs_zeros and not method.plans and not automatic and problem.form.n_internal == 0):
        raise SettingsError("system", problem.system.name, "a system with zeros for method={!r}: without zeros it has no internal "
                            "dynamics, its exact inverse u = (y_d^(r) - C A^r x) / (C A^(r-1) B) is causal and bounded; "
                            "method='ocp' gives it held at a period".format(method.name))


def loop_block(result: InversionResult, gains: tuple[float, float], source: str,
               drive: tuple[float | None, float | None] = (None, None)) -> dict[str, Any]:
    """The summary's loop block: alone and with the joint PD.

    The summary's ``loop`` block: the table judged with the feedforward alone and with the joint PD closed.

    Parameters
    ----------
    result : InversionResult
        A link's result judged in the loop (its ``sampled`` block).
    gains : (float, float)
        The joint PD's ``(k_P, k_D)``.
    source : str
        Where the gains come from, in words.
    drive : (float or None, float or None)
        The absolute torque bounds, the peak's and the change between rows' (given, or the link's ``[drive]``; ``None``:
        the rule's, relative to the move): where one is, what the motor delivers in the loop (the table and the PD's
        correction, ``peak_torque`` and ``torque_rate`` of the ``pd`` block) is held against them (``drive``: the
        absolute bounds, ``within_drive``: whether it holds them).
    """
    held = result.summary["sampled"]  # every method judges a link's table in the loop its criteria carry (Criteria.loop)
    pd: dict[str, Any] = {"during": float(held["loop_error"]), "after": float(held["loop_after"])}
    if held.get("loop_torque") is not None:  # a torque bound is the motor's: what the motor delivers in the loop, against it
        top, rate = drive
        pd.update(peak_torque=float(held["loop_torque"]), torque_rate=float(held["loop_torque_rate"]), drive=[top, rate],
                  within_drive=bool((top is None or held["loop_torque"] <= top * (1 + 1e-12))
                                    and (rate is None or held["loop_torque_rate"] <= rate * (1 + 1e-12))))
    return {"controller": "pd", "kp": float(gains[0]), "kd": float(gains[1]), "gains": source, "period": held.get("period"),
            "hold": held.get("hold"), "pd": pd,
            "feedforward": {"during": held.get("max_tip_error"), "after": held.get("after_end_excursion")},
            "bound": float(result.summary["max_error"])}


def bounds_record(bounds: Any, acceptance: Acceptance) -> dict[str, Any]:
    """The summary's bounds block: each bound with its rule.

    The bounds a result was judged by, each with its rule (the summary's ``bounds`` block): the tip (during the move,
    after it, and with more modes), the peak torque and the change between the held rows.

    Parameters
    ----------
    bounds : Criteria
        What it was judged by.
    acceptance : Acceptance
        Its figures.
    """
    held = acceptance.sampled
    rate, rate_rule = bounds.rate_limit(0.0 if held is None else held.rigid_torque_rate, acceptance.link)
    return {"max_error": bounds.max_error, "more_modes_error": bounds.truncation_factor * bounds.max_error,
            "more_modes_rule": f"{bounds.truncation_factor:g} x max_error",
            "max_torque": bounds.torque_limit(acceptance.rigid_torque), "max_torque_rule": bounds.torque_rule(acceptance.link),
            "max_torque_rate": rate, "max_torque_rate_rule": rate_rule}


def beyond_limit(limit: CausalLimit, problem: Problem | None = None) -> InversionError:
    """The refusal of a move beyond its causal limit.

    The refusal of a move whose causal limit exceeds its bound: the limit, the shortest duration that meets the bound,
    pre-actuation.

    Parameters
    ----------
    limit : CausalLimit
        The move's causal limit.
    problem : Problem, optional
        The problem: the shortest duration within its torque and rate bounds is quoted too (the causal limit's own lets
        the input be as large and as fast as it needs).
    """
    assert limit.bound is not None
    longer = ("" if limit.shortest_duration is None else
              f"; within {limit.bound:.4g} the same move needs at least {limit.shortest_duration:.4g} s (it lasts {limit.duration:g} s)")
    bounded = _bounded_duration(problem, limit) if problem is not None and limit.shortest_duration is not None else None
    if bounded:
        longer += f", and held at {1e3 * problem.period:.3g} ms within the torque and rate bounds, {bounded}"  # type: ignore[union-attr]
    exc = InversionError(f"{limit.sentence()}: a bound of {limit.bound:.4g} ({100 * limit.bound / (limit.move or 1.0):.3g} % of the move) "
                         f"cannot be met{longer}, or with pre-actuation (preview=S seconds, or method='stable': torque before t0)")
    exc.status = "causal-limit"  # type: ignore[attr-defined]
    exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
    return exc


def _bounded_duration(problem: Problem, limit: CausalLimit) -> str:
    """The shortest duration of the move within the problem's torque and rate bounds, as a refusal quotes it ("" where the
    programme is refused or no duration is found)."""
    assert limit.bound is not None  # (a refusal's limit has its bound)
    duration = max(limit.shortest_duration or 0.0, problem.trajectory.duration)
    criteria = problem.criteria(float(limit.bound), hold="zoh", loop=None)
    if not searchable(problem.form, duration, criteria):
        return ""  # (its one programme beyond what the search for a duration may spend: not solved for a refusal)
    try:
        bounded = bounded_limit(problem.system, stretched(problem.trajectory, duration), criteria, shortest=True)
    except (InversionError, SettingsError):
        return ""
    if bounded.shortest_duration is None:
        return ""
    return f"at least {bounded.shortest_duration:.4g} s"


def beyond_bounds(bounded: BoundedLimit, limit: CausalLimit) -> InversionError:
    """The refusal of a move beyond its bounded causal limit.

    The refusal of a move no causal feedforward within the bounds can follow (before any method is tried): the bounded
    causal limit, the shortest duration within the bounds, the causal limit, and what would change the verdict.

    Parameters
    ----------
    bounded : BoundedLimit
        The bounded causal limit, beyond the bound.
    limit : CausalLimit
        The causal limit.
    """
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


def judged_run(problem: Problem, method: InversionMethod, limit: CausalLimit, say: Callable[[str], None],
               explain: bool = False) -> InversionResult:
    """One method's result, judged on what reaches the link.

    One method's result, judged on what reaches the link, or its refusal quoting the causal limit.

    ``explain``: where a method that plans its table returns none (unsolved, or proved infeasible at its own margins),
    lead the refusal with the bounded causal limit when it rules every feedforward within the bounds out (the automatic
    choice computes that limit before its stages instead).

    Parameters
    ----------
    problem : Problem
        What the user asked.
    method : InversionMethod
        The method.
    limit : CausalLimit
        The move's causal limit (computed once by the door).
    say : callable
        The progress display.
    explain : bool
        Ask the bounded causal limit first, for a method that plans its table.
    """
    if limit.exceeds and method.causal:
        raise beyond_limit(limit, problem)
    bounded = None
    first = explain and method.plans and method.limit_first(problem)
    if first:
        # cheap things first: the table these methods return is judged within the drive's bounds at the controller's
        # period; where no causal feedforward held there can meet the bound, neither can they (no solve)
        bounded = bounded_at(problem, problem.period, limit.bound, say)
        if bounded is not None and bounded.exceeds:
            raise beyond_bounds(bounded, limit)
    try:
        with one_thread():  # skinny products and small solves: a BLAS pool would only spin
            result = method.solve(problem, say)
        if result.case is not problem.case:  # the paper's case it is (its gains close the loop), decided once by the problem
            result = replace(result, case=problem.case)
        acceptance = result.acceptance
        if acceptance is None:
            raise InversionError(f"{method.refusal_name(result)} returned no acceptance (inversion.acceptance.judge): a result is "
                                 "what reaches the link, or a failure")
        # what every method returns is judged by the same bounds, on what reaches the link (inversion.acceptance)
        judged = problem.criteria(float(result.summary["max_error"]))
        failure = acceptance.failure(judged)
        if failure is not None:
            exc = InversionError(f"{method.refusal_name(result)}: {failure[1]}")
            exc.status = failure[0]  # type: ignore[attr-defined]
            raise exc
    except InversionError as exc:
        if explain and getattr(exc, "unsolved", False) and not limit.exceeds:
            if bounded is None:
                bounded = bounded_at(problem, problem.period, limit.bound, say)
                if bounded is not None and bounded.exceeds and method.plans and not first:
                    raise beyond_bounds(bounded, limit) from None  # the refusal asking it first gives
            if bounded is not None and bounded.exceeds:
                exc.args = (f"no causal feedforward within the bounds exists: {bounded.sentence()}, above the bound "
                            f"{bounded.bound:.4g}; {exc}" + ("" if limit.method == "none" else f"; {limit.sentence()}"),)
                exc.bounded_limit = bounded.as_dict()  # type: ignore[attr-defined]
        if limit.method != "none" and method.causal and "no causal feedforward" not in str(exc):
            exc.args = (f"{exc}; {limit.sentence()}",)
        if getattr(exc, "causal_limit", None) is None:
            exc.causal_limit = limit.as_dict()  # type: ignore[attr-defined]
        raise
    result.summary["method"] = str(result.summary.get("method", "ssef"))
    result.summary["causal_limit"] = limit.as_dict()
    result.summary["bounds"] = bounds_record(judged, acceptance)
    return result


def bending(result: InversionResult) -> dict[str, float]:
    """A link's largest elastic deflection at its output on a table.

    Over the table's rows, on the linear model: ``y - x_out theta`` (m) and its share of ``x_out``: a move near the
    drive's limit bends the link, and the linear model assumes small deflections (``sflm simulate --plant
    nonlinear-large`` tells what the link does). Empty for a system.

    Parameters
    ----------
    result : InversionResult
        A link's result.
    """
    theta = getattr(result, "theta_d", None)
    if theta is None:
        return {}
    summary: Any = result.summary
    x_out = float(summary.get("output_at") or 1.0)
    peak = float(np.abs(np.asarray(result.y, dtype=float) - x_out * np.asarray(theta, dtype=float)).max())
    return {"peak_deflection": peak, "relative_deflection": peak / x_out}

"""The one door of every inversion method: :func:`invert`.

It takes one :class:`~inversion.problem.Problem` (the model, the move, the bounds every method shares, the controller's
sampling, the loop, the spread, the margin: validated when it is made) and a method -- an object of the registry
(:mod:`inversion.options`: the family, the polynomial redefinition, stable inversion, optimal control, ZV and ZVD
input shaping, the re-planned output, each in its own module) or its name --, computes the move's causal limit once,
runs the method and judges what it returns on what reaches the link (:func:`inversion.choice.judged_run`); without a
method, the automatic choice across methods (:class:`inversion.choice.Automatic`) or, for the paper's case as shipped,
the paper's member. The flat keywords of the last release (``max_error=``, ``segments=``, ...) still work, with a
:class:`DeprecationWarning` naming the new spelling.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, Callable, Mapping

from .choice import Automatic, beyond_limit, bounds_record, judged_run
from .config import DEFAULTS
from .errors import SettingsError
from .family.method import Family
from .lti.causal_limit import causal_limit
from .margin import margin_block
from .options import InversionMethod, ZeroSet, as_method, method_names
from .problem import Bounds, Loop, Problem, Sampling
from .result import InversionResult

__all__ = ["invert", "resolve", "from_keywords", "beyond_limit", "bounds_record", "loop_block", "check_bounds", "MAX_SAMPLES", "LEGACY"]

#: Largest number of samples one inversion may produce (:data:`inversion.config.DEFAULTS`).
MAX_SAMPLES = DEFAULTS.max_samples

#: The keywords of the last release's ``invert``, each with the new spelling (where it goes now).
LEGACY: dict[str, str] = {
    **{k: f"inversion.Bounds({k}=...)" for k in ("max_error", "max_torque", "max_torque_rate")},
    **{k: f"inversion.Sampling({k}=...)" for k in ("rate", "period", "hold", "window")},
    "controller": "inversion.Loop(controller=...)", "gains": "inversion.Loop(gains=...)",
    **{k: f"inversion.Problem(..., {k}=...)" for k in ("uncertainty", "margin", "preview")},
    **{k: f"method=inversion.Family({k}=...) (or the method's own class)" for k in (
        "segments", "h", "cdec", "joining", "end", "edges", "settings", "auto", "eps", "initial_internal_state", "solver", "tol",
        "zeros", "objective")},
}


def invert(problem: Problem | Any, trajectory: Any = None, method: InversionMethod | str | None = None, *,
           progress: Callable[[str], None] | None = None, **legacy: Any) -> InversionResult:
    """Causal inverse torque of a link (or input of a linear system) for a desired output, judged where it is used.

    Parameters
    ----------
    problem : Problem, or a model
        What is asked (:class:`~inversion.problem.Problem`: the model, the move, the :class:`~inversion.problem.Bounds`,
        the :class:`~inversion.problem.Sampling`, the :class:`~inversion.problem.Loop`, the spread, the margin, the
        preview). A model (a loaded :class:`modelgen.Model` or any SISO linear system) with ``trajectory`` is the problem
        of the defaults.
    trajectory : Trajectory, optional
        The desired output, with a model in place of a problem.
    method : InversionMethod or str, optional
        The method (an object of :mod:`inversion.options`'s registry, or its name for its default options:
        ``"ssef"``, ``"polynomial"``, ``"stable"``, ``"ocp"``, ``"zv"``, ``"zvd"``, ``"replan"``). ``None``: the paper's
        member for the paper's case as shipped, else the automatic choice across methods
        (:class:`~inversion.choice.Automatic`: the family first, the re-planned output where no member passes, the
        optimal-control feedforward last; stable inversion competes where ``problem.preview`` allows pre-actuation).
        ``summary["method"]`` names the result, ``summary["auto"]["stages"]`` what was tried.
    progress : callable, optional
        Receives one-line messages of the work.
    **legacy
        The last release's flat keywords (``max_error=``, ``period=``, ``segments=``, ...: :data:`LEGACY` gives each one's
        new spelling), accepted with a :class:`DeprecationWarning` for this release.

    Returns
    -------
    InversionResult
        The samples, the signals (the closed form as Chebyshev series), and the ``summary``: the method's figures, what
        reaches the link (``sampled``: the held table through the window, with more modes, in the loop), the ``bounds``
        it was judged by, the ``margin`` kept, the ``causal_limit``.

    Raises
    ------
    SettingsError
        For a value out of range (named, with the accepted range).
    InversionError
        When no result within the bounds is found, with its figures: the causal limit or the bounded causal limit where
        they rule every causal feedforward out, else what each method found. Never a torque that is not what it claims.

    References
    ----------
    The paper, Eqs. (12), (14)-(17), (28)-(36); docs/method.md.

    Examples
    --------
    >>> import modelgen, inversion
    >>> problem = inversion.Problem(modelgen.load("paper-sim"), inversion.smoothstep(1.57, 5.5, 5))
    >>> result = inversion.invert(problem, method=inversion.Family(segments=5, h=2, cdec=(1e-4, 1.0)))
    >>> round(result.summary["max_redefinition_error"], 5)
    0.00573
    """
    problem, method = _request(problem, trajectory, method, legacy)
    return resolve(problem, method, progress)


def resolve(problem: Problem, method: InversionMethod | str | None = None,
            progress: Callable[[str], None] | None = None) -> InversionResult:
    """:func:`invert` of a problem and a method (or ``None``, the default), the flat keywords already placed.

    Parameters
    ----------
    problem : Problem
        What is asked.
    method : InversionMethod, str or None
        The method, its name, or ``None``.
    progress : callable, optional
        The progress display.
    """
    if not isinstance(problem, Problem):
        raise SettingsError("problem", problem, "an inversion.Problem (or a model with its trajectory)")
    say = progress or (lambda message: None)
    chosen = _default_method(problem) if method is None else as_method(method)
    _check(problem, chosen)
    # the causal limit: no causal feedforward from rest holds the move closer (docs/method.md section 7); computed once,
    # with the shortest duration that meets the bound where it exceeds it
    across = isinstance(chosen, Automatic)
    judged = across or chosen.judged_at_bound(problem)
    bound = problem.bound(judged=judged)
    limit = causal_limit(problem.system, problem.trajectory, bound)
    if across:
        result = chosen.choose(problem, limit, say)  # type: ignore[union-attr]
    else:
        result = judged_run(problem, chosen, limit, say, explain=True)
    if "margin" not in result.summary:
        aimed = (result.summary.get("ocp") or {}).get("aimed")
        asked = getattr(chosen, "margin_asked", lambda p: None)(problem)
        judged_bound = float(bound) if bound is not None and math.isfinite(bound) else float(result.summary["max_error"])
        result.summary["margin"] = margin_block(result, judged_bound, aimed=aimed, asked=asked, gains=problem.gains)
    if problem.gains is not None:
        result.summary["loop"] = loop_block(result, problem.gains, problem.gains_source)
    return result


def _default_method(problem: Problem, family: Family | None = None) -> InversionMethod:
    """The method of ``method=None``: the family's member where one is given or the case is the paper's as shipped (its
    own member), else the automatic choice across methods (also wherever pre-actuation is allowed)."""
    family = family or Family()
    if family.auto is None and (family.chooses(problem) or problem.preview is not None):
        return Automatic(family=family)
    return family


def _check(problem: Problem, method: InversionMethod) -> None:
    """What the door refuses of a method and a problem before any work (each refusal names the key)."""
    if problem.preview is not None and not isinstance(method, Automatic) and method.causal:
        raise SettingsError("preview", problem.preview, f"None with method={method.name!r} (pre-actuation is stable inversion's; "
                                                        "method=None lets it compete with the causal methods)")
    family = method.family if isinstance(method, Automatic) else method
    if not problem.link:
        if isinstance(family, Family):
            family.check_system(problem)
        if method.needs_zeros and not method.plans and not isinstance(method, Automatic) and problem.form.n_internal == 0:
            raise SettingsError("system", problem.system.name, "a system with zeros for method={!r}: without zeros it has no internal "
                                "dynamics, its exact inverse u = (y_d^(r) - C A^r x) / (C A^(r-1) B) is causal and bounded; "
                                "method='ocp' gives it held at a period".format(method.name))


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
    held = result.summary["sampled"]  # every method judges a link's table in the loop its criteria carry (Criteria.loop)
    return {"controller": "pd", "kp": float(gains[0]), "kd": float(gains[1]), "gains": source, "period": held.get("period"),
            "hold": held.get("hold"), "pd": {"during": float(held["loop_error"]), "after": float(held["loop_after"])},
            "feedforward": {"during": held.get("max_tip_error"), "after": held.get("after_end_excursion")},
            "bound": float(result.summary["max_error"])}


def _request(problem: Any, trajectory: Any, method: Any, legacy: Mapping[str, Any]) -> tuple[Problem, InversionMethod | str | None]:
    """The problem and the method of :func:`invert`'s arguments (the flat keywords placed, with a warning)."""
    unknown = sorted(set(legacy) - set(LEGACY))
    if unknown:
        raise SettingsError(unknown[0], legacy[unknown[0]], "a keyword of inversion.invert: problem, trajectory, method, progress "
                                                            "(the bounds, the sampling and the loop go in the Problem, a method's "
                                                            "options in its object)")
    if isinstance(problem, Problem):
        if trajectory is not None:
            raise SettingsError("trajectory", trajectory, "None with a Problem (the problem holds its move)")
        if legacy:
            name = sorted(legacy)[0]
            raise SettingsError(name, legacy[name], f"None with a Problem: {LEGACY[name]}")
        return problem, method
    if trajectory is None:
        raise SettingsError("trajectory", None, "a desired output (inversion.smoothstep, ...) with a model, or an inversion.Problem")
    given = {k: v for k, v in legacy.items() if v is not None and not (k == "zeros" and v == ZeroSet.ALL)}
    if given:
        warnings.warn("inversion.invert's flat keywords are deprecated (they go with the next release): "
                      + "; ".join(f"{k}= -> {LEGACY[k]}" for k in sorted(given)), DeprecationWarning, stacklevel=3)
    return from_keywords(problem, trajectory, method, legacy)


def from_keywords(model: Any, trajectory: Any, method: Any, keywords: Mapping[str, Any]) -> tuple[Problem, InversionMethod | None]:
    """The problem and the method flat keywords describe: the last release's ``invert`` keywords, and the command line's
    flags, which map here (no warning).

    Parameters
    ----------
    model : Model or a linear system
        The model.
    trajectory : Trajectory
        The move.
    method : InversionMethod, str or None
        The method asked for.
    keywords : mapping
        ``max_error``, ``period``, ``segments``, ... (:data:`LEGACY`).
    """
    get = keywords.get
    zeros = get("zeros") or ZeroSet.ALL
    preview = get("preview")
    problem = Problem(model, trajectory,
                      bounds=Bounds(max_error=get("max_error"), max_torque=get("max_torque"), max_torque_rate=get("max_torque_rate")),
                      sampling=Sampling(rate=get("rate"), period=get("period"), hold=get("hold"), window=get("window")),
                      loop=Loop(controller=get("controller"), gains=get("gains")), uncertainty=get("uncertainty"),
                      margin=get("margin"), preview=preview)
    own = {k: keywords[k] for k in keywords if k in Family.__dataclass_fields__ and keywords[k] is not None}
    if isinstance(method, str) and method not in method_names():
        as_method(method)  # the refusal, naming the methods
    if method is not None and zeros != ZeroSet.ALL and (isinstance(method, InversionMethod) or method != Family.name):
        raise SettingsError("zeros", zeros, f"'all' with method={getattr(method, 'name', method)!r} (zeros are left free by the "
                                            "SSEF inversion only)")
    if method is None:
        family = Family(**own)
        return problem, _default_method(problem, family)
    if isinstance(method, InversionMethod):
        return problem, as_method(method, own)
    if method != Family.name:
        own.pop("solver", None)  # the segment systems' solver and tolerance are the family's
        own.pop("tol", None)
        if own.get("objective") == "energy" and method != "ocp":
            raise SettingsError("objective", own["objective"], "'torque' or 'error' (the energy objective is the optimal-control "
                                                               "method's)")
        if method != "ocp":
            own.pop("objective", None)  # the automatic choice's objective: nothing for a method without a choice to make
    return problem, as_method(method, own)


def check_bounds(trajectory: Any, **values: Any) -> None:
    """Check bounds and sampling as a :class:`~inversion.problem.Problem` checks them (this function's former home).

    Parameters
    ----------
    trajectory : Trajectory
        The move (the period must fit it).
    **values
        ``max_error``, ``max_torque``, ``max_torque_rate``, ``rate``, ``period``, ``hold``, ``window``, ``objective``.
    """
    from .options import Objective, checked
    from .problem import check_period

    Bounds(**{k: values.get(k) for k in ("max_error", "max_torque", "max_torque_rate")})
    check_period(Sampling(**{k: values.get(k) for k in ("rate", "period", "hold", "window")}).period, trajectory)
    if values.get("objective") is not None:
        checked(Objective, "objective", values["objective"])


def __getattr__(name: str) -> Any:
    """``METHODS``, the registered methods' names (:func:`inversion.options.method_names`: the registry is the only list)."""
    if name == "METHODS":
        return method_names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""The one door of every inversion method: :func:`invert`.

It takes one :class:`~inversion.problem.Problem` (the model, the move, the bounds every method shares, the controller's
sampling, the loop, the spread, the margin: validated when it is made) and a method -- an object of the registry
(:mod:`inversion.options`: the family, the polynomial redefinition, stable inversion, optimal control, ZV and ZVD
input shaping, the re-planned output, each in its own module) or its name --, and hands them to
:func:`inversion.methods.judged.solve`: the causal limit computed once, the method run and judged on what reaches the
link. Without a method, the automatic choice across methods (:class:`inversion.methods.automatic.Automatic`) or, for the
paper's case as shipped, the paper's member. The flat keywords of the last release (``max_error=``, ``segments=``, ...)
still work, with a :class:`DeprecationWarning` naming the new spelling (:data:`inversion.methods.keywords.LEGACY`).
"""

from __future__ import annotations

import warnings
from typing import Any, Callable, Mapping

from .errors import SettingsError
from .methods.judged import beyond_limit, bounds_record, loop_block, solve
from .methods.keywords import LEGACY, default_method, from_keywords
from .options import InversionMethod, ZeroSet, as_method, method_names
from .problem import MAX_SAMPLES, Bounds, Problem, Sampling, check_period
from .result import InversionResult

__all__ = ["invert", "resolve", "shortest", "from_keywords", "beyond_limit", "bounds_record", "loop_block", "check_bounds", "MAX_SAMPLES",
           "LEGACY"]


def invert(problem: Problem | Any, trajectory: Any = None, method: InversionMethod | str | None = None, *,
           progress: Callable[[str], None] | None = None, **legacy: Any) -> InversionResult:
    """Causal feedforward of a problem, judged where it is used.

    Causal inverse torque of a link (or input of a linear system) for a desired output, judged where it is used.

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
        (:class:`~inversion.methods.automatic.Automatic`: the family first, the re-planned output where no member
        passes, the optimal-control feedforward last; stable inversion competes where ``problem.preview`` allows
        pre-actuation). ``summary["method"]`` names the result, ``summary["auto"]["stages"]`` what was tried.
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
    """The door of a problem and a method, keywords already placed.

    :func:`invert` of a problem and a method (or ``None``: the default), the flat keywords already placed.

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
    return solve(problem, default_method(problem) if method is None else as_method(method), progress or (lambda message: None))


def shortest(problem: Problem, profile: Callable[[float], Any] | str | None = None, method: InversionMethod | str | None = None,
             progress: Callable[[str], None] | None = None) -> InversionResult:
    """The shortest move within the drive's bounds, and its table.

    Of a given profile (:func:`inversion.methods.shortest.shortest_move`) or of any (``profile="free"``:
    :func:`inversion.methods.fastest.fastest_move`).

    Parameters
    ----------
    problem : Problem
        What is asked: its move (the distance; its profile the default one), its absolute bounds.
    profile : callable, "free" or None
        ``profile(T)``, the move of duration ``T``; ``"free"``: the tip's path free too; ``None``: the problem's move
        stretched in time (:func:`inversion.signals.trajectory.stretched`).
    method : InversionMethod, str or None
        The method the table is asked of (default: optimal control).
    progress : callable, optional
        The progress display.
    """
    from .methods.fastest import fastest_move
    from .methods.shortest import shortest_move

    if not isinstance(problem, Problem):
        raise SettingsError("problem", problem, "an inversion.Problem (or a model with its trajectory)")
    if profile == "free":
        return fastest_move(problem, method=method, say=progress)
    if isinstance(profile, str) or not (profile is None or callable(profile)):
        raise SettingsError("profile", profile, "None (the problem's move stretched), a function of the duration, or 'free'")
    return shortest_move(problem, profile, method, progress)


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


def check_bounds(trajectory: Any, **values: Any) -> None:
    """Check bounds and sampling as a Problem checks them.

    Check bounds and sampling as a :class:`~inversion.problem.Problem` checks them (this function's former home).

    Parameters
    ----------
    trajectory : Trajectory
        The move (the period must fit it).
    **values
        ``max_error``, ``max_torque``, ``max_torque_rate``, ``rate``, ``period``, ``hold``, ``window``, ``objective``.
    """
    from .options import Objective, checked

    Bounds(**{k: values.get(k) for k in ("max_error", "max_torque", "max_torque_rate")})
    check_period(Sampling(**{k: values.get(k) for k in ("rate", "period", "hold", "window")}).period, trajectory)
    if values.get("objective") is not None:
        checked(Objective, "objective", values["objective"])


def __getattr__(name: str) -> Any:
    """``METHODS``, the registered methods' names (:func:`inversion.options.method_names`: the registry is the only list)."""
    if name == "METHODS":
        return method_names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

"""Flat keywords mapped onto the typed request: the last release's ``invert(model, trajectory, max_error=..., segments=...)``
and the command line's flags become a :class:`~inversion.problem.Problem` and a method object (:func:`from_keywords`).
Without a method, the default (:func:`default_method`): the paper's member for its case as shipped, or the automatic
choice.
"""

from __future__ import annotations

from typing import Any, Mapping

from ..errors import SettingsError
from ..family.method import Family
from ..options import InversionMethod, ZeroSet, as_method, method_named
from ..problem import Bounds, Loop, Problem, Sampling
from .automatic import Automatic

__all__ = ["from_keywords", "method_from_keywords", "default_method", "LEGACY"]

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


def default_method(problem: Problem, family: Family | None = None) -> InversionMethod:
    """The method of ``method=None``.

    The method of ``method=None``: the family's member where one is given or the case is the paper's as shipped (its
    own member), else the automatic choice across methods (also wherever pre-actuation is allowed).

    Parameters
    ----------
    problem : Problem
        What is asked.
    family : Family, optional
        The family's options given.
    """
    family = family or Family()
    if family.auto is None and (family.chooses(problem) or problem.preview is not None):
        return Automatic(family=family)
    return family


def from_keywords(model: Any, trajectory: Any, method: Any, keywords: Mapping[str, Any]) -> tuple[Problem, InversionMethod]:
    """The problem and the method flat keywords describe.

    The problem and the method flat keywords describe: the last release's ``invert`` keywords (no warning here).

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
    problem = Problem(model, trajectory,
                      bounds=Bounds(max_error=get("max_error"), max_torque=get("max_torque"), max_torque_rate=get("max_torque_rate")),
                      sampling=Sampling(rate=get("rate"), period=get("period"), hold=get("hold"), window=get("window")),
                      loop=Loop(controller=get("controller"), gains=get("gains")), uncertainty=get("uncertainty"),
                      margin=get("margin"), preview=get("preview"))
    return problem, method_from_keywords(problem, method, keywords)


def method_from_keywords(problem: Problem, method: Any, keywords: Mapping[str, Any]) -> InversionMethod:
    """The method a name and the family's flat options describe.

    The method a name (or object, or ``None``) and the family's flat options describe (the command line's member
    flags map here).

    The family's options reach another method where its class has a field of the same name (a rest ``end`` reaches the
    re-plan and optimal control); ``zeros``, ``solver``, ``tol`` and ``objective`` are the family's (and the objective
    optimal control's): given to a method without them, refused, or -- the segment systems' solver and tolerance, the
    automatic choice's objective -- left out.

    Parameters
    ----------
    problem : Problem
        What is asked.
    method : InversionMethod, str or None
        The method asked for.
    keywords : mapping
        The family's options (``segments``, ``h``, ``objective``, ...); others are ignored.
    """
    own = {k: keywords[k] for k in keywords if k in Family.__dataclass_fields__ and keywords[k] is not None}
    if method is None:
        return default_method(problem, Family(**own))
    if isinstance(method, InversionMethod):
        return as_method(method, own)
    kind = method_named(method)
    fields = set(getattr(kind, "__dataclass_fields__", {}))
    zeros = own.pop("zeros", ZeroSet.ALL)
    if zeros != ZeroSet.ALL and "zeros" not in fields:
        raise SettingsError("zeros", zeros, f"'all' with method={method!r} (zeros are left free by the SSEF inversion only)")
    if "zeros" in fields:
        own["zeros"] = zeros
    for name in ("solver", "tol"):  # the segment systems' solver and tolerance are the family's
        if name not in fields:
            own.pop(name, None)
    if "objective" in own and "objective" not in fields:
        if own["objective"] == "energy":
            raise SettingsError("objective", own["objective"], "'torque' or 'error' (the energy objective is the optimal-control "
                                                               "method's)")
        own.pop("objective")  # the automatic choice's objective: nothing for a method without a choice to make
    return kind.from_options(own)

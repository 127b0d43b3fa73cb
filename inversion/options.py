"""The named choices of an inversion, as string enumerations checked once, and each method's options as a frozen type.

Each choice is a :class:`enum.StrEnum`: its members are the strings users type
(``joining="anchored"``, ``--end rest``), compare and hash as those strings, and print as
them (in JSON and in ``repr``). :func:`checked` turns a user's value into a member, or raises
:class:`~inversion.errors.SettingsError` naming the setting and what it accepts.

>>> checked(Joining, "joining", "anchored") is Joining.ANCHORED
True
>>> checked(Joining, "joining", "glued")
Traceback (most recent call last):
...
modelgen.errors.SettingsError: joining = 'glued' is not accepted; expected one of paper, position, anchored

Each method takes its own options (:class:`FamilyOptions`, :class:`PolynomialOptions`, :class:`StableOptions`,
:class:`OcpOptions`, :class:`ShapingOptions`, as SymForce's ``CodegenConfig`` per backend) beside the ones every method
shares (the bounds, the sampling, the progress display); :func:`method_options` builds one from :func:`inversion.invert`'s
keywords, and an option its type has no field for is refused there, naming what the method takes:

>>> method_options("ocp", {"objective": "energy", "segments": None}).objective
'energy'
>>> method_options("stable", {"segments": 4})
Traceback (most recent call last):
...
modelgen.errors.SettingsError: segments = 4 is not accepted; expected nothing: stable inversion has no member to choose \
(it tracks y_d exactly): it takes preview only (and the bounds and sampling every method takes)
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from enum import StrEnum
from typing import Any, Mapping, TypeVar

from .errors import SettingsError

__all__ = ["Choice", "Joining", "Method", "End", "Edges", "Hold", "Objective", "ZeroSet", "Solver", "checked", "values",
           "FamilyOptions", "PolynomialOptions", "StableOptions", "OcpOptions", "ShapingOptions", "ReplanOptions", "MethodOptions",
           "SHARED_OPTIONS", "method_options"]


class Choice(StrEnum):
    """A string that knows its alternatives.

    A named choice: a string that knows its alternatives, shown as the string it is (``'anchored'``).
    """

    def __repr__(self) -> str:
        return repr(self.value)


class Joining(Choice):
    """The conditions that fix a segment's exponentials."""

    PAPER = "paper"
    POSITION = "position"
    ANCHORED = "anchored"


class Method(Choice):
    """How the feedforward is computed (:func:`inversion.invert`)."""

    SSEF = "ssef"
    POLYNOMIAL = "polynomial"
    STABLE = "stable"
    OCP = "ocp"
    ZV = "zv"
    ZVD = "zvd"
    REPLAN = "replan"


class End(Choice):
    """How the feedforward ends.

    How the feedforward ends: the paper's (free: the torque stops at ``t_f`` whatever the link does),
    at rest at ``t_f`` (its Remark 2), or held on ``y_d(t_f)`` while the internal modes settle
    (:mod:`inversion.family.settle`: a causal post-actuation).
    """

    FREE = "free"
    REST = "rest"
    SETTLE = "settle"


class Edges(Choice):
    """How the redefined output meets ``y_d`` at ``t_0`` and ``t_f``.

    How the redefined output meets ``y_d`` at ``t_0`` and ``t_f``: matching ``yddot_d`` and its first ``h`` derivatives
    there (the paper's joining), or matching ``yddot_d`` with those derivatives zero -- the output leaves and reaches rest
    as smoothly as ``h`` allows, so that a move whose jerk jumps at its ends (a quintic) does not make the torque change
    slope with it.
    """

    MATCH = "match"
    REST = "rest"


class Hold(Choice):
    """How a controller holds the feedforward's samples."""

    POINT = "point"
    ZOH = "zoh"


class Objective(Choice):
    """What a choice minimises.

    What a choice minimises: the peak torque within the error bound, the error within the torque limit (the
    automatic choice), or the input's energy (the optimal-control feedforward).
    """

    TORQUE = "torque"
    ERROR = "error"
    ENERGY = "energy"


class ZeroSet(Choice):
    """The unstable zeros the inversion constrains."""

    ALL = "all"
    PHYSICAL = "physical"
    CONVERGED = "converged"


class Solver(Choice):
    """Linear solvers of the segment systems.

    Linear solvers of the segment systems: LAPACK's LU, SVD least squares, Gaussian elimination in any precision.
    """

    LU = "lu"
    LSTSQ = "lstsq"
    GE = "ge"


E = TypeVar("E", bound=StrEnum)


def values(kind: type[StrEnum]) -> tuple[str, ...]:
    """The accepted strings of a choice, in order.

    Parameters
    ----------
    kind : type[StrEnum]
        A choice's enumeration.
    """
    return tuple(member.value for member in kind)


def checked(kind: type[E], name: str, value: Any, accepted: tuple[str, ...] | None = None) -> E:
    """``value`` as a member of ``kind``.

    Parameters
    ----------
    kind : StrEnum subclass
        The choice.
    name : str
        The setting's name, for the message.
    value : Any
        What the user gave.
    accepted : tuple of str, optional
        A subset of the members that this use accepts (default: all of them).

    Raises
    ------
    SettingsError
        If ``value`` is not one of the accepted strings.
    """
    allowed = values(kind) if accepted is None else accepted
    if isinstance(value, str) and value in allowed:
        return kind(value)
    raise SettingsError(name, value, "one of " + ", ".join(allowed))


#: The keywords of :func:`inversion.invert` every method takes: the bounds it is judged by, the sampling, the progress display.
SHARED_OPTIONS = ("max_error", "max_torque", "max_torque_rate", "rate", "period", "hold", "window", "progress", "margin", "loop", "corners")


@dataclass(frozen=True)
class FamilyOptions:
    """The paper's method's own options.

    The paper's method's own options (:func:`inversion.invert` documents each).

    Attributes
    ----------
    settings, auto, segments, h, cdec, joining, eps, end, edges, initial_internal_state, solver, tol, zeros, objective :
        The member given (``settings`` or its parts), whether it is chosen automatically, the zeros constrained, the
        segment systems' solver and tolerance, and what the automatic choice minimises.
    """

    settings: Any = None
    auto: bool | None = None
    segments: Any = None
    h: int | None = None
    cdec: Any = None
    joining: str | None = None
    eps: float | None = None
    end: str | None = None
    edges: str | None = None
    initial_internal_state: Any = None
    solver: str | None = None
    tol: float | None = None
    zeros: str = "all"
    objective: str | None = None


@dataclass(frozen=True)
class PolynomialOptions:
    """The polynomial redefinition's own options.

    The polynomial redefinition's own options: its segmentation, smoothness and joining.

    Attributes
    ----------
    segments, h, joining :
        As the family's (the paper's member's when not given).
    """

    segments: Any = None
    h: int | None = None
    joining: str | None = None


@dataclass(frozen=True)
class StableOptions:
    """Stable inversion's own option.

    Attributes
    ----------
    preview : float or None
        Seconds of torque allowed before the move (its pre-actuation truncated there; ``None``: as long as it needs).
    """

    preview: float | None = None


@dataclass(frozen=True)
class OcpOptions:
    """The optimal-control feedforward's own options.

    Attributes
    ----------
    objective : {"torque", "energy"} or None
        What it minimises (``"torque"`` when ``None``).
    end : {"rest", "free"} or None
        At rest after the move (``"rest"`` when ``None``) or free.
    ramp : int or None
        Periods per row of its programme, the input linear between the rows (the automatic choice's, for a long move:
        :func:`inversion.baselines.ocp.ocp_inversion`).
    """

    objective: str | None = None
    end: str | None = None
    ramp: int | None = None


@dataclass(frozen=True)
class ShapingOptions:
    """Input shaping takes no option of its own.

    Input shaping takes no option of its own (its impulses follow from the plant's first mode).
    """


@dataclass(frozen=True)
class ReplanOptions:
    """The re-planned output's own option.

    Its output is chosen by a linear programme within the bound (:mod:`inversion.baselines.replan`).

    Attributes
    ----------
    end : {"settle", "rest"} or None
        The internal modes settle after ``t_f`` (``"settle"`` when ``None``) or are at rest there.
    """

    end: str | None = None


MethodOptions = FamilyOptions | PolynomialOptions | StableOptions | OcpOptions | ShapingOptions | ReplanOptions

#: Each method's options type and what it is called in a refusal (with why it takes so little, where that is not plain).
_OPTIONS: dict[str, tuple[type[Any], str]] = {
    "ssef": (FamilyOptions, "the family"), "polynomial": (PolynomialOptions, "the polynomial redefinition"),
    "stable": (StableOptions, "stable inversion has no member to choose (it tracks y_d exactly):"),
    "ocp": (OcpOptions, "the optimal-control feedforward"),
    "zv": (ShapingOptions, "input shaping"), "zvd": (ShapingOptions, "input shaping"),
    "replan": (ReplanOptions, "the re-planned output"),
}


def method_options(method: str, given: Mapping[str, Any]) -> Any:
    """The options of ``method`` from ``invert``'s keywords.

    The options of ``method`` from :func:`inversion.invert`'s keywords; one its type has no field for is refused.

    Parameters
    ----------
    method : str
        A :class:`Method`.
    given : mapping
        Keywords other than :data:`SHARED_OPTIONS`; ``None`` (and ``auto=False``, ``zeros="all"``) is "not given".

    Returns
    -------
    FamilyOptions, PolynomialOptions, StableOptions, OcpOptions, ShapingOptions or ReplanOptions
        The method's options.

    Raises
    ------
    SettingsError
        For the first option given that the method does not take, naming what it takes.
    """
    kind, label = _OPTIONS[str(checked(Method, "method", method))]
    accepted = [f.name for f in fields(kind)]
    unset = {"auto": False, "zeros": "all"}
    for name, value in given.items():
        if name not in accepted and value is not None and not (name in unset and value == unset[name]):
            takes = ", ".join(accepted) if accepted else "no option of its own"
            raise SettingsError(name, value, f"nothing: {label} {'it ' if label.endswith(':') else ''}takes {takes} only (and "
                                             "the bounds and sampling every method takes)")
    return kind(**{name: value for name, value in given.items() if name in accepted and value is not None})

"""The named choices of an inversion, as string enumerations checked once.

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
"""

from __future__ import annotations

from enum import StrEnum
from typing import Any, TypeVar

from .errors import SettingsError

__all__ = ["Choice", "Joining", "Method", "End", "Edges", "Hold", "Objective", "ZeroSet", "Solver", "checked", "values"]


class Choice(StrEnum):
    """A named choice: a string that knows its alternatives, shown as the string it is (``'anchored'``)."""

    def __repr__(self) -> str:
        return repr(self.value)


class Joining(Choice):
    """The conditions that fix a segment's exponentials (:mod:`inversion.family.ssef`)."""

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


class End(Choice):
    """How the feedforward ends: the paper's (free: the torque stops at ``t_f`` whatever the link does),
    at rest at ``t_f`` (its Remark 2), or held on ``y_d(t_f)`` while the internal modes settle
    (:mod:`inversion.family.settle`: a causal post-actuation)."""

    FREE = "free"
    REST = "rest"
    SETTLE = "settle"


class Edges(Choice):
    """How the redefined output meets ``y_d`` at ``t_0`` and ``t_f``: matching ``yddot_d`` and its first ``h`` derivatives
    there (the paper's joining), or matching ``yddot_d`` with those derivatives zero -- the output leaves and reaches rest
    as smoothly as ``h`` allows, so that a move whose jerk jumps at its ends (a quintic) does not make the torque change
    slope with it."""

    MATCH = "match"
    REST = "rest"


class Hold(Choice):
    """How a controller at a period holds the feedforward's samples (:func:`inversion.acceptance.held_table`)."""

    POINT = "point"
    ZOH = "zoh"


class Objective(Choice):
    """What a choice minimises: the peak torque within the error bound, the error within the torque limit (the
    automatic choice), or the input's energy (the optimal-control feedforward)."""

    TORQUE = "torque"
    ERROR = "error"
    ENERGY = "energy"


class ZeroSet(Choice):
    """The unstable zeros the inversion constrains (:mod:`inversion.lti.zero_dynamics`)."""

    ALL = "all"
    PHYSICAL = "physical"
    CONVERGED = "converged"


class Solver(Choice):
    """Linear solvers of the segment systems: LAPACK's LU, SVD least squares, Gaussian elimination in any precision."""

    LU = "lu"
    LSTSQ = "lstsq"
    GE = "ge"


E = TypeVar("E", bound=StrEnum)


def values(kind: type[StrEnum]) -> tuple[str, ...]:
    """The accepted strings of a choice, in order."""
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

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

Each method is an object (:class:`InversionMethod`, as pysindy's optimisers and SymForce's per-backend
``CodegenConfig``): its options are the fields of its class, which lives in the method's own module and is registered
once (:func:`register`). :func:`registered` is the only list of methods: the automatic choice's order, ``compare``'s
rows, the command line's ``--method`` choices, the summaries, the plots and the C export read it. A method's name is
shorthand for its object with default options (:func:`as_method`); an option its class has no field for is refused,
naming what the method takes:

>>> import inversion  # the built-in methods registered
>>> as_method("ocp", {"objective": "energy", "segments": None}).objective
'energy'
>>> as_method("stable", {"segments": 4})
Traceback (most recent call last):
...
modelgen.errors.SettingsError: segments = 4 is not accepted; expected nothing: stable inversion takes no option of its \
own (and the bounds and sampling every method takes, in the Problem)
"""

from __future__ import annotations

import warnings
from dataclasses import fields, is_dataclass
from enum import StrEnum
from typing import Any, Callable, ClassVar, Mapping, TypeVar

from .errors import SettingsError

__all__ = ["Choice", "Joining", "End", "Edges", "Hold", "Objective", "ZeroSet", "Solver", "checked", "values",
           "InversionMethod", "register", "unregister", "registered", "method_names", "method_named", "as_method", "method_options"]


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


class InversionMethod:
    """A method of inversion: its options and what is its own.

    A method of inversion: its options (the fields of a frozen dataclass subclass) and what is its own.

    A subclass lives in its method's module and is made known by :func:`register`; the door (:func:`inversion.invert`)
    hands it the :class:`~inversion.problem.Problem` -- the model, the move, the bounds every method shares, the
    controller's sampling, the loop -- and judges what it returns by the same acceptance as every other method. What a
    subclass says of itself:

    * ``name`` (the string users type: ``--method NAME``), ``label`` (in a sentence: "the optimal-control feedforward"),
      ``title`` (a figure's: "optimal-control feedforward (held)"), ``rank`` (its place in the lists: the command line's
      choices, ``compare``'s rows);
    * ``stage``: its place in the automatic choice across methods (``None``: not tried there; methods of one stage compete,
      a later stage runs only where no method of the earlier ones passed); ``needs_zeros``: whether it has nothing to do
      for a system without zeros;
    * ``plans``: whether it plans its table within the bounds (optimal control, the re-plan): held to the tip bound, the
      bounded causal limit asked before it runs (:meth:`limit_first`); else a result the caller fixed is held to the
      looser quality gate;
    * ``least_peak``: whether it plans its table for the least peak input (optimal control): the automatic choice asks it
      too where an earlier stage's table needs more than :attr:`inversion.config.Defaults.torque_tolerance` above the
      least peak any causal table can have;
    * ``causal``: ``False`` for a method that acts before the move (stable inversion): the causal limit does not refuse it;
    * :meth:`solve` (the method's own work), :meth:`check` (what it refuses before any work), :meth:`variants` (its rows
      in ``compare``), :meth:`settings_text` (its settings in a sentence: ``compare``'s column), :meth:`c_text` (the C
      header's), :meth:`report` (the first lines of ``sflm invert``'s text), :meth:`for_automatic` (how it runs as a
      stage of the automatic choice).
    """

    name: ClassVar[str] = ""
    label: ClassVar[str] = ""
    title: ClassVar[str] = "feedforward"
    rank: ClassVar[float] = 100.0
    stage: ClassVar[float | None] = None
    needs_zeros: ClassVar[bool] = True
    plans: ClassVar[bool] = False
    causal: ClassVar[bool] = True
    least_peak: ClassVar[bool] = False
    #: whether its figures draw its output as the redefined one (a redefinition) or as the model's
    redefines: ClassVar[bool] = False
    #: what it is, in the command line's help (``--method NAME: help``)
    help: ClassVar[str] = ""
    #: how its signals are made, as the exported C's header says it
    series_text: ClassVar[str] = "its closed form re-expanded"

    def solve(self, problem: Any, say: Callable[[str], None]) -> Any:
        """The method's result for a problem, or its refusal.

        The method's result for ``problem`` (an :class:`~inversion.result.InversionResult` whose ``acceptance`` the door
        judges), or an :class:`~inversion.errors.InversionError` with its figures.

        Parameters
        ----------
        problem : Problem
            What the user asked (validated when it was made).
        say : callable
            The progress display (one line at a time).
        """
        raise NotImplementedError(f"{type(self).__name__}.solve")

    def check(self, problem: Any) -> None:
        """Refuse what this method cannot do for a problem.

        Refuse, before any work, what this method cannot do for ``problem`` (:class:`~inversion.errors.SettingsError`).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """

    def check_system(self, problem: Any) -> None:
        """Refuse options this method cannot apply to the system.

        Refuse, before any work, options this method cannot apply to the problem's system (a generic system's).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """

    def judged_at_bound(self, problem: Any) -> bool:
        """Whether its result is held to the tip bound.

        Whether its result is held to the tip bound (else to the quality gate of a result the caller fixed).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return self.plans

    def limit_first(self, problem: Any) -> bool:
        """Whether the bounded causal limit is asked before it runs.

        Whether a method that plans (:attr:`plans`) has the bounded causal limit asked before it runs (a refusal at once,
        with the figure, where no table within the bounds exists); ``False`` where its own programme is a fraction of the
        limit's (the limit is then asked where it fails: the same refusal).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return self.plans

    def refusal_name(self, result: Any) -> str:
        """What a result of it is called in a refusal.

        What a result of it is called when it is refused (its label; a member's settings).

        Parameters
        ----------
        result : InversionResult
            The refused result.
        """
        return self.label or self.name

    def takes_part(self, problem: Any) -> bool:
        """Whether it is a stage of the automatic choice.

        Whether it is a stage of the automatic choice for ``problem`` (``False``: absent from its record).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return True

    def prepare(self, problem: Any, stop: Callable[[], bool]) -> None:
        """Work ahead of the automatic choice's stages.

        What its stage will do that depends on neither the tube nor the bounded causal limit, done while that limit is
        computed on another thread (the automatic choice's first stage), kept where the stage finds it
        (:func:`inversion.family.auto.shared_members`), until ``stop()``. Nothing by default; never a refusal (the stage
        refuses).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        stop : callable
            Asked between pieces of the work: ``True`` once the limit is known.
        """

    def for_automatic(self, stage: Any) -> tuple["InversionMethod", Any] | str:
        """How it runs as a stage of the automatic choice.

        How it runs as a stage of the automatic choice across methods: ``(method, problem)``, or a reason to skip it
        (recorded).

        Parameters
        ----------
        stage : inversion.methods.automatic.Stage
            The choice's figures so far: the problem, the family's options, the tube aimed at, the bounded causal limit.
        """
        return self, stage.aimed()

    def compared(self, problem: Any, run: Callable[[Any, "InversionMethod"], Any]) -> tuple[Any, str]:
        """Its row of compare: its result and a note.

        Its row of ``compare``: the result of ``run(problem, self)`` (the door) and a note.

        Parameters
        ----------
        problem : Problem
            The comparison's problem.
        run : callable
            ``run(problem, method)``: the door (:func:`inversion.api.resolve`).
        """
        return run(problem, self), ""

    def variants(self) -> list[tuple[str, "InversionMethod"]]:
        """compare's rows of this method.

        ``compare``'s rows of this method: ``(row name, the method as run there)``."""
        return [(self.name, self)]

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """The result's settings in a sentence.

        The result's settings in a sentence (``compare``'s ``settings`` column, the exported C's header).

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary.get("settings") or {}
        return f"method {self.name}: " + ", ".join(f"{k} {v}" for k, v in settings.items() if isinstance(v, (int, float, str)))

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """What the exported C's header says of the result.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        return self.settings_text(summary)

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of sflm invert's text of its result.

        The first lines of ``sflm invert``'s text of a result of this method (what reaches the link follows them).

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        return [f"{summary.get('model', '?')}: {self.label or self.name} ({self.settings_text(summary)})",
                f"  {'trajectory':<19s} {summary.get('trajectory', '?')}",
                f"  {'max |y - y_d|':<19s} {summary.get('max_redefinition_error', float('nan')):.4g} "
                f"(accepted {summary.get('max_error', float('nan')):.3g})",
                f"  {'peak input':<19s} {summary.get('peak_torque', float('nan')):.5g}"]

    @classmethod
    def from_options(cls, given: Mapping[str, Any]) -> "InversionMethod":
        """The method with ``given`` options (flat keywords; ``None`` and a field's own default are "not given").

        Parameters
        ----------
        given : mapping
            Option names and values.

        Raises
        ------
        SettingsError
            For the first option given that the method does not take, naming what it takes.
        """
        # (a field marked internal is the automatic choice's to set, not an option: OptimalControl.tube_floor)
        accepted: list[str] = [f.name for f in fields(cls) if not f.metadata.get("internal")] if is_dataclass(cls) else []
        defaults: dict[str, Any] = {f.name: f.default for f in fields(cls)} if is_dataclass(cls) else {}
        for name, value in given.items():
            if name not in accepted and value is not None and not _unset(name, value):
                takes = (", ".join(accepted) + " only") if accepted else "no option of its own"
                raise SettingsError(name, value, f"nothing: {cls.label or cls.name} takes {takes} (and the bounds and sampling "
                                                 "every method takes, in the Problem)")
        return cls(**{name: value for name, value in given.items()
                      if name in accepted and value is not None and not (name in defaults and defaults[name] is value)})


def _unset(name: str, value: Any) -> bool:
    """The values that mean "not given" for an option a method does not take (the old keywords' defaults)."""
    return (name, value) in (("auto", False), ("zeros", "all"))


#: The registered methods by name (:func:`register`): the only list.
_REGISTRY: dict[str, type[InversionMethod]] = {}


def register(method: type[InversionMethod]) -> type[InversionMethod]:
    """Make a method known by its ``name`` (a class decorator).

    Parameters
    ----------
    method : type
        A subclass of :class:`InversionMethod` with a ``name``.

    Returns
    -------
    type
        ``method`` (so that it decorates its class).

    Raises
    ------
    ValueError
        For a class without a name, or a name another class holds.
    """
    name = getattr(method, "name", "")
    if not isinstance(name, str) or not name or not name.replace("-", "").replace("_", "").isalnum():
        raise ValueError(f"{method.__name__}: a method needs a name of letters, digits, '-' and '_'")
    held = _REGISTRY.get(name)
    if held is not None and held.__qualname__ != method.__qualname__:
        raise ValueError(f"{method.__name__}: the name {name!r} is {held.__qualname__}'s")
    _REGISTRY[name] = method
    return method


def unregister(name: str) -> None:
    """Forget the method ``name`` (a test's own, once it is done).

    Parameters
    ----------
    name : str
        A registered method's name.
    """
    _REGISTRY.pop(name, None)


def registered() -> tuple[type[InversionMethod], ...]:
    """The registered methods in their order (``rank``, then name)."""
    return tuple(sorted(_REGISTRY.values(), key=lambda m: (m.rank, m.name)))


def method_names() -> tuple[str, ...]:
    """The registered methods' names in their order.

    The registered methods' names in their order (the command line's ``--method`` choices)."""
    return tuple(m.name for m in registered())


def method_named(name: Any) -> type[InversionMethod]:
    """The registered method called ``name``.

    Parameters
    ----------
    name : str
        A method's name.

    Raises
    ------
    SettingsError
        For a name no method holds, naming those that are.
    """
    if isinstance(name, str) and name in _REGISTRY:
        return _REGISTRY[name]
    raise SettingsError("method", name, "None (the automatic choice across methods) or " + " or ".join(repr(m) for m in method_names()))


def as_method(method: Any, given: Mapping[str, Any] | None = None) -> InversionMethod:
    """A method object from a name, a class or an object.

    A method object from a name, a class or an object (a name is shorthand for its class with ``given`` options).

    Parameters
    ----------
    method : str, type or InversionMethod
        What the caller gave.
    given : mapping, optional
        Options (flat keywords) for a name or a class.

    Raises
    ------
    SettingsError
        For an unknown name, or an option the method does not take.
    """
    if isinstance(method, InversionMethod):
        if given and any(v is not None and not _unset(k, v) for k, v in given.items()):
            raise SettingsError(next(k for k, v in given.items() if v is not None and not _unset(k, v)), "given twice",
                                f"the options of {method.name} in its object ({type(method).__name__}(...)) only")
        return method
    kind = method if isinstance(method, type) and issubclass(method, InversionMethod) else method_named(method)
    return kind.from_options(given or {})


def method_options(method: str, given: Mapping[str, Any]) -> InversionMethod:
    """The options of a method from flat keywords (as_method).

    The options of ``method`` from flat keywords: :func:`as_method` (its former name).

    Parameters
    ----------
    method : str
        A method's name.
    given : mapping
        Its options.
    """
    return as_method(method, given)


#: The options classes of the last release, by the name of the method whose class replaces each (a DeprecationWarning).
_FORMER = {"FamilyOptions": "ssef", "PolynomialOptions": "polynomial", "StableOptions": "stable", "OcpOptions": "ocp",
           "ShapingOptions": "zv", "ReplanOptions": "replan"}


def __getattr__(name: str) -> Any:
    """The former options classes (``FamilyOptions`` ...): the method classes that replace them, with a warning."""
    if name in _FORMER:
        kind = method_named(_FORMER[name])
        warnings.warn(f"inversion.options.{name} is {kind.__module__}.{kind.__name__} now (the method object carries its "
                      "options); the old name goes with the next release", DeprecationWarning, stacklevel=2)
        return kind
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

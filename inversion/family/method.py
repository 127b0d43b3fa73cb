"""The paper's method as an object: :class:`Family`, a member of the family of sums of stable exponentials or its
automatic choice, with its options.

>>> import modelgen, inversion
>>> problem = inversion.Problem(modelgen.load("paper-sim"), inversion.smoothstep(1.57, 5.5, 5))
>>> result = inversion.invert(problem, method=inversion.Family(segments=5, h=2, cdec=(1e-4, 1.0)))
>>> round(result.summary["max_redefinition_error"], 5)
0.00573
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Mapping

from ..config import DEFAULTS, default
from ..errors import InversionError, SettingsError
from ..options import End, InversionMethod, Objective, Solver, ZeroSet, checked, register, values
from ..problem import Problem
from ..result import InversionResult, report_row, summary_words
from ..settings import InversionSettings, decide_auto, describe
from .piecewise import family_form, ssef_inversion

__all__ = ["Family", "member_text"]

#: The member's own options (the rest are how it is solved and chosen).
MEMBER_KEYS = ("segments", "h", "cdec", "joining", "eps", "end", "edges")


@register
@dataclass(frozen=True)
class Family(InversionMethod):
    """The paper's inversion by output redefinition.

    The paper's piece-wise causal inversion by output redefinition (Eqs. (12), (28)-(36)).

    A member given (``settings`` or its parts), the paper's for its cases as shipped, or the automatic choice of a member
    within the problem's bounds (``auto``; :mod:`inversion.family.auto`). ``None`` is "not given".

    Attributes
    ----------
    segments : int or sequence of float, optional
        Number of equal segments, or their boundaries ``[t0, ..., tf]`` (Eq. (28)).
    h : int, optional
        Order of smooth joining, Eq. (30).
    cdec : (float, float), optional
        ``(Cdec_f, Cdec_s)``, Eq. (35); ``0 < Cdec_f < Cdec_s <= 1``.
    joining : {"paper", "position", "anchored"}, optional
        The joining conditions (:mod:`inversion.family.ssef`).
    eps : float, optional
        Zeros with ``Re >= -eps`` are treated as unstable (default 0).
    end : {"free", "rest", "settle"}, optional
        How the feedforward ends (:class:`~inversion.options.End`).
    edges : {"match", "rest"}, optional
        How the redefined output meets ``y_d`` at ``t_0`` and ``t_f`` (:class:`~inversion.options.Edges`).
    settings : InversionSettings, mapping or path, optional
        A member chosen before (``best.json`` of :func:`inversion.explore`, or a ``summary.json``); the values above
        override it.
    auto : bool, optional
        Choose the member automatically (default: when no member is given and the case is not the paper's as shipped).
    objective : {"torque", "error"}, optional
        What the automatic choice minimises: the peak torque within the tip bound (default) or the error within the
        torque bound.
    zeros : {"all", "physical", "converged"}
        The unstable zeros constrained (:mod:`inversion.lti.zero_dynamics`; a link's only).
    initial_internal_state : array_like, optional
        ``X_I(t0) = [delta; deltadot]`` (default: rest; a link's only).
    solver : {"lu", "lstsq"}, optional
        The segment systems' linear solver (the other one checks it; default ``"lu"``).
    tol : float, optional
        Largest accepted relative constraint residual of a segment system (default ``1e-8``).
    """

    name = "ssef"
    label = "the family"
    title = "causal feedforward"
    rank = 0.0
    redefines = True
    help = "the paper's causal inversion alone"
    stage = 0.0

    segments: Any = None
    h: int | None = None
    cdec: Any = None
    joining: str | None = None
    eps: float | None = None
    end: str | None = None
    edges: str | None = None
    settings: Any = None
    auto: bool | None = None
    objective: str | None = None
    zeros: str = "all"
    initial_internal_state: Any = None
    solver: str | None = None
    tol: float | None = None

    def __post_init__(self) -> None:
        if self.solver is not None and self.solver not in (Solver.LU, Solver.LSTSQ):
            raise SettingsError("solver", self.solver, "'lu' or 'lstsq'")
        for key, value in self.explicit.items():  # each value as invert checks it, for every command before any work
            InversionSettings(**{key: value})     # (issue 59, item 4: compare wrote rows of failures with exit 0)
        tol = self.tol
        if tol is not None and (isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1):
            raise SettingsError("tol", tol, "a number in (0, 1)")
        if self.objective is not None:
            checked(Objective, "objective", self.objective)
        if self.zeros not in values(ZeroSet):
            raise SettingsError("zeros", self.zeros, " or ".join(repr(z) for z in values(ZeroSet)))
        if self.zeros != ZeroSet.ALL and self.end == End.REST:
            raise SettingsError("zeros", self.zeros, "'all' with end='rest' (a rest end holds every internal mode at zero at t_f; "
                                                     "a free mode ends on its particular solution)")

    @property
    def explicit(self) -> dict[str, Any]:
        """The member's values given (``segments``, ``h``, ``cdec``, ``joining``, ``eps``, ``end``, ``edges``)."""
        return {k: getattr(self, k) for k in MEMBER_KEYS if getattr(self, k) is not None}

    def chooses(self, problem: Problem) -> bool:
        """Whether the member is chosen automatically.

        Whether the member is chosen automatically for ``problem`` (:func:`inversion.settings.decide_auto`).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return decide_auto(problem.case, self.explicit, self.settings, self.auto)

    def judged_at_bound(self, problem: Problem) -> bool:
        """A chosen member at the tip bound, a fixed one at the gate.

        A member chosen within the bounds is held to the tip bound; one the caller fixed to the quality gate.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return self.chooses(problem)

    def refusal_name(self, result: InversionResult) -> str:
        """What a member is called in a refusal: its settings.

        What a member is, for a refusal: its settings (:func:`inversion.settings.describe`).

        Parameters
        ----------
        result : InversionResult
            A member's result.
        """
        return describe(result.settings)

    def check_system(self, problem: Problem) -> None:
        """A generic system: from rest, every zero constrained.

        A generic system starts from rest with every zero constrained (its zeros have no continuum to be judged against).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        if not problem.link:
            if self.zeros != ZeroSet.ALL:
                raise SettingsError("zeros", self.zeros, "'all' for a generic system (its zeros have no continuum to be judged "
                                                         "against)")
            if self.initial_internal_state is not None:
                raise SettingsError("initial_internal_state", self.initial_internal_state, "None for a generic system: it "
                                                                                           "starts from rest")

    def check(self, problem: Problem) -> None:
        """Refuse what the family cannot do for the problem.

        The system's options (:meth:`check_system`), an objective of the family's, a move within the sample limit.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        self.check_system(problem)
        if self.objective == Objective.ENERGY:
            raise SettingsError("objective", self.objective, "'torque' or 'error' (the energy objective is the optimal-control "
                                                             "method's)")
        count = int(math.floor(problem.trajectory.duration * problem.rate + 1e-9)) + 1
        if count > DEFAULTS.max_samples:
            raise SettingsError("rate", problem.rate, f"at most {DEFAULTS.max_samples / problem.trajectory.duration:.4g} Hz for "
                                                      f"this trajectory ({DEFAULTS.max_samples} samples)")

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The member's (or the chosen member's) feedforward.

        The member's (or the chosen member's) feedforward (:func:`inversion.family.piecewise.ssef_inversion`).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        say : callable
            The progress display.
        """
        self.check(problem)
        return ssef_inversion(problem.system, problem.trajectory, self.explicit, settings=self.settings, auto=self.auto,
                              max_error=problem.bounds.max_error, max_torque=problem.max_torque,
                              max_torque_rate=problem.max_torque_rate, objective=self.objective, rate=problem.rate,
                              period=problem.sampling.period, hold=problem.sampling.hold, window=problem.window,
                              initial_internal_state=self.initial_internal_state, solver=default("solver", self.solver),  # type: ignore[arg-type]
                              tol=default("tol", self.tol), progress=say, zeros=self.zeros, case=problem.case, loop=problem.gains)

    def prepare(self, problem: Problem, stop: Callable[[], bool]) -> None:
        """The first grid's members solved ahead of the search.

        Where the member is chosen: the first grid's members solved and measured in closed form
        (:func:`inversion.family.auto.presolve`), which depends on neither the tube nor the bounds, for the search to
        take them bit for bit.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        stop : callable
            Asked between batches of members.
        """
        from .auto import presolve

        if self.settings is not None or not self.chooses(problem):
            return
        try:
            self.check(problem)
            form = family_form(problem.system, self.zeros)
        except (InversionError, SettingsError):
            return
        presolve(form, problem.trajectory, fixed=self.explicit, window=problem.window, initial_internal_state=self.initial_internal_state,
                 solver=default("solver", self.solver), tol=default("tol", self.tol), stop=stop)  # type: ignore[arg-type]

    def variants(self) -> list[tuple[str, InversionMethod]]:
        """compare's rows: the family as given, and with a rest end.

        ``compare``'s rows: the family as given, and with a rest end (the paper's Remark 2)."""
        return [("ssef", self), ("ssef-rest", replace(self, end=End.REST))]

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """The member in a sentence.

        The member, ``"5 segments, h = 2, Cdec = (0.0001, 1), paper, free end"``.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return (f"{len(settings['segments']) - 1} segments, h = {settings['h']}, Cdec = ({settings['cdec'][0]:g}, "
                f"{settings['cdec'][1]:g}), {settings['joining']}, {settings.get('end', 'free')} end")

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """The member as the exported C's header names it.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return (f"member: {len(settings['segments']) - 1} segments, h = {settings['h']}, Cdec = ({settings['cdec'][0]:g}, "
                f"{settings['cdec'][1]:g}), joining {settings['joining']}, {settings.get('end', 'free')} end")

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of ``sflm invert``'s text of a member.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s, st, v = summary, summary["settings"], summary["verification"]
        w = summary_words(s)
        m, unit, sym = w["m"], w["unit"], w["sym"]
        precision = (f"{max(v['precision_torque_difference'], v['precision_output_difference']):.1g} in extended precision"
                     if v["precision"] == "longdouble" else "extended precision unavailable on this platform")
        return [
            f"{s['model']}: piece-wise causal inversion (the family of sums of exponentials), {member_text(st)}, r = {s['r']} "
            f"({s['n_unstable']} unstable zero{'s' if s['n_unstable'] != 1 else ''})",
            report_row("trajectory", s["trajectory"]),
            report_row("max |y~ - y_d|", f"{s['max_redefinition_error']:.4g}{m} = {100 * s['relative_redefinition_error']:.3g} % of "
                       f"the {s['move']:.4g}{m} move (at t = {s['time_of_max_redefinition_error']:.4g} s; accepted "
                       f"{s['max_error']:.3g}{m})"),
            report_row("y~(tf)", f"{s['final_redefined_output']:.6g}{m} (desired {s['final_desired_output']:.6g}{m}); "
                       f"ydot~(tf) {s['final_redefined_velocity']:.3g}{w['speed']}"),
            report_row(f"peak |{sym}|", f"{s['peak_torque']:.5g}{unit} (at t = {s['time_of_peak_torque']:.4g} s)"),
            report_row(f"{w['inp']} at joints", f"largest jump {s['max_torque_jump']:.2g}{unit}; {sym}(t0) = "
                       f"{s['torque_at_start']:.2g}{unit}"),
            report_row("segment systems", f"largest residual {s['max_constraint_residual']:.2g}, largest condition number "
                       f"{s['max_condition_number']:.3g}"),
            report_row("verified", f"solvers agree to {max(v['solver_torque_difference'], v['solver_output_difference']):.1g}, "
                       f"{precision}; the linear plant follows y~ to {v['plant_output_error']:.1g} of the move"),
        ]


def member_text(settings: Mapping[str, Any]) -> str:
    """A member's settings in words.

    ``"5 segments, h = 2, Cdec = (0.0001, 1), paper"`` from a summary's settings block (its edges and end when not the
    paper's).

    Parameters
    ----------
    settings : mapping
        A member's settings (a summary's ``settings``, or ``best.json``).
    """
    segments = settings["segments"]
    count = segments if isinstance(segments, int) else len(segments) - 1
    fast, slow = settings["cdec"]
    end = settings.get("end", "free")
    ending = "" if end == "free" else f", {end} end"
    edges = ", rest edges" if settings.get("edges", "match") == "rest" else ""
    return (f"{count} segment{'s' if count != 1 else ''}, h = {settings['h']}, Cdec = ({fast:g}, {slow:g}), "
            f"{settings['joining']}{edges}{ending}")



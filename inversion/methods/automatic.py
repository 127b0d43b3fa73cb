"""The automatic choice across methods (:class:`Automatic`), the default method of :func:`inversion.invert`.

It runs the registered methods stage by stage
(:attr:`inversion.options.InversionMethod.stage`: the family first, stable inversion beside it where pre-actuation is
allowed, the re-planned output where neither passes, the optimal-control feedforward last) and returns the least peak
input of those that pass a stage, with the record of every stage; a move no causal feedforward within the bounds can
follow is refused before any stage with the bounded causal limit.

A stage that passes is judged against the least peak any causal table within the tube can have
(:func:`inversion.methods.bounded_limit.least_peak`): more than :attr:`~inversion.config.Defaults.torque_tolerance`
above it, the later stages that plan for the least peak (:attr:`InversionMethod.least_peak`: optimal control) are asked
too, and their table is returned where it needs that much less and tolerates enough plant error
(:attr:`~inversion.config.Defaults.torque_robustness`, :attr:`~inversion.config.Defaults.robust_enough`: a table that
rides its tube may hold it for the nominal plant alone).
"""

from __future__ import annotations

import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any, Callable

from ..config import DEFAULTS
from ..errors import InversionError, SettingsError
from ..family.auto import shared_members
from ..family.method import Family
from ..lti.causal_limit import CausalLimit
from ..options import InversionMethod, registered
from ..problem import Problem
from ..result import InversionResult
from ..threads import one_thread
from .bounded_limit import BoundedLimit, bounded_at, least_peak, limit_work, unbounded
from .judged import beyond_bounds, beyond_limit, judged_run
from .margin import margin_block, robustness_radius, tolerated

__all__ = ["Automatic", "Stage", "NO_ZEROS", "BESIDE_WORK"]

#: Why a method that works on the internal dynamics is skipped for a system without zeros.
NO_ZEROS = ("a system without zeros has no internal dynamics: its exact inverse is causal, and the optimal-control "
            "feedforward gives it held at the period")


@dataclass
class Stage:
    """The automatic choice's figures, as each stage reads them.

    The automatic choice's figures, as each stage's method reads them (:meth:`InversionMethod.for_automatic`).

    Attributes
    ----------
    problem : Problem
        The caller's problem.
    family : Family
        The family's options the choice was given (its end, edges and objective shape the other stages too).
    bound : float
        The tip bound (m).
    kept : float
        The share of the bound kept free.
    aim : float
        The tube the stages aim within (m).
    beyond : str or None
        Why every causal method is skipped (the causal limit), or ``None``.
    say : callable
        The progress display.
    limit : CausalLimit
        The move's causal limit.
    bounded : BoundedLimit or None
        The bounded causal limit, once asked.
    asked : bool
        Whether it was asked.
    note : str
        What the running stage adds to its record's message.
    why : str or None
        Why a later stage runs though an earlier one passed (its table's peak beyond the least), or ``None``.
    """

    problem: Problem
    family: Family
    bound: float
    kept: float
    aim: float
    beyond: str | None
    say: Callable[[str], None]
    limit: CausalLimit
    bounded: BoundedLimit | None = None
    note: str = ""
    why: str | None = None
    asked: bool = field(default=False, repr=False)

    def aimed(self, **changes: Any) -> Problem:
        """The problem a stage runs, its tip bound the tube.

        The problem a stage runs: the tip bound the tube, no margin of its own, no pre-actuation (unless ``changes`` say).

        Parameters
        ----------
        **changes
            Other fields of the problem (``preview``).
        """
        # a tube of zero (a move of zero length, whose default bound is zero): the default's, zero too
        return replace(self.problem, bounds=replace(self.problem.bounds, max_error=self.aim if self.aim > 0 else None), margin=0.0,
                       **{"preview": None, **changes})

    def bounded_limit(self, ask: bool = False, solving: Callable[[], None] | None = None,
                      solved: Callable[[float], None] | None = None) -> BoundedLimit | None:
        """The bounded causal limit at the controller's period.

        The bounded causal limit at the controller's period (computed here where ``ask`` and not asked before).

        Parameters
        ----------
        ask : bool
            Compute it if it was not.
        solving, solved : callable, optional
            As :func:`~inversion.methods.bounded_limit.bounded_limit`'s.
        """
        if ask and self.bounded is None and not self.asked:
            self.asked = True
            self.bounded = bounded_at(self.problem, self.problem.period, self.bound, self.say, solving, solved)
        return self.bounded


@dataclass(frozen=True)
class Automatic(InversionMethod):
    """The automatic choice across methods.

    The automatic choice across methods: the registered methods stage by stage, the least peak input of a stage that
    passes.

    Attributes
    ----------
    family : Family
        The family's options (a member's parts left free are searched; its ``end``, ``edges`` and ``objective`` shape the
        re-plan's and optimal control's stages too).
    order : tuple of str, optional
        The methods tried, by name, in stages (default: the registry's, by each method's ``stage``); a name stands alone
        in its stage.
    """

    name = "auto"
    label = "the automatic choice"

    family: Family = field(default_factory=Family)
    order: tuple[str, ...] | None = None

    def stages(self) -> list[list[InversionMethod]]:
        """The methods of each stage, in order."""
        if self.order is not None:
            from ..options import method_named

            return [[self.family if name == Family.name else method_named(name)()] for name in self.order]
        groups: dict[float, list[InversionMethod]] = {}
        for kind in registered():
            if kind.stage is not None:
                groups.setdefault(kind.stage, []).append(self.family if kind is Family else kind())
        return [groups[key] for key in sorted(groups)]

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:  # pragma: no cover - run by choose()
        """Not run directly: the door calls choose().

        The door calls :meth:`choose` with the causal limit it computed.

        Parameters
        ----------
        problem : Problem
            What is asked.
        say : callable
            The progress display.
        """
        raise InversionError("the automatic choice runs through inversion.invert")

    def choose(self, problem: Problem, limit: CausalLimit, say: Callable[[str], None]) -> InversionResult:
        """The automatic choice's result, or its refusal.

        The automatic choice's result, or its refusal with every stage's outcome and the limits.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        limit : CausalLimit
            The move's causal limit.
        say : callable
            The progress display.
        """
        bound = limit.bound
        assert bound is not None
        if limit.exceeds and problem.preview is None:
            raise beyond_limit(limit, problem)
        # cheap things first: a move whose table no result can hold (one row a sample) is refused before any programme
        count = int(math.floor(problem.trajectory.duration * problem.rate + 1e-9)) + 1
        if count > DEFAULTS.max_samples:
            raise SettingsError("rate", problem.rate, f"at most {DEFAULTS.max_samples / problem.trajectory.duration:.4g} Hz for this "
                                f"trajectory ({DEFAULTS.max_samples} samples; its {problem.trajectory.duration:g} s at this rate are {count})")
        has_zeros = problem.link or problem.form.n_internal > 0
        beyond = f"beyond the causal limit ({limit.sentence()})" if limit.exceeds else None
        stage = Stage(problem, self.family, bound, 0.0, bound, beyond, say, limit)
        with shared_members():  # (what the first stage prepares beside the limit, its search finds)
            return self._staged(stage, has_zeros, limit)

    def _staged(self, stage: Stage, has_zeros: bool, limit: CausalLimit) -> InversionResult:
        """:meth:`choose`'s work once the stage's figures are made: the limits, then the stages."""
        problem, say, bound, beyond = stage.problem, stage.say, stage.bound, stage.beyond
        if beyond is None and problem.preview is None:
            # what any causal feedforward within the drive's bounds can reach (a chain programme, a fraction of a second);
            # beyond the bound, no method has a table to return, and none is searched
            bounded = self._bounded_beside(stage, has_zeros)
            if bounded is not None and bounded.exceeds:
                raise beyond_bounds(bounded, limit)
        # the room the bounded causal limit leaves; without a torque or rate bound the causal limit's (it stands for it)
        floor = stage.bounded.error if stage.bounded is not None else limit.error if unbounded(problem) else None
        room = None if floor is None or not bound > 0 else max(0.0, 1.0 - float(floor) / bound)
        asked = problem.kept
        stage.kept = asked if room is None else min(asked, room / 2)
        stage.aim = bound * (1 - stage.kept)
        if stage.kept > 0:
            say(f"aiming within {stage.aim:.4g} ({100 * stage.kept:.3g} % of the bound {bound:.4g} kept free)")
        records: list[dict[str, Any]] = []
        passed: list[InversionResult] = []
        stages = self.stages()
        for index, methods in enumerate(stages):
            for method in methods:
                result = self._attempt(method, stage, has_zeros, records)
                if result is not None:
                    passed.append(result)
            if passed:
                break
        if not passed:
            raise _no_method(records, limit, stage.bounded)
        best = min(passed, key=_peak)
        later = [method for methods in stages[index + 1:] for method in methods if method.least_peak]
        least = self._least_peak(stage, best, later)
        radius = None
        asked_too = later if least is not None and least["beyond"] else []
        if asked_too:
            assert least is not None
            radius = robustness_radius(best, stage.bound, gains=problem.gains)
            least["screened"] = _screened(radius, stage)
            if least["screened"]["skipped"]:
                stage.say(f"{stage.why}, but a table riding the tube would tolerate about {100 * least['screened']['predicted']:.2g} % "
                          "plant error by this one's sensitivity: optimal control not asked")
                asked_too = []
        kept_radius = radius
        for method in asked_too:
            assert least is not None
            result = self._attempt(method, stage, has_zeros, records)
            if result is not None and _peak(result) * (1 + least["tolerance"]) < _peak(best):
                best, radius, least["robustness"] = _robuster(best, result, stage, kept_radius)
        chosen = _chosen(best, records, stage, asked, room, problem.gains, radius)
        if least is not None:
            chosen.summary["auto"]["least_peak"] = {k: v for k, v in least.items() if k != "beyond"}
        return chosen

    def _bounded_beside(self, stage: Stage, has_zeros: bool) -> BoundedLimit | None:
        """The bounded causal limit, the first stage's methods preparing beside it.

        The bounded causal limit on a second thread; while HPIPM solves its programme (and lets the GIL go), the first
        stage's methods do what does not depend on it (:meth:`InversionMethod.prepare`: the family's first grid solved);
        a refusal's shortest duration is sought alone. Every BLAS pool at one thread: the same bits whichever thread runs
        when. Where the limit is not computed (neither the torque nor its rate bounded), or its programme is smaller
        than :data:`BESIDE_WORK`, asked here alone.
        """
        problem = stage.problem
        first = [m for m in self.stages()[0] if m.takes_part(problem) and (has_zeros or not m.needs_zeros)]
        if (not first or unbounded(problem)
                or limit_work(problem.form, problem.trajectory.duration, problem.criteria(stage.bound, period=problem.period)) < BESIDE_WORK):
            return stage.bounded_limit(ask=True)
        # prepared only while HPIPM solves the limit's programme: its Python (the programme built, read back) has the GIL
        # to itself, and a refusal's shortest duration is sought alone
        solving, known = threading.Event(), threading.Event()
        with one_thread(), ThreadPoolExecutor(max_workers=1) as second:
            found = second.submit(stage.bounded_limit, True, solving.set, lambda error: known.set())
            while not solving.wait(0.005) and not found.done():
                pass
            for method in first:
                method.prepare(problem, lambda: known.is_set() or found.done())
            return found.result()

    def _least_peak(self, stage: Stage, best: InversionResult, later: list[InversionMethod]) -> dict[str, Any] | None:
        """The least peak any causal table within the tube can have, where a later stage plans for it.

        ``None`` where it is not asked (no such stage; another objective; a loop the feedforward alone need not hold) or
        not found; else its figures, ``beyond`` whether ``best``'s peak exceeds it by more than the tolerance (and
        :attr:`Stage.why` says so).
        """
        problem, family = stage.problem, stage.family
        if not later or family.objective not in (None, "torque") or problem.loop.closed or not stage.aim > 0:
            return None
        started = time.perf_counter()
        stage.say(f"the least peak input of any causal table within {stage.aim:.4g} (a chain programme)")
        try:
            lower = least_peak(problem.system, problem.trajectory, problem.criteria(stage.aim, hold="zoh", loop=None), stage.aim)
        except (InversionError, SettingsError) as exc:
            stage.say(f"the least peak input: not found ({exc})")
            return None
        tolerance = DEFAULTS.torque_tolerance
        peak = _peak(best)
        beyond = peak > (1 + tolerance) * lower
        if beyond:
            stage.why = (f"{best.summary['method']}'s table needs a peak input of {peak:.4g}, {100 * (peak / lower - 1):.3g} % above the "
                         f"least any causal table within {stage.aim:.4g} can have ({lower:.4g})")
        return {"peak_torque": lower, "tube": stage.aim, "tolerance": tolerance, "seconds": time.perf_counter() - started,
                "beyond": beyond}

    def _attempt(self, method: InversionMethod, stage: Stage, has_zeros: bool,
                 records: list[dict[str, Any]]) -> InversionResult | None:
        """One stage's method: skipped with its reason, refused with its figures, or passed."""
        stage.note = ""
        if not method.takes_part(stage.problem):
            return None  # unrecorded
        planned: Any = None
        if method.causal and stage.beyond is not None:
            planned = stage.beyond
        elif method.needs_zeros and not has_zeros:
            planned = NO_ZEROS
        else:
            planned = method.for_automatic(stage)
        if isinstance(planned, str):
            records.append(_record(method, "skipped", planned, 0.0))
            return None
        run, problem = planned
        start = time.perf_counter()
        try:
            result = judged_run(problem, run, stage.limit, stage.say)
        except (InversionError, SettingsError) as exc:
            status = getattr(exc, "status", "too-large" if isinstance(exc, SettingsError) else "failed")
            records.append(_record(method, status, str(exc) + stage.note, time.perf_counter() - start))
            stage.say(f"{method.label}: {status}")
            return None
        records.append(_record(method, "passed", f"peak input {result.summary['peak_torque']:.4g}" + stage.note,
                               time.perf_counter() - start, peak_torque=float(result.summary["peak_torque"])))
        return result


#: The bounded causal limit is computed beside the first stage's preparation from this programme size on
#: (:func:`inversion.chain.programme.work`'s units; about 0.3 s of HPIPM): below it, what the two threads cost each other
#: (the GIL shared by the programme's building and the family's batches, the thread) is more than a solve saves. Measured
#: on an AMD EPYC: the 3 mm strip's 0.6 s move, 7.0e6, 0.10 s (beside it, its refusal took 1.08 x as long); a transfer
#: function with complex zeros, 4.4 s at 1 ms, 4.8e7, 0.81 s (the family's first grid done meanwhile: 0.89 x).
BESIDE_WORK = 20_000_000
#: A cheaper table is not asked for where the earlier table's sensitivity says it would tolerate this many times less
#: plant error than it must (a first-order estimate; the factor covers its error, measured both ways: on the 3 mm
#: strip's 1.5 s move the estimate was 0.080 %, optimal control's table's own radius 0.054 %; on own-aluminium's 2 s
#: move 0.21 % against 0.588 %, below the 0.985 % it had to reach). A wrong skip keeps the earlier table, as before.
SCREEN = 3.0


def _loops(stage: Stage) -> tuple[str, ...]:
    """The loops a table is judged in, as the robustness radius names them."""
    return ("feedforward",) if stage.problem.loop.alone else ("feedforward", "pd")


def _screened(radius: dict[str, Any], stage: Stage) -> dict[str, Any]:
    """Whether a table riding the tube would tolerate too little plant error to be taken, by the earlier table's radius.

    Each edge the earlier table's radius found (a parameter, a side, a loop) gives its error's growth with that
    parameter's error, ``(E - e_0) / edge``; a table whose tip is at the tube ``E (1 - kept)`` with the same growth breaks
    the bound at ``E kept`` over it. The least of those (edges beyond the span say nothing and are passed over), ``SCREEN``
    times over, below what the choice asks (:func:`_robuster`): the cheaper table is not asked for.
    """
    bound, aim = stage.bound, stage.aim
    predicted = [(bound - aim) * abs(edge) / (bound - float(radius[loop]["nominal_error"]))
                 for loop in _loops(stage) if loop in radius and float(radius[loop]["nominal_error"]) < bound
                 for entry in radius[loop].values() if isinstance(entry, dict) and "lower" in entry
                 for edge, beyond in ((entry["lower"], entry["lower_beyond_span"]), (entry["upper"], entry["upper_beyond_span"]))
                 if edge is not None and not beyond]
    earlier = tolerated(radius, _loops(stage))
    asked = min(DEFAULTS.torque_robustness * earlier, DEFAULTS.robust_enough)
    least = min(predicted, default=math.inf)
    return {"predicted": least if math.isfinite(least) else None, "earlier": earlier, "factor": SCREEN,
            "skipped": bool(SCREEN * least < asked)}


def _robuster(earlier: InversionResult, cheaper: InversionResult, stage: Stage, known: dict[str, Any] | None = None
              ) -> tuple[InversionResult, dict[str, Any], dict[str, Any]]:
    """Of an earlier stage's table and a later one's that needs less peak input, the one the automatic choice returns.

    The cheaper, unless it tolerates less than :attr:`inversion.config.Defaults.torque_robustness` of the plant error the
    earlier one tolerates (:func:`inversion.methods.margin.tolerated`, in the loops judged) and less than
    :attr:`~inversion.config.Defaults.robust_enough`; with its radius and the record (``known``: the earlier's radius).
    """
    problem = stage.problem
    loops = _loops(stage)
    stage.say("the robustness radius of both tables (the cheaper is taken where it tolerates as much plant error)")
    radii = [known if r is earlier and known is not None else robustness_radius(r, stage.bound, gains=problem.gains)
             for r in (earlier, cheaper)]
    errors = [tolerated(radius, loops) for radius in radii]
    share, enough = DEFAULTS.torque_robustness, DEFAULTS.robust_enough
    keep = errors[1] < min(share * errors[0], enough)
    record = {"share": share, "enough": enough, "loops": list(loops), "span": float(radii[0]["span"]),
              "tables": [{"method": r.summary["method"], "peak_torque": _peak(r), "tolerated": e} for r, e in zip((earlier, cheaper), errors)],
              "kept": earlier.summary["method"] if keep else cheaper.summary["method"]}
    return (earlier, radii[0], record) if keep else (cheaper, radii[1], record)


def _peak(result: InversionResult) -> float:
    """A result's peak input."""
    return float(result.summary["peak_torque"])


def _record(method: InversionMethod, status: str, message: str, seconds: float, **more: Any) -> dict[str, Any]:
    """A stage's record in the summary's ``auto["stages"]``."""
    return {"method": method.name, "name": method.label, "status": status, "message": message, "seconds": seconds, **more}


def _chosen(best: InversionResult, stages: list[dict[str, Any]], stage: Stage, asked: float, room: float | None,
            gains: tuple[float, float] | None = None, radius: dict[str, Any] | None = None) -> InversionResult:
    """The automatic choice's result: its record of every stage, the caller's bound and the margin it keeps."""
    chosen = best.summary["method"]
    for record in stages:
        record["chosen"] = record["method"] == chosen
    bounded = stage.bounded
    best.summary["auto"] = {**(best.summary.get("auto") or {}), "stages": stages,
                            **({} if bounded is None else {"bounded_limit": bounded.as_dict()})}
    judged_at = float(best.summary["max_error"])
    best.summary["max_error"] = stage.bound  # the caller's bound; the table was judged within `judged_at`, inside it
    ocp: Any = best.summary.get("ocp") or {}
    aimed = min(judged_at, float(ocp.get("aimed", judged_at)))
    best.summary["margin"] = {**margin_block(best, stage.bound, aimed=aimed, asked=asked, gains=gains, found=radius), "room": room}
    return best


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

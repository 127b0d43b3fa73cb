"""The shortest move of a given profile within the drive's bounds, certified, with its table (issue 57).

A user starts from "0.5 m, this motor, this much error allowed: how fast?". For a profile ``y_d(t; T)`` -- a smoothstep of
a distance, its duration ``T`` free -- and absolute bounds (the peak torque and its change between the controller's rows:
given, or the geometry file's ``[drive]``), the bounded causal limit (:mod:`inversion.methods.bounded_limit`) is the least
error any causal feedforward held at the controller's period reaches within them: where it exceeds the tip bound at a
duration ``T_lo``, no causal table exists for that move -- a certificate, one chain programme --, and the limit falls as
the move lengthens. The search starts where a rigid body along the profile needs the drive's bounds
(:func:`profile_floor`), brackets the duration where the limit meets the bound (doubling, then narrowed on ``log E*``
against ``log T`` to ``precision``, two programmes at a time on two threads), then returns the table the door returns
for the shortest duration it passes at, judged like any other (the held rows, the window, more modes, both loops): its
summary's ``shortest`` block has the certified lower bound, the returned duration, their gap, what the margin costs in
duration, the rigid body's bang-bang floor with the same peak torque, and every ``(T, E*)`` the search computed (the
curve ``sflm invert --plot`` draws).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from ..config import DEFAULTS
from ..errors import InversionError, SettingsError
from ..options import as_method
from ..problem import Problem
from ..result import InversionResult
from ..signals.trajectory import Trajectory, stretched
from .bounded_limit import bounded_limit, evaluated, keep_bounded, narrowed
from .judged import bending, solve
from .ocp import OptimalControl

__all__ = ["ShortestMove", "shortest_move", "absolute_bound", "deflection_bound", "PRECISION", "LONGEST"]

#: The bracket of the duration is narrowed to this relative width (the gap between the certified lower bound and the
#: duration the bounded limit meets the bound at).
PRECISION = 0.005
#: The search gives up beyond this multiple of the rigid body's bang-bang floor (or of the move asked, the longer).
LONGEST = 64.0
#: The returned table is looked for at the aimed duration and at most this many steps of ``PRECISION`` above it.
TRIES = 12
#: Where a move's least tube in the loop cannot keep the margin (:func:`_longer`), the next is aimed at a least tube this
#: fraction of the one that keeps it (the exponent is a secant's: inside, so that one more move is seldom needed) ...
_INSIDE_NEEDED = 0.98
#: ... and at most this fraction longer.
_LONGEST_STEP = 0.2


@dataclass
class ShortestMove:
    """The shortest move's figures (the summary's ``shortest`` block).

    Attributes
    ----------
    lower : float
        A duration (s) at which no causal feedforward held at the period, within the torque and rate bounds, keeps the tip
        within the bound: ``lower_error`` (the bounded causal limit there) exceeds it.
    lower_error : float
        The bounded causal limit at ``lower`` (m).
    upper : float
        The least duration found at which the bounded limit meets the bound (``precision`` above ``lower`` at most).
    aimed : float
        The least duration found at which it meets the bound less the margin (the table's tube).
    duration : float
        The returned move's duration.
    bound : float
        The tip bound (m).
    margin : float
        The share of the bound the table was aimed to keep free.
    rigid_floor : float
        The rigid body's bang-bang time with the same peak torque, ``2 sqrt(J D / (x T))`` (a floor for any rest-to-rest
        move of this distance with this drive).
    curve : list of (float, float)
        Every ``(T, E*)`` computed, in order of ``T``.
    tried : list of dict
        The durations inverted and what the door said of each (``"margin"``: within the bounds, but less than half the
        margin kept: a longer move was tried; ``beyond_aimed`` in :meth:`as_dict`: what those tries cost in duration).
    profile : {"given", "free"}
        The move's profile: the one asked (stretched), or free (:mod:`inversion.methods.fastest`: the path is the
        programme's).
    beside : dict
        The other answers' figures, for a free profile (:func:`inversion.methods.fastest.fastest_move`).
    """

    lower: float
    lower_error: float
    upper: float
    aimed: float
    duration: float
    bound: float
    margin: float
    rigid_floor: float
    curve: list[tuple[float, float]] = field(default_factory=list)
    tried: list[dict[str, Any]] = field(default_factory=list)
    profile: str = "given"
    beside: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"lower_bound": self.lower, "lower_bound_error": self.lower_error, "upper": self.upper, "aimed": self.aimed,
                "duration": self.duration, "gap": self._gap(), "margin_cost": self.aimed / self.upper - 1.0,
                "beyond_aimed": self.duration / self.aimed - 1.0,
                "bound": self.bound, "margin": self.margin, "rigid_floor": self.rigid_floor,
                "curve": [[t, e] for t, e in sorted(self.curve)], "tried": self.tried, "profile": self.profile,
                **({"beside": self.beside} if self.beside else {})}

    def _gap(self) -> float:
        """The returned duration over the certified lower bound, less one (``inf`` where no duration is ruled out)."""
        return self.duration / self.lower - 1.0 if self.lower > 0 else math.inf

    def sentence(self) -> str:
        """The figures in a sentence."""
        what = "of any profile" if self.profile == "free" else "within the bounds"
        return (f"no causal feedforward {what} meets the bound in {self.lower:.4g} s (the least error there is "
                f"{self.lower_error:.4g}, above {self.bound:.4g}); this table moves in {self.duration:.4g} s, "
                f"{100 * self._gap():.2g} % longer" + (
                    f" (the margin of {100 * self.margin:g} % costs {100 * (self.aimed / self.upper - 1):.2g} % of the duration)"
                    if self.margin > 0 else "") + f"; a rigid body with the same peak torque needs {self.rigid_floor:.4g} s")


def shortest_move(problem: Problem, profile: Callable[[float], Trajectory] | None = None, method: Any = None,
                  say: Callable[[str], None] | None = None, precision: float = PRECISION, curve: int = 0) -> InversionResult:
    """The shortest move of a profile within the bounds, and its table.

    Certified by the bounded causal limit (module docstring).

    Parameters
    ----------
    problem : Problem
        The model, the bounds (absolute: given, or the model's ``[drive]``), the sampling, the loop, the margin; its
        trajectory is one of the profile's (its duration a first guess).
    profile : callable, optional
        ``profile(T)``: the move of duration ``T`` (the same distance); default the problem's move stretched in time
        (:func:`inversion.signals.trajectory.stretched`).
    method : InversionMethod or str, optional
        The method the table is asked of (default: optimal control, the method that plans its table within the bounds: at
        the limit the family and the re-plan have no member to offer).
    say : callable, optional
        The progress display.
    precision : float, optional
        The bracket's relative width.
    curve : int, optional
        Durations of the bounded limit's curve computed for its plot beyond those the search needs, spread from the
        start of the search to 1.5 x the returned move (``sflm invert --plot``: 6); none by default (the search computes
        four to six, near the answer).

    Returns
    -------
    InversionResult
        The returned move's result, judged like any other; ``summary["shortest"]`` (:meth:`ShortestMove.as_dict`).

    Raises
    ------
    SettingsError
        Without absolute torque bounds (the shortest move of a stronger motor is shorter still).
    InversionError
        Where no duration up to :data:`LONGEST` times the rigid floor (or the move asked) meets the bound, or no table is found just above
        the shortest that does, with the figures.
    """
    say = say or (lambda message: None)
    if profile is None:
        move = problem.trajectory
        profile = lambda duration: stretched(move, duration)  # noqa: E731
    bound = absolute_bound(problem, problem.trajectory.move(), method)
    problem, max_deflection, deflection_rule = deflection_bound(problem)
    margin = problem.kept
    curve_of: dict[float, float] = {}
    moves: dict[float, Trajectory] = {}

    def limit(duration: float) -> float:
        """The bounded causal limit of the move of ``duration`` (``inf`` where its programme is refused)."""
        if duration not in curve_of:
            try:
                move = profile(duration)
                found = bounded_limit(problem.system, move, problem.criteria(bound, hold="zoh", loop=None), shortest=False,
                                      max_deflection=max_deflection)
                curve_of[duration] = float(found.error)
                moves[duration] = move  # the limit the table's judgement asks first (bounded_at): this one, not solved again
                keep_bounded(replace(problem, trajectory=move), found)
            except (InversionError, SettingsError) as exc:
                say(f"shortest: {duration:.4g} s not computed ({exc})")
                curve_of[duration] = math.inf
        return curve_of[duration]

    floor = rigid_bang_bang(problem)
    say(f"shortest: the rigid body's bang-bang floor with this drive is {floor:.4g} s; bracketing the bounded limit")
    # (the search gives up beyond LONGEST times the rigid floor, or the move asked where there is none: a system's)
    reach = max(floor, problem.trajectory.duration)
    start = max(floor, profile_floor(problem, profile(problem.trajectory.duration)), 4 * problem.period)
    lower, upper = duration_bracket(limit, bound, start, reach, precision)
    aimed = upper
    if margin > 0:
        tube = bound * (1 - margin)
        aimed = duration_bracket(limit, tube, upper, reach, precision, known=curve_of)[1]
    found = ShortestMove(lower, curve_of[lower], upper, aimed, aimed, bound, margin, floor)
    result, duration = _returned_table(problem, profile, moves, limit, curve_of, found, method, say, precision)
    if result is not None and curve > 0:  # the plot's curve: its shape between the start and the answer
        say(f"shortest: {curve} more durations of the bounded limit's curve, for its plot")
        for extra in np.geomspace(start, 1.5 * duration, curve):
            if not any(abs(extra / known - 1.0) < 0.02 for known in curve_of):
                limit(float(extra))
    found.curve = sorted(curve_of.items())
    if result is None:
        failure = InversionError(f"no table found within {100 * TRIES * precision:.2g} % above the shortest duration the bounded limit "
                                 f"allows ({found.sentence()}); the last: {found.tried[-1]['message']}")
        failure.shortest = found.as_dict()  # type: ignore[attr-defined]
        raise failure
    found.duration = duration
    result.summary["shortest"] = {**found.as_dict(), **bending(result), "max_deflection": max_deflection,  # type: ignore[typeddict-unknown-key]
                                  "max_deflection_rule": deflection_rule}
    return result


def _returned_table(problem: Problem, profile: Callable[[float], Trajectory], moves: dict[float, Trajectory],
                    limit: Callable[[float], float], curve: dict[float, float], found: ShortestMove, method: Any,
                    say: Callable[[str], None], precision: float) -> tuple[InversionResult | None, float]:
    """The shortest move's table and its duration, from the duration aimed at (:func:`shortest_move`; ``None`` where no
    table is found: ``found.tried`` says why)."""
    margin, bound = problem.kept, found.bound
    result = None
    duration = found.aimed
    # at its limit a move's table planned alone leaves the joint PD loop little of the margin: planned for both at once,
    # refused after its first programme where its least tube shows it cannot keep half the margin (a longer move tried)
    keep = margin / 2 if margin > 0 and method is None else None
    planner = OptimalControl(loop_first=True, keep=keep) if method is None else as_method(method)
    kept: tuple[InversionResult, float] | None = None  # the first table within the bounds that lost the margin, and its move
    short: list[tuple[float, float, float]] = []  # the moves whose least tube could not keep it: (duration, tube, needed)
    for attempt in range(TRIES):
        say(f"shortest: the table of the move in {duration:.4g} s")
        limit(duration)  # (its bounded limit: on the curve, and the table's judgement asks it)
        try:
            result = solve(replace(problem, trajectory=moves.get(duration) or profile(duration)), planner, say)
        except (InversionError, SettingsError) as exc:
            if getattr(exc, "status", None) == "margin" and getattr(exc, "least_tube", None) is not None:
                tube, needed = float(getattr(exc, "least_tube")), float(getattr(exc, "tube_needed"))
                found.tried.append({"duration": duration, "status": "margin", "least_tube": tube})
                short.append((duration, tube, needed))
                say(f"shortest: {duration:.4g} s cannot keep {100 * keep:g} % of the bound free (its least tube {tube / bound:.4g} of "  # type: ignore[operator]
                    f"it, {needed / bound:.4g} needed): longer")
                duration = _longer(short, curve, precision)
            else:
                found.tried.append({"duration": duration, "status": getattr(exc, "status", "failed"), "message": str(exc)})
                duration *= 1 + precision * 2 ** min(attempt, 4)  # 0.5 %, 1 %, 2 %, 4 %, 8 %, ...: what the loop drags is found fast
            continue
        free = float((result.summary.get("margin") or {}).get("held", margin))
        if margin > 0 and free < margin / 2 and attempt < TRIES - 1:
            # within the bounds, but what the least tube does not see (more modes, the rows between) took more than half
            # the margin: a longer move keeps it (the first such table kept, should none)
            found.tried.append({"duration": duration, "status": "margin", "method": result.summary["method"], "margin": free})
            say(f"shortest: {duration:.4g} s keeps {100 * free:.2g} % of the bound free ({100 * margin:g} % asked): longer")
            kept = kept or (result, duration)
            duration *= 1 + precision * 2 ** min(attempt, 4)
            result = None
            continue
        found.tried.append({"duration": duration, "status": "passed", "method": result.summary["method"]})
        break
    if result is None and kept is None and short:  # none longer kept the margin: the first within the bounds, without it
        duration = short[0][0]
        say(f"shortest: no move up to {100 * TRIES * precision:.2g} % longer keeps the margin: the table of {duration:.4g} s")
        try:
            kept = (solve(replace(problem, trajectory=moves.get(duration) or profile(duration)), OptimalControl(loop_first=True), say),
                    duration)
        except (InversionError, SettingsError) as exc:
            found.tried.append({"duration": duration, "status": getattr(exc, "status", "failed"), "message": str(exc)})
    if result is None and kept is not None:  # none longer kept the margin: the shortest within the bounds, said so
        result, duration = kept
    return result, duration


def _longer(short: list[tuple[float, float, float]], curve: dict[float, float], precision: float) -> float:
    """The next duration the shortest move's table is asked at, where the last ``short`` could not keep the margin.

    Its least tube ``E_l(T)`` (the joint PD loop's, the motor's) falls with the duration about as the bounded limit's
    does: a power of it. The exponent is the secant's through the last two such moves, or the bounded limit's curve's
    near the last (its two nearest durations); the duration aimed at brings ``E_l`` to ``_INSIDE_NEEDED`` of the tube
    that keeps the margin, at least ``precision`` and at most ``_LONGEST_STEP`` longer. Measured on the 3 mm strip's
    smoothstep in both loops: the bounded limit's exponent -5.9, the loop's least tube's -5.8 to -4.7.
    """
    T1, E1, needed = short[-1]
    slope = math.nan
    if len(short) > 1 and short[-2][1] > E1 > 0 and T1 != short[-2][0]:
        slope = math.log(E1 / short[-2][1]) / math.log(T1 / short[-2][0])
    else:
        near = sorted((t for t, e in curve.items() if 0 < e < math.inf), key=lambda t: abs(math.log(t / T1)))[:2]
        if len(near) == 2 and abs(math.log(near[0] / near[1])) > precision / 10:
            (t0, e0), (t2, e2) = sorted((t, curve[t]) for t in near)
            slope = math.log(e2 / e0) / math.log(t2 / t0)
    if not slope < 0:  # (no exponent known: the steps of a table refused)
        return T1 * (1 + 2 * precision)
    factor = math.exp(math.log(_INSIDE_NEEDED * needed / E1) / slope)
    return T1 * min(max(factor, 1 + precision), 1 + _LONGEST_STEP)


def absolute_bound(problem: Problem, distance: float, method: Any = None) -> float:
    """The tip bound of a shortest move, its problem's bounds checked.

    Parameters
    ----------
    problem : Problem
        The problem.
    distance : float
        The move.
    method : InversionMethod or str, optional
        The method the table is asked of.

    Raises
    ------
    SettingsError
        Without absolute torque bounds (the shortest move of a stronger motor is shorter still), a tip bound not below
        the move, pre-actuation, or a method that is not causal (the certificate is of causal tables).
    """
    if problem.preview is not None:
        raise SettingsError("preview", problem.preview, "None for the shortest move (its certificate is of causal tables, "
                            "from the move's start)")
    if method is not None and not as_method(method).causal:
        raise SettingsError("method", getattr(method, "name", method), "a causal method for the shortest move (its certificate is "
                            "of causal tables), or None: optimal control")
    if not problem.absolute:
        raise SettingsError("max_torque", problem.bounds.max_torque, "absolute bounds for the shortest move: max_torque and "
                            "max_torque_rate, or the geometry file's drive.max_torque and drive.max_torque_rate; the defaults "
                            "grow with the move's own need")
    if not (math.isfinite(distance) and distance != 0):  # (before the bound: a bound is not the fault of a move of nothing)
        raise SettingsError("distance", distance, "a finite non-zero distance for the shortest move (a move of nothing takes no time)")
    bound = problem.bound()
    if not (math.isfinite(bound) and 0 < bound < abs(distance)):
        raise SettingsError("max_error", bound, "a finite bound below the move itself (the tip held still would meet it)")
    return float(bound)


def deflection_bound(problem: Problem) -> tuple[Problem, float | None, str | None]:
    """The shortest move's bound on a link's deflection, and whence.

    At the link's output: the given ``max_deflection``; for a link without one, :data:`inversion.config.Defaults.fastest_deflection` of the
    output's distance from the hub (the linear model's small deflections: at the drive's limit a light link bends by a
    large share of its length), the problem returned carrying it (the door plans and judges the table within it).

    Parameters
    ----------
    problem : Problem
        The problem.

    Returns
    -------
    tuple
        The problem, the bound (``None``: none, a system or ``inf`` given) and its rule in words (``None`` for a system).

    Raises
    ------
    SettingsError
        For a bound given to a system.
    """
    given = problem.bounds.max_deflection
    if not problem.link:
        if given is not None:
            raise SettingsError("max_deflection", given, "None for a system (a link's elastic deflection)")
        return problem, None, None
    if given is None:
        share = DEFAULTS.fastest_deflection
        value = share * float(problem.form.output_at or 1.0)
        return (problem.with_bounds(max_deflection=value), value,
                f"{100 * share:g} % of the output's distance from the hub (the default: the linear model's small deflections)")
    if not math.isfinite(given):
        return problem, None, "none (max_deflection inf)"
    return problem, float(given), "the given max_deflection"


def rigid_bang_bang(problem: Problem) -> float:
    """The rigid body's bang-bang time over the move with the peak torque bound: ``2 sqrt(J theta / T)`` (a link's inertia
    ``J`` about the hub and the joint angle ``theta = D / x_out``; a system's: its rigid mode's ``D / (G(0)-free) ...``:
    not defined, 0)."""
    form = problem.form
    inertia = getattr(form, "inertia", None)
    if inertia is None or problem.max_torque is None:
        return 0.0
    x_out = float(form.output_at or 1.0)
    angle = abs(problem.trajectory.move()) / x_out
    return 2.0 * math.sqrt(float(inertia) * angle / float(problem.max_torque))


def profile_floor(problem: Problem, move: Trajectory) -> float:
    """Where the search for the shortest duration starts: the duration below which a rigid body along the profile needs
    more than the drive's peak torque, or more than its change between rows.

    The move's rigid need at its duration ``T_0`` (:func:`inversion.acceptance.demand`) scales as ``T^-2`` (the torque)
    and about ``T^-3`` (its change over a period): ``T_0 max(sqrt(need / T_max), cbrt(need rate / R_max))``. A start, not
    a certificate (the bounded limit there is computed like any other); 0 for a system (its need is static). Measured on
    the 3 mm strip's smoothstep of order 2: 0.346 s, 1.2 x the bang-bang floor -- one programme fewer to bracket.

    Parameters
    ----------
    problem : Problem
        The problem (absolute bounds).
    move : Trajectory
        The profile at the problem's duration.
    """
    from ..acceptance import demand

    form = problem.form
    if getattr(form, "inertia", None) is None or not problem.max_torque or not problem.max_torque_rate:
        return 0.0
    need = demand(form, move, problem.period)
    torque = math.sqrt(need.rigid_torque / float(problem.max_torque))
    rate = (need.rigid_rate / float(problem.max_torque_rate)) ** (1 / 3)
    return float(move.duration) * max(torque, rate) if math.isfinite(torque + rate) else 0.0


def duration_bracket(limit: Callable[[float], float], bound: float, start: float, floor: float, precision: float,
                     known_infeasible: float | None = None, known: dict[float, float] | None = None,
                     together: bool = True) -> tuple[float, float]:
    """``(lower, upper)``: a duration whose limit exceeds ``bound`` and one whose limit meets it, ``precision`` apart at most.

    The durations computed before (``known``) seed the bracket; else it doubles up from ``start``, a duration and its
    double at a time (and halves down from a feasible one). Then narrowed two durations a round
    (:func:`inversion.methods.bounded_limit.narrowed`). ``together``: two programmes at a time on two threads (the
    default; ``limit`` is then called from both); ``False``: one after the other.
    """
    points = dict(known or {})
    infeasible = [t for t, e in points.items() if not e <= bound]
    feasible = [t for t, e in points.items() if e <= bound]
    low = max((t for t in infeasible if not feasible or t < min(feasible)), default=known_infeasible)
    high = min((t for t in feasible if low is None or t > low), default=None)
    longest = LONGEST * max(floor, start)
    if high is None:
        high = max(start, 1e-6) if low is None else 2.0 * low
        while True:
            if high not in points:  # (its double too: needed next where it fails)
                evaluated(limit, [high, 2.0 * high] if together and 2.0 * high <= longest else [high], points, None, together)
            if points[high] <= bound:
                break
            low = high
            high *= 2.0
            if high > longest:
                raise InversionError(f"no duration up to {high / 2:.4g} s meets the bound {bound:.4g} within the torque and rate "
                                     f"bounds (the bounded limit there is {limit(high / 2):.4g}): a larger max_error or stronger "
                                     "bounds")
    if low is None:
        low = high
        while limit(low) <= bound:
            high, low = low, low / 2.0
            if low < 1e-6:
                raise InversionError("every duration down to a microsecond meets the bound: the bound holds the tip anywhere")

    def excess(t: float) -> float:
        value = limit(t)
        if not math.isfinite(value):
            return math.inf
        return math.log(value / bound) if value > 0 else -math.inf  # (a limit of zero meets any bound)

    return narrowed(excess, low, high, precision, together=together)

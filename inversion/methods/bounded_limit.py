"""The bounded causal limit: the least error any causal feedforward within the actuator's bounds can reach.

The causal limit (:mod:`inversion.lti.causal_limit`) bounds the error of any causal input, however large and however
fast. A drive has bounds, and the acceptance (:class:`inversion.acceptance.Criteria`) judges every result by them: the
peak torque ``T`` and the change between the controller's rows ``R``. On the exactly discretised model at the
controller's period ``DT`` (:func:`inversion.lti.discrete.zero_order_hold`), from rest at ``t0``, with inputs
``u_0 .. u_{M-1}`` held over the move and a horizon after it (free there too: a feedforward may settle after
``t_f``)::

    minimise    E
    subject to  |C x_k - y_d(t_k)| <= E                  (at the rows; y_d(t_f) after the move)
                |u_k| <= T,  |u_k - u_{k-1}| <= R        (u_{-1}: the input before the move)

The acceptance holds a table's tip to the bound at exactly these rows (:class:`inversion.acceptance.Sampled`'s
``max_tip_error``), so every causal feedforward held at ``DT`` that it passes meets these rows (it is asked more: after
a longer window, with more modes), and errs by at least ``E*``: where ``E*`` exceeds the bound, no
causal method -- the family, a re-planned output, optimal control, any other -- has a result to return at these
bounds, and a refusal can say so with the figure.

It is a chain programme (:mod:`inversion.chain.programme`), solved by HPIPM's Riccati-based interior point in time
linear in the periods: the 3 mm strip's 0.5 m in 0.6 s at 1 ms in 0.1 s (4 modes: 0.14 s), where HiGHS's interior point
took 2.1 s (5.5 s) and had to keep the states of longer moves only every few periods; every period is kept now. The
horizon after the move is a third of the move's duration (at most the window), and at its last row the move's
unstable zeros bound what the rows after it could still do (:func:`inversion.chain.programme.zero_directions`): without
that end a slow unstable zero's constraint lay beyond a short horizon ((0.5 - s)/(s (s + 2)), 1 in 4 s at 10 ms: 19.5 %
of the move, below the causal limit's 38.9 %; with it 41.90 %, what a horizon of 40 s gives without it). Fewer rows only
lower ``E*``: it stays a bound. HPIPM stops on its iteration limit alone, so the same programme gives the same ``E*``
on a free and on a busy machine.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model

from ..acceptance import WORDS, Criteria, demand, window_length
from ..chain.programme import MAX_LP_WORK, Chain, check_size, work
from ..errors import InversionError, SettingsError
from ..lti.discrete import zero_order_hold
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form
from ..signals.trajectory import Trajectory, stretched

__all__ = ["BoundedLimit", "bounded_limit", "bounded_at", "unbounded", "keep_bounded", "least_peak", "shortest_duration", "searchable", "limit_work", "deflection_row", "DEFLECTION_INSIDE", "LONGEST_STRETCH"]

FloatArray = NDArray[np.float64]
#: The horizon after the move, as a fraction of its duration (at most the window).
_AFTER = 1 / 3
#: What the programme resolves of ``E*``, a fraction of the output's scale (HPIPM's residuals within 1e-12 of it).
_RESOLUTION = 1e-9


@dataclass(frozen=True)
class BoundedLimit:
    """The least error within the torque and rate bounds.

    Attributes
    ----------
    error : float
        ``E*`` (m; the output's units for a system): no causal feedforward held at ``period`` within the bounds keeps
        the tip closer to ``y_d`` at the rows.
    move : float
        The move (for the relative figure).
    period : float
        The controller's period (s).
    max_torque : float
        The peak bound ``T``.
    max_torque_rate : float
        The bound ``R`` on the change between rows.
    bound : float or None
        The error bound asked for.
    link : bool
        A link (torque, tip) or a system (input, output).
    seconds : float
        The programmes' time.
    rows_apart : int
        The tip is bounded at every ``rows_apart``-th row: 1, every row (the programme keeps every period since it is a
        chain programme; the record keeps the key).
    duration : float
        The move's duration (s).
    torque_rule, rate_rule : str
        Where ``T`` and ``R`` come from (``3 x the rigid need``, ``the given max_torque``; :class:`inversion.acceptance.Criteria`).
    resolution : float
        What the programme resolves of ``E*``: HPIPM's tolerance on its residuals in the output's units (``1e-9`` of the
        move).
    shortest_duration : float or None
        The least duration of the same move (``y_d`` stretched in time, :func:`inversion.signals.trajectory.stretched`)
        whose limit meets the bound within the same bounds (their defaults resolved against the stretched move's need), to
        three digits, rounded up; ``None`` when not asked for or not found (:func:`shortest_duration`).
    longer_than : float or None
        A duration of the same move that does not meet it (at most 2 % shorter, rounded down; or the longest tried where
        the search's work ran out, :data:`SEARCH_WORK`, with ``shortest_duration`` ``None``).
    max_deflection : float or None
        The link's deflection at its output bounded within it at every row (m; ``None``: not bounded).
    """

    error: float
    move: float
    period: float
    max_torque: float
    max_torque_rate: float
    bound: float | None = None
    link: bool = True
    seconds: float = 0.0
    rows_apart: int = 1
    duration: float = 0.0
    shortest_duration: float | None = None
    longer_than: float | None = None
    resolution: float = 0.0
    torque_rule: str = ""
    rate_rule: str = ""
    max_deflection: float | None = None

    @property
    def exceeds(self) -> bool:
        """Whether ``E*`` exceeds the bound (no feedforward within the bounds passes).

        By more than the programme resolves (:attr:`resolution`): a move of zero length has ``E* = 8e-13``, not above a
        bound of 0.
        """
        return self.bound is not None and self.error > self.bound + self.resolution

    def sentence(self) -> str:
        """The limit as a sentence.

        ``held at 1 ms with the torque within T and its change within R a period, no causal feedforward keeps ...``.
        """
        w = WORDS[self.link]
        torque = f" ({self.torque_rule})" if self.torque_rule else ""
        rate = f" ({self.rate_rule})" if self.rate_rule else ""
        bent = "" if self.max_deflection is None else f" and the link's deflection at its output within {self.max_deflection:.4g} m"
        return (f"held at {1e3 * self.period:.3g} ms with the {w['inp']} within {self.max_torque:.4g}{torque} and its change within "
                f"{self.max_torque_rate:.4g} a period{rate}{bent}, no causal feedforward keeps the {w['out']} closer than {self.error:.4g} "
                f"({100 * self.error / (self.move or 1.0):.3g} % of the move) at "
                + ("the rows" if self.rows_apart == 1 else f"one row in {self.rows_apart}")
                + " (a chain programme on the model)")

    def duration_sentence(self) -> str:
        """The shortest duration within the bounds, as a sentence.

        ``within the same bounds the same move needs more than L s, and X s meets it (it lasts T s)``, or ``""`` where not
        found.
        """
        if self.shortest_duration is None:
            if self.longer_than is None:
                return ""
            return (f"within the same bounds the same move needs more than {self.longer_than:.3g} s (it lasts "
                    f"{self.duration:.4g} s; longer moves were not tried: their programmes are beyond the search's work)")
        if self.longer_than is None or self.longer_than >= self.shortest_duration:
            return f"within the same bounds the same move meets it in {self.shortest_duration:.3g} s (it lasts {self.duration:.4g} s)"
        return (f"within the same bounds the same move needs more than {self.longer_than:.3g} s, and {self.shortest_duration:.3g} s "
                f"meets it (it lasts {self.duration:.4g} s)")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (a refusal's ``bounded_limit`` record)."""
        return {"error": self.error, "relative_error": self.error / (self.move or 1.0), "move": self.move, "period": self.period,
                "max_torque": self.max_torque, "max_torque_rate": self.max_torque_rate, "bound": self.bound, "seconds": self.seconds,
                "rows_apart": self.rows_apart, "duration": self.duration, "shortest_duration": self.shortest_duration,
                "longer_than": self.longer_than,
                "max_torque_rule": self.torque_rule, "max_torque_rate_rule": self.rate_rule, "max_deflection": self.max_deflection}


def bounded_limit(model: Model | LinearSystem, trajectory: Trajectory, bounds: Criteria, shortest: bool | None = None,
                  max_deflection: float | None = None, solving: Callable[[], None] | None = None,
                  solved: Callable[[float], None] | None = None) -> BoundedLimit:
    """The least error of a causal feedforward within the bounds.

    The least error any causal feedforward held at the bounds' period, within their torque and rate bounds, reaches on
    the model (module docstring).

    Parameters
    ----------
    model : Model or LinearSystem
        The plant (its linear model).
    trajectory : Trajectory
        The desired output.
    bounds : Criteria
        The acceptance's bounds: ``max_error`` (the bound ``E*`` is compared with), the period, the torque and rate bounds
        (their defaults resolved against the rigid need as the acceptance resolves them).
    shortest : bool, optional
        Also the shortest duration within the bounds (:func:`shortest_duration`); ``None`` (the default): only where the
        limit exceeds the bound.
    max_deflection : float, optional
        A link's elastic deflection at its output within it at every row (:attr:`inversion.problem.Bounds.max_deflection`;
        the shortest move's).
    solving, solved : callable, optional
        Called as its programme goes to HPIPM (which lets the GIL go), and with the limit once it is solved, before the
        shortest duration is sought: the automatic choice does other work beside it in between.

    Raises
    ------
    SettingsError
        For a programme larger than :data:`inversion.chain.programme.MAX_LP_WORK` (naming the least period accepted).
    InversionError
        When HPIPM does not solve the programme within its iterations (its status and residuals named).
    """
    started = time.perf_counter()
    form, chain, rate_rule = _chain_of(model, trajectory, bounds)
    link = form.inertia is not None
    period, T, R = float(bounds.period), float(chain.peak), chain.rate  # type: ignore[arg-type]
    if max_deflection is not None and not math.isfinite(max_deflection):
        max_deflection = None  # inf: not bounded
    if max_deflection is not None:
        chain = replace(chain, deflection=deflection_row(form, max_deflection))
    if solving is not None:
        solving()
    try:
        E = max(chain.solve().error, 0.0) + 0.0  # not -0 from rounding (max(-0.0, 0.0) is -0.0)
    except InversionError as exc:
        raise InversionError(f"the bounded causal limit was not found: {exc}") from None
    if solved is not None:
        solved(E)
    bound = float(bounds.max_error)
    resolution = _RESOLUTION * chain.output_scale
    longer = None
    if shortest or (shortest is None and E > bound + resolution):
        longer = shortest_duration(form, trajectory, bounds, E, max_deflection=max_deflection)
    return BoundedLimit(error=E, move=trajectory.move(), period=period, max_torque=T, max_torque_rate=R, bound=bound, link=link,
                        seconds=time.perf_counter() - started, rows_apart=1, duration=trajectory.duration,
                        shortest_duration=None if longer is None else longer[1], longer_than=None if longer is None else longer[0],
                        resolution=resolution, torque_rule=bounds.torque_rule(link), rate_rule=rate_rule,
                        max_deflection=max_deflection)


def least_peak(model: Model | LinearSystem, trajectory: Trajectory, bounds: Criteria, aim: float) -> float:
    """The least peak input of a causal feedforward within a tube.

    The least peak ``max |u_k|`` of any causal feedforward held at the bounds' period, its change between rows within
    their rate bound, whose output stays within ``aim`` of ``y_d`` at the rows of the move and of the horizon after it:
    the programme of the module docstring with ``E`` given and the peak minimised (the inputs free after the move too: a
    relaxation of every table the acceptance passes, so no table within ``aim`` at its rows has a smaller peak).

    Parameters
    ----------
    model : Model or LinearSystem
        The plant (its linear model).
    trajectory : Trajectory
        The desired output.
    bounds : Criteria
        The period and the rate bound (its default resolved against the rigid need).
    aim : float
        The tube (m), positive.

    Raises
    ------
    InversionError
        When HPIPM does not solve the programme within its iterations.
    """
    _, chain, _ = _chain_of(model, trajectory, bounds)
    try:
        found = replace(chain, error=float(aim), peak=None, output_scale=float(aim)).solve()
    except InversionError as exc:
        raise InversionError(f"the least peak within the tube was not found: {exc}") from None
    return found.peak


def _chain_of(model: Model | LinearSystem, trajectory: Trajectory, bounds: Criteria) -> tuple[Any, Chain, str]:
    """The module docstring's programme for a move and its bounds: the normal form, the chain and the rate bound's rule."""
    form = normal_form(model)
    period = float(bounds.period)
    asked = demand(form, trajectory, period)
    need, need_rate = asked.rigid_torque, asked.rigid_rate
    T = bounds.torque_limit(need)
    R, rate_rule = bounds.rate_limit(need_rate, form.inertia is not None)
    after = min(window_length(form, bounds.window), _AFTER * trajectory.duration)
    return form, _programme(form, trajectory, period, after, need, T, R), rate_rule


#: The longest stretch :func:`shortest_duration` tries, in multiples of the move's duration.
LONGEST_STRETCH = 64.0
#: The most work :func:`shortest_duration`'s programmes may take together (:func:`inversion.chain.programme.work`'s
#: units: three quarters of one linear programme's limit, about 68 000 stages of the paper's member, 7 s of HPIPM here).
#: Beyond it the search stops with what it has: a duration that fails, and the bracket as far as it was narrowed or none
#: above it (issue 59, item 11: the paper's move with its torque's change bounded to 1e-6 a period searched 80 CPU-s for
#: "more than 41.1 s, and 41.8 s meets it").
SEARCH_WORK = 3 * MAX_LP_WORK // 4
#: :func:`shortest_duration` brackets the duration to this fraction (then rounds up to three digits).
_PRECISION = 0.02


def shortest_duration(form: Any, trajectory: Trajectory, bounds: Criteria, error: float | None = None,
                      max_deflection: float | None = None) -> tuple[float, float | None] | None:
    """The least duration of the same move within the bounds.

    The least duration whose bounded causal limit meets the bound: ``y_d`` stretched in time (:func:`inversion.signals.trajectory.stretched`); the bounds as given, their defaults
    resolved against the stretched move's rigid need (a longer move needs less: its torque and rate bounds shrink with
    it). The limit falls as the move lengthens: stretched first by ``sqrt(E* / bound)`` (at least 2 %, at most twice),
    then doubled until it meets the bound (at most :data:`LONGEST_STRETCH` times),
    then narrowed to 2 % (two durations a round on two threads, :func:`narrowed`), and the duration that met it rounded up
    to three digits.

    Parameters
    ----------
    form : NormalForm
        The plant.
    trajectory : Trajectory
        The move.
    bounds : Criteria
        The bounds (``max_error`` the bound met).
    error : float, optional
        The limit at the move's own duration, where known.
    max_deflection : float, optional
        The link's deflection at its output bounded within it at every row, as in the limit itself.

    Returns
    -------
    tuple of float, or None
        Seconds: a duration that does not meet the bound and one that does, 2 % apart at most (three digits, rounded
        down and up; further apart where the search's work, :data:`SEARCH_WORK`, ran out while narrowing, and the second
        ``None`` where it ran out before any duration met the bound); the move's own duration twice where it meets the
        bound already; ``None`` where no duration up to :data:`LONGEST_STRETCH` times it does, or the programme grows
        beyond what one solve takes.
    """
    bound = float(bounds.max_error)
    T0 = trajectory.duration
    spent = 0  # the search's work so far (inversion.chain.programme.work's units)

    def affordable(duration: float) -> bool:
        """Whether the programme of the move stretched to ``duration`` fits in what is left of :data:`SEARCH_WORK`."""
        nonlocal spent
        spent += limit_work(form, duration, bounds)
        return spent <= SEARCH_WORK

    def excess(duration: float) -> float | None:
        """``log(E* / bound)`` of the move stretched to ``duration`` (``None``: not computed)."""
        move = stretched(trajectory, duration)
        period = float(bounds.period)
        asked = demand(form, move, period)
        T, R = bounds.torque_limit(asked.rigid_torque), bounds.rate_limit(asked.rigid_rate, form.inertia is not None)[0]
        after = min(window_length(form, bounds.window), _AFTER * duration)
        try:
            chain = _programme(form, move, period, after, asked.rigid_torque, T, R)
            if max_deflection is not None:
                chain = replace(chain, deflection=deflection_row(form, max_deflection))
            E = chain.solve().error
        except (InversionError, SettingsError):
            return None
        return math.log(max(E, 1e-300) / max(bound + _RESOLUTION * chain.output_scale, 1e-300))

    if error is not None and error <= bound + _RESOLUTION * (abs(trajectory.move()) or 1.0):
        return T0, T0
    if not bound > 0 or error is None:
        return None
    # the limit falls smoothly as the move lengthens, at least as the square of the duration's inverse where measured
    # (E* ~ T^-p, p 2.3 to 5: the 3 mm strip's cliff 2.7, a system with three zeros 4 and 5, a 2-mode link's torque bound
    # 2.3): first stretched by sqrt(E* / bound) -- where the limit falls so, it meets the bound there, a little past
    # where it first does -- at least 2 % and at most twice, then doubled until it meets the bound; then the bracket
    # narrowed (the 3 mm strip's 0.6 s move: 0.726 s tried first, not 1.2 s)
    first = min(2.0, max(1.0 + 0.999 * _PRECISION, math.sqrt(error / bound)))
    low, high = math.log(T0), math.log(first * T0)
    f_low = math.log(error / bound)
    while True:
        if not affordable(math.exp(high)):  # a duration that fails is known; the one that meets it is not sought further
            return _rounded(math.exp(low), -1), None
        f_high = excess(math.exp(high))
        if f_high is None:
            return None
        if f_high <= 0:
            break
        low, f_low, high = high, f_high, high + math.log(2.0)
        if math.exp(high) > LONGEST_STRETCH * T0:
            return None
    # then narrowed two durations a round (:func:`narrowed`: on the 3 mm strip's 0.6 s move one round, where Brent's method
    # computed two programmes in turn); a duration not computed, or beyond what is left of the search's work, ends it with
    # the bracket as far as it was narrowed (only computed limits certify)
    seen = {math.exp(low): f_low, math.exp(high): f_high}

    def paid(duration: float) -> None:
        if not affordable(duration):
            raise _Unfinished

    def computed(duration: float) -> float:
        f = excess(duration)
        if f is None:
            raise _Unfinished
        return f

    try:
        lower, upper = narrowed(computed, math.exp(low), math.exp(high), _PRECISION, seen, before=paid)
    except _Unfinished:
        lower = max(t for t, f in seen.items() if f > 0)
        upper = min(t for t, f in seen.items() if not f > 0 and t > lower)
    return _rounded(lower, -1), _rounded(upper, 1)


def searchable(form: Any, duration: float, bounds: Criteria) -> bool:
    """Whether a limit is within what a duration's search may spend.

    Whether the programme of the bounded causal limit of a move lasting ``duration``, at the bounds' period, fits in
    :data:`SEARCH_WORK` (:func:`inversion.chain.programme.work`'s units): a refusal quoting a duration asks no more (a
    73 s move of a 2-mode link at 1 ms: 18 s of HPIPM, for a duration the search could not narrow within its work).

    Parameters
    ----------
    form : NormalForm
        The plant.
    duration : float
        The move's duration (s).
    bounds : Criteria
        The period and the window after the move.
    """
    return limit_work(form, duration, bounds) <= SEARCH_WORK


def limit_work(form: Any, duration: float, bounds: Criteria) -> int:
    """The size of a move's bounded-limit programme.

    The work (:func:`inversion.chain.programme.work`) of the bounded causal limit's programme of a move lasting
    ``duration``, at the bounds' period, through the window after it.

    Parameters
    ----------
    form : NormalForm
        The plant.
    duration : float
        The move's duration (s).
    bounds : Criteria
        The period and the window after the move.
    """
    period = float(bounds.period)
    periods = math.ceil(duration / period) + math.ceil(min(window_length(form, bounds.window), _AFTER * duration) / period)
    return work(periods, form.n_states)


class _Unfinished(Exception):
    """:func:`shortest_duration`'s narrowing stopped: a limit not computed, or the search's work spent."""


def narrowed(excess: Callable[[float], float], low: float, high: float, precision: float,
             seen: dict[float, float] | None = None, before: Callable[[float], None] | None = None,
             together: bool = True) -> tuple[float, float]:
    """A bracket of durations narrowed to ``high / low - 1 <= precision``.

    ``excess`` (``log(E* / bound)`` of a duration) is positive at ``low`` and not at ``high``. Two durations a round, on
    two threads (HPIPM lets the GIL go): the root of ``log E*`` against ``log T`` interpolated through the bracket's ends
    and the nearest duration computed beyond them (inverse quadratic interpolation, as Brent's method; the secant where
    there are two), and a duration ``precision`` apart around it (:func:`_probes`), so that a root guessed within half
    the precision closes the bracket in one round -- where Brent's method (SciPy's ``brentq``) computed the guess, then a
    step of its tolerance towards the other end, one after the other. Where two rounds running do not halve the bracket
    (in ``log T``), the next splits it in thirds. The bracket is read back from every duration computed (``seen``, updated;
    it may hold ``low``'s and ``high``'s values), so both its ends are computed durations. Deterministic: each duration's
    value is its own, whichever thread computes it when. Measured on the 3 mm strip's shortest smoothstep (the bound, then
    the margin's tube): two rounds where Brent's method took four programmes in turn. A duration whose limit was not
    computed (``excess`` infinite) counts as above the bound: bisected past first.

    Parameters
    ----------
    excess : callable
        ``log(E* / bound)`` of a duration; ``inf`` where not computed, ``-inf`` where the limit is zero. Called on a
        second thread too: it must not depend on the order of its calls.
    low, high : float
        The bracket (s).
    precision : float
        Its relative width asked.
    seen : dict, optional
        The durations computed and their excess.
    before : callable, optional
        Called with each duration before its excess is asked, in this thread and in a fixed order (a search's account of
        its work; it may raise to stop the search).
    together : bool, optional
        Two durations a round on two threads (the default); ``False``: one after the other in this thread (a search that
        already runs beside other work).
    """
    seen = {} if seen is None else seen
    evaluated(excess, [end for end in (low, high) if end not in seen], seen, before, together)
    while not math.isfinite(seen[low]) and high / low - 1.0 > precision:  # (no line through an infinite end)
        low, high = _halved(excess, low, high, seen, before)
    if not together:
        return _one_at_a_time(excess, low, high, precision, seen, before)
    width, slow = math.inf, 0
    for _ in range(60):
        low = max(t for t, f in seen.items() if f > 0)
        high = min(t for t, f in seen.items() if not f > 0 and t > low)
        if high / low - 1.0 <= precision:
            return low, high
        now = math.log(high / low)
        slow = slow + 1 if now > 0.5 * width else 0
        width = now
        evaluated(excess, _probes(seen, low, high, precision, thirds=slow >= 2), seen, before, together)
    raise InversionError(f"the duration's bracket was not narrowed to {100 * precision:.2g} % in 60 rounds ({low!r} to {high!r} s)")


def _one_at_a_time(excess: Callable[[float], float], low: float, high: float, precision: float, seen: dict[float, float],
                   before: Callable[[float], None] | None) -> tuple[float, float]:
    """:func:`narrowed` one duration at a time: Brent's method (SciPy's ``brentq``) on ``log E*`` against ``log T``, and a
    last step of its tolerance towards the other end, so that both ends are computed durations (the 3 mm strip's
    shortest smoothstep: 4 programmes inside the same bracket where regula falsi, Illinois, took 7)."""
    from scipy.optimize import brentq  # lazy: keeps `import inversion` fast

    ends = {math.log(low): low, math.log(high): high}  # (exp(log(T)) is not T one time in three: no end solved twice)

    def at(s: float) -> float:
        t = ends.get(s, math.exp(s))
        evaluated(excess, [t], seen, before, False)
        return min(max(seen[t], -1e3), 1e3)  # (an infinite end as far beyond every finite log-excess met)

    if high / low - 1.0 > precision:
        brentq(at, math.log(low), math.log(high), xtol=0.999 * math.log1p(precision), rtol=1e-14, maxiter=60)
    low = max(t for t, f in seen.items() if f > 0)
    high = min(t for t, f in seen.items() if not f > 0 and t > low)
    while high / low - 1.0 > precision:  # (Brent ends within its tolerance; kept for a limit that is not monotone)
        low, high = _halved(excess, low, high, seen, before)
    return low, high


def _halved(excess: Callable[[float], float], low: float, high: float, seen: dict[float, float],
            before: Callable[[float], None] | None) -> tuple[float, float]:
    """The half of the bracket (in ``log T``) the root is in, its middle computed."""
    middle = math.sqrt(low * high)
    evaluated(excess, [middle], seen, before, False)
    return (middle, high) if seen[middle] > 0 else (low, middle)


def _probes(seen: dict[float, float], low: float, high: float, precision: float, thirds: bool) -> list[float]:
    """:func:`narrowed`'s next two durations inside ``(low, high)``: around the interpolated root, ``precision`` apart
    less a thousandth (both inside the bracket); where the root is guessed within half that of an end (computed already),
    ``precision`` and twice it in from that end (the 2 % of a system with a zero at +2's 7.5 % bound: 6.612 and 6.483 s,
    where the pair at the end was 6.612 and 6.7435 s, a thousandth of the precision from the end's 6.7441 s); its thirds
    where ``thirds`` or nothing can be interpolated."""
    a, b = math.log(low), math.log(high)
    fa, fb = seen[low], seen[high]
    half = 0.4995 * math.log1p(precision)
    guess = math.nan
    if not thirds and math.isfinite(fa) and math.isfinite(fb):
        points = [(a, fa), (b, fb)]
        beyond = [(abs(math.log(t) - (a if t < low else b)), t) for t, f in seen.items()
                  if math.isfinite(f) and (t < low or t > high)]
        if beyond:
            t = min(beyond)[1]
            points.append((math.log(t), seen[t]))
        guess = _root(points)
        if not (guess > a and guess < b):
            guess = a + fa * (b - a) / (fa - fb)  # the secant's (inside: fa > 0 >= fb)
    if not math.isfinite(guess):
        return [math.exp(a + (b - a) / 3), math.exp(a + 2 * (b - a) / 3)]
    if b - a > 4.002 * half:  # a root guessed within half the precision of an end: that end is known already, so the pair
        # steps in from it, ``precision`` and twice it (each probe closes the bracket with the end or the other probe)
        if guess < a + 1.001 * half:
            return [math.exp(a + 2 * half), math.exp(a + 4 * half)]
        if guess > b - 1.001 * half:
            return [math.exp(b - 2 * half), math.exp(b - 4 * half)]
    guess = min(max(guess, a + 1.001 * half), b - 1.001 * half)
    return [math.exp(guess - half), math.exp(guess + half)]


def _root(points: list[tuple[float, float]]) -> float:
    """Where the curve through ``points`` (``(log T, excess)``) meets zero: ``log T`` as a polynomial in the excess
    (inverse interpolation, Lagrange's form) at zero; ``nan`` where two excesses are equal."""
    total = 0.0
    for i, (x, f) in enumerate(points):
        term = x
        for j, (_, g) in enumerate(points):
            if j != i:
                if f == g:
                    return math.nan
                term *= g / (g - f)
        total += term
    return total


def evaluated(excess: Callable[[float], float], durations: list[float], seen: dict[float, float],
              before: Callable[[float], None] | None = None, together: bool = True) -> None:
    """A function of durations computed two at a time.

    ``seen`` updated with ``excess`` of each of ``durations`` not in it: the others on a second thread while the first is
    computed in this one (``together``; HPIPM lets the GIL go), else one after the other. ``before`` is called for each
    first, in this thread and in order; where it raises at one, those before it are computed (and kept) and then it is
    raised.

    Parameters
    ----------
    excess : callable
        A duration's value (computed once each).
    durations : list of float
        The durations (s).
    seen : dict
        The values computed so far, updated.
    before : callable, optional
        Called with each duration before it is computed (a search's account of its work).
    together : bool, optional
        Two threads (the default) or one.
    """
    from concurrent.futures import ThreadPoolExecutor

    durations = [t for t in dict.fromkeys(durations) if t not in seen]
    stopped: BaseException | None = None
    asked = []
    for t in durations:
        try:
            if before is not None:
                before(t)
        except Exception as exc:  # noqa: BLE001 (the caller's own: raised once the ones before are kept)
            stopped = exc
            break
        asked.append(t)
    if together and len(asked) > 1:
        with ThreadPoolExecutor(max_workers=1) as second:
            later = [second.submit(excess, t) for t in asked[1:]]
            seen[asked[0]] = excess(asked[0])
            for t, future in zip(asked[1:], later):
                seen[t] = future.result()
    else:
        for t in asked:
            seen[t] = excess(t)
    if stopped is not None:
        raise stopped


#: A table planned within a deflection bound holds it this share inside at the rows: between them the link bends a
#: little more (measured on the 3 mm strip's fastest move at 2 ms: 1.1e-4 of the bound).
DEFLECTION_INSIDE = 1e-3


def deflection_row(form: Any, bound: float) -> tuple[FloatArray, float]:
    """A link's elastic deflection at its output as a state row.

    The row and its bound (:attr:`inversion.chain.programme.Chain.deflection`): ``y - x_out theta``: the output's row
    less ``x_out`` times the hub angle's (the link's state starts with it).

    Parameters
    ----------
    form : NormalForm
        A link's normal form.
    bound : float
        The bound (m).
    """
    row = np.asarray(form.C, dtype=float).reshape(-1).copy()
    row[0] -= float(form.output_at or 1.0)
    return row, float(bound)


def _rounded(value: float, direction: int) -> float:
    """``value`` to three digits, rounded up (``direction`` 1) or down (-1)."""
    digits = 10.0 ** (math.floor(math.log10(value)) - 2)
    step = math.ceil(value / digits - 1e-9) if direction > 0 else math.floor(value / digits + 1e-9)
    return round(step * digits, 12)


def _programme(form: Any, trajectory: Trajectory, period: float, after: float, need: float, T: float, R: float) -> Chain:
    """The module docstring's programme as a chain: every period of the move and of the horizon ``after`` it, the inputs
    free within ``T`` and ``R`` throughout, ``E`` minimised, the zero directions bounded at the last row."""
    K = max(1, math.ceil(trajectory.duration / period - 1e-9))
    M = K + max(1, math.ceil(after / period - 1e-9))
    N = form.n_states
    check_size(M, N, False, period, trajectory.duration + after, "the bounded causal limit of this move", linear=True)
    t0, tf = trajectory.t0, trajectory.tf
    times = t0 + np.arange(M + 1) * period
    y = trajectory.derivative(np.clip(times, t0, tf), 0)
    x0 = np.asarray(form.state(np.array([float(y[0])]), np.zeros(1), np.zeros((1, form.n_internal)))[0], dtype=float)
    before = float(form.equilibrium_input(float(y[0])))
    Ad, Bd = zero_order_hold(form.A, form.B, period)
    # each state in units of its size when a torque of the rigid need's size drives the plant over the move (a flexible
    # mode's coordinate is 1e-5 of the hub's angle)
    run = np.arange(M) * period
    size = Chain.state_sizes(Ad, Bd, need * np.sin(2 * np.pi * run / trajectory.duration) * (run <= trajectory.duration))
    return Chain(Ad=Ad, Bd=Bd, C=np.asarray(form.C, dtype=float), x0=x0, before=before, y=y, K=M, hold=None, error=None, peak=T,
                 rate=R, size=size, input_scale=max(need, 1e-300), output_scale=abs(trajectory.move()) or 1.0, terminal=True)


#: The last bounded causal limits computed, with the model and move they are of (the same objects: compared by identity).
_KEPT: list[tuple[Any, Any, tuple[Any, ...], "BoundedLimit | None"]] = []


def bounded_at(problem: Any, period: float, bound: float | None, say: Any, solving: Callable[[], None] | None = None,
               solved: Callable[[float], None] | None = None) -> "BoundedLimit | None":
    """A problem's bounded causal limit, kept for its model and move.

    The bounded causal limit of a problem at the controller's period and a tip bound, or ``None`` where there is no bound
    or the programme is too large or not solved (the methods that plan a table are then tried all the same).

    Kept for the model and move it is of: ``compare`` and the automatic choice ask again for each method.

    Parameters
    ----------
    problem : Problem
        The model, the move, the bounds and the window.
    period : float
        The controller's period (s).
    bound : float or None
        The tip bound (m).
    say : callable
        The progress display.
    solving, solved : callable, optional
        As :func:`bounded_limit`'s (called only where the limit is computed here).
    """
    if bound is None:  # no bound judged: nothing to rule out
        return None
    model, trajectory = problem.system, problem.trajectory
    key = _key(problem, period, bound)
    for kept_model, kept_trajectory, kept_key, kept in _KEPT:
        if kept_model is model and kept_trajectory is trajectory and kept_key == key:
            return kept
    if unbounded(problem):
        say("the bounded causal limit: not asked (neither the torque nor its change between rows is bounded: the causal "
            "limit stands for it)")
        _keep(problem, period, bound, None)
        return None
    say(f"the least error within the torque and rate bounds at {1e3 * period:.3g} ms (a chain programme)")
    try:
        found = bounded_limit(model, trajectory, problem.criteria(bound, period=period, hold="zoh", loop=None),
                              max_deflection=_deflection(problem), solving=solving, solved=solved)
    except (InversionError, SettingsError) as exc:
        say(f"the bounded causal limit: not computed ({exc})")
        found = None
    _keep(problem, period, bound, found)
    return found


def unbounded(problem: Any) -> bool:
    """Whether a problem bounds neither the torque nor its rate.

    Whether a problem bounds neither the torque nor its change between rows (both given as infinite, no deflection
    bound). The bounded causal limit is then no bounded question: its programme holds only the tip, and its inputs, free
    of any bound, run to the size of the held plant's inverse at the rows (an unstable zero's, ``e^{z DT}`` a row), where
    its interior point converged slowly and not to its digits (``(2 - s)/((s + 1)^3 (s + 2))``, 1 in 6 s at 1 ms: 420
    iterations, 26 s, ``E*`` still 0.5 % above the causal limit it approaches). The causal limit
    (:mod:`inversion.lti.causal_limit`) stands for it.

    Parameters
    ----------
    problem : Problem
        The model, the move and the bounds.
    """
    torque, rate = getattr(problem, "max_torque", None), getattr(problem, "max_torque_rate", None)
    return (torque is not None and rate is not None and math.isinf(torque) and math.isinf(rate)
            and _deflection(problem) is None)


def _deflection(problem: Any) -> float | None:
    """The problem's bound on a link's deflection (given, or the shortest move's), if any: the table is planned and
    judged within it, so the limit that rules tables out is too."""
    bounds = getattr(problem, "bounds", None)
    return None if bounds is None or not getattr(problem, "link", False) else bounds.max_deflection


def _key(problem: Any, period: float, bound: float) -> tuple[Any, ...]:
    """What a kept bounded limit is of, beside its model and move."""
    return (period, bound, problem.window, problem.max_torque, problem.max_torque_rate, _deflection(problem))


def _keep(problem: Any, period: float, bound: float, found: "BoundedLimit | None") -> None:
    _KEPT.insert(0, (problem.system, problem.trajectory, _key(problem, period, bound), found))
    del _KEPT[4:]


def keep_bounded(problem: Any, found: BoundedLimit) -> None:
    """Keep a bounded limit computed elsewhere for :func:`bounded_at`.

    The shortest move's, of the duration whose table it then asks for (the same programme, not solved twice). Only one
    within its bound, computed at the problem's period within the problem's deflection bound: what :func:`bounded_at`
    computes itself.

    Parameters
    ----------
    problem : Problem
        The model, the move (the very trajectory object the table is then asked of) and the bounds.
    found : BoundedLimit
        Its bounded causal limit at the problem's period.
    """
    if found.bound is not None and not found.exceeds and found.period == problem.period:
        _keep(problem, problem.period, found.bound, found)

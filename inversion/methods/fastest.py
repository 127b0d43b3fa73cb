"""The fastest move of any profile within the drive's bounds, certified, with its table (issue 57, item 3).

:mod:`inversion.methods.shortest` finds the shortest move of a given profile. Here the tip's path is free too: a
rest-to-rest move by a distance ``D`` whose tip, from the move's end ``t_f = K DT`` on, stays within the bound ``E`` of the
target through the window ``W``, the torque and its change between the controller's rows within the drive's absolute
bounds, and a link's elastic deflection at its output within ``delta`` (the linear model's small deflections:
:func:`inversion.methods.shortest.deflection_bound`). On the plant held at the controller's period, from rest, with ``K``
rows of input and the input that holds the plant at rest on the target after them (a chain programme,
:mod:`inversion.chain.programme`, its rows during the move left free)::

    minimise    E
    subject to  |C x_k - (y_0 + D)| <= E              k = K .. K + W / DT   (the move's end and the window)
                |u_k| <= T,  |u_k - u_{k-1}| <= R      (u_{-1} the input at rest before, u_k = u_hold from K on)
                |C x_k - x_out theta_k| <= delta       every row
                the move's unstable zeros bounded at the last row

Its least ``E*(K)`` is at most the bounded limit of any profile of that distance and duration (their rows during the
move are dropped), and it cannot rise with ``K`` (a table of fewer rows is one of more, held at ``u_hold`` sooner): the
least ``K`` with ``E*(K)`` within the bound (:func:`_least_rows`) is the fastest move -- at ``K - 1`` rows no causal table
of any profile exists, a certificate to the row. It is computed for the link alone: a table held in the joint PD's loop
too holds alone. With a margin the rows are found again for the tube ``(1 - margin) E``.

The table (:func:`_rest_rows`): the smoothest within every bound (least sum of squared changes between rows) that brings
the link to rest on the target at the move's end, its tip within the tube through the window, at the least rows that
can (a row fewer cannot), planned for both loops where the joint PD is judged (the link stacked with its loop,
:class:`inversion.methods.ocp.Stacked`). Its tip's path, at the rows and half-way between them (the degree-5 spline
through them, :func:`inversion.signals.trajectory.from_samples`, ending on the target), is the move's trajectory, and
the door judges the table as an optimal-control table (:class:`_Planned`: the held rows, the window, more modes, the
loop, the margin); where the judgement refuses it, the move is planned again a little longer. With a spread of the
link's values (``uncertainty``) or a ``method`` given, that method inverts the path instead. Beside the move the summary
reports the rigid body's bang-bang floor, the shortest smoothstep's certified bracket
(:func:`inversion.methods.bounded_limit.bounded_limit`) and the rigid bang-bang shaped by a ZV shaper on the first
flexible mode, time-optimal input shaping's answer (:func:`zv_bang_bang`).
"""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from ..acceptance import demand, window_length
from ..chain.programme import Chain, ChainResult, check_size
from ..errors import InversionError, SettingsError
from ..lti.discrete import recurrence, zero_order_hold
from ..options import as_method
from ..problem import Loop, Problem
from ..result import InversionResult
from ..signals.trajectory import MAX_SPLINE_SAMPLES, from_samples, smoothstep
from ..threads import one_thread
from .judged import bending, solve
from .ocp import RATE_INSIDE, OptimalControl, Stacked, between_rows, held_maps, held_result, loop_motor, rest_state_of
from .bounded_limit import DEFLECTION_INSIDE, bounded_limit, deflection_row
from .shortest import LONGEST, PRECISION, ShortestMove, duration_bracket, rigid_bang_bang, TRIES, absolute_bound, deflection_bound

__all__ = ["fastest_move", "free_limit", "zv_bang_bang", "SMOOTHSTEP_ORDER"]

FloatArray = NDArray[np.float64]
#: The smoothstep the fastest move is compared with (its order: the command line's default).
SMOOTHSTEP_ORDER = 5
#: The shortest smoothstep beside the fastest move is bracketed to this relative width (a figure to compare with, not a
#: move returned: on paper-sim's link 10 programmes where :data:`inversion.methods.shortest.PRECISION` took 12).
BESIDE_PRECISION = 0.02


@dataclass(frozen=True)
class _Free:
    """The free move's data: the plant the plan holds (the link alone, or alone and in its joint PD loop at once), held
    at the period, its ends, the drive's bounds and the window's rows."""

    form: Any  # the nominal plant's normal form
    plan: Any  # what the programme holds: the form, or the form stacked with its joint PD loop (inversion.methods.ocp)
    Ad: FloatArray
    Bd: FloatArray
    period: float
    start: float
    target: float
    before: float
    hold: float
    max_torque: float
    max_rate: float
    after: int
    max_deflection: float | None = None

    @classmethod
    def of(cls, problem: Problem, distance: float, max_deflection: float | None = None, alone: bool = False) -> "_Free":
        form = problem.form
        period = float(problem.period)
        start = float(problem.trajectory.y_start)
        # with the joint PD judged (and not ``alone``), the table is planned for both loops (the PD closed on the plan's own
        # hub angle and rate, held over each period: the optimal-control programme's loop plant)
        plan = form if problem.gains is None or alone else Stacked.of(form, (), problem.gains)
        Ad, Bd = held_maps(plan, period)
        after = max(1, math.ceil(window_length(form, problem.window) / period - 1e-9))
        return cls(form, plan, Ad, Bd, period, start, start + distance, float(form.equilibrium_input(start)),
                   float(form.equilibrium_input(start + distance)), float(problem.max_torque or 0.0),
                   float(problem.max_torque_rate or 0.0), after,
                   max_deflection)

    @property
    def loops(self) -> str:
        """The loops the plan holds, in words."""
        return "with the feedforward alone" if self.plan is self.form else "alone and with the joint PD"

    def chain(self, rows: int, inside: float = 0.0, error: float | None = None, rest: bool = False) -> Chain:
        """The programme of the module docstring with ``rows`` rows of input (the rate bound ``inside`` of it inside); with
        ``error``, the smoothest table (least sum of squared changes between rows) holding the tip within it instead; with
        ``rest``, the link at rest on the target at the move's end (then the link alone needs one row after it: at rest
        it stays)."""
        M = rows + (1 if rest and self.plan is self.form else self.after)
        N = self.plan.n_states
        check_size(M, N, False, self.period, M * self.period, "the fastest move's programme",
                   rows=8 + 4 * (int(np.atleast_2d(self.plan.C).shape[0]) - 1), linear=error is None)
        y = np.full(M + 1, np.nan)
        y[0], y[rows:] = self.start, self.target
        run = np.arange(M) * self.period
        drive = self.max_torque * np.sin(2 * np.pi * run / (rows * self.period)) * (run <= rows * self.period)
        x0 = np.asarray(self.plan.state(np.array([self.start]), np.zeros(1), np.zeros((1, self.form.n_internal)))[0], dtype=float)
        return Chain(Ad=self.Ad, Bd=self.Bd, C=np.asarray(self.plan.C, dtype=float), x0=x0, before=self.before, y=y, K=rows,
                     hold=self.hold, error=error, peak=self.max_torque, rate=self.max_rate * (1 - inside),
                     size=Chain.state_sizes(self.Ad, self.Bd, drive), input_scale=self.max_torque,
                     output_scale=(abs(self.target - self.start) or 1.0) if error is None else error,
                     terminal=self.plan is self.form and not rest, deflection=self.bend(inside=error is not None),
                     smoothness=0.0 if error is None else 1.0, rest=rest_state_of(self.plan, self.target) if rest else None,
                     rest_at=rows if rest else None, motor=None if self.plan is self.form else
                     loop_motor(self.plan, self.Ad, self.Bd, self.hold, self.target, self.max_torque, self.max_rate))

    def bend(self, inside: bool = False) -> tuple[FloatArray, float] | None:
        """The deflection's rows and bound (:attr:`inversion.chain.programme.Chain.deflection`), where one is asked: each
        plant's, the link alone and in the loop; for a table (``inside``), a hair inside the bound (between the rows too,
        :data:`inversion.methods.bounded_limit.DEFLECTION_INSIDE`)."""
        if self.max_deflection is None:
            return None
        row, bound = deflection_row(self.form, self.max_deflection * (1 - DEFLECTION_INSIDE if inside else 1.0))
        N = self.form.n_states
        copies = self.plan.n_states // N
        rows = np.zeros((copies, copies * N))
        for i in range(copies):
            rows[i, i * N:(i + 1) * N] = row
        return rows, bound

    def path(self, rows: int, found: ChainResult) -> Any:
        """The tip's path the programme's table gives: its rows and half-way points over the move, the target at its end."""
        if 2 * rows + 1 > MAX_SPLINE_SAMPLES:
            raise SettingsError("period", self.period, f"a longer period for a move of {rows} rows: its path's spline goes through "
                                f"at most {MAX_SPLINE_SAMPLES} points, two a row")
        form, h = self.form, self.period
        Ad, Bd = zero_order_hold(form.A, form.B, h)
        X, _ = recurrence(Ad, Bd[:, None], self.x0(), np.asarray(found.u, dtype=float)[:, None])
        Ah, Bh = zero_order_hold(form.A, form.B, h / 2)
        C = np.asarray(form.C, dtype=float)
        rows_tip = X[:rows] @ C
        half = (X[:rows] @ Ah.T + np.outer(found.u, Bh)) @ C
        t = np.empty(2 * rows + 1)
        y = np.empty(2 * rows + 1)
        t[0:-1:2], t[1::2], t[-1] = np.arange(rows) * h, (np.arange(rows) + 0.5) * h, rows * h
        y[0:-1:2], y[1::2], y[-1] = rows_tip, half, self.target
        return from_samples(t, y, f"the fastest move's path ({self.target - self.start:g} in {rows * h:.6g} s)")

    def x0(self) -> FloatArray:
        """The nominal plant at rest on the start."""
        return np.asarray(self.form.state(np.array([self.start]), np.zeros(1), np.zeros((1, self.form.n_internal)))[0], dtype=float)


def free_limit(problem: Problem, distance: float, rows: int) -> float:
    """The least tip error after a move of any profile in K rows.

    Within the drive's bounds, ``K`` rows of the controller: ``E*(K)`` of the module docstring: no causal feedforward
    held at the problem's period, within its absolute torque and rate bounds, holds the tip closer to the target from
    the move's end through the window.

    Parameters
    ----------
    problem : Problem
        The model, the period, the window and the absolute bounds (its trajectory gives the start).
    distance : float
        The move.
    rows : int
        The rows of input (the move lasts ``rows`` periods).

    Raises
    ------
    InversionError
        Where HPIPM does not solve the programme.
    """
    return float(_Free.of(problem, distance).chain(int(rows)).solve().error)


def fastest_move(problem: Problem, distance: float | None = None, method: Any = None, say: Callable[[str], None] | None = None
                 ) -> InversionResult:
    """The fastest move of any profile, and its table.

    Within the drive's absolute bounds, certified by the free move's programme (module docstring).

    Parameters
    ----------
    problem : Problem
        The model, the bounds (absolute: given, or the model's ``[drive]``; a ``max_deflection`` at every row of the
        move and the window), the sampling, the loop, the margin; its trajectory's start is the move's (and its distance
        the default ``distance``).
    distance : float, optional
        The move (default: the problem's trajectory's).
    method : InversionMethod or str, optional
        The method the table of the path is asked of (default: optimal control).
    say : callable, optional
        The progress display.

    Returns
    -------
    InversionResult
        The move's result, judged like any other, its trajectory the path; ``summary["shortest"]`` the figures
        (:meth:`inversion.methods.shortest.ShortestMove.as_dict`, ``profile`` ``"free"``, ``beside``: the shortest
        smoothstep's bracket and the ZV-shaped bang-bang).

    Raises
    ------
    SettingsError
        Without absolute torque bounds, or a bound not below the move.
    InversionError
        Where no move up to :data:`inversion.methods.shortest.LONGEST` times the rigid floor meets the bound, or no table
        is found just above the fastest, with the figures.
    """
    say = say or (lambda message: None)
    distance = float(problem.trajectory.move() if distance is None else distance)
    bound = absolute_bound(problem, distance, method)
    problem, max_deflection, deflection_rule = deflection_bound(problem)
    free = _Free.of(problem, distance, max_deflection)
    # the certificate is the feedforward's alone (a table that holds in the loop too holds alone): a smaller programme
    alone = free if free.plan is free.form else _Free.of(problem, distance, max_deflection, alone=True)
    h = free.period
    floor = rigid_bang_bang(problem)
    curve: dict[int, float] = {}

    def limit(rows: int) -> float:
        if rows not in curve:
            try:
                found = alone.chain(rows).solve()
            except SettingsError:  # beyond one solve's size (naming the period that fits): no longer move is computed either
                raise
            except InversionError as exc:
                say(f"fastest: {rows * h:.4g} s not computed ({exc})")
                curve[rows] = math.inf
            else:
                curve[rows] = max(float(found.error), 0.0)
                say(f"fastest: in {rows * h:.4g} s the tip can be within {curve[rows]:.3g} after the move")
        return curve[rows]

    say(f"fastest: the rigid body's bang-bang floor with this drive is {floor:.4g} s; the rows of the fastest move of any profile")
    # the search gives up beyond LONGEST times the rigid floor or the move asked (a system has no floor)
    longest = max(8, math.ceil(LONGEST * max(floor, problem.trajectory.duration, 4 * h) / h))
    grow = 1.1 if floor > 0 else 2.0  # a tenth more a step above a rigid floor; doubled from a few rows without one
    upper = _least_rows(limit, bound, max(2, math.ceil(floor / h)), longest, h, grow=grow)
    aimed = upper if problem.kept <= 0 else _least_rows(limit, bound * (1 - problem.kept), upper + 1, longest, h, known=curve, grow=grow)
    lower = max((k for k, e in curve.items() if k < upper and not e <= bound), default=0)
    found = ShortestMove(lower * h, curve.get(lower, math.inf), upper * h, aimed * h, aimed * h, bound, problem.kept, floor)
    found.profile = "free"
    # (a spread of the link's values: optimal control plans the path's table for its corners too, where the plan is the
    # nominal link's)
    chosen = as_method(method) if method is not None else OptimalControl() if problem.corners is not None else None
    tube = bound * (1 - problem.kept)
    result, rows = None, aimed
    # the shortest smoothstep beside it needs only the certified lower bound: its bounded limits (HPIPM, which releases
    # the GIL) are computed on a second thread while the table is planned and judged, every BLAS pool at one thread (the
    # same bits whichever thread runs when), its progress said after
    heard: list[str] = []
    with one_thread(), ThreadPoolExecutor(max_workers=1) as second:
        beside = second.submit(_beside, problem, free, distance, bound, lower * h, heard.append)
        for attempt in range(TRIES):
            try:
                # (a move whose least error after it is nothing leaves the link at rest: a row count that can end at rest)
                still = min((k for k, e in curve.items() if k > rows and e <= 1e-9 * abs(distance)), default=None)
                rows, table = _rest_rows(alone, free, rows, tube, longest, say, still)
                say(f"fastest: the table of the move in {rows * h:.4g} s")
                path = free.path(rows, table)
                given = chosen if chosen is not None else _Planned(table=_table_result(problem, free, path, table, bound))
                result = solve(replace(problem, trajectory=path), given, say)
            except (InversionError, SettingsError) as exc:
                found.tried.append({"duration": rows * h, "status": getattr(exc, "status", "failed"), "message": str(exc)})
                rows += max(1, math.ceil(rows * PRECISION * 2 ** min(attempt, 4)))
                continue
            found.tried.append({"duration": rows * h, "status": "passed", "method": result.summary["method"]})
            break
        found.beside = beside.result()
    for line in heard:
        say(line)
    found.curve = sorted((k * h, e) for k, e in curve.items())
    if result is None:
        failure = InversionError(f"no table found for a path up to {rows * h:.4g} s ({found.sentence()}); the last: "
                                 f"{found.tried[-1]['message'] if found.tried else 'none planned'}")
        failure.shortest = found.as_dict()  # type: ignore[attr-defined]
        raise failure
    found.duration = rows * h
    result.summary["shortest"] = {**found.as_dict(), **bending(result), "max_deflection": max_deflection,  # type: ignore[typeddict-unknown-key]
                                  "max_deflection_rule": deflection_rule, "rest_cost": found.duration / found.aimed - 1.0}
    return result


def _rest_rows(alone: _Free, free: _Free, start: int, tube: float, longest: int, say: Callable[[str], None],
               still: int | None = None) -> tuple[int, ChainResult]:
    """The least rows from ``start`` with a table that ends at rest, and that table.

    The smoothest table (least sum of squared changes between rows) within every bound that brings the link to rest on
    the target at the move's end, its tip within ``tube`` of it through the window, a hair inside the rate bound (the
    optimal control's own). Near the least rows at which the tip can be within ``tube`` after the move it cannot yet be
    at rest: the link alone (``alone``, a programme of the move and one row) is tried at ``start``, then at ``still``
    (rows whose least error after the move is nothing, where known) or 1, 2, 4, ... rows more until one is solved, then
    bisected to the row; the table is then planned for ``free``'s plants (with the
    joint PD loop: its references the plan's own states, at rest after the move as the loop a controller runs holds
    them, its tip within ``tube`` through the window), a row more where that is not solved.
    """
    solved: dict[int, ChainResult | None] = {}

    def at(rows: int) -> ChainResult | None:
        if rows not in solved:
            try:
                solved[rows] = alone.chain(rows, inside=RATE_INSIDE, error=tube, rest=True).solve()
            except InversionError:
                solved[rows] = None
        return solved[rows]

    low, step, high = start - 1, 1, start
    if still is not None and at(start) is None and at(still) is not None:
        low, high = start, still
    while at(high) is None:
        low, high, step = high, high + step, 2 * step
        if high > longest:
            raise InversionError(f"no table ends at rest within every bound up to {low * free.period:.4g} s (its tip within "
                                 f"{tube:.4g} after the move)")
    if high - low > 1:
        say(f"fastest: a table at rest at the move's end in {high * free.period:.4g} s; the least rows for one")
    while high - low > 1:
        middle = (low + high) // 2
        if at(middle) is None:
            low = middle
        else:
            high = middle
    if free is alone:
        found = solved[high]
        assert found is not None
        return high, found
    return _loop_rows(free, high, tube)


def _loop_rows(free: _Free, high: int, tube: float) -> tuple[int, ChainResult]:
    """The table for both loops at the least of ``high``, ``high + 1``, ``+ 2``, ``+ 4``, ``+ 8`` rows that has one
    (:func:`_rest_rows`; the loop's tip through the window too).

    Two at a time: the next on a second thread while this one is solved (HPIPM releases the GIL; each programme is its
    own, so the table is the one the rows tried in turn would give, bit for bit). A programme not solved runs to HPIPM's
    first iteration limit, half as long again as one solved: on the 3 mm strip's fastest move in both loops at 2 ms the
    loops are solved at the third (measured: the command 0.89 x the wall time of the rows tried in turn).
    """
    def solved(rows: int) -> ChainResult | InversionError:
        try:
            return free.chain(rows, inside=RATE_INSIDE, error=tube, rest=True).solve()
        except InversionError as exc:
            return exc

    tries = (high, high + 1, high + 2, high + 4, high + 8)
    last: InversionError | None = None
    ahead = ThreadPoolExecutor(max_workers=1)
    try:
        for rows, following in zip(tries[::2], (*tries[1::2], None)):
            later = None if following is None else ahead.submit(solved, following)
            found = solved(rows)
            if isinstance(found, ChainResult):  # (the one beside it not waited for)
                return rows, found
            last = found
            if later is not None:
                found = later.result()
                if isinstance(found, ChainResult):
                    return following, found  # type: ignore[return-value]
                last = found
    finally:  # (a programme still solving for a table already found is left to end on its own)
        ahead.shutdown(wait=False, cancel_futures=True)
    raise InversionError(f"no table for both loops ends at rest within every bound in {high * free.period:.4g} to "
                         f"{(high + 8) * free.period:.4g} s ({last})")


@dataclass(frozen=True)
class _Planned(OptimalControl):
    """Optimal control whose table is the fastest move's own (planned before, :func:`_rest_rows`): the door judges it as
    any optimal-control table (not registered: no method of its own)."""

    table: Any = field(default=None, repr=False, compare=False)

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The table planned.

        Parameters
        ----------
        problem : Problem
            The move (its path).
        say : callable
            The progress display.
        """
        return self.table


def _table_result(problem: Problem, free: _Free, path: Any, table: ChainResult, bound: float) -> InversionResult:
    """The planned table as an optimal-control result ending at rest (judged: the held rows, the window, more modes, the
    loop)."""
    form, h = free.form, free.period
    rows = table.u.size
    u = np.asarray(table.u, dtype=float)
    Ad, Bd = zero_order_hold(form.A, form.B, h)
    drive = np.concatenate([u, np.full(free.after, free.hold)])
    X, _ = recurrence(Ad, Bd[:, None], free.x0(), drive[:, None])
    times = path.t0 + np.arange(X.shape[0]) * h
    y_d = path.derivative(np.clip(times, path.t0, path.tf), 0)
    between = between_rows(form, X[:-1], drive, times, path, h)
    rigid = demand(form, path, h).rigid_torque
    stats = {**table.record(), "attempts": [], "margin": problem.kept, "aimed": float(table.error), "margins_tried": [],
             "planned": f"the fastest move's table, the smoothest of {rows} rows within the bounds, {free.loops}"}
    return held_result(problem.system, form, path, u, X, times, y_d, h, float(bound), "torque", "rest",
                   window_length(form, problem.window), stats, 0.0, rigid, problem.criteria(bound, hold="zoh"), between)


def _least_rows(limit: Callable[[int], float], bound: float, start: int, longest: int, step: float,
                known: dict[int, float] | None = None, grow: float = 2.0) -> int:
    """The least rows whose limit meets ``bound``.

    From ``start`` (``known``: the limits computed before; ``step``: a row's seconds, for the messages), each next try
    where the line through the two longest failing moves tried crosses the bound (the limit falls nearly as a line
    there, and reaches 0 soon after: a line through a feasible point would aim far past it), rounded up; ``grow`` times
    the longest failing move while there is no such line and no feasible move (the caller's 1.1 above a rigid floor:
    the fastest move is seldom far above it), at most twice it; bisected where the line aims outside the bracket or a
    guess repeats. Measured on the 3 mm strip (the bound's search and the margin's): 8 programmes, where doubling with
    bisection took 21 and regula falsi 15.
    """
    failed = {k: v for k, v in (known or {}).items() if not v <= bound}
    low = max(failed, default=0)
    high = min((k for k, v in (known or {}).items() if v <= bound and k > low), default=None)
    rows = max(1, start)
    for _ in range(4 * max(8, longest.bit_length() * 4)):
        value = limit(rows)
        if value <= bound:
            high = rows if high is None else min(high, rows)
        else:
            failed[rows] = value
            low = max(low, rows)
        if high is not None and high - low <= 1:
            return high
        if high is None and low >= longest:
            raise InversionError(f"no move up to {low * step:.4g} s meets the bound {bound:.4g} within the torque, rate and "
                                 f"deflection bounds (the least error after the move there is {limit(low):.4g}): a larger max_error, "
                                 "stronger bounds or a larger max_deflection")
        tail = sorted(k for k, v in failed.items() if math.isfinite(v))[-2:]
        guess = None
        if len(tail) == 2 and failed[tail[0]] > failed[tail[1]]:
            (k1, e1), (k2, e2) = ((k, failed[k]) for k in tail)
            guess = math.ceil(k2 + (e2 - bound) * (k2 - k1) / (e1 - e2) - 1e-9)
        if high is None:
            grown = math.ceil(grow * max(low, rows))
            rows = min(longest, max(low + 1, min(guess, 2 * max(low, 1)) if guess is not None else grown))
        elif low == 0:
            rows = high // 2
        elif guess is not None and low < guess < high and guess not in failed:
            rows = guess
        else:  # the line aims past the bracket (through a plateau of the limit): halved
            rows = (low + high) // 2
    raise InversionError(f"the shortest move meeting the bound {bound:.4g} was not found between {low * step:.4g} s and "
                         f"{(high or longest) * step:.4g} s")


def _beside(problem: Problem, free: _Free, distance: float, bound: float, lower: float, say: Callable[[str], None]
            ) -> dict[str, Any]:
    """What the other answers cost: the shortest smoothstep's certified bracket and the ZV-shaped bang-bang."""
    out: dict[str, Any] = {}
    order = SMOOTHSTEP_ORDER
    curve: dict[float, float] = {}
    criteria = problem.criteria(bound, hold="zoh", loop=None)

    def limit(duration: float) -> float:
        if duration not in curve:
            try:
                curve[duration] = float(bounded_limit(problem.system, smoothstep(distance, duration, order, free.start), criteria,
                                                      shortest=False, max_deflection=free.max_deflection).error)
            except (InversionError, SettingsError):
                curve[duration] = math.inf
        return curve[duration]

    say(f"fastest: beside it, the shortest smoothstep of order {order}")
    try:
        low, high = duration_bracket(limit, bound, max(lower, 4 * free.period), max(rigid_bang_bang(problem), lower), BESIDE_PRECISION,
                                     together=False)  # (beside the fastest move's own search: one thread)
        out["smoothstep"] = {"order": order, "lower_bound": low, "upper": high}
    except InversionError as exc:
        out["smoothstep"] = {"order": order, "status": str(exc)}
    shaped = zv_bang_bang(problem, distance, bound)
    if shaped is not None:
        out["zv_bang_bang"] = shaped
    return out


def zv_bang_bang(problem: Problem, distance: float, bound: float) -> dict[str, Any] | None:
    """The rigid bang-bang shaped by a ZV shaper on the first mode.

    At the peak torque, on the model. The bang-bang torque ``+tau, -tau`` over two equal halves of ``n`` rows each
    (``n`` the least with ``tau = J theta / (n DT)^2`` within the peak bound: the hub at rest on ``theta`` at the end),
    convolved with the ZV shaper's two impulses ``1 / (1 + K)`` and ``K / (1 + K)``,
    ``K = exp(-zeta pi / sqrt(1 - zeta^2))``, half the first mode's damped period apart (rounded to the rows).
    Time-optimal input shaping's move: it cancels the first mode's vibration at the joint, not at the tip, and its
    torque steps.

    Parameters
    ----------
    problem : Problem
        A link's problem with absolute bounds.
    distance : float
        The tip's move.
    bound : float
        The tip bound after the move.

    Returns
    -------
    dict or None
        ``duration``, ``error_after`` (the tip's largest distance from the target at the rows from the move's end through
        the window, on the model), ``holds_bound``, ``peak``, ``largest_change``, ``within_rate``, ``mode_frequency`` (Hz),
        ``mode_damping``, ``peak_deflection`` (the link's largest elastic deflection at its output, m); ``None`` for a
        system (no rigid body) or a link without a flexible mode.
    """
    form = problem.form
    inertia = getattr(form, "inertia", None)
    if inertia is None:
        return None
    poles = np.linalg.eigvals(np.asarray(form.A, dtype=float))
    modes = poles[poles.imag > 1e-9 * max(1.0, float(np.abs(poles).max()))]
    if modes.size == 0:
        return None
    first = modes[np.argmin(np.abs(modes))]
    wn = float(abs(first))
    zeta = float(-first.real / wn)
    wd = wn * math.sqrt(max(1.0 - zeta * zeta, 1e-300))
    h = float(problem.period)
    angle = distance / float(form.output_at or 1.0)
    T = float(problem.max_torque)
    n = max(1, math.ceil(math.sqrt(float(inertia) * abs(angle) / T) / h - 1e-9))
    tau = float(inertia) * angle / (n * h) ** 2
    delay = max(1, int(round(math.pi / (wd * h))))
    K = math.exp(-zeta * math.pi / math.sqrt(max(1.0 - zeta * zeta, 1e-300)))
    bang = np.concatenate([np.full(n, tau), np.full(n, -tau)])
    rows = 2 * n + delay
    u = np.zeros(rows)
    u[: 2 * n] += bang / (1 + K)
    u[delay:] += bang * K / (1 + K)
    free = _Free.of(replace(problem, loop=Loop(controller="none")), distance)  # the feedforward alone
    drive = np.concatenate([u, np.full(free.after, free.hold)])
    X, _ = recurrence(free.Ad, free.Bd[:, None], free.x0(), drive[:, None])
    tip = X[rows:] @ np.asarray(form.C, dtype=float)
    error = float(np.abs(tip - free.target).max())
    change = float(np.abs(np.diff(np.concatenate([[free.before], u, [free.hold]]))).max())
    bends = float(np.abs(X @ deflection_row(form, 1.0)[0]).max())
    limit = problem.bounds.max_deflection
    return {"duration": rows * h, "error_after": error, "holds_bound": error <= bound, "peak": float(np.abs(u).max()),
            "within_deflection": None if limit is None else bends <= limit,
            "largest_change": change, "within_rate": change <= float(problem.max_torque_rate), "mode_frequency": wd / (2 * math.pi),
            "mode_damping": zeta, "peak_deflection": bends}

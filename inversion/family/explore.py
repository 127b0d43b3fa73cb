"""The family explorer: every member of a grid, measured and verified, on local processes or a Dask cluster.

The paper offers "a family of answers" and chooses from it by trial and error.
:func:`explore` evaluates a grid of members (segments x ``h`` x ``Cdec_f`` x ``Cdec_s`` x
joining x how the feedforward ends) with exactly the code :func:`inversion.invert` uses
(:func:`~inversion.family.member.evaluate_members`: the same figures, the same checks, the same
statuses, the same measure of the plant left alone after the feedforward ends), marks the
Pareto front in (redefinition error, peak torque) and the member the automatic choice's rule
takes (:mod:`inversion.family.auto`: by its objective, among the members that meet its bounds --
and that member's whole acceptance, :mod:`inversion.acceptance`, is checked before it is
chosen), and writes ``explore.csv`` and ``best.json``.

Members that share segments, ``h`` and joining are solved as one batch (they differ in
their exponents only); the batches are the units of work. They run in local processes
(``workers``, default all cores), in the calling process (``workers=1``), or on any
executor with ``submit`` -- a :class:`concurrent.futures.Executor` or a
``dask.distributed.Client`` (the optional extra ``sflm[dask]``). Each member costs a
closed-form scan of its segments, not a sampled inversion (see :mod:`inversion.family.figures`);
``invert`` additionally drives the plant with the chosen member's torque.
"""

from __future__ import annotations

import concurrent.futures
import csv
import itertools
import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Sequence

from numpy.typing import ArrayLike

from modelgen.model import Model

from ..acceptance import Criteria, demand, given_rule, larger_model, summary_keys, table_rate
from ..config import DEFAULTS, default, held_period, tip_bound
from ..errors import SettingsError
from ..lti.system import NormalForm, normal_form
from ..options import Edges, End, Joining, Objective, checked
from ..problem import check_period, paper_case
from ..settings import InversionSettings, paper_settings
from ..signals.trajectory import Trajectory
from ..threads import one_thread, worker_count
from .auto import ERROR_TORQUE_MARGIN, objective_key
from .auto import batches as batches_of
from .member import MemberResult, evaluate_member, evaluate_members, member_acceptance, point_table, segment_anchors
from .ssef import SolverName

__all__ = ["explore", "Exploration", "EXPLORE_COLUMNS", "ROBUST_COLUMN", "DEFAULT_GRID", "pareto_front"]

#: Columns of ``explore.csv`` (a contract relied on by scripts).
EXPLORE_COLUMNS = (
    "segments", "h", "cdec_fast", "cdec_slow", "joining", "status", "max_redefinition_error",
    "relative_redefinition_error", "peak_torque", "max_condition_number", "max_constraint_residual",
    "pareto", "chosen", "paper", "message", "end", "torque_ratio", "after_end_excursion", "post_actuation_time",
    "edges", "torque_rate_ratio",
)
#: The column ``explore --uncertainty`` adds (the worst case on the perturbed links, relative to the move).
ROBUST_COLUMN = "worst_case_error"
#: The explorer's default grid: the automatic choice's first grid (:data:`inversion.config.DEFAULTS`).
DEFAULT_GRID: dict[str, tuple[Any, ...]] = DEFAULTS.grid.as_dict()
#: Statuses whose figures are shown (sound members; ``max-torque`` only exceeds the caller's bound).
_SHOWN = ("ok", "max-torque")


@dataclass(frozen=True)
class Exploration:
    """The explored family.

    Attributes
    ----------
    rows : list of dict
        One per member, keys :data:`EXPLORE_COLUMNS` (figures ``None`` for a failed member).
    best : dict or None
        The chosen row: the member the automatic choice's rule takes (:mod:`inversion.family.auto`:
        its objective among the rows within its bounds, whose whole acceptance passes);
        ``None`` if no member does.
    model, trajectory : str
        What was explored.
    grid : dict
        The grid.
    seconds : float
        Wall time.
    workers : str
        Where it ran.
    summary : dict
        ``summary.json``: the counts, the bounds, the choice and its rule (and ``robustness`` once judged on perturbed
        links).
    """

    rows: list[dict[str, Any]]
    best: dict[str, Any] | None
    model: str
    trajectory: str
    grid: dict[str, list[Any]]
    seconds: float
    workers: str
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def succeeded(self) -> list[dict[str, Any]]:
        """The rows with status ``ok``."""
        return [r for r in self.rows if r["status"] == "ok"]

    @property
    def front(self) -> list[dict[str, Any]]:
        """The Pareto-optimal rows, by increasing error."""
        return sorted((r for r in self.rows if r["pareto"]), key=lambda r: r["max_redefinition_error"])

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns of ``explore.csv``: :data:`EXPLORE_COLUMNS`, then ``worst_case_error`` once the family has been judged
        on perturbed links (:func:`inversion.studies.robustness.judge_family`; empty where a member was not judged)."""
        judged = "robustness" in self.summary
        return EXPLORE_COLUMNS + (ROBUST_COLUMN,) if judged else EXPLORE_COLUMNS

    def best_settings(self) -> InversionSettings | None:
        """The best member's settings."""
        return None if self.best is None else _row_settings(self.best)

    def write(self, folder: str | Path) -> list[Path]:
        """Write ``explore.csv``, ``best.json`` and ``summary.json``.

        Write ``explore.csv``, ``best.json`` (if a member succeeded) and ``summary.json``.

        Parameters
        ----------
        folder : str or Path
            An existing folder.

        Returns
        -------
        list of Path
            The files written.
        """
        folder = Path(folder)
        columns = self.columns
        with open(folder / "explore.csv", "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(columns)
            for row in self.rows:
                writer.writerow(["" if row[c] is None else (repr(row[c]) if isinstance(row[c], float) else row[c]) for c in columns])
        files = [folder / "explore.csv"]
        if self.best is not None:
            best = {
                "settings": _row_settings(self.best).to_dict(),
                "model": self.model,
                "trajectory": self.trajectory,
                "trajectory_spec": self.summary.get("trajectory_spec"),
                **{k: self.best[k] for k in ("max_redefinition_error", "relative_redefinition_error", "peak_torque",
                                             "max_condition_number")},
                "objective": self.summary.get("objective", ""),
            }
            (folder / "best.json").write_text(json.dumps(best, indent=1) + "\n")
            files.append(folder / "best.json")
        (folder / "summary.json").write_text(json.dumps(self.summary, indent=1) + "\n")
        files.append(folder / "summary.json")
        return files


def _row_settings(row: dict[str, Any]) -> InversionSettings:
    return InversionSettings(segments=int(row["segments"]), h=int(row["h"]), cdec=(row["cdec_fast"], row["cdec_slow"]),
                             joining=row["joining"], end=row.get("end", "free"), edges=row.get("edges", "match"))


def pareto_front(points: Sequence[tuple[float, float]]) -> list[bool]:
    """The points not dominated in (first, second), both minimised.

    A point is dominated when another is no worse in both coordinates and better in one.

    Parameters
    ----------
    points : Sequence[tuple[float, float]]
        The points ``(first, second)``.
    """
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front = [False] * len(points)
    best_second = math.inf
    for i in order:
        if points[i][1] < best_second:
            front[i] = True
            best_second = points[i][1]
    return front


@dataclass(frozen=True)
class _Context:
    """What a worker needs (plain NumPy: no compiled code crosses the process boundary)."""

    form: NormalForm
    trajectory: Trajectory
    initial_internal_state: Any
    solver: SolverName
    tol: float
    max_error: float | None
    max_torque: float | None
    parent: int
    rigid: float
    window: float | None
    period: float
    rigid_rate: float


def _row(result: MemberResult, paper: InversionSettings | None, rigid: float) -> dict[str, Any]:
    s = result.settings
    shown = result.status in _SHOWN and result.figures is not None
    fig = result.figures
    after = result.after if shown else None
    return {
        "segments": s.segment_count,
        "h": s.h,
        "cdec_fast": s.cdec[0],
        "cdec_slow": s.cdec[1],
        "joining": s.joining,
        "status": result.status,
        "max_redefinition_error": fig.max_error if shown and fig else None,
        "relative_redefinition_error": fig.relative_error if shown and fig else None,
        "peak_torque": fig.peak_torque if shown and fig else None,
        "max_condition_number": result.max_condition_number if shown else None,
        "max_constraint_residual": result.max_constraint_residual if shown else None,
        "pareto": 0,
        "chosen": 0,
        "paper": int(paper is not None and s == paper),
        "message": result.message,
        "end": str(s.end),
        "torque_ratio": fig.peak_torque / rigid if shown and fig and rigid > 0 else None,
        "after_end_excursion": after.max_tip_excursion if after is not None else None,
        "post_actuation_time": (result.tail.length if result.tail is not None else 0.0) if shown else None,
        "edges": str(s.edges),
        "torque_rate_ratio": None,  # judged for the members the choice considers (:func:`_choose`)
    }


def _evaluate_batch(context: _Context, batch: list[InversionSettings], paper: InversionSettings | None) -> list[dict[str, Any]]:
    """Evaluate one batch of members."""
    anchors = segment_anchors(context.form, context.trajectory, batch[0])
    results = evaluate_members(
        context.form, context.trajectory, batch, initial_internal_state=context.initial_internal_state, anchors=anchors,
        solver=context.solver, tol=context.tol, max_error=context.max_error, max_torque=context.max_torque, verify=True,
        window=context.window,
    )
    return [_row(r, paper, context.rigid) for r in results]


_LIMITED: list[Any] = []


def _worker_batch(context: _Context, batch: list[InversionSettings], paper: InversionSettings | None) -> list[dict[str, Any]]:
    """:func:`_evaluate_batch` with the BLAS pools held to one thread (many small products: a
    pool of threads would only spin). A worker process keeps the limit for its life (setting
    it costs milliseconds); in the caller's own process it is undone afterwards."""
    from threadpoolctl import ThreadpoolController

    if os.getpid() == context.parent:
        with one_thread():
            return _evaluate_batch(context, batch, paper)
    if not _LIMITED:
        _LIMITED.append(ThreadpoolController().limit(limits=1))
    return _evaluate_batch(context, batch, paper)


def _choose(model: Any, form: NormalForm, trajectory: Trajectory, ok: list[dict[str, Any]], bounds: Criteria, rigid: float,
            objective: str | None, context: _Context) -> dict[str, Any]:
    """The row the automatic choice's rule takes (:mod:`inversion.family.auto`): by its objective among the rows within its
    bounds (the error, the plant's motion after the feedforward ends, the torque limit), the first whose whole acceptance
    passes (the plant check, more modes, the held table: evaluated again here, in this process)."""
    chosen = checked(Objective, "objective", default("objective", objective))
    limit = bounds.torque_limit(rigid)
    limit_rule = given_rule(bounds) if bounds.max_torque is not None else f"{bounds.torque_ratio:g} x the rigid-body need ({rigid:.4g})"
    within = [r for r in ok if r["max_redefinition_error"] <= bounds.max_error and r["after_end_excursion"] is not None
              and r["after_end_excursion"] <= bounds.max_error]
    if chosen == Objective.ERROR and bounds.max_torque is None and within:
        least = min(r["peak_torque"] for r in within)
        if ERROR_TORQUE_MARGIN * least < limit:
            limit, limit_rule = ERROR_TORQUE_MARGIN * least, f"{ERROR_TORQUE_MARGIN:g} x the least peak torque within the bound ({least:.4g})"
    rate_limit = bounds.rate_limit(context.rigid_rate, form.inertia is not None)[0]
    candidates = [r for r in within if r["peak_torque"] <= limit]
    candidates.sort(key=objective_key(chosen, [r["peak_torque"] for r in candidates]))
    rule = (("least peak torque" if chosen == Objective.TORQUE else "least max |y~ - y_d|")
            + f" among members within {bounds.max_error:.4g} m of y_d during and after the move with peak torque <= {limit:.4g}")
    larger = larger_model(model, bounds.extra_modes)
    judged = stepping = 0
    for row in candidates:
        if judged >= _ACCEPT_LIMIT or stepping >= _RATE_LIMIT:
            break
        member = evaluate_member(form, trajectory, _row_settings(row), initial_internal_state=context.initial_internal_state,
                                 solver=context.solver, tol=context.tol, max_error=bounds.max_error, max_torque=limit, verify=True,
                                 plant=True, window=bounds.window)
        if not member.ok:
            continue
        # the held rows' rate first (the closed form at the rows: milliseconds), the whole acceptance for those within it
        row["torque_rate_ratio"] = table_rate(*point_table(member, bounds.period)) / context.rigid_rate if context.rigid_rate else None
        if row["torque_rate_ratio"] is not None and row["torque_rate_ratio"] * context.rigid_rate > rate_limit * (1 + 1e-9):
            stepping += 1
            continue
        judged += 1
        acceptance, _, _ = member_acceptance(member, form, trajectory, bounds, link=form.inertia is not None, larger=larger)
        if acceptance.failure(bounds, (limit, limit_rule)) is None:
            top, verification = summary_keys(acceptance)
            return {"row": row, "objective": str(chosen), "rule": rule, "limit": limit, "limit_rule": limit_rule,
                    "acceptance": {**top, **verification}}
    during = [r for r in ok if r["max_redefinition_error"] <= bounds.max_error]
    ends = sorted({str(r["end"]) for r in ok}) or ["free"]
    if not during:
        why = f"no verified member is within {bounds.max_error:.4g} m of y_d during the move"
    elif not within:
        why = (f"{len(during)} verified members are within {bounds.max_error:.4g} m of y_d during the move, and every one strays "
               f"further after it (the link left with the torque ended)")
        if ends == ["free"]:
            why += "; the free end leaves the link moving: the rest and settle ends stop it"
    elif not candidates:
        why = f"{len(within)} members are within the bound during and after the move, none within the torque limit {limit:.4g}"
    else:
        rated = [r for r in candidates if r["torque_rate_ratio"] is not None]
        stepped = sum(1 for r in rated if r["torque_rate_ratio"] * context.rigid_rate > rate_limit * (1 + 1e-9))
        why = (f"{len(candidates)} members are within the bounds; of the {len(rated)} of least "
               f"{'peak torque' if chosen == Objective.TORQUE else 'error'} judged, {stepped} change their held rows faster than "
               f"{rate_limit:.4g} a row and the rest failed in full (more modes or the held table)")
    return {"row": None, "objective": str(chosen), "rule": rule, "limit": limit, "limit_rule": limit_rule, "acceptance": None,
            "why": why}


#: Candidates whose whole acceptance is tried before the explorer chooses none.
_ACCEPT_LIMIT = 12
#: Candidates refused for the held rows' rate before the explorer chooses none.
_RATE_LIMIT = 200


def _values(name: str, given: Iterable[Any] | None, default: tuple[Any, ...]) -> list[Any]:
    values = list(default if given is None else given)
    if not values:
        raise SettingsError(name, values, "a non-empty list")
    return values


def _is_dask(executor: Any) -> bool:
    return type(executor).__module__.startswith("distributed")


def explore(
    model: Any,
    trajectory: Trajectory,
    segments: Iterable[int] | None = None,
    h: Iterable[int] | None = None,
    cdec_fast: Iterable[float] | None = None,
    cdec_slow: Iterable[float] | None = None,
    joining: Iterable[str] | None = None,
    *,
    eps: float | None = None,
    end: str | Iterable[str] | None = None,
    edges: str | Iterable[str] | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    max_torque_rate: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: SolverName | None = None,
    tol: float | None = None,
    workers: int | None = None,
    executor: Any = None,
    progress: Callable[[int, int], None] | None = None,
    objective: str | None = None,
    period: float | None = None,
    hold: str | None = None,
    window: float | None = None,
) -> Exploration:
    """Evaluate a grid of members of the family.

    Parameters
    ----------
    model : Model, NormalForm or any SISO system
        The model (its matrices are what crosses to the workers), or a generic system as
        :func:`inversion.invert` takes it (a python-control or ``scipy.signal`` system, a
        tuple ``(A, B, C)``; ``peak_torque`` is then the peak of its input).
    trajectory : Trajectory
        The desired trajectory (picklable, for workers: the shipped trajectory types are).
    segments, h, cdec_fast, cdec_slow, joining : iterable, optional
        The grid (default :data:`DEFAULT_GRID`; pairs with ``cdec_fast >= cdec_slow`` are
        skipped, ``h`` beyond the trajectory's derivatives too).
    eps : float, optional
        Tolerance of the unstable set (default :data:`inversion.config.DEFAULTS`).
    end : str or iterable of str, optional
        How the members end (:class:`~inversion.settings.InversionSettings`): ``"free"``,
        ``"settle"`` (``anchored`` members only), ``"rest"``; default ``"free"`` (the paper's).
    edges : str or iterable of str, optional
        How the members meet ``y_d`` at its ends (:class:`~inversion.options.Edges`): ``"match"``
        (the paper's, the default) or ``"rest"``.
    max_error : float, optional
        Quality gate of the rows (m; default 5 % of the move); the chosen member's bound is
        the automatic choice's (default 1 % of the move).
    max_torque : float, optional
        Members with a larger peak torque get status ``max-torque``.
    max_torque_rate : float, optional
        The chosen member's bound on the change of its held table from row to row (as :func:`inversion.invert`).
    objective, period, hold, window : optional
        As :func:`inversion.invert`: how the member the automatic choice's rule takes is
        chosen and judged (``chosen``, ``best.json``).
    initial_internal_state, solver, tol :
        As :func:`inversion.invert`.
    workers : int, optional
        Local processes (default: the CPUs available); 1 runs in this process.
    executor : optional
        A :class:`concurrent.futures.Executor` or a ``dask.distributed.Client`` to run on
        instead.
    progress : callable, optional
        ``progress(done, total)`` in members, after every batch.

    Returns
    -------
    Exploration

    Raises
    ------
    SettingsError
        For an empty or invalid grid value.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import experiment_trajectory
    >>> family = explore(modelgen.load("paper-exp"), experiment_trajectory(), segments=[6, 12], h=[2],
    ...                  cdec_fast=[0.01], cdec_slow=[1.0], joining=["paper", "anchored"], workers=1)
    >>> [(r["segments"], r["joining"], r["status"], r["paper"]) for r in family.rows]
    [(6, 'paper', 'ok', 1), (6, 'anchored', 'ok', 0), (12, 'paper', 'ok', 0), (12, 'anchored', 'ok', 0)]
    >>> round(family.rows[0]["max_redefinition_error"], 7)  # the paper's member: 1.355 mm
    0.0013548
    """
    import time

    started = time.perf_counter()
    eps = default("eps", eps)
    solver = default("solver", solver)
    tol = default("tol", tol)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise SettingsError("workers", workers, "an integer >= 1 (1 runs in this process; leave it out for all cores)")
    check_period(period, trajectory)
    form = normal_form(model)
    grid = {
        "segments": _values("segments", segments, DEFAULT_GRID["segments"]),
        "h": _values("h", h, DEFAULT_GRID["h"]),
        "cdec_fast": _values("cdec_fast", cdec_fast, DEFAULT_GRID["cdec_fast"]),
        "cdec_slow": _values("cdec_slow", cdec_slow, DEFAULT_GRID["cdec_slow"]),
        "joining": _values("joining", joining, DEFAULT_GRID["joining"]),
        "end": _values("end", [end] if isinstance(end, str) else end, (End.FREE,)),
        "edges": _values("edges", [edges] if isinstance(edges, str) else edges, (Edges.MATCH,)),
    }
    batches = _grid_batches(grid, trajectory, form.rho, eps)
    case = paper_case(model, trajectory) if isinstance(model, Model) else None
    paper = paper_settings(case) if case is not None else None
    bounds = Criteria(max_error=tip_bound(max_error, trajectory.move()), max_torque=max_torque,
                    torque_ratio=DEFAULTS.torque_ratio, window=window, extra_modes=DEFAULTS.extra_modes,
                    period=held_period(period), hold=default("hold", hold),
                    max_torque_rate=max_torque_rate)
    asked = demand(form, trajectory, bounds.period)
    rigid, rate = asked.rigid_torque, asked.rigid_rate
    context = _Context(form, trajectory, initial_internal_state, solver, tol, max_error, max_torque, os.getpid(), rigid, window,
                       bounds.period, rate)
    rows, where = _evaluate_grid(context, batches, paper, workers, executor, progress)
    order = {(s.segment_count, s.h, s.joining, s.cdec, str(s.end), str(s.edges)): i for i, s in enumerate(m for b in batches for m in b)}
    rows.sort(key=lambda r: order[(r["segments"], r["h"], r["joining"], (r["cdec_fast"], r["cdec_slow"]), r["end"], r["edges"])])
    ok = [r for r in rows if r["status"] == "ok"]
    for r, flag in zip(ok, pareto_front([(r["max_redefinition_error"], r["peak_torque"]) for r in ok])):
        r["pareto"] = int(flag)
    choice = _choose(model, form, trajectory, ok, bounds, rigid, objective, context)
    best = choice["row"]
    if best is not None:
        best["chosen"] = 1
    seconds = time.perf_counter() - started
    summary = _summary(form, trajectory, rows, ok, choice, bounds, rigid, grid, seconds, where)
    return Exploration(rows, best, form.name, trajectory.name, grid, seconds, where, summary)


def _grid_batches(grid: Mapping[str, Sequence[Any]], trajectory: Trajectory, rho: int, eps: float) -> list[list[InversionSettings]]:
    """The grid's members in batches (the same segments, ``h`` and joining share their plans); a grid that does not fit
    the trajectory is a :class:`SettingsError`."""
    top_h = None if trajectory.max_derivative is None else trajectory.max_derivative - rho
    batches: list[list[InversionSettings]] = []
    for k, hh, j in itertools.product(grid["segments"], grid["h"], grid["joining"]):
        if top_h is not None and hh > top_h:
            continue
        cdecs = [(f, s) for f, s in itertools.product(grid["cdec_fast"], grid["cdec_slow"]) if f < s]
        ends = [e for e in grid["end"] if checked(End, "end", e) != End.SETTLE or j == Joining.ANCHORED]  # settle: anchored only
        members = [InversionSettings(segments=k, h=hh, cdec=cd, joining=j, eps=eps, end=e, edges=g) for e in ends for cd in cdecs
                   for g in grid["edges"]]
        for batch in batches_of(members):
            batch[0].boundaries(trajectory, rho)
            batches.append(batch)
    if not batches:
        raise SettingsError("h", grid["h"], f"orders the trajectory supports (at most {top_h})")
    return batches


def _evaluate_grid(context: "_Context", batches: list[list[InversionSettings]], paper: InversionSettings | None, workers: int | None,
                   executor: Any, progress: Callable[[int, int], None] | None) -> tuple[list[dict[str, Any]], str]:
    """Every batch's rows, in this process, on local processes or on the executor given (a Dask client), and where."""
    total = sum(len(b) for b in batches)
    rows: list[dict[str, Any]] = []

    def collect(part: list[dict[str, Any]]) -> None:
        rows.extend(part)
        if progress is not None:
            progress(len(rows), total)

    count = worker_count(workers)
    if executor is None and (count <= 1 or len(batches) == 1):
        with one_thread():
            for batch in batches:
                collect(_evaluate_batch(context, batch, paper))
        return rows, "this process"
    if executor is None:
        heavy_first = sorted(batches, key=lambda b: -b[0].segment_count * b[0].h)  # even out the workers' ends
        with concurrent.futures.ProcessPoolExecutor(max_workers=count) as pool:
            futures = [pool.submit(_worker_batch, context, batch, paper) for batch in heavy_first]
            for future in concurrent.futures.as_completed(futures):
                collect(future.result())
        return rows, f"{count} local processes"
    futures = [executor.submit(_worker_batch, context, batch, paper) for batch in batches]
    if _is_dask(executor):
        from distributed import as_completed

        where = f"Dask scheduler {getattr(executor, 'scheduler', None) and executor.scheduler.address}"
        completed: Iterable[Any] = as_completed(futures)
    else:
        where = type(executor).__name__
        completed = concurrent.futures.as_completed(futures)
    for future in completed:
        collect(future.result())
    return rows, where


def _summary(form: Any, trajectory: Trajectory, rows: list[dict[str, Any]], ok: list[dict[str, Any]], choice: dict[str, Any],
             bounds: Criteria, rigid: float, grid: dict[str, Any], seconds: float, where: str) -> dict[str, Any]:
    """The exploration's ``summary.json``."""
    failed: dict[str, int] = {}
    for r in rows:
        if r["status"] != "ok":
            failed[r["status"]] = failed.get(r["status"], 0) + 1
    best = choice["row"]
    return {
        "model": form.name,
        "trajectory": trajectory.name,
        "trajectory_spec": trajectory.spec,
        "members": len(rows),
        "succeeded": len(ok),
        "failed": dict(sorted(failed.items())),
        "pareto": sum(r["pareto"] for r in rows),
        "objective": choice["objective"],
        "rule": choice["rule"],
        "max_error": bounds.max_error,
        "max_torque": choice["limit"],
        "max_torque_rule": choice["limit_rule"],
        "rigid_torque": rigid,
        "acceptance": choice["acceptance"],
        "best": None if best is None else {k: best[k] for k in EXPLORE_COLUMNS if k != "message"},
        "no_choice": choice.get("why"),
        "paper_member": next(({k: r[k] for k in EXPLORE_COLUMNS} for r in rows if r["paper"]), None),
        "grid": grid,
        "seconds": seconds,
        "members_per_second": len(rows) / seconds if seconds > 0 else math.inf,
        "workers": where,
        "command": "explore",  # whose summary.json this is: sflm invert and simulate do not write over it
    }

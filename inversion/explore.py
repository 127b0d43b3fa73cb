"""The family explorer: every member of a grid, measured and verified, on local processes or a Dask cluster.

The paper offers "a family of answers" and chooses from it by trial and error.
:func:`explore` evaluates a grid of members (segments x ``h`` x ``Cdec_f`` x ``Cdec_s`` x
joining) with exactly the code :func:`inversion.invert` uses
(:func:`~inversion.member.evaluate_members`: the same figures, the same checks, the same
statuses), marks the Pareto front in (redefinition error, peak torque) and the member the
automatic choice's rule takes (the smallest error within the torque budget; see
:mod:`inversion.auto`), and writes ``explore.csv`` and ``best.json``.

Members that share segments, ``h`` and joining are solved as one batch (they differ in
their exponents only); the batches are the units of work. They run in local processes
(``workers``, default all cores), in the calling process (``workers=1``), or on any
executor with ``submit`` -- a :class:`concurrent.futures.Executor` or a
``dask.distributed.Client`` (the optional extra ``sflm[dask]``). Each member costs a
closed-form scan of its segments, not a sampled inversion (see :mod:`inversion.figures`);
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
from typing import Any, Callable, Iterable, Sequence

from numpy.typing import ArrayLike

from modelgen.model import Model

from .config import DEFAULTS
from .errors import SettingsError
from .figures import Figures
from .member import MemberResult, evaluate_members, segment_anchors, torque_budget
from .settings import InversionSettings, paper_case, paper_settings
from .ssef import Solver
from .system import NormalForm, normal_form
from .threads import one_thread
from .trajectory import Trajectory

__all__ = ["explore", "Exploration", "EXPLORE_COLUMNS", "DEFAULT_GRID", "pareto_front"]

#: Columns of ``explore.csv`` (a contract relied on by scripts).
EXPLORE_COLUMNS = (
    "segments", "h", "cdec_fast", "cdec_slow", "joining", "status", "max_redefinition_error",
    "relative_redefinition_error", "peak_torque", "max_condition_number", "max_constraint_residual",
    "pareto", "chosen", "paper", "message",
)
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
        The chosen row: the smallest redefinition error among the successful members within
        the torque budget -- ``max_torque``, or the automatic choice's default
        (:func:`~inversion.member.torque_budget`) -- ``None`` if no member succeeded.
    model, trajectory : str
        What was explored.
    grid : dict
        The grid.
    seconds : float
        Wall time.
    workers : str
        Where it ran.
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

    def best_settings(self) -> InversionSettings | None:
        """The best member's settings."""
        return None if self.best is None else _row_settings(self.best)

    def write(self, folder: str | Path) -> list[Path]:
        """Write ``explore.csv``, ``best.json`` (if a member succeeded) and ``summary.json``."""
        folder = Path(folder)
        with open(folder / "explore.csv", "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(EXPLORE_COLUMNS)
            for row in self.rows:
                writer.writerow(["" if row[c] is None else (repr(row[c]) if isinstance(row[c], float) else row[c]) for c in EXPLORE_COLUMNS])
        files = [folder / "explore.csv"]
        if self.best is not None:
            best = {
                "settings": _row_settings(self.best).to_dict(),
                "model": self.model,
                "trajectory": self.trajectory,
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
                             joining=row["joining"])


def _figures_of_row(row: dict[str, Any]) -> Figures:
    """The figures a row shows (enough for the torque budget's rule)."""
    relative = row["relative_redefinition_error"]
    move = row["max_redefinition_error"] / relative if relative else 0.0
    return Figures(row["max_redefinition_error"], math.nan, move, row["peak_torque"], math.nan, 0)


def pareto_front(points: Sequence[tuple[float, float]]) -> list[bool]:
    """Which points are not dominated in (first, second), both minimised.

    A point is dominated when another is no worse in both coordinates and better in one.
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
    solver: Solver
    tol: float
    max_error: float | None
    max_torque: float | None
    parent: int


def _row(result: MemberResult, paper: InversionSettings | None) -> dict[str, Any]:
    s = result.settings
    shown = result.status in _SHOWN and result.figures is not None
    fig = result.figures
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
    }


def _evaluate_batch(context: _Context, batch: list[InversionSettings], paper: InversionSettings | None) -> list[dict[str, Any]]:
    """Evaluate one batch of members."""
    anchors = segment_anchors(context.form, context.trajectory, batch[0])
    results = evaluate_members(
        context.form, context.trajectory, batch, initial_internal_state=context.initial_internal_state, anchors=anchors,
        solver=context.solver, tol=context.tol, max_error=context.max_error, max_torque=context.max_torque, verify=True,
    )
    return [_row(r, paper) for r in results]


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
    end: str = "free",
    max_error: float | None = None,
    max_torque: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: Solver | None = None,
    tol: float | None = None,
    workers: int | None = None,
    executor: Any = None,
    progress: Callable[[int, int], None] | None = None,
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
    end : {"free", "rest"}
        How every member ends (:class:`~inversion.settings.InversionSettings`).
    max_error : float, optional
        Quality gate (m; default 5 % of the move).
    max_torque : float, optional
        Members with a larger peak torque get status ``max-torque``.
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
    eps = DEFAULTS.eps if eps is None else eps
    solver = DEFAULTS.solver if solver is None else solver
    tol = DEFAULTS.tol if tol is None else tol
    form = normal_form(model)
    grid = {
        "segments": _values("segments", segments, DEFAULT_GRID["segments"]),
        "h": _values("h", h, DEFAULT_GRID["h"]),
        "cdec_fast": _values("cdec_fast", cdec_fast, DEFAULT_GRID["cdec_fast"]),
        "cdec_slow": _values("cdec_slow", cdec_slow, DEFAULT_GRID["cdec_slow"]),
        "joining": _values("joining", joining, DEFAULT_GRID["joining"]),
    }
    top_h = None if trajectory.max_derivative is None else trajectory.max_derivative - form.rho
    batches: list[list[InversionSettings]] = []
    for k, hh, j in itertools.product(grid["segments"], grid["h"], grid["joining"]):
        if top_h is not None and hh > top_h:
            continue
        cdecs = [(f, s) for f, s in itertools.product(grid["cdec_fast"], grid["cdec_slow"]) if f < s]
        batch = [InversionSettings(segments=k, h=hh, cdec=cd, joining=j, eps=eps, end=end) for cd in cdecs]
        if batch:
            batch[0].boundaries(trajectory, form.rho)  # a grid that does not fit the trajectory is a user error
            batches.append(batch)
    if not batches:
        raise SettingsError("h", grid["h"], f"orders the trajectory supports (at most {top_h})")
    total = sum(len(b) for b in batches)
    case = paper_case(model, trajectory) if isinstance(model, Model) else None
    paper = paper_settings(case) if case is not None else None
    context = _Context(form, trajectory, initial_internal_state, solver, tol, max_error, max_torque, os.getpid())
    rows: list[dict[str, Any]] = []
    done = 0

    def collect(part: list[dict[str, Any]]) -> None:
        nonlocal done
        rows.extend(part)
        done += len(part)
        if progress is not None:
            progress(done, total)

    count = workers if workers is not None else len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    if executor is None and (count <= 1 or len(batches) == 1):
        where = "this process"
        with one_thread():
            for batch in batches:
                collect(_evaluate_batch(context, batch, paper))
    elif executor is None:
        where = f"{count} local processes"
        heavy_first = sorted(batches, key=lambda b: -b[0].segment_count * b[0].h)  # even out the workers' ends
        with concurrent.futures.ProcessPoolExecutor(max_workers=count) as pool:
            futures = [pool.submit(_worker_batch, context, batch, paper) for batch in heavy_first]
            for future in concurrent.futures.as_completed(futures):
                collect(future.result())
    else:
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
    order = {(s.segment_count, s.h, s.joining, s.cdec): i for i, s in enumerate(m for b in batches for m in b)}
    rows.sort(key=lambda r: order[(r["segments"], r["h"], r["joining"], (r["cdec_fast"], r["cdec_slow"]))])
    ok = [r for r in rows if r["status"] == "ok"]
    for r, flag in zip(ok, pareto_front([(r["max_redefinition_error"], r["peak_torque"]) for r in ok])):
        r["pareto"] = int(flag)
    budget, rule = max_torque, "given"
    if max_torque is None:  # the automatic choice's rule (inversion.auto); ok rows are within the gate
        found = torque_budget([_figures_of_row(r) for r in ok], math.inf)
        if found is not None:
            budget, rule = found
    candidates = [r for r in ok if budget is None or r["peak_torque"] <= budget]
    best = min(candidates, key=lambda r: (r["max_redefinition_error"], r["segments"]), default=None)
    if best is not None:
        best["chosen"] = 1
    seconds = time.perf_counter() - started
    failed: dict[str, int] = {}
    for r in rows:
        if r["status"] != "ok":
            failed[r["status"]] = failed.get(r["status"], 0) + 1
    summary = {
        "model": form.name,
        "trajectory": trajectory.name,
        "members": len(rows),
        "succeeded": len(ok),
        "failed": dict(sorted(failed.items())),
        "pareto": sum(r["pareto"] for r in rows),
        "objective": "smallest max |y~ - y_d| among the successful members"
        + ("" if budget is None else f" with peak torque <= {budget:.4g} N m"),
        "max_torque": budget,
        "max_torque_rule": rule,
        "best": None if best is None else {k: best[k] for k in EXPLORE_COLUMNS if k != "message"},
        "paper_member": next(({k: r[k] for k in EXPLORE_COLUMNS} for r in rows if r["paper"]), None),
        "grid": grid,
        "seconds": seconds,
        "members_per_second": len(rows) / seconds if seconds > 0 else math.inf,
        "workers": where,
    }
    return Exploration(rows, best, form.name, trajectory.name, grid, seconds, where, summary)

"""Automatic choice from the family: a feedforward a user can apply, judged by what reaches the link.

The paper chooses ``(Cdec_f, Cdec_s)``, the segments and ``h`` by trial and error and calls the
resulting family of answers the method's advantage. :func:`choose` searches it for the
engineer's formulation of the problem (``objective``):

* ``"torque"`` (the default) -- the member of **least peak torque** whose redefinition is
  within the bound of ``y_d`` (``max_error``, default 1 % of the move): what an optimal-control
  solver minimises too (members within 2 % of the least torque count as equal: the smallest
  error among them wins);
* ``"error"`` -- the member of **least redefinition error** within the torque limit.

A member is a candidate only if what reaches the link meets the same bounds
(:mod:`inversion.acceptance`): its torque at most ``max_torque`` -- by default three times
what a rigid body needs along ``y_d`` (for ``"error"`` also at most 1.5 times the least torque
within the bound) -- and the linear plant left alone after the feedforward ends keeps the tip
within the bound of ``y_d(t_f)``. The search:

1. a coarse grid over segments, ``h``, ``(Cdec_f, Cdec_s)``, the joining and how the feedforward
   ends (free, held while the link settles, at rest; :meth:`inversion.config.SearchGrid.coarse`;
   the dimensions the caller fixes are left alone), each member solved and measured in closed
   form, the plant's free motion after its end in one batch;
2. the candidates ranked by the objective and verified in that order (solver independence and
   extended precision, :mod:`inversion.family.verify`) until one passes;
3. a refinement around it -- neighbouring segment counts, decay constants and ``h`` --
   ranked and verified the same way;
4. the winner's acceptance: the linear plant driven by its torque (the plant check), the model
   with more modes driven by it (truncation) and the plant as a controller at its period
   drives it (the held table); if it fails, the next verified candidate.

The result is that member, or an :class:`~inversion.errors.InversionError` that names the
nearest alternatives the search saw (their error, peak torque and torque ratio) and what would
help. The search is recorded (members tried, failed and why, the limits and their rules, the
trade not made, time).
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Iterator, Mapping

import numpy as np
from numpy.typing import ArrayLike

from ..acceptance import WORDS, Acceptance, Criteria, demand, given_rule, need_ratio, need_word, table_rate
from ..config import DEFAULTS, default
from ..errors import InversionError, SettingsError
from ..lti.system import NormalForm
from ..options import Edges, End, Joining, Objective, checked
from ..settings import InversionSettings, describe
from ..signals.chebyshev import PiecewiseChebyshev
from ..signals.trajectory import Trajectory
from .member import FAILURES, MemberResult, evaluate_member, evaluate_members, member_acceptance, point_table, rest_failure, segment_anchors
from .ssef import SolverName
from .verify import check_member

__all__ = ["choose", "batches", "objective_key", "shared_members", "presolve", "GRID", "ChosenMember"]

#: The first stage's grid: the coarse part of the one the explorer maps by default (:data:`inversion.config.DEFAULTS`).
GRID: dict[str, tuple[Any, ...]] = DEFAULTS.grid.coarse().as_dict()
#: Members verified per stage before giving up on it.
_VERIFY_LIMIT = 40
#: Verified candidates whose acceptance is tried before the search gives up.
_ACCEPT_LIMIT = 12
#: For the ``error`` objective the torque limit is at most this multiple of the least torque within the bound.
ERROR_TORQUE_MARGIN = DEFAULTS.torque_margin
#: The batches solved within :func:`shared_members` (``None`` outside it): each batch's results by what they depend on.
_SHARED: ContextVar[dict[tuple[Any, ...], tuple[Any, list[MemberResult]]] | None] = ContextVar("shared_members", default=None)


@contextmanager
def shared_members() -> Iterator[None]:
    """Searches within it share the batches they solve.

    Within it, a search (:func:`choose`) takes a batch of members another search already solved -- the same members,
    the same form and trajectory objects, the same options and window -- from it rather than solving it again:
    ``compare``'s family rows (the family as given and with a rest end) search the same grid, the rest end's part of it
    twice. A batch is taken whole or not at all, so each member's figures are those of the same batch solved again,
    bit for bit. It ends with the block (the results are kept until then); within another, the outer one's.
    """
    if _SHARED.get() is not None:  # (within another: the outer one's batches)
        yield
        return
    token = _SHARED.set({})
    try:
        yield
    finally:
        _SHARED.reset(token)


@dataclass(frozen=True)
class ChosenMember:
    """The member the automatic choice returns, with what it measured.

    Attributes
    ----------
    member : MemberResult
        The member, verified and plant-checked.
    acceptance : Acceptance
        What reaches the link (:mod:`inversion.acceptance`).
    signals : PiecewiseChebyshev
        The signals it feeds forward (its torque, a link's joint references).
    record : dict
        The search (the summary's ``auto`` block).
    """

    member: MemberResult
    acceptance: Acceptance
    signals: PiecewiseChebyshev
    record: dict[str, Any]


def _top_h(trajectory: Trajectory, rho: int) -> int:
    """The largest ``h`` the trajectory's derivatives allow (``h + rho`` of them are needed)."""
    return 20 if trajectory.max_derivative is None else trajectory.max_derivative - rho


def _ends(fixed: Mapping[str, Any], joining: str) -> tuple[str, ...]:
    """How the members of a joining may end: as fixed, or free, held while settling (anchored only), at rest."""
    if "end" in fixed:
        return (fixed["end"],)
    return (End.FREE, End.SETTLE, End.REST) if joining == Joining.ANCHORED else (End.FREE, End.REST)


def _edges(fixed: Mapping[str, Any], trajectory: Trajectory, h: int, rho: int) -> tuple[str, ...]:
    """How the members may meet ``y_d`` at its ends: as fixed; else the paper's, and at rest too where the two differ --
    where some derivative of ``yddot_d`` the joining matches (orders ``1 .. h + rho - 2``) is not zero at ``t_0`` or
    ``t_f`` (a quintic's jerk)."""
    if "edges" in fixed:
        return (fixed["edges"],)
    top = h + rho if trajectory.max_derivative is None else min(h + rho, trajectory.max_derivative)
    ends = ((trajectory.t0, "+"), (trajectory.tf, "-"))
    sizes = [abs(float(trajectory.derivative([t], k, side)[0])) * trajectory.duration ** (k - 2) for k in range(3, top + 1)
             for t, side in ends]
    scale = max([*sizes, float(np.abs(trajectory.derivative(np.linspace(trajectory.t0, trajectory.tf, 64), 2)).max()), 1e-300])
    return (Edges.MATCH, Edges.REST) if any(m > 1e-9 * scale for m in sizes) else (Edges.MATCH,)


def _grid(fixed: Mapping[str, Any], trajectory: Trajectory, rho: int = 2) -> list[InversionSettings]:
    """The first stage's members, with the caller's fixed values."""
    segments: Iterable[Any] = (fixed["segments"],) if "segments" in fixed else GRID["segments"]
    top_h = _top_h(trajectory, rho)
    hs: tuple[int, ...] = (fixed["h"],) if "h" in fixed else tuple(h for h in GRID["h"] if h <= top_h)
    if "cdec" in fixed:
        cdecs: Iterable[tuple[float, float]] = ((float(fixed["cdec"][0]), float(fixed["cdec"][1])),)
    else:
        cdecs = [(f, s) for f, s in itertools.product(GRID["cdec_fast"], GRID["cdec_slow"]) if f < s]
    joinings: Iterable[str] = (fixed["joining"],) if "joining" in fixed else GRID["joining"]
    eps = fixed.get("eps", DEFAULTS.eps)
    out = []
    edges = {h: _edges(fixed, trajectory, h, rho) for h in hs}  # (y_d's derivatives at its ends: once an h, not a member)
    for k, h, cd, j in itertools.product(tuple(segments), tuple(hs), tuple(cdecs), tuple(joinings)):
        for end in _ends(fixed, j):
            if end == End.SETTLE and j != Joining.ANCHORED:
                raise SettingsError("end", end, "'settle' with joining='anchored' (only it ends the unstable internal modes at zero)")
            for edge in edges[h]:
                out.append(InversionSettings(segments=k if isinstance(k, int) else tuple(k), h=h, cdec=cd, joining=j, eps=eps, end=end,
                                             edges=edge))
    if not out:
        raise SettingsError("h", fixed.get("h"), f"an order the trajectory {trajectory.name} supports (h + {rho} <= {top_h + rho})")
    return out


def batches(members: Iterable[InversionSettings]) -> list[list[InversionSettings]]:
    """Members grouped into batches that share their systems.

    Members grouped into batches that share their segment systems (segments, ``h``, joining, ``eps``, rest end or not,
    edges).

    Parameters
    ----------
    members : Iterable[InversionSettings]
        The members.
    """
    groups: dict[tuple[Any, ...], list[InversionSettings]] = {}
    for s in members:
        groups.setdefault((s.segments, s.h, s.joining, s.eps, s.plan_end, s.edges), []).append(s)
    return list(groups.values())


def _neighbours(best: InversionSettings, fixed: Mapping[str, Any], trajectory: Trajectory, rho: int = 2) -> list[InversionSettings]:
    """Members around ``best``: segment counts, decay constants and ``h`` nearby; the grid's edges extended."""
    out: set[InversionSettings] = set()
    k = best.segment_count
    counts = {k} if "segments" in fixed else {max(1, k - 2), max(1, k - 1), k, k + 1, k + 2, round(k * 1.5), round(k * 2)}
    fast, slow = best.cdec
    if "cdec" in fixed:
        cdecs = {best.cdec}
    else:
        fasts = {fast * 10**e for e in (-2.0, -1.0, -0.5, 0.0, 0.5, 1.0)}
        if fast <= min(GRID["cdec_fast"]):
            fasts |= {fast * 1e-2, fast * 1e-4}
        cdecs = {(f, s) for f in fasts for s in {slow, 1.0, 0.7, 0.3} if 0 < f < s <= 1 and f > 1e-300}
    top_h = _top_h(trajectory, rho)
    hs = {best.h} if "h" in fixed else {h for h in (best.h - 1, best.h, best.h + 1) if 1 <= h <= min(top_h, 4)}
    for kk, cd, h in itertools.product(counts, cdecs, hs):
        segments: Any = best.segments if "segments" in fixed else int(kk)
        out.add(best.with_changes(segments=segments, cdec=cd, h=h))
    out.discard(best)
    return sorted(out, key=lambda s: (s.segment_count, s.h, s.cdec, s.joining, s.end))


def _entry(result: MemberResult, rigid: float, kind: str | None = None) -> dict[str, Any]:
    """A member the search saw, as the record and the messages show it."""
    fig, after = result.figures, result.after
    assert fig is not None
    entry: dict[str, Any] = {"settings": result.settings.to_dict(), "max_redefinition_error": fig.max_error,
                             "relative_redefinition_error": fig.relative_error, "peak_torque": fig.peak_torque,
                             "torque_ratio": need_ratio(fig.peak_torque, rigid),
                             "after_end_excursion": None if after is None else after.max_tip_excursion,
                             "post_actuation_time": 0.0 if result.tail is None else result.tail.length}
    return entry if kind is None else {"kind": kind, **entry}


def _alternatives(usable: list[MemberResult], chosen: MemberResult, rigid: float, count: int = 2) -> list[dict[str, Any]]:
    """The trade the choice did not make: candidates with markedly less torque (at most 0.8 of the chosen one's)
    or markedly smaller error (at most half) -- for each direction ``count`` members at levels spaced
    geometrically to the extreme seen, each the best at its level. Not verified: ``invert(..., max_torque=...)``
    or ``max_error=`` makes that choice with the checks."""
    assert chosen.figures is not None
    top_torque, top_error = chosen.figures.peak_torque, chosen.figures.max_error
    out: list[dict[str, Any]] = []

    def add(best: MemberResult, kind: str) -> None:
        entry = _entry(best, rigid, kind)
        if all(e["settings"] != entry["settings"] for e in out):
            out.append(entry)

    least = min((r.figures.peak_torque for r in usable), default=top_torque)  # type: ignore[union-attr]
    if least < 0.8 * top_torque:
        for k in range(1, count + 1):
            level = top_torque * (least / top_torque) ** (k / count) * (1 + 1e-12)
            add(min((r for r in usable if r.figures.peak_torque <= level), key=lambda r: r.figures.max_error), "less torque")  # type: ignore[union-attr]
    smallest = min((r.figures.max_error for r in usable), default=top_error)  # type: ignore[union-attr]
    if smallest < 0.5 * top_error:
        for k in range(1, count + 1):
            level = top_error * (smallest / top_error) ** (k / count) * (1 + 1e-12)
            add(min((r for r in usable if r.figures.max_error <= level), key=lambda r: r.figures.peak_torque), "smaller error")  # type: ignore[union-attr]
    return out


def objective_key(objective: str, torques: Iterable[float]) -> Callable[[Any], tuple[float, ...]]:
    """The ranking of candidates by ``objective``.

    ``"torque"``: the least peak torque, members within ``DEFAULTS.torque_tie`` (2 %) of the
    least counting as equal, the smallest error among them first; then by peak torque.
    ``"error"``: the smallest error, then the least torque. Ties: the shorter post-actuation,
    fewer segments.

    Parameters
    ----------
    objective : str
        ``"torque"`` or ``"error"``.
    torques : Iterable[float]
        The candidates' peak torques (N m).
    """
    least = min(torques, default=math.inf)
    tie = least * (1 + DEFAULTS.torque_tie)

    def figures(item: Any) -> tuple[float, float, float, int]:
        if isinstance(item, dict):  # an explorer's row
            return item["peak_torque"], item["max_redefinition_error"], item["post_actuation_time"] or 0.0, item["segments"]
        fig = item.figures
        return fig.peak_torque, fig.max_error, 0.0 if item.tail is None else item.tail.length, item.settings.segment_count

    def key(item: Any) -> tuple[float, ...]:
        peak, error, post, segments = figures(item)
        if objective == Objective.TORQUE:
            return (0.0, error, peak, post, segments) if peak <= tie else (1.0, peak, error, post, segments)
        return (error, peak, post, segments)

    return key


def _batch_key(form: NormalForm, trajectory: Trajectory, batch: list[InversionSettings], options: Mapping[str, Any],
               window: float | None) -> tuple[Any, ...]:
    """What a batch's results depend on, for :func:`shared_members`: the form and the move (the same objects), the members,
    the options and the window."""
    start = options["initial_internal_state"]
    state = None if start is None else tuple(np.asarray(start, dtype=float).ravel().tolist())
    return (id(form), id(trajectory), tuple(batch), state, options["solver"], options["tol"], window)


def _solved(form: NormalForm, trajectory: Trajectory, batch: list[InversionSettings], anchors: dict[tuple[Any, float], Any],
            options: Mapping[str, Any], window: float | None) -> list[MemberResult]:
    """A batch solved and measured in closed form (``anchors``: its segmentation's, computed once and kept there)."""
    base = batch[0]
    key = (base.segments, base.eps)
    if base.joining == Joining.ANCHORED and key not in anchors:
        anchors[key] = segment_anchors(form, trajectory, base)
    return evaluate_members(form, trajectory, batch, anchors=anchors.get(key), max_error=math.inf, verify=False, window=window,
                            **options)


def _options(initial_internal_state: ArrayLike | None, solver: SolverName | None, tol: float | None) -> dict[str, Any]:
    """A search's options for its members, the defaults resolved."""
    return {"initial_internal_state": initial_internal_state, "solver": default("solver", solver), "tol": default("tol", tol)}


def _normalised(fixed: Mapping[str, Any] | None) -> dict[str, Any]:
    """The values a search keeps, each checked (joining, end, edges by their names)."""
    out = dict(fixed or {})
    for key, kind in (("joining", Joining), ("end", End), ("edges", Edges)):
        if key in out:
            out[key] = checked(kind, key, out[key])
    return out


def presolve(form: NormalForm, trajectory: Trajectory, *, fixed: Mapping[str, Any] | None = None, window: float | None = None,
             initial_internal_state: ArrayLike | None = None, solver: SolverName | None = None, tol: float | None = None,
             stop: Callable[[], bool] = lambda: False) -> int:
    """Solve the first grid's batches ahead of a search.

    Solve the batches of the first grid :func:`choose` would search with these values, into :func:`shared_members`
    (nothing outside it), until ``stop()``: what a search does first that depends on neither its bounds nor its
    objective, done while something else runs (the bounded causal limit, on another thread). The search takes them from
    there, bit for bit. A grid that does not fit the move is left to the search to refuse.

    Parameters
    ----------
    form : NormalForm
        The model's matrices (the object the search is given).
    trajectory : Trajectory
        The move (the object the search is given).
    fixed, window, initial_internal_state, solver, tol :
        As :func:`choose` and its bounds.
    stop : callable
        Asked before each batch.

    Returns
    -------
    int
        The batches solved.
    """
    shared = _SHARED.get()
    if shared is None:
        return 0
    options = _options(initial_internal_state, solver, tol)
    try:
        grid = _grid(_normalised(fixed), trajectory, form.rho)
        grid[0].boundaries(trajectory, form.rho)
    except (InversionError, SettingsError):
        return 0
    anchors: dict[tuple[Any, float], Any] = {}
    done = 0
    for batch in batches(grid):
        if stop():
            break
        key = _batch_key(form, trajectory, batch, options, window)
        if key not in shared:
            shared[key] = ((form, trajectory), _solved(form, trajectory, batch, anchors, options, window))
            done += 1
    return done


class _Search:
    """The state of one automatic choice: the members seen, verified, accepted, and why others failed."""

    def __init__(self, form: NormalForm, trajectory: Trajectory, bounds: Criteria, objective: Objective, options: dict[str, Any],
                 count: Callable[[int, int], None] | None = None):
        self.form, self.trajectory, self.bounds, self.objective, self.options = form, trajectory, bounds, objective, options
        self.count, self.total = count, 0
        self.seen: dict[InversionSettings, MemberResult] = {}
        self.verified: dict[InversionSettings, bool] = {}
        self.failures: Counter[str] = Counter()
        self.anchors: dict[tuple[Any, float], Any] = {}
        asked = demand(form, trajectory, bounds.period)
        self.rigid, rigid_rate = asked.rigid_torque, asked.rigid_rate
        self.rate_limit = bounds.rate_limit(rigid_rate, form.inertia is not None)[0]
        self.limit = bounds.torque_limit(self.rigid)
        self.link = form.inertia is not None
        self.words = WORDS[self.link]
        self.rule = (given_rule(bounds) if bounds.max_torque is not None else
                     f"{bounds.torque_ratio:g} x the {need_word(self.link)} ({self.rigid:.4g})")

    def run(self, candidates: list[InversionSettings]) -> None:
        fresh = [s for s in candidates if s not in self.seen]
        self.total = len(self.seen) + len(fresh)
        shared = _SHARED.get()
        for batch in batches(fresh):
            key = None if shared is None else _batch_key(self.form, self.trajectory, batch, self.options, self.bounds.window)
            if shared is not None and key in shared:
                results = shared[key][1]
            else:
                results = _solved(self.form, self.trajectory, batch, self.anchors, self.options, self.bounds.window)
                if shared is not None and key is not None:
                    shared[key] = ((self.form, self.trajectory), results)  # (the objects kept: their ids stay theirs)
            for result in results:
                self.seen[result.settings] = result
                if result.status in FAILURES or result.status == "settle":
                    self.failures[result.status] += 1
            if self.count is not None:
                self.count(len(self.seen), self.total)


    def within(self, result: MemberResult, torque: bool = True) -> bool:
        """Whether a solved member meets the bounds its closed form can tell: error, after its end, torque."""
        fig, after = result.figures, result.after
        return (result.status == "ok" and fig is not None and after is not None and fig.max_error <= self.bounds.max_error
                and after.max_tip_excursion <= self.bounds.max_error and (not torque or fig.peak_torque <= self.limit))

    def error_limit(self) -> None:
        """The ``error`` objective's torque limit: at most 1.5 x the least torque within the bound (no doubling)."""
        if self.objective != Objective.ERROR or self.bounds.max_torque is not None:
            return
        within = [r.figures.peak_torque for r in self.seen.values() if self.within(r, torque=False)]  # type: ignore[union-attr]
        if within and ERROR_TORQUE_MARGIN * min(within) < self.limit:
            self.limit = ERROR_TORQUE_MARGIN * min(within)
            self.rule = f"{ERROR_TORQUE_MARGIN:g} x the least peak {self.words['inp']} within the bound ({min(within):.4g})"

    def ranked(self) -> list[MemberResult]:
        usable = [r for r in self.seen.values() if self.within(r) and self.verified.get(r.settings, True) is not False]
        return sorted(usable, key=objective_key(self.objective, [r.figures.peak_torque for r in usable]))  # type: ignore[union-attr]

    def nearest(self) -> MemberResult | None:
        """The member the objective prefers among those within the bounds the closed form tells, verified or not (the
        refinement's seed when none has passed yet)."""
        within = [r for r in self.seen.values() if self.within(r)]
        return min(within, key=objective_key(self.objective, [r.figures.peak_torque for r in within]), default=None)  # type: ignore[union-attr]

    def rate_ok(self, result: MemberResult) -> bool:
        """Whether a member's torque, sampled at the controller's rows, changes from row to row within the rate bound (the
        first row against the input before it): cheap, so a member that steps is passed over before it is verified."""
        rows, before, after = point_table(result, self.bounds.period)
        return table_rate(rows, before, after) <= self.rate_limit * (1 + 1e-12)

    def best_verified(self, skip: set[InversionSettings] = frozenset()) -> MemberResult | None:  # type: ignore[assignment]
        count = 0
        for result in (r for r in self.ranked() if r.settings not in skip):
            if self.verified.get(result.settings):
                return result
            if count >= _VERIFY_LIMIT:
                return None
            assert result.redefinition is not None and result.figures is not None
            if not self.rate_ok(result):
                self.verified[result.settings] = False
                self.failures["torque-rate"] += 1
                continue
            count += 1
            checks = check_member(result.redefinition, result.figures, primary=self.options["solver"])
            failed = checks.failure()
            if failed is None and result.settings.end == End.REST:
                failed = rest_failure(result.redefinition, result.figures)
            self.verified[result.settings] = failed is None
            if failed is not None:
                self.failures[failed[0]] += 1
                continue
            return result
        return None


def choose(
    form: NormalForm,
    trajectory: Trajectory,
    *,
    fixed: Mapping[str, Any] | None = None,
    bounds: Criteria,
    objective: str | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: SolverName | None = None,
    tol: float | None = None,
    progress: Callable[[str], None] | None = None,
    larger: tuple[int, dict[str, Any]] | None = None,
) -> ChosenMember:
    """Search the family for the member the objective prefers.

    Search the family for the member the objective prefers among those that reach the link as asked (module docstring).

    Parameters
    ----------
    form : NormalForm
        The model's matrices.
    trajectory : Trajectory
        The desired trajectory.
    fixed : mapping, optional
        Values of ``segments``, ``h``, ``cdec``, ``joining``, ``eps``, ``end`` the search keeps.
    bounds : Criteria
        The error bound (m), the torque limit, the after-end window, the period and hold of the
        held table (:class:`~inversion.acceptance.Criteria`).
    objective : {"torque", "error"}, optional
        What the choice minimises (default :data:`inversion.config.DEFAULTS`, ``"torque"``).
    initial_internal_state, solver, tol :
        As :func:`inversion.invert`.
    progress : callable, optional
        Receives a one-line message per stage; if it has a ``count(done, total)`` method (a progress bar), that is
        called as the members are evaluated (``total`` grows when the search refines).
    larger : (int, dict), optional
        The model with more modes for the truncation check (a link's; ``None`` for a system).

    Returns
    -------
    ChosenMember
        The member, its acceptance, its signals and the record of the search.

    Raises
    ------
    InversionError
        If no member passes, naming the nearest alternatives the search saw and what would help.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import Family, invert, smoothstep
    >>> r = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 3), method=Family())  # not the paper's trajectory
    >>> r.summary["relative_redefinition_error"] <= 0.01, r.summary["torque_ratio"] <= 3
    (True, True)
    >>> r.summary["auto"]["objective"]
    'torque'
    """
    chosen_objective = checked(Objective, "objective", default("objective", objective))
    options = _options(initial_internal_state, solver, tol)
    fixed = _normalised(fixed)
    started = time.perf_counter()

    def say(message: str) -> None:
        if progress is not None:
            progress(message)

    search = _Search(form, trajectory, bounds, chosen_objective, options, getattr(progress, "count", None))
    grid = _grid(fixed, trajectory, form.rho)
    grid[0].boundaries(trajectory, form.rho)  # fixed segments that do not fit the trajectory: a user error
    say(f"auto: {len(grid)} members on the first grid")
    search.run(grid)
    search.error_limit()
    best = search.best_verified()
    seed = best if best is not None else search.nearest()  # no member passed the first grid: refine around the nearest
    if seed is not None:
        neighbours = _neighbours(seed.settings, fixed, trajectory, form.rho)
        say(f"auto: {'best so far' if best is not None else 'none passes yet; nearest'} {describe(seed.settings)} "
            f"({seed.figures.max_error:.3g} m, {seed.figures.peak_torque:.4g} peak); {len(neighbours)} neighbours")  # type: ignore[union-attr]
        search.run(neighbours)
        best = search.best_verified()
    final: ChosenMember | None = None
    tried: set[InversionSettings] = set()
    while best is not None and len(tried) < _ACCEPT_LIMIT:
        tried.add(best.settings)
        member = evaluate_member(form, trajectory, best.settings, max_error=bounds.max_error, max_torque=search.limit, verify=True,
                                 plant=True, window=bounds.window, **options)
        if member.ok:
            acceptance, signals, member = member_acceptance(member, form, trajectory, bounds, link=form.inertia is not None, larger=larger)
            failed = acceptance.failure(bounds, (search.limit, search.rule))
            if failed is None:
                final = ChosenMember(member, acceptance, signals, {})
                break
            search.failures[failed[0]] += 1
        else:
            search.failures[member.status] += 1
        search.verified[best.settings] = False
        best = search.best_verified(tried)
    seconds = time.perf_counter() - started
    usable = [r for r in search.seen.values() if search.within(r) and search.verified.get(r.settings) is not False]
    record: dict[str, Any] = {
        "objective": str(chosen_objective),
        "rule": (f"least peak {search.words['inp']}" if chosen_objective == Objective.TORQUE else "least max |y~ - y_d|")
        + f" among verified members within {bounds.max_error:.4g}{search.words['m']} of y_d (during the move and after it) "
        f"with peak {search.words['inp']} <= {search.limit:.4g}",
        "max_error": bounds.max_error,
        "max_torque": search.limit,
        "max_torque_rule": search.rule,
        "rigid_torque": search.rigid,
        "members": len(search.seen),
        "succeeded": sum(1 for r in search.seen.values() if r.status == "ok"),
        "candidates": len(usable),
        "verified": sum(1 for v in search.verified.values() if v),
        "failed": dict(sorted(search.failures.items())),
        "fixed": {k: (list(v) if isinstance(v, tuple) else v) for k, v in fixed.items()},
        "seconds": seconds,
    }
    if final is None:
        raise _no_member(search, fixed, record)
    record["alternatives"] = _alternatives(usable, final.member, search.rigid)
    say(f"auto: chose {describe(final.member.settings)}: {final.member.figures.max_error:.3g}{search.words['m']}, peak {search.words['inp']} "  # type: ignore[union-attr]
        f"{final.member.figures.peak_torque:.4g} ({len(search.seen)} members, {seconds:.1f} s)")  # type: ignore[union-attr]
    return ChosenMember(final.member, final.acceptance, final.signals, record)


def _failed(search: _Search, member: MemberResult) -> list[str]:
    """The tests a member the search saw failed, in the acceptance's words (a refusal's nearest member names them)."""
    fig, after, bound = member.figures, member.after, search.bounds.max_error
    out = []
    if fig is not None and fig.max_error > bound:
        out.append(f"the error bound during the move ({fig.max_error:.4g} > {bound:.4g})")
    if after is not None and after.max_tip_excursion > bound:
        out.append(f"the error bound after the move ({after.max_tip_excursion:.4g} > {bound:.4g})")
    if fig is not None and fig.peak_torque > search.limit:
        out.append(f"the peak {search.words['inp']} bound ({fig.peak_torque:.4g} > {search.limit:.4g}, {search.rule})")
    if not out and not search.rate_ok(member):
        out.append("the bound on the change between rows")
    if not out and search.verified.get(member.settings) is False:
        out.append("its verification (the held table, the window after the move or more modes)")
    return out or [f"its status: {member.status}"]


def _no_member(search: _Search, fixed: Mapping[str, Any], record: dict[str, Any]) -> InversionError:
    """The failure of a search, with the nearest alternatives it saw and what would help."""
    solved = [r for r in search.seen.values() if r.status == "ok" and r.figures is not None and r.after is not None]
    bound = search.bounds.max_error
    move = next((r.figures.move for r in solved), 0.0) or 1.0  # type: ignore[union-attr]
    nearest: list[dict[str, Any]] = []
    if solved:
        closest = min(solved, key=lambda r: max(r.figures.max_error, r.after.max_tip_excursion))  # type: ignore[union-attr]
        picked = [(closest, "smallest error, during and after the move")]
        within = [r for r in solved if search.within(r, torque=False)]
        if within:
            picked.append((min(within, key=lambda r: r.figures.peak_torque), f"least {search.words['inp']} within the bound"))  # type: ignore[union-attr]
        nearest = [{**_entry(member, search.rigid, kind), "failed": _failed(search, member)} for member, kind in picked]
    record["alternatives"] = nearest
    reasons = ", ".join(f"{n} {k}" for k, n in sorted(search.failures.items())) or "none"
    shown = "; ".join(f"{e['kind']}: {describe(InversionSettings.from_dict(e['settings']))}, {100 * e['relative_redefinition_error']:.3g} % "
                      f"of the move, {100 * (e['after_end_excursion'] or 0) / move:.3g} % after its end, peak {search.words['inp']} "
                      f"{e['peak_torque']:.4g} ({e['torque_ratio']:.3g} x the {need_word(search.link)})" for e in nearest) or "no member solved"
    helps = []
    if fixed.get("end") == End.FREE:
        helps.append("end='settle' or end='rest' (held after t_f)")
    start = _start_rate(search)
    if fixed.get("edges") == Edges.MATCH and start is not None and start > search.rate_limit:
        helps.append(f"edges='rest' (a member matching y_d's derivatives at its start changes its input by {start:.3g} over the first "
                     f"row, {start / search.rate_limit:.3g} x the rate bound {search.rate_limit:.3g}), or a larger max_torque_rate")
    m = search.words["m"]
    helps += ["a longer move", f"a larger max_error (now {bound:.4g}{m})", f"a max_torque above {search.limit:.4g}",
              "method='ocp' (the optimal-control feedforward, which meets the rate bound by construction)",
              "method='stable' (non-causal: input before t0)"]
    exc = InversionError(
        f"no member of the family passes: none reaches {'the link' if search.link else 'the system'} within {bound:.4g}{m} "
        f"({100 * bound / move:.3g} % of the move) with max_torque = {search.limit:.4g} ({search.rule}): {record['members']} tried in "
        f"{record['seconds']:.1f} s (failures: {reasons}); nearest: {shown}; what may help: {', '.join(helps)}")
    exc.record = record  # type: ignore[attr-defined]
    return exc


def _start_rate(search: _Search) -> float | None:
    """How much every member's input changes over the first row: from rest the exact inverse's input starts with the rate
    ``y_d^(rho+1)(t_0) / C A^(rho-1) B`` (its output matches ``y_d`` and ``h >= 1`` of its derivatives at ``t_0``), whatever
    the member. ``None`` when the trajectory does not have that derivative."""
    form, trajectory = search.form, search.trajectory
    order = form.rho + 1
    if trajectory.max_derivative is not None and order > trajectory.max_derivative:
        return None
    return abs(float(trajectory.derivative([trajectory.t0], order, "+")[0])) * search.bounds.period / abs(form.CAB)

"""Automatic choice from the family: the smallest redefinition error within the torque limit, verified.

The paper chooses ``(Cdec_f, Cdec_s)``, the segments and ``h`` by trial and error and calls
the resulting family of answers the method's advantage. :func:`choose` searches it:

1. a coarse grid over segments, ``h``, ``(Cdec_f, Cdec_s)`` and the joining (dimensions
   the caller fixed are left alone), each member solved and measured in closed form;
2. the members ranked by redefinition error (those above ``max_torque`` left out) and
   verified in that order (solver independence and extended precision,
   :mod:`inversion.verify`) until one passes;
3. a refinement around it -- neighbouring segment counts and decay constants, the grid
   extended where the best member sits on its edge -- ranked and verified the same way;
4. the winner driven through the linear plant (the plant check) and held to the quality
   gate; if it fails, the next verified member.

The result is the verified member with the smallest ``max |y~ - y_d|`` whose peak torque
respects ``max_torque``, or an :class:`~inversion.errors.InversionError` that says what
the search found. Without ``max_torque`` the budget is
:data:`~inversion.member.TORQUE_MARGIN` (1.5) times the least peak torque the first stage found
within the quality gate, doubled as often as needed for a member within 1 % of the move: the
smallest error is otherwise often bought with a transient of tens or hundreds of times the
torque the move needs. ``max_torque=math.inf`` lifts it. The search
is recorded (members tried, failed and why, the torque budget and its rule, the trade not
made, time).
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from typing import Any, Callable, Iterable, Mapping

from numpy.typing import ArrayLike

from .config import DEFAULTS
from .errors import InversionError, SettingsError
from .member import FAILURES, MemberResult, evaluate_member, evaluate_members, rest_failure, segment_anchors, torque_budget
from .options import End, Joining, checked
from .settings import InversionSettings, describe
from .ssef import Solver
from .system import NormalForm
from .trajectory import Trajectory
from .verify import check_member

__all__ = ["choose", "batches", "GRID"]

#: The first stage's grid: the one the explorer maps by default (:data:`inversion.config.DEFAULTS`).
GRID: dict[str, tuple[Any, ...]] = DEFAULTS.grid.as_dict()
#: Members verified per stage before giving up on it.
_VERIFY_LIMIT = 40


def _top_h(trajectory: Trajectory, rho: int) -> int:
    """The largest ``h`` the trajectory's derivatives allow (``h + rho`` of them are needed)."""
    return 20 if trajectory.max_derivative is None else trajectory.max_derivative - rho


def _grid(fixed: Mapping[str, Any], trajectory: Trajectory, rho: int = 2) -> list[InversionSettings]:
    """The first stage's members, with the caller's fixed values."""
    segments: Iterable[Any] = (fixed["segments"],) if "segments" in fixed else GRID["segments"]
    top_h = _top_h(trajectory, rho)
    hs: Iterable[int] = (fixed["h"],) if "h" in fixed else tuple(h for h in GRID["h"] if h <= top_h)
    if "cdec" in fixed:
        cdecs: Iterable[tuple[float, float]] = ((float(fixed["cdec"][0]), float(fixed["cdec"][1])),)
    else:
        cdecs = itertools.product(GRID["cdec_fast"], GRID["cdec_slow"])
    joinings: Iterable[str] = (fixed["joining"],) if "joining" in fixed else GRID["joining"]
    eps = fixed.get("eps", 0.0)
    end = fixed.get("end", "free")
    out = []
    for k, h, cd, j in itertools.product(tuple(segments), tuple(hs), tuple(cdecs), tuple(joinings)):
        out.append(InversionSettings(segments=k if isinstance(k, int) else tuple(k), h=h, cdec=cd, joining=j, eps=eps, end=end))
    if not out:
        raise SettingsError("h", fixed.get("h"), f"an order the trajectory {trajectory.name} supports (h + {rho} <= {top_h + rho})")
    return out


def batches(members: Iterable[InversionSettings]) -> list[list[InversionSettings]]:
    """Members grouped into batches that share segments, ``h``, joining, ``eps`` and end (solved together)."""
    groups: dict[tuple[Any, ...], list[InversionSettings]] = {}
    for s in members:
        groups.setdefault((s.segments, s.h, s.joining, s.eps, s.end), []).append(s)
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
    return sorted(out, key=lambda s: (s.segment_count, s.h, s.cdec, s.joining))


def _alternatives(results: Iterable[MemberResult], chosen: MemberResult, count: int = 2) -> list[dict[str, Any]]:
    """The trade the choice did not make: members the search saw with markedly less torque (at most
    0.8 of the chosen one's) or markedly smaller error (at most half), within the quality gate.

    For each direction, ``count`` members at levels spaced geometrically to the extreme seen,
    each the best at its level. Not verified: ``invert(..., max_torque=...)`` makes that choice
    with the checks.
    """
    assert chosen.figures is not None
    usable = [r for r in results if r.status == "ok" and r.figures is not None and r.figures.max_error <= chosen.max_error]
    top_torque, top_error = chosen.figures.peak_torque, chosen.figures.max_error
    out: list[dict[str, Any]] = []

    def add(best: MemberResult, kind: str) -> None:
        entry = {"kind": kind, "settings": best.settings.to_dict(), "max_redefinition_error": best.figures.max_error,  # type: ignore[union-attr]
                 "peak_torque": best.figures.peak_torque}  # type: ignore[union-attr]
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


def choose(
    form: NormalForm,
    trajectory: Trajectory,
    *,
    fixed: Mapping[str, Any] | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: Solver | None = None,
    tol: float | None = None,
    progress: Callable[[str], None] | None = None,
) -> tuple[MemberResult, dict[str, Any]]:
    """Search the family for the verified member with the smallest redefinition error.

    Parameters
    ----------
    form : NormalForm
        The model's matrices.
    trajectory : Trajectory
        The desired trajectory.
    fixed : mapping, optional
        Values of ``segments``, ``h``, ``cdec``, ``joining``, ``eps`` the search keeps.
    max_error : float, optional
        Quality gate of the chosen member (m; default 5 % of the move).
    max_torque : float, optional
        Members with a larger peak torque (N m) are not chosen.
    initial_internal_state, solver, tol :
        As :func:`inversion.invert`.
    progress : callable, optional
        Receives a one-line message per stage.

    Returns
    -------
    member : MemberResult
        The chosen member, verified and plant-checked.
    record : dict
        The search: ``members`` tried, ``failed`` (count per reason), ``verified``,
        ``seconds``, ``objective`` and the chosen ``settings``.

    Raises
    ------
    InversionError
        If no member passes, with the best figures the search saw.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import invert, smoothstep
    >>> r = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 3))  # not the paper's trajectory
    >>> r.summary["relative_redefinition_error"] < 1e-4
    True
    >>> r.summary["auto"]["max_torque_rule"].split(" (")[0]
    '1.5 x the least peak torque within the quality gate'
    """
    fixed = dict(fixed or {})
    solver = DEFAULTS.solver if solver is None else solver
    tol = DEFAULTS.tol if tol is None else tol
    if "joining" in fixed:
        fixed["joining"] = checked(Joining, "joining", fixed["joining"])
    started = time.perf_counter()
    seen: dict[InversionSettings, MemberResult] = {}
    verified: dict[InversionSettings, bool] = {}
    failures: Counter[str] = Counter()

    def say(message: str) -> None:
        if progress is not None:
            progress(message)

    anchors: dict[tuple[Any, float], Any] = {}

    def run(candidates: list[InversionSettings]) -> None:
        fresh = [s for s in candidates if s not in seen]
        for batch in batches(fresh):
            base = batch[0]
            key = (base.segments, base.eps)
            if base.joining == Joining.ANCHORED and key not in anchors:
                anchors[key] = segment_anchors(form, trajectory, base)
            results = evaluate_members(form, trajectory, batch, initial_internal_state=initial_internal_state,
                                       anchors=anchors.get(key), solver=solver, tol=tol, max_error=math.inf, verify=False)
            for result in results:
                seen[result.settings] = result
                if result.status in FAILURES:
                    failures[result.status] += 1

    limit = {"torque": max_torque}

    def ranked() -> list[MemberResult]:
        usable = [r for r in seen.values() if r.status == "ok" and verified.get(r.settings, True) is not False]
        if limit["torque"] is not None:
            usable = [r for r in usable if r.figures is not None and r.figures.peak_torque <= limit["torque"]]
        return sorted(usable, key=lambda r: (r.figures.max_error if r.figures else math.inf, r.settings.segment_count))

    def best_verified() -> MemberResult | None:
        for count, result in enumerate(ranked()):
            if verified.get(result.settings):
                return result
            if count >= _VERIFY_LIMIT:
                return None
            assert result.redefinition is not None and result.figures is not None
            checks = check_member(result.redefinition, result.figures, primary=solver)
            failed = checks.failure()
            if failed is None and result.settings.end == End.REST:
                failed = rest_failure(result.redefinition, result.figures)
            verified[result.settings] = failed is None
            if failed is not None:
                failures[failed[0]] += 1
                continue
            return result
        return None

    grid = _grid(fixed, trajectory, form.rho)
    grid[0].boundaries(trajectory, form.rho)  # fixed segments that do not fit the trajectory: a user error
    say(f"auto: {len(grid)} members on the first grid")
    run(grid)
    rule = "given"
    if max_torque is None:
        budget = torque_budget([r.figures for r in seen.values() if r.status == "ok" and r.figures is not None], max_error)
        if budget is not None:
            limit["torque"], rule = budget
    best = best_verified()
    if best is not None:
        neighbours = _neighbours(best.settings, fixed, trajectory, form.rho)
        say(f"auto: best so far {describe(best.settings)} ({best.figures.max_error:.3g} m); {len(neighbours)} neighbours")  # type: ignore[union-attr]
        run(neighbours)
        best = best_verified()
    final: MemberResult | None = None
    while best is not None:
        final = evaluate_member(form, trajectory, best.settings, initial_internal_state=initial_internal_state,
                                solver=solver, tol=tol, max_error=max_error, max_torque=limit["torque"], verify=True, plant=True)
        if final.ok:
            break
        failures[final.status] += 1
        if final.status == "max-error":  # every other verified member is further from y_d
            final = None
            break
        verified[best.settings] = False
        final = None
        best = best_verified()
    seconds = time.perf_counter() - started
    torque = limit["torque"]
    record: dict[str, Any] = {
        "objective": "smallest max |y~ - y_d| among verified members"
        + ("" if torque is None else f" with peak torque <= {torque:.4g} N m"),
        "max_torque": torque,
        "max_torque_rule": rule,
        "members": len(seen),
        "succeeded": sum(1 for r in seen.values() if r.status == "ok"),
        "verified": sum(1 for v in verified.values() if v),
        "failed": dict(sorted(failures.items())),
        "fixed": {k: (list(v) if isinstance(v, tuple) else v) for k, v in fixed.items()},
        "seconds": seconds,
    }
    if final is None:
        usable = [r for r in seen.values() if r.figures is not None and r.status == "ok"]
        closest = min(usable, key=lambda r: r.figures.max_error, default=None)  # type: ignore[union-attr]
        detail = (
            f"; the smallest error seen was {closest.figures.max_error:.3g} m ({describe(closest.settings)}, "  # type: ignore[union-attr]
            f"peak torque {closest.figures.peak_torque:.3g} N m)" if closest is not None else ""  # type: ignore[union-attr]
        )
        reasons = ", ".join(f"{n} {k}" for k, n in sorted(failures.items())) or "none"
        raise InversionError(
            f"no member of the family passes: {len(seen)} tried in {seconds:.1f} s (failures: {reasons}){detail}"
            + ("" if torque is None else f"; max_torque = {torque:.4g} N m ({rule})")
        )
    record["settings"] = final.settings.to_dict()
    record["alternatives"] = _alternatives(seen.values(), final)
    say(f"auto: chose {describe(final.settings)}: {final.figures.max_error:.3g} m, peak torque "  # type: ignore[union-attr]
        f"{final.figures.peak_torque:.4g} N m ({len(seen)} members, {seconds:.1f} s)")  # type: ignore[union-attr]
    return final, record

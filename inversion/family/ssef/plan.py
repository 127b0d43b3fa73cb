"""The segment systems of a batch of members before they are solved: exponents, targets, anchors, rest rows.

:func:`build_plan` gathers, for members that share a segmentation, ``h``, joining and end,
everything the conditions of :mod:`inversion.family.ssef.conditions` need: the exponents of every
segment of every member (:mod:`inversion.family.ssef.basis`), the desired acceleration and its
derivatives at the joints, ``y_d`` and ``ydot_d`` there, the exact-tracking anchors of the
``anchored`` joining (:mod:`inversion.family.anchors`) and, for a rest end, the modal rows of
``X_I(t_f) = 0``. :func:`mode_kinds` says how each internal mode is evaluated.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from ...lti.internal import ModalInternalDynamics
from ...options import Edges, End, Joining
from ...signals.trajectory import Trajectory
from ..anchors import tracking_anchors
from .basis import exponents, matched_exponents, row_count

__all__ = ["SegmentPlan", "build_plan", "segment_durations", "mode_kinds", "FROM_START", "ANCHORED", "FREE"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


@dataclass(frozen=True, eq=False)
class SegmentPlan:
    """The segment systems of a batch of members, unsolved.

    The members of a batch share the segmentation, ``h``, the joining and the internal
    dynamics and differ in ``(Cdec_f, Cdec_s)``, hence in their exponents. Per-segment
    arrays run over a flat axis ``b K + k`` (member ``b``, segment ``k``); one member is a
    batch of one.

    Attributes
    ----------
    joining : str
        ``"paper"``, ``"position"`` or ``"anchored"``.
    h : int
        Order of smooth joining.
    bounds : ndarray, shape (K+1,)
        The joints ``t_0 .. t_K``.
    cdecs : ndarray, shape (B, 2)
        ``(Cdec_f, Cdec_s)`` of every member.
    mu : ndarray, shape (B K, r)
        Exponents of every segment of every member.
    accel_start, accel_end : ndarray, shape (K, h+1)
        ``yddot_d^(p)`` at ``t_k+`` and ``t_{k+1}-``.
    position : ndarray, shape (K+1, 2)
        ``y_d`` and ``ydot_d`` at the joints.
    anchors : ndarray of complex, shape (K+1, 2n), or None
        ``z*`` at the joints (``anchored`` only).
    z_initial : ndarray of complex, shape (2n,)
        The modal internal state at ``t_0``.
    modal : ModalInternalDynamics
        The diagonalised internal dynamics.
    matched : ndarray of int, shape (B K,)
        Matched exponentials in each segment (the last ones of ``mu``).
    singular : ndarray of bool, shape (B,)
        Members with an exponent equal to an unstable zero (the paper's conditions are
        then singular); they are not solved.
    end : str
        ``"free"`` (the paper's) or ``"rest"``: the last segment also ends on ``y_d(t_f)``,
        ``ydot_d(t_f)`` and ``X_I = 0`` (zero deflections and rates).
    rest_rows : tuple of (int, str)
        The modal rows of the rest conditions (every mode but the anchored unstable ones,
        which end on ``z*(t_f) = 0`` already): ``(i, "re")`` or ``(i, "im")``.
    pad : ndarray of int, shape (B K,)
        Columns that the segment does not use (the first ones of ``mu``; their
        coefficients are held at zero): the other segments' share of the last one's extra
        exponentials, so that every segment has ``r`` columns.
    """

    joining: str
    h: int
    bounds: FloatArray
    cdecs: FloatArray
    mu: FloatArray
    accel_start: FloatArray
    accel_end: FloatArray
    position: FloatArray
    anchors: ComplexArray | None
    z_initial: ComplexArray
    modal: ModalInternalDynamics
    matched: NDArray[np.intp]
    singular: NDArray[np.bool_]
    end: str = "free"
    rest_rows: tuple[tuple[int, str], ...] = ()
    pad: NDArray[np.intp] | None = None

    @property
    def extra(self) -> int:
        """The rows of the rest conditions (``end="rest"``; 0 otherwise)."""
        return 0 if self.end != End.REST else len(self.rest_rows) + (2 if self.joining == Joining.PAPER else 0)

    @cached_property
    def padding(self) -> NDArray[np.intp]:
        """:attr:`pad`, zeros when not given."""
        return np.zeros(self.mu.shape[0], dtype=np.intp) if self.pad is None else self.pad

    @property
    def members(self) -> int:
        """Number of members ``B``."""
        return int(self.cdecs.shape[0])

    @property
    def count(self) -> int:
        """Number of segments ``K`` of a member."""
        return int(self.bounds.size - 1)

    @cached_property
    def durations(self) -> FloatArray:
        """``T_k`` of one member (equal segments exactly equal, not up to the rounding of the joints)."""
        return segment_durations(self.bounds)

    @cached_property
    def flat_durations(self) -> FloatArray:
        """``T_k`` on the flat axis."""
        return np.tile(self.durations, self.members)

    @cached_property
    def flat_segment(self) -> NDArray[np.intp]:
        """The segment ``k`` of each flat index."""
        return np.tile(np.arange(self.count), self.members)

    @property
    def r(self) -> int:
        """Exponentials per segment."""
        return int(self.mu.shape[1])

    @cached_property
    def equal_segments(self) -> bool:
        """Whether all segments have the same duration and conditions (then a member's segments share their exponents)."""
        return bool(np.ptp(self.durations) == 0) and self.end == End.FREE

    @cached_property
    def rep(self) -> NDArray[np.intp]:
        """For each flat segment, the index of its system among :attr:`unique_flat`: the segments of
        a member with equal durations share one matrix (only the right-hand sides differ)."""
        n = self.members * self.count
        return np.arange(n) // self.count if self.equal_segments else np.arange(n)

    @cached_property
    def unique_flat(self) -> NDArray[np.intp]:
        """The flat segments whose matrices stand for all (one per member for equal segments)."""
        n = self.members * self.count
        return np.arange(self.members) * self.count if self.equal_segments else np.arange(n)

    def share(self, flat: NDArray[np.intp]) -> NDArray[np.intp] | None:
        """The block whose exponentials each block may reuse.

        For blocks of the flat segments ``flat`` on one common grid of local times: the block
        whose exponentials each may reuse (``None`` when segments differ in duration).

        Parameters
        ----------
        flat : NDArray[np.intp]
            Flat indices of the segments, one a block.
        """
        if not self.equal_segments:
            return None
        member = flat // self.count
        first = np.full(self.members, -1, dtype=np.intp)
        first[member[::-1]] = np.arange(flat.size)[::-1]
        return first[member]

    def subset(self, members: Sequence[int]) -> "SegmentPlan":
        """The plan of some of the members (in the order given).

        Parameters
        ----------
        members : Sequence[int]
            Indices of the members kept.
        """
        chosen = np.asarray(members, dtype=np.intp)
        flat = (chosen[:, None] * self.count + np.arange(self.count)[None, :]).ravel()
        return replace(self, cdecs=self.cdecs[chosen], mu=self.mu[flat], matched=self.matched[flat], singular=self.singular[chosen],
                       pad=None if self.pad is None else self.pad[flat])


def segment_durations(bounds: FloatArray) -> FloatArray:
    """Segment durations, near-equal ones made exactly equal.

    Segment durations; segments equal to a few ulps are made exactly equal.

    Parameters
    ----------
    bounds : FloatArray
        The segments' bounds (s).
    """
    durations = np.diff(bounds)
    if durations.size > 1 and np.ptp(durations) <= 1e-12 * durations.max():
        durations[:] = (bounds[-1] - bounds[0]) / durations.size
    return durations


def build_plan(
    modal: ModalInternalDynamics,
    trajectory: Trajectory,
    bounds: FloatArray,
    h: int,
    cdecs: Sequence[tuple[float, float]],
    joining: str,
    z_initial: ComplexArray,
    anchors: ComplexArray | None = None,
    end: str = "free",
    edges: str = "match",
) -> SegmentPlan:
    """The segment systems' data: exponents, targets, anchors.

    Parameters
    ----------
    modal : ModalInternalDynamics
    trajectory : Trajectory
    bounds : ndarray
        The joints ``t_0 .. t_K`` (validated).
    h : int
        Order of smooth joining.
    cdecs : sequence of (float, float)
        ``(Cdec_f, Cdec_s)`` of each member (validated).
    joining : str
        One of :data:`JOININGS`.
    z_initial : ndarray of complex
        Modal internal state at ``t_0``.
    anchors : ndarray of complex, optional
        :func:`~inversion.family.anchors.tracking_anchors` for these bounds (computed if not
        given; the explorer shares them between members).
    end : {"free", "rest"}
        ``"rest"``: the last segment also ends at rest (module docstring); it has ``E`` more
        exponentials, which the other segments carry as unused columns.
    edges : {"match", "rest"}
        ``"rest"``: at ``t_0`` and ``t_f`` the first ``h`` derivatives of ``yddot~`` are zero
        instead of ``y_d``'s (:class:`~inversion.options.Edges`); the same rows, other targets.
    """
    durations = segment_durations(np.asarray(bounds, dtype=float))
    K = durations.size
    cd = np.asarray(cdecs, dtype=float).reshape(-1, 2)
    B = cd.shape[0]
    rest_rows = _rest_rows(modal, joining) if end == End.REST else ()
    extra_rows = 0 if end != End.REST else len(rest_rows) + (2 if joining == Joining.PAPER else 0)
    base = row_count(joining, h, len(modal.rows))
    r = base + extra_rows
    mu = np.empty((B * K, r))
    matched = np.zeros(B * K, dtype=np.intp)
    pad = np.zeros(B * K, dtype=np.intp)
    distinct: dict[tuple[float, float, float, bool], tuple[FloatArray, int]] = {}  # equal segments share exponents
    for b, (fast, slow) in enumerate(cd):
        for k, T in enumerate(durations):
            last = end == End.REST and k == K - 1
            key = (float(fast), float(slow), float(T), last)
            if key not in distinct:
                fitted = matched_exponents(modal, key[2], key[0]) if joining == Joining.ANCHORED else np.zeros(0)
                own = exponents(key[2], key[0], key[1], (r if last else base) - fitted.size)
                unused = np.full(0 if last else extra_rows, own[0])  # held at zero by identity rows
                distinct[key] = (np.r_[unused, own, fitted], fitted.size)
            mu[b * K + k], matched[b * K + k] = distinct[key]
            pad[b * K + k] = 0 if last else extra_rows
    singular = np.zeros(B, dtype=bool)
    if joining != Joining.ANCHORED and modal.rows:
        lam = modal.lam[modal.row_modes]
        gap = np.abs(mu[:, :, None] - lam[None, None, :]).min(axis=(1, 2)).reshape(B, K).min(axis=1)
        singular = gap <= 1e-12 * max(float(np.abs(lam).max()), 1.0)
    accel_start = trajectory.derivatives(bounds[:-1], range(2, h + 3), "+")
    accel_end = trajectory.derivatives(bounds[1:], range(2, h + 3), "-")
    if edges == Edges.REST:  # the output leaves and reaches rest: yddot~ joins yddot_d there, its derivatives are zero
        accel_start[0, 1:] = 0.0
        accel_end[-1, 1:] = 0.0
    position = np.vstack([trajectory.derivatives(bounds[:1], range(2), "+"), trajectory.derivatives(bounds[1:], range(2), "-")])
    if joining == Joining.ANCHORED and anchors is None:
        anchors = tracking_anchors(modal, trajectory, bounds)
    return SegmentPlan(
        joining=joining,
        h=h,
        bounds=np.asarray(bounds, dtype=float),
        cdecs=cd,
        mu=mu,
        accel_start=accel_start,
        accel_end=accel_end,
        position=position,
        anchors=anchors if joining == Joining.ANCHORED else None,
        z_initial=np.asarray(z_initial, dtype=complex),
        modal=modal,
        matched=matched,
        singular=singular,
        end=end,
        rest_rows=rest_rows,
        pad=pad if extra_rows else None,
    )


def _rest_rows(modal: ModalInternalDynamics, joining: str) -> tuple[tuple[int, str], ...]:
    """The modal rows of ``X_I(t_f) = 0``: a real mode's value, a complex pair's real and imaginary
    parts of one member; not the anchored unstable modes (they end on ``z*(t_f) = 0`` already)."""
    from modelgen.zeros import IMAGINARY_TOL

    lam = modal.lam
    rows: list[tuple[int, str]] = []
    taken: set[int] = set()
    for i in range(lam.size):
        if i in taken or (joining == Joining.ANCHORED and modal.unstable[i]):
            continue
        taken.add(i)
        if abs(lam[i].imag) <= IMAGINARY_TOL * abs(lam[i]):
            rows.append((i, "re"))
            continue
        partner = [j for j in range(lam.size) if j not in taken and abs(lam[j] - lam[i].conjugate()) <= 1e-8 * abs(lam[i])]
        if partner:
            taken.add(partner[0])
        rows += [(i, "re"), (i, "im")]
    return tuple(rows)


FROM_START, ANCHORED, FREE = 0, 1, 2


def mode_kinds(plan: SegmentPlan) -> NDArray[np.intp]:
    """How each internal mode is evaluated.

    How each internal mode is evaluated: 0 from its start value (stable), 1 anchored at the
    segment's end (``anchored`` unstable), 2 without complementary part (the paper's unstable,
    and the free ones of :mod:`inversion.lti.zero_dynamics` with any joining).

    Parameters
    ----------
    plan : SegmentPlan
        The batch's segment systems.
    """
    modal = plan.modal
    kinds = np.where(~modal.unstable, FROM_START, ANCHORED if plan.joining == Joining.ANCHORED else FREE)
    return np.where(modal.free, FREE, kinds).astype(np.intp)

"""The segment problem: output redefinition by a summation of stable exponential functions.

In segment ``k`` (local time ``s = t - t_k`` in ``[0, T]``) the desired acceleration is
replaced by (Eq. (29))::

    yddot~(s) = sum_{j=1}^{r} c_j exp(mu_j s),   mu_j <= 0

with ``mu_j`` equally spaced from ``ln(Cdec_s)/T`` to ``ln(Cdec_f)/T`` (Eqs. (34)-(36)).
The ``r`` coefficients solve one linear condition per exponential. Three *joinings*
choose the conditions:

``paper`` -- the paper's, Eqs. (30)-(31), ``r = 2(h+1) + n_u``:

1. smooth joining, ``p = 0..h``: ``yddot~^(p)`` equals ``yddot_d^(p)`` at ``t_k+`` and
   ``t_{k+1}-``;
2. bounded unstable modes with continuity (conditions 3-2 and 3-3): for ``i`` in ``U``,
   ``sum_j beta_i c_j / (mu_j - lambda_i) = z_i(t_k)`` -- the complementary part of
   ``z_i`` vanishes and it starts where the previous segment ended. A complex pair gives
   the real and imaginary parts of one member, so ``c`` stays real.

``y~`` and ``ydot~`` are carried from segment to segment and drift from ``y_d``; so is the
unstable state, which short segments amplify geometrically.

``position`` -- the paper's conditions plus ``ydot~(t_{k+1}) = ydot_d(t_{k+1})`` and
``y~(t_{k+1}) = y_d(t_{k+1})`` at every joint (``r = 2(h+1) + 2 + n_u``): no drift of the
output, but the unstable state is still carried.

``anchored`` -- smooth and position joining as ``position``, and the unstable modes start
and end every segment on the exact-tracking values ``z*`` of :mod:`inversion.anchors`
(a finite-horizon condition instead of 3-2)::

    z_i(t_k) + beta_i int_0^T exp(-lambda_i u) yddot~(u) du = exp(-lambda_i T) z*_i(t_{k+1})

The segments then pass no unstable state to each other (nothing to amplify), ``y_d``
satisfies the conditions of every interior segment, and the systems are independent. An
unstable zero much faster than the slow exponentials (``|lambda| > 2 |mu_f|``) makes its
condition nearly a combination of the smooth-joining rows (it only sees the first
``1/|lambda|`` seconds of the segment); for such zeros the basis takes *matched*
exponentials in place of as many slow ones: ``-|lambda|`` for a real zero,
``-2|lambda|/3`` and ``-4|lambda|/3`` for a complex pair. That keeps the segment systems of
models with many modes solvable in double precision (condition numbers of 1e6-1e9 where
the equally spaced basis reaches 1e15-1e18).

``end="rest"`` (the paper's Remark 2) adds to the last segment ``y~(t_f) = y_d(t_f)``,
``ydot~(t_f) = ydot_d(t_f)`` (the ``paper`` joining lacks them) and ``X_I(t_f) = 0`` -- zero
deflections and rates -- for every mode not anchored already: as many more exponentials
there. The other segments keep the same number of columns, the extra ones held at zero by
identity rows (and absent from every other row), so that all systems still solve in one batch.

Everything then follows in closed form (no ODE is integrated): ``ydot~``, ``y~``, and each
internal mode ``z_i(s) = sum_j W_ji exp(mu_j s) + K_i exp(lambda_i (s - a_i))`` with
``W_ji = beta_i c_j/(mu_j - lambda_i)``, anchored at ``a_i = 0`` (stable modes: ``K_i``
from ``z_i(0)``), at ``a_i = T`` (anchored unstable modes: from ``z*_i(t_{k+1})``) or
without a complementary part (``K_i = 0``, the paper's unstable modes).

The assembly and the evaluation work in double or in extended precision (the inputs'
``dtype``); :mod:`inversion.verify` uses that to re-evaluate a result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any, Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InversionError
from .exponentials import complex_dtype, exp_difference, exp_integrals
from .anchors import tracking_anchors
from .internal import ModalInternalDynamics
from .trajectory import Trajectory, derivative_key

__all__ = [
    "JOININGS",
    "Joining",
    "Solver",
    "SegmentPlan",
    "SegmentSolution",
    "exponents",
    "matched_exponents",
    "row_count",
    "PlanSolution",
    "build_plan",
    "segment_matrices",
    "solve_plan",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
Joining = Literal["paper", "position", "anchored"]
Solver = Literal["lu", "lstsq", "ge"]

#: Joining variants (see the module docstring).
JOININGS: tuple[str, ...] = ("paper", "position", "anchored")
#: An unstable zero faster than this multiple of the fastest slow exponent gets a matched
#: exponential in the ``anchored`` joining.
MATCH_RATIO = 2.0
#: Smallest ratio between two matched rates (keeps their columns apart).
_MATCH_GAP = 1.25
#: ``|mu_j - lambda_i| T`` below which a mode's term is evaluated by the series of
#: :func:`~inversion.exponentials.exp_difference` instead of the split form.
_SERIES_LIMIT = 0.2


def exponents(duration: float, cdec_fast: float, cdec_slow: float, r: int) -> FloatArray:
    """Equally spaced exponents of one segment, Eqs. (34)-(36).

    ``mu_s = ln(Cdec_s)/T``, ``mu_f = ln(Cdec_f)/T``, ``mu_j = mu_s + (mu_f - mu_s)(j-1)/(r-1)``.
    ``Cdec_s = 1`` gives ``mu_1 = 0``: a constant term.
    """
    mu_s = math.log(cdec_slow) / duration
    mu_f = math.log(cdec_fast) / duration
    return np.asarray(mu_s + (mu_f - mu_s) * np.arange(r) / max(r - 1, 1))


def matched_exponents(modal: ModalInternalDynamics, duration: float, cdec_fast: float) -> FloatArray:
    """Exponents matched to the unstable zeros faster than the slow ones (``anchored``).

    A real zero ``lambda`` with ``|lambda| > MATCH_RATIO |ln(Cdec_f)|/T`` gives
    ``-|lambda|``; a complex pair gives ``-2|lambda|/3`` and ``-4|lambda|/3`` (one per
    constraint row). Rates closer than a factor 1.25 are spread to that ratio.
    """
    fastest = abs(math.log(cdec_fast)) / duration
    pairs = {i for i, part in modal.rows if part == "im"}
    rates: list[float] = []
    for i, part in modal.rows:
        size = float(abs(modal.lam[i]))
        if size <= MATCH_RATIO * fastest:
            continue
        if i not in pairs:
            rates.append(size)
        else:
            rates.append(size * (2.0 / 3.0 if part == "re" else 4.0 / 3.0))
    rates.sort()
    for k in range(1, len(rates)):
        rates[k] = max(rates[k], _MATCH_GAP * rates[k - 1])
    return -np.asarray(rates, dtype=float)


def row_count(joining: str, h: int, n_unstable_rows: int) -> int:
    """``r``: conditions (and exponentials) per segment."""
    return 2 * (h + 1) + (0 if joining == "paper" else 2) + n_unstable_rows


@dataclass(frozen=True, eq=False)
class SegmentPlan:
    """Everything about the segment systems of a batch of members except their solution.

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
        return 0 if self.end != "rest" else len(self.rest_rows) + (2 if self.joining == "paper" else 0)

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
        return _durations(self.bounds)

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
        return bool(np.ptp(self.durations) == 0) and self.end == "free"

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
        """For blocks of the flat segments ``flat`` on one common grid of local times: the block
        whose exponentials each may reuse (``None`` when segments differ in duration)."""
        if not self.equal_segments:
            return None
        member = flat // self.count
        first = np.full(self.members, -1, dtype=np.intp)
        first[member[::-1]] = np.arange(flat.size)[::-1]
        return first[member]

    def subset(self, members: Sequence[int]) -> "SegmentPlan":
        """The plan of some of the members (in the order given)."""
        chosen = np.asarray(members, dtype=np.intp)
        flat = (chosen[:, None] * self.count + np.arange(self.count)[None, :]).ravel()
        return replace(self, cdecs=self.cdecs[chosen], mu=self.mu[flat], matched=self.matched[flat], singular=self.singular[chosen],
                       pad=None if self.pad is None else self.pad[flat])


def _durations(bounds: FloatArray) -> FloatArray:
    """Segment durations; segments equal to a few ulps are made exactly equal."""
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
) -> SegmentPlan:
    """The segment systems' data of a batch of members: exponents, targets, anchors.

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
        :func:`~inversion.anchors.tracking_anchors` for these bounds (computed if not
        given; the explorer shares them between members).
    end : {"free", "rest"}
        ``"rest"``: the last segment also ends at rest (module docstring); it has ``E`` more
        exponentials, which the other segments carry as unused columns.
    """
    durations = _durations(np.asarray(bounds, dtype=float))
    K = durations.size
    cd = np.asarray(cdecs, dtype=float).reshape(-1, 2)
    B = cd.shape[0]
    rest_rows = _rest_rows(modal, joining) if end == "rest" else ()
    extra_rows = 0 if end != "rest" else len(rest_rows) + (2 if joining == "paper" else 0)
    base = row_count(joining, h, len(modal.rows))
    r = base + extra_rows
    mu = np.empty((B * K, r))
    matched = np.zeros(B * K, dtype=np.intp)
    pad = np.zeros(B * K, dtype=np.intp)
    distinct: dict[tuple[float, float, float, bool], tuple[FloatArray, int]] = {}  # equal segments share exponents
    for b, (fast, slow) in enumerate(cd):
        for k, T in enumerate(durations):
            last = end == "rest" and k == K - 1
            key = (float(fast), float(slow), float(T), last)
            if key not in distinct:
                fitted = matched_exponents(modal, key[2], key[0]) if joining == "anchored" else np.zeros(0)
                own = exponents(key[2], key[0], key[1], (r if last else base) - fitted.size)
                unused = np.full(0 if last else extra_rows, own[0])  # held at zero by identity rows
                distinct[key] = (np.r_[unused, own, fitted], fitted.size)
            mu[b * K + k], matched[b * K + k] = distinct[key]
            pad[b * K + k] = 0 if last else extra_rows
    singular = np.zeros(B, dtype=bool)
    if joining != "anchored" and modal.rows:
        lam = modal.lam[modal.row_modes]
        gap = np.abs(mu[:, :, None] - lam[None, None, :]).min(axis=(1, 2)).reshape(B, K).min(axis=1)
        singular = gap <= 1e-12 * max(float(np.abs(lam).max()), 1.0)
    accel_start = trajectory.derivatives(bounds[:-1], range(2, h + 3), "+")
    accel_end = trajectory.derivatives(bounds[1:], range(2, h + 3), "-")
    position = np.vstack([trajectory.derivatives(bounds[:1], range(2), "+"), trajectory.derivatives(bounds[1:], range(2), "-")])
    if joining == "anchored" and anchors is None:
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
        anchors=anchors if joining == "anchored" else None,
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
        if i in taken or (joining == "anchored" and modal.unstable[i]):
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


def _unstable_rows(plan: SegmentPlan, mu: NDArray[Any], T: NDArray[Any], cdtype: np.dtype[Any]) -> NDArray[Any]:
    """Unstable-mode rows of every flat segment, shape (B K, n_rows, r), in the precision of ``mu``."""
    modal = plan.modal
    idx, imag = modal.row_modes, modal.row_imag
    lam = modal.lam[idx].astype(cdtype)[None, :, None]
    beta = modal.beta[idx].astype(cdtype)[None, :, None]
    diff = mu[:, None, :] - lam
    if plan.joining == "anchored":
        rows = beta * exp_difference(diff, np.zeros((), dtype=cdtype), T[:, None, None])
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            rows = beta / diff
    return np.where(imag[None, :, None], rows.imag, rows.real)


def _dtypes(dtype: Any) -> tuple[np.dtype[Any], np.dtype[Any]]:
    """The real and complex types of a precision."""
    dtype = np.dtype(dtype)
    return dtype, complex_dtype(np.zeros(0, dtype=dtype))


def segment_matrices(plan: SegmentPlan, dtype: Any = np.float64, flat: NDArray[np.intp] | None = None) -> NDArray[Any]:
    """The conditions of flat segments as matrices, shape (len(flat), r, r) (module docstring).

    Parameters
    ----------
    plan : SegmentPlan
    dtype : numpy dtype
        ``float64`` or ``longdouble``.
    flat : ndarray of int, optional
        Which flat segments (default: all).
    """
    dtype, cdtype = _dtypes(dtype)
    flat = np.arange(plan.mu.shape[0]) if flat is None else flat
    mu = plan.mu[flat].astype(dtype)
    T = plan.flat_durations[flat].astype(dtype)
    n, r = mu.shape
    h1 = plan.h + 1
    A = np.empty((n, r, r), dtype=dtype)
    eT = np.exp(mu * T[:, None])
    powers = mu[:, None, :] ** np.arange(h1, dtype=dtype)[None, :, None]  # (n, h+1, r)
    A[:, 0 : 2 * h1 : 2] = powers  # Eq. (30) at t_k+
    A[:, 1 : 2 * h1 : 2] = powers * eT[:, None, :]  # and at t_{k+1}-
    row = 2 * h1
    _, p1, p2 = exp_integrals(mu * T[:, None])
    if plan.joining != "paper":
        A[:, row] = T[:, None] * p1  # ydot~(T) - ydot~(0)
        A[:, row + 1] = (T * T)[:, None] * p2  # y~(T) - y~(0) - ydot~(0) T
        row += 2
    E = plan.extra
    if E:  # the rest conditions in the last segment; in the others, identity rows hold the unused columns at zero
        pad = plan.padding[flat]
        last = pad == 0
        block = np.zeros((n, E, r), dtype=dtype)
        if np.any(last):
            q = 0
            if plan.joining == "paper":
                block[last, 0] = T[last, None] * p1[last]
                block[last, 1] = (T[last] * T[last])[:, None] * p2[last]
                q = 2
            ends = _end_rows(plan, dtype, cdtype, flat[last])["z"]  # (., r, 2n): c -> z(T)
            for m, (i, part) in enumerate(plan.rest_rows):
                block[last, q + m] = ends[:, :, i].imag if part == "im" else ends[:, :, i].real
        A[:, row : row + E] = block
        if plan.modal.rows:
            A[:, row + E :] = _unstable_rows(plan, mu, T, cdtype)
        unused = ~last
        A[np.ix_(unused, np.arange(r), np.arange(E))] = 0  # the unused columns appear in their identity rows only
        A[unused, row : row + E, :E] = np.eye(E, dtype=dtype)
        return A
    if plan.modal.rows:
        A[:, row:] = _unstable_rows(plan, mu, T, cdtype)
    return A


_FROM_START, _ANCHORED, _FREE = 0, 1, 2


def _mode_kinds(plan: SegmentPlan) -> NDArray[np.intp]:
    """How each internal mode is evaluated: 0 from its start value (stable), 1 anchored at the
    segment's end (``anchored`` unstable), 2 without complementary part (the paper's unstable,
    and the free ones of :mod:`inversion.zero_dynamics` with any joining)."""
    modal = plan.modal
    kinds = np.where(~modal.unstable, _FROM_START, _ANCHORED if plan.joining == "anchored" else _FREE)
    return np.where(modal.free, _FREE, kinds).astype(np.intp)


def _end_rows(plan: SegmentPlan, dtype: np.dtype[Any], cdtype: np.dtype[Any], flat: NDArray[np.intp]) -> dict[str, NDArray[Any]]:
    """The linear maps from ``c`` to the end values of the flat segments ``flat`` (start values enter separately).

    ``ydot~(T) = ydot~(0) + ydot . c``, ``y~(T) = y~(0) + ydot~(0) T + y . c``,
    ``z(T) = growth z(0) + z . c`` (``growth`` = ``e^{lambda T}`` for the modes evaluated from
    their start, 0 for the paper's unstable ones; anchored modes end on their anchor).
    """
    mu = plan.mu[flat].astype(dtype)
    T = plan.flat_durations[flat].astype(dtype)
    modal = plan.modal
    lam = modal.lam.astype(cdtype)
    beta = modal.beta.astype(cdtype)
    kinds = _mode_kinds(plan)
    _, p1, p2 = exp_integrals(mu * T[:, None])
    z = np.zeros(mu.shape + (lam.size,), dtype=cdtype)
    growth = np.zeros((mu.shape[0], lam.size), dtype=cdtype)
    start = kinds == _FROM_START
    if np.any(start):
        z[:, :, start] = beta[start] * exp_difference(mu[:, :, None], lam[start][None, None, :], T[:, None, None])
        growth[:, start] = np.exp(np.outer(T, lam[start]))
    free = kinds == _FREE
    if np.any(free):
        with np.errstate(divide="ignore", invalid="ignore"):
            z[:, :, free] = beta[free] * np.exp(mu * T[:, None])[:, :, None] / (mu[:, :, None] - lam[free])
    return {"ydot": T[:, None] * p1, "y": (T * T)[:, None] * p2, "z": z, "growth": growth}


def _rhs(plan: SegmentPlan, flat: NDArray[np.intp], y0: NDArray[Any], ydot0: NDArray[Any], z0: NDArray[Any], dtype: np.dtype[Any]) -> NDArray[Any]:
    """Right-hand sides of the flat segments ``flat`` for their start states, shape (len(flat), r)."""
    cdtype = complex_dtype(np.zeros(0, dtype=dtype))
    k = plan.flat_segment[flat]
    h1 = plan.h + 1
    b = np.empty((flat.size, plan.r), dtype=dtype)
    b[:, 0 : 2 * h1 : 2] = plan.accel_start[k]
    b[:, 1 : 2 * h1 : 2] = plan.accel_end[k]
    row = 2 * h1
    T = plan.durations[k].astype(dtype)
    if plan.joining != "paper":
        end = plan.position[k + 1].astype(dtype)
        b[:, row] = end[:, 1] - ydot0
        b[:, row + 1] = end[:, 0] - y0 - ydot0 * T
        row += 2
    E = plan.extra
    if E:  # rest: y_d(t_f), ydot_d(t_f) (the paper's joining) and z(T) = 0; zero for the unused columns
        b[:, row : row + E] = 0
        last = plan.padding[flat] == 0
        if np.any(last):
            q = 0
            if plan.joining == "paper":
                end = plan.position[k[last] + 1].astype(dtype)
                b[last, row] = end[:, 1] - ydot0[last]
                b[last, row + 1] = end[:, 0] - y0[last] - ydot0[last] * T[last]
                q = 2
            target = -_end_rows(plan, dtype, cdtype, flat[last])["growth"] * z0[last].astype(cdtype)  # X_I(t_f) = 0
            for m, (i, part) in enumerate(plan.rest_rows):
                b[last, row + q + m] = target[:, i].imag if part == "im" else target[:, i].real
        row += E
    modal = plan.modal
    if modal.rows:
        idx, imag = modal.row_modes, modal.row_imag
        z_start = z0[:, idx].astype(cdtype)
        if plan.joining == "anchored":
            assert plan.anchors is not None
            lam = modal.lam[idx].astype(cdtype)
            value = np.exp(-np.outer(T, lam)) * plan.anchors[k + 1][:, idx].astype(cdtype) - z_start
        else:
            value = z_start
        b[:, row:] = np.where(imag[None, :], value.imag, value.real)
    return b


def _ge_factor(A: NDArray[Any]) -> tuple[NDArray[Any], NDArray[np.intp]]:
    """LU factorisation with partial pivoting in the precision of ``A``, batched.

    LAPACK works in double only; this small dense factorisation (``r <= ~40``) lets
    :mod:`inversion.verify` solve the segment systems in ``longdouble``.

    Parameters
    ----------
    A : ndarray, shape (K, n, n)

    Returns
    -------
    LU : ndarray, shape (K, n, n)
        ``U`` on and above the diagonal, the multipliers of ``L`` below it.
    perm : ndarray of int, shape (K, n)
        Row ``i`` of the factorised matrix is row ``perm[i]`` of ``A``.
    """
    LU = A.copy()
    K, n, _ = LU.shape
    batch = np.arange(K)
    perm = np.tile(np.arange(n), (K, 1))
    for col in range(n):
        pivot = col + np.argmax(np.abs(LU[:, col:, col]), axis=1)
        for M in (LU, perm):
            top = M[batch, col].copy()
            M[batch, col] = M[batch, pivot]
            M[batch, pivot] = top
        factors = LU[:, col + 1 :, col] / LU[:, col, col][:, None]
        LU[:, col + 1 :, col + 1 :] -= factors[:, :, None] * LU[:, col, col + 1 :][:, None, :]
        LU[:, col + 1 :, col] = factors
    return LU, perm


def _ge_substitute(LU: NDArray[Any], perm: NDArray[np.intp], B: NDArray[Any]) -> NDArray[Any]:
    """Solve with :func:`_ge_factor`'s factors for right-hand sides ``B`` (shape (K, n, m))."""
    K, n, _ = LU.shape
    X = B[np.arange(K)[:, None], perm].copy()
    for row in range(1, n):  # forward: L has a unit diagonal
        X[:, row] -= np.einsum("kj,kjm->km", LU[:, row, :row], X[:, :row])
    for row in range(n - 1, -1, -1):
        X[:, row] = (X[:, row] - np.einsum("kj,kjm->km", LU[:, row, row + 1 :], X[:, row + 1 :])) / LU[:, row, row][:, None]
    return X


@dataclass(frozen=True, eq=False)
class _Scaled:
    """Row- and column-equilibrated segment matrices."""

    matrices: NDArray[Any]
    row_scale: NDArray[Any]
    col_scale: NDArray[Any]

    @classmethod
    def of(cls, A: NDArray[Any]) -> "_Scaled":
        with np.errstate(invalid="ignore"):
            row_scale = np.abs(A).max(axis=2)
            row_scale[~(row_scale > 0)] = 1
            As = A / row_scale[:, :, None]
            col_scale = np.abs(As).max(axis=1)
            col_scale[~(col_scale > 0)] = 1
        return cls(As / col_scale[:, None, :], row_scale, col_scale)

    def take(self, rows: NDArray[np.intp]) -> "_Scaled":
        """The matrices ``rows``."""
        return _Scaled(self.matrices[rows], self.row_scale[rows], self.col_scale[rows])

    @cached_property
    def _finite(self) -> NDArray[np.bool_]:
        return np.asarray(np.all(np.isfinite(self.matrices), axis=(1, 2)))

    @cached_property
    def _lu(self) -> tuple[NDArray[Any], NDArray[np.intp]]:
        """LU factors of every matrix in its own precision (``ge``), computed once for every right-hand side."""
        M = np.where(self._finite[:, None, None], self.matrices, np.eye(self.matrices.shape[1], dtype=self.matrices.dtype))
        with np.errstate(all="ignore"):
            return _ge_factor(M)

    @cached_property
    def _svd(self) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
        """``U^T``, ``1/S`` (zero below a relative cutoff of ``r eps``) and ``V`` of every matrix (``lstsq``)."""
        M = self.matrices
        Ut = np.full(M.shape, np.nan)
        inv = np.full(M.shape[:2], np.nan)
        V = np.full(M.shape, np.nan)
        good = self._finite
        if np.any(good):
            try:
                U, S, Vh = np.linalg.svd(M[good])
            except np.linalg.LinAlgError:
                return Ut, inv, V
            cutoff = S[:, :1] * np.finfo(float).eps * M.shape[-1]
            Ut[good] = np.transpose(U, (0, 2, 1))
            inv[good] = np.where(S > cutoff, 1.0 / np.where(S > 0, S, 1.0), 0.0)
            V[good] = np.transpose(Vh, (0, 2, 1))
        return Ut, inv, V

    def solve(self, flat: NDArray[np.intp], B: NDArray[Any], solver: str) -> NDArray[Any]:
        """Solve the flat segments ``flat`` for right-hand sides ``B`` (shape (len(flat), r, m)); NaN where singular."""
        Bs = B / self.row_scale[flat][:, :, None]
        if solver == "ge":
            LU, perm = self._lu
            with np.errstate(all="ignore"):
                x = _ge_substitute(LU[flat], perm[flat], Bs)
            x[~self._finite[flat]] = np.nan
        elif solver == "lstsq":  # least squares by the SVD: V (S^+ (U^T b))
            Ut, inv, V = self._svd
            with np.errstate(all="ignore"):
                x = V[flat] @ (inv[flat][:, :, None] * (Ut[flat] @ Bs))
        else:
            M = self.matrices[flat]
            x = np.full(Bs.shape, np.nan, dtype=M.dtype)
            good = self._finite[flat] & np.all(np.isfinite(Bs), axis=(1, 2))
            if np.any(good):
                with np.errstate(all="ignore"):
                    try:
                        x[good] = np.linalg.solve(M[good], Bs[good])  # LAPACK gesv: LU with partial pivoting
                    except np.linalg.LinAlgError:
                        for i in np.flatnonzero(good):  # find the singular ones
                            try:
                                x[i] = np.linalg.solve(M[i], Bs[i])
                            except np.linalg.LinAlgError:
                                pass
        return np.asarray(x / self.col_scale[flat][:, :, None])

    def conditions(self) -> FloatArray:
        """2-norm condition numbers of the scaled matrices (double precision)."""
        M = np.asarray(self.matrices, dtype=float)
        out = np.full(M.shape[0], math.inf)
        finite = np.all(np.isfinite(M), axis=(1, 2))
        if np.any(finite):
            singular = np.linalg.svd(M[finite], compute_uv=False)
            with np.errstate(divide="ignore"):
                out[finite] = np.where(singular[:, -1] > 0, singular[:, 0] / singular[:, -1], math.inf)
        return out


def _groups(share: NDArray[np.intp] | None) -> tuple[NDArray[np.intp], int] | None:
    """``(representatives, group size)`` when ``share`` forms equal runs of consecutive blocks."""
    if share is None or share.size == 0:
        return None
    starts = np.flatnonzero(np.r_[True, share[1:] != share[:-1]])
    size = share.size // starts.size
    if starts.size * size != share.size or not np.array_equal(starts, np.arange(starts.size) * size):
        return None
    reps = share[starts]
    if not np.array_equal(reps, starts) or np.unique(reps).size != reps.size:
        return None
    return reps, int(size)


class Coefficients:
    """The solved segments of a batch of members, stacked: a vectorised closed-form evaluator.

    ``yddot~ = sum_j c_kj e^{mu_kj s}`` with its integrals from the start values, and each
    internal mode ``z_i = sum_j W_kji e^{mu_kj s} + K_ki e^{lambda_i (s - a_ki)}`` plus the
    terms of exponents within ``0.2/T`` of ``lambda_i`` (cancellation-free, through
    :func:`exp_difference`). ``X_I = Re(V z)`` is formed from real coefficients. Any set
    of (segment, local time) points is evaluated in one pass, in the precision of ``c``.
    """

    def __init__(self, plan: SegmentPlan, c: NDArray[Any], y0: NDArray[Any], ydot0: NDArray[Any], z0: NDArray[Any]):
        dtype = c.dtype
        cdtype = complex_dtype(c)
        modal = plan.modal
        self.plan = plan
        self.mu = plan.mu.astype(dtype)
        self.c = c
        self.T = plan.flat_durations.astype(dtype)
        self.y0 = y0
        self.ydot0 = ydot0
        self.z0 = z0
        self.lam = modal.lam.astype(cdtype)
        self.beta = modal.beta.astype(cdtype)
        self.V = modal.V.astype(cdtype)
        kinds = _mode_kinds(plan)
        zT = np.zeros_like(z0)
        if plan.joining == "anchored":
            assert plan.anchors is not None
            zT = plan.anchors[plan.flat_segment + 1].astype(cdtype)
        diff = self.mu[:, :, None] - self.lam[None, None, :]
        apart = (np.abs(diff) * self.T[:, None, None] >= _SERIES_LIMIT) | (kinds == _FREE)[None, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            W = np.where(apart, self.beta * c[:, :, None] / diff, 0)
        eT = np.exp(self.mu * self.T[:, None])
        from_start = z0 - W.sum(axis=1)
        from_end = zT - np.einsum("kr,kri->ki", eT, W)
        Kc = np.where(kinds == _FROM_START, from_start, np.where(kinds == _ANCHORED, from_end, 0))
        self.W = W
        self.Kc = Kc
        self.anchor = np.where(kinds == _ANCHORED, self.T[:, None], dtype.type(0)).astype(dtype)
        self.G = np.real(np.einsum("kri,ni->krn", W, self.V))  # coefficients of e^{mu s} in X_I
        self.KV = Kc[:, :, None] * self.V.T[None, :, :]  # (K, mode, state)
        self.kinds = kinds
        # exponent rates of the complementary terms: none for the paper's unstable modes (their
        # K is zero, and exp(lambda s) of a fast unstable zero would overflow)
        self.rate = np.where(kinds == _FREE, 0, self.lam)
        tk, tj, ti = np.nonzero(~apart)  # (k, j, i) of the exponents near a zero, sorted by k
        self.close = (tk, tj, ti)
        self._close_start = np.searchsorted(tk, np.arange(self.T.size))
        self._close_count = np.bincount(tk, minlength=self.T.size)

    def _close_terms(self, flat: NDArray[np.intp], s: NDArray[Any]) -> NDArray[Any] | None:
        """``z`` terms of the exponents near a zero, shape (S, M, 2n) (``None`` if there are none)."""
        count = self._close_count[flat]
        total = int(count.sum())
        if total == 0:
            return None
        tk, tj, ti = self.close
        q = np.repeat(np.arange(flat.size), count)
        t = np.repeat(self._close_start[flat], count) + np.arange(total) - np.repeat(np.cumsum(count) - count, count)
        k, j, i = tk[t], tj[t], ti[t]
        mu, lam, T = self.mu[k, j][:, None], self.lam[i][:, None], self.T[k][:, None]
        weight = (self.beta[i] * self.c[k, j])[:, None]
        sv = s[q]
        value = np.empty(sv.shape, dtype=self.W.dtype)
        anchored = self.kinds[i] == _ANCHORED
        st = ~anchored
        if np.any(st):  # from the start: beta c (e^{mu s} - e^{lam s})/(mu - lam)
            value[st] = weight[st] * exp_difference(mu[st], lam[st], sv[st])
        if np.any(anchored):  # from the end: -beta c e^{mu T} (e^{-lam w} - e^{-mu w})/(mu - lam), w = T - s
            a = anchored
            value[a] = -weight[a] * np.exp(mu[a] * T[a]) * exp_difference(-lam[a], -mu[a], T[a] - sv[a])
        out = np.zeros(s.shape + (self.lam.size,), dtype=self.W.dtype)
        np.add.at(out, (q[:, None], np.arange(s.shape[1])[None, :], i[:, None]), value)
        return out

    def evaluate_blocks(
        self, flat: NDArray[np.intp], s: NDArray[Any], modal_state: bool = False, share: NDArray[np.intp] | None = None,
        top: int = 4,
    ) -> dict[str, NDArray[Any]]:
        """Values at local times ``s[q, m]`` of the flat segments ``flat[q]``.

        Parameters
        ----------
        flat : ndarray of int, shape (S,)
        s : ndarray, shape (S, M)
        modal_state : bool
            Also return the modal state ``z``.
        share : ndarray of int, shape (S,), optional
            For each block, a block with the same exponents and times (equal segments of a
            member): the exponentials are computed once for each such group.
        top : int
            The highest derivative of ``y~`` returned (at least 2): ``jerk``, ``snap``, ``y(5)``,
            ... are the derivatives of ``yddot~`` (:func:`~inversion.trajectory.derivative_key`).

        Returns
        -------
        dict
            ``y, ydot, yddot`` and the derivatives up to ``top`` (shape (S, M)), ``XI``
            (shape (S, M, 2n)); with ``modal_state`` also ``z``.
        """
        groups = _groups(share)
        if groups is not None:
            return self._evaluate_groups(flat, s, modal_state, *groups, top)
        mu = self.mu[flat][:, None, :]
        c = self.c[flat][:, :, None]  # (S, r, 1): sums over exponents are products
        E, p1, p2 = exp_integrals(mu * s[:, :, None])
        y0 = self.y0[flat][:, None]
        ydot0 = self.ydot0[flat][:, None]
        out = {
            "yddot": (E @ c)[..., 0],
            "ydot": ydot0 + s * (p1 @ c)[..., 0],
            "y": y0 + ydot0 * s + s * s * (p2 @ c)[..., 0],
        }
        for p in range(3, top + 1):
            out[derivative_key(p)] = (E @ (c * mu[:, 0, :, None] ** (p - 2)))[..., 0]
        # complementary terms only for the modes that carry one in these blocks (none for the
        # paper's free unstable modes, whose exponentials would only be multiplied by zero)
        Kc = self.Kc[flat]
        active = np.flatnonzero(np.any(Kc != 0, axis=0))
        growth = np.exp((s[:, :, None] - self.anchor[flat][:, None, active]) * self.rate[active])
        close = self._close_terms(flat, s)
        XI = E @ self.G[flat] + np.real(growth @ self.KV[flat][:, active, :])
        if close is not None:
            XI = XI + np.real(close @ self.V.T)
        out["XI"] = XI
        if modal_state:
            z = E @ self.W[flat]
            z[..., active] += growth * Kc[:, None, active]
            out["z"] = z if close is None else z + close
        return out

    def magnitudes(self, flat: NDArray[np.intp], s: NDArray[Any], top: int = 2) -> dict[str, NDArray[Any]]:
        """Sums of the magnitudes of the terms behind ``y, ydot, yddot`` (and the derivatives up to
        ``top``) and ``X_I`` at the points ``(flat[q], s[q])`` (one point each): what their
        rounding is proportional to.

        The terms of the closed form can exceed its value by orders of magnitude (nearly
        dependent exponentials give large coefficients of alternating sign); rounding each
        term, and each ``exp``, by ``eps`` leaves an error up to ``eps`` times these sums.
        """
        s = np.asarray(s, dtype=float)
        c = np.abs(self.c[flat].astype(float))
        E, p1, p2 = exp_integrals(self.mu[flat].astype(float) * s[:, None])
        E, p1, p2 = np.abs(E), np.abs(p1), np.abs(p2)
        y0, ydot0 = np.abs(self.y0[flat].astype(float)), np.abs(self.ydot0[flat].astype(float))
        XI = np.einsum("qj,qjn->qn", E, np.abs(self.G[flat].astype(float)))
        growth = np.abs(np.exp((s[:, None] - self.anchor[flat].astype(float)) * np.where(self.Kc[flat] != 0, self.rate, 0)))
        XI = XI + np.einsum("qi,qin->qn", growth * (self.Kc[flat] != 0), np.abs(self.KV[flat]))
        close = self._close_terms(flat, s[:, None])
        if close is not None:
            XI = XI + np.abs(close[:, 0, :]) @ np.abs(self.V.T)
        out = {
            "yddot": (c * E).sum(axis=1),
            "ydot": ydot0 + s * (c * p1).sum(axis=1),
            "y": y0 + ydot0 * s + s * s * (c * p2).sum(axis=1),
            "XI": XI,
        }
        rate = np.abs(self.mu[flat].astype(float))
        for p in range(3, top + 1):
            out[derivative_key(p)] = (c * E * rate ** (p - 2)).sum(axis=1)
        return out

    def _evaluate_groups(
        self, flat: NDArray[np.intp], s: NDArray[Any], modal_state: bool, reps: NDArray[np.intp], size: int, top: int
    ) -> dict[str, NDArray[Any]]:
        """:meth:`evaluate_blocks` for groups of ``size`` consecutive blocks that share exponents and times.

        The exponentials are formed once per group, and every sum over exponents or modes
        becomes one matrix product per group (``(M, r) @ (r, size)``).
        """
        R = reps.size
        M = s.shape[1]
        mu = self.mu[flat[reps]][:, None, :]  # (R, 1, r)
        sr = s[reps]
        E, p1, p2 = exp_integrals(mu * sr[:, :, None])  # (R, M, r)
        growth = np.exp((sr[:, :, None] - self.anchor[flat[reps]][:, None, :]) * self.rate)  # (R, M, 2n)
        c = self.c[flat].reshape(R, size, -1)  # (R, G, r)
        ct = np.swapaxes(c, 1, 2)  # (R, r, G)

        def per_block(values: NDArray[Any]) -> NDArray[Any]:  # (R, M, G) -> (S, M)
            return np.swapaxes(values, 1, 2).reshape(R * size, M)

        ydot0 = self.ydot0[flat][:, None]
        out = {
            "yddot": per_block(E @ ct),
            "ydot": ydot0 + s * per_block(p1 @ ct),
            "y": self.y0[flat][:, None] + ydot0 * s + s * s * per_block(p2 @ ct),
        }
        for p in range(3, top + 1):
            out[derivative_key(p)] = per_block(E @ (ct * mu[:, 0, :, None] ** (p - 2)))

        def per_state(matrix: NDArray[Any], coefficients: NDArray[Any]) -> NDArray[Any]:
            # (R, M, k) @ (R, k, G * n) -> (S, M, n)
            k = coefficients.shape[-2]
            stacked = np.swapaxes(coefficients.reshape(R, size, k, -1), 1, 2).reshape(R, k, -1)
            return np.swapaxes((matrix @ stacked).reshape(R, M, size, -1), 1, 2).reshape(R * size, M, -1)

        XI = per_state(E, self.G[flat]) + np.real(per_state(growth, self.KV[flat]))
        close = self._close_terms(flat, s)
        if close is not None:
            XI = XI + np.real(close @ self.V.T)
        out["XI"] = XI
        if modal_state:
            z = per_state(E, self.W[flat]) + growth[np.repeat(np.arange(R), size)] * self.Kc[flat][:, None, :]
            out["z"] = z if close is None else z + close
        return out

    def evaluate(self, kk: NDArray[np.intp], s: NDArray[Any], modal_state: bool = False, top: int = 4) -> dict[str, NDArray[Any]]:
        """Values at local times ``s`` of the flat segments ``kk`` (same length): :meth:`evaluate_blocks` with one point a block."""
        out = self.evaluate_blocks(np.asarray(kk, dtype=np.intp), np.asarray(s)[:, None], modal_state, top=top)
        return {name: value[:, 0] for name, value in out.items()}


@dataclass(frozen=True, eq=False)
class SegmentSolution:
    """The redefined output of one segment and its linear system's figures.

    Attributes
    ----------
    index : int
        Segment number (0-based).
    t_start, duration : float
        ``t_k`` and ``T_k`` (s).
    mu, c : ndarray
        Exponents (1/s) and coefficients (m/s^2) of Eq. (29).
    y0, ydot0 : float
        ``y~(t_k)`` and ``ydot~(t_k)``.
    z0 : ndarray of complex
        Modal internal state at ``t_k``.
    z_end : ndarray of complex or None
        The anchors ``z*(t_{k+1})`` of the unstable modes (``anchored`` joining).
    residual : float
        Relative residual ``||A c - b||_inf / ||b||_inf`` of the row-scaled system.
    condition : float
        2-norm condition number of the row- and column-scaled matrix (the one solved).
    propagation : ndarray, shape (n_u, n_u)
        ``paper``/``position``: the linear map from the unstable modal state at the
        segment's start to its value at the end (real constraint coordinates), with the
        targets held at zero; its powers decide whether the carried unstable state stays
        bounded. Empty for ``anchored`` (no unstable state is carried).
    stack : Coefficients
        The evaluator of the batch the segment was solved in.
    flat : int
        Its index in ``stack``.
    """

    index: int
    t_start: float
    duration: float
    mu: NDArray[Any]
    c: NDArray[Any]
    y0: Any
    ydot0: Any
    z0: NDArray[Any]
    z_end: NDArray[Any] | None
    residual: float
    condition: float
    propagation: FloatArray
    stack: Coefficients
    flat: int

    @property
    def t_end(self) -> float:
        """``t_{k+1}``."""
        return self.t_start + self.duration

    def yddot_derivative(self, s: ArrayLike, p: int = 0) -> NDArray[Any]:
        """``d^p yddot~ / ds^p`` at local times ``s``."""
        s = np.atleast_1d(np.asarray(s, dtype=self.c.dtype))
        return np.asarray(np.exp(np.outer(s, self.mu)) @ (self.c * self.mu**p))

    def _values(self, s: ArrayLike, modal_state: bool) -> dict[str, NDArray[Any]]:
        s = np.atleast_1d(np.asarray(s, dtype=self.c.dtype))
        return self.stack.evaluate(np.full(s.size, self.flat, dtype=np.intp), s, modal_state)

    def evaluate(self, s: ArrayLike, modal: ModalInternalDynamics | None = None) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any]]:
        """``y~, ydot~, yddot~`` and the modal internal state ``z`` (shape (N, 2n)) at local times ``s``."""
        v = self._values(s, True)
        return v["y"], v["ydot"], v["yddot"], v["z"]

    def evaluate_state(self, s: ArrayLike, modal: ModalInternalDynamics | None = None) -> dict[str, NDArray[Any]]:
        """``y, ydot, yddot, jerk, snap`` and ``X_I = Re(V z)`` at local times ``s`` (no complex ``z`` formed)."""
        return self._values(s, False)


@dataclass(frozen=True, eq=False)
class PlanSolution:
    """The solved segment systems of a batch of members.

    Attributes
    ----------
    plan : SegmentPlan
    c : ndarray, shape (B K, r)
        Coefficients (NaN for a member that could not be solved).
    y0, ydot0 : ndarray, shape (B K,)
        ``y~`` and ``ydot~`` at the start of every segment.
    z0 : ndarray of complex, shape (B K, 2n)
        The modal internal state there.
    residuals : ndarray, shape (B K,)
        Relative constraint residual of every segment system.
    propagation : ndarray, shape (B K, n_rows, n_rows)
        The maps of the carried unstable state (``paper``, ``position``; empty otherwise).
    stack : Coefficients
        The evaluator.
    scaled : _Scaled
        The equilibrated matrices (their condition numbers are computed on demand).
    """

    plan: SegmentPlan
    c: NDArray[Any]
    y0: NDArray[Any]
    ydot0: NDArray[Any]
    z0: NDArray[Any]
    residuals: FloatArray
    propagation: FloatArray
    stack: Coefficients
    scaled: _Scaled

    @cached_property
    def conditions(self) -> FloatArray:
        """2-norm condition number of every (equilibrated) segment system."""
        return self.scaled.conditions()[self.plan.rep]

    def subset(self, members: Sequence[int]) -> "PlanSolution":
        """The solution of some of the members (in the order given)."""
        plan = self.plan.subset(members)
        flat = (np.asarray(members, dtype=np.intp)[:, None] * plan.count + np.arange(plan.count)[None, :]).ravel()
        with np.errstate(all="ignore"):
            stack = Coefficients(plan, self.c[flat], self.y0[flat], self.ydot0[flat], self.z0[flat])
        scaled = self.scaled.take(self.plan.rep[flat[plan.unique_flat]])
        propagation = self.propagation[flat] if self.propagation.size else self.propagation
        return PlanSolution(plan, self.c[flat], self.y0[flat], self.ydot0[flat], self.z0[flat], self.residuals[flat],
                            propagation, stack, scaled)

    def failure(self, member: int, tol: float) -> InversionError | None:
        """Why member ``member`` is not solved to ``tol`` (``None`` if it is)."""
        plan = self.plan
        if plan.singular[member]:
            return InversionError("an exponent equals an unstable zero (the paper's conditions are singular); change cdec")
        K = plan.count
        part = slice(member * K, (member + 1) * K)
        bad = ~(np.all(np.isfinite(self.c[part]), axis=1) & (self.residuals[part] <= tol))
        if not np.any(bad):
            return None
        k = int(np.argmax(bad))
        residual, condition = float(self.residuals[member * K + k]), float(self.conditions[member * K + k])
        return InversionError(
            f"segment {k} [{plan.bounds[k]:.6g}, {plan.bounds[k + 1]:.6g}] s: constraint residual {residual:.3e} "
            f"exceeds {tol:.1e} (condition number {condition:.3e}, r = {plan.r}); choose cdec further apart, "
            f"fewer conditions (h) or more segments",
            segment=k,
            residual=residual,
            condition=condition,
        )

    def segments(self, member: int = 0) -> list[SegmentSolution]:
        """The segments of one member."""
        plan = self.plan
        K = plan.count
        anchors = plan.anchors
        out = []
        for k in range(K):
            f = member * K + k
            out.append(
                SegmentSolution(
                    index=k,
                    t_start=float(plan.bounds[k]),
                    duration=float(plan.durations[k]),
                    mu=self.stack.mu[f][plan.padding[f] :],
                    c=self.c[f][plan.padding[f] :],
                    y0=self.y0[f],
                    ydot0=self.ydot0[f],
                    z0=self.z0[f],
                    z_end=None if anchors is None else anchors[k + 1].astype(self.z0.dtype),
                    residual=float(self.residuals[f]),
                    condition=float(self.conditions[f]),
                    propagation=self.propagation[f] if self.propagation.size else np.zeros((0, 0)),
                    stack=self.stack,
                    flat=f,
                )
            )
        return out


def solve_plan(plan: SegmentPlan, solver: Solver = "lu", dtype: Any = np.float64) -> PlanSolution:
    """Solve the segment systems of a batch of members.

    ``anchored`` systems are independent (all solved in one batch); ``paper`` and
    ``position`` ones take the unstable state (and, for ``paper``, the output) where the
    previous segment of the same member ended (segment by segment, members batched). A
    member that cannot be solved gets NaN coefficients; :meth:`PlanSolution.failure` says
    why.

    Parameters
    ----------
    plan : SegmentPlan
    solver : {"lu", "lstsq", "ge"}
        LAPACK's LU with partial pivoting, least squares by the SVD (a check), or
        Gaussian elimination in the working precision (for ``longdouble``).
    dtype : numpy dtype
        ``float64`` (with ``lu``/``lstsq``) or ``longdouble`` (with ``ge``).
    """
    dtype, cdtype = _dtypes(dtype)
    modal = plan.modal
    B, K, r = plan.members, plan.count, plan.r
    n = B * K
    n_rows = len(modal.rows)
    idx, imag = modal.row_modes, modal.row_imag
    rep = plan.rep  # equal segments of a member share one matrix: factorised once
    A = segment_matrices(plan, dtype, plan.unique_flat)
    scaled = _Scaled.of(A)
    rows = {name: value[rep] for name, value in _end_rows(plan, dtype, cdtype, plan.unique_flat).items()}
    T = plan.flat_durations.astype(dtype)
    y0 = np.empty(n, dtype=dtype)
    ydot0 = np.empty(n, dtype=dtype)
    z0 = np.empty((n, modal.lam.size), dtype=cdtype)
    c = np.full((n, r), np.nan, dtype=dtype)
    b_all = np.zeros((n, r), dtype=dtype)
    propagation = np.zeros((n, n_rows, n_rows) if plan.joining != "anchored" else (0, 0, 0))
    solvable = np.repeat(~plan.singular, K)
    first = np.arange(B) * K
    if plan.joining == "anchored":
        assert plan.anchors is not None
        k_of = plan.flat_segment
        y0[:] = plan.position[k_of, 0]
        ydot0[:] = plan.position[k_of, 1]
        z0[:] = plan.anchors[k_of].astype(cdtype)
        z0[first] = plan.z_initial.astype(cdtype)
        flat = np.arange(n)
        b_all[:] = _rhs(plan, flat, y0, ydot0, z0, dtype)
        c[:] = scaled.solve(rep[flat], b_all[:, :, None], solver)[:, :, 0]
        stable = ~modal.unstable
        for k in range(1, K):  # the stable modes carry over; the unstable ones are anchored
            f = first + k
            z0[np.ix_(f, stable)] = rows["growth"][np.ix_(f - 1, stable)] * z0[np.ix_(f - 1, stable)] + np.einsum(
                "br,bri->bi", c[f - 1], rows["z"][f - 1][:, :, stable]
            )
        if plan.extra:  # the rest conditions see the stable modes' state at the last segment's start
            f = first + K - 1
            b_all[f] = _rhs(plan, f, y0[f], ydot0[f], z0[f], dtype)
            c[f] = scaled.solve(rep[f], b_all[f][:, :, None], solver)[:, :, 0]
    else:
        y = np.full(B, plan.position[0, 0], dtype=dtype)
        yd = np.full(B, plan.position[0, 1], dtype=dtype)
        z = np.tile(plan.z_initial.astype(cdtype), (B, 1))
        unit = np.zeros((B, r, n_rows), dtype=dtype)
        unit[:, r - n_rows :, :] = np.eye(n_rows, dtype=dtype)
        for k in range(K):
            f = first + k
            y0[f], ydot0[f], z0[f] = y, yd, z
            b = _rhs(plan, f, y, yd, z, dtype)
            b_all[f] = b
            x = scaled.solve(rep[f], np.concatenate([b[:, :, None], unit], axis=2), solver)
            c[f] = x[:, :, 0]
            if n_rows:
                mu = plan.mu[f].astype(dtype)
                with np.errstate(divide="ignore", invalid="ignore"):
                    end = modal.beta[idx].astype(cdtype)[None, :, None] / (mu[:, None, :] - modal.lam[idx].astype(cdtype)[None, :, None])
                end = end * np.exp(mu * T[f][:, None])[:, None, :]
                with np.errstate(all="ignore"):
                    propagation[f] = np.asarray(np.einsum("bqr,brp->bqp", np.where(imag[None, :, None], end.imag, end.real), x[:, :, 1:]), dtype=float)
            with np.errstate(all="ignore"):
                y = y0[f] + ydot0[f] * T[f] + np.einsum("br,br->b", rows["y"][f], c[f])
                yd = ydot0[f] + np.einsum("br,br->b", rows["ydot"][f], c[f])
                z = rows["growth"][f] * z0[f] + np.einsum("br,bri->bi", c[f], rows["z"][f])
    c[~solvable] = np.nan
    with np.errstate(all="ignore"):
        residual_vec = (np.einsum("krj,kj->kr", A[rep], c) - b_all) / scaled.row_scale[rep]
        scale = np.abs(b_all / scaled.row_scale[rep]).max(axis=1)
        worst = np.abs(residual_vec).max(axis=1)
        residuals = np.asarray(np.where(scale > 0, worst / np.where(scale > 0, scale, 1), worst), dtype=float)
    residuals[~np.isfinite(residuals)] = np.inf
    with np.errstate(all="ignore"):
        stack = Coefficients(plan, c, y0, ydot0, z0)
    return PlanSolution(plan, c, y0, ydot0, z0, residuals, propagation, stack, scaled)

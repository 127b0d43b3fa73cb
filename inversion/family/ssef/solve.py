"""Solving the segment systems: equilibrated, by LU, SVD least squares or Gaussian elimination in any precision.

``anchored`` systems are independent (solved in one batch); ``paper`` and ``position``
segments take the state the previous one ended with. Equal segments of a member share one
factorised matrix. The solution carries its residuals, its condition numbers (on demand)
and the propagation maps of the carried unstable state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any, Literal, Sequence

import numpy as np
from numpy.typing import NDArray

from ...config import DEFAULTS
from ...errors import InversionError
from ...options import Joining
from .conditions import end_rows, precision_types, right_hand_sides, segment_matrices
from .evaluate import Coefficients, SegmentSolution
from .plan import SegmentPlan

__all__ = ["SolverName", "PlanSolution", "solve_plan"]

FloatArray = NDArray[np.float64]
SolverName = Literal["lu", "lstsq", "ge"]


def _ge_factor(A: NDArray[Any]) -> tuple[NDArray[Any], NDArray[np.intp]]:
    """LU factorisation with partial pivoting in the precision of ``A``, batched.

    LAPACK works in double only; this small dense factorisation (``r <= ~40``) lets
    :mod:`inversion.family.verify` solve the segment systems in ``longdouble``.

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
        """The solution of some of the members (in the order given).

        Parameters
        ----------
        members : Sequence[int]
            Indices of the members kept.
        """
        plan = self.plan.subset(members)
        flat = (np.asarray(members, dtype=np.intp)[:, None] * plan.count + np.arange(plan.count)[None, :]).ravel()
        with np.errstate(all="ignore"):
            stack = Coefficients(plan, self.c[flat], self.y0[flat], self.ydot0[flat], self.z0[flat])
        scaled = self.scaled.take(self.plan.rep[flat[plan.unique_flat]])
        propagation = self.propagation[flat] if self.propagation.size else self.propagation
        return PlanSolution(plan, self.c[flat], self.y0[flat], self.ydot0[flat], self.z0[flat], self.residuals[flat],
                            propagation, stack, scaled)

    def failure(self, member: int, tol: float) -> InversionError | None:
        """Why ``member`` is not solved to ``tol`` (``None`` if it is).

        Parameters
        ----------
        member : int
            The member's index.
        tol : float
            The residual tolerance.
        """
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
        """The segments of one member.

        Parameters
        ----------
        member : int, optional
            The member's index.
        """
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


def solve_plan(plan: SegmentPlan, solver: SolverName = DEFAULTS.solver, dtype: Any = np.float64) -> PlanSolution:
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
    dtype, cdtype = precision_types(dtype)
    modal = plan.modal
    B, K, r = plan.members, plan.count, plan.r
    n = B * K
    n_rows = len(modal.rows)
    idx, imag = modal.row_modes, modal.row_imag
    rep = plan.rep  # equal segments of a member share one matrix: factorised once
    A = segment_matrices(plan, dtype, plan.unique_flat)
    scaled = _Scaled.of(A)
    rows = {name: value[rep] for name, value in end_rows(plan, dtype, cdtype, plan.unique_flat).items()}
    T = plan.flat_durations.astype(dtype)
    y0 = np.empty(n, dtype=dtype)
    ydot0 = np.empty(n, dtype=dtype)
    z0 = np.empty((n, modal.lam.size), dtype=cdtype)
    c = np.full((n, r), np.nan, dtype=dtype)
    b_all = np.zeros((n, r), dtype=dtype)
    propagation = np.zeros((n, n_rows, n_rows) if plan.joining != Joining.ANCHORED else (0, 0, 0))
    solvable = np.repeat(~plan.singular, K)
    first = np.arange(B) * K
    if plan.joining == Joining.ANCHORED:
        assert plan.anchors is not None
        k_of = plan.flat_segment
        y0[:] = plan.position[k_of, 0]
        ydot0[:] = plan.position[k_of, 1]
        z0[:] = plan.anchors[k_of].astype(cdtype)
        z0[first] = plan.z_initial.astype(cdtype)
        flat = np.arange(n)
        b_all[:] = right_hand_sides(plan, flat, y0, ydot0, z0, dtype)
        c[:] = scaled.solve(rep[flat], b_all[:, :, None], solver)[:, :, 0]
        stable = ~modal.unstable
        for k in range(1, K):  # the stable modes carry over; the unstable ones are anchored
            f = first + k
            z0[np.ix_(f, stable)] = rows["growth"][np.ix_(f - 1, stable)] * z0[np.ix_(f - 1, stable)] + np.einsum(
                "br,bri->bi", c[f - 1], rows["z"][f - 1][:, :, stable]
            )
        if plan.extra:  # the rest conditions see the stable modes' state at the last segment's start
            f = first + K - 1
            b_all[f] = right_hand_sides(plan, f, y0[f], ydot0[f], z0[f], dtype)
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
            b = right_hand_sides(plan, f, y, yd, z, dtype)
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

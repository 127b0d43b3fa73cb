"""The conditions of the segment systems, linear in the coefficients ``c``: matrices and right-hand sides.

The rows, in order: smooth joining (Eq. (30)) at both ends, ``p = 0..h``; position joining
(``position``, ``anchored``); the rest conditions of a rest end; the unstable modes'
conditions (3-2 and 3-3 of the paper, or the anchored finite-horizon ones). Everything is
assembled in the precision of the inputs (double, or ``longdouble`` for the extended-precision
check of :mod:`inversion.family.verify`). :func:`end_rows` maps ``c`` to a segment's end values.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...lti.exponentials import complex_dtype, exp_difference, exp_integrals
from ...options import Joining
from .plan import FREE, FROM_START, SegmentPlan, mode_kinds

__all__ = ["segment_matrices", "end_rows", "right_hand_sides", "precision_types"]


def _unstable_rows(plan: SegmentPlan, mu: NDArray[Any], T: NDArray[Any], cdtype: np.dtype[Any]) -> NDArray[Any]:
    """Unstable-mode rows of every flat segment, shape (B K, n_rows, r), in the precision of ``mu``."""
    modal = plan.modal
    idx, imag = modal.row_modes, modal.row_imag
    lam = modal.lam[idx].astype(cdtype)[None, :, None]
    beta = modal.beta[idx].astype(cdtype)[None, :, None]
    diff = mu[:, None, :] - lam
    if plan.joining == Joining.ANCHORED:
        rows = beta * exp_difference(diff, np.zeros((), dtype=cdtype), T[:, None, None])
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            rows = beta / diff
    return np.where(imag[None, :, None], rows.imag, rows.real)


def precision_types(dtype: Any) -> tuple[np.dtype[Any], np.dtype[Any]]:
    """The real and complex types of a precision.

    Parameters
    ----------
    dtype : Any
        A real floating type.
    """
    dtype = np.dtype(dtype)
    return dtype, complex_dtype(np.zeros(0, dtype=dtype))


def segment_matrices(plan: SegmentPlan, dtype: Any = np.float64, flat: NDArray[np.intp] | None = None) -> NDArray[Any]:
    """The conditions of flat segments as matrices, shape (F, r, r).

    Parameters
    ----------
    plan : SegmentPlan
    dtype : numpy dtype
        ``float64`` or ``longdouble``.
    flat : ndarray of int, optional
        Which flat segments (default: all).
    """
    dtype, cdtype = precision_types(dtype)
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
    if plan.joining != Joining.PAPER:
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
            if plan.joining == Joining.PAPER:
                block[last, 0] = T[last, None] * p1[last]
                block[last, 1] = (T[last] * T[last])[:, None] * p2[last]
                q = 2
            ends = end_rows(plan, dtype, cdtype, flat[last])["z"]  # (., r, 2n): c -> z(T)
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


def end_rows(plan: SegmentPlan, dtype: np.dtype[Any], cdtype: np.dtype[Any], flat: NDArray[np.intp]) -> dict[str, NDArray[Any]]:
    """The linear maps from ``c`` to the segments' end values.

    The linear maps from ``c`` to the end values of the flat segments ``flat`` (start values enter separately).

    ``ydot~(T) = ydot~(0) + ydot . c``, ``y~(T) = y~(0) + ydot~(0) T + y . c``,
    ``z(T) = growth z(0) + z . c`` (``growth`` = ``e^{lambda T}`` for the modes evaluated from
    their start, 0 for the paper's unstable ones; anchored modes end on their anchor).

    Parameters
    ----------
    plan : SegmentPlan
        The batch's segment systems.
    dtype : np.dtype[Any]
        The real type of the precision.
    cdtype : np.dtype[Any]
        The complex type.
    flat : NDArray[np.intp]
        Flat indices of the segments.
    """
    mu = plan.mu[flat].astype(dtype)
    T = plan.flat_durations[flat].astype(dtype)
    modal = plan.modal
    lam = modal.lam.astype(cdtype)
    beta = modal.beta.astype(cdtype)
    kinds = mode_kinds(plan)
    _, p1, p2 = exp_integrals(mu * T[:, None])
    z = np.zeros(mu.shape + (lam.size,), dtype=cdtype)
    growth = np.zeros((mu.shape[0], lam.size), dtype=cdtype)
    start = kinds == FROM_START
    if np.any(start):
        z[:, :, start] = beta[start] * exp_difference(mu[:, :, None], lam[start][None, None, :], T[:, None, None])
        growth[:, start] = np.exp(np.outer(T, lam[start]))
    free = kinds == FREE
    if np.any(free):
        with np.errstate(divide="ignore", invalid="ignore"):
            z[:, :, free] = beta[free] * np.exp(mu * T[:, None])[:, :, None] / (mu[:, :, None] - lam[free])
    return {"ydot": T[:, None] * p1, "y": (T * T)[:, None] * p2, "z": z, "growth": growth}


def right_hand_sides(plan: SegmentPlan, flat: NDArray[np.intp], y0: NDArray[Any], ydot0: NDArray[Any], z0: NDArray[Any], dtype: np.dtype[Any]) -> NDArray[Any]:
    """Right-hand sides of the flat segments for their start states.

    Parameters
    ----------
    plan : SegmentPlan
        The batch's segment systems.
    flat : NDArray[np.intp]
        Flat indices of the segments.
    y0 : NDArray[Any]
        Each segment's start ``y~``.
    ydot0 : NDArray[Any]
        Its start ``ydot~``.
    z0 : NDArray[Any]
        Its start modal state.
    dtype : np.dtype[Any]
        The precision.
    """
    cdtype = complex_dtype(np.zeros(0, dtype=dtype))
    k = plan.flat_segment[flat]
    h1 = plan.h + 1
    b = np.empty((flat.size, plan.r), dtype=dtype)
    b[:, 0 : 2 * h1 : 2] = plan.accel_start[k]
    b[:, 1 : 2 * h1 : 2] = plan.accel_end[k]
    row = 2 * h1
    T = plan.durations[k].astype(dtype)
    if plan.joining != Joining.PAPER:
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
            if plan.joining == Joining.PAPER:
                end = plan.position[k[last] + 1].astype(dtype)
                b[last, row] = end[:, 1] - ydot0[last]
                b[last, row + 1] = end[:, 0] - y0[last] - ydot0[last] * T[last]
                q = 2
            target = -end_rows(plan, dtype, cdtype, flat[last])["growth"] * z0[last].astype(cdtype)  # X_I(t_f) = 0
            for m, (i, part) in enumerate(plan.rest_rows):
                b[last, row + q + m] = target[:, i].imag if part == "im" else target[:, i].real
        row += E
    modal = plan.modal
    if modal.rows:
        idx, imag = modal.row_modes, modal.row_imag
        z_start = z0[:, idx].astype(cdtype)
        if plan.joining == Joining.ANCHORED:
            assert plan.anchors is not None
            lam = modal.lam[idx].astype(cdtype)
            value = np.exp(-np.outer(T, lam)) * plan.anchors[k + 1][:, idx].astype(cdtype) - z_start
        else:
            value = z_start
        b[:, row:] = np.where(imag[None, :], value.imag, value.real)
    return b

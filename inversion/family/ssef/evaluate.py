"""The solved segments in closed form: a vectorised evaluator of ``y~``, its derivatives and the internal state.

No ODE is integrated: ``ydot~``, ``y~`` are the integrals of the sum of exponentials, and
each internal mode is ``z_i(s) = sum_j W_ji e^{mu_j s} + K_i e^{lambda_i (s - a_i)}``, with
the exponents close to a zero summed cancellation-free (docs/method.md section 3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...lti.exponentials import complex_dtype, exp_difference, exp_integrals
from ...lti.internal import ModalInternalDynamics
from ...options import Joining
from ...signals.trajectory import derivative_key
from .plan import ANCHORED, FREE, FROM_START, SegmentPlan, mode_kinds

__all__ = ["Coefficients", "SegmentSolution", "SERIES_LIMIT", "summed_in_order"]

FloatArray = NDArray[np.float64]

#: ``|mu_j - lambda_i| T`` below which a mode's term is evaluated by the series of
#: :func:`~inversion.lti.exponentials.exp_difference` instead of the split form.
SERIES_LIMIT = 0.2


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



def summed_in_order(out: NDArray[Any], q: NDArray[np.intp], i: NDArray[np.intp], value: NDArray[Any]) -> None:
    """Terms added to their (block, mode) in order, as np.add.at adds.

    ``out[q[t], :, i[t]] += value[t]`` for every term ``t``, in ``t``'s order: ``np.add.at``'s sums, bit for bit. The terms of a pair ``(q, i)`` are added as ``np.add.at`` adds them (``out + v_1 + v_2 + ...``, in the order given),
    in a pass for each term's rank within its pair: within a pass no two terms meet, so each is one fancy-indexed
    addition (``np.add.at`` took 5 % of a family's search on hyperbolic with 8 modes).

    Parameters
    ----------
    out : ndarray, shape (S, M, L)
        Added to in place.
    q, i : ndarray of int, shape (T,)
        Each term's block and mode.
    value : ndarray, shape (T, M)
        The terms.
    """
    if q.size == 0:
        return
    pair = q * out.shape[2] + i
    order = np.argsort(pair, kind="stable")
    first = np.r_[0, np.flatnonzero(np.diff(pair[order])) + 1]
    rank = np.empty(q.size, dtype=np.intp)
    rank[order] = np.arange(q.size) - np.repeat(first, np.diff(np.r_[first, q.size]))
    for r in range(int(rank.max()) + 1):
        at = rank == r
        out[q[at], :, i[at]] += value[at]

class Coefficients:
    """The solved segments of a batch of members, stacked.

    The solved segments of a batch of members, stacked: a vectorised closed-form evaluator.

    ``yddot~ = sum_j c_kj e^{mu_kj s}`` with its integrals from the start values, and each
    internal mode ``z_i = sum_j W_kji e^{mu_kj s} + K_ki e^{lambda_i (s - a_ki)}`` plus the
    terms of exponents within ``0.2/T`` of ``lambda_i`` (cancellation-free, through
    :func:`exp_difference`). ``X_I = Re(V z)`` is formed from real coefficients. Any set
    of (segment, local time) points is evaluated in one pass, in the precision of ``c``.

    Parameters
    ----------
    plan : SegmentPlan
        The batch's segment systems.
    c : NDArray[Any]
        The solved coefficients.
    y0 : NDArray[Any]
        Each segment's start ``y~``.
    ydot0 : NDArray[Any]
        Its start ``ydot~``.
    z0 : NDArray[Any]
        Its start modal state.
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
        kinds = mode_kinds(plan)
        zT = np.zeros_like(z0)
        if plan.joining == Joining.ANCHORED:
            assert plan.anchors is not None
            zT = plan.anchors[plan.flat_segment + 1].astype(cdtype)
        diff = self.mu[:, :, None] - self.lam[None, None, :]
        apart = (np.abs(diff) * self.T[:, None, None] >= SERIES_LIMIT) | (kinds == FREE)[None, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            W = np.where(apart, self.beta * c[:, :, None] / diff, 0)
        eT = np.exp(self.mu * self.T[:, None])
        from_start = z0 - W.sum(axis=1)
        from_end = zT - np.einsum("kr,kri->ki", eT, W)
        Kc = np.where(kinds == FROM_START, from_start, np.where(kinds == ANCHORED, from_end, 0))
        self.W = W
        self.Kc = Kc
        self.anchor = np.where(kinds == ANCHORED, self.T[:, None], dtype.type(0)).astype(dtype)
        self.G = np.real(np.einsum("kri,ni->krn", W, self.V))  # coefficients of e^{mu s} in X_I
        self.KV = Kc[:, :, None] * self.V.T[None, :, :]  # (K, mode, state)
        self.kinds = kinds
        # exponent rates of the complementary terms: none for the paper's unstable modes (their
        # K is zero, and exp(lambda s) of a fast unstable zero would overflow)
        self.rate = np.where(kinds == FREE, 0, self.lam)
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
        anchored = self.kinds[i] == ANCHORED
        st = ~anchored
        if np.any(st):  # from the start: beta c (e^{mu s} - e^{lam s})/(mu - lam)
            value[st] = weight[st] * exp_difference(mu[st], lam[st], sv[st])
        if np.any(anchored):  # from the end: -beta c e^{mu T} (e^{-lam w} - e^{-mu w})/(mu - lam), w = T - s
            a = anchored
            value[a] = -weight[a] * np.exp(mu[a] * T[a]) * exp_difference(-lam[a], -mu[a], T[a] - sv[a])
        out = np.zeros(s.shape + (self.lam.size,), dtype=self.W.dtype)
        summed_in_order(out, q, i, value)
        return out

    def evaluate_blocks(
        self, flat: NDArray[np.intp], s: NDArray[Any], modal_state: bool = False, share: NDArray[np.intp] | None = None,
        top: int = 4, functional: NDArray[Any] | None = None,
    ) -> dict[str, NDArray[Any]]:
        """Values at local times ``s[q, m]`` of segments ``flat[q]``.

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
            ... are the derivatives of ``yddot~`` (:func:`~inversion.signals.trajectory.derivative_key`).
        functional : ndarray, shape (2n,) or (2n, F), optional
            Return ``XIf = X_I . functional`` (shape (S, M), or (S, M, F) for F columns) instead of ``X_I``: linear
            functions of the internal state (the torque's, Eq. (12); a link's joint references) at the cost of as many
            states.

        Returns
        -------
        dict
            ``y, ydot, yddot`` and the derivatives up to ``top`` (shape (S, M)), ``XI``
            (shape (S, M, 2n)) or ``XIf``; with ``modal_state`` also ``z``.
        """
        groups = _groups(share)
        if groups is not None:
            return self._evaluate_groups(flat, s, modal_state, *groups, top, functional)
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
        if functional is not None and np.ndim(functional) == 2:  # a few functions of X_I (columns): their coefficients first
            F = np.asarray(functional).astype(self.G.dtype)
            value = E @ (self.G[flat] @ F) + np.real(growth @ (self.KV[flat][:, active, :] @ F))
            if close is not None:
                value = value + np.real(close @ (self.V.T @ F))
            out["XIf"] = value
        elif functional is not None:  # one function of X_I: its coefficients first, then one product a block
            f = np.asarray(functional).astype(self.G.dtype)
            value = (E @ (self.G[flat] @ f)[:, :, None])[..., 0] + np.real(growth @ (self.KV[flat][:, active, :] @ f)[:, :, None])[..., 0]
            if close is not None:
                value = value + np.real(close @ (self.V.T @ f))
            out["XIf"] = value
        else:
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
        """Sums of the terms' magnitudes behind each value.

        Sums of the magnitudes of the terms behind ``y, ydot, yddot`` (and the derivatives up to
        ``top``) and ``X_I`` at the points ``(flat[q], s[q])`` (one point each): what their
        rounding is proportional to.

        The terms of the closed form can exceed its value by orders of magnitude (nearly
        dependent exponentials give large coefficients of alternating sign); rounding each
        term, and each ``exp``, by ``eps`` leaves an error up to ``eps`` times these sums.

        Parameters
        ----------
        flat : NDArray[np.intp]
            Flat index of each point's segment.
        s : NDArray[Any]
            Local time of each point (s).
        top : int, optional
            Highest derivative of ``y`` included.
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
        self, flat: NDArray[np.intp], s: NDArray[Any], modal_state: bool, reps: NDArray[np.intp], size: int, top: int,
        functional: NDArray[Any] | None = None,
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

        close = self._close_terms(flat, s)
        if functional is not None and np.ndim(functional) == 2:  # a few functions of X_I (evaluate_blocks' docstring)
            F = np.asarray(functional).astype(self.G.dtype)
            value = per_state(E, self.G[flat] @ F) + np.real(per_state(growth, self.KV[flat] @ F))
            if close is not None:
                value = value + np.real(close @ (self.V.T @ F))
            out["XIf"] = value
        elif functional is not None:  # one function of X_I (module docstring of evaluate_blocks)
            f = np.asarray(functional).astype(self.G.dtype)
            value = per_state(E, (self.G[flat] @ f)[..., None])[..., 0] + np.real(per_state(growth, (self.KV[flat] @ f)[..., None]))[..., 0]
            if close is not None:
                value = value + np.real(close @ (self.V.T @ f))
            out["XIf"] = value
        else:
            XI = per_state(E, self.G[flat]) + np.real(per_state(growth, self.KV[flat]))
            if close is not None:
                XI = XI + np.real(close @ self.V.T)
            out["XI"] = XI
        if modal_state:
            z = per_state(E, self.W[flat]) + growth[np.repeat(np.arange(R), size)] * self.Kc[flat][:, None, :]
            out["z"] = z if close is None else z + close
        return out

    def evaluate(self, kk: NDArray[np.intp], s: NDArray[Any], modal_state: bool = False, top: int = 4,
                 functional: NDArray[Any] | None = None) -> dict[str, NDArray[Any]]:
        """Values at local times ``s`` of the flat segments ``kk``.

        Parameters
        ----------
        kk : NDArray[np.intp]
            Flat index of each point's segment.
        s : NDArray[Any]
            Local time of each point (s).
        modal_state : bool, optional
            Whether to return the modal state ``z`` too.
        top : int, optional
            Highest derivative of ``y`` returned.
        functional : NDArray[Any] | None, optional
            A row applied to ``X_I`` in place of ``X_I`` itself, if given.
        """
        out = self.evaluate_blocks(np.asarray(kk, dtype=np.intp), np.asarray(s)[:, None], modal_state, top=top, functional=functional)
        return {name: value[:, 0] for name, value in out.items()}


@dataclass(frozen=True, eq=False)
class SegmentSolution:
    """The redefined output of one segment and its system's figures.

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
        """``d^p yddot~ / ds^p`` at local times ``s``.

        Parameters
        ----------
        s : ArrayLike
            Local times (s).
        p : int, optional
            The derivative's order.
        """
        s = np.atleast_1d(np.asarray(s, dtype=self.c.dtype))
        return np.asarray(np.exp(np.outer(s, self.mu)) @ (self.c * self.mu**p))

    def _values(self, s: ArrayLike, modal_state: bool) -> dict[str, NDArray[Any]]:
        s = np.atleast_1d(np.asarray(s, dtype=self.c.dtype))
        return self.stack.evaluate(np.full(s.size, self.flat, dtype=np.intp), s, modal_state)

    def evaluate(self, s: ArrayLike, modal: ModalInternalDynamics | None = None) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any], NDArray[Any]]:
        """``y~``, its derivatives and the modal state ``z`` at ``s``.

        ``y~, ydot~, yddot~`` and the modal internal state ``z`` (shape (N, 2n)) at local times ``s``.

        Parameters
        ----------
        s : ArrayLike
            Local times (s).
        modal : ModalInternalDynamics | None, optional
            The diagonalised internal dynamics (``None``: the plan's).
        """
        v = self._values(s, True)
        return v["y"], v["ydot"], v["yddot"], v["z"]

    def evaluate_state(self, s: ArrayLike, modal: ModalInternalDynamics | None = None) -> dict[str, NDArray[Any]]:
        """Outputs and ``X_I = Re(V z)`` at local times ``s``.

        ``y, ydot, yddot, jerk, snap`` and ``X_I = Re(V z)`` at local times ``s`` (no complex ``z`` formed).

        Parameters
        ----------
        s : ArrayLike
            Local times (s).
        modal : ModalInternalDynamics | None, optional
            The diagonalised internal dynamics (``None``: the plan's).
        """
        return self._values(s, False)

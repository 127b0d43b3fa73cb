"""One segment of the output redefinition by a summation of stable exponential functions.

In segment ``k`` (local time ``s = t - t_k`` in ``[0, T]``) the desired acceleration is
replaced by (Eq. (29))::

    yddot~(s) = sum_{j=1}^{r} c_j exp(mu_j s),   mu_j <= 0

with ``mu_j`` equally spaced from ``ln(Cdec_s)/T`` to ``ln(Cdec_f)/T`` (Eqs. (34)-(36)).
The ``r = 2(h+1) + n_u`` coefficients solve (Eq. (31)):

1. smooth joining, ``p = 0..h`` (Eq. (30))::

       sum_j c_j mu_j^p             = yddot_d^(p)(t_k+)
       sum_j c_j mu_j^p exp(mu_j T) = yddot_d^(p)(t_{k+1}-)

2. bounded unstable modes with continuity (conditions 3-2 and 3-3): for ``i`` in ``U``
   ``sum_j beta_i c_j / (mu_j - lambda_i) = z_i(t_k)`` -- the complementary part of
   ``z_i`` vanishes and it starts where the previous segment ended. A complex pair gives
   the real and imaginary parts of one member, so ``c`` stays real.

Everything then follows in closed form (no ODE is integrated): ``ydot~``, ``y~``, the
unstable modes ``z_i(s) = sum_j beta_i c_j/(mu_j - lambda_i) exp(mu_j s)`` and the stable
ones ``z_i(s) = exp(lambda_i s) z_i(0) + beta_i sum_j c_j (exp(mu_j s) - exp(lambda_i s))/(mu_j - lambda_i)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import scipy.linalg as sla
from numpy.typing import ArrayLike, NDArray

from .errors import InversionError
from .exponentials import exp_difference, exp_integrals
from .internal import ModalInternalDynamics

__all__ = ["exponents", "SegmentSolution", "solve_segment"]

#: ``|mu_j - lambda_i| T`` below which the stable-mode term is evaluated by the series
#: of :func:`~inversion.exponentials.exp_difference` instead of the split form.
_SERIES_LIMIT = 0.2

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]
Solver = Literal["lu", "lstsq"]


def exponents(duration: float, cdec_fast: float, cdec_slow: float, r: int) -> FloatArray:
    """Exponents of one segment, Eqs. (34)-(36).

    ``mu_s = ln(Cdec_s)/T``, ``mu_f = ln(Cdec_f)/T``, ``mu_j = mu_s + (mu_f - mu_s)(j-1)/(r-1)``.
    ``Cdec_s = 1`` gives ``mu_1 = 0``: a constant term.
    """
    mu_s = math.log(cdec_slow) / duration
    mu_f = math.log(cdec_fast) / duration
    return mu_s + (mu_f - mu_s) * np.arange(r) / max(r - 1, 1)


@dataclass(frozen=True)
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
    residual : float
        Relative residual ``||A c - b||_inf / ||b||_inf`` of the row-scaled system.
    condition : float
        2-norm condition number of the row- and column-scaled matrix (the one solved;
        the matrix as assembled is typically 1e3 times worse).
    propagation : ndarray, shape (n_u, n_u)
        The linear map from the unstable modal state at the segment's start to its value
        at the end (real constraint coordinates), with the trajectory's targets held at
        zero. Its powers decide whether the unstable state, carried from segment to
        segment, stays bounded: a spectral radius above 1 amplifies it geometrically.
    """

    index: int
    t_start: float
    duration: float
    mu: FloatArray
    c: FloatArray
    y0: float
    ydot0: float
    z0: ComplexArray
    residual: float
    condition: float
    propagation: FloatArray

    @property
    def t_end(self) -> float:
        """``t_{k+1}``."""
        return self.t_start + self.duration

    def yddot_derivative(self, s: ArrayLike, p: int = 0) -> FloatArray:
        """``d^p yddot~ / ds^p`` at local times ``s``."""
        s = np.atleast_1d(np.asarray(s, dtype=float))
        return np.asarray(np.exp(np.outer(s, self.mu)) @ (self.c * self.mu**p))

    def _output_terms(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``E = e^{mu s}`` and ``yddot~, ydot~, y~`` at local times ``s``.

        The integrals of ``e^{mu s}`` are ``(e^{mu s} - 1)/mu`` and
        ``(e^{mu s} - 1 - mu s)/mu^2``. For an exponent with ``|mu| T >= 0.2`` the direct
        forms err by at most ~75 eps of the term's scale ``|c| T^2``; slower exponents
        (``mu = 0`` included) use the series of :func:`exp_integrals`.
        """
        E = np.exp(np.outer(s, self.mu))
        slow = np.abs(self.mu) * self.duration < _SERIES_LIMIT
        fast = ~slow
        cf, mf = self.c[fast], self.mu[fast]
        v1, v2 = cf / mf, cf / mf**2
        # one product for the three: E @ [c, c/mu, c/mu^2] (the slow columns enter below)
        coef = np.zeros((self.mu.size, 3))
        coef[:, 0] = self.c
        coef[fast, 1] = v1
        coef[fast, 2] = v2
        out = E @ coef
        yddot = out[:, 0]
        ydot = self.ydot0 + out[:, 1] - v1.sum()
        y = self.y0 + (self.ydot0 - v1.sum()) * s + out[:, 2] - v2.sum()
        zero = self.mu == 0.0  # the constant term of Cdec_s = 1: exactly c s and c s^2/2
        if np.any(zero):
            c0 = float(self.c[zero].sum())
            ydot = ydot + c0 * s
            y = y + 0.5 * c0 * s * s
        slow &= ~zero
        if np.any(slow):
            _, p1, p2 = exp_integrals(np.outer(s, self.mu[slow]))
            ydot = ydot + s * (p1 @ self.c[slow])
            y = y + s * s * (p2 @ self.c[slow])
        return E, y, ydot, yddot

    def _modal_terms(
        self, modal: ModalInternalDynamics
    ) -> tuple[ComplexArray, ComplexArray, list[tuple[int, NDArray[np.bool_]]]]:
        """Coefficients of the modal solution ``z(s) = W^T e^{mu s} + K e^{lambda s} + (close terms)``.

        Unstable modes: ``W_ji = beta_i c_j/(mu_j - lambda_i)``, ``K_i = 0`` (no complementary
        part, condition 3-2). Stable modes: the same ``W`` for exponents well apart from
        ``lambda_i`` and ``K_i = z_i(0) - sum_j W_ji``; exponents within ``0.2/T`` of
        ``lambda_i`` are listed in the third output and summed through the
        cancellation-free :func:`exp_difference`.
        """
        lam, beta = modal.lam, modal.beta
        diff = self.mu[:, None] - lam[None, :]
        W = np.zeros((self.mu.size, lam.size), dtype=complex)
        K = np.zeros(lam.size, dtype=complex)
        close_terms: list[tuple[int, NDArray[np.bool_]]] = []
        U = modal.unstable
        W[:, U] = self.c[:, None] * beta[None, U] / diff[:, U]
        for i in np.flatnonzero(~U):
            apart = np.abs(diff[:, i]) * self.duration >= _SERIES_LIMIT
            W[apart, i] = beta[i] * self.c[apart] / diff[apart, i]
            K[i] = self.z0[i] - W[:, i].sum()
            if not np.all(apart):
                close_terms.append((int(i), ~apart))
        return W, K, close_terms

    def _close(self, s: FloatArray, modal: ModalInternalDynamics, i: int, close: NDArray[np.bool_]) -> ComplexArray:
        """``beta_i sum_j c_j (e^{mu_j s} - e^{lambda_i s})/(mu_j - lambda_i)`` over exponents near ``lambda_i``."""
        kernel = exp_difference(self.mu[None, close], modal.lam[i], s[:, None])
        return np.asarray(modal.beta[i] * (kernel @ self.c[close]))

    def evaluate(
        self, s: ArrayLike, modal: ModalInternalDynamics
    ) -> tuple[FloatArray, FloatArray, FloatArray, ComplexArray]:
        """``y~, ydot~, yddot~`` and the modal internal state ``z`` at local times ``s``.

        Parameters
        ----------
        s : array_like
            Local times in ``[0, T]``.
        modal : ModalInternalDynamics
            The diagonalised internal dynamics.

        Returns
        -------
        y, ydot, yddot : ndarray, shape (N,)
        z : ndarray of complex, shape (N, 2n)
        """
        s = np.atleast_1d(np.asarray(s, dtype=float))
        E, y, ydot, yddot = self._output_terms(s)
        W, K, close_terms = self._modal_terms(modal)
        z = _real_times_complex(E, W)
        stable = ~modal.unstable
        z[:, stable] += np.exp(np.outer(s, modal.lam[stable])) * K[stable]
        for i, close in close_terms:
            z[:, i] += self._close(s, modal, i, close)
        return y, ydot, yddot, z

    def evaluate_state(
        self, s: ArrayLike, modal: ModalInternalDynamics
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, ComplexArray]:
        """``y~, ydot~, yddot~``, the internal state ``X_I = Re(V z)`` and ``z`` at the last time.

        The same values as :meth:`evaluate` (to rounding), computed without forming ``z``
        at every sample: the coefficients of ``e^{mu_j s}`` in ``X_I`` are real,
        ``Re(V W^T)``.

        Returns
        -------
        y, ydot, yddot : ndarray, shape (N,)
        XI : ndarray, shape (N, 2n)
        z_last : ndarray of complex, shape (2n,)
            The modal state at ``s[-1]`` (carried to the next segment).
        """
        s = np.atleast_1d(np.asarray(s, dtype=float))
        E, y, ydot, yddot = self._output_terms(s)
        W, K, close_terms = self._modal_terms(modal)
        XI = E @ np.real(W @ modal.V.T)
        stable = np.flatnonzero(~modal.unstable)
        growth = np.exp(np.outer(s, modal.lam[stable]))
        if stable.size:
            XI += np.real(growth @ (K[stable, None] * modal.V[:, stable].T))
        z_last = E[-1] @ W
        z_last[stable] += growth[-1] * K[stable]
        for i, close in close_terms:
            extra = self._close(s, modal, i, close)
            XI += np.real(extra[:, None] * modal.V[:, i][None, :])
            z_last[i] += extra[-1]
        return y, ydot, yddot, XI, z_last


def _real_times_complex(R: FloatArray, C: ComplexArray) -> ComplexArray:
    """``R @ C`` for real ``R`` without promoting ``R`` to complex."""
    return np.asarray(R @ C.real + 1j * (R @ C.imag))


def solve_segment(
    index: int,
    t_start: float,
    duration: float,
    targets_start: FloatArray,
    targets_end: FloatArray,
    y0: float,
    ydot0: float,
    z0: ComplexArray,
    modal: ModalInternalDynamics,
    cdec: tuple[float, float],
    solver: Solver = "lu",
    tol: float = 1e-8,
) -> SegmentSolution:
    """Solve the ``r x r`` system of one segment (conditions 1-3 above).

    Parameters
    ----------
    index, t_start, duration :
        Segment number, ``t_k``, ``T_k``.
    targets_start, targets_end : ndarray, shape (h+1,)
        ``yddot_d^(p)`` at ``t_k+`` and ``t_{k+1}-``.
    y0, ydot0 : float
        ``y~`` and ``ydot~`` at ``t_k``.
    z0 : ndarray of complex
        Modal internal state at ``t_k``.
    modal : ModalInternalDynamics
        Diagonalised internal dynamics.
    cdec : (float, float)
        ``(Cdec_f, Cdec_s)``.
    solver : {"lu", "lstsq"}
        LU with partial pivoting, or SVD-based least squares (same answer; a check).
    tol : float
        Largest accepted relative residual.

    Raises
    ------
    InversionError
        When the residual exceeds ``tol`` (or is not finite); carries the residual and
        the condition number.
    """
    h1 = targets_start.size
    n_rows = 2 * h1
    idx, imag = modal.row_modes, modal.row_imag
    n_u = idx.size
    r = n_rows + n_u
    mu = exponents(duration, cdec[0], cdec[1], r)
    eT = np.exp(mu * duration)
    powers = mu[None, :] ** np.arange(h1)[:, None]  # (h+1, r): mu^p
    A = np.empty((r, r))
    b = np.empty(r)
    A[0:n_rows:2] = powers  # Eq. (30) at t_k+
    A[1:n_rows:2] = powers * eT  # and at t_{k+1}-
    b[0:n_rows:2] = targets_start
    b[1:n_rows:2] = targets_end
    # conditions 3-2/3-3: sum_j beta_i c_j/(mu_j - lambda_i) = z_i(t_k), real or imaginary part
    diff = mu[None, :] - modal.lam[idx, None]
    if n_u and np.abs(diff).min() <= 1e-12 * max(float(np.abs(modal.lam[idx]).max()), 1.0):
        raise InversionError(f"segment {index}: an exponent equals an unstable zero; change cdec", segment=index)
    rows = modal.beta[idx, None] / diff
    A[n_rows:] = np.where(imag[:, None], rows.imag, rows.real)
    b[n_rows:] = np.where(imag, z0[idx].imag, z0[idx].real)
    # equilibrate rows and columns, solve, undo the column scaling
    row_scale = np.abs(A).max(axis=1)
    row_scale[row_scale == 0] = 1.0
    As = A / row_scale[:, None]
    bs = b / row_scale
    col_scale = np.abs(As).max(axis=0)
    col_scale[col_scale == 0] = 1.0
    Ass = As / col_scale[None, :]
    # right-hand sides: the targets, and a unit value of each unstable-state row (for the
    # propagation map); one factorisation serves all of them
    rhs = np.zeros((r, 1 + n_u))
    rhs[:, 0] = bs
    rhs[n_rows:, 1:] = np.diag(1.0 / row_scale[n_rows:])
    with np.errstate(all="ignore"):
        try:
            if solver == "lu":
                x = np.linalg.solve(Ass, rhs)  # LAPACK gesv: LU with partial pivoting
            else:
                x = sla.lstsq(Ass, rhs, check_finite=False)[0]
        except (np.linalg.LinAlgError, sla.LinAlgError, ValueError):
            x = np.full((r, 1 + n_u), np.nan)
        cols = x / col_scale[:, None]
        c = cols[:, 0]
        residual_vec = As @ c - bs
        end_rows = rows * eT[None, :]  # the same rows at the end of the segment
        propagation = np.where(imag[:, None], end_rows.imag, end_rows.real) @ cols[:, 1:]
    scale = float(np.abs(bs).max())
    residual = float(np.abs(residual_vec).max() / scale) if scale > 0 else float(np.abs(residual_vec).max())
    if np.all(np.isfinite(Ass)):
        singular = np.linalg.svd(Ass, compute_uv=False)
        condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else math.inf
    else:
        condition = math.inf
    if not (np.all(np.isfinite(c)) and math.isfinite(residual)) or residual > tol:
        raise InversionError(
            f"segment {index} [{t_start:.6g}, {t_start + duration:.6g}] s: constraint residual {residual:.3e} "
            f"exceeds {tol:.1e} (condition number {condition:.3e}, r = {r}); choose cdec further apart, "
            f"fewer conditions (h) or more segments",
            segment=index,
            residual=residual,
            condition=condition,
        )
    return SegmentSolution(
        index=index,
        t_start=t_start,
        duration=duration,
        mu=mu,
        c=c,
        y0=float(y0),
        ydot0=float(ydot0),
        z0=np.asarray(z0, dtype=complex),
        residual=residual,
        condition=condition,
        propagation=propagation,
    )

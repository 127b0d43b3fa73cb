"""Zeros of the tip transfer function ``Y(s)/tau(s)`` and the class of the internal dynamics.

The zeros are the eigenvalues of ``A_I`` (Eq. (14)); :func:`transmission_zeros` computes
them independently as the finite generalised eigenvalues of the Rosenbrock pencil.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "IMAGINARY_TOL",
    "NEAR_TOL",
    "classify_internal_dynamics",
    "is_unstable",
    "transmission_zeros",
]

#: Relative tolerance below which a real part counts as zero (round-off of the
#: eigenvalue solver: undamped zeros come out with ``|Re| ~ 1e-15 |z|``).
IMAGINARY_TOL = 1e-9
#: Default relative tolerance of "near non-hyperbolic": ``|Re z| < NEAR_TOL |z|``.
NEAR_TOL = 0.05


def transmission_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike) -> NDArray[np.complex128]:
    """Finite zeros of a SISO state-space system from the Rosenbrock pencil.

    Solves ``[[A, B], [C, 0]] v = s [[I, 0], [0, 0]] v`` and keeps the finite
    eigenvalues.

    Parameters
    ----------
    A : array_like, shape (N, N)
    B : array_like, shape (N,) or (N, 1)
    C : array_like, shape (N,) or (1, N)

    Returns
    -------
    ndarray of complex
        The finite transmission zeros, sorted by :func:`numpy.sort_complex`.
    """
    A = np.asarray(A, dtype=float)
    N = A.shape[0]
    B = np.asarray(B, dtype=float).reshape(N, 1)
    C = np.asarray(C, dtype=float).reshape(1, N)
    pencil = np.block([[A, B], [C, np.zeros((1, 1))]])
    E = np.zeros((N + 1, N + 1))
    E[:N, :N] = np.eye(N)
    import scipy.linalg as sla  # lazy: keeps the import of the package fast

    alpha, beta = sla.eig(pencil, E, right=False, homogeneous_eigvals=True)
    scale = np.abs(alpha) + np.abs(beta)
    finite = np.abs(beta) > 1e-9 * np.where(scale > 0, scale, 1.0)
    return np.sort_complex(alpha[finite] / beta[finite])


def is_unstable(zeros: ArrayLike, eps: float = 0.0) -> NDArray[np.bool_]:
    """Mask of the zeros treated as unstable: ``Re z >= -eps`` (docs/method.md section 2).

    Parameters
    ----------
    zeros : array_like of complex
    eps : float
        Non-negative tolerance (1/s). Zeros with ``|Re z| <= IMAGINARY_TOL |z|`` count
        as purely imaginary, hence unstable, whatever ``eps``.
    """
    z = np.asarray(zeros, dtype=complex)
    if eps < 0 or not np.isfinite(eps):
        raise ValueError(f"eps must be a finite number >= 0, got {eps}")
    return np.asarray((z.real >= -eps) | (np.abs(z.real) <= IMAGINARY_TOL * np.abs(z)))


def classify_internal_dynamics(zeros: ArrayLike, near_tol: float = NEAR_TOL) -> str:
    """Class of the internal dynamics from the zeros (docs/method.md section 2).

    Returns
    -------
    str
        ``"non-hyperbolic"`` if some zero is purely imaginary
        (``|Re z| <= IMAGINARY_TOL |z|``), ``"near-non-hyperbolic"`` if some zero has
        ``|Re z| < near_tol |z|``, else ``"hyperbolic"``.
    """
    z = np.asarray(zeros, dtype=complex)
    nonzero = z[np.abs(z) > 0]
    ratio = np.abs(nonzero.real) / np.abs(nonzero)
    if np.any(ratio <= IMAGINARY_TOL):
        return "non-hyperbolic"
    if np.any(ratio < near_tol):
        return "near-non-hyperbolic"
    return "hyperbolic"

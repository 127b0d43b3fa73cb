"""Zeros of the tip transfer function ``Y(s)/tau(s)`` and the class of the internal dynamics.

The zeros are the eigenvalues of ``A_I`` (Eq. (14)); :func:`transmission_zeros` computes
them independently as the finite generalised eigenvalues of the Rosenbrock pencil.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "assignment",
    "IMAGINARY_TOL",
    "cluster_roots",
    "NEAR_TOL",
    "classify_internal_dynamics",
    "is_unstable",
    "is_imaginary",
    "transmission_zeros",
]

#: Relative tolerance below which a real part counts as zero (round-off of the
#: eigenvalue solver: undamped zeros come out with ``|Re| ~ 1e-15 |z|``).
IMAGINARY_TOL = 1e-9
#: Default relative tolerance of "near non-hyperbolic": ``|Re z| < NEAR_TOL |z|``.
NEAR_TOL = 0.05


def transmission_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike) -> NDArray[np.complex128]:
    """Finite zeros of a SISO state-space system (Rosenbrock pencil).

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
    """Mask of the zeros treated as unstable: ``Re z >= -eps``.

    Mask of the zeros treated as unstable: ``Re z >= -eps`` (docs/method.md section 2).

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


def is_imaginary(zeros: ArrayLike) -> NDArray[np.bool_]:
    """Mask of the zeros treated as purely imaginary.

    ``|Re z| <= IMAGINARY_TOL max(|z|, 1)``: their modes neither decay forwards nor backwards in time.

    Parameters
    ----------
    zeros : array_like of complex
        The zeros.
    """
    z = np.asarray(zeros, dtype=complex)
    return np.asarray(np.abs(z.real) <= IMAGINARY_TOL * np.maximum(np.abs(z), 1.0))


def classify_internal_dynamics(zeros: ArrayLike, near_tol: float = NEAR_TOL) -> str:
    """Class of the internal dynamics from the zeros.

    Class of the internal dynamics from the zeros (docs/method.md section 2).

    Parameters
    ----------
    zeros : ArrayLike
        The zeros.
    near_tol : float, optional
        Largest ``|Re z| / |z|`` that counts as near the imaginary axis.

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


#: Relative accuracy assumed of a computed root of multiplicity one (a backward error of ``1e3 eps``).
ROOT_ACCURACY = 1e3 * float(np.finfo(float).eps)
#: How far above rounding the elementary symmetric functions of a cluster may be (:func:`cluster_roots`).
_CLUSTER_SLACK = 1e3


def cluster_roots(roots: ArrayLike, scale: float | None = None) -> list[tuple[complex, int]]:
    """Computed roots with their rounding noise removed.

    Computed roots (poles, zeros) with their rounding noise removed: repeated roots as one value and a multiplicity.

    A root ``c`` of multiplicity ``m`` comes out of an eigenvalue solver as ``m`` values spread
    around it (``(s + 2)^3``: ``-2.00002, -1.99999 +- 2.1e-5 i``) whose mean is accurate to
    rounding: the values are ``c + w_k`` with the polynomial ``prod (s - w_k)`` equal to ``s^m``
    up to rounding. A group of the ``m`` nearest values is taken as one root when the
    elementary symmetric functions of their deviations from their mean are within
    ``1e3 ROOT_ACCURACY C(m, j) scale^j`` (what perturbing ``(s - c)^m``'s coefficients by
    rounding gives); the largest such group is taken first. Distinct roots farther apart
    than the square root of rounding stay distinct. Then a real or imaginary part below
    ``ROOT_ACCURACY^(1/m)`` of the scale is zero (``9.99e-16 +- 4i`` is ``+-4i``).

    Parameters
    ----------
    roots : array_like of complex
        The computed roots.
    scale : float, optional
        The size of the spectrum they come from (default: the largest root's modulus, at least 1).

    Returns
    -------
    list of (complex, int)
        Each distinct root and its multiplicity, sorted by real part then imaginary part.

    Examples
    --------
    >>> import numpy as np
    >>> [(complex(np.round(c, 9)), m) for c, m in cluster_roots(np.roots(np.poly([-2, -2, -2, 4j, -4j])))]
    [((-2+0j), 3), (-4j, 1), (4j, 1)]
    """
    values = np.asarray(roots, dtype=complex).reshape(-1)
    if values.size == 0:
        return []
    size = float(scale) if scale is not None else max(float(np.abs(values).max()), 1.0)
    from math import comb

    def fits(group: list[int]) -> bool:
        deviations = values[group] - values[group].mean()
        symmetric = np.poly(deviations)
        return all(abs(symmetric[j]) <= _CLUSTER_SLACK * ROOT_ACCURACY * comb(len(group), j) * size ** j
                   for j in range(2, len(group) + 1))

    left = list(range(values.size))
    out: list[tuple[complex, int]] = []
    while left:
        best = [left[0]]
        for i in left:
            nearest = sorted(left, key=lambda k: abs(values[k] - values[i]))
            for m in range(len(nearest), len(best), -1):
                if fits(nearest[:m]):
                    best = nearest[:m]
                    break
        centre = complex(values[best].mean())
        noise = ROOT_ACCURACY ** (1.0 / len(best)) * size
        out.append((complex(0.0 if abs(centre.real) <= noise else centre.real, 0.0 if abs(centre.imag) <= noise else centre.imag),
                    len(best)))
        left = [k for k in left if k not in best]
    return sorted(out, key=lambda item: (item[0].real, item[0].imag))


def assignment(cost: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """The assignment of least total cost of a cost matrix.

    A row to each column of a (rectangular) cost matrix.

    :func:`scipy.optimize.linear_sum_assignment`'s answer, by SciPy's sparse-graph matching
    (:func:`scipy.sparse.csgraph.min_weight_full_bipartite_matching`), which loads in a tenth of the time of
    :mod:`scipy.optimize` (0.02 s against 0.14 s after :mod:`scipy.linalg`): a model's zeros are matched on every load.

    Parameters
    ----------
    cost : array_like, shape (m, n)
        Finite costs (zeros allowed: every pair is an edge).

    Returns
    -------
    rows, cols : ndarray of int
        The pairs, ``rows`` increasing (``min(m, n)`` of them).

    Examples
    --------
    >>> assignment([[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]])
    (array([0, 1, 2]), array([1, 0, 2]))
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import min_weight_full_bipartite_matching

    matrix = np.asarray(cost, dtype=float)
    if matrix.size == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    transposed = matrix.shape[0] > matrix.shape[1]  # the matching covers the smaller side: rows
    work = matrix.T if transposed else matrix
    # a zero entry would be no edge: every cost shifted up by one more than its spread (the same assignment)
    shifted = work - work.min() + 1.0
    rows, cols = min_weight_full_bipartite_matching(csr_matrix(shifted))
    rows, cols = np.asarray(rows, dtype=np.intp), np.asarray(cols, dtype=np.intp)
    if transposed:
        rows, cols = cols, rows
    order = np.argsort(rows)
    return rows[order], cols[order]

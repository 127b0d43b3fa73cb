"""An independent continuum reference: a converged finite-element model of the SFLM.

The assumed-mode model truncates the link to ``n`` shapes; its frequencies and zeros
move with ``n``. This module computes the same quantities from a finite-element model
that shares nothing with the assumed-mode code: cubic Hermite Euler-Bernoulli elements
in the inertial deflection ``u(x, t) = x theta + w(x, t)`` (linear model, docs/method.md
section 1), ``u(0) = 0``, ``u'(0) = theta`` carrying the hub inertia, the payload on the
tip degrees of freedom. Eigenvalues converge as ``h^4``; :func:`continuum_reference`
runs two meshes and reports the difference as the error estimate.

Zeros of ``Y(s)/tau(s)``: with ``y = u(x_out) = 0`` imposed, the torque absorbs the hub
equation; removing that equation and writing the unknowns in a basis of the constraint's
null space (for the tip, ``x_out = L``: dropping the tip-displacement unknown) leaves a
square (non-symmetric) pencil whose eigenvalues are the zeros. ``u(x_out)`` is read through
the element's cubic Hermite interpolation, so any ``0 < x_out <= L`` is measured exactly.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg as sla
from numpy.typing import NDArray

from .geometry import Geometry
from .model import sort_zeros

__all__ = ["ContinuumReference", "continuum_reference", "fe_matrices", "fe_frequencies_zeros", "output_row", "quadratic_pairs"]


def fe_matrices(geometry: Geometry, elements: int) -> tuple[NDArray[np.float64], NDArray[np.float64], int, int]:
    """Assemble the finite-element mass and stiffness matrices.

    Parameters
    ----------
    geometry : Geometry
        The link.
    elements : int
        Number of beam elements along the link.

    Returns
    -------
    M, K : ndarray
        Over the unknowns ``[u'(0), u_1, u'_1, ..., u_N, u'_N]`` (``u(0) = 0`` removed).
    hub, tip : int
        Indices of ``u'(0) = theta`` (where the torque acts) and of ``u(L)`` (the output).
    """
    g = geometry
    h = g.length / elements
    EI, rho = g.flexural_rigidity, g.linear_density
    ke = EI / h**3 * np.array(
        [[12, 6 * h, -12, 6 * h], [6 * h, 4 * h * h, -6 * h, 2 * h * h], [-12, -6 * h, 12, -6 * h], [6 * h, 2 * h * h, -6 * h, 4 * h * h]]
    )
    me = rho * h / 420 * np.array(
        [
            [156, 22 * h, 54, -13 * h],
            [22 * h, 4 * h * h, 13 * h, -3 * h * h],
            [54, 13 * h, 156, -22 * h],
            [-13 * h, -3 * h * h, -22 * h, 4 * h * h],
        ]
    )
    ndof = 2 * (elements + 1)
    K = np.zeros((ndof, ndof))
    M = np.zeros((ndof, ndof))
    for e in range(elements):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += ke
        M[s, s] += me
    M[1, 1] += g.hub_inertia
    M[-2, -2] += g.payload_mass
    M[-1, -1] += g.payload_inertia
    keep = slice(1, ndof)  # u(0) = 0
    return M[keep, keep], K[keep, keep], 0, ndof - 3


def output_row(geometry: Geometry, elements: int, output_at: float | None = None) -> NDArray[np.float64]:
    """The output row ``c`` of a finite-element mesh at ``x_out``.

    ``c`` with ``u(x_out) = c . [u'(0), u_1, u'_1, ..]`` (cubic Hermite interpolation; the tip by default).

    Parameters
    ----------
    geometry : Geometry
        The link.
    elements : int
        Number of beam elements along the link.
    output_at : float | None, optional
        Where the output is measured (m from the hub; ``None``: the tip).
    """
    L = geometry.length
    x = L if output_at is None else float(output_at)
    h = L / elements
    e = min(int(x // h), elements - 1)  # the element holding x (the last one for x = L)
    xi = x / h - e
    shape = np.array([1 - 3 * xi**2 + 2 * xi**3, h * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3, h * (xi**3 - xi**2)])
    row = np.zeros(2 * (elements + 1))
    row[2 * e : 2 * e + 4] = shape
    return row[1:]  # u(0) = 0 removed


def fe_frequencies_zeros(
    geometry: Geometry, elements: int, output_at: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.complex128]]:
    """Flexible frequencies (Hz) and zeros of one finite-element mesh.

    Flexible natural frequencies (Hz) and zeros of one finite-element mesh, the output at ``output_at`` (default the tip).

    Damping is Rayleigh, ``C = (2 zeta / omega_1) K`` with the mesh's own first flexible frequency, plus the hub viscous
    damping, as in the assumed-mode model. The hub's equation is the one the torque absorbs, so the zeros see
    ``C_z = a K_z`` (``a = 2 zeta / omega_1``): ``(s^2 M_z + s C_z + K_z) v = 0`` is ``(s^2 M_z + (1 + a s) K_z) v = 0``,
    and each eigenvalue ``lam`` of the pencil ``(-K_z, M_z)`` (the undamped ``s^2``) gives the pair of zeros
    ``s^2 - a lam s - lam = 0`` (an ``m x m`` pencil, not the ``2m x 2m`` first-order one; an infinite ``lam``, where
    ``M_z`` is singular, leaves ``s = -1/a``). Modal damping (``geometry.modal_damping``) gives each of the mesh's modes
    its ratio, ``C = M Phi diag(2 zeta_i omega_i) Phi^T M``, and the zeros come from the ``2m x 2m`` first-order pencil.

    Parameters
    ----------
    geometry : Geometry
        The link.
    elements : int
        Number of beam elements along the link.
    output_at : float | None, optional
        Where the output is measured (m from the hub; ``None``: the tip).
    """
    M, K, hub, tip = fe_matrices(geometry, elements)
    w2 = np.sort(sla.eigh(K, M, eigvals_only=True))[1:]
    omega = np.sqrt(np.clip(w2, 0.0, None))
    a = 2 * geometry.damping_ratio / omega[0]
    rows = [i for i in range(M.shape[0]) if i != hub]
    c = output_row(geometry, elements, output_at)
    pivot = int(np.argmax(np.abs(c)))  # u_pivot = -(c . u - c_pivot u_pivot) / c_pivot
    cols = [j for j in range(M.shape[0]) if j != pivot]
    P = np.eye(M.shape[0])[:, cols]
    P[pivot] = -c[cols] / c[pivot]
    Mz, Kz = (X[rows] @ P for X in (M, K))
    if geometry.modal_damping:  # each of the mesh's modes its own ratio: the zeros of the quadratic pencil, first order
        w2_all, Phi = sla.eigh(K, M)
        ratios = np.asarray(geometry.modal_ratios(w2_all.size - 1))
        gains = np.concatenate([[0.0], 2 * ratios * np.sqrt(np.clip(w2_all[1:], 0.0, None))])
        Cz = (((M @ Phi) * gains) @ (M @ Phi).T)[rows] @ P
        m = Mz.shape[0]
        first = np.block([[np.zeros((m, m)), np.eye(m)], [-Kz, -Cz]])
        mass = np.block([[np.eye(m), np.zeros((m, m))], [np.zeros((m, m)), Mz]])
        alpha, beta = sla.eigvals(first, mass, homogeneous_eigvals=True)
        finite = np.abs(beta) > 1e-12 * np.abs(alpha)
        return omega / (2 * np.pi), sort_zeros(alpha[finite] / beta[finite])
    alpha, beta = sla.eigvals(-Kz, Mz, homogeneous_eigvals=True)
    finite = beta != 0
    zeros = quadratic_pairs(a, alpha[finite] / beta[finite])
    if a > 0:
        zeros = np.concatenate([zeros, np.full(int(np.count_nonzero(~finite & (alpha != 0))), -1.0 / a)])
    return omega / (2 * np.pi), sort_zeros(zeros)


def quadratic_pairs(a: float, lam: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """Both roots of ``s^2 - a lam s - lam = 0`` without cancellation.

    Both roots of ``s^2 - a lam s - lam = 0`` for each ``lam`` (``+-sqrt(lam)`` for ``a = 0``), without cancellation.

    With ``b = -a lam``, ``c = -lam``: ``q = -(b + sign sqrt(b^2 - 4c)) / 2``, the sign making the two terms add; the
    roots are ``q`` and ``c / q``.

    Parameters
    ----------
    a : float
        The damping's factor (Rayleigh, stiffness-proportional).
    lam : NDArray[np.complex128]
        The undamped eigenvalues, one quadratic each.
    """
    lam = np.asarray(lam, dtype=complex)
    b, c = -a * lam, -lam
    d = np.sqrt(b * b - 4 * c)
    d = np.where((np.conj(b) * d).real >= 0, d, -d)
    q = -(b + d) / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        other = np.where(q != 0, c / np.where(q != 0, q, 1.0), 0.0)
    return np.concatenate([q, other])


@dataclass(frozen=True)
class ContinuumReference:
    """Finite-element reference values and their discretisation error.

    Attributes
    ----------
    natural_frequencies_hz : ndarray
        Lowest flexible natural frequencies (Hz).
    zeros : ndarray of complex
        Lowest zeros (sorted by magnitude).
    frequency_error_hz : ndarray
        ``|f(N) - f(N/2)|``, an upper estimate of the error of ``natural_frequencies_hz``.
    zero_error : ndarray
        The same for the zeros.
    elements : int
        Elements of the finer mesh.
    """

    natural_frequencies_hz: NDArray[np.float64]
    zeros: NDArray[np.complex128]
    frequency_error_hz: NDArray[np.float64]
    zero_error: NDArray[np.float64]
    elements: int


def continuum_reference(geometry: Geometry, count: int = 6, elements: int = 240, output_at: float | None = None) -> ContinuumReference:
    """Lowest frequencies and zeros of a converged FE model.

    Lowest ``count`` frequencies and ``2 count`` zeros of a converged finite-element model.

    Parameters
    ----------
    geometry : Geometry
        The link.
    count : int
        Number of frequencies (and zero pairs) to return.
    elements : int
        Elements of the finer of the two meshes.
    output_at : float, optional
        Where the output is measured (m; default the tip).
    """
    from .derived import kept

    def computed() -> dict[str, NDArray[Any]]:
        f_fine, z_fine = fe_frequencies_zeros(geometry, elements, output_at)
        f_coarse, z_coarse = fe_frequencies_zeros(geometry, elements // 2, output_at)
        nz = 2 * count
        z_fine, z_coarse = z_fine[:nz], z_coarse[: nz + 4]
        return {"frequencies": f_fine[:count], "zeros": z_fine, "frequency_error": np.abs(f_fine[:count] - f_coarse[:count]),
                "zero_error": np.array([np.min(np.abs(z_coarse - z)) for z in z_fine], dtype=float)}

    # two meshes' generalised eigenproblems, 0.3 s of every `sflm info`: kept with the compiled models, read back
    key = {"geometry": geometry.as_dict(), "count": int(count), "elements": int(elements),
           "output_at": None if output_at is None else float(output_at)}
    values = kept("continuum", key, computed, ("continuum.py", "model.py", "geometry.py"))
    return ContinuumReference(
        natural_frequencies_hz=values["frequencies"],
        zeros=values["zeros"],
        frequency_error_hz=values["frequency_error"],
        zero_error=values["zero_error"],
        elements=elements,
    )

"""Modal form of the internal dynamics (Eq. (14) diagonalised, Eqs. (15)-(17)).

``A_I = V diag(lambda) V^-1``, ``z = V^-1 X_I``, ``zdot_i = lambda_i z_i + beta_i yddot``
with ``beta = V^-1 B_I``. The unstable set is ``{i : Re lambda_i >= -eps}``; purely
imaginary zeros belong to it, as in the paper.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.zeros import IMAGINARY_TOL, is_unstable

from ..config import DEFAULTS
from ..errors import InversionError, SettingsError

__all__ = ["ModalInternalDynamics"]

#: Largest accepted condition number of the eigenvector matrix (repeated or nearly
#: repeated zeros make the modal form meaningless).
_MAX_COND_V = 1e10


@dataclass(frozen=True)
class ModalInternalDynamics:
    """The internal dynamics in modal coordinates.

    Attributes
    ----------
    lam : ndarray of complex, shape (2n,)
        Eigenvalues of ``A_I`` (the zeros).
    V, Vinv : ndarray of complex
        Eigenvectors and their inverse.
    beta : ndarray of complex, shape (2n,)
        ``V^-1 B_I``.
    unstable : ndarray of bool
        Membership of the unstable set ``U``.
    rows : tuple of (int, str)
        The real constraint rows of the unstable set: ``(i, "re")`` for a real ``lambda_i``,
        ``(i, "re"), (i, "im")`` for one member of each complex pair.
    cond_V : float
        Condition number of ``V``.
    free : ndarray of bool
        Unstable modes left without constraint rows (:mod:`inversion.lti.zero_dynamics`):
        they follow their bounded particular solution inside each segment and are not in
        ``unstable``.
    """

    lam: NDArray[np.complex128]
    V: NDArray[np.complex128]
    Vinv: NDArray[np.complex128]
    beta: NDArray[np.complex128]
    unstable: NDArray[np.bool_]
    rows: tuple[tuple[int, str], ...]
    cond_V: float
    free: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))

    def __post_init__(self) -> None:
        if self.free.shape != self.lam.shape:
            object.__setattr__(self, "free", np.zeros(self.lam.shape, dtype=bool))

    @cached_property
    def row_modes(self) -> NDArray[np.intp]:
        """Mode index of each constraint row."""
        return np.array([i for i, _ in self.rows], dtype=np.intp)

    @cached_property
    def row_imag(self) -> NDArray[np.bool_]:
        """Whether each constraint row takes the imaginary part."""
        return np.array([part == "im" for _, part in self.rows], dtype=bool)

    @classmethod
    def from_matrices(cls, AI: ArrayLike, BI: ArrayLike, eps: float = DEFAULTS.eps, free: ArrayLike = ()) -> "ModalInternalDynamics":
        """Diagonalise ``A_I``.

        Parameters
        ----------
        AI, BI : array_like
            Internal dynamics of Eq. (14).
        eps : float
            Tolerance of the unstable set (1/s, >= 0): zeros with ``Re >= -eps`` are
            constrained (near-non-hyperbolic zeros can be treated as unstable with it).
        free : array_like of complex
            Unstable zeros to leave without constraint rows (matched to ``eig(A_I)`` within
            ``1e-8`` relative; conjugates together).

        Raises
        ------
        SettingsError
            For a negative or non-finite ``eps``.
        InversionError
            If ``A_I`` is not diagonalisable to working accuracy, or a ``free`` zero is not one
            of its unstable eigenvalues.
        """
        if not isinstance(eps, (int, float)) or not np.isfinite(eps) or eps < 0:
            raise SettingsError("eps", eps, "a finite number >= 0 (1/s)")
        AI = np.asarray(AI, dtype=float)
        BI = np.asarray(BI, dtype=float).reshape(-1)
        lam, V = np.linalg.eig(AI)
        cond_V = float(np.linalg.cond(V)) if V.size else 1.0  # no internal dynamics (relative degree = order): nothing to diagonalise
        if not np.isfinite(cond_V) or cond_V > _MAX_COND_V:
            raise InversionError(
                f"the internal dynamics A_I is not diagonalisable to working accuracy: cond(V) = {cond_V:.3e} "
                f"(> {_MAX_COND_V:.0e}; repeated zeros?)",
                condition=cond_V,
            )
        Vinv = np.linalg.inv(V)
        beta = Vinv @ BI
        unstable = is_unstable(lam, eps)
        released = np.zeros(lam.shape, dtype=bool)
        for z in np.atleast_1d(np.asarray(free, dtype=complex)):
            match = (np.abs(lam - z) <= 1e-8 * max(abs(z), 1e-300)) | (np.abs(lam - np.conj(z)) <= 1e-8 * max(abs(z), 1e-300))
            if not np.any(match & unstable):
                raise InversionError(f"the zero {z:.6g} to leave free is not an unstable zero of A_I ({lam})")
            released |= match & unstable
        unstable &= ~released
        rows: list[tuple[int, str]] = []
        taken: set[int] = set()
        for i in np.flatnonzero(unstable):
            if i in taken:
                continue
            z = lam[i]
            if abs(z.imag) <= IMAGINARY_TOL * abs(z):
                rows.append((int(i), "re"))
                taken.add(int(i))
                continue
            partner = [j for j in np.flatnonzero(unstable) if j not in taken and j != i
                       and abs(lam[j] - z.conjugate()) <= 1e-8 * abs(z)]
            if not partner:
                raise InversionError(f"unstable zero {z} has no conjugate partner in the unstable set (eps too tight?)")
            rows += [(int(i), "re"), (int(i), "im")]
            taken.update({int(i), int(partner[0])})
        return cls(lam, V, Vinv, beta, unstable, tuple(rows), cond_V, released)

    @property
    def n_unstable(self) -> int:
        """``n_u``: the size of the unstable set (= number of constraint rows)."""
        return int(np.count_nonzero(self.unstable))

    def to_modal(self, XI: ArrayLike) -> NDArray[np.complex128]:
        """``z = V^-1 X_I``.

        Parameters
        ----------
        XI : ArrayLike
            Internal states.
        """
        return np.asarray(self.Vinv @ np.asarray(XI, dtype=float), dtype=complex)

    def to_physical(self, z: NDArray[np.complex128]) -> NDArray[np.float64]:
        """``X_I = Re(V z)`` for ``z`` of shape ``(..., 2n)``.

        Parameters
        ----------
        z : NDArray[np.complex128]
            Modal states.
        """
        return np.asarray(np.real(z @ self.V.T))

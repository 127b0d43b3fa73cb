"""The numbers the inversion needs from a model: output normal form and plant matrices.

:class:`NormalForm` is plain NumPy (no compiled code, no SymPy): it is what the segment
problem, the figures, the verification and the explorer's worker processes use. For the
flexible link (relative degree 2, Eqs. (9)-(14)):

* the plant ``Xdot = A X + B tau``, ``y = C X``;
* the internal dynamics ``X_I = [delta; deltadot]``, ``X_Idot = A_I X_I + B_I yddot``;
* ``X = T^-1 [y; ydot; X_I]``;
* the inverse input, Eq. (12): ``tau = (yddot - C A^2 X) / (C A B)``.

A generic SISO system of relative degree 2 (:mod:`inversion.linear_system`) gives the same
numbers from its numerical normal form (:meth:`NormalForm.of_system`), in its balanced
realisation; its input ``u`` takes the place of ``tau``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .internal import ModalInternalDynamics

__all__ = ["NormalForm"]

FloatArray = NDArray[np.float64]

_CACHE: dict[int, tuple[Any, "NormalForm"]] = {}


@dataclass(frozen=True, eq=False)
class NormalForm:
    """A SISO linear system of relative degree 2 in the coordinates of the inversion.

    Attributes
    ----------
    name : str
        Model name (for messages).
    A, B, C : ndarray
        Plant (P9): ``Xdot = A X + B u``, ``y = C X``.
    AI, BI : ndarray
        Internal dynamics (P14), driven by ``yddot``.
    Tinv : ndarray
        ``X = Tinv [y; ydot; X_I]``.
    CA2 : ndarray
        The row ``C A^2``.
    CAB : float
        ``C A B`` (nonzero).
    free_zeros : tuple of complex
        Unstable zeros the inversion leaves without constraint rows
        (:mod:`inversion.zero_dynamics`; empty: every unstable zero is constrained).
    """

    name: str
    A: FloatArray
    B: FloatArray
    C: FloatArray
    AI: FloatArray
    BI: FloatArray
    Tinv: FloatArray
    CA2: FloatArray
    CAB: float
    free_zeros: tuple[complex, ...] = ()
    _modal: dict[float, ModalInternalDynamics] = field(default_factory=dict, repr=False)

    @classmethod
    def of_model(cls, model: Any) -> "NormalForm":
        """The normal form of a loaded :class:`modelgen.Model` (cached per model)."""
        cached = _CACHE.get(id(model))
        if cached is None or cached[0] is not model:
            if len(_CACHE) > 64:
                _CACHE.clear()
            form = cls(
                name=str(model.name),
                A=np.asarray(model.A, dtype=float),
                B=np.asarray(model.B, dtype=float).reshape(-1),
                C=np.asarray(model.C_out, dtype=float).reshape(-1),
                AI=np.asarray(model.AI, dtype=float),
                BI=np.asarray(model.BI, dtype=float).reshape(-1),
                Tinv=np.asarray(model.Tinv, dtype=float),
                CA2=np.asarray(model.CA2, dtype=float).reshape(-1),
                CAB=float(model.CAB),
            )
            cached = _CACHE[id(model)] = (model, form)
        return cached[1]

    @classmethod
    def of_system(cls, system: Any) -> "NormalForm":
        """The normal form of a :class:`~inversion.linear_system.LinearSystem` of relative degree 2 (cached per system).

        The plant matrices are the balanced realisation's (``X = system.scale * X_b``).
        """
        cached = _CACHE.get(id(system))
        if cached is None or cached[0] is not system:
            if len(_CACHE) > 64:
                _CACHE.clear()
            c = system.coordinates
            if c.rho != 2:
                raise ValueError(f"NormalForm holds relative degree 2, not {c.rho}")
            A, B, C = system.balanced
            form = cls(name=system.name, A=A, B=B, C=C, AI=c.AI, BI=c.BI, Tinv=c.Tinv, CA2=c.CArho, CAB=c.gain)
            cached = _CACHE[id(system)] = (system, form)
        return cached[1]

    def equilibrium_input(self, y: float) -> float:
        """The input that holds the plant at rest with output ``y`` (``X_I = 0``, ``ydot = 0``).

        Zero for the link (its rigid mode is a double integrator); ``y / G(0)`` for a
        system with a finite static gain.
        """
        return float(-(self.CA2 @ self.Tinv[:, 0]) * y / self.CAB)

    @property
    def n_internal(self) -> int:
        """Dimension of the internal state ``X_I`` (``2n`` for ``n`` modes)."""
        return int(self.AI.shape[0])

    @property
    def n_states(self) -> int:
        """Dimension of the plant state."""
        return int(self.A.shape[0])

    def modal(self, eps: float = 0.0) -> ModalInternalDynamics:
        """The diagonalised internal dynamics for the unstable-set tolerance ``eps`` (cached)."""
        key = float(eps)
        if key not in self._modal:
            self._modal[key] = ModalInternalDynamics.from_matrices(self.AI, self.BI, key, self.free_zeros)
        return self._modal[key]

    def state(self, y: Any, ydot: Any, XI: Any) -> Any:
        """``X = Tinv [y; ydot; X_I]`` for samples in rows (any float precision)."""
        Tinv = self.Tinv.astype(np.result_type(XI, np.float64))
        return np.asarray(y)[..., None] * Tinv[:, 0] + np.asarray(ydot)[..., None] * Tinv[:, 1] + XI @ Tinv[:, 2:].T

    def torque(self, yddot: Any, X: Any) -> Any:
        """Eq. (12): ``(yddot - C A^2 X) / (C A B)`` for samples in rows (any float precision)."""
        CA2 = self.CA2.astype(np.result_type(X, np.float64))
        return (np.asarray(yddot) - X @ CA2) / self.CAB

    def torque_of_output(self, yddot: Any, y: Any, ydot: Any, XI: Any) -> Any:
        """Eq. (12) from ``y, ydot, yddot, X_I`` without forming ``X``: ``C A^2 X = w . [y; ydot; X_I]``, ``w = Tinv^T (C A^2)^T``."""
        w = (self.Tinv.T @ self.CA2).astype(np.result_type(XI, np.float64))
        return (np.asarray(yddot) - w[0] * np.asarray(y) - w[1] * np.asarray(ydot) - XI @ w[2:]) / self.CAB

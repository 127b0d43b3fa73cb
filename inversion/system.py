"""The numbers the inversion needs from a model: output normal form and plant matrices.

:class:`NormalForm` is plain NumPy (no compiled code, no SymPy): it is what the segment
problem, the figures, the verification and the explorer's worker processes use. For the
flexible link (relative degree 2, Eqs. (9)-(14)):

* the plant ``Xdot = A X + B tau``, ``y = C X``;
* the internal dynamics ``X_I = [delta; deltadot]``, ``X_Idot = A_I X_I + B_I yddot``;
* ``X = T^-1 [y; ydot; X_I]``;
* the inverse input, Eq. (12): ``tau = (yddot - C A^2 X) / (C A B)``.

A generic SISO system (:mod:`inversion.linear_system`) gives the same numbers from its
numerical normal form (:meth:`NormalForm.of_system`), in its balanced realisation; its input
``u`` takes the place of ``tau``. Whatever its relative degree ``rho``, the internal
dynamics are written as driven by ``yddot`` -- the quantity the segment problem redefines --
through a change of internal coordinates (docs/method.md, section 5e)::

    X_I = Z + sum_j F_j y^(j),     Zdot = A_I Z + B_I' yddot

* ``rho = 1`` (``X_Idot = A_I X_I + B_I ydot``): ``F_1 = -A_I^-1 B_I``, ``B_I' = A_I^-1 B_I``;
* ``rho >= 3`` (driven by ``y^(rho)``): ``F_j = A_I^(rho-1-j) B_I`` for ``j = 2 .. rho-1``,
  ``B_I' = A_I^(rho-2) B_I``.

Then ``X = Tinv [y; ydot; Z] + sum_{j=2}^{rho-1} H_j y^(j)`` and the input is
``u = (y^(rho) - C A^rho X) / (C A^(rho-1) B)``. The redefined ``y~^(rho)`` is a derivative
(``rho >= 2``) or the integral (``rho = 1``) of the sum of stable exponentials ``yddot~``: a
sum of stable exponentials itself (with a constant term for ``rho = 1``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .internal import ModalInternalDynamics
from .trajectory import derivative_key

__all__ = ["NormalForm", "normal_form"]

FloatArray = NDArray[np.float64]

_CACHE: dict[int, tuple[Any, "NormalForm"]] = {}


@dataclass(frozen=True, eq=False)
class NormalForm:
    """A SISO linear system in the coordinates of the inversion (module docstring).

    Attributes
    ----------
    name : str
        Model name (for messages).
    A, B, C : ndarray
        Plant (P9): ``Xdot = A X + B u``, ``y = C X``.
    AI, BI : ndarray
        Internal dynamics (P14), driven by ``yddot``: ``A_I`` and ``B_I'``.
    Tinv : ndarray
        ``X = Tinv [y; ydot; Z] + higher [yddot .. y^(rho-1)]`` (``Z = X_I`` for ``rho = 2``).
    CA2 : ndarray
        The row ``C A^rho`` (``C A^2`` for the link).
    CAB : float
        ``C A^(rho-1) B`` (nonzero; ``C A B`` for the link).
    free_zeros : tuple of complex
        Unstable zeros the inversion leaves without constraint rows
        (:mod:`inversion.zero_dynamics`; empty: every unstable zero is constrained).
    rho : int
        Relative degree: the input is ``(y^(rho) - C A^rho X) / C A^(rho-1) B``.
    higher : ndarray, shape (N, max(rho - 2, 0))
        The columns ``H_j`` of ``y^(j)``, ``j = 2 .. rho-1``, in ``X``.
    shift : ndarray, shape (2n, max(rho, 2))
        ``F_j`` as columns ``j = 0 .. max(rho, 2) - 1``: ``X_I = Z + shift [y; ydot; ..]``
        (zero for ``rho = 2``).
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
    rho: int = 2
    higher: FloatArray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    shift: FloatArray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
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
        """The normal form of a :class:`~inversion.linear_system.LinearSystem`, any relative degree (cached per system).

        The plant matrices are the balanced realisation's (``X = system.scale * X_b``); the
        internal coordinates are those driven by ``yddot`` (module docstring).
        """
        cached = _CACHE.get(id(system))
        if cached is None or cached[0] is not system:
            if len(_CACHE) > 64:
                _CACHE.clear()
            c = system.coordinates
            rho, AI, BI = c.rho, c.AI, c.BI
            A, B, C = system.balanced
            N, m = A.shape[0], AI.shape[0]
            P = c.Tinv[:, rho:]  # X_I -> X
            shift = np.zeros((m, max(rho, 2)))
            if rho == 1:
                BI = np.linalg.solve(AI, c.BI) if m else c.BI
                shift[:, 1] = -BI
            power = c.BI.copy()
            for j in range(rho - 1, 1, -1):  # F_j = A_I^(rho-1-j) B_I
                shift[:, j] = power
                power = AI @ power
            if rho >= 3:
                BI = power  # A_I^(rho-2) B_I
            # the column of y^(j) in X: its own (j < rho) and the one it reaches through X_I = Z + F_j y^(j)
            columns = [(c.Tinv[:, j] if j < rho else np.zeros(N)) + P @ shift[:, j] for j in range(max(rho, 2))]
            Tinv = np.column_stack(columns[:2] + [P])
            higher = np.column_stack(columns[2:]) if rho > 2 else np.zeros((N, 0))
            form = cls(name=system.name, A=A, B=B, C=C, AI=AI, BI=np.asarray(BI, dtype=float), Tinv=Tinv, CA2=c.CArho, CAB=c.gain,
                       rho=rho, higher=higher, shift=shift)
            cached = _CACHE[id(system)] = (system, form)
        return cached[1]

    @property
    def drive(self) -> str:
        """The name of ``y^(rho)`` (the derivative the input sees) in a dictionary of values."""
        return derivative_key(self.rho)

    @property
    def top(self) -> int:
        """The highest derivative of ``y`` that the state and the input need (at least ``yddot``)."""
        return max(self.rho, 2)

    def equilibrium_input(self, y: float) -> float:
        """The input that holds the plant at rest with output ``y`` (``X_I = 0``, every derivative 0).

        Zero for the link (its rigid mode is a double integrator); ``y / G(0)`` for a
        system with a finite static gain.
        """
        return float(-(self.CA2 @ self.Tinv[:, 0]) * y / self.CAB)

    def internal_start(self, XI: Any, values: dict[str, Any]) -> Any:
        """``Z = X_I - shift [y; ydot; ..]`` from the physical internal state and the output's derivatives (one point)."""
        XI = np.asarray(XI, dtype=float).reshape(-1)
        if not self.shift.any():
            return XI
        chain = np.array([float(np.asarray(values[derivative_key(j)]).reshape(-1)[0]) for j in range(self.shift.shape[1])])
        return XI - self.shift @ chain

    def state_of(self, values: dict[str, Any]) -> Any:
        """``X`` from a dictionary of values (``y, ydot, XI`` and, for ``rho >= 3``, ``yddot .. y^(rho-1)``)."""
        X = self.state(values["y"], values["ydot"], values["XI"])
        for j in range(self.higher.shape[1]):
            X = X + np.asarray(values[derivative_key(j + 2)])[..., None] * self.higher[:, j].astype(X.dtype)
        return X

    def input_of(self, values: dict[str, Any], X: Any) -> Any:
        """The input from the values' ``y^(rho)`` and the state: Eq. (12) generalised."""
        return self.torque(values[self.drive], X)

    def input_of_output(self, values: dict[str, Any]) -> Any:
        """:meth:`input_of` without forming ``X`` (``C A^rho X`` as one row on the outputs)."""
        if self.higher.shape[1]:
            return self.input_of(values, self.state_of(values))
        return self.torque_of_output(values[self.drive], values["y"], values["ydot"], values["XI"])

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
        """Eq. (12): ``(yddot - C A^2 X) / (C A B)`` for samples in rows (any float precision); for a
        generic system ``(y^(rho) - C A^rho X) / C A^(rho-1) B`` with ``y^(rho)`` in place of ``yddot``."""
        CA2 = self.CA2.astype(np.result_type(X, np.float64))
        return (np.asarray(yddot) - X @ CA2) / self.CAB

    def torque_of_output(self, yddot: Any, y: Any, ydot: Any, XI: Any) -> Any:
        """Eq. (12) from ``y, ydot, yddot, X_I`` without forming ``X``: ``C A^2 X = w . [y; ydot; X_I]``, ``w = Tinv^T (C A^2)^T``
        (``rho <= 2``; ``yddot`` is ``y^(rho)``)."""
        w = (self.Tinv.T @ self.CA2).astype(np.result_type(XI, np.float64))
        return (np.asarray(yddot) - w[0] * np.asarray(y) - w[1] * np.asarray(ydot) - XI @ w[2:]) / self.CAB


def normal_form(model: Any) -> NormalForm:
    """The :class:`NormalForm` of a loaded link model, of any SISO system :func:`inversion.invert`
    accepts (:func:`~inversion.linear_system.as_linear_system`), or the form itself.

    Raises
    ------
    SettingsError
        For something that is not a model or an accepted system (naming what it is).
    """
    if isinstance(model, NormalForm):
        return model
    from modelgen.model import Model

    if isinstance(model, Model):
        return NormalForm.of_model(model)
    from .linear_system import as_linear_system

    return NormalForm.of_system(as_linear_system(model))

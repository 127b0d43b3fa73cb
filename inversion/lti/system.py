"""The numbers the inversion needs from a model: output normal form and plant matrices.

:class:`NormalForm` is plain NumPy (no compiled code, no SymPy): it is what the segment
problem, the figures, the verification and the explorer's worker processes use. For the
flexible link (relative degree 2, Eqs. (9)-(14)):

* the plant ``Xdot = A X + B tau``, ``y = C X``;
* the internal dynamics ``X_I = [delta; deltadot]``, ``X_Idot = A_I X_I + B_I yddot``;
* ``X = T^-1 [y; ydot; X_I]``;
* the inverse input, Eq. (12): ``tau = (yddot - C A^2 X) / (C A B)``.

A generic SISO system (:mod:`inversion.lti.linear_system`) gives the same numbers from its
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

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np
from numpy.typing import NDArray

from ..config import DEFAULTS
from ..signals.trajectory import derivative_key
from .internal import ModalInternalDynamics

__all__ = ["NormalForm", "normal_form"]

FloatArray = NDArray[np.float64]

_CACHE: dict[int, tuple[Any, "NormalForm"]] = {}


@dataclass(frozen=True, eq=False)
class NormalForm:
    """A SISO linear system in the inversion's coordinates.

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
        (:mod:`inversion.lti.zero_dynamics`; empty: every unstable zero is constrained).
    rho : int
        Relative degree: the input is ``(y^(rho) - C A^rho X) / C A^(rho-1) B``.
    higher : ndarray, shape (N, max(rho - 2, 0))
        The columns ``H_j`` of ``y^(j)``, ``j = 2 .. rho-1``, in ``X``.
    shift : ndarray, shape (2n, max(rho, 2))
        ``F_j`` as columns ``j = 0 .. max(rho, 2) - 1``: ``X_I = Z + shift [y; ydot; ..]``
        (zero for ``rho = 2``).
    inertia : float or None
        A link's ``J = M[0, 0]`` (hub, link and payload about the joint, kg m^2); ``None``
        for a generic system.
    output_at : float or None
        Where a link's output is measured (m); ``None`` for a generic system.
    joint_damping : float
        A link's viscous damping on the joint (``b_h`` and the joint's share of Rayleigh
        damping, N m s/rad: the ``(0, 0)`` entry of ``-M A_vv``); zero for a generic system.
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
    inertia: float | None = None
    output_at: float | None = None
    joint_damping: float = 0.0
    _modal: dict[float, ModalInternalDynamics] = field(default_factory=dict, repr=False)

    @classmethod
    def of_model(cls, model: Any) -> "NormalForm":
        """The normal form of a loaded :class:`modelgen.Model` (cached per model)."""
        cached = _CACHE.get(id(model))
        if cached is None or cached[0] is not model:
            if len(_CACHE) > 64:
                _CACHE.clear()
            matrices = {k: getattr(model, k) for k in ("A", "B", "C_out", "AI", "BI", "Tinv", "CA2", "CAB", "M")}
            cached = _CACHE[id(model)] = (model, cls.of_matrices(str(model.name), matrices, float(model.output_at)))
        return cached[1]

    @classmethod
    def of_matrices(cls, name: str, matrices: Mapping[str, Any], output_at: float) -> "NormalForm":
        """The normal form of a link from its matrices (``A, B, C_out, AI, BI, Tinv, CA2, CAB, M``: a
        :class:`modelgen.Model`'s, or :func:`modelgen.linear.linear_model`'s)."""
        A = np.asarray(matrices["A"], dtype=float)
        M = np.asarray(matrices["M"], dtype=float)
        n1 = M.shape[0]
        return cls(
            name=name,
            A=A,
            B=np.asarray(matrices["B"], dtype=float).reshape(-1),
            C=np.asarray(matrices["C_out"], dtype=float).reshape(-1),
            AI=np.asarray(matrices["AI"], dtype=float),
            BI=np.asarray(matrices["BI"], dtype=float).reshape(-1),
            Tinv=np.asarray(matrices["Tinv"], dtype=float),
            CA2=np.asarray(matrices["CA2"], dtype=float).reshape(-1),
            CAB=float(matrices["CAB"]),
            inertia=float(M[0, 0]),
            output_at=float(output_at),
            joint_damping=float(-(M[0] @ A[n1:, n1:])[0]),
        )

    @classmethod
    def of_system(cls, system: Any) -> "NormalForm":
        """The normal form of a :class:`~inversion.lti.linear_system.LinearSystem`, any relative degree (cached per system).

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
        """The input that holds the plant at rest with output ``y``.

        Zero for the link (its rigid mode is a double integrator); ``y / G(0)`` for a
        system with a finite static gain.

        Parameters
        ----------
        y : float
            The output held.
        """
        return float(-(self.CA2 @ self.Tinv[:, 0]) * y / self.CAB)

    def internal_start(self, XI: Any, values: dict[str, Any]) -> Any:
        """``Z = X_I - shift [y; ydot; ..]`` at one point.

        ``Z = X_I - shift [y; ydot; ..]`` from the physical internal state and the output's derivatives (one point).

        Parameters
        ----------
        XI : Any
            The physical internal state.
        values : dict[str, Any]
            The output and its derivatives.
        """
        XI = np.asarray(XI, dtype=float).reshape(-1)
        if not self.shift.any():
            return XI
        chain = np.array([float(np.asarray(values[derivative_key(j)]).reshape(-1)[0]) for j in range(self.shift.shape[1])])
        return XI - self.shift @ chain

    def state_of(self, values: dict[str, Any]) -> Any:
        """``X`` from a dictionary of values.

        ``X`` from a dictionary of values (``y, ydot, XI`` and, for ``rho >= 3``, ``yddot .. y^(rho-1)``).

        Parameters
        ----------
        values : dict[str, Any]
            The output, its derivatives and ``XI``.
        """
        X = self.state(values["y"], values["ydot"], values["XI"])
        for j in range(self.higher.shape[1]):
            X = X + np.asarray(values[derivative_key(j + 2)])[..., None] * self.higher[:, j].astype(X.dtype)
        return X

    def input_of(self, values: dict[str, Any], X: Any) -> Any:
        """The input from the values: Eq. (12) generalised.

        The input from the values' ``y^(rho)`` and the state: Eq. (12) generalised.

        Parameters
        ----------
        values : dict[str, Any]
            The output's values, ``y^(rho)`` among them.
        X : Any
            The state.
        """
        return self.torque(values[self.drive], X)

    def input_of_output(self, values: dict[str, Any]) -> Any:
        """:meth:`input_of` without forming ``X``.

        :meth:`input_of` without forming ``X`` (``C A^rho X`` as one row on the outputs).

        Parameters
        ----------
        values : dict[str, Any]
            The output's values and ``XI``.
        """
        if self.higher.shape[1]:
            return self.input_of(values, self.state_of(values))
        return self.torque_of_output(values[self.drive], values["y"], values["ydot"], values["XI"])

    def rigid_part(self, u_held: float = 0.0) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The plant's rigid motion, decoupled from the rest.

        The plant's part at ``s = 0`` (its rigid motion), decoupled from the rest.

        The plant with its input held at ``u_held``, ``[Xdot; 0] = [[A, B], [0, 0]] [X; u]``, is
        put in real Schur form with its eigenvalues at zero first (``|lambda| <= 1e-9`` of the
        largest) and block-diagonalised by a Sylvester equation, ``T11`` nilpotent.

        Parameters
        ----------
        u_held : float, optional
            The input held.

        Returns
        -------
        T11 : ndarray, shape (m, m)
            The nilpotent block (a link's rigid mode: the double integrator; the held input
            adds one zero of its own).
        rows : ndarray, shape (m, N + 1)
            The map from ``[X; u]`` to the coordinates ``w1`` of that block.
        out : ndarray, shape (m,)
            The output's row on ``w1``: ``y = out . w1 + (decaying and oscillating rest)``.
        """
        import scipy.linalg as sla  # lazy: keeps `import inversion` fast

        N = self.n_states
        Aa = np.zeros((N + 1, N + 1))
        Aa[:N, :N], Aa[:N, N] = self.A, self.B
        tol = 1e-9 * max(float(np.abs(np.linalg.eigvals(self.A)).max(initial=0.0)), 1.0)
        T, Z, m = sla.schur(Aa, output="real", sort=lambda re, im: math.hypot(re, im) <= tol)
        T11, T12, T22 = T[:m, :m], T[:m, m:], T[m:, m:]
        X = sla.solve_sylvester(T11, -T22, -T12) if m and m < N + 1 else np.zeros((m, N + 1 - m))
        # [w1; w2] = S^-1 Z^T [X; u], S = [[I, X], [0, I]]: w1 = (Z^T)_1 - X (Z^T)_2
        Zt = Z.T
        rows = Zt[:m] - X @ Zt[m:]
        Ca = np.append(self.C, 0.0)
        out = Ca @ Z[:, :m]
        return T11, rows, out

    def drift(self, X: Any, u_held: float = 0.0) -> FloatArray:
        """The output's rate the plant keeps with its input held.

        The output's rate that the plant keeps for ever from the states ``X`` with the input held at ``u_held``.

        Left alone, a link keeps turning at the rate its angular momentum gives
        (``x_out h / J``, ``h`` the momentum about the joint); a stable system keeps none.
        Exact: the rigid part's ``y = out . e^{T11 t} w1`` grows as ``out . T11 w1 t`` (the
        higher powers of ``T11`` vanish for the links and for systems with at most a double
        integrator).

        Parameters
        ----------
        X : Any
            States.
        u_held : float, optional
            The input held.
        """
        T11, rows, out = self.rigid_part(u_held)
        Xa = np.concatenate([np.atleast_2d(np.asarray(X, dtype=float)), np.full((np.atleast_2d(X).shape[0], 1), u_held)], axis=1)
        return np.asarray((Xa @ rows.T) @ T11.T @ out)

    def low_frequency_gain(self) -> tuple[int, float]:
        """``(m, g)`` with ``G(s) -> g / s^m`` as ``s -> 0``.

        ``(m, g)`` with ``G(s) -> g / s^m`` as ``s -> 0``: the plant as a rigid body sees it.

        A link is a double integrator at low frequency (``m = 2``, ``g = x_out / J``); a system
        with a finite static gain has ``m = 0``, ``g = G(0)``.
        """
        import scipy.linalg as sla  # lazy: keeps `import inversion` fast

        N = self.n_states
        tol = 1e-9 * max(float(np.abs(np.linalg.eigvals(self.A)).max(initial=0.0)), 1.0)
        T, Z, m = sla.schur(self.A, output="real", sort=lambda re, im: math.hypot(re, im) <= tol)
        T11, T12, T22 = T[:m, :m], T[:m, m:], T[m:, m:]
        X = sla.solve_sylvester(T11, -T22, -T12) if m and m < N else np.zeros((m, N - m))
        Bz, Cz = Z.T @ self.B, self.C @ Z
        B1, C1 = Bz[:m] - X @ Bz[m:], Cz[:m]
        scale = float(np.abs(self.C).sum() * np.abs(self.B).sum()) * max(float(np.abs(self.A).max()), 1.0) ** max(m - 1, 0)
        power = np.eye(m)
        best = (0, 0.0)
        for k in range(m):  # the coefficient of s^-(k+1): C1 T11^k B1
            value = float(C1 @ power @ B1)
            if abs(value) > 1e-10 * scale:
                best = (k + 1, value)
            power = power @ T11
        if best[0]:
            return best
        C2, B2 = Cz[m:] + C1 @ X, Bz[m:]
        return 0, float(-C2 @ np.linalg.solve(T22, B2)) if N - m else 0.0

    def rigid_input(self, derivatives: Any) -> float:
        """The peak input a rigid body needs along the desired output.

        The peak input a rigid body needs along the desired output (the scale of a plausible feedforward).

        A link: ``max |J yddot_d + b ydot_d| / x_out`` (a rigid link of the same inertia
        ``J`` and joint damping ``b``, Eq. (6) without its deflections). A generic system: its static inverse along ``y_d``,
        ``max |y_d^(m)| / |g|`` with ``G(s) -> g / s^m`` (:meth:`low_frequency_gain`;
        ``max |y_d| / |G(0)|`` for a finite static gain).

        Parameters
        ----------
        derivatives : callable
            ``derivatives(k)``: ``y_d^(k)`` on a dense grid of the move.
        """
        need = self.rigid_need(derivatives)
        return float(np.abs(need).max()) if need.size else float("inf")

    @property
    def need_orders(self) -> tuple[int, ...]:
        """The orders of ``y_d``'s derivatives :meth:`rigid_need` reads: 1 and 2 for a link, ``m`` for a system."""
        if self.inertia is not None and self.output_at is not None:
            return (1, 2)
        return (self.low_frequency_gain()[0],)

    def rigid_need(self, derivatives: Any) -> FloatArray:
        """The input a rigid body needs along the desired output.

        The input a rigid body needs along the desired output, on the grid ``derivatives`` gives (:meth:`rigid_input`):
        ``(J yddot_d + b ydot_d) / x_out`` for a link, ``y_d^(m) / g`` for a generic system (empty when ``g = 0``).

        Parameters
        ----------
        derivatives : Any
            A function ``k -> y_d^(k)`` on the grid.
        """
        if self.inertia is not None and self.output_at is not None:
            return np.asarray((self.inertia * derivatives(2) + self.joint_damping * derivatives(1)) / self.output_at, dtype=float)
        m, g = self.low_frequency_gain()
        return np.asarray(derivatives(m), dtype=float) / g if g else np.zeros(0)

    @property
    def n_internal(self) -> int:
        """Dimension of the internal state ``X_I`` (``2n`` for ``n`` modes)."""
        return int(self.AI.shape[0])

    @property
    def n_states(self) -> int:
        """Dimension of the plant state."""
        return int(self.A.shape[0])

    def modal(self, eps: float = DEFAULTS.eps) -> ModalInternalDynamics:
        """The diagonalised internal dynamics for ``eps`` (cached).

        Parameters
        ----------
        eps : float, optional
            The unstable-set tolerance.
        """
        key = float(eps)
        if key not in self._modal:
            self._modal[key] = ModalInternalDynamics.from_matrices(self.AI, self.BI, key, self.free_zeros)
        return self._modal[key]

    def state(self, y: Any, ydot: Any, XI: Any) -> Any:
        """``X = Tinv [y; ydot; X_I]`` for samples in rows.

        ``X = Tinv [y; ydot; X_I]`` for samples in rows (any float precision).

        Parameters
        ----------
        y : Any
            Outputs.
        ydot : Any
            Their rates.
        XI : Any
            Internal states.
        """
        Tinv = self.Tinv.astype(np.result_type(XI, np.float64))
        return np.asarray(y)[..., None] * Tinv[:, 0] + np.asarray(ydot)[..., None] * Tinv[:, 1] + XI @ Tinv[:, 2:].T

    def torque(self, yddot: Any, X: Any) -> Any:
        """Eq. (12): the input from the output and the state.

        Eq. (12): ``(yddot - C A^2 X) / (C A B)`` for samples in rows (any float precision); for a
        generic system ``(y^(rho) - C A^rho X) / C A^(rho-1) B`` with ``y^(rho)`` in place of ``yddot``.

        Parameters
        ----------
        yddot : Any
            The output's ``rho``-th derivative.
        X : Any
            States.
        """
        CA2 = self.CA2.astype(np.result_type(X, np.float64))
        return (np.asarray(yddot) - X @ CA2) / self.CAB

    def torque_of_output(self, yddot: Any, y: Any, ydot: Any, XI: Any) -> Any:
        """Eq. (12) from ``y, ydot, yddot, X_I`` without forming ``X``.

        Eq. (12) from ``y, ydot, yddot, X_I`` without forming ``X``: ``C A^2 X = w . [y; ydot; X_I]``, ``w = Tinv^T (C A^2)^T``
        (``rho <= 2``; ``yddot`` is ``y^(rho)``).

        Parameters
        ----------
        yddot : Any
            The output's ``rho``-th derivative.
        y : Any
            Outputs.
        ydot : Any
            Their rates.
        XI : Any
            Internal states.
        """
        w = (self.Tinv.T @ self.CA2).astype(np.result_type(XI, np.float64))
        return (np.asarray(yddot) - w[0] * np.asarray(y) - w[1] * np.asarray(ydot) - XI @ w[2:]) / self.CAB


def normal_form(model: Any) -> NormalForm:
    """The :class:`NormalForm` of a link model or a SISO system.

    The :class:`NormalForm` of a loaded link model, of any SISO system :func:`inversion.invert`
    accepts (:func:`~inversion.lti.linear_system.as_linear_system`), or the form itself.

    Parameters
    ----------
    model : Any
        A loaded link model, a SISO system or a normal form.

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

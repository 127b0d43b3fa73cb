"""The numeric SFLM model: matrices, zeros and frequencies for one geometry.

A :class:`Model` is what the later layers consume. Its arrays are evaluated once, at
construction, from the model functions (the compiled ones of :mod:`modelgen.codegen`)
at the geometry's parameter vector.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import ModelError
from .geometry import Geometry
from .interface import CompiledFunctions
from .modes import ModalConstants, ModeShapes
from .paper import PaperCase
from .zeros import classify_internal_dynamics, is_unstable, transmission_zeros

__all__ = ["Model", "natural_frequencies", "sort_zeros", "MATRIX_NAMES"]

FloatArray = NDArray[np.float64]

#: Matrices a model carries, in the order the CLI prints them.
MATRIX_NAMES: tuple[str, ...] = ("M", "K", "C", "D", "H", "A", "B", "C_out", "AI", "BI", "T", "Tinv", "CA2")

#: A link's natural frequencies beyond this (Hz) are refused: rigid to any controller, not computable beside its rigid body.
MAX_FREQUENCY_HZ = 1e7
#: The inertia about the hub (hub, payload and link) beyond this multiple of the link's own is refused (a 1e12 kg payload
#: on a 0.5 m aluminium link, 1e13 x: CAB was zero to rounding).
MAX_INERTIA_RATIO = 1e9
#: Largest relative disagreement accepted between eig(A_I) and the Rosenbrock zeros.
_ZERO_CHECK_TOL = 1e-6
#: Margin over ``eps kappa ||A_I||`` allowed between eig(A_I) and the pencil for an ill-conditioned zero.
_ZERO_CHECK_MARGIN = 1e3
#: Below this fraction of the rigid link's ``L/J`` (both independent of the states' scales),
#: ``CAB`` draws a warning; it still loads. paper-exp: 8.6e-4 with 2 modes, 1.3e-5 with 12.
_CAB_WARNING = 1e-4


def natural_frequencies(K: FloatArray, M: FloatArray) -> FloatArray:
    """Undamped flexible natural frequencies (rad/s), ascending.

    The rigid-body mode (the hub rotation, ``omega = 0``) is dropped: of the ``n + 1``
    generalised eigenvalues of ``(K, M)`` the ``n`` largest are returned.

    Parameters
    ----------
    K : FloatArray
        Stiffness matrix.
    M : FloatArray
        Mass matrix.
    """
    import scipy.linalg as sla  # lazy: keeps the import of the package fast

    w2 = sla.eigh(K, M, eigvals_only=True)
    w2 = np.sort(w2)[1:]
    return np.sqrt(np.clip(w2, 0.0, None))


def sort_zeros(zeros: ArrayLike) -> NDArray[np.complex128]:
    """Zeros sorted by magnitude, then real and imaginary part.

    Zeros sorted by magnitude, then real part (descending), then imaginary part (descending).

    Parameters
    ----------
    zeros : ArrayLike
        Complex zeros.
    """
    z = np.asarray(zeros, dtype=complex)
    mag = np.round(np.abs(z), 9)
    order = np.lexsort((-np.round(z.imag, 9), -np.round(z.real, 9), mag))
    return z[order]


@dataclass(frozen=True, eq=False)
class Model:
    """A linear and nonlinear SFLM model for one geometry and mode set.

    Attributes
    ----------
    geometry : Geometry
        The link; ``geometry.modes`` and ``geometry.mode_shapes`` describe the model.
    shapes : ModeShapes
        The assumed modes.
    constants : ModalConstants
        Their modal integrals.
    parameter_names : tuple of str
        Names of the entries of ``parameters``.
    parameters : ndarray
        The parameter vector ``p`` every model function takes.
    M, K, C : ndarray, shape (n+1, n+1)
        Mass, stiffness and damping matrices of (P8).
    D, H : ndarray, shape (n+1,)
        Output row and input column.
    A, B, C_out : ndarray
        State space (P9, P10).
    CAB : float
        ``C_out A B`` (P11), nonzero: the relative degree is 2.
    CA2 : ndarray, shape (2(n+1),)
        ``C_out A^2``.
    AI, BI : ndarray
        Internal dynamics (P14).
    T, Tinv : ndarray
        ``[y; ydot; delta; deltadot] = T X`` and its inverse.
    zeros : ndarray of complex
        Eigenvalues of ``AI``: the zeros of ``Y(s)/tau(s)``.
    natural_frequencies_hz : ndarray
        Flexible natural frequencies (Hz), ascending.
    internal_dynamics : str
        ``"hyperbolic"``, ``"non-hyperbolic"`` or ``"near-non-hyperbolic"``.
    n_unstable : int
        Zeros with ``Re z >= 0`` (purely imaginary ones count as unstable).
    functions : CompiledFunctions or None
        The model functions behind the arrays: compiled C loaded by :func:`casadi.external`,
        or in-process :class:`casadi.Function` objects without a compiler (see
        :mod:`modelgen.codegen`; the contract is :class:`modelgen.interface.CompiledFunctions`).
    case : PaperCase or None
        The paper's case when the model is a shipped preset as shipped
        (:func:`modelgen.paper.preset_case`), decided once when it is loaded.
    """

    geometry: Geometry
    shapes: ModeShapes
    constants: ModalConstants
    parameter_names: tuple[str, ...]
    parameters: FloatArray
    M: FloatArray
    K: FloatArray
    C: FloatArray
    D: FloatArray
    H: FloatArray
    A: FloatArray
    B: FloatArray
    C_out: FloatArray
    CAB: float
    CA2: FloatArray
    AI: FloatArray
    BI: FloatArray
    T: FloatArray
    Tinv: FloatArray
    zeros: NDArray[np.complex128] = field(init=False)
    natural_frequencies_hz: FloatArray = field(init=False)
    internal_dynamics: str = field(init=False)
    n_unstable: int = field(init=False)
    functions: CompiledFunctions | None = None
    case: PaperCase | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        self._check_scales()
        self._check_cab()
        import scipy.linalg as sla  # lazy: keeps `import modelgen` fast

        eigenvalues, left, right = sla.eig(self.AI, left=True, right=True)
        zeros = sort_zeros(eigenvalues)
        # the cross-check: the Rosenbrock pencil of the balanced system (balancing makes it
        # independent of the states' scales, e.g. of the mode shapes' normalisation)
        A, (scale, _) = sla.matrix_balance(self.A, permute=False, separate=True)
        check = transmission_zeros(A, np.asarray(self.B).reshape(-1) / scale, np.asarray(self.C_out).reshape(-1) * scale)
        if check.size != zeros.size:
            raise ModelError(
                f"zeros: eig(A_I) gives {zeros.size}, the Rosenbrock pencil {check.size}; "
                f"eig(A_I) = {zeros}, pencil = {check}"
            )
        from .zeros import assignment  # a matching: scipy.optimize (0.14 s to import) not needed on every load

        # each zero to the accuracy its conditioning allows: eps kappa_i ||A_I|| (kappa_i the
        # eigenvalue's condition number), with a margin for the pencil's own rounding
        kappa = np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0) / np.maximum(
            np.abs(np.sum(left.conj() * right, axis=0)), 1e-300)
        cost = np.abs(eigenvalues[:, None] - check[None, :])
        rows, cols = assignment(cost)
        size = np.maximum(np.abs(eigenvalues[rows]), 1.0)
        rel = cost[rows, cols] / size
        allowed = np.maximum(_ZERO_CHECK_TOL, _ZERO_CHECK_MARGIN * np.finfo(float).eps * kappa[rows]
                             * float(np.linalg.norm(self.AI, 2)) / size)
        if np.any(rel > allowed):
            worst = int(np.argmax(rel / allowed))
            raise ModelError(
                f"zeros: eig(A_I) and the Rosenbrock pencil disagree by {rel[worst]:.2e} (relative) at "
                f"{eigenvalues[rows][worst]:.6g}, beyond its conditioning ({allowed[worst]:.2e}); "
                f"eig(A_I) = {zeros}, pencil = {check}"
            )
        object.__setattr__(self, "zeros", zeros)
        object.__setattr__(self, "natural_frequencies_hz", natural_frequencies(self.K, self.M) / (2 * np.pi))
        object.__setattr__(self, "internal_dynamics", classify_internal_dynamics(zeros))
        object.__setattr__(self, "n_unstable", int(np.count_nonzero(is_unstable(zeros))))

    def _check_scales(self) -> None:
        """Refuse, in the geometry's words, a link whose model double precision cannot hold: natural frequencies beyond
        :data:`MAX_FREQUENCY_HZ` (a link this stiff, or this short, is rigid to any controller; its zeros came out of
        rounding), or a hub and payload whose inertia dwarfs the link's own by more than :data:`MAX_INERTIA_RATIO` (its
        flexibility is lost in rounding beside them)."""
        g = self.geometry
        hz = natural_frequencies(self.K, self.M) / (2 * np.pi)
        values = (f"EI = {g.flexural_rigidity:.4g} N m^2, linear density {g.linear_density:.4g} kg/m, length {g.length:.4g} m, "
                  f"hub inertia {g.hub_inertia:.4g} kg m^2, payload {g.payload_mass:.4g} kg and {g.payload_inertia:.4g} kg m^2")
        if hz.size and not (np.all(np.isfinite(hz)) and float(hz.max()) <= MAX_FREQUENCY_HZ):
            raise ModelError(f"the link's natural frequencies reach {float(np.nanmax(hz)):.3g} Hz ({values}): beyond "
                             f"{MAX_FREQUENCY_HZ:.0e} Hz a link is rigid to any controller and its model is not computable in "
                             "double precision; check the geometry's values and units (SI: Pa, kg/m^3, m, kg)")
        own = g.linear_density * g.length ** 3 / 3.0  # the link's own inertia about the hub
        ratio = float(self.M[0, 0]) / own if own > 0 else math.inf
        if not ratio <= MAX_INERTIA_RATIO:
            raise ModelError(f"the inertia about the hub, {float(self.M[0, 0]):.4g} kg m^2, is {ratio:.3g} x the link's own "
                             f"({own:.4g}) ({values}): beyond {MAX_INERTIA_RATIO:.0e} x the link's flexibility is lost in "
                             "rounding beside the hub and payload; check the payload's and the hub's values and units")

    def _check_cab(self) -> None:
        """``CAB`` (P11): refused only when it is zero to rounding; a small one is a truncation trend, with a warning.

        The continuum's tip does not feel a hub torque instantly (no finite relative degree);
        an assumed-mode model's ``CAB`` shrinks, and changes sign, as modes are added. That is
        the model's truncation, not an error: it loads, and the warning says so.
        """
        terms = float((np.abs(np.asarray(self.C_out).reshape(1, -1)) @ np.abs(self.A) @ np.abs(np.asarray(self.B).reshape(-1, 1)))[0, 0])
        if not np.isfinite(self.CAB) or abs(self.CAB) <= 1e3 * np.finfo(float).eps * max(terms, 1e-300):
            raise ModelError(f"CAB = {self.CAB!r} is zero to rounding (its terms sum to {terms:.3g}): the relative degree "
                             "is not 2 for this geometry")
        rigid = self.geometry.length / float(self.M[0, 0])  # a rigid link's C A B: L / J
        if abs(self.CAB) < _CAB_WARNING * rigid:
            from .errors import warn

            warn(f"CAB = {self.CAB:.3g} is {abs(self.CAB) / rigid:.2g} of the rigid link's L/J = {rigid:.3g} with "
                 f"{self.M.shape[0] - 1} modes: the tip's direct response to a hub torque fades as modes are added (the "
                 "continuum's tip does not respond instantly, its relative degree is not finite); the model loads, its "
                 "highest zeros and the torque's sensitivity to them are truncation effects")

    @property
    def n(self) -> int:
        """Number of assumed modes."""
        return int(self.M.shape[0] - 1)

    @property
    def name(self) -> str:
        """Geometry name."""
        return self.geometry.name

    @property
    def mode_family(self) -> str:
        """Mode-shape family."""
        return self.shapes.family

    @property
    def output_at(self) -> float:
        """Where the output ``y = x theta + w(x)`` is measured (m; the tip, ``L``, unless loaded with ``output_at``)."""
        names = self.parameter_names
        return float(self.parameters[names.index("x_out")]) if "x_out" in names else float(self.geometry.length)

    @property
    def compiled_functions(self) -> CompiledFunctions:
        """:attr:`functions`, or :class:`ModelError` for a model built from matrices alone."""
        if self.functions is None:
            raise ModelError("this model has no generated functions (built from matrices alone); load it with modelgen.load")
        return self.functions

    @property
    def state_names(self) -> list[str]:
        """Names of the state ``X = [theta; delta_1..n; thetadot; deltadot_1..n]`` (P9)."""
        n = self.n
        return ["theta", *(f"delta{i}" for i in range(1, n + 1)), "thetadot", *(f"deltadot{i}" for i in range(1, n + 1))]

    def to_control(self) -> Any:
        """The linear model (P9) as a python-control ``StateSpace``.

        States are named after :attr:`state_names`; its zeros are :attr:`zeros`. Needs the
        optional dependency python-control (``pip install "sflm[control]"``).

        Returns
        -------
        control.StateSpace
            ``(A, B, C_out, 0)`` with input ``tau`` and output ``y``: :func:`control.zeros`
            and :func:`control.poles` of it are :attr:`zeros` and the model's poles.

        Raises
        ------
        ModelError
            When python-control is not installed.
        """
        try:
            import control
        except ImportError:
            raise ModelError('Model.to_control needs python-control: pip install "sflm[control]" (or "control>=0.10")') from None
        return control.ss(np.asarray(self.A, dtype=float), np.asarray(self.B, dtype=float).reshape(-1, 1),
                          np.asarray(self.C_out, dtype=float).reshape(1, -1), np.zeros((1, 1)),
                          inputs=["tau"], outputs=["y"], states=self.state_names, name=self.name)

    def summary(self) -> dict[str, Any]:
        """Everything ``sflm info --json`` prints, as JSON values."""
        def listify(a: Any) -> Any:
            return np.asarray(a, dtype=float).tolist()

        out: dict[str, Any] = {
            "name": self.name,
            "source": self.geometry.source,
            "modes": self.n,
            "mode_shapes": self.mode_family,
            "output_at": self.output_at,
            "geometry": self.geometry.as_dict(),
            "beta_L": listify(self.shapes.betas),
            "natural_frequencies_hz": listify(self.natural_frequencies_hz),
            "zeros": [[float(z.real), float(z.imag)] for z in self.zeros],
            "internal_dynamics": self.internal_dynamics,
            "n_unstable": self.n_unstable,
            "CAB": float(self.CAB),
            "parameters": {"names": list(self.parameter_names), "values": listify(self.parameters)},
        }
        for name in MATRIX_NAMES:
            out[name] = listify(getattr(self, name))
        return out

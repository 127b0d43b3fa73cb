"""Any SISO linear system as a client of the inversion: conversion and the numerical normal form.

A control engineer hands :func:`inversion.invert` a python-control ``StateSpace`` or
``TransferFunction``, a ``scipy.signal`` LTI system, or a tuple ``(A, B, C)`` (or
``(A, B, C, D)`` with ``D = 0``). :func:`as_linear_system` turns any of them into a
:class:`LinearSystem`: continuous time, one input, one output, strictly proper, a nonzero
transfer function.

**Relative degree.** ``rho`` is the first ``k >= 1`` with a Markov parameter
``C A^(k-1) B`` above the rounding of its computation (``1e3 N eps |C| |A|^(k-1) |B|``); the
count of finite transmission zeros (:func:`modelgen.zeros.transmission_zeros`) must agree,
``N - rho``.

**Normal form** (docs/method.md, section 5e). With ``xi = [y, ydot, ..., y^(rho-1)] = R X``
(``R`` the rows ``C A^k``, ``k < rho``) the internal coordinates are ``X_I = N X`` with::

    X_Idot = A_I X_I + B_I y^(rho)

-- driven by ``y^(rho)`` alone, as the link's ``[delta; deltadot]`` in Eq. (14), so that the
segment problem of :mod:`inversion.family.ssef` applies unchanged. ``N`` is found in two steps,
both well conditioned:

1. ``N0``: an orthonormal basis of the rows that annihilate ``B`` and are orthogonal to
   ``C, ..., C A^(rho-2)``; then ``eta = N0 X`` obeys ``etadot = Q eta + P xi`` (no ``u``);
2. ``X_I = eta + M xi`` removes the ``xi`` coupling when ``Q M - M S = P`` (``S`` the shift
   of the integrator chain): a Sylvester equation, solvable exactly when no zero sits at
   ``s = 0`` (``S`` is nilpotent). Then ``A_I = Q``, ``B_I = M e_rho``.

``y^(rho) = C A^rho X + C A^(rho-1) B u`` gives the input (Eq. (12) generalised)::

    u = (y^(rho) - C A^rho X) / (C A^(rho-1) B).

The realisation is first balanced (:func:`scipy.linalg.matrix_balance`, a diagonal
similarity) so that a companion form with coefficients spread over many decades does not
lose digits; states are reported in the caller's realisation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from modelgen.zeros import transmission_zeros

from ..errors import InversionError, SettingsError

__all__ = ["LinearSystem", "NormalCoordinates", "as_linear_system", "normal_coordinates", "relative_degree"]

FloatArray = NDArray[np.float64]

#: What :func:`as_linear_system` accepts (for messages).
ACCEPTED = ("a python-control StateSpace or TransferFunction, a scipy.signal LTI system (lti, StateSpace, "
            "TransferFunction, ZerosPolesGain) or a tuple (A, B, C) of a continuous-time SISO system")
#: Smallest ``|zero| / |A|`` accepted: a zero closer to ``s = 0`` makes the Sylvester
#: equation of the normal form singular (the output would carry a pure derivative).
_ORIGIN_TOL = 1e-9
#: Largest accepted relative disagreement between ``eig(A_I)`` and the transmission zeros
#: (each zero within this fraction of the largest, after matching).
_ZERO_TOL = 1e-6


@dataclass(frozen=True)
class NormalCoordinates:
    """The normal form of a SISO system of relative degree ``rho``.

    Attributes
    ----------
    rho : int
        Relative degree.
    T, Tinv : ndarray, shape (N, N)
        ``[xi; X_I] = T X`` and its inverse.
    AI, BI : ndarray
        Internal dynamics ``X_Idot = A_I X_I + B_I y^(rho)``.
    CArho : ndarray, shape (N,)
        The row ``C A^rho``.
    gain : float
        ``C A^(rho-1) B`` (nonzero): the high-frequency gain.
    residual : float
        ``|T (A - B C A^rho / gain) - blockdiag(S, A_I) T| / (|A| |T|)``: how well the
        coordinates bring the inverse system to normal form.
    """

    rho: int
    T: FloatArray
    Tinv: FloatArray
    AI: FloatArray
    BI: FloatArray
    CArho: FloatArray
    gain: float
    residual: float


def relative_degree(A: FloatArray, B: FloatArray, C: FloatArray) -> int:
    """The first ``k`` whose Markov parameter is above its rounding.

    The first ``k >= 1`` whose Markov parameter ``C A^(k-1) B`` is above its rounding.

    The test is made on the scaled system ``(A / |A|, B / |B|, C / |C|)`` -- a change of time
    unit and of the input's and output's units, which leaves every zero Markov parameter zero --
    and each product's rounding is bounded by its elementwise magnitudes (``N eps |C| |A|^(k-1)
    |B|``, the forward error of the products), not by norms: a high order or a large gain
    (``(2 - s)/(s + 1)^30``, ``1e300/(s + 1)^3``) neither overflows nor hides its first nonzero
    parameter under a norm bound that grows as ``|A|^k``.

    Parameters
    ----------
    A : FloatArray
        State matrix.
    B : FloatArray
        Input matrix.
    C : FloatArray
        Output row.

    Raises
    ------
    SettingsError
        When every Markov parameter up to ``N`` vanishes (the transfer function is zero).
    """
    N = A.shape[0]
    eps = np.finfo(float).eps

    def unit(x: FloatArray) -> FloatArray:
        big = float(np.abs(x).max(initial=0.0))
        return x / big if big > 0 else x

    An, Bn, Cn = unit(A), unit(B), unit(C)
    absA, absB = np.abs(An), np.abs(Bn)
    row, magnitude = Cn.copy(), np.abs(Cn)
    for k in range(1, N + 1):
        markov = float(row @ Bn)
        rounding = 1e3 * N * eps * float(magnitude @ absB)
        if abs(markov) > rounding and markov != 0.0:
            return k
        row, magnitude = row @ An, magnitude @ absA
    raise SettingsError("system", "a zero transfer function", "a system whose output depends on its input "
                        "(every Markov parameter C A^k B, k < N, vanishes)")


def normal_coordinates(A: FloatArray, B: FloatArray, C: FloatArray, rho: int | None = None) -> NormalCoordinates:
    """The normal form of ``(A, B, C)``, any relative degree.

    Parameters
    ----------
    A : FloatArray
        State matrix.
    B : FloatArray
        Input matrix.
    C : FloatArray
        Output row.
    rho : int | None, optional
        The relative degree (``None``: computed).

    Raises
    ------
    SettingsError
        For a zero at (or within ``1e-9 |A|`` of) ``s = 0``.
    """
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    N = A.shape[0]
    rho = relative_degree(A, B, C) if rho is None else rho
    rows = [C]
    for _ in range(rho):
        rows.append(rows[-1] @ A)
    R = np.vstack(rows[:rho])  # y .. y^(rho-1)
    CArho = rows[rho]
    gain = float(rows[rho - 1] @ B)
    m = N - rho
    if m == 0:
        Tinv = np.asarray(np.linalg.inv(R), dtype=float)
        return NormalCoordinates(rho, R, Tinv, np.zeros((0, 0)), np.zeros(0), CArho, gain, 0.0)
    # 1. N0: orthonormal rows annihilating B and orthogonal to C .. C A^(rho-2)
    constraints = np.vstack([B[None, :], R[: rho - 1]]) if rho > 1 else B[None, :]
    N0 = sla.null_space(constraints).T  # (m, N)
    if N0.shape[0] != m:
        raise InversionError(f"the system is degenerate to working accuracy: of its {N} states, {N0.shape[0]} (not {m}) are "
                             f"free of the input and of the output's first {rho - 1} derivatives -- a pole cancelled by a zero "
                             "to rounding, or coefficients spanning more than a double's precision: cancel the common factors, "
                             "or rescale time or the output")
    T0 = np.vstack([R, N0])
    T0inv = np.linalg.inv(T0)
    F = N0 @ A @ T0inv  # etadot = F [xi; eta] = P xi + Q eta
    P, Q = F[:, :rho], F[:, rho:]
    zeros = np.linalg.eigvals(Q)
    scale = max(float(np.linalg.norm(A, 2)), np.finfo(float).tiny)
    if np.min(np.abs(zeros)) <= _ORIGIN_TOL * scale:
        closest = zeros[np.argmin(np.abs(zeros))]
        raise SettingsError("system", f"a zero at s = {closest:.3g}", "no zero at s = 0: the normal form drives the internal "
                            "dynamics by y^(rho), which a zero at the origin (a pure derivative in the numerator) does not allow")
    S = np.eye(rho, k=1)  # xidot = S xi + e_rho y^(rho)
    M = sla.solve_sylvester(Q, -S, P)  # Q M - M S = P
    T = np.vstack([R, N0 + M @ R])
    Tinv = T0inv @ np.block([[np.eye(rho), np.zeros((rho, m))], [-M, np.eye(m)]])
    AI, BI = np.asarray(Q, dtype=float), np.asarray(M[:, rho - 1], dtype=float)
    Abar = A - np.outer(B, CArho) / gain
    block = np.zeros((N, N))
    block[:rho, :rho] = S
    block[rho:, rho:] = AI
    residual = float(np.linalg.norm(T @ Abar - block @ T) / (scale * np.linalg.norm(T)))
    return NormalCoordinates(rho, T, Tinv, AI, BI, CArho, gain, residual)


@dataclass(frozen=True, eq=False)
class LinearSystem:
    """A continuous-time SISO linear system the inversion accepts.

    Attributes
    ----------
    name : str
        For messages and the summary.
    A, B, C : ndarray
        The caller's realisation ``Xdot = A X + B u``, ``y = C X``.
    scale : ndarray, shape (N,)
        The balancing similarity: ``X = scale * X_b`` with ``X_b`` the state the inversion
        works in.
    coordinates : NormalCoordinates
        The normal form of the balanced realisation.
    zeros : ndarray of complex
        The transmission zeros (the eigenvalues of ``A_I``, checked against the pencil).
    balanced : (ndarray, ndarray, ndarray)
        ``(A_b, B_b, C_b)``: the realisation the inversion works in (``X = scale * X_b``).
    input_name, output_name : str
    """

    name: str
    A: FloatArray
    B: FloatArray
    C: FloatArray
    scale: FloatArray
    coordinates: NormalCoordinates
    zeros: NDArray[np.complex128]
    balanced: tuple[FloatArray, FloatArray, FloatArray] = field(repr=False)
    input_name: str = "u"
    output_name: str = "y"

    @property
    def relative_degree(self) -> int:
        """``rho``."""
        return self.coordinates.rho

    @property
    def transformation(self) -> FloatArray:
        """``T`` with ``[y, .., y^(rho-1), X_I] = T X`` in the caller's coordinates."""
        return self.coordinates.T / self.scale[None, :]

    def report(self) -> dict[str, Any]:
        """What the summary records about the system (``system`` key)."""
        c = self.coordinates
        return {
            "name": self.name,
            "states": int(self.A.shape[0]),
            "relative_degree": c.rho,
            "high_frequency_gain": c.gain,  # C A^(rho-1) B: the same in every realisation
            "normal_form_residual": c.residual,
            "transformation": self.transformation.tolist(),
            "input": self.input_name,
            "output": self.output_name,
        }


def _matrices(system: Any) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, str, str]:
    """``A, B, C, D`` and the signal names of any accepted description."""
    names = ("u", "y")
    module = type(system).__module__.split(".")[0]
    if isinstance(system, tuple) and len(system) in (3, 4):
        parts = system
    elif module == "control":
        import control  # the caller has it: it handed us one of its objects

        if getattr(system, "dt", 0) not in (0, None):
            raise SettingsError("system", f"a discrete-time system (dt = {system.dt})", ACCEPTED)
        if system.ninputs != 1 or system.noutputs != 1:
            raise SettingsError("system", f"{system.ninputs} inputs, {system.noutputs} outputs", ACCEPTED)
        ss = control.ss(system) if not isinstance(system, control.StateSpace) else system
        names = (str(ss.input_labels[0]), str(ss.output_labels[0]))
        parts = (ss.A, ss.B, ss.C, ss.D)
    elif module == "scipy":
        if getattr(system, "dt", None) is not None:
            raise SettingsError("system", f"a discrete-time system (dt = {system.dt})", ACCEPTED)
        if not hasattr(system, "to_ss"):
            raise SettingsError("system", type(system).__name__, ACCEPTED)
        ss = system.to_ss()
        parts = (ss.A, ss.B, ss.C, ss.D)
    else:
        raise SettingsError("system", type(system).__name__, ACCEPTED)
    try:
        A = np.atleast_2d(np.asarray(parts[0], dtype=float))
        B = np.asarray(parts[1], dtype=float)
        C = np.asarray(parts[2], dtype=float)
        D = np.asarray(parts[3], dtype=float) if len(parts) == 4 else np.zeros((1, 1))
    except (TypeError, ValueError) as exc:
        raise SettingsError("system", "matrices that are not numbers", f"{ACCEPTED} ({exc})") from None
    N = A.shape[0]
    if A.ndim != 2 or A.shape != (N, N) or N == 0:
        raise SettingsError("system", f"A of shape {A.shape}", "a square, non-empty A")
    if B.size != N or (B.ndim == 2 and B.shape[1] != 1):
        raise SettingsError("system", f"B of shape {B.shape} for {N} states", f"one input: B of shape ({N},) or ({N}, 1)")
    if C.size != N or (C.ndim == 2 and C.shape[0] != 1):
        raise SettingsError("system", f"C of shape {C.shape} for {N} states", f"one output: C of shape ({N},) or (1, {N})")
    if D.size != 1:
        raise SettingsError("system", f"D of shape {D.shape}", "a SISO system (D of one element)")
    for label, value in (("A", A), ("B", B), ("C", C), ("D", D)):
        if not np.all(np.isfinite(value)):
            raise SettingsError("system", f"{label} with non-finite entries", "finite matrices")
    if float(D.reshape(-1)[0]) != 0.0:
        raise SettingsError("system", f"D = {float(D.reshape(-1)[0]):.6g}", "a strictly proper system (D = 0): with a direct "
                            "feedthrough the output has no relative degree to redefine")
    return A, B.reshape(-1), C.reshape(-1), D, names[0], names[1]


def as_linear_system(system: Any, name: str | None = None) -> LinearSystem:
    """Any accepted SISO description as a :class:`LinearSystem`.

    Parameters
    ----------
    system : control.StateSpace, control.TransferFunction, scipy.signal.lti or tuple
        The plant: ``(A, B, C)`` or ``(A, B, C, D)`` with ``D = 0``.
    name : str, optional
        Its name in messages and the summary (default: python-control's name, else
        ``"system"``).

    Raises
    ------
    SettingsError
        For anything that is not a continuous-time, strictly proper SISO system with a
        nonzero transfer function and no zero at ``s = 0``, naming what is wrong.
    InversionError
        When the normal form cannot be trusted: its zeros disagree with the transmission
        zeros of the pencil, or its residual exceeds ``1e-8`` (figures in the message).

    Examples
    --------
    >>> import numpy as np
    >>> from inversion.lti.linear_system import as_linear_system
    >>> s = as_linear_system((np.array([[0.0, 1.0], [-2.0, -3.0]]), np.array([0.0, 1.0]), np.array([1.0, -1.0])))
    >>> s.relative_degree, np.round(s.zeros.real, 12).tolist()
    (1, [1.0])
    """
    if isinstance(system, LinearSystem):
        return system
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    A, B, C, _, input_name, output_name = _matrices(system)
    label = name or (str(getattr(system, "name", "")) if type(system).__module__.startswith("control") else "") or "system"
    Ab, (scale, _) = sla.matrix_balance(A, permute=False, separate=True)
    scale = np.asarray(scale, dtype=float)
    Bb, Cb = B / scale, C * scale
    coordinates = normal_coordinates(Ab, Bb, Cb)
    if not coordinates.residual <= 1e-8:
        raise InversionError(f"the normal form of {label} is not accurate: residual {coordinates.residual:.3e} (> 1e-8)")
    zeros = np.asarray(np.sort_complex(np.linalg.eigvals(coordinates.AI)) if coordinates.AI.size else np.zeros(0), dtype=complex)
    pencil = transmission_zeros(Ab, Bb, Cb)
    if pencil.size != zeros.size:
        raise InversionError(f"{label}: relative degree {coordinates.rho} leaves {zeros.size} zeros, the pencil has {pencil.size} "
                             f"finite ones ({pencil}); the relative degree is ambiguous to working accuracy")
    if zeros.size:
        size = max(float(np.abs(zeros).max()), 1.0)
        gaps = [float(np.abs(pencil - z).min()) for z in zeros]
        if max(gaps) > _ZERO_TOL * size:
            raise InversionError(f"{label}: the normal form's zeros {zeros} and the pencil's {pencil} differ by up to "
                                 f"{max(gaps):.3e} (> {_ZERO_TOL:g} of the largest)")
    return LinearSystem(name=label, A=A, B=B, C=C, scale=scale, coordinates=coordinates, zeros=zeros, balanced=(Ab, Bb, Cb),
                        input_name=input_name, output_name=output_name)


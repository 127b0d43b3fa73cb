"""Assumed mode shapes of the link and their modal constants (Eq. (3)).

Three families (docs/method.md section 1, "Mode shapes"):

``clamped-mass``
    Eigenfunctions of a link clamped at the hub and carrying the tip payload
    ``(m_t, I_t)``: ``phi(x) = cosh bx - cos bx - s (sinh bx - sin bx)`` with ``b`` a root of
    the frequency equation of the tip boundary conditions
    ``EI w''(L) = omega^2 I_t w'(L)``, ``EI w'''(L) = -omega^2 m_t w(L)``.
``clamped-free``
    The same with ``m_t = I_t = 0`` (``bL = 1.8751, 4.6941, 7.8548, ...``).
``polynomial``
    The span of ``(x/L)^2 .. (x/L)^(n+1)``: exact to integrate, a cross-check of the
    other two. An assumed-mode (Ritz) model depends only on the span of its shapes, so
    the monomials are represented in the equivalent, well-conditioned basis
    ``phi_j = (x/L)^2 P_{j-1}(2x/L - 1)`` (``P_k`` Legendre polynomials): the monomial
    mass matrix is Hilbert-like and its condition number passes 1e12 at ``n = 8``.

The transcendental shapes are evaluated in a cancellation-free form: with
``C1 (cosh - cos) + C2 (sinh - sin)`` written as
``[(C1 + C2) e^{bx} + (C1 - C2) e^{-bx}]/2 - C1 cos bx - C2 sin bx`` and ``C1 + C2``
obtained from a formula in which the growing exponentials cancel analytically. The
naive form loses about ``bL / ln 10`` digits and is wrong beyond mode 4 or so.

Modal integrals are computed by Gauss-Legendre quadrature of these shapes rather than
in closed form: the shapes are entire functions, so the quadrature converges
geometrically (the node count grows with ``bL``; doubling it changes nothing at
1e-14), it integrates the polynomial family exactly, and it keeps SymPy off the numeric
path. The closed-form integrals of the tip-mass family are long and suffer the same
cancellation as the naive shapes.
"""

from __future__ import annotations

import contextlib
import contextvars
import functools
import math
from dataclasses import dataclass, field
from typing import Any, Iterator

import numpy as np
from numpy.polynomial.legendre import leggauss as _leggauss, legder, legmul, legval, poly2leg
from numpy.typing import ArrayLike, NDArray

from .errors import GeometryError, ModelError
from .geometry import MODE_FAMILIES, Geometry

__all__ = [
    "ModeShapes",
    "ModalConstants",
    "frequency_determinant",
    "frequency_roots",
    "mode_shapes",
    "modal_constants",
]

FloatArray = NDArray[np.float64]

#: Step of the bracketing grid in ``bL``. Over payload ratios mu in [0, 1e5] and kappa in
#: [0, 1e4] the smallest gap between consecutive roots (first 20) is 0.079 (the first two
#: roots of an extreme payload), so a step of 0.01 cannot step over a pair of roots.
_GRID_STEP = 0.01


@functools.lru_cache(maxsize=64)
def leggauss(nodes: int) -> tuple[FloatArray, FloatArray]:
    """Gauss-Legendre nodes and weights, computed once per count (an eigenproblem each: a calibration asks thousands of
    times). The arrays are shared: read them, never write them."""
    xg, wg = _leggauss(nodes)
    xg.flags.writeable = False
    wg.flags.writeable = False
    return xg, wg


def _scaled_rows(beta: FloatArray | float, mu: float, kappa: float) -> tuple[FloatArray, ...]:
    """Boundary-condition rows of the tip, each scaled by ``exp(-bL)``.

    Returns ``a1, a2`` (moment condition) and ``b1, b2`` (shear condition), the
    coefficients of ``C1`` and ``C2`` in ``phi = C1 (cosh - cos) + C2 (sinh - sin)``,
    multiplied by ``exp(-bL)`` so that no overflow occurs for large ``bL``.
    """
    b = np.asarray(beta, dtype=float)
    e = np.exp(-b)
    ch = 0.5 * (1.0 + e * e)  # cosh(b) e^-b
    sh = 0.5 * (1.0 - e * e)  # sinh(b) e^-b
    c = np.cos(b) * e
    s = np.sin(b) * e
    k3 = kappa * b**3
    mb = mu * b
    a1 = (ch + c) - k3 * (sh + s)
    a2 = (sh + s) - k3 * (ch - c)
    b1 = (sh - s) + mb * (ch - c)
    b2 = (ch + c) + mb * (sh - s)
    return a1, a2, b1, b2


def frequency_determinant(beta: ArrayLike, mass_ratio: float, inertia_ratio: float) -> FloatArray:
    """Scaled frequency determinant of the link with tip payload.

    With ``K = kappa b^3``, ``m = mu b`` (``b = bL``) the 2x2 determinant of the tip
    conditions is ``2 [1 + ch c + m (c sh - s ch) - K (c sh + s ch) - K m (ch c - 1)]``
    (``ch = cosh b``, ``c = cos b``, ...). It is evaluated multiplied by ``exp(-b)``, in
    which form its growing exponentials have cancelled analytically, and divided by
    ``(1 + K)(1 + m)``.

    Parameters
    ----------
    beta : array_like
        Values of ``bL``.
    mass_ratio : float
        ``mu = m_t / (rho L)``.
    inertia_ratio : float
        ``kappa = I_t / (rho L^3)``.

    Returns
    -------
    ndarray
        Bounded, oscillating, with the same simple roots as the determinant.
    """
    b = np.asarray(beta, dtype=float)
    e = np.exp(-b)
    ch = 0.5 * (1.0 + e * e)  # cosh(b) e^-b
    sh = 0.5 * (1.0 - e * e)  # sinh(b) e^-b
    c = np.cos(b)
    s = np.sin(b)
    k3 = inertia_ratio * b**3
    mb = mass_ratio * b
    det = e + ch * c + mb * (c * sh - s * ch) - k3 * (c * sh + s * ch) - k3 * mb * (ch * c - e)
    return np.asarray(det / ((1.0 + k3) * (1.0 + mb)))


def frequency_roots(n: int, mass_ratio: float = 0.0, inertia_ratio: float = 0.0) -> FloatArray:
    """First ``n`` roots ``b_j L`` of the frequency equation.

    First ``n`` roots ``b_j L`` of the clamped-with-tip-payload frequency equation.

    Parameters
    ----------
    n : int
        Number of roots wanted (>= 1).
    mass_ratio : float
        ``m_t / (rho L)`` (0 for a clamped-free link).
    inertia_ratio : float
        ``I_t / (rho L^3)``.

    Returns
    -------
    ndarray
        ``n`` increasing roots; ``omega_j = (b_j L)^2 sqrt(EI / (rho L^4))`` are the
        natural frequencies of the link clamped at the hub.

    Raises
    ------
    ModelError
        If fewer than ``n`` roots are bracketed (never expected; reported with figures).

    Examples
    --------
    >>> np.round(frequency_roots(3), 5)
    array([1.8751 , 4.69409, 7.85476])
    """
    if n < 1:
        raise GeometryError("modes", n, "an integer >= 1")
    n, mass_ratio, inertia_ratio = int(n), float(mass_ratio), float(inertia_ratio)
    if not _KEEP_ROOTS.get():  # a trial link's (roots_not_kept): remembered in this process, not in the cache
        return np.array(_found(n, mass_ratio, inertia_ratio))
    kept = _kept_roots(n, mass_ratio, inertia_ratio, _brackets(n, mass_ratio, inertia_ratio))
    if kept is not None:
        return kept
    roots = np.array(_found(n, mass_ratio, inertia_ratio))
    _keep_roots(n, mass_ratio, inertia_ratio, roots)
    return roots


def _brackets(n: int, mass_ratio: float, inertia_ratio: float) -> list[tuple[float, float]]:
    """The grid's intervals holding the first ``n`` sign changes of the frequency determinant (a
    :class:`~modelgen.errors.ModelError` where it holds fewer)."""
    upper = (n + 1.5) * math.pi + 10.0
    grid = np.arange(1e-4, upper + _GRID_STEP, _GRID_STEP)
    values = frequency_determinant(grid, mass_ratio, inertia_ratio)
    change = np.nonzero(np.signbit(values[:-1]) != np.signbit(values[1:]))[0]
    if change.size < n:
        raise ModelError(
            f"frequency equation: only {change.size} roots found below bL = {upper:.1f} "
            f"for n = {n} (mass ratio {mass_ratio:g}, inertia ratio {inertia_ratio:g})"
        )
    return [(float(grid[i]), float(grid[i + 1])) for i in change[:n]]


@functools.lru_cache(maxsize=1024)
def _found(n: int, mass_ratio: float, inertia_ratio: float) -> tuple[float, ...]:
    """The first ``n`` roots, to the last digit (remembered, the grid's scan with them: a fit evaluates a link at the
    same ratios many times)."""
    from scipy.optimize import brentq  # lazy: keeps `import modelgen` fast (0.4 s), and a load whose roots are kept

    return tuple(float(brentq(frequency_determinant, a, b, args=(mass_ratio, inertia_ratio), xtol=1e-15, rtol=1e-15))
                 for a, b in _brackets(n, mass_ratio, inertia_ratio))


#: Whether :func:`frequency_roots` looks up and keeps its roots in the model cache (:func:`roots_not_kept`).
_KEEP_ROOTS: contextvars.ContextVar[bool] = contextvars.ContextVar("sflm_keep_roots", default=True)


@contextlib.contextmanager
def roots_not_kept() -> Iterator[None]:
    """Within it, the frequency equation's roots are found and neither looked up nor kept in the model cache.

    The cache keeps a loaded link's roots for its next load (a file a link). A search over a link's parameters (a
    calibration's thousand trial links, each its own payload ratios) would write a file each: 56 000 files and 224 MB
    in a cache after the test suite's fits. Within it they are remembered in the process instead (a fit evaluates
    links at the same ratios many times: its Jacobian's steps in the damping, its starts).
    """
    token = _KEEP_ROOTS.set(False)
    try:
        yield
    finally:
        _KEEP_ROOTS.reset(token)


def _roots_file(n: int, mass_ratio: float, inertia_ratio: float) -> Any:
    """Where the roots of a frequency equation are kept (the model cache's ``roots/``), by a digest of what sets them."""
    import hashlib

    from .files import cache_root

    key = f"{n}|{float(mass_ratio)!r}|{float(inertia_ratio)!r}|{_GRID_STEP!r}"
    return cache_root() / "roots" / (hashlib.sha256(key.encode()).hexdigest()[:40] + ".json"), key


def _kept_roots(n: int, mass_ratio: float, inertia_ratio: float, brackets: list[tuple[float, float]]) -> FloatArray | None:
    """The roots found before, if each still lies in its bracket with the determinant changing sign across it (checked:
    a file in a cache is no authority), else ``None``."""
    import json

    path, key = _roots_file(n, mass_ratio, inertia_ratio)
    try:
        data = json.loads(path.read_text())
        roots = np.asarray(data["roots"], dtype=float)
        if data.get("key") != key or roots.shape != (n,):
            return None
    except (OSError, ValueError, KeyError, TypeError):
        return None
    for root, (a, b) in zip(roots, brackets):
        if not a <= root <= b:
            return None
        near = np.array([max(a, root - 4e-15 * root), min(b, root + 4e-15 * root)])
        ends = frequency_determinant(near, mass_ratio, inertia_ratio)
        if not (ends[0] == 0 or ends[1] == 0 or np.signbit(ends[0]) != np.signbit(ends[1])):
            return None
    return roots


def _keep_roots(n: int, mass_ratio: float, inertia_ratio: float, roots: FloatArray) -> None:
    """Keep the roots for the next load (where the cache can be written; nothing is lost where it cannot)."""
    from .files import write_json

    path, key = _roots_file(n, mass_ratio, inertia_ratio)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(path, {"key": key, "roots": [float(r) for r in roots]})
    except OSError:
        pass


@dataclass(frozen=True)
class ModeShapes:
    """A set of ``n`` assumed mode shapes ``phi_j(x)`` on ``[0, L]``.

    Attributes
    ----------
    family : str
        One of :data:`~modelgen.geometry.MODE_FAMILIES`.
    length : float
        Link length ``L`` (m).
    betas : ndarray
        ``b_j L`` of the transcendental families (empty for ``polynomial``).
    mass_ratio, inertia_ratio : float
        Payload ratios the shapes were computed for.
    scale : ndarray
        Factors applied to each normalised shape (ones by default). The model's zeros,
        frequencies and ``CAB`` do not depend on them.

    Notes
    -----
    Shapes are normalised to ``int_0^L phi_j^2 dx = L``; transcendental ones with
    ``phi_j''(0) > 0`` (for ``clamped-free`` that is the textbook
    ``cosh - cos - s (sinh - sin)``), polynomial ones with ``phi_j(L) > 0``.
    """

    family: str
    length: float
    betas: FloatArray
    mass_ratio: float = 0.0
    inertia_ratio: float = 0.0
    scale: FloatArray = field(default_factory=lambda: np.ones(0))
    _coef: FloatArray = field(default_factory=lambda: np.zeros((0, 5)), repr=False)

    @property
    def n(self) -> int:
        """Number of modes."""
        return int(self.scale.size)

    def __call__(self, x: ArrayLike, derivative: int = 0) -> FloatArray:
        """Evaluate the ``derivative``-th x-derivative of every shape.

        Parameters
        ----------
        x : array_like
            Positions along the link (m), in ``[0, L]``.
        derivative : int
            Order of the derivative with respect to ``x`` (0..4).

        Returns
        -------
        ndarray
            Shape ``(n, len(x))``.
        """
        xi = np.atleast_1d(np.asarray(x, dtype=float)) / self.length
        k = int(derivative)
        if self.family == "polynomial":
            # Legendre series in u = 2 xi - 1; du/dx = 2 / L
            u = 2.0 * xi - 1.0
            vals = np.array([legval(u, legder(c, k)) for c in self._coef]) * 2.0**k
            return np.asarray(vals * self.scale[:, None] / self.length**k)
        return np.asarray(self.scale[:, None] * _shape_values(self._coef, xi, k) / self.length**k)

    def scaled(self, factors: ArrayLike) -> "ModeShapes":
        """The same shapes multiplied by ``factors`` (one per mode).

        Return the same shapes multiplied by ``factors`` (one per mode, nonzero).

        Parameters
        ----------
        factors : ArrayLike
            One nonzero factor a mode.
        """
        f = np.asarray(factors, dtype=float).reshape(-1)
        if f.size != self.n or not np.all(np.isfinite(f)) or np.any(f == 0):
            raise GeometryError("scale", factors, f"{self.n} finite nonzero factors")
        return ModeShapes(
            self.family, self.length, self.betas, self.mass_ratio, self.inertia_ratio, self.scale * f, self._coef
        )


def _shape_values(coef: FloatArray, xi: FloatArray, k: int) -> FloatArray:
    """Cancellation-free ``d^k phi / d xi^k`` for rows ``[beta, P, Q, C1s, C2s]`` of ``coef``.

    ``phi(xi) = [P e^{beta(xi-1)} + Q e^{-beta xi} - 2 C1s cos(beta xi) - 2 C2s sin(beta xi)]
    / (2 norm)`` with the normalisation folded into the coefficients.
    """
    beta = coef[:, 0:1]
    P, Q, C1s, C2s = (coef[:, i : i + 1] for i in range(1, 5))
    bx = beta * xi[None, :]
    cos_k = np.cos(bx + k * math.pi / 2)  # d^k cos(u)/du^k
    sin_k = np.sin(bx + k * math.pi / 2)
    sign = -1.0 if k % 2 else 1.0
    vals = P * np.exp(bx - beta) + sign * Q * np.exp(-bx) - 2.0 * C1s * cos_k - 2.0 * C2s * sin_k
    return np.asarray(0.5 * beta**k * vals)


def _coefficients(beta: float, mu: float, kappa: float) -> FloatArray:
    """``[beta, P, Q, C1s, C2s]`` of one transcendental shape (not yet normalised)."""
    a1, a2, b1, b2 = (float(v) for v in _scaled_rows(beta, mu, kappa))
    e = math.exp(-beta)
    s, c = math.sin(beta), math.cos(beta)
    if math.hypot(a1, a2) >= math.hypot(b1, b2):
        c1s, c2s = a2, -a1  # null vector of the moment row
        k3 = kappa * beta**3
        p = (-e + s - c) - k3 * (e - c - s)  # C1 + C2 = a2 - a1, exponentials cancelled
    else:
        c1s, c2s = b2, -b1  # null vector of the shear row
        mb = mu * beta
        p = (e + c + s) + mb * (-e - s + c)  # C1 + C2 = b2 - b1
    sign = 1.0 if c1s >= 0 else -1.0
    return np.array([beta, sign * p, sign * (c1s - c2s), sign * c1s, sign * c2s])


def quadrature_nodes(shapes: ModeShapes) -> int:
    """Gauss-Legendre node count used for ``shapes`` (grows with the largest ``bL``)."""
    top = float(np.max(shapes.betas)) if shapes.betas.size else 0.0
    return 40 + 2 * int(math.ceil(top)) + 2 * shapes.n


def mode_shapes(geometry: Geometry, n: int | None = None, family: str | None = None) -> ModeShapes:
    """Build the assumed mode shapes for a geometry.

    Parameters
    ----------
    geometry : Geometry
        The link; its ``modes`` and ``mode_shapes`` are the defaults.
    n : int, optional
        Number of modes (overrides ``geometry.modes``).
    family : str, optional
        Mode-shape family (overrides ``geometry.mode_shapes``).

    Returns
    -------
    ModeShapes
    """
    n = geometry.modes if n is None else n
    family = geometry.mode_shapes if family is None else family
    if family not in MODE_FAMILIES:
        raise GeometryError("mode_shapes", family, "one of " + ", ".join(MODE_FAMILIES))
    L = geometry.length
    if family == "polynomial":
        return normalised(polynomial_shapes(n, L))
    mu = geometry.payload_mass_ratio if family == "clamped-mass" else 0.0
    kappa = geometry.payload_inertia_ratio if family == "clamped-mass" else 0.0
    betas = frequency_roots(n, mu, kappa)
    coef = np.array([_coefficients(float(b), mu, kappa) for b in betas])
    return normalised(ModeShapes(family, L, betas, mu, kappa, np.ones(n), coef))


def polynomial_shapes(n: int, length: float, monomial: bool = False) -> ModeShapes:
    """Unnormalised shapes spanning ``(x/L)^2 .. (x/L)^(n+1)``.

    Parameters
    ----------
    n : int
        Number of shapes.
    length : float
        Link length.
    monomial : bool
        Return the monomials ``(x/L)^(j+1)`` themselves (ill-conditioned for ``n > 6``)
        instead of ``(x/L)^2 P_{j-1}(2x/L - 1)``.
    """
    xi_one = poly2leg([0.5, 0.5])  # xi = (u + 1)/2 as a Legendre series in u
    xi_squared = legmul(xi_one, xi_one)
    coef = np.zeros((n, n + 2))
    for j in range(n):
        if monomial:
            series = xi_squared
            for _ in range(j):
                series = legmul(series, xi_one)
        else:
            series = legmul(xi_squared, np.eye(j + 1)[j])
        coef[j, : series.size] = series
    return ModeShapes("polynomial", length, np.zeros(0), scale=np.ones(n), _coef=coef)


def normalised(shapes: ModeShapes) -> ModeShapes:
    """``shapes`` scaled to ``int_0^L phi_j^2 dx = L`` (sign kept)."""
    xg, wg = leggauss(quadrature_nodes(shapes))
    values = shapes(0.5 * shapes.length * (xg + 1.0))
    norms = np.sqrt(0.5 * (values**2) @ wg)
    coef = shapes._coef.copy()
    if shapes.family == "polynomial":
        coef /= norms[:, None]
    else:
        coef[:, 1:] /= norms[:, None]
    return ModeShapes(
        shapes.family, shapes.length, shapes.betas, shapes.mass_ratio, shapes.inertia_ratio, np.ones(shapes.n), coef
    )


@dataclass(frozen=True)
class ModalConstants:
    """Modal integrals and tip values of a set of shapes.

    Attributes
    ----------
    S : ndarray, shape (n,)
        ``int_0^L x phi_j dx`` (m^2 times shape units).
    N : ndarray, shape (n, n)
        ``int_0^L phi_i phi_j dx``.
    G : ndarray, shape (n, n)
        ``int_0^L phi_i'' phi_j'' dx``.
    phi_L : ndarray, shape (n,)
        ``phi_j(L)``.
    dphi_L : ndarray, shape (n,)
        ``phi_j'(L)``.
    nodes : int
        Gauss-Legendre nodes used.
    P : ndarray, shape (n, n)
        ``int_0^L (L^2 - x^2) phi_i' phi_j' dx``: the link's share of the geometric (centrifugal)
        stiffening (docs/method.md section 1a).
    Q : ndarray, shape (n, n)
        ``int_0^L phi_i' phi_j' dx``: the payload's share (its foreshortening ``u_c(L)``).
    """

    S: FloatArray
    N: FloatArray
    G: FloatArray
    phi_L: FloatArray
    dphi_L: FloatArray
    nodes: int
    P: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    Q: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))


def modal_constants(shapes: ModeShapes, nodes: int | None = None) -> ModalConstants:
    """Integrate the modal constants of Eq. (6)'s matrices.

    Parameters
    ----------
    shapes : ModeShapes
        The assumed modes.
    nodes : int, optional
        Gauss-Legendre node count (default :func:`quadrature_nodes`).

    Returns
    -------
    ModalConstants
    """
    nodes = quadrature_nodes(shapes) if nodes is None else int(nodes)
    L = shapes.length
    xg, wg = leggauss(nodes)
    x = 0.5 * L * (xg + 1.0)
    w = 0.5 * L * wg
    phi = shapes(x, 0)
    d1 = shapes(x, 1)
    d2 = shapes(x, 2)
    S = phi @ (w * x)
    N = (phi * w) @ phi.T
    G = (d2 * w) @ d2.T
    P = (d1 * (w * (L * L - x * x))) @ d1.T
    Q = (d1 * w) @ d1.T
    tip = np.array([L])
    return ModalConstants(
        S=S,
        N=0.5 * (N + N.T),
        G=0.5 * (G + G.T),
        phi_L=shapes(tip, 0)[:, 0],
        dphi_L=shapes(tip, 1)[:, 0],
        nodes=nodes,
        P=0.5 * (P + P.T),
        Q=0.5 * (Q + Q.T),
    )

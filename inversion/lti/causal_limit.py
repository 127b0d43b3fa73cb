"""The causal limit: the least error any causal feedforward from rest can hold a move to (docs/method.md section 7).

Let the plant have zeros ``z`` with ``Re z > 0``. A bounded input from rest after which the
plant settles has a Laplace transform that converges for ``Re s > 0``, so the output
satisfies ``Y(z) = G(z) U(z) = 0`` at each such zero. With ``e = y - y_d`` (both measured from
the start, ``y_d`` held at ``y_d(t_f)`` after the move): ``E(z) = -Y_d(z)``. No causal
feedforward -- whatever its method -- can therefore hold ``max_t |e(t)|`` below::

    eps_min = min ||e||_inf  subject to  int_0^inf e^{-z t} e(t) dt = -Y_d(z)  for every such z

(the real and imaginary parts of one of a complex pair). For one real zero the bound
``|int e^{-z t} e dt| <= ||e||_inf / z`` is met by a constant error, so ``eps_min = z |Y_d(z)|``
exactly (:func:`causal_limit` says ``"closed form"``). For several, the programme is solved as
a linear programme on a grid that resolves each kernel ``e^{-z t}`` over its decay (HiGHS's dual simplex, through
``highspy``): with ``e = v / s``, ``|v| <= 1``, maximise ``s`` subject to
``int k_i v = s c_i``. Purely imaginary zeros give kernels that do not decay: over an
unbounded window they constrain nothing (they are reported, not used).

``Y_d(z)`` is computed by Gauss-Legendre quadrature on each piece of the trajectory, split so
that ``|z|`` times a sub-interval is at most 2 (32 nodes: exact to rounding for the polynomial
moves and their exponential weight), plus the tail ``(y_d(t_f) - y_d(t_0)) e^{-z T} / z``.

The limit bounds the error alone: with a torque bound as well the least error is the
optimal-control feedforward's (:mod:`inversion.methods.ocp`), which approaches this limit as its period
shrinks and its torque bound grows. :attr:`CausalLimit.shortest_duration` is the least
duration of the same trajectory shape (``y_d`` stretched in time) whose limit meets the bound:
``Y_d`` of the stretched move is ``(T / T_0) Y_d(z T / T_0)``, and the limit falls fast with
``T`` (bisection).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..signals.trajectory import Trajectory

__all__ = ["CausalLimit", "causal_limit", "laplace_transform", "constraining_zeros", "limit_error"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Zeros with ``Re z <= IMAGINARY * |z|`` are purely imaginary (they constrain nothing over an unbounded window).
IMAGINARY = 1e-9
#: Gauss-Legendre nodes per sub-interval of :func:`laplace_transform`.
_NODES = 32
#: Each kernel ``e^{-z t}`` is resolved over this many of its time constants ...
_DECAY = 40.0
#: ... on this many points, and an oscillating one with at least this many points a radian.
_POINTS_PER_KERNEL = 1500
_PER_RADIAN = 4.0
#: Most grid points of the linear programme.
_MAX_POINTS = 40_000


@dataclass(frozen=True)
class CausalLimit:
    """The least error any causal feedforward from rest can reach.

    The least error any causal feedforward from rest can hold a move to (module docstring).

    Attributes
    ----------
    error : float
        ``eps_min`` (m; the output's units for a system): no causal feedforward keeps ``max |y - y_d|`` below it.
    relative_error : float
        Of the move.
    move : float
        The move.
    duration : float
        The move's duration (s).
    zeros : tuple of complex
        The zeros with ``Re z > 0`` it comes from (one of each complex pair).
    imaginary : tuple of complex
        Purely imaginary zeros (one of each pair): no constraint over an unbounded window.
    method : str
        ``"closed form"`` (one real zero), ``"linear programme"`` or ``"none"`` (no such zero: the limit is 0).
    bound : float or None
        The bound it was judged against (m).
    shortest_duration : float or None
        The least duration of the same trajectory shape whose limit meets ``bound`` (s); ``0.0`` when no zero
        constrains; ``None`` when not asked for, or not found within a thousand times the duration.
    """

    error: float
    relative_error: float
    move: float
    duration: float
    zeros: tuple[complex, ...]
    imaginary: tuple[complex, ...]
    method: str
    bound: float | None = None
    shortest_duration: float | None = None

    @property
    def exceeds(self) -> bool:
        """Whether the limit is above the bound (no causal feedforward can meet it)."""
        return self.bound is not None and self.error > self.bound

    def zeros_text(self) -> str:
        """The constraining zeros as a reader sees them.

        The constraining zeros as a reader sees them (``65.26``, ``1.2+-3.4i``), and the imaginary ones' note.
        """
        shown = ", ".join(f"{z.real:.4g}" if z.imag == 0 else f"{z.real:.4g}±{abs(z.imag):.4g}i" for z in self.zeros)
        text = shown or "none with Re > 0"
        if self.imaginary:
            text += "; " + ", ".join(f"±{abs(z.imag):.4g}i" for z in self.imaginary) + " purely imaginary: no constraint over an unbounded window"
        return text

    def sentence(self) -> str:
        """The limit as a sentence.

        ``no causal feedforward from rest can hold this move closer than X % of the move (zeros ...)``.
        """
        if self.method == "none":
            return f"no zero with Re > 0 constrains a causal feedforward from rest (zeros: {self.zeros_text()})"
        return (f"no causal feedforward from rest can hold this move closer than {self.error:.4g} ({100 * self.relative_error:.3g} % "
                f"of the move; zeros {self.zeros_text()})")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (the summaries' ``causal_limit`` block)."""
        return {"error": self.error, "relative_error": self.relative_error, "move": self.move, "duration": self.duration,
                "zeros": [[z.real, z.imag] for z in self.zeros], "imaginary_zeros": [[z.real, z.imag] for z in self.imaginary],
                "method": self.method, "bound": self.bound, "shortest_duration": self.shortest_duration}


def constraining_zeros(zeros: ArrayLike) -> tuple[tuple[complex, ...], tuple[complex, ...]]:
    """The zeros that constrain a causal feedforward.

    The zeros with ``Re z > 0`` (one of each complex pair, ``Im >= 0``) and the purely imaginary ones (``Im > 0``).

    Parameters
    ----------
    zeros : ArrayLike
        The plant's zeros.
    """
    z = np.asarray(zeros, dtype=complex).reshape(-1)
    size = np.maximum(np.abs(z), np.finfo(float).tiny)
    right = z[(z.real > IMAGINARY * size) & (z.imag >= -IMAGINARY * size)]
    imaginary = z[(np.abs(z.real) <= IMAGINARY * size) & (z.imag > 0)]
    real_parts = [complex(v.real, 0.0) if abs(v.imag) <= IMAGINARY * abs(v) else complex(v) for v in right]
    return tuple(sorted(real_parts, key=lambda v: (v.real, v.imag))), tuple(complex(0.0, v.imag) for v in sorted(imaginary, key=abs))


def laplace_transform(trajectory: Trajectory, z: ArrayLike, stretch: float = 1.0) -> ComplexArray:
    """The Laplace transform of the move at each ``z``.

    ``int_0^inf e^{-z s} (y_d(t_0 + s) - y_d(t_0)) ds`` of the move (held at ``y_d(t_f)`` after it), at each ``z`` (``Re z > 0``).

    ``stretch``: the same shape over ``stretch`` times the duration (``(T / T_0) Y_d(z T / T_0)``).

    Parameters
    ----------
    trajectory : Trajectory
        The desired output.
    z : ArrayLike
        Points with ``Re z > 0``.
    stretch : float, optional
        The ratio of durations.
    """
    zs = np.asarray(z, dtype=complex).reshape(-1) * stretch
    t0, tf = trajectory.t0, trajectory.tf
    y0 = trajectory.y_start
    rise = trajectory.y_final - y0
    knots = np.array([t0, *[b for b in trajectory.breakpoints if t0 < b < tf], tf])
    nodes, weights = np.polynomial.legendre.leggauss(_NODES)
    out = np.empty(zs.size, dtype=complex)
    for i, zi in enumerate(zs):
        total = 0j
        horizon = t0 + (_DECAY * 2.5 + 20.0) / max(zi.real, np.finfo(float).tiny)  # e^{-120}: nothing beyond it shows
        for a, b in zip(knots[:-1], knots[1:]):
            if a >= horizon:
                break
            b = min(b, horizon)
            count = int(min(20_000, max(1, math.ceil(abs(zi) * (b - a) / 2.0))))
            edges = np.linspace(a, b, count + 1)
            half = 0.5 * np.diff(edges)
            s = (edges[:-1, None] + half[:, None] * (nodes[None, :] + 1.0)).reshape(-1)
            inside = np.clip(s, a, b)
            y = trajectory.derivative(inside, 0, "+") - y0
            total += complex(np.sum(np.repeat(half, _NODES) * np.tile(weights, count) * np.exp(-zi * (s - t0)) * y))
        out[i] = total + rise * np.exp(-zi * (tf - t0)) / zi
    return out * stretch


def _constraints(zeros: tuple[complex, ...], values: ComplexArray) -> tuple[list[tuple[complex, str]], FloatArray]:
    """The real constraints ``int k_i e = c_i``: a kernel per real zero, the real and imaginary parts of a complex one."""
    kernels: list[tuple[complex, str]] = []
    rhs: list[float] = []
    for z, value in zip(zeros, values):
        kernels.append((z, "re"))
        rhs.append(-float(value.real))
        if z.imag != 0:
            kernels.append((z, "im"))
            rhs.append(-float(value.imag))
    return kernels, np.array(rhs)


def _grid(zeros: tuple[complex, ...]) -> tuple[FloatArray, FloatArray]:
    """Points and trapezoid weights resolving every kernel over its decay (module docstring)."""
    pieces = [np.zeros(1)]
    for z in zeros:
        horizon = _DECAY / z.real
        count = int(max(_POINTS_PER_KERNEL, math.ceil(_PER_RADIAN * abs(z.imag) * horizon)))
        pieces.append(np.linspace(0.0, horizon, count + 1))
        pieces.append(np.geomspace(1e-3 / abs(z), horizon, 200))  # the start, where a fast kernel is largest
    t = np.unique(np.concatenate(pieces))
    if t.size > _MAX_POINTS:
        t = np.unique(np.quantile(t, np.linspace(0.0, 1.0, _MAX_POINTS)))
    weights = np.zeros(t.size)
    steps = np.diff(t)
    weights[:-1] += steps / 2
    weights[1:] += steps / 2
    return t, weights


def _kernel_matrix(kernels: list[tuple[complex, str]], t: FloatArray, weights: FloatArray) -> FloatArray:
    rows = []
    for z, part in kernels:
        value = np.exp(-z * t)
        rows.append((value.real if part == "re" else value.imag) * weights)
    return np.array(rows)


def limit_error(zeros: tuple[complex, ...], values: ComplexArray, matrix: FloatArray | None = None) -> float:
    """``eps_min`` for the constraining ``zeros`` (module docstring).

    ``eps_min`` for the constraining ``zeros`` and ``Y_d`` at them (``values``; module docstring). ``matrix``: the
    kernels on the programme's grid (:func:`_kernel_matrix`), when several zeros constrain.

    Parameters
    ----------
    zeros : tuple[complex, ...]
        The constraining zeros.
    values : ComplexArray
        ``Y_d`` at them.
    matrix : FloatArray | None, optional
        The kernels on the programme's grid, if several constrain.
    """
    if not zeros:
        return 0.0
    if len(zeros) == 1 and zeros[0].imag == 0:
        return float(zeros[0].real * abs(values[0]))
    kernels, rhs = _constraints(zeros, values)
    if not np.any(rhs):
        return 0.0
    if matrix is None:
        t, weights = _grid(zeros)
        matrix = _kernel_matrix(kernels, t, weights)
    n = matrix.shape[1]
    scale = float(np.abs(rhs).max())
    # variables [v_1 .. v_n, s]: maximise s with int k_i v = s c_i, |v| <= 1; then e = v / s
    equality = np.hstack([matrix, -(rhs / scale)[:, None]])
    status, s, message = _maximise_last(equality, n)
    if status == "unbounded":  # the constraints ask for no error at all
        return 0.0
    if status != "optimal" or not s > 0:
        from ..errors import InversionError

        raise InversionError(f"the causal limit's linear programme failed ({message})")
    return float(scale / s)


def _maximise_last(equality: FloatArray, n: int) -> tuple[str, float, str]:
    """``max s`` over ``[v; s]`` with ``equality [v; s] = 0``, ``|v| <= 1``, ``s >= 0``, by HiGHS's dual simplex.

    HiGHS through its own Python interface (``highspy``), its dual simplex as SciPy's ``linprog(method="highs")`` asks
    for it, without presolve: a few dense rows leave it nothing to reduce (with HiGHS 1.16 presolve took 30-250 ms of a
    solve that takes 3 ms without it).
    The same values as ``linprog`` to rounding (30 programmes of the presets, a transfer function's complex pair and their
    shortest durations, 2026-12-07: 28 bit for bit, two 2e-16 apart), without importing :mod:`scipy.optimize` (0.25-0.45
    s, more than the programme; the automatic choice needs nothing else from it).

    Returns
    -------
    tuple
        ``("optimal" | "unbounded" | HiGHS's status, s, HiGHS's words)``.
    """
    import highspy  # lazy: keeps `import inversion` fast (0.02 s)

    rows = equality.shape[0]
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = n + 1, rows
    lp.col_cost_ = np.r_[np.zeros(n), -1.0]
    lp.col_lower_ = np.r_[-np.ones(n), 0.0]
    lp.col_upper_ = np.r_[np.ones(n), highspy.kHighsInf]
    lp.row_lower_ = lp.row_upper_ = np.zeros(rows)
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise  # (column by column: the kernels are dense)
    nonzero = equality != 0
    lp.a_matrix_.start_ = np.r_[0, np.cumsum(nonzero.sum(axis=0))].astype(np.int32)
    lp.a_matrix_.index_ = np.nonzero(nonzero.T)[1].astype(np.int32)
    lp.a_matrix_.value_ = equality.T[nonzero.T]
    solver = highspy._Highs()  # type: ignore[attr-defined]  # (the interface without its callbacks: their set-up prints a banner)
    solver.setOptionValue("output_flag", False)
    solver.setOptionValue("simplex_strategy", 1)  # the dual simplex, as SciPy asks
    solver.setOptionValue("presolve", "off")  # (a few dense rows: nothing to reduce; 3 ms against 30-250 ms with it)
    solver.passModel(lp)
    solver.run()
    status = solver.getModelStatus()
    words = solver.modelStatusToString(status)
    if status == highspy.HighsModelStatus.kOptimal:
        return "optimal", float(solver.getSolution().col_value[n]), words
    if status == highspy.HighsModelStatus.kUnbounded:
        return "unbounded", math.inf, words
    return str(status), math.nan, words


def causal_limit(model: Any, trajectory: Trajectory, bound: float | None = None, *, zeros: ArrayLike | None = None,
                 shortest: bool | None = None) -> CausalLimit:
    """The causal limit of ``trajectory`` on ``model``.

    Parameters
    ----------
    model : NormalForm, Model or LinearSystem, or None
        Whose zeros constrain (``eig(A_I)``); ignored when ``zeros`` is given.
    trajectory : Trajectory
        The move.
    bound : float, optional
        The error bound (m): :attr:`CausalLimit.exceeds` tells whether the limit is above it, and
        with ``shortest`` the least duration that meets it is found.
    zeros : array_like, optional
        The zeros (default: the model's).
    shortest : bool, optional
        Find :attr:`CausalLimit.shortest_duration` (needs ``bound``); ``None`` (the default): only when the limit exceeds
        the bound, where a refusal quotes it.

    Returns
    -------
    CausalLimit

    Examples
    --------
    >>> from inversion import smoothstep
    >>> limit = causal_limit(None, smoothstep(1.0, 4.0, 6), 0.01, zeros=[2.0, -1.0, -3.0])  # (2 - s)/((s + 1)(s + 3))
    >>> round(100 * limit.relative_error, 3), limit.method, limit.exceeds  # docs/method.md section 7: 3.074 %
    (3.074, 'closed form', True)
    """
    if zeros is None:
        from .system import normal_form

        zeros = np.linalg.eigvals(normal_form(model).AI) if normal_form(model).AI.size else np.zeros(0)
    right, imaginary = constraining_zeros(zeros)
    move = trajectory.move()
    duration = trajectory.duration
    if not right:
        return CausalLimit(0.0, 0.0, move, duration, (), imaginary, "none", bound, 0.0 if bound is not None else None)
    values = laplace_transform(trajectory, right)
    kernels, _ = _constraints(right, values)
    matrix = None
    if not (len(right) == 1 and right[0].imag == 0):
        t, weights = _grid(right)
        matrix = _kernel_matrix(kernels, t, weights)
    error = limit_error(right, values, matrix)
    method = "closed form" if matrix is None else "linear programme"
    relative = error / move if move > 0 else 0.0
    found = None
    if bound is not None and (shortest or (shortest is None and error > bound)):
        found = _shortest(right, trajectory, bound, error, matrix)
    return CausalLimit(error, relative, move, duration, right, imaginary, method, bound, found)


def _shortest(zeros: tuple[complex, ...], trajectory: Trajectory, bound: float, error: float, matrix: FloatArray | None) -> float | None:
    """The least stretch of the move's duration whose limit meets ``bound``, in seconds (bisection; ``None`` beyond 1000x)."""

    def limit(stretch: float) -> float:
        return limit_error(zeros, laplace_transform(trajectory, zeros, stretch), matrix)

    low, high = 1.0, 1.0
    if error > bound:
        while limit(high) > bound:
            low, high = high, high * 2.0
            if high > 1e3:
                return None
    else:
        while low > 1e-3 and limit(low / 2.0) <= bound:
            low /= 2.0
        high, low = low, low / 2.0
        if high <= 1e-3:
            return high * trajectory.duration
    for _ in range(30):
        middle = math.sqrt(low * high)
        if limit(middle) <= bound:
            high = middle
        else:
            low = middle
        if high / low < 1 + 1e-4:
            break
    return high * trajectory.duration

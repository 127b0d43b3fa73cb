"""Desired end-effector trajectories ``y_d(t)`` with exact derivatives.

A trajectory is defined on ``[t0, tf]`` and held at rest outside it (``y = y_d(t0)``
before, ``y = y_d(tf)`` after, every derivative 0). The inversion needs
``yddot_d`` and its derivatives up to order ``h`` at the segment joints (Eq. (30)), as
one-sided limits where the trajectory has a breakpoint.

* :func:`smoothstep` -- the paper's simulation family, ``y = D P(t/T)`` with
  ``P(u) = u^(o+1) sum_{k=0}^{o} C(o+k, k) (1-u)^k``: degree ``2o + 1``, derivatives
  ``1..o`` zero at both ends (Eq. (37) for ``o = 5``);
* :func:`experiment_trajectory` -- the experiment's acceleration, a C1 piecewise cubic
  Hermite through ``(0,0), (0.2,a), (0.4,-a), (0.6,0)`` with zero slopes, integrated
  exactly (section 8, Fig. 8);
* :class:`CallableTrajectory` -- a user function giving derivatives;
* :func:`from_csv` -- sampled ``t, y`` data through a quintic smoothing spline.
"""

from __future__ import annotations

import csv
import math
from abc import ABC, abstractmethod
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import TrajectoryError
from .pieces import Pieces

if TYPE_CHECKING:
    from scipy.interpolate import PPoly

__all__ = [
    "Trajectory",
    "DERIVATIVE_NAMES",
    "derivative_key",
    "PolynomialTrajectory",
    "CallableTrajectory",
    "smoothstep",
    "experiment_trajectory",
    "from_csv",
    "from_samples",
    "trajectory_from_spec",
    "stretched",
    "MAX_CSV_ROWS",
    "MAX_SPLINE_SAMPLES",
]

FloatArray = NDArray[np.float64]
Side = Literal["+", "-"]

#: Names of ``y`` and its first derivatives in the dictionaries of values the inversion passes
#: around (``y^(k)`` for higher ``k``: :func:`derivative_key`).
DERIVATIVE_NAMES = ("y", "ydot", "yddot", "jerk", "snap")


def derivative_key(k: int) -> str:
    """The name of ``y^(k)`` in a dictionary of values.

    The name of ``y^(k)`` in a dictionary of values: ``y, ydot, yddot, jerk, snap``, then ``y(5)``, ...

    Parameters
    ----------
    k : int
        The derivative's order.
    """
    return DERIVATIVE_NAMES[k] if k < len(DERIVATIVE_NAMES) else f"y({k})"


class Trajectory(ABC):
    """A desired tip trajectory ``y_d(t)`` on ``[t0, tf]``.

    Attributes
    ----------
    t0, tf : float
        Start and end of the manoeuvre (s).
    max_derivative : int or None
        Highest derivative of ``y_d`` available (``None``: every order).
    breakpoints : tuple of float
        Interior times where some derivative jumps (one-sided limits are used there).
    name : str
        Short description.
    spec : str or None
        The specification :func:`trajectory_from_spec` reads it back from (``smoothstep:0.5:2:2``,
        ``paper-exp``, a CSV file's absolute path), where it has one: a summary records it, so that
        what was inverted can be inverted again from the summary alone.
    """

    t0: float
    tf: float
    max_derivative: int | None
    breakpoints: tuple[float, ...]
    name: str
    spec: str | None = None

    @abstractmethod
    def _inside(self, t: FloatArray, k: int, side: Side) -> FloatArray:
        """The ``k``-th derivative at times inside ``[t0, tf]``."""

    def derivative(self, t: ArrayLike, k: int = 0, side: Side = "+") -> FloatArray:
        """``d^k y_d / dt^k`` at ``t``.

        Parameters
        ----------
        t : array_like
            Times (s). Outside ``[t0, tf]`` the trajectory is at rest.
        k : int
            Order of the derivative (0 is the position).
        side : {"+", "-"}
            At a breakpoint, the right (``+``) or left (``-``) limit. At ``t0`` and ``tf``
            the values inside the manoeuvre are returned (``+`` at ``t0``, ``-`` at ``tf``).

        Raises
        ------
        TrajectoryError
            If ``k`` exceeds :attr:`max_derivative` or a value is not finite.
        """
        if self.max_derivative is not None and k > self.max_derivative:
            raise TrajectoryError(
                "derivative order", k, f"at most {self.max_derivative} (the trajectory {self.name} has no more)"
            )
        tt = np.atleast_1d(np.asarray(t, dtype=float))
        if tt.min(initial=self.t0) >= self.t0 and tt.max(initial=self.tf) <= self.tf:
            out = self._inside(tt, k, side)
        else:
            out = np.zeros_like(tt)
            inside = (tt >= self.t0) & (tt <= self.tf)
            if np.any(inside):
                out[inside] = self._inside(tt[inside], k, side)
            if k == 0:
                out[tt < self.t0] = self._inside(np.array([self.t0]), 0, "+")[0]
                out[tt > self.tf] = self._inside(np.array([self.tf]), 0, "-")[0]
        if not np.all(np.isfinite(out)):
            bad = tt[~np.isfinite(out)][0]
            raise TrajectoryError(f"y_d^({k}) at t = {bad:g}", float(out[~np.isfinite(out)][0]), "a finite number")
        return out

    def derivatives(self, t: ArrayLike, orders: range | list[int], side: Side = "+") -> FloatArray:
        """``d^k y_d / dt^k`` for every ``k`` in ``orders``.

        ``d^k y_d / dt^k`` for every ``k`` in ``orders``: shape ``(len(t), len(orders))``.

        Parameters
        ----------
        t : array_like
            Times (s).
        orders : range or list of int
            The derivatives' orders.
        side : {"+", "-"}
            At a breakpoint, the limit from the right or from the left.
        """
        return np.column_stack([self.derivative(t, k, side) for k in orders])

    def values(self, t: ArrayLike, top: int, side: Side = "+") -> dict[str, FloatArray]:
        """``y_d`` and its derivatives up to order ``top`` at ``t``.

        ``y_d`` and its derivatives up to order ``top`` at ``t``, named by :func:`derivative_key`.

        Parameters
        ----------
        t : array_like
            Times (s).
        top : int
            The highest derivative.
        side : {"+", "-"}
            At a breakpoint, the limit from the right or from the left.
        """
        return {derivative_key(k): self.derivative(t, k, side) for k in range(top + 1)}

    @property
    def duration(self) -> float:
        """``tf - t0`` (s)."""
        return self.tf - self.t0

    @property
    def y_start(self) -> float:
        """``y_d(t0)``, where the move starts."""
        return float(self.derivative([self.t0], 0)[0])

    @property
    def y_final(self) -> float:
        """``y_d(tf)``, where the move ends (the limit from inside)."""
        return float(self.derivative([self.tf], 0, "-")[0])

    def move(self, points: int = 4001) -> float:
        """The range of ``y_d`` over the manoeuvre (m).

        The range of ``y_d`` over the manoeuvre (m), on a grid and the breakpoints.

        Parameters
        ----------
        points : int
            Points of the grid.
        """
        t = np.union1d(np.linspace(self.t0, self.tf, points), [b for b in self.breakpoints if self.t0 <= b <= self.tf])
        return float(np.ptp(self.derivative(t, 0)))


class PolynomialTrajectory(Trajectory):
    """A piecewise polynomial ``y_d``.

    In SciPy's ``PPoly`` layout, evaluated as ``PPoly`` evaluates it (:class:`~inversion.signals.pieces.Pieces`).

    Parameters
    ----------
    ppoly : PPoly or Pieces
        ``y_d`` on ``[ppoly.x[0], ppoly.x[-1]]`` (its coefficients ``c`` and breakpoints ``x`` are kept, as a
        :class:`.Pieces`).
    name : str
        Description.
    max_derivative : int or None
        Highest derivative available (``None``: the pieces are exact polynomials).
    """

    def __init__(self, ppoly: PPoly | Pieces, name: str, max_derivative: int | None = None):
        x = np.asarray(ppoly.x, dtype=float)
        if not np.all(np.isfinite(ppoly.c)) or not np.all(np.isfinite(x)):
            raise TrajectoryError("trajectory", name, "finite polynomial coefficients")
        if np.ndim(ppoly.c) != 2:
            raise TrajectoryError("trajectory", name, "scalar polynomial pieces (coefficients of shape (k + 1, m))")
        self.ppoly = Pieces(ppoly.c, x)
        self.t0 = float(x[0])
        self.tf = float(x[-1])
        self.breakpoints = tuple(float(v) for v in x[1:-1])
        self.max_derivative = max_derivative
        self.name = name
        self._derivs: dict[int, Pieces] = {0: self.ppoly}

    def _piece_poly(self, k: int) -> Pieces:
        if k not in self._derivs:
            self._derivs[k] = self.ppoly.derivative(k)
        return self._derivs[k]

    def _inside(self, t: FloatArray, k: int, side: Side) -> FloatArray:
        pp = self._piece_poly(k)
        x = pp.x
        values = np.asarray(pp(t))  # right-continuous at breakpoints
        if x.size <= 2:
            return values
        # at (or within rounding of) an interior breakpoint: the requested one-sided limit
        # (joints computed as t0 + k T/K land on breakpoints only up to an ulp or two)
        tol = 1e-12 * max(self.tf - self.t0, 1.0)
        nearest = np.clip(np.searchsorted(x, t), 1, x.size - 1)
        nearest = np.where(np.abs(t - x[nearest - 1]) < np.abs(t - x[nearest]), nearest - 1, nearest)
        at = (np.abs(t - x[nearest]) <= tol) & (nearest > 0) & (nearest < x.size - 1)
        if np.any(at):
            knot = nearest[at]
            piece = knot - 1 if side == "-" else knot
            local = x[knot] - x[piece]
            val = np.zeros(knot.size)
            for row in pp.c[:, piece]:  # Horner in each piece's local variable
                val = val * local + row
            values[at] = val
        return values


class CallableTrajectory(Trajectory):
    """A trajectory given by a function ``func(t, k)``.

    A trajectory given by a function ``func(t, k) -> d^k y_d/dt^k`` (vectorised in ``t``).

    Parameters
    ----------
    func : callable
        ``func(t: ndarray, k: int) -> ndarray``, valid on ``[t0, tf]``.
    t0, tf : float
        The manoeuvre interval.
    max_derivative : int
        Highest derivative ``func`` can give.
    breakpoints : sequence of float
        Interior times where a derivative jumps (``func`` is then called with ``t``
        nudged by one ulp to the requested side).
    name : str
        Description.
    """

    def __init__(
        self,
        func: Callable[[FloatArray, int], ArrayLike],
        t0: float,
        tf: float,
        max_derivative: int,
        breakpoints: tuple[float, ...] = (),
        name: str = "callable",
    ):
        if not (math.isfinite(t0) and math.isfinite(tf) and tf > t0):
            raise TrajectoryError("trajectory interval", (t0, tf), "finite t0 < tf")
        if not isinstance(max_derivative, int) or max_derivative < 2:
            raise TrajectoryError("max_derivative", max_derivative, "an integer >= 2 (yddot must exist)")
        self.func = func
        self.t0, self.tf = float(t0), float(tf)
        self.max_derivative = max_derivative
        self.breakpoints = tuple(sorted(float(b) for b in breakpoints))
        self.name = name

    def _inside(self, t: FloatArray, k: int, side: Side) -> FloatArray:
        tt = t.copy()
        for b in self.breakpoints:
            tt[t == b] = np.nextafter(b, np.inf if side == "+" else -np.inf)
        return np.asarray(self.func(tt, k), dtype=float).reshape(t.shape)


def stretched(trajectory: Trajectory, duration: float) -> Trajectory:
    """The same move over another duration.

    ``y_s(t) = y_d(t_0 + (t - t_0) T_0 / T)``. The shape of the move is kept, its start time too; its ``k``-th derivative scales by ``(T_0 / T)^k``. A piecewise
    polynomial move stays one (exactly: its breakpoints and coefficients rescaled); any other is wrapped.

    Parameters
    ----------
    trajectory : Trajectory
        The move ``y_d`` over ``T_0``.
    duration : float
        The new duration ``T`` (s, > 0).

    Raises
    ------
    TrajectoryError
        For a duration that is not a finite number > 0.

    Examples
    --------
    >>> move = smoothstep(1.0, 2.0, 2)
    >>> slow = stretched(move, 4.0)
    >>> slow.duration, round(float(slow.derivative([2.0], 0)[0]), 12), round(float(slow.derivative([2.0], 1)[0]), 12)
    (4.0, 0.5, 0.46875)
    """
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not math.isfinite(duration) or duration <= 0:
        raise TrajectoryError("duration", duration, "a finite number > 0 (s)")
    a = float(duration) / trajectory.duration  # t - t0 = a (s - t0)
    t0 = trajectory.t0
    name = f"{trajectory.name}, over {duration:.4g} s"
    if isinstance(trajectory, PolynomialTrajectory):
        pp = trajectory.ppoly
        order = pp.c.shape[0]
        powers = a ** -(order - 1 - np.arange(order))  # the coefficient of (t - x_i)^j scales by a^-j
        return PolynomialTrajectory(Pieces(pp.c * powers[:, None], t0 + (np.asarray(pp.x) - t0) * a), name, trajectory.max_derivative)

    def value(t: FloatArray, k: int) -> FloatArray:
        return trajectory.derivative(t0 + (np.asarray(t) - t0) / a, k) * a ** (-k)

    return CallableTrajectory(value, t0, t0 + float(duration), trajectory.max_derivative or 12,
                              tuple(t0 + (b - t0) * a for b in trajectory.breakpoints), name)


def smoothstep(distance: float, duration: float, order: int = 5, start: float = 0.0) -> PolynomialTrajectory:
    """Rest-to-rest polynomial from 0 to ``distance``.

    Rest-to-rest polynomial of degree ``2 order + 1`` from 0 to ``distance``.

    ``y(t) = distance P((t - start)/duration)``, ``P(u) = u^(o+1) sum_{k=0}^{o} C(o+k,k) (1-u)^k``:
    derivatives ``1..order`` vanish at both ends. The paper's simulation trajectory is
    ``smoothstep(1.57, 5.5, 5)`` (Eq. (37), Fig. 3).

    Parameters
    ----------
    distance : float
        The move (m).
    duration : float
        Its duration (s, > 0).
    order : int
        The derivatives that vanish at both ends.
    start : float
        Its start time (s).

    Raises
    ------
    TrajectoryError
        For a non-finite distance, a non-positive duration or an order outside 1..12.
    """
    if not isinstance(distance, (int, float)) or not math.isfinite(distance):
        raise TrajectoryError("distance", distance, "a finite number (m)")
    if not isinstance(duration, (int, float)) or not math.isfinite(duration) or duration <= 0:
        raise TrajectoryError("duration", duration, "a finite number > 0 (s)")
    if isinstance(order, bool) or not isinstance(order, int) or not 1 <= order <= 12:
        raise TrajectoryError("order", order, "an integer in 1..12")
    u = np.polynomial.Polynomial([0.0, 1.0])
    P = u ** (order + 1) * sum((math.comb(order + k, k) * (1 - u) ** k for k in range(order + 1)), np.polynomial.Polynomial([0.0]))
    # as a polynomial in the local time t - start, highest power first
    coef = np.asarray(P.coef, dtype=float) * float(distance) / float(duration) ** np.arange(P.coef.size)
    pieces = Pieces(coef[::-1].reshape(-1, 1), np.array([start, start + duration]))
    result = PolynomialTrajectory(pieces, f"smoothstep({distance:g} m, {duration:g} s, order {order})")
    if start == 0:
        result.spec = f"smoothstep:{float(distance)!r}:{float(duration)!r}:{order}"
    return result


def experiment_trajectory(peak_acceleration: float = 2.5, duration: float = 0.6) -> PolynomialTrajectory:
    """The experiment's trajectory (section 8, Figs. 8-9).

    ``yddot_d`` is the C1 piecewise cubic Hermite through ``(0, 0), (T/3, a), (2T/3, -a),
    (T, 0)`` with zero slope at every knot; ``y_d`` is its exact double integral from rest.
    With ``a = 2.5`` m/s^2 and ``T = 0.6`` s: ``y_d(T) = 0.1`` m, ``ydot_d(T) = 0``.

    Parameters
    ----------
    peak_acceleration : float
        ``a`` (m/s^2).
    duration : float
        ``T`` (s).
    """
    if not math.isfinite(peak_acceleration):
        raise TrajectoryError("peak_acceleration", peak_acceleration, "a finite number (m/s^2)")
    if not math.isfinite(duration) or duration <= 0:
        raise TrajectoryError("duration", duration, "a finite number > 0 (s)")
    from scipy.interpolate import CubicHermiteSpline, PPoly  # lazy: keeps `import inversion` fast

    knots = np.linspace(0.0, duration, 4)
    acc = CubicHermiteSpline(knots, [0.0, peak_acceleration, -peak_acceleration, 0.0], np.zeros(4))
    y = acc.antiderivative(2)  # zero value and slope at t = 0
    result = PolynomialTrajectory(
        PPoly(y.c, y.x), f"experiment (piecewise cubic acceleration, peak {peak_acceleration:g} m/s^2, {duration:g} s)"
    )
    if (peak_acceleration, duration) == (2.5, 0.6):
        result.spec = "paper-exp"
    return result


#: Most rows of a trajectory CSV (about 40 MB of text): more is refused before it is read into memory.
MAX_CSV_ROWS = 2_000_000
#: Most samples the spline goes through. Interpolated, a sample's rounding ``delta`` reaches the ``k``-th derivative as
#: ``delta / dt^k``: a million samples of an exact quintic over 2 s (``dt = 2 us``) give a fifth derivative of noise,
#: and the torque with it. Denser data is thinned to this many (every ``k``-th sample, the ends kept), with a warning.
MAX_SPLINE_SAMPLES = 20_000


def from_csv(path: str | Path, smoothing: float | None = None, degree: int = 5) -> PolynomialTrajectory:
    """A trajectory from a CSV with columns ``t`` and ``y``.

    A trajectory from sampled data: a CSV with columns ``t`` and ``y`` (header required).

    The samples go through a smoothing spline of ``degree`` (default 5, giving
    ``yddot`` and its derivatives up to order 3). At most :data:`MAX_CSV_ROWS` rows are read;
    more than :data:`MAX_SPLINE_SAMPLES` are thinned to that many, with a warning (the
    smoothing scaled with them, as ``s`` is about ``n sigma^2``).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    smoothing : float, optional
        Spline smoothing factor ``s`` of :func:`scipy.interpolate.splrep`
        (default 0: interpolate).
    degree : int
        Spline degree, 3..5.

    Raises
    ------
    TrajectoryError
        For an unreadable file, missing columns, non-finite values, times not strictly
        increasing, fewer than ``degree + 2`` samples or more than :data:`MAX_CSV_ROWS`.
    """
    path = Path(path)
    if not 3 <= degree <= 5:
        raise TrajectoryError("degree", degree, "3, 4 or 5")
    t, y, offset, resolution = _read_samples(path)
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise TrajectoryError("trajectory file", str(path), "finite t and y values")
    if t.size < degree + 2:
        raise TrajectoryError("trajectory file", str(path), f"at least {degree + 2} samples")
    if not np.all(np.diff(t) > 0):
        raise TrajectoryError("trajectory file", str(path), "strictly increasing times t")
    shifted = ""
    if offset:  # times far from 0: taken from the first, exactly (their text), and said so
        from modelgen.errors import warn

        shifted = f"; its times from {offset} s"
        warn(f"{path.name}: its times start at {offset} s, where a double resolves only {resolution:.2g} s (the steps are "
             f"{float(np.diff(t).min()):.3g} s): the move is taken from its first sample, t = 0 at {offset} s")
    s = 0.0 if smoothing is None else float(smoothing)
    if not math.isfinite(s) or s < 0:
        raise TrajectoryError("smoothing", smoothing, "a finite number >= 0")
    if t.size > MAX_SPLINE_SAMPLES:
        stride = math.ceil((t.size - 1) / (MAX_SPLINE_SAMPLES - 1))
        keep = np.unique(np.r_[np.arange(0, t.size, stride), t.size - 1])
        from modelgen.errors import warn

        warn(f"{path.name}: {t.size} samples, {float(np.median(np.diff(t))):.3g} s apart: the spline goes through one in {stride} "
             f"({keep.size} samples), since interpolating them all would turn their rounding into the derivatives the torque is "
             "made of (a sample's error reaches the k-th derivative divided by the spacing to the k)"
             + (f"; the smoothing scaled with them to {s * keep.size / t.size:.3g}" if s else ""))
        s *= keep.size / t.size
        t, y = t[keep], y[keep]
    from scipy.interpolate import splrep  # lazy: keeps `import inversion` fast

    tck = splrep(t, y, k=degree, s=s)
    if smoothing is None:
        _noise_hint(path, t, y, tck, degree)
    return _spline(tck, t, f"{path.name} (degree-{degree} spline{shifted})", degree)


def _spline(tck: tuple, t: FloatArray, name: str, degree: int) -> PolynomialTrajectory:
    """The spline ``tck`` as a trajectory over the samples' times ``t`` (its pieces inside them)."""
    from scipy.interpolate import PPoly  # lazy: keeps `import inversion` fast

    pp = PPoly.from_spline(tck)
    inside = (pp.x[:-1] >= t[0]) & (pp.x[1:] <= t[-1]) & (np.diff(pp.x) > 0)
    x = np.r_[pp.x[:-1][inside], pp.x[1:][inside][-1]]
    return PolynomialTrajectory(PPoly(pp.c[:, inside], x), name, max_derivative=degree)


def from_samples(t: ArrayLike, y: ArrayLike, name: str) -> PolynomialTrajectory:
    """The trajectory through samples (from_csv's spline, s = 0).

    As :func:`from_csv` reads them from a file with ``smoothing=0``: the degree-5 spline through every sample; the samples are kept (``samples``), so that a run writes them as its move's
    CSV and reads the same trajectory back, bit for bit (:func:`inversion.realtime.runs.write_run`).

    Parameters
    ----------
    t, y : array_like
        The times (strictly increasing, at least 7, at most :data:`MAX_SPLINE_SAMPLES`) and the values.
    name : str
        Its description.

    Raises
    ------
    TrajectoryError
        For samples the spline cannot go through.
    """
    from scipy.interpolate import splrep  # lazy: keeps `import inversion` fast

    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if not (t.shape == y.shape and t.ndim == 1 and 7 <= t.size <= MAX_SPLINE_SAMPLES and np.all(np.isfinite(t))
            and np.all(np.isfinite(y)) and np.all(np.diff(t) > 0)):
        raise TrajectoryError("samples", f"{t.size} samples", f"7 to {MAX_SPLINE_SAMPLES} finite samples at strictly increasing times")
    result = _spline(splrep(t, y, k=5, s=0.0), t, name, 5)
    result.samples = (t, y)  # type: ignore[attr-defined]
    return result


def _read_samples(path: Path) -> tuple[FloatArray, FloatArray, str, float]:
    """The ``t`` and ``y`` columns of a CSV with a header (at most :data:`MAX_CSV_ROWS` rows, refused before they fill
    memory), the first time's text where the times were taken from it (``""`` where not) and a double's resolution of
    them.

    Times far from zero keep few digits for the steps between them (near 1e12 s a double resolves 1.2e-4 s; near 1.7e9 s,
    the epoch's, 2.4e-7 s, and a 1 kHz record's spline changed the torque by 1.3 %): where the resolution exceeds 1e-9 of
    the least step, the times are taken from the first sample, subtracted exactly from their text."""
    texts: list[str] = []
    t: list[float] = []
    y: list[float] = []
    try:
        with open(path, newline="", encoding="utf-8-sig") as handle:  # a byte-order mark is no part of the first name
            reader = csv.reader(handle)
            header = [name.strip() for name in next(reader, [])]
            if "t" not in header or "y" not in header:
                raise TrajectoryError("trajectory file", str(path), f"a CSV with a header naming columns t and y (its first line "
                                      f"names {', '.join(repr(h) for h in header[:6]) or 'nothing'})")
            for name in ("t", "y"):
                if header.count(name) > 1:
                    raise TrajectoryError("trajectory file", str(path), f"one column named {name} (the header names it "
                                          f"{header.count(name)} times: which is meant?)")
            it, iy = header.index("t"), header.index("y")
            for number, row in enumerate(reader, 2):
                if not row:
                    continue
                if len(t) >= MAX_CSV_ROWS:
                    raise TrajectoryError("trajectory file", str(path), f"at most {MAX_CSV_ROWS:,} samples (a trajectory needs far "
                                          f"fewer: the spline goes through at most {MAX_SPLINE_SAMPLES:,})")
                try:
                    t.append(float(row[it]))
                    y.append(float(row[iy]))
                    texts.append(row[it].strip())
                except (IndexError, ValueError):
                    raise TrajectoryError("trajectory file", str(path), f"numeric t and y values in every row (line {number}: "
                                          f"{','.join(row)[:60]!r})") from None
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise TrajectoryError("trajectory file", str(path), f"a readable CSV file ({exc.__class__.__name__})") from None
    if not t:
        raise TrajectoryError("trajectory file", str(path), "a CSV with a header naming columns t and y, and rows of samples")
    times = np.array(t)
    steps = np.diff(times)
    resolution = float(np.spacing(np.abs(times).max())) if np.all(np.isfinite(times)) else 0.0
    if times.size > 1 and np.all(steps > 0) and resolution > 1e-9 * float(steps.min()):
        from decimal import Decimal, InvalidOperation

        try:
            first = Decimal(texts[0])
            return np.array([float(Decimal(text) - first) for text in texts]), np.array(y), texts[0], resolution
        except InvalidOperation:
            pass
    return times, np.array(y), "", resolution


def _noise_hint(path: Path, t: FloatArray, y: FloatArray, tck: tuple, degree: int) -> None:
    """Warn when the samples look noisy: interpolated, their noise reaches the acceleration (and the torque).

    The noise is estimated from the third differences (``var(Delta^3 e) = 20 sigma^2`` for white noise); the
    interpolating spline's peak acceleration is compared with a smoothing spline's at ``s = n sigma^2`` (the
    usual choice), and a ratio above 1.5 is reported with the smoothing that removes it.
    """
    from scipy.interpolate import splev, splrep

    if t.size < 8:
        return
    sigma = float(np.sqrt(np.mean(np.diff(y, 3) ** 2) / 20.0))
    if not sigma > 1e-12 * max(float(np.ptp(y)), 1e-300):
        return
    s = t.size * sigma**2
    fine = np.linspace(t[0], t[-1], min(20 * t.size, 200_001))
    raw = float(np.abs(splev(fine, tck, der=2)).max())
    smooth = float(np.abs(splev(fine, splrep(t, y, k=degree, s=s), der=2)).max())
    if raw > 1.5 * smooth:
        from modelgen.errors import warn

        warn(f"{path.name}: the samples look noisy (about {sigma:.2g} rms from the third differences); interpolated, the "
             f"acceleration peaks at {raw:.3g}, {raw / smooth:.3g} x what a smoothing spline gives ({smooth:.3g}), and the torque "
             f"with it: pass a smoothing, trajectory='{path.name}:smoothing={s:.3g}'")


def trajectory_from_spec(spec: str) -> Trajectory:
    """Parse a trajectory specification of the command line.

    ``paper-sim`` (``smoothstep:1.57:5.5:5``), ``paper-exp`` (the experiment's),
    ``smoothstep:DISTANCE:DURATION[:ORDER]`` or the path of a CSV file, optionally with its
    spline's smoothing, ``FILE.csv:smoothing=S`` (:func:`from_csv`).

    Parameters
    ----------
    spec : str
        The specification.

    Raises
    ------
    TrajectoryError
        For anything else.
    """
    accepted = "paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER], or a CSV file of columns t,y (FILE.csv, or FILE.csv:smoothing=S)"
    if spec == "paper-sim":
        return smoothstep(1.57, 5.5, 5)
    if spec == "paper-exp":
        return experiment_trajectory(2.5, 0.6)
    if spec.startswith("smoothstep:"):
        parts = spec.split(":")[1:]
        if len(parts) not in (2, 3):
            raise TrajectoryError("trajectory", spec, accepted)
        try:
            distance, duration = float(parts[0]), float(parts[1])
            order = int(parts[2]) if len(parts) == 3 else 5
        except ValueError:
            raise TrajectoryError("trajectory", spec, accepted) from None
        return smoothstep(distance, duration, order)
    smoothing: float | None = None
    if ":smoothing=" in spec:  # FILE.csv:smoothing=S
        spec, _, value = spec.rpartition(":smoothing=")
        try:
            smoothing = float(value)
        except ValueError:
            raise TrajectoryError("trajectory", f"{spec}:smoothing={value}", "FILE.csv:smoothing=S with a number S >= 0") from None
    if Path(spec).suffix.lower() == ".csv" or _is_file(spec):
        if not _is_file(spec):
            raise TrajectoryError("trajectory", spec, "an existing CSV file")
        result = from_csv(spec, smoothing=smoothing)
        result.spec = str(Path(spec).resolve()) + ("" if smoothing is None else f":smoothing={smoothing!r}")
        return result
    raise TrajectoryError("trajectory", spec, accepted)


def _is_file(path: str) -> bool:
    """Whether ``path`` names an existing file (a name too long for the system, or with a NUL, names none)."""
    try:
        return Path(path).is_file()
    except (OSError, ValueError):
        return False

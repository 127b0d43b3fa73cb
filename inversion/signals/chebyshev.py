"""A solved member's signals as piecewise Chebyshev series: the well-conditioned way to evaluate its closed form.

The closed form of a member (:mod:`inversion.family.ssef`) sums terms such as ``c_j e^{mu_j s}``
whose sizes can exceed their sum by orders of magnitude: the equally spaced exponentials
of Eq. (34)-(36) are nearly dependent, so the coefficients alternate in sign, and an
internal mode whose zero lies among the exponents has particular and complementary parts
that cancel (measured on a link nobody tuned to: ``sum |c_j e^{mu_j s}|`` is 5e4 times
``|yddot~|``, a mode's parts 5e5 times the mode). Any evaluator of the closed form in double
precision is uncertain by ``eps`` times those sums (up to 3.5e-9 of the peak torque there,
:meth:`~inversion.family.redefinition.Redefinition.rounding`), and two evaluators that sum in
different orders disagree by as much.

The signals themselves are smooth on each segment. :func:`inversion.family.series.chebyshev_signals` evaluates the
closed form -- the same double-precision coefficients -- in extended precision
(``numpy.longdouble``: 2048 times finer than double on x86-64) at Chebyshev points and
re-expands each signal in a Chebyshev series on pieces of the segment, halving a piece
until the series' last coefficients fall below ``1e-15`` of the signal's peak, or stop
falling at the rounding of the extended-precision values (a boundary layer of a fast stable
mode gets short pieces near the joint; a smooth segment is one piece). Where
``numpy.longdouble`` is double (Windows, Apple silicon) the series are as accurate as the
closed form in double, no more. Evaluating a series is well conditioned: its rounding is
``eps`` times the signal, not times the terms. The samples of :func:`inversion.invert`
(Chebyshev polynomials by their recurrence, one matrix product per piece) and the exported C
(:mod:`inversion.realtime.feedforward_c`, Clenshaw's recurrence) evaluate the same series, so they agree to
``1e-15``, and both are within the series' truncation and the extended-precision rounding of
the member's exact closed form (``tests/inversion/realtime/test_feedforward_c.py`` measures it).

A stable inversion (:mod:`inversion.methods.stable`) is re-expanded by the same core
(:func:`fit_chebyshev`) from its quadrature and tails, over its whole span.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InversionError

__all__ = ["PiecewiseChebyshev", "fit_chebyshev", "chebyshev_nodes", "held_values", "DEGREE", "TOLERANCE", "LINK_SIGNALS",
           "SYSTEM_SIGNALS"]

FloatArray = NDArray[np.float64]
#: Degree of every piece's series.
DEGREE = 24
#: A piece is halved until its last three Chebyshev coefficients are below this fraction of
#: the signal's peak.
TOLERANCE = 1e-15
#: Deepest halving of a segment (a piece of 2^-40 of it), and most pieces in all.
_MAX_DEPTH = 40
_MAX_PIECES = 20_000


@dataclass(frozen=True)
class PiecewiseChebyshev:
    """Signals on a span as Chebyshev series on its pieces.

    Signals on a span (a member's segments, or a stable inversion's intervals) as Chebyshev series on pieces of them.

    Attributes
    ----------
    names : tuple of str
        The signals (``tau, theta_d, thetadot_d`` for a link; ``u`` for a generic system).
    bounds : ndarray, shape (K+1,)
        The segments' joints ``t_0 .. t_K`` (s).
    piece_start : ndarray of int, shape (K+1,)
        The pieces of segment ``k``: ``piece_start[k] .. piece_start[k+1]``.
    edges : ndarray, shape (P+K,)
        Local times (s, from the segment's start) where the pieces of each segment begin,
        then the segment's duration: piece ``p`` of segment ``k`` spans
        ``[edges[p + k], edges[p + k + 1]]``.
    coefficients : ndarray, shape (P, S, DEGREE + 1)
        The series of each signal on each piece, in ``x = (2 s - a - b)/(b - a)``.
    peaks : ndarray, shape (S,)
        The signals' largest magnitudes at the Chebyshev points.
    tail : float
        The largest of the pieces' last coefficients, relative to the peaks (``1e-15``, or
        the rounding of the closed form in extended precision where that is larger).
    """

    names: tuple[str, ...]
    bounds: FloatArray
    piece_start: NDArray[np.intp]
    edges: FloatArray
    coefficients: FloatArray
    peaks: FloatArray
    tail: float = 0.0

    @property
    def pieces(self) -> int:
        """Number of pieces over all segments."""
        return int(self.coefficients.shape[0])

    def locate(self, t: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.intp], FloatArray]:
        """Segment, piece and local time of each time.

        Segment, piece and local time ``s = t - t_k`` of each time (clipped to the span).

        Parameters
        ----------
        t : ArrayLike
            Times (s).
        """
        t = np.asarray(t, dtype=float)
        K = self.bounds.size - 1
        k = np.clip(np.searchsorted(self.bounds, t, side="right") - 1, 0, K - 1)
        s = np.clip(t - self.bounds[k], 0.0, self.bounds[k + 1] - self.bounds[k])
        first = self.piece_start[k]
        count = self.piece_start[k + 1] - first
        p = first.copy()
        for step in range(1, int(count.max(initial=1))):  # pieces per segment are few: a linear scan
            later = (step < count) & (s >= self.edges[np.minimum(first + k + step, self.edges.size - 1)])
            p = np.where(later, first + step, p)
        return k, p, s

    def evaluate(self, t: ArrayLike, chunk: int = 8192, derivative: int = 0) -> dict[str, FloatArray]:
        """Every signal at the times ``t``, or a derivative of it.

        Every signal at the times ``t`` (clipped to the span), or its ``derivative``-th time derivative.

        The samples of each piece, in chunks of ``chunk`` that stay in cache, form the
        Chebyshev polynomials by their recurrence and meet the piece's coefficients in one
        matrix product: what Clenshaw's recurrence (the exported C's) computes, to rounding.
        A derivative is the series of the derivative (exact: ``chebder``), scaled to time.

        Parameters
        ----------
        t : ArrayLike
            Times (s).
        chunk : int, optional
            Samples evaluated at once.
        derivative : int, optional
            The derivative's order.
        """
        k, p, s = self.locate(t)
        a, b = self.edges[p + k], self.edges[p + k + 1]
        x = np.atleast_1d((2.0 * s - a - b) / (b - a))
        coefficients = self.coefficients if derivative == 0 else self._derived(derivative)
        out = _series_values(coefficients, np.atleast_1d(p), x, chunk)
        return {name: out[m].reshape(np.shape(s)) for m, name in enumerate(self.names)}

    def _derived(self, order: int) -> FloatArray:
        """Coefficients of the ``order``-th time derivative on every piece (padded to the same degree; kept)."""
        cache: dict[int, FloatArray] = self.__dict__.setdefault("_derivatives", {})
        if order not in cache:
            from numpy.polynomial import chebyshev as C

            widths = np.diff(self.edges)[self._piece_edges()]  # b - a of each piece
            derived = C.chebder(self.coefficients, m=order, axis=2) * (2.0 / widths[:, None, None]) ** order
            cache[order] = np.concatenate([derived, np.zeros(derived.shape[:2] + (order,))], axis=2)
        return cache[order]

    def _piece_edges(self) -> NDArray[np.intp]:
        """For each piece, the index of its start in :attr:`edges` (piece ``p`` of segment ``k`` starts at ``p + k``)."""
        K = self.bounds.size - 1
        segment = np.repeat(np.arange(K), np.diff(self.piece_start))
        return np.arange(self.pieces) + segment

    def primitive(self, signal: int = 0) -> tuple[FloatArray, FloatArray]:
        """The series of one signal's integral on every piece.

        The series of the integral of one signal on every piece (zero at its start; shape (P, DEGREE + 2)) and
        the integral from the span's start to each piece's start and to its end (shape (P + 1,)).

        Parameters
        ----------
        signal : int, optional
            The signal's index.
        """
        from numpy.polynomial import chebyshev as C

        widths = np.diff(self.edges)[self._piece_edges()]
        primitive = C.chebint(self.coefficients[:, signal, :], lbnd=-1, axis=1) * (widths[:, None] / 2)
        totals = C.chebval(1.0, primitive.T)
        return primitive, np.concatenate([[0.0], np.cumsum(totals)])

    def integral(self, t: ArrayLike, before: ArrayLike | None = None, after: ArrayLike | None = None) -> dict[str, FloatArray]:
        """``int_{t_0}^{t}`` of every signal (exact).

        ``int_{t_0}^{t}`` of every signal (exact: the series integrate to series of one degree more).

        Outside the span the signals are held at the constants ``before`` and ``after`` (per
        signal; default zero): the integral goes on linearly there.

        Parameters
        ----------
        t : ArrayLike
            Times (s).
        before : ArrayLike | None, optional
            Each signal's value before the span (default zero).
        after : ArrayLike | None, optional
            Each signal's value after it (default zero).
        """
        from numpy.polynomial import chebyshev as C

        t = np.atleast_1d(np.asarray(t, dtype=float))
        S = len(self.names)
        lo, hi = float(self.bounds[0]), float(self.bounds[-1])
        widths = np.diff(self.edges)[self._piece_edges()]
        primitive = C.chebint(self.coefficients, lbnd=-1, axis=2) * (widths[:, None, None] / 2)  # zero at each piece's start
        totals = C.chebval(1.0, np.moveaxis(primitive, 2, 0))  # (P, S): each piece's integral
        start = np.vstack([np.zeros((1, S)), np.cumsum(totals, axis=0)])  # the integral up to each piece
        k, p, s = self.locate(t)
        a, b = self.edges[p + k], self.edges[p + k + 1]
        x = (2.0 * s - a - b) / (b - a)
        out = start[p].T + _series_values(primitive, p, x, 8192)
        first = np.zeros(S) if before is None else np.asarray(before, dtype=float).reshape(S)
        last = np.zeros(S) if after is None else np.asarray(after, dtype=float).reshape(S)
        early, late = t < lo, t > hi
        out[:, early] = first[:, None] * (t[early] - lo)[None, :]
        out[:, late] = start[-1][:, None] + last[:, None] * (t[late] - hi)[None, :]
        return {name: out[m] for m, name in enumerate(self.names)}

    def means(self, edges: ArrayLike, before: ArrayLike | None = None, after: ArrayLike | None = None) -> dict[str, FloatArray]:
        """Every signal's mean over each interval.

        Every signal's mean over the intervals ``[edges[i], edges[i+1]]``: the value a zero-order hold applies.

        The mean of a period matches the zeroth moment of the plant's response to it (the
        convolution with ``e^{A (t_{k+1} - s)} B``), where the signal's value at the period's
        start lags it by half a period (docs/method.md section 4b). ``before``, ``after``: the
        signals outside the span (:meth:`integral`).

        Parameters
        ----------
        edges : ArrayLike
            The intervals' edges (s), increasing.
        before : ArrayLike | None, optional
            Each signal's value before the span (default zero).
        after : ArrayLike | None, optional
            Each signal's value after it (default zero).
        """
        edges = np.asarray(edges, dtype=float)
        F = self.integral(edges, before, after)
        width = np.diff(edges)
        return {name: np.diff(values) / width for name, values in F.items()}


#: Below this many points a piece on average, :func:`_series_values` takes every point at once rather than piece by
#: piece (a held table of 690 rows, its references' series with it: 17 ms an evaluation piece by piece, Python's loop).
_FEW_POINTS = 32


def _series_values(coefficients: FloatArray, p: NDArray[np.intp], x: FloatArray, chunk: int) -> FloatArray:
    """``sum_j coefficients[p_i, :, j] T_j(x_i)`` for every point, shape (signals, points): the points of each
    piece, in chunks, form the Chebyshev polynomials by their recurrence and meet the coefficients in one product --
    or, where the pieces are many and their points few (:data:`_FEW_POINTS`), each point meets its own piece's."""
    out = np.empty((coefficients.shape[1], x.size))
    order = np.argsort(p, kind="stable")
    runs = np.flatnonzero(np.diff(p[order])) + 1
    degree = coefficients.shape[2] - 1
    if x.size < _FEW_POINTS * (runs.size + 1):  # many pieces of few points each (a held table's): every point at once
        for lo in range(0, x.size, chunk):
            part = slice(lo, min(lo + chunk, x.size))
            out[:, part] = np.einsum("psj,jp->sp", coefficients[p[part]], _polynomials(x[part], degree))
        return out
    for run in np.split(order, runs):
        if run.size == 0:
            continue
        piece = coefficients[p[run[0]]]  # (S, D + 1)
        contiguous = run[-1] - run[0] + 1 == run.size  # sorted times: one slice of the samples
        for lo in range(0, run.size, chunk):
            at = slice(run[0] + lo, run[0] + min(lo + chunk, run.size)) if contiguous else run[lo : lo + chunk]
            out[:, at] = piece @ _polynomials(x[at], degree)
    return out


def _polynomials(x: FloatArray, degree: int) -> FloatArray:
    """``T_0(x) .. T_degree(x)`` by their recurrence, shape (degree + 1, points)."""
    T = np.empty((degree + 1, x.size))
    T[0] = 1.0
    if degree:
        T[1] = x
    for j in range(2, degree + 1):
        T[j] = 2.0 * x * T[j - 1] - T[j - 2]
    return T


def _clenshaw(c: FloatArray, x: FloatArray) -> FloatArray:
    """``sum_k c[..., k] T_k(x)`` (the order the exported C follows)."""
    b1 = np.zeros_like(x)
    b2 = np.zeros_like(x)
    for j in range(c.shape[-1] - 1, 0, -1):
        b1, b2 = 2.0 * x * b1 - b2 + c[..., j], b1
    return x * b1 - b2 + c[..., 0]


def chebyshev_nodes(degree: int) -> NDArray[Any]:
    """Chebyshev points of the first kind in extended precision.

    Parameters
    ----------
    degree : int
        The series' degree ``n - 1``.

    Returns
    -------
    ndarray of longdouble
        ``cos((j + 1/2) pi / n)``, ``j = 0 .. n - 1``.
    """
    n = degree + 1
    pi = np.longdouble(4) * np.arctan(np.longdouble(1))
    return np.cos((np.arange(n, dtype=np.longdouble) + np.longdouble(0.5)) * pi / n)


def _coefficients(values: NDArray[Any]) -> NDArray[Any]:
    """Chebyshev coefficients of values at :func:`chebyshev_nodes` (last axis), in their precision.

    ``c_k = (2 / n) sum_j f_j cos(k (j + 1/2) pi / n)``, ``c_0`` halved: a type-II DCT,
    :func:`scipy.fft.dct` (pocketfft, in extended precision for ``numpy.longdouble``; more
    accurate than the cosine matrix's product, 1.2e-19 against 1.6e-18 of unit values).
    """
    from scipy.fft import dct  # lazy: keeps `import inversion` fast

    n = values.shape[-1]
    out = dct(values, type=2, axis=-1)
    out /= n
    out[..., 0] /= 2
    return out


def fit_chebyshev(
    names: tuple[str, ...], bounds: FloatArray, evaluate: Callable[[NDArray[np.intp], NDArray[Any]], NDArray[Any]],
    noise: Callable[[FloatArray], FloatArray] | None = None, degree: int = DEGREE, tolerance: float = TOLERANCE,
) -> PiecewiseChebyshev:
    """Piecewise Chebyshev series of signals (module docstring).

    Piecewise Chebyshev series of signals on the intervals ``bounds`` (module docstring).

    Parameters
    ----------
    names : tuple of str
        The signals' names.
    bounds : ndarray, shape (K+1,)
        The intervals (segments; the signals may jump or kink between them).
    evaluate : callable
        ``evaluate(k, s) -> values`` of shape ``(P, S, n)``: the signals at local times
        ``s`` (shape ``(P, n)``, extended precision) of the intervals ``k``.
    noise : callable, optional
        ``noise(peaks)``: per signal, the largest tail a piece may stop at when halving no
        longer lowers it (the rounding of ``evaluate``); default ``1e3 * tolerance``.
    degree, tolerance :
        The series' degree; the halving stops when the last three coefficients are below
        ``tolerance`` times the signal's peak.

    Raises
    ------
    InversionError
        When the series do not converge (more than 20 000 pieces).
    """
    ld = np.dtype(np.longdouble)
    bounds = np.asarray(bounds, dtype=float)
    K = bounds.size - 1
    durations = np.diff(bounds)
    x = chebyshev_nodes(degree)

    def series(k: NDArray[np.intp], a: FloatArray, b: FloatArray) -> tuple[NDArray[Any], FloatArray]:
        """Coefficients (pieces, signals, degree + 1) of the pieces ``[a, b]`` of intervals ``k``, and
        each signal's largest magnitude at their points."""
        half, mid = (b.astype(ld) - a.astype(ld)) / 2, (b.astype(ld) + a.astype(ld)) / 2
        out = np.asarray(evaluate(k, mid[:, None] + half[:, None] * x[None, :]))  # (P, S, n)
        return _coefficients(out), np.abs(out).max(axis=(0, 2)).astype(float)

    # one piece per interval first: the peaks the tolerance is relative to
    pieces: list[list[tuple[float, float, NDArray[Any]]]] = [[] for _ in range(K)]
    k = np.arange(K)
    a, b = np.zeros(K), durations.copy()
    coefficients, peaks = series(k, a, b)
    peaks = np.maximum(peaks, np.finfo(float).tiny)
    floor = np.full(len(names), 1e3 * tolerance) if noise is None else noise(peaks)
    parent = np.full(K, np.inf)
    worst = 0.0
    for _ in range(_MAX_DEPTH):
        tail = np.abs(coefficients[:, :, -3:]).max(axis=2).astype(float) / peaks  # (P, S)
        # converged; or at the rounding of the values, where halving no longer helps
        stalled = np.all(tail <= floor, axis=1) & (tail.max(axis=1) > parent / 4)
        done = np.all(tail <= tolerance, axis=1) | stalled
        for q in np.flatnonzero(done):
            pieces[k[q]].append((float(a[q]), float(b[q]), coefficients[q]))
        worst = max(worst, float(tail[done].max(initial=0.0)))
        if np.all(done):
            break
        k, a, b, parent = k[~done], a[~done], b[~done], np.repeat(tail[~done].max(axis=1), 2)
        if 2 * k.size > _MAX_PIECES:
            raise InversionError(f"the Chebyshev re-expansion of the member needs more than {_MAX_PIECES} pieces "
                                 f"(series tails up to {tail.max():.1e} of the peaks)")
        middle = (a + b) / 2
        k, a, b = np.repeat(k, 2), np.column_stack([a, middle]).ravel(), np.column_stack([middle, b]).ravel()
        coefficients = series(k, a, b)[0]
    else:
        raise InversionError(f"the Chebyshev re-expansion of the member did not converge in {_MAX_DEPTH} halvings")
    piece_start = [0]
    edges: list[float] = []
    blocks = []
    for seg in range(K):
        ordered = sorted(pieces[seg], key=lambda item: item[0])
        edges += [start for start, _, _ in ordered] + [float(durations[seg])]
        blocks += [c for _, _, c in ordered]
        piece_start.append(piece_start[-1] + len(ordered))
    return PiecewiseChebyshev(
        names=names,
        bounds=bounds,
        piece_start=np.asarray(piece_start, dtype=np.intp),
        edges=np.asarray(edges, dtype=float),
        coefficients=np.asarray(np.stack(blocks), dtype=float),
        peaks=peaks,
        tail=worst,
    )


#: The signals of a link's feedforward: the torque and the joint references of the PD law.
LINK_SIGNALS = ("tau", "theta_d", "thetadot_d")
#: The signal of a generic system's feedforward: its input.
SYSTEM_SIGNALS = ("u",)


def held_values(names: tuple[str, ...], t0: float, period: float, values: FloatArray) -> PiecewiseChebyshev:
    """Held values as piecewise Chebyshev series.

    One constant a period.

    Parameters
    ----------
    names : tuple of str
        The signals.
    t0, period : float
        The first period's start and the period (s).
    values : ndarray, shape (K, S)
        Each period's values.
    """
    K, S = values.shape
    bounds = t0 + np.arange(K + 1) * period
    coefficients = np.zeros((K, S, DEGREE + 1))
    coefficients[:, :, 0] = values
    edges = np.column_stack([np.zeros(K), np.full(K, period)]).ravel()
    return PiecewiseChebyshev(names=names, bounds=bounds, piece_start=np.arange(K + 1, dtype=np.intp), edges=edges,
                              coefficients=coefficients, peaks=np.maximum(np.abs(values).max(axis=0), np.finfo(float).tiny))


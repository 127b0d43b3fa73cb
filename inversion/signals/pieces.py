"""A piecewise polynomial evaluated with NumPy alone: what a smoothstep move needs of SciPy's ``PPoly``.

:class:`scipy.interpolate.PPoly` is the reference for piecewise polynomials, and every spline and re-planned move is one.
Importing ``scipy.interpolate`` costs about 0.15 s (it brings ``scipy.optimize``, ``scipy.special`` and
``scipy.spatial``), a quarter of one ``sflm invert paper-sim`` run (``python -X importtime -m sflm.cli invert
paper-sim``), and a smoothstep move needs nothing of it but the evaluation and the derivative. :class:`Pieces` is that
part, with ``PPoly``'s layout and its arithmetic in the same order, so that its values are ``PPoly``'s bit for bit
(``tests/inversion/signals/test_pieces.py``):

* ``c[m, i]`` is the coefficient of ``(t - x[i])^(k - m)`` on ``[x[i], x[i + 1])``, ``k = c.shape[0] - 1``;
* a time is in the piece whose left end it reaches (right-continuous at a breakpoint, the last piece closed), and
  outside ``[x[0], x[-1]]`` the first or last piece is extended (``PPoly``'s ``extrapolate=True``);
* a value is ``sum_j c[k - j, i] s^j`` with ``s^j`` built up by products, as ``PPoly``'s ``evaluate_poly1``;
* the derivative's coefficients are the coefficients times the falling factorials, as ``PPoly.derivative``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Pieces"]

FloatArray = NDArray[np.float64]

#: Up to this many times a call is evaluated in whole ``(powers, times)`` arrays (fewer calls); above it, power by power
#: (a cumulative product across the short axis of a wide array is slow): the same values either way.
_FEW = 64


class Pieces:
    """A piecewise polynomial in ``PPoly``'s layout.

    ``y(t)`` as polynomials on the intervals between breakpoints, as :class:`scipy.interpolate.PPoly` holds it.

    Parameters
    ----------
    c : array_like, shape (k + 1, m)
        The coefficients, highest power first: ``c[j, i]`` multiplies ``(t - x[i])^(k - j)``.
    x : array_like, shape (m + 1,)
        The breakpoints, increasing.
    """

    def __init__(self, c: ArrayLike, x: ArrayLike):
        self.c = np.array(c, dtype=float, ndmin=2)
        self.x = np.array(x, dtype=float)
        if self.x.ndim != 1 or self.c.ndim != 2 or self.x.size != self.c.shape[1] + 1 or self.x.size < 2:
            raise ValueError(f"coefficients of shape (k + 1, m) and m + 1 breakpoints expected: shapes {self.c.shape}, "
                             f"{self.x.shape}")
        if not np.all(np.diff(self.x) >= 0):
            raise ValueError("breakpoints in increasing order expected")

    def __call__(self, t: ArrayLike) -> FloatArray:
        """The values at ``t`` (any shape), as ``PPoly.__call__`` gives them."""
        t = np.asarray(t, dtype=float)
        degree = self.c.shape[0] - 1
        flat = t.reshape(-1)
        if self.c.shape[1] == 1:  # one piece (a smoothstep): no search
            s = flat - self.x[0]
            coef = self.c[::-1, :]  # the lowest power first, broadcast over the times
        else:
            piece = np.clip(np.searchsorted(self.x, flat, side="right") - 1, 0, self.c.shape[1] - 1)
            s = flat - self.x[piece]
            coef = self.c[::-1, piece]
        # PPoly's order: s^j a running product, the terms added lowest power first
        if flat.size > _FEW:
            value = np.zeros(flat.size)
            power = np.ones(flat.size)
            for j in range(degree + 1):
                value += coef[j] * power
                if j < degree:
                    power *= s
            return value.reshape(t.shape)
        # few times: in whole arrays, cumprod and cumsum being sequential as the loop (a pairwise sum would differ in the
        # last bit), a few calls instead of three per power
        powers = np.empty((degree + 1, flat.size))
        powers[0] = 1.0
        if degree:
            np.cumprod(np.broadcast_to(s, (degree, flat.size)), axis=0, out=powers[1:])
        return np.cumsum(coef * powers, axis=0)[-1].reshape(t.shape)

    def derivative(self, nu: int = 1) -> Pieces:
        """The ``nu``-th derivative.

        A constant zero piece where ``nu`` exceeds the degree.

        Parameters
        ----------
        nu : int
            The order (``0``: a copy).
        """
        if nu == 0:
            return Pieces(self.c.copy(), self.x)
        rows = self.c.shape[0] - nu
        if rows <= 0:
            return Pieces(np.zeros((1, self.c.shape[1])), self.x)
        factor = np.array([float(math.perm(power, nu)) for power in range(rows + nu - 1, nu - 1, -1)])
        return Pieces(self.c[:rows] * factor[:, None], self.x)

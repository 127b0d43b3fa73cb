"""Cancellation-free kernels of the closed-form solution (docs/method.md, section 2).

Integrals of ``exp(mu s)`` have removable singularities at ``mu = 0`` and at
``mu = lambda``; evaluated naively they lose every digit there. These functions keep
full relative accuracy through the limits.

Every kernel works in the precision of its input: ``float64`` (the working precision)
or ``numpy.longdouble`` (used to re-evaluate a result in extended precision, see
:mod:`inversion.family.verify`); complex inputs give ``complex128`` or ``clongdouble``.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["phi1", "phi2", "exp_integrals", "exp_difference", "real_dtype", "complex_dtype"]

#: Below this ``|x|`` the kernels use their Taylor series, with as many terms as the
#: precision needs (:func:`_terms`: 11 for float64, at most ``_TERMS``, whose truncation
#: 0.2^20/21! ~ 2e-34 is below the rounding of every supported precision); above it the
#: direct formula loses at most ~eps/0.2 relative.
_SERIES = 0.2
_TERMS = 20


def real_dtype(*arrays: Any) -> np.dtype[Any]:
    """``longdouble`` if any input is extended precision, else float64."""
    extended = any(np.asarray(a).dtype in (np.dtype(np.longdouble), np.dtype(np.clongdouble)) for a in arrays)
    return np.dtype(np.longdouble) if extended and np.dtype(np.longdouble) != np.dtype(np.float64) else np.dtype(np.float64)


def complex_dtype(*arrays: Any) -> np.dtype[Any]:
    """The complex type of the precision of :func:`real_dtype`."""
    return np.dtype(np.clongdouble) if real_dtype(*arrays) == np.dtype(np.longdouble) else np.dtype(np.complex128)


@lru_cache(maxsize=None)
def _terms(dtype: np.dtype[Any]) -> int:
    """Series terms that reach the rounding of ``dtype`` for ``|x| < _SERIES``: 11 for ``float64``."""
    eps = float(np.finfo(dtype).eps) / 4
    k = 1
    while _SERIES**k / math.factorial(k + 1) >= eps and k < _TERMS:
        k += 1
    return k


@lru_cache(maxsize=None)
def _inverse_factorials(dtype: np.dtype[Any]) -> NDArray[Any]:
    """``1/k!`` for ``k = 0 .. _TERMS + 2``, rounded once in ``dtype``."""
    one = dtype.type(1)
    return np.array([one / dtype.type(math.factorial(k)) for k in range(_TERMS + 3)], dtype=dtype)


def phi1(x: ArrayLike) -> NDArray[Any]:
    """``(e^x - 1)/x``, 1 at ``x = 0``.

    ``(e^x - 1)/x``, 1 at ``x = 0`` (so ``s phi1(mu s) = int_0^s e^(mu u) du``).

    Parameters
    ----------
    x : ArrayLike
        A real or complex array (its precision is kept).
    """
    return exp_integrals(np.asarray(x))[1]


def phi2(x: ArrayLike) -> NDArray[Any]:
    """``(e^x - 1 - x)/x^2``, 1/2 at ``x = 0``.

    ``(e^x - 1 - x)/x^2``, 1/2 at ``x = 0`` (``s^2 phi2(mu s)`` is the double integral).

    Parameters
    ----------
    x : ArrayLike
        A real or complex array (its precision is kept).
    """
    return exp_integrals(np.asarray(x))[2]


def exp_integrals(x: ArrayLike) -> tuple[NDArray[Any], NDArray[Any], NDArray[Any]]:
    """``e^x``, ``phi1`` and ``phi2`` of an array, sharing one exp.

    Faster than the three separately (``exp`` is vectorised, ``expm1`` is not); relative
    accuracy ~1e-15 in double precision (the series is used below ``|x| = 0.2``, where the
    direct forms cancel). The precision follows the input (``float64`` or ``longdouble``; a complex input gives
    ``complex128`` or ``clongdouble``).

    Parameters
    ----------
    x : ArrayLike
        A real or complex array.
    """
    dtype = complex_dtype(x) if np.iscomplexobj(x) else real_dtype(x)
    x = np.asarray(x, dtype=dtype)
    E = np.exp(x)
    small = np.abs(x) < _SERIES
    with np.errstate(divide="ignore", invalid="ignore"):
        p1 = (E - 1) / x  # |x| >= 0.2: E - 1 loses at most ~5 ulp
        p2 = (p1 - 1) / x
    zero = x == 0  # the constant term of Cdec_s = 1: exact limits
    p1[zero] = 1
    p2[zero] = dtype.type(1) / 2
    small &= ~zero
    if np.any(small):
        inv = _inverse_factorials(dtype)
        xs = x[small]
        top = _terms(dtype)  # Horner over k = 0..top: p1 = sum x^k/(k+1)!, p2 = sum x^k/(k+2)!
        s1 = np.full(xs.shape, inv[top + 1], dtype=dtype)
        s2 = np.full(xs.shape, inv[top + 2], dtype=dtype)
        for k in range(top - 1, -1, -1):
            s1 *= xs
            s1 += inv[k + 1]
            s2 *= xs
            s2 += inv[k + 2]
        p1[small] = s1
        p2[small] = s2
    return E, p1, p2


def exp_difference(a: ArrayLike, b: ArrayLike, s: ArrayLike) -> NDArray[Any]:
    """``(e^(a s) - e^(b s)) / (a - b)``, complex allowed.

    ``(e^(a s) - e^(b s)) / (a - b)``, ``s e^(b s)`` when ``a = b`` (complex allowed).

    Parameters
    ----------
    a, b, s : array_like
        Broadcast together; ``Re a, Re b <= 0`` keeps every exponential bounded. The
        precision follows the inputs (``complex128`` or ``clongdouble``).
    """
    cdtype = complex_dtype(a, b, s)
    a = np.asarray(a, dtype=cdtype)
    b = np.asarray(b, dtype=cdtype)
    s = np.asarray(s, dtype=cdtype.type(0).real.dtype)
    a, b, s = np.broadcast_arrays(a, b, s)
    w = (a - b) * s
    out = np.empty(w.shape, dtype=cdtype)
    small = np.abs(w) < _SERIES
    if np.any(small):
        inv = _inverse_factorials(s.dtype)
        ws = w[small]
        series = np.zeros_like(ws)
        for k in range(_terms(s.dtype) - 1, -1, -1):  # (e^w - 1)/w = sum_k w^k/(k+1)!
            series = series * ws + inv[k + 1]
        out[small] = s[small] * np.exp(b[small] * s[small]) * series
    big = ~small
    out[big] = (np.exp(a[big] * s[big]) - np.exp(b[big] * s[big])) / (a[big] - b[big])
    return out

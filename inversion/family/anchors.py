"""The internal state that tracks the desired output exactly: anchors of the ``anchored`` joining.

For an unstable zero ``lambda`` (``Re lambda >= 0``), the modal internal state that keeps
``y = y_d`` exactly and ends at rest is the bounded solution of
``zdot = lambda z + beta yddot_d``, integrated backwards from the end of the manoeuvre
(the trajectory is at rest after ``t_f``)::

    z*(t) = -beta int_t^{t_f} exp(lambda (t - s)) yddot_d(s) ds,      z*(t_f) = 0.

It is the non-causal (stable-inversion) value of the mode; for a purely imaginary zero it is
a finite integral because ``yddot_d`` vanishes after ``t_f``. The ``anchored`` joining
(:mod:`inversion.family.ssef`) makes every segment start and end its unstable modes on ``z*``,
so the segments do not pass an unstable state to each other, and ``y_d`` itself satisfies
the conditions of every interior segment.

``z*`` at the joints is computed by the backward recurrence
``z*(t_k) = exp(-lambda T_k) z*(t_{k+1}) - beta int_0^{T_k} exp(-lambda u) yddot_d(t_k + u) du``
(stable for ``Re lambda >= 0``), the integrals by composite Gauss-Legendre quadrature on
panels short enough for the exponential (at most 20 e-folds or radians each), split at the
trajectory's breakpoints and cut where the weight falls below ``exp(-45)``.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..lti.internal import ModalInternalDynamics
from ..signals.trajectory import Trajectory

__all__ = ["exponential_moments", "tracking_anchors"]

ComplexArray = NDArray[np.complex128]
FloatArray = NDArray[np.float64]

#: Gauss-Legendre order of one panel; with at most ``_PANEL`` e-folds/radians per panel the
#: exponential and a polynomial trajectory of degree <= 23 are integrated to rounding.
_ORDER = 24
_PANEL = 20.0
#: The weight ``exp(-Re(lambda) u)`` is dropped beyond ``u = _CUT / Re(lambda)``.
_CUT = 45.0
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(_ORDER)


def _panels(length: float, rate: complex, cuts: list[float]) -> FloatArray:
    """Panel edges on ``[0, length]`` for the weight ``exp(-rate u)``, honouring ``cuts``."""
    top = length
    if rate.real > 0:
        top = min(length, _CUT / rate.real)
    pieces = [c for c in cuts if 0.0 < c < top]
    edges = [0.0, *pieces, top]
    out: list[float] = [0.0]
    for lo, hi in zip(edges[:-1], edges[1:]):
        count = max(1, math.ceil(abs(rate) * (hi - lo) / _PANEL))
        out += list(lo + (hi - lo) * np.arange(1, count + 1) / count)
    return np.asarray(out)


def exponential_moments(
    trajectory: Trajectory, start: float, end: float, rates: ComplexArray, order: int = 2
) -> ComplexArray:
    """Exponential moments of ``y_d``'s derivatives over a segment.

    ``int_0^T exp(-rate u) y_d^(order)(start + u) du`` for each rate, ``T = end - start``.

    Parameters
    ----------
    trajectory : Trajectory
        The desired trajectory.
    start, end : float
        The interval (s).
    rates : ndarray of complex
        The exponents; ``Re rate >= 0`` is where the quadrature is cut short, any other
        value is integrated over the whole interval.
    order : int
        Derivative of ``y_d`` integrated (2: the acceleration).

    Returns
    -------
    ndarray of complex, shape of ``rates``
    """
    rates = np.asarray(rates, dtype=complex).reshape(-1)
    length = end - start
    cuts = [b - start for b in trajectory.breakpoints if start < b < end]
    nodes: list[FloatArray] = []
    weights: list[FloatArray] = []
    owner: list[NDArray[np.intp]] = []
    for i, rate in enumerate(rates):
        edges = _panels(length, complex(rate), cuts)
        mid = 0.5 * (edges[1:] + edges[:-1])
        half = 0.5 * np.diff(edges)
        u = (mid[:, None] + half[:, None] * _NODES[None, :]).ravel()
        nodes.append(u)
        weights.append((half[:, None] * _WEIGHTS[None, :]).ravel())
        owner.append(np.full(u.size, i, dtype=np.intp))
    u_all = np.concatenate(nodes)
    values = trajectory.derivative(start + u_all, order)  # nodes never sit on a breakpoint
    w_all = np.concatenate(weights) * values
    rate_all = rates[np.concatenate(owner)]
    terms = w_all * np.exp(-rate_all * u_all)
    return np.bincount(np.concatenate(owner), weights=terms.real, minlength=rates.size) + 1j * np.bincount(
        np.concatenate(owner), weights=terms.imag, minlength=rates.size
    )


def tracking_anchors(modal: ModalInternalDynamics, trajectory: Trajectory, bounds: FloatArray) -> ComplexArray:
    """``z*`` of the unstable modes at every joint.

    ``z*`` of the unstable modes at every joint (zero for the stable modes).

    Parameters
    ----------
    modal : ModalInternalDynamics
        The diagonalised internal dynamics (its unstable set).
    trajectory : Trajectory
        The desired trajectory (at rest after its end).
    bounds : ndarray
        The joints ``t_0 .. t_K``.

    Returns
    -------
    ndarray of complex, shape (K + 1, 2n)
        ``z*(t_k)``; the last row is zero (rest after ``t_f``).
    """
    unstable = np.flatnonzero(modal.unstable)
    out = np.zeros((bounds.size, modal.lam.size), dtype=complex)
    if unstable.size == 0:
        return out
    lam = modal.lam[unstable]
    beta = modal.beta[unstable]
    z = np.zeros(unstable.size, dtype=complex)
    for k in range(bounds.size - 2, -1, -1):
        duration = float(bounds[k + 1] - bounds[k])
        moments = exponential_moments(trajectory, float(bounds[k]), float(bounds[k + 1]), lam)
        z = np.exp(-lam * duration) * z - beta * moments
        out[k, unstable] = z
    return out

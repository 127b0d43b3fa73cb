"""The linear plant driven exactly: a zero-order hold of held samples, a quintic Hermite hold of a smooth input.

Both use the exact discretisation of ``Xdot = A X + B u`` over a step ``d``: the matrix
exponential of the plant augmented with the input's own dynamics.

* :func:`zero_order_hold` -- ``A_d = e^{A d}``, ``B_d = int_0^d e^{A s} ds B`` (one exponential
  of ``[[A, B], [0, 0]] d``): the plant as a digital controller drives it, each sample held
  for a period; :func:`run_held` steps it.
* :func:`run_smooth` -- between consecutive points the input is the quintic Hermite
  polynomial of its values, slopes and curvatures at both ends (an error of
  ``O(d^6 u^(6))``), exactly discretised with the chain of its derivatives as extra states.

No ODE solver is involved: the plant's own dynamics, however stiff, are exact.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["zero_order_hold", "run_held", "run_smooth"]

FloatArray = NDArray[np.float64]


def zero_order_hold(A: ArrayLike, B: ArrayLike, step: float) -> tuple[FloatArray, FloatArray]:
    """``(A_d, B_d)`` of the plant held over ``step`` (s).

    Examples
    --------
    >>> Ad, Bd = zero_order_hold([[0.0, 1.0], [0.0, 0.0]], [0.0, 1.0], 0.1)  # a double integrator
    >>> Ad.round(12).tolist(), Bd.round(12).tolist()
    ([[1.0, 0.1], [0.0, 1.0]], [0.005, 0.1])
    """
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    A = np.asarray(A, dtype=float)
    B = np.asarray(B, dtype=float).reshape(-1)
    N = A.shape[0]
    M = np.zeros((N + 1, N + 1))
    M[:N, :N], M[:N, N] = A * step, B * step
    E = sla.expm(M)
    return E[:N, :N], E[:N, N]


def run_held(Ad: FloatArray, Bd: FloatArray, x0: ArrayLike, u: ArrayLike) -> FloatArray:
    """The states ``x_0 .. x_K`` of ``x_{k+1} = A_d x_k + B_d u_k`` (shape (K+1, N))."""
    u = np.asarray(u, dtype=float).reshape(-1)
    x = np.asarray(x0, dtype=float).reshape(-1).copy()
    states = np.empty((u.size + 1, x.size))
    states[0] = x
    forced = np.outer(u, Bd)
    for k in range(u.size):
        x = Ad @ x + forced[k]
        states[k + 1] = x
    return states


@functools.lru_cache(maxsize=256)
def _quintic_step(A_bytes: bytes, B_bytes: bytes, N: int, d: float) -> tuple[FloatArray, FloatArray]:
    """``e^{A d}`` and the map from the quintic hold's coefficients to the state: one exponential of the
    plant augmented with the chain of the input's derivatives (kept: intervals of equal steps share it)."""
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    A = np.frombuffer(A_bytes).reshape(N, N)
    B = np.frombuffer(B_bytes)
    M = np.zeros((N + 6, N + 6))
    M[:N, :N] = A * d
    M[:N, N] = B * d
    for p in range(5):
        M[N + p, N + p + 1] = 1.0
    E = sla.expm(M)
    return E[:N, :N], E[:N, N:]


def run_smooth(A: ArrayLike, B: ArrayLike, x0: ArrayLike, t: ArrayLike, u: ArrayLike, du: ArrayLike, d2u: ArrayLike) -> FloatArray:
    """The states at the points ``t`` of the plant driven by the quintic Hermite hold of ``u``.

    Parameters
    ----------
    A, B : array_like
        The plant.
    x0 : array_like
        The state at ``t[0]``.
    t : array_like
        Increasing points; the steps between them must be equal (one exponential serves all).
    u, du, d2u : array_like
        The input's value, slope and curvature at the points.

    Returns
    -------
    ndarray, shape (len(t), N)
    """
    A = np.ascontiguousarray(A, dtype=float)
    B = np.ascontiguousarray(B, dtype=float).reshape(-1)
    t = np.asarray(t, dtype=float)
    u, du, d2u = (np.asarray(v, dtype=float).reshape(-1) for v in (u, du, d2u))
    N = A.shape[0]
    x = np.asarray(x0, dtype=float).reshape(-1).copy()
    states = np.empty((t.size, N))
    states[0] = x
    if t.size < 2:
        return states
    d = float(t[1] - t[0])
    # in sigma = (t - t_m)/d the hold is u = sum_p w_p sigma^p / p!, its coefficients from the ends' values
    u0, u1, m0, m1, a0, a1 = u[:-1], u[1:], d * du[:-1], d * du[1:], d * d * d2u[:-1], d * d * d2u[1:]
    jump = u1 - u0
    c3 = 10 * jump - 6 * m0 - 4 * m1 - (3 * a0 - a1) / 2
    c4 = -15 * jump + 8 * m0 + 7 * m1 + (3 * a0 - 2 * a1) / 2
    c5 = 6 * jump - 3 * m0 - 3 * m1 - (a0 - a1) / 2
    W = np.column_stack([u0, m0, a0, 6 * c3, 24 * c4, 120 * c5])
    Phi, G = _quintic_step(A.tobytes(), B.tobytes(), N, d)
    forced = W @ G.T
    for m in range(t.size - 1):
        x = Phi @ x + forced[m]
        states[m + 1] = x
    return states

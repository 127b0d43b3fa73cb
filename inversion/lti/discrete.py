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

Both step the recurrence ``x_{k+1} = Phi x_k + G w_k`` by blocks (:func:`recurrence`): within a
block of ``L`` steps every state is the block's first state through ``Phi^j`` plus a lower
triangular Toeplitz product of the inputs, so that a table of ``K`` rows costs ``K / L`` small
matrix products in Python and the rest in BLAS -- 7 500 rows of a 6-state plant in 0.4 ms where
a step a row took 11 ms. Only powers ``Phi^j``, ``j <= L``, are formed: no eigen-decomposition
(a link's rigid mode, a repeated pole, are defective), and the rounding is that of ``L`` steps.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["zero_order_hold", "run_held", "run_smooth", "smooth_run", "recurrence", "BLOCK"]

FloatArray = NDArray[np.float64]

#: Steps per block of :func:`recurrence`.
BLOCK = 64


def zero_order_hold(A: ArrayLike, B: ArrayLike, step: float) -> tuple[FloatArray, FloatArray]:
    """``(A_d, B_d)`` of the plant held over ``step`` (s).

    Parameters
    ----------
    A : ArrayLike
        The plant's state matrix.
    B : ArrayLike
        Its input matrix.
    step : float
        The hold's length (s).

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


def run_held(Ad: FloatArray, Bd: FloatArray, x0: ArrayLike, u: ArrayLike, C: ArrayLike | None = None) -> FloatArray:
    """The states or outputs of a held discrete-time plant.

    The states ``x_0 .. x_K`` of ``x_{k+1} = A_d x_k + B_d u_k`` (shape (K+1, N)), or with ``C`` the outputs
    ``C x_0 .. C x_K`` (shape (K+1,) for one row of ``C``).

    Parameters
    ----------
    Ad : FloatArray
        The held plant's state matrix.
    Bd : FloatArray
        Its input matrix.
    x0 : ArrayLike
        The initial state.
    u : ArrayLike
        The inputs held, one a step.
    C : ArrayLike | None, optional
        Output rows, if outputs are wanted.
    """
    u = np.asarray(u, dtype=float).reshape(-1, 1)
    Bd = np.asarray(Bd, dtype=float).reshape(-1, 1)
    out, _ = recurrence(Ad, Bd, x0, u, C)
    return out


def recurrence(Phi: ArrayLike, G: ArrayLike, x0: ArrayLike, W: ArrayLike, C: ArrayLike | None = None,
               block: int = BLOCK) -> tuple[FloatArray, FloatArray]:
    """``x_{k+1} = Phi x_k + G w_k`` over the rows of ``W``, by blocks.

    Parameters
    ----------
    Phi : array_like, shape (N, N)
    G : array_like, shape (N, P)
    x0 : array_like, shape (N,)
    W : array_like, shape (K, P)
        The inputs, a row a step.
    C : array_like, shape (Q, N) or (N,), optional
        Output rows: the outputs ``C x_k`` are returned instead of the states.
    block : int
        Steps per block.

    Returns
    -------
    out : ndarray
        The states ``x_0 .. x_K`` (shape (K+1, N)), or the outputs (shape (K+1, Q), or (K+1,) for a single row ``C``).
    x_end : ndarray, shape (N,)
        ``x_K``.

    Examples
    --------
    >>> import numpy as np
    >>> Phi, G = np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.005], [0.1]])  # a double integrator held at 0.1 s
    >>> y, x = recurrence(Phi, G, [0.0, 0.0], np.ones((300, 1)), C=[1.0, 0.0])
    >>> round(float(y[-1]), 9), x.round(9).tolist()  # t = 30 s under a unit input: t^2 / 2 and t
    (450.0, [450.0, 30.0])
    """
    Phi = np.ascontiguousarray(Phi, dtype=float)
    N = Phi.shape[0]
    G = np.ascontiguousarray(np.asarray(G, dtype=float).reshape(N, -1))
    P = G.shape[1]
    W = np.asarray(W, dtype=float).reshape(-1, P)
    x0 = np.asarray(x0, dtype=float).reshape(N)
    single = C is not None and np.asarray(C).ndim == 1
    Cm = np.eye(N) if C is None else np.ascontiguousarray(np.asarray(C, dtype=float).reshape(-1, N))
    Q, K = Cm.shape[0], W.shape[0]
    if K == 0:
        out = (Cm @ x0)[None, :]
        return (out[:, 0] if single else out), x0.copy()
    L = block if K >= block else 1 << (K - 1).bit_length()  # a power of two: few sizes of maps to keep
    blocks = -(-K // L)
    powers, observe, toeplitz, carry = _block_maps(Phi.tobytes(), G.tobytes(), Cm.tobytes(), N, P, Q, L)
    padded = np.zeros((blocks * L, P))
    padded[:K] = W
    Wb = padded.reshape(blocks, L * P)
    # the states where the blocks start: one small product a block
    forced = Wb @ carry
    starts = np.empty((blocks + 1, N))
    starts[0] = x0
    step = powers[L]
    for b in range(blocks):
        starts[b + 1] = step @ starts[b] + forced[b]
    # every output of every block at once: two matrix products
    inside = starts[:blocks] @ observe
    inside += Wb @ toeplitz
    out = np.empty((K + 1, Q))
    out[:K] = inside.reshape(blocks * L, Q)[:K]
    # x_K: from the last block's start, the steps that remain in it
    last = (K - 1) // L
    r = K - last * L
    x_end = powers[r] @ starts[last] + np.einsum("inp,ip->n", _tail_maps(powers, G, r), padded[last * L : last * L + r])
    out[K] = Cm @ x_end
    return (out[:, 0] if single else out), x_end


@functools.lru_cache(maxsize=64)
def _block_maps(Phi_bytes: bytes, G_bytes: bytes, C_bytes: bytes, N: int, P: int, Q: int, L: int) -> tuple[FloatArray, ...]:
    """The maps of a block of ``L`` steps (kept: a table and its window, a member and the next, share them): the powers
    ``Phi^j`` (``j = 0 .. L``), the outputs ``C Phi^j`` as one ``(N, L Q)`` matrix, the Toeplitz blocks ``C Phi^(j-1-i) G``
    (``i < j``) as one ``(L P, L Q)`` matrix, and ``Phi^(L-1-i) G`` as one ``(L P, N)`` matrix."""
    Phi = np.frombuffer(Phi_bytes).reshape(N, N)
    G = np.frombuffer(G_bytes).reshape(N, P)
    Cm = np.frombuffer(C_bytes).reshape(Q, N)
    powers = np.empty((L + 1, N, N))
    powers[0] = np.eye(N)
    for j in range(1, L + 1):
        powers[j] = Phi @ powers[j - 1]
    observe = np.einsum("qn,jnm->jqm", Cm, powers[:L])  # (L, Q, N): C Phi^j
    markov = np.einsum("jqn,np->jqp", observe, G)  # (L, Q, P): C Phi^j G
    index = np.arange(L)[:, None] - 1 - np.arange(L)[None, :]  # j - 1 - i
    toeplitz = np.where((index >= 0)[:, :, None, None], markov[np.clip(index, 0, L - 1)], 0.0)  # (L, L, Q, P): [j, i]
    carry = _tail_maps(powers, G, L)  # (L, N, P)
    return (powers, observe.transpose(2, 0, 1).reshape(N, L * Q), toeplitz.transpose(1, 3, 0, 2).reshape(L * P, L * Q),
            carry.transpose(0, 2, 1).reshape(L * P, N))


def _tail_maps(powers: FloatArray, G: FloatArray, r: int) -> FloatArray:
    """``Phi^(r-1-i) G`` for ``i = 0 .. r-1`` (shape (r, N, P)): the inputs' share in the state ``r`` steps on."""
    return np.einsum("inm,mp->inp", powers[r - 1 :: -1][:r], G)


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


def run_smooth(A: ArrayLike, B: ArrayLike, x0: ArrayLike, t: ArrayLike, u: ArrayLike, du: ArrayLike, d2u: ArrayLike,
               C: ArrayLike | None = None) -> FloatArray:
    """The plant driven by the quintic Hermite hold of ``u``.

    The states at the points ``t`` of the plant driven by the quintic Hermite hold of ``u`` (with ``C``: the outputs).

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
    C : array_like, optional
        Output rows: the outputs are returned instead of the states.

    Returns
    -------
    ndarray, shape (len(t), N), or the outputs
    """
    return smooth_run(A, B, x0, t, u, du, d2u, C)[0]


def smooth_run(A: ArrayLike, B: ArrayLike, x0: ArrayLike, t: ArrayLike, u: ArrayLike, du: ArrayLike, d2u: ArrayLike,
               C: ArrayLike | None = None) -> tuple[FloatArray, FloatArray]:
    """:func:`run_smooth`, and the state at ``t[-1]``.

    Parameters
    ----------
    A : ArrayLike
        The plant's state matrix.
    B : ArrayLike
        Its input matrix.
    x0 : ArrayLike
        The initial state.
    t : ArrayLike
        Times (s).
    u : ArrayLike
        The input at ``t``.
    du : ArrayLike
        Its derivative.
    d2u : ArrayLike
        Its second derivative.
    C : ArrayLike | None, optional
        Output rows, if outputs are wanted.
    """
    A = np.ascontiguousarray(A, dtype=float)
    B = np.ascontiguousarray(B, dtype=float).reshape(-1)
    t = np.asarray(t, dtype=float)
    u, du, d2u = (np.asarray(v, dtype=float).reshape(-1) for v in (u, du, d2u))
    N = A.shape[0]
    x = np.asarray(x0, dtype=float).reshape(-1).copy()
    if t.size < 2:
        return recurrence(np.eye(N), np.zeros((N, 1)), x, np.zeros((0, 1)), C)
    d = float(t[1] - t[0])
    # in sigma = (t - t_m)/d the hold is u = sum_p w_p sigma^p / p!, its coefficients from the ends' values
    u0, u1, m0, m1, a0, a1 = u[:-1], u[1:], d * du[:-1], d * du[1:], d * d * d2u[:-1], d * d * d2u[1:]
    jump = u1 - u0
    c3 = 10 * jump - 6 * m0 - 4 * m1 - (3 * a0 - a1) / 2
    c4 = -15 * jump + 8 * m0 + 7 * m1 + (3 * a0 - 2 * a1) / 2
    c5 = 6 * jump - 3 * m0 - 3 * m1 - (a0 - a1) / 2
    W = np.column_stack([u0, m0, a0, 6 * c3, 24 * c4, 120 * c5])
    Phi, G = _quintic_step(A.tobytes(), B.tobytes(), N, d)
    return recurrence(Phi, G, x, W, C)

"""State space and internal dynamics from the second-order matrices (Eqs. (9)-(14)), in NumPy.

This is the reference the generated functions are checked against: the same formulas,
written directly in NumPy from ``M, K, C, D, H``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["state_space"]

FloatArray = NDArray[np.float64]


def state_space(
    M: FloatArray, K: FloatArray, C: FloatArray, D: FloatArray, H: FloatArray
) -> dict[str, FloatArray]:
    """Linear state space, internal dynamics and output transformation.

    Parameters
    ----------
    M, K, C : ndarray, shape (n+1, n+1)
        Mass, stiffness and damping matrices of (P8).
    D : ndarray, shape (n+1,)
        Output row, ``y = D q``.
    H : ndarray, shape (n+1,)
        Input column.

    Returns
    -------
    dict
        ``A, B, C_out`` (P10), ``CAB`` (scalar, P11), ``CA2`` (row ``C_out A^2``),
        ``AI, BI`` (P14; ``Mbar = M_d - m phi_L^T / L``), ``T`` (maps
        ``[theta; delta; thetadot; deltadot]`` to ``[y; ydot; delta; deltadot]``) and
        ``Tinv``.
    """
    m1 = M.shape[0]
    n = m1 - 1
    D = np.asarray(D, dtype=float).reshape(m1)
    H = np.asarray(H, dtype=float).reshape(m1)
    Z = np.zeros((m1, m1))
    A = np.block([[Z, np.eye(m1)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    B = np.concatenate([np.zeros(m1), np.linalg.solve(M, H)])
    C_out = np.concatenate([D, np.zeros(m1)])
    CAB = float(C_out @ A @ B)
    CA2 = C_out @ A @ A
    L = D[0]
    phi_L = D[1:]
    m = M[1:, 0]
    Mbar = M[1:, 1:] - np.outer(m, phi_L) / L
    Kd = K[1:, 1:]
    Cd = C[1:, 1:]
    AI = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(Mbar, Kd), -np.linalg.solve(Mbar, Cd)]])
    BI = np.concatenate([np.zeros(n), -np.linalg.solve(Mbar, m / L)])
    T = np.zeros((2 * m1, 2 * m1))
    T[0, :m1] = D
    T[1, m1:] = D
    T[2 : 2 + n, 1:m1] = np.eye(n)
    T[2 + n :, m1 + 1 :] = np.eye(n)
    Tinv = np.zeros_like(T)
    Tinv[0, 0] = 1.0 / L
    Tinv[0, 2 : 2 + n] = -phi_L / L
    Tinv[1 : m1, 2 : 2 + n] = np.eye(n)
    Tinv[m1, 1] = 1.0 / L
    Tinv[m1, 2 + n :] = -phi_L / L
    Tinv[m1 + 1 :, 2 + n :] = np.eye(n)
    return {
        "A": A,
        "B": B,
        "C_out": C_out,
        "CAB": np.asarray(CAB),
        "CA2": CA2,
        "AI": AI,
        "BI": BI,
        "T": T,
        "Tinv": Tinv,
    }

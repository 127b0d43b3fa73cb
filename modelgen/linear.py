"""The linear model (P6)-(P10) assembled directly from the modal integrals, in NumPy.

The linear model's matrices are the Hessians of quadratic forms whose entries are the modal
integrals (docs/method.md section 1)::

    M = [[J, m^T], [m, M_d]],  J = I_h + rho L^3/3 + m_t L^2 + I_t,
    m_j = rho S_j + m_t L phi_j(L) + I_t phi_j'(L),
    M_d,ij = rho N_ij + m_t phi_i(L) phi_j(L) + I_t phi_i'(L) phi_j'(L),
    K = diag(0, EI G),  C = (2 zeta / omega_1) K + diag(b_h, 0 .. 0) + Dm,
    D = [x_out, phi_j(x_out)],  H = [1, 0 .. 0]

so they need no symbolic differentiation and no compiled code: :func:`linear_matrices` gives
what the generated ``sflm_matrices`` gives for the same parameter vector (the tests hold
them equal to rounding), and :func:`linear_model` builds the state space of any geometry and
number of modes in milliseconds -- what a check with more modes than the model's needs
(:mod:`inversion.acceptance`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .damping import modal_damping_matrix
from .geometry import Geometry
from .modes import mode_shapes, modal_constants
from .parameters import parameter_names, parameter_values
from .statespace import state_space

__all__ = ["second_order_matrices", "linear_matrices", "linear_model", "rigid_inertia"]

FloatArray = NDArray[np.float64]


def second_order_matrices(p: ArrayLike, n: int) -> dict[str, FloatArray]:
    """``M, K, C, D, H`` of (P8) from the parameter vector ``p``.

    ``M, K, C, D, H`` of (P8) from the parameter vector ``p`` (order of :func:`~modelgen.parameters.parameter_names`).

    Parameters
    ----------
    p : array_like
        The parameter vector every generated function takes.
    n : int
        Number of assumed modes.
    """
    names = parameter_names(n)
    v = dict(zip(names, np.asarray(p, dtype=float).reshape(-1)))
    L, EI, rho = v["L"], v["EI"], v["rho"]
    I_h, m_t, I_t, b_h = v["I_h"], v["m_t"], v["I_t"], v["b_h"]
    modes = range(1, n + 1)
    S = np.array([v[f"S_{j}"] for j in modes])
    phiL = np.array([v[f"phiL_{j}"] for j in modes])
    dphiL = np.array([v[f"dphiL_{j}"] for j in modes])
    N = np.zeros((n, n))
    G = np.zeros((n, n))
    for i in modes:
        for j in modes:
            a, b = min(i, j), max(i, j)
            N[i - 1, j - 1] = v[f"N_{a}_{b}"]
            G[i - 1, j - 1] = v[f"G_{a}_{b}"]
    M = np.zeros((n + 1, n + 1))
    M[0, 0] = rigid_inertia(L, rho, I_h, m_t, I_t)
    M[0, 1:] = M[1:, 0] = rho * S + m_t * L * phiL + I_t * dphiL
    M[1:, 1:] = rho * N + m_t * np.outer(phiL, phiL) + I_t * np.outer(dphiL, dphiL)
    K = np.zeros((n + 1, n + 1))
    K[1:, 1:] = EI * G
    C = (2 * v["zeta"] / v["omega_1"]) * K
    C[0, 0] += b_h
    for i in range(n + 1):
        for j in range(n + 1):
            C[i, j] += v[f"Dm_{min(i, j)}_{max(i, j)}"]
    D = np.concatenate([[v["x_out"]], [v[f"phiX_{j}"] for j in modes]])
    H = np.zeros(n + 1)
    H[0] = 1.0
    return {"M": M, "K": K, "C": C, "D": D, "H": H}


def rigid_inertia(L: float, rho: float, I_h: float, m_t: float, I_t: float) -> float:
    """The whole link's inertia about the joint (kg m^2).

    ``J = I_h + rho L^3/3 + m_t L^2 + I_t``: the whole link's inertia about the joint (kg m^2).

    Parameters
    ----------
    L : float
        Link length (m).
    rho : float
        Linear density (kg/m).
    I_h : float
        Hub inertia (kg m^2).
    m_t : float
        Tip mass (kg).
    I_t : float
        Tip inertia (kg m^2).
    """
    return float(I_h + rho * L**3 / 3 + m_t * L**2 + I_t)


def linear_matrices(p: ArrayLike, n: int) -> dict[str, Any]:
    """Everything the generated ``sflm_matrices`` returns, from ``p``.

    Everything the generated ``sflm_matrices`` returns, from ``p``: ``M, K, C, D, H`` and the state space of
    :func:`~modelgen.statespace.state_space` (``A, B, C_out, CAB, CA2, AI, BI, T, Tinv``).

    Parameters
    ----------
    p : ArrayLike
        The parameter vector.
    n : int
        Number of assumed modes.
    """
    mats = second_order_matrices(p, n)
    return {**mats, **state_space(mats["M"], mats["K"], mats["C"], mats["D"], mats["H"])}


def linear_model(geometry: Geometry, modes: int | None = None, output_at: float | None = None) -> dict[str, Any]:
    """The linear model of a geometry with ``modes`` assumed modes.

    The linear model of a geometry with ``modes`` assumed modes (default the geometry's), measured at ``output_at``.

    No symbolic work and no compiled code: the shapes, their modal integrals (Gauss-Legendre),
    ``omega_1`` of the Rayleigh damping (or the modal damping's matrix) from ``(K, M)``, then :func:`linear_matrices`.

    Parameters
    ----------
    geometry : Geometry
        The link.
    modes : int | None, optional
        Number of assumed modes (``None``: the geometry's).
    output_at : float | None, optional
        Where the output is measured (m from the hub; ``None``: the tip).

    Returns
    -------
    dict
        ``linear_matrices`` plus ``p`` (the parameter vector) and ``n``.
    """
    from .loader import output_location
    from .model import natural_frequencies

    g = geometry.with_model(modes)
    shapes = mode_shapes(g)
    constants = modal_constants(shapes)
    x = output_location(g, output_at)
    output = None if x == g.length else (x, np.asarray(shapes(np.array([x]), 0)[:, 0], dtype=float))
    first = second_order_matrices(parameter_values(g, constants, omega_1=1.0, output=output), shapes.n)
    omega_1 = float(natural_frequencies(first["K"], first["M"])[0])
    modal = modal_damping_matrix(first["M"], first["K"], g.modal_ratios(shapes.n)) if g.modal_damping else None
    p = parameter_values(g, constants, omega_1=omega_1, output=output, modal=modal)
    return {**linear_matrices(p, shapes.n), "p": p, "n": shapes.n}

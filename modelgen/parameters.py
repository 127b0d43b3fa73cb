"""The parameter vector ``p`` shared by the symbolic model and the generated code.

Every generated function takes ``p`` as its first input, so one compiled library serves
every geometry with the same number of modes. ``p`` holds the physical parameters and
the mode constants (modal integrals, tip values of the shapes); its order is fixed here
and recorded in each manifest. This module does not import SymPy.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .geometry import Geometry
from .modes import ModalConstants

__all__ = ["PHYSICAL_PARAMETERS", "parameter_names", "parameter_values"]

#: Physical parameters, in order, with their meaning (SI units).
PHYSICAL_PARAMETERS: dict[str, str] = {
    "L": "link length (m)",
    "EI": "flexural rigidity (N m^2)",
    "rho": "linear density (kg/m)",
    "I_h": "hub inertia (kg m^2)",
    "m_t": "payload mass (kg)",
    "I_t": "payload inertia (kg m^2)",
    "b_h": "hub viscous damping (N m s/rad)",
    "zeta": "Rayleigh damping ratio of the first flexible mode",
    "omega_1": "first flexible natural frequency of (K_B, M) (rad/s), Eq. (7)",
}


def parameter_names(n: int) -> list[str]:
    """Names of the entries of ``p`` for ``n`` modes, in order.

    After the physical parameters come, for ``j = 1..n``: ``S_j = int x phi_j``,
    ``phiL_j = phi_j(L)``, ``dphiL_j = phi_j'(L)``; then for ``i <= j``:
    ``N_i_j = int phi_i phi_j`` and ``G_i_j = int phi_i'' phi_j''``; last, where the output
    is measured: ``x_out`` (m, ``0 < x_out <= L``) and ``phiX_j = phi_j(x_out)``, so that
    ``y = x_out theta + w(x_out)`` (the tip, ``x_out = L``, by default); then the geometric
    stiffening's ``P_i_j = int (L^2 - x^2) phi_i' phi_j'`` and ``Q_i_j = int phi_i' phi_j'``; last, the
    modal damping's matrix ``Dm_i_j`` over ``q = [theta, delta_1..n]`` (``0 <= i <= j <= n``; zero for Rayleigh
    damping, :func:`modelgen.damping.modal_damping_matrix`), added to the damping matrix ``C``.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    """
    names = list(PHYSICAL_PARAMETERS)
    modes = range(1, n + 1)
    names += [f"S_{j}" for j in modes]
    names += [f"phiL_{j}" for j in modes]
    names += [f"dphiL_{j}" for j in modes]
    names += [f"N_{i}_{j}" for i in modes for j in modes if i <= j]
    names += [f"G_{i}_{j}" for i in modes for j in modes if i <= j]
    names += ["x_out"] + [f"phiX_{j}" for j in modes]
    names += [f"P_{i}_{j}" for i in modes for j in modes if i <= j]
    names += [f"Q_{i}_{j}" for i in modes for j in modes if i <= j]
    names += [f"Dm_{i}_{j}" for i in range(n + 1) for j in range(n + 1) if i <= j]
    return names


def parameter_values(
    geometry: Geometry, constants: ModalConstants, omega_1: float, output: tuple[float, NDArray[np.float64]] | None = None,
    modal: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Assemble ``p`` for a geometry and its modes.

    Parameters
    ----------
    geometry : Geometry
        Physical parameters.
    constants : ModalConstants
        Modal integrals of the chosen shapes.
    omega_1 : float
        First flexible natural frequency (rad/s) used by Rayleigh damping, Eq. (7); it
        only enters the damping matrix (pass any positive value when ``zeta = 0``).
    output : (float, ndarray), optional
        ``(x_out, phi_j(x_out))``: where the output is measured (default the tip,
        ``(L, phi_j(L))``).
    modal : ndarray, optional
        The modal damping's ``(n + 1, n + 1)`` matrix (default zero: Rayleigh damping only).
    """
    n = constants.S.size
    g = geometry
    values = [
        g.length,
        g.flexural_rigidity,
        g.linear_density,
        g.hub_inertia,
        g.payload_mass,
        g.payload_inertia,
        g.hub_viscous_damping,
        g.damping_ratio,
        omega_1,
    ]
    values += list(constants.S) + list(constants.phi_L) + list(constants.dphi_L)
    upper = np.triu_indices(n)
    values += list(constants.N[upper]) + list(constants.G[upper])
    x_out, phi_x = (g.length, constants.phi_L) if output is None else output
    values += [x_out] + list(phi_x)
    P = constants.P if constants.P.shape == (n, n) else np.zeros((n, n))
    Q = constants.Q if constants.Q.shape == (n, n) else np.zeros((n, n))
    values += list(P[upper]) + list(Q[upper])
    values += list(np.zeros((n + 1, n + 1))[np.triu_indices(n + 1)] if modal is None else np.asarray(modal)[np.triu_indices(n + 1)])
    return np.asarray(values, dtype=float)

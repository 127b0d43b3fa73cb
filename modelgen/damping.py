"""The link's damping in its two forms: Rayleigh's (Eq. (7)) and modal.

Rayleigh's form, ``C = (2 zeta / omega_1) K + diag(b_h, 0..0)``, is assembled by the model itself (the symbolic model,
:mod:`modelgen.lagrange`, and the linear one, :mod:`modelgen.linear`). The modal form gives each flexible mode of the
linear model its own ratio (``[damping] modal = [...]`` in the geometry file): its matrix is computed here from the
model's mass and stiffness matrices and enters the generated code as the parameters ``Dm_i_j``
(:func:`modelgen.parameters.parameter_values`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["modal_damping_matrix"]

FloatArray = NDArray[np.float64]


def modal_damping_matrix(M: FloatArray, K: FloatArray, ratios: tuple[float, ...]) -> FloatArray:
    """The damping matrix that gives each flexible mode its own ratio.

    ``Dm = M Phi diag(2 zeta_i omega_i) Phi^T M`` over ``q = [theta, delta_1..n]``, with ``(omega_i, Phi)`` the modes of
    ``(K, M)`` (the hub free; ``Phi^T M Phi = I``): in modal coordinates each flexible mode gets ``2 zeta_i omega_i``,
    the rigid body (``omega_0 = 0``) none. With the hub's viscous damping added the modes couple again, as on the
    bench.

    Parameters
    ----------
    M, K : FloatArray
        The linear model's mass and stiffness matrices, ``(n + 1, n + 1)``.
    ratios : tuple of float
        The ratios of the ``n`` flexible modes, lowest first.
    """
    import scipy.linalg as sla

    w2, Phi = sla.eigh(K, M)
    omega = np.sqrt(np.clip(w2, 0.0, None))
    gains = np.concatenate([[0.0], 2 * np.asarray(ratios, dtype=float)[: omega.size - 1] * omega[1:]])
    MPhi = M @ Phi
    Dm = (MPhi * gains) @ MPhi.T
    return 0.5 * (Dm + Dm.T)

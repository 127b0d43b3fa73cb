"""Model matrices evaluated straight from the SymPy expressions (the reference backend).

The compiled functions of :mod:`modelgen.codegen` are checked against this: ``M, K, C,
D, H`` lambdified from :func:`modelgen.lagrange.derive`, and the state space from the
NumPy formulas of :mod:`modelgen.statespace`.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
import sympy as sp
from numpy.typing import NDArray

from .lagrange import derive
from .statespace import state_space

__all__ = ["ReferenceFunctions"]


class ReferenceFunctions:
    """Evaluate the linear model of ``n`` modes from SymPy at a parameter vector.

    Parameters
    ----------
    n : int
        Number of assumed modes.
    """

    def __init__(self, n: int):
        self.n = n
        self.symbolic = derive(n)
        args = list(self.symbolic.params.values())
        self._second_order: Callable[..., tuple[NDArray[np.float64], ...]] = sp.lambdify(
            [args],
            [self.symbolic.M, self.symbolic.K, self.symbolic.C, self.symbolic.D, self.symbolic.H],
            modules="numpy",
        )

    def matrices(self, p: NDArray[np.float64]) -> dict[str, NDArray[np.float64]]:
        """``M, K, C, D, H`` and the state space of :func:`~modelgen.statespace.state_space` at ``p``."""
        M, K, C, D, H = (np.asarray(a, dtype=float) for a in self._second_order(np.asarray(p, dtype=float)))
        out = {"M": M, "K": K, "C": C, "D": D.reshape(-1), "H": H.reshape(-1)}
        out.update(state_space(M, K, C, out["D"], out["H"]))
        return out

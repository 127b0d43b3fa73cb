"""The boundary between the generated code and the numerics, as a typed contract.

:class:`CompiledFunctions` is what :mod:`inversion` and :mod:`simulation` may rely on from
a model's functions, whether they run compiled C (``casadi.external``) or in-process CasADi
(the no-compiler fallback). :class:`modelgen.compiled.ModelFunctions` implements it; a
test double or another code generator may too. The roles and their signatures are those
of :data:`modelgen.abi.ROLES`. This module imports neither CasADi nor SciPy, so that
``import inversion`` stays light.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["CompiledFunctions"]

FloatArray = NDArray[np.float64]


@runtime_checkable
class CompiledFunctions(Protocol):
    """The generated functions of an ``n``-mode model (:data:`ROLES`).

    Attributes
    ----------
    n : int
        Number of assumed modes.
    functions : Mapping[str, casadi.Function]
        Role -> CasADi function ``sflm_<role>``.
    compiled : bool
        Whether the functions run compiled C.
    manifest : dict
        The manifest of the cache entry they come from.
    folder : Path or None
        That cache entry (``None`` for functions built in memory).
    """

    @property
    def n(self) -> int: ...

    @property
    def functions(self) -> Mapping[str, Any]: ...

    @property
    def compiled(self) -> bool: ...

    @property
    def manifest(self) -> Mapping[str, Any]: ...

    @property
    def folder(self) -> Path | None: ...

    def call(self, role: str, *args: ArrayLike | float) -> list[FloatArray]:
        """One evaluation of ``role``, outputs shaped as declared.

        Parameters
        ----------
        role : str
            One of :data:`~modelgen.abi.ROLES`.
        """
        ...

    def matrices(self, p: ArrayLike) -> dict[str, FloatArray]:
        """Every matrix role at the parameters ``p``.

        Every matrix role (``M K C D H A B C_out CAB CA2 AI BI T Tinv``) at the parameters ``p``.

        Parameters
        ----------
        p : ArrayLike
            The parameter vector.
        """
        ...

    def inverse_torque(self, p: ArrayLike, X: ArrayLike, yddot: ArrayLike) -> FloatArray:
        """Eq. (12) for samples in rows of ``X``, one batch call a block.

        Parameters
        ----------
        p : ArrayLike
            The parameter vector.
        X : ArrayLike
            States in rows.
        yddot : ArrayLike
            The output's second derivative at each row.
        """
        ...

    def map(self, role: str, p: ArrayLike, *columns: ArrayLike) -> list[FloatArray]:
        """``role`` at many samples (rows of each column), ``p`` shared.

        Parameters
        ----------
        role : str
            One of :data:`~modelgen.abi.ROLES`.
        p : ArrayLike
            The parameter vector.
        """
        ...

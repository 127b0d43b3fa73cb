"""Which zeros of a model can be trusted: converged ones, unconverged ones, truncation artefacts.

An assumed-mode model truncates the link; its lowest zeros converge to the continuum's as
``n`` grows, its highest do not. Worse, from ``n = 3-4`` on, undamped models show complex
quadruplets at the top of the zero spectrum where the continuum has only real or purely
imaginary zeros: truncation artefacts, which take the place of true zeros and, counted as
unstable, enlarge every segment system of the inversion for nothing the physics contains.

:func:`zero_status` compares every zero with the continuum reference of
:mod:`modelgen.continuum` (a converged finite-element model with the same damping):

* **converged** -- within ``tol`` (relative) of a reference zero whose own discretisation
  error is ten times smaller;
* **artefact** -- not converged, and genuinely complex (``|Re z|`` and ``|Im z|`` both above
  ``NEAR_TOL |z|``): the continuum of a link (undamped: real or imaginary zeros; with
  Rayleigh damping: small real parts) has no such zero;
* otherwise **unconverged**: a true zero not yet at its continuum value (more modes move it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .zeros import NEAR_TOL, is_unstable

if TYPE_CHECKING:
    from .continuum import ContinuumReference
    from .model import Model

__all__ = ["ZeroStatus", "zero_status", "DEFAULT_ZERO_TOL"]

#: Relative distance to the continuum's zero below which a zero counts as converged.
DEFAULT_ZERO_TOL = 1e-3


@dataclass(frozen=True)
class ZeroStatus:
    """The zeros of a model judged against the continuum.

    Attributes
    ----------
    zeros : ndarray of complex
        The model's zeros (its order).
    converged, artefact : ndarray of bool
        Aligned with ``zeros`` (module docstring).
    reference : ndarray of complex
        The continuum zero each converges to: one each, of least total relative distance
        (:func:`scipy.optimize.linear_sum_assignment`); NaN for a genuinely complex zero (the
        truncation's: the continuum has none like it).
    relative_error : ndarray
        ``|z - z_ref| / |z_ref|`` (NaN without a partner).
    tol : float
        The tolerance of ``converged``.
    """

    zeros: NDArray[np.complex128]
    converged: NDArray[np.bool_]
    artefact: NDArray[np.bool_]
    reference: NDArray[np.complex128]
    relative_error: NDArray[np.float64]
    tol: float

    @property
    def n_unstable(self) -> int:
        """Unstable zeros, all counted (what the inversion uses)."""
        return int(np.count_nonzero(is_unstable(self.zeros)))

    @property
    def n_unstable_converged(self) -> int:
        """Unstable zeros that have converged to the continuum's."""
        return int(np.count_nonzero(is_unstable(self.zeros) & self.converged))

    @property
    def n_unstable_without_artefacts(self) -> int:
        """Unstable zeros that are not truncation artefacts (converged or not)."""
        return int(np.count_nonzero(is_unstable(self.zeros) & ~self.artefact))

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the keys of ``sflm info --json``."""
        return {
            "zeros_converged": [bool(v) for v in self.converged],
            "zeros_artefact": [bool(v) for v in self.artefact],
            "zeros_continuum": [[float(v.real), float(v.imag)] if np.isfinite(v) else None for v in self.reference],
            "zeros_relative_error": [float(v) if np.isfinite(v) else None for v in self.relative_error],
            "zero_tolerance": self.tol,
            "n_unstable_converged": self.n_unstable_converged,
            "n_unstable_without_artefacts": self.n_unstable_without_artefacts,
        }


def zero_status(model: Model, tol: float | None = None, reference: ContinuumReference | None = None) -> ZeroStatus:
    """Judge every zero of ``model`` against the continuum.

    Parameters
    ----------
    model : Model
    tol : float, optional
        Relative tolerance of ``converged`` (default :data:`DEFAULT_ZERO_TOL`).
    reference : ContinuumReference, optional
        :func:`modelgen.continuum.continuum_reference` of the model's geometry (measured
        where the model is, :attr:`Model.output_at`) with at least ``n + 2`` zero pairs (computed when not given: about 0.3 s).
    """
    from .continuum import continuum_reference

    tol = DEFAULT_ZERO_TOL if tol is None else float(tol)
    if reference is None:
        reference = continuum_reference(model.geometry, count=model.n + 3, output_at=model.output_at)
    from .zeros import assignment

    ref = np.asarray(reference.zeros, dtype=complex)
    err = np.asarray(reference.zero_error, dtype=float)
    zeros = np.asarray(model.zeros, dtype=complex)
    magnitude = np.maximum(np.abs(zeros), 1e-300)
    complex_ = (np.abs(zeros.real) > NEAR_TOL * magnitude) & (np.abs(zeros.imag) > NEAR_TOL * magnitude)
    # one continuum zero per model zero (an assignment of least total relative distance), the genuinely complex ones
    # left out: they are the truncation's, with no continuum zero to converge to (nearest neighbours paired two model
    # zeros with one continuum zero, and an artefact with whatever was close: relative errors of 1.7)
    relative_all = np.abs(zeros[:, None] - ref[None, :]) / np.maximum(np.abs(ref), 1e-300)[None, :]
    matched = np.full(zeros.size, complex(np.nan, np.nan))
    relative = np.full(zeros.size, np.nan)
    trusted = np.zeros(zeros.size, dtype=bool)
    true = np.flatnonzero(~complex_)
    if true.size:
        rows, cols = assignment(relative_all[true][:, : ref.size] if ref.size >= true.size else relative_all[true])
        picked = true[rows]
        matched[picked], relative[picked] = ref[cols], relative_all[picked, cols]
        trusted[picked] = err[cols] <= 0.1 * tol * np.abs(ref[cols])
    converged = (relative <= tol) & trusted
    return ZeroStatus(zeros, converged, ~converged & complex_, matched, relative, float(tol))

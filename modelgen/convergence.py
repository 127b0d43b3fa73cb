"""Truncation error of the assumed-mode model, measured against the continuum reference."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .continuum import ContinuumReference, continuum_reference
from .geometry import Geometry
from .model import Model

__all__ = ["Convergence", "convergence"]


@dataclass(frozen=True)
class Convergence:
    """Models for ``n = 1..N`` and the same link's continuum reference.

    Attributes
    ----------
    geometry : Geometry
        The link.
    models : list[Model]
        The models with ``n = 1..N`` modes.
    reference : ContinuumReference
        The finite-element reference of the same link.
    """

    geometry: Geometry
    models: list[Model]
    reference: ContinuumReference


def convergence(
    geometry: Geometry,
    max_modes: int,
    loader: Callable[[Geometry], Model],
    progress: Callable[[int, int], None] | None = None,
    output_at: float | None = None,
) -> Convergence:
    """Models for ``n = 1..max_modes`` and the continuum reference.

    Parameters
    ----------
    geometry : Geometry
        The link (its mode family is kept; ``modes`` is varied).
    max_modes : int
        Largest ``n``.
    loader : callable
        ``loader(geometry) -> Model`` (e.g. :func:`modelgen.load`).
    progress : callable, optional
        Called as ``progress(n, max_modes)`` before each model is built.
    output_at : float, optional
        Where the loader's models measure the output (m; default the tip): the reference
        measures there too.
    """
    models = []
    for n in range(1, max_modes + 1):
        if progress is not None:
            progress(n, max_modes)
        models.append(loader(geometry.with_model(modes=n)))
    return Convergence(geometry, models, continuum_reference(geometry, count=3, output_at=output_at))

"""The paper's cases in the closed loop: their fitted plant assumptions as :func:`simulate` arguments.

The values and their provenance live in :mod:`modelgen.paper`; :func:`simulate` takes a
case's gains, compensation, pulse law and span by itself when the model and trajectory
are the case's. What it never takes by itself is a plant that differs from the model:
:func:`fitted_plant` turns a case's plant assumptions (fitted to what the paper
observed) into explicit arguments, each with its source, for ``sflm reproduce`` and
``sflm simulate --paper-plant``.
"""

from __future__ import annotations

from typing import Any

from modelgen.paper import PaperCase

__all__ = ["fitted_plant"]


def fitted_plant(case: PaperCase) -> dict[str, Any]:
    """:func:`simulation.simulate`'s keywords for ``case``'s plant.

    Parameters
    ----------
    case : PaperCase
        A paper case.

    Returns
    -------
    dict
        ``coulomb_friction``, ``breakaway_friction`` (when the case assumes them),
        ``plant_overrides`` and ``plant_sources`` (every value's provenance). Empty for a
        case without plant assumptions.

    Examples
    --------
    >>> from modelgen.paper import CASES
    >>> sorted(fitted_plant(CASES["paper-exp"]))
    ['breakaway_friction', 'coulomb_friction', 'plant_overrides', 'plant_sources']
    >>> fitted_plant(CASES["paper-sim"])
    {}
    """
    if not case.plant:
        return {}
    out: dict[str, Any] = {"plant_overrides": {}, "plant_sources": {}}
    for name, value in case.plant.items():
        if name in ("coulomb_friction", "breakaway_friction"):
            out[name] = float(value.value)
        else:
            out["plant_overrides"][name] = float(value.value)
        out["plant_sources"][name] = value.source
    return out

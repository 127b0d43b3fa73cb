"""How the closed loop's end depends on plant values the model does not know: sweeps of simulations.

A plant value that a report assumes (the experiment's friction, the link's damping) is
honest only with its effect beside it. :func:`plant_sweep` simulates one feedforward on
a list of plants and controllers and returns one row per run with the figures that
describe the end of the run: the mean tip error over the last second, the vibration
about it (peak to peak), the error at the end, the pulses.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping, Sequence

from inversion.result import InversionResult
from modelgen.model import Model

from .closed_loop import simulate

__all__ = ["plant_sweep", "SWEEP_FIGURES"]

#: Figures of a run copied into its row.
SWEEP_FIGURES = ("steady_tip_error", "residual_vibration", "final_tip_error", "settled", "peak_torque")


def plant_sweep(
    model: Model,
    inversion: InversionResult,
    plants: Sequence[Mapping[str, Any]],
    controllers: Sequence[str] = ("pd", "two-stage"),
    progress: Callable[[int, int], None] | None = None,
    **common: Any,
) -> list[dict[str, Any]]:
    """Simulate every plant of ``plants`` with every controller.

    Parameters
    ----------
    model, inversion
        As for :func:`simulation.simulate`.
    plants : sequence of mappings
        Each: ``label`` (a dict of the swept values, copied into the rows) and any of
        ``coulomb_friction``, ``breakaway_friction``, ``plant_overrides``, ``plant_sources``.
    controllers : sequence of str
        Controllers to run on each plant.
    progress : callable, optional
        ``progress(done, total)`` after each run.
    **common
        Further keyword arguments of :func:`simulation.simulate` for every run.

    Returns
    -------
    list of dict
        Per run: the label's values, ``controller``, :data:`SWEEP_FIGURES` and ``pulses``
        (their number).
    """
    rows: list[dict[str, Any]] = []
    total = len(plants) * len(controllers)
    for plant in plants:
        kwargs = {k: v for k, v in plant.items() if k != "label"}
        for controller in controllers:
            result = simulate(model, inversion, controller=controller, **kwargs, **common)  # type: ignore[arg-type]
            s = result.summary
            row: dict[str, Any] = dict(plant.get("label", {}))
            row["controller"] = controller
            row.update({key: s[key] for key in SWEEP_FIGURES})  # type: ignore[literal-required]
            row["pulses"] = len(s["pulses"])
            rows.append(row)
            if progress is not None:
                progress(len(rows), total)
    return rows

"""The closed loop on the links the user may have: :func:`simulate` on every perturbed geometry (``simulate --uncertainty``).

:func:`inversion.studies.robustness.robustness` judges a feedforward on the perturbed *linear* models in
the joint-PD loop, fast enough to compare members. This module runs the loop the user asked for
-- the plant they chose (by default the nonlinear stiffened one), its friction, its controller --
on each perturbed link: the geometry with the values changed (:meth:`Uncertainty.perturbed`,
exactly what an edited geometry file gives) loaded with the model's modes, shapes and output
point, driven by the same feedforward and by the joint PD tuned for the *nominal* model (the
controller does not know the link differs either). The figure is the largest tip error
``max |y - y_d|`` over the run (``y_d`` held at ``y_d(t_f)`` after the move), relative to the move.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from inversion.result import InversionResult
from inversion.studies.robustness import UNCERTAIN_KEYS, Uncertainty, parse_uncertainty
from modelgen.errors import SettingsError
from modelgen.geometry import parameter_value
from modelgen.loader import load
from modelgen.model import Model

from .closed_loop import SimulationResult, simulate
from .plant import OVERRIDABLE

__all__ = ["simulate_uncertain"]


def simulate_uncertain(model: Model, inversion: InversionResult, uncertainty: str | Uncertainty, *,
                       nominal: SimulationResult | None = None, progress: Callable[[int, int], None] | None = None,
                       **options: Any) -> SimulationResult:
    """:func:`simulate` on the nominal and every perturbed link.

    Parameters
    ----------
    model : Model
        The nominal link (the model the feedforward was computed for).
    inversion : InversionResult
        The feedforward.
    uncertainty : str or Uncertainty
        ``link.flexural_rigidity=10%,payload.mass=20%`` (:func:`inversion.studies.robustness.parse_uncertainty`): every corner,
        and its seeded samples.
    nominal : SimulationResult, optional
        The nominal run with the same ``options``, when already done (default: run here).
    progress : callable, optional
        ``progress(done, total)`` after each perturbed run.
    **options
        The keyword arguments of :func:`simulate` (plant, controller, friction, ``t_end``, ``rate`` ...); the gains are
        the nominal run's on every link.

    Returns
    -------
    SimulationResult
        The nominal run, its summary gaining ``robustness``: ``uncertainty``, ``corners``, ``samples``, ``plant``,
        ``gains``, ``nominal_error`` and ``worst_case_error`` (the largest ``max |y - y_d|`` relative to the move),
        ``worst_parameters``, ``worst_factors``, ``errors`` (every set's, corners first) and ``final_errors`` (the tip
        error at the end of each run, relative to the move).

    Raises
    ------
    SettingsError
        For a plant override of a parameter the uncertainty perturbs (it would replace the perturbation).
    """
    if not isinstance(uncertainty, Uncertainty):
        uncertainty = parse_uncertainty(uncertainty)
    overridden = {OVERRIDABLE[name][0]: name for name in options.get("plant_overrides") or {} if name in OVERRIDABLE}
    for key, _ in uncertainty.ranges:
        if UNCERTAIN_KEYS.get(key) in overridden:
            raise SettingsError("uncertainty", uncertainty.spec(), f"keys the plant overrides leave alone ({key} is overridden as "
                                f"{overridden[UNCERTAIN_KEYS[key]]}: the override would replace the perturbation)")
    if nominal is None:
        nominal = simulate(model, inversion, **options)
    gains = {"kp": nominal.summary["kp"], "kd": nominal.summary["kd"]}
    move = abs(float(inversion.trajectory.move())) or 1.0
    sets = uncertainty.perturbed(model.geometry)
    errors, finals = [], []
    for done, (factors, geometry) in enumerate(sets, 1):
        # the perturbed link on the model's own modes, shapes and output point (the compiled functions: a cache hit)
        link = load(geometry, modes=model.n, mode_shapes=model.mode_family, output_at=uncertainty.output_at(model, geometry))
        try:
            run = simulate(link, inversion, **{**options, **gains, "progress": None})
        except SettingsError as exc:  # which of the links refused the plant, in the spec's words
            if exc.parameter != "plant":
                raise
            corner = ", ".join(f"{key} x {factor:.6g}" for key, factor in factors.items())
            raise SettingsError("plant", exc.value, f"{exc.accepted} (on the perturbed link {corner} of --uncertainty "
                                                    f"{uncertainty.spec()})") from None
        errors.append(run.summary["max_tracking_error"] / move)
        finals.append(run.summary["final_tip_error"] / move)
        if progress is not None:
            progress(done, len(sets))
    worst = int(np.argmax(errors))
    factors, geometry = sets[worst]
    nominal.summary["robustness"] = {
        "uncertainty": uncertainty.spec(), "corners": 2 ** len(uncertainty.ranges), "samples": uncertainty.samples,
        "seed": uncertainty.seed, "plant": nominal.summary["plant"]["kind"], "gains": gains,
        "nominal_error": nominal.summary["max_tracking_error"] / move, "worst_case_error": float(errors[worst]),
        "worst_parameters": {k: parameter_value(geometry, k) for k in factors},
        "worst_factors": factors, "errors": [float(e) for e in errors], "final_errors": [float(e) for e in finals],
    }
    return nominal

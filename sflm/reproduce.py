"""``sflm reproduce``: the paper's simulation (section 7) and experiment (section 8), end to end.

Generate the model's code, invert the paper's trajectory with the paper's member,
simulate the closed loop, write the paper's figures and a ``report.md`` (:mod:`sflm.paper_report`)
that puts our numbers beside the paper's and states what is assumed: every value the
paper does not give, where it comes from, and what it changes. For the experiment, the
plant values fitted to the paper's observations are applied as labelled assumptions and
swept (friction, damping) so that their effect is in the report.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

import modelgen
from inversion import Family, Problem, invert, trajectory_from_spec
from inversion.errors import SettingsError
from inversion.settings import paper_settings
from modelgen.export import export_model
from modelgen.paper import CASES, PaperCase
from simulation import SimulationResult, simulate
from simulation.cases import fitted_plant
from simulation.plant import PlantKind
from simulation.sensitivity import plant_sweep

from .plots import acceleration_figure, line_figure, plot_inversion, plot_simulation, sensitivity_figure, velocity_displacement_figure
from .paper_report import report_markdown

__all__ = ["reproduce", "Reproduction", "REPRODUCIBLE", "FRICTION_SWEEP", "DAMPING_SWEEP", "PAPER_PLANT"]

#: The plant a reproduction simulates: the paper's own nonlinear model (P4), without the geometric stiffening sflm's
#: default nonlinear plant adds (docs/method.md section 1a) -- the paper's figures are of its model.
PAPER_PLANT: PlantKind = "nonlinear-paper"

REPRODUCIBLE = ("paper-sim", "paper-exp")
#: Sliding friction of the experiment's plant in the sensitivity (N m); the compensated average is 0.45.
FRICTION_SWEEP = (0.45, 0.50, 0.55, 0.60)
#: Damping ratio of the experiment's plant in the sensitivity (0: the model's).
DAMPING_SWEEP = (0.0, 0.005, 0.01, 0.02)


@dataclass(frozen=True)
class Reproduction:
    """What :func:`reproduce` wrote.

    Attributes
    ----------
    folder : Path
        Where it wrote.
    files : list[Path]
        The files written.
    report : Path
        The report.
    numbers : dict[str, Any]
        The report's figures.
    """

    folder: Path
    files: list[Path]
    report: Path
    numbers: dict[str, Any]


def _step(message: str, progress: Callable[[str], None] | None) -> None:
    if progress is not None:
        progress(message)


def _simulation_figures(sim: SimulationResult, folder: Path, numbers: tuple[int, int, int], suffix: str, after: str) -> list[Path]:
    """The paper's torque, tip and tip-error figures of one closed-loop run (``after``: the law after t_f)."""
    f_tau, f_tip, f_err = numbers
    return plot_simulation(
        sim,
        folder,
        (f"fig{f_tau}_torque{suffix}.png", f"fig{f_tip}_tip{suffix}.png", f"fig{f_err}_tip_error{suffix}.png"),
        (
            f"Fig. {f_tau}: base torque (feedforward + PD, then {after})",
            f"Fig. {f_tip}: desired and actual end-effector displacement",
            f"Fig. {f_err}: {{error}}",
        ),
    )


def _effects(model: Any, case: PaperCase) -> dict[str, str]:
    """What each assumed model value changes: the model again with an alternative value.

    Alternatives: +10 % for a material value, 1 % for a damping taken as zero, a payload
    of a tenth of the link's mass for a mass taken as zero.
    """
    g = model.geometry
    out: dict[str, str] = {}
    alternatives: dict[str, tuple[str, dict[str, float]]] = {
        "link.youngs_modulus": ("E +10 %", {"flexural_rigidity": 1.1 * g.flexural_rigidity}),
        "link.density": ("density +10 %", {"linear_density": 1.1 * g.linear_density}),
        "damping.ratio": ("zeta = 0.01", {"damping_ratio": 0.01}),
        "payload.mass": ("m_t = a tenth of the link's mass", {"payload_mass": 0.1 * g.linear_density * g.length}),
    }
    for key in case.model:
        if key not in alternatives or not case.model[key].assumed:
            continue
        label, change = alternatives[key]
        other = modelgen.load(replace(g, **change))
        f0, f1 = model.natural_frequencies_hz[0], other.natural_frequencies_hz[0]
        z0 = np.abs(model.zeros).min()
        z1 = np.abs(other.zeros).min()
        out[key] = (f"{label}: first frequency {f0:.4g} -> {f1:.4g} Hz, smallest |zero| {z0:.4g} -> {z1:.4g} rad/s, "
                    f"unstable zeros {model.n_unstable} -> {other.n_unstable}")
    return out


def _sweeps(model: Any, inversion: Any, case: PaperCase, progress: Callable[[str], None] | None) -> dict[str, list[dict[str, Any]]]:
    """The experiment's steady errors against the assumed friction and damping (each about the fitted plant)."""
    fitted = fitted_plant(case)
    gap = fitted["breakaway_friction"] - fitted["coulomb_friction"]
    zeta = fitted["plant_overrides"].get("zeta", 0.0)
    source = "sensitivity of the report (sflm reproduce)"
    friction = [
        {"label": {"coulomb_friction": Fc, "breakaway_friction": Fc + gap, "zeta": zeta}, "coulomb_friction": Fc,
         "breakaway_friction": Fc + gap, "plant_overrides": {"zeta": zeta},
         "plant_sources": {"coulomb_friction": source, "breakaway_friction": source, "zeta": source}}
        for Fc in FRICTION_SWEEP
    ]
    damping = [
        {"label": {"zeta": z}, "coulomb_friction": fitted["coulomb_friction"], "breakaway_friction": fitted["breakaway_friction"],
         "plant_overrides": {"zeta": z}, "plant_sources": {"coulomb_friction": source, "breakaway_friction": source, "zeta": source}}
        for z in DAMPING_SWEEP
    ]
    _step(f"{case.name}: sensitivity, {2 * (len(friction) + len(damping))} closed-loop runs", progress)
    return {"friction": plant_sweep(model, inversion, friction, plant=PAPER_PLANT), "damping": plant_sweep(model, inversion, damping, plant=PAPER_PLANT)}


def reproduce(name: str, folder: Path, progress: Callable[[str], None] | None = None) -> Reproduction:
    """Run the paper's case ``name`` end to end into ``folder``.

    Run the paper's case ``name`` end to end and write figures and ``report.md`` into ``folder``.

    Parameters
    ----------
    name : str
        ``"paper-sim"`` or ``"paper-exp"``.
    folder : Path
        Where to write.
    progress : Callable[[str], None] | None, optional
        A callback given each stage's name, or ``None``.

    Raises
    ------
    SettingsError
        If ``name`` is not ``paper-sim`` or ``paper-exp``, or ``folder`` cannot be written.
    """
    if name not in REPRODUCIBLE:
        raise SettingsError("case", name, "paper-sim or paper-exp")
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / ".sflm-write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise SettingsError("--out", str(folder), f"a folder that can be created and written ({exc.strerror})") from None
    case = CASES[name]
    started = time.perf_counter()

    _step(f"{name}: model (derive, generate and compile on first use)", progress)
    model = modelgen.load(name)
    export = export_model(model, folder / "generated", bool(getattr(model.functions, "cache_hit", False)), started)

    member = paper_settings(case)
    _step(f"{name}: inversion ({member.segment_count} segments, h = {member.h}, Cdec = {member.cdec})", progress)
    inversion = invert(Problem(model, trajectory_from_spec(case.trajectory.value)), method=Family(settings=member))
    inversion.write_csv(folder / "inversion.csv")
    inversion.write_summary(folder / "inversion-summary.json")
    files: list[Path] = [folder / "inversion.csv", folder / "inversion-summary.json"]
    files += [folder / "generated" / f for f in export.files]
    files += plot_inversion(inversion, folder, prefix="inversion_")

    sims: dict[str, SimulationResult] = {}
    sweeps: dict[str, list[dict[str, Any]]] = {}
    if name == "paper-sim":
        _step(f"{name}: closed loop, nonlinear and linear plants", progress)
        sims["pd"] = simulate(model, inversion, PAPER_PLANT, "pd")
        sims["pd-linear"] = simulate(model, inversion, "linear", "pd")
        t = inversion.t
        files.append(line_figure(
            folder / "fig3_desired_displacement.png",
            [(t, inversion.y_d, "desired", {"lw": 2.2, "color": "0.6"}), (t, inversion.y, "redefined", {"lw": 1.0, "color": "C0", "ls": "--"})],
            "time (s)", "end-effector displacement (m)", "Fig. 3: desired end-effector displacement",
        ))
        files += _simulation_figures(sims["pd"], folder, (4, 5, 6), "", "PD")
    else:
        _step(f"{name}: closed loop with PD alone and with the two-stage controller, fitted and model plants", progress)
        fitted = fitted_plant(case)
        sims["pd"] = simulate(model, inversion, PAPER_PLANT, "pd", **fitted)
        sims["two-stage"] = simulate(model, inversion, PAPER_PLANT, "two-stage", **fitted)
        sims["pd-model-plant"] = simulate(model, inversion, PAPER_PLANT, "pd")
        sims["two-stage-model-plant"] = simulate(model, inversion, PAPER_PLANT, "two-stage")
        sweeps = _sweeps(model, inversion, case, progress)
        files.append(acceleration_figure(folder / "fig8_desired_acceleration.png", inversion, "Fig. 8: desired end-effector acceleration"))
        files.append(velocity_displacement_figure(folder / "fig9_desired_velocity_displacement.png", inversion, "Fig. 9: desired end-effector velocity and displacement"))
        files += _simulation_figures(sims["pd"], folder, (10, 11, 12), "_pd", "PD alone")
        files += _simulation_figures(sims["two-stage"], folder, (14, 15, 16), "_two_stage", "pulse-width control")
        files.append(sensitivity_figure(
            folder / "sensitivity.png",
            [("coulomb_friction", "plant's sliding friction F_c (N m)", sweeps["friction"]),
             ("zeta", "plant's damping ratio zeta", sweeps["damping"])],
            f"{name}: tip error over the last second against the assumed plant (compensated friction "
            f"{sims['pd'].summary['friction_compensation']:g} N m)",
        ))
        with open(folder / "sensitivity.json", "w") as handle:
            json.dump(sweeps, handle, indent=1)
        files.append(folder / "sensitivity.json")
    for key, sim in sims.items():
        sim.write_csv(folder / f"simulation-{key}.csv")
        sim.write_summary(folder / f"simulation-{key}-summary.json")
        files += [folder / f"simulation-{key}.csv", folder / f"simulation-{key}-summary.json"]

    _step(f"{name}: the causal inversion beside its baselines (rest end, polynomial, stable inversion)", progress)
    from inversion.studies.compare import compare

    from .plots import comparison_figure

    comparison = compare(Problem(model, trajectory_from_spec(case.trajectory.value)))
    files.append(comparison.write_csv(folder / "compare.csv"))
    files.append(comparison_figure(comparison, folder / "compare.png", f"{name}: the causal inversion and its baselines"))

    effects = _effects(model, case)
    second = modelgen.load(name, modes=2).natural_frequencies_hz[1] if model.n < 2 else model.natural_frequencies_hz[1]
    numbers = {
        "zeros": [[float(z.real), float(z.imag)] for z in model.zeros],
        "n_unstable": model.n_unstable,
        "natural_frequencies_hz": model.natural_frequencies_hz.tolist(),
        "second_frequency_hz": float(second),
        "inversion": {k: inversion.summary[k] for k in ("max_redefinition_error", "final_redefined_output", "peak_torque",
                                                        "max_torque_jump", "max_constraint_residual", "max_condition_number", "r")},
        "simulations": {k: {m: s.summary[m] for m in ("final_tip_error", "steady_tip_error", "residual_vibration",
                                                      "max_tracking_error", "max_redefined_tracking_error", "peak_torque",
                                                      "settling_time", "settled")}
                        | {"pulses": len(s.summary["pulses"]), "plant": s.summary["plant"]} for k, s in sims.items()},
        "assumptions": {k: v.as_dict() | ({"effect": effects[k.removeprefix("model.")]} if k.removeprefix("model.") in effects else {})
                        for k, v in case.assumptions().items()},
        "sensitivity": sweeps,
        "comparison": comparison.rows,
        "seconds": time.perf_counter() - started,
    }
    (folder / "numbers.json").write_text(json.dumps(numbers, indent=1) + "\n")
    files.append(folder / "numbers.json")
    report = folder / "report.md"
    report.write_text(report_markdown(name, model, case, inversion, sims, sweeps, effects, numbers, files, folder))
    files.append(report)
    return Reproduction(folder, files, report, numbers)

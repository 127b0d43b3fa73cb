"""``sflm reproduce``: the paper's simulation (section 7) and experiment (section 8), end to end.

Generate the model's code, invert the paper's trajectory with the paper's settings,
simulate the closed loop, write the paper's figures and a ``report.md`` that puts our
numbers beside the paper's.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

import modelgen
from inversion import invert, trajectory_from_spec
from inversion.cases import CASES, PaperCase
from inversion.errors import SettingsError
from inversion.simulate import SimulationResult, simulate
from modelgen.export import export_model
from modelgen.paper import PAPER

from .formatting import zero_pairs
from .plots import acceleration_figure, line_figure, plot_inversion, plot_simulation, velocity_displacement_figure

__all__ = ["reproduce", "Reproduction", "REPRODUCIBLE"]

REPRODUCIBLE = ("paper-sim", "paper-exp")

# docs/method.md section 7: an independent implementation of sections 1-2 with the paper's settings
_METHOD_REFERENCE = {
    "paper-sim": {"max_redefinition_error": 5.73e-3, "final_redefined_output": 1.56427, "peak_torque": 0.4310},
    "paper-exp": {"max_redefinition_error": 1.81e-3},
}


@dataclass(frozen=True)
class Reproduction:
    """What :func:`reproduce` wrote."""

    folder: Path
    files: list[Path]
    report: Path
    numbers: dict[str, Any]


def _step(message: str, progress: Callable[[str], None] | None) -> None:
    if progress is not None:
        progress(message)


def _simulate_case(model: Any, inversion: Any, case: PaperCase, controller: str, plant: str = "nonlinear") -> SimulationResult:
    return simulate(model, inversion, plant=plant, controller=controller, **case.simulation_settings())  # type: ignore[arg-type]


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
            f"Fig. {f_err}: tip error, then {after} ({{steady}})",
        ),
    )


def reproduce(name: str, folder: Path, progress: Callable[[str], None] | None = None) -> Reproduction:
    """Run the paper's case ``name`` end to end and write figures and ``report.md`` into ``folder``.

    Raises
    ------
    SettingsError
        If ``name`` is not ``paper-sim`` or ``paper-exp``.
    """
    if name not in REPRODUCIBLE:
        raise SettingsError("case", name, "paper-sim or paper-exp")
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    case = CASES[name]
    started = time.perf_counter()

    _step(f"{name}: model (derive, generate and compile on first use)", progress)
    model = modelgen.load(name)
    export = export_model(model, folder / "generated", model.functions.cache_hit, started)

    _step(f"{name}: inversion ({case.segments} segments, h = {case.h}, Cdec = {case.cdec})", progress)
    inversion = invert(model, trajectory_from_spec(case.trajectory), segments=case.segments, h=case.h, cdec=case.cdec)
    inversion.write_csv(folder / "inversion.csv")
    inversion.write_summary(folder / "inversion-summary.json")
    files: list[Path] = [folder / "inversion.csv", folder / "inversion-summary.json"]
    files += [folder / "generated" / f for f in export.files]
    files += plot_inversion(inversion, folder, prefix="inversion_")

    sims: dict[str, SimulationResult] = {}
    if name == "paper-sim":
        _step(f"{name}: closed loop, nonlinear and linear plants", progress)
        sims["pd"] = _simulate_case(model, inversion, case, "pd")
        sims["pd-linear"] = _simulate_case(model, inversion, case, "pd", plant="linear")
        t = inversion.t
        files.append(line_figure(
            folder / "fig3_desired_displacement.png",
            [(t, inversion.y_d, "desired", {"lw": 2.2, "color": "0.6"}), (t, inversion.y, "redefined", {"lw": 1.0, "color": "C0", "ls": "--"})],
            "time (s)", "end-effector displacement (m)", "Fig. 3: desired end-effector displacement",
        ))
        files += _simulation_figures(sims["pd"], folder, (4, 5, 6), "", "PD")
    else:
        _step(f"{name}: closed loop with PD alone and with the two-stage controller", progress)
        sims["pd"] = _simulate_case(model, inversion, case, "pd")
        sims["two-stage"] = _simulate_case(model, inversion, case, "two-stage")
        files.append(acceleration_figure(folder / "fig8_desired_acceleration.png", inversion, "Fig. 8: desired end-effector acceleration"))
        files.append(velocity_displacement_figure(folder / "fig9_desired_velocity_displacement.png", inversion, "Fig. 9: desired end-effector velocity and displacement"))
        files += _simulation_figures(sims["pd"], folder, (10, 11, 12), "_pd", "PD alone")
        files += _simulation_figures(sims["two-stage"], folder, (14, 15, 16), "_two_stage", "pulse-width control")
    for key, sim in sims.items():
        sim.write_csv(folder / f"simulation-{key}.csv")
        sim.write_summary(folder / f"simulation-{key}-summary.json")
        files += [folder / f"simulation-{key}.csv", folder / f"simulation-{key}-summary.json"]

    numbers = {
        "zeros": [[float(z.real), float(z.imag)] for z in model.zeros],
        "n_unstable": model.n_unstable,
        "natural_frequencies_hz": model.natural_frequencies_hz.tolist(),
        "inversion": {k: inversion.summary[k] for k in ("max_redefinition_error", "final_redefined_output", "peak_torque", "max_torque_jump", "max_constraint_residual", "max_condition_number", "r")},
        "simulations": {k: {m: s.summary[m] for m in ("final_tip_error", "steady_tip_error", "residual_vibration", "max_tracking_error", "peak_torque", "settling_time")} | {"pulses": len(s.summary["pulses"])} for k, s in sims.items()},
        "seconds": time.perf_counter() - started,
    }
    (folder / "numbers.json").write_text(json.dumps(numbers, indent=1) + "\n")
    files.append(folder / "numbers.json")
    report = folder / "report.md"
    report.write_text(_report(name, model, case, inversion, sims, files, folder))
    files.append(report)
    return Reproduction(folder, files, report, numbers)


def _row(*cells: Any) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _report(name: str, model: Any, case: PaperCase, inv: Any, sims: dict[str, SimulationResult], files: list[Path], folder: Path) -> str:
    paper = PAPER[name]
    ref = _METHOD_REFERENCE[name]
    s = inv.summary
    ours_z = ", ".join(zero_pairs(model.zeros))
    paper_z = ", ".join(zero_pairs(np.array(paper["zeros"], dtype=complex), digits=2))
    lines = [
        f"# Reproduction of the paper's {'simulation' if name == 'paper-sim' else 'experiment'} ({case.description})",
        "",
        "\"Piece-wise causal inversion by output redefinition for a flexible link manipulator\", "
        "Trans. CSME 33(2), 2009. Generated by `sflm reproduce " + name + "` "
        f"(sflm {modelgen.__version__}, Python {sys.version.split()[0]}).",
        "",
        "## Model",
        "",
        _row("quantity", "ours", "paper", "note"),
        _row("---", "---", "---", "---"),
        _row("assumed modes", f"{model.n} {model.mode_family}", "2" if name == "paper-sim" else "1", "mode shapes of the paper's reference [14] are not at hand"),
        _row("zeros of Y(s)/tau(s)", ours_z, paper_z, "same structure; the values move with the mode shapes and with n (`sflm info " + name + " --convergence`)"),
        _row("unstable zeros n_u", model.n_unstable, paper["n_unstable"], "purely imaginary zeros count as unstable"),
        _row("internal dynamics", model.internal_dynamics, "non-hyperbolic" if name == "paper-sim" else "hyperbolic", ""),
        _row("flexible frequencies (Hz)", ", ".join(f"{f:.4g}" for f in model.natural_frequencies_hz), f"second mode {paper['second_frequency_hz']} Hz" if "second_frequency_hz" in paper else "not reported",
             "our second frequency with 2 modes: 52.94 Hz" if name == "paper-exp" else ""),
        "",
        "## Inversion",
        "",
        f"{len(s['segments'])} equal segments, h = {s['settings']['h']}, Cdec = {tuple(s['settings']['cdec'])}, "
        f"r = {s['r']} exponentials per segment.",
        "",
        _row("quantity", "ours", "independent implementation (docs/method.md)", "paper"),
        _row("---", "---", "---", "---"),
        _row("max abs(y~ - y_d)", f"{s['max_redefinition_error'] * 1e3:.4g} mm", f"{ref['max_redefinition_error'] * 1e3:.3g} mm", "shown in its figures only"),
    ]
    if name == "paper-sim":
        lines += [
            _row("y~(t_f)", f"{s['final_redefined_output']:.6g} m", f"{ref['final_redefined_output']} m", "y_d(t_f) = 1.57 m"),
            _row("peak abs(tau_l)", f"{s['peak_torque']:.4g} N m", f"{ref['peak_torque']} N m", "Fig. 4"),
        ]
    else:
        lines += [
            _row("peak abs(tau_l)", f"{s['peak_torque']:.4g} N m", "", "Fig. 10 (with PD and friction compensation)"),
        ]
    lines += [
        _row("torque jump at the joints", f"{s['max_torque_jump']:.2g} N m", "< 1e-11 N m", "continuous"),
        _row("segment systems", f"residual <= {s['max_constraint_residual']:.1g}, condition <= {s['max_condition_number']:.2g}", "", ""),
        "",
    ]
    if name == "paper-exp":
        lines += [
            "The independent implementation's 1.81 mm takes the left limit of the jerk's slope at the knots "
            "0.2 s and 0.4 s at the start of the next segment too; with the one-sided limits of Eq. (30) "
            "(ours) the redefinition error is 1.355 mm. The test suite reproduces both.",
            "",
        ]
    lines += ["## Closed loop", ""]
    if name == "paper-sim":
        pd, lin = sims["pd"].summary, sims["pd-linear"].summary
        lines += [
            f"Eq. (40) with k_P = {case.kp:g}, k_D = {case.kd:g}; after t_f = 5.5 s the PD alone holds "
            f"theta_d = y_d(t_f)/L. Simulated to {case.t_end:g} s.",
            "",
            _row("quantity", "nonlinear plant (P4)", "linear plant (P8)", "paper"),
            _row("---", "---", "---", "---"),
            _row("max abs(y - y~) during the manoeuvre", f"{pd['max_redefined_tracking_error'] * 1e3:.3g} mm", f"{lin['max_redefined_tracking_error'] * 1e3:.2g} mm", "exact model: PD has nothing to correct"),
            _row("max abs(y_d - y)", f"{pd['max_tracking_error'] * 1e3:.4g} mm", f"{lin['max_tracking_error'] * 1e3:.4g} mm", "Fig. 6"),
            _row(f"tip error at {case.t_end:g} s", f"{pd['final_tip_error'] * 1e3:.3g} mm", f"{lin['final_tip_error'] * 1e3:.3g} mm", "approaches 0 (Fig. 6)"),
            _row("peak applied torque", f"{pd['peak_torque']:.4g} N m", f"{lin['peak_torque']:.4g} N m", "Fig. 4"),
            "",
        ]
    else:
        pd, two = sims["pd"].summary, sims["two-stage"].summary
        lines += [
            f"Eq. (40) with k_P = {case.kp:g}, k_D = {case.kd:g}, plus the measured average dry friction "
            f"{case.friction_compensation:g} N m in the direction of the desired motion (stage 1); after t_f = 0.6 s "
            "PD alone (without the two-stage controller) or pulse-width control (stage 2). Nonlinear plant, "
            f"simulated to {case.t_end:g} s.",
            "",
            "Assumptions (the paper does not give them): the true hub friction is "
            f"{case.plant_coulomb:g} N m sliding and {case.plant_breakaway:g} N m breakaway, about 20 % above the "
            "average the controller compensates (the paper: the friction \"is hard to model exactly\"); the link's "
            f"material damping is {case.plant_damping:g} (Rayleigh). With the plant's friction equal to the "
            "compensated average, PD alone ends within 0.1 mm: the steady error comes from the mismatch.",
            "",
            _row("quantity", "PD alone", "two-stage", "paper"),
            _row("---", "---", "---", "---"),
            _row("steady tip error (mean over the last second)", f"{pd['steady_tip_error'] * 1e3:.3g} mm", f"{two['steady_tip_error'] * 1e3:.3g} mm", "about 10 mm / about 1 mm (Figs. 12, 16)"),
            _row("residual vibration (half peak-to-peak)", f"{pd['residual_vibration'] * 1e3:.2g} mm", f"{two['residual_vibration'] * 1e3:.2g} mm", "slowly vanishing vibration (Figs. 15-16)"),
            _row(f"tip error at {case.t_end:g} s", f"{pd['final_tip_error'] * 1e3:.3g} mm", f"{two['final_tip_error'] * 1e3:.3g} mm", ""),
            _row("pulses of stage 2", "-", len(two["pulses"]), "widths growing with the error"),
            _row("peak applied torque", f"{pd['peak_torque']:.4g} N m", f"{two['peak_torque']:.4g} N m", "Figs. 10, 14"),
            "",
        ]
    figures = [f for f in files if f.suffix == ".png"]
    lines += ["## Figures", ""] + [f"* [{f.name}]({f.relative_to(folder)})" for f in figures]
    lines += ["", "## Data", ""] + [f"* `{f.relative_to(folder)}`" for f in files if f.suffix in (".csv", ".json")]
    return "\n".join(lines) + "\n"

"""``sflm simulate``."""

from __future__ import annotations

import argparse
from typing import Any
from .arguments import add_inversion_arguments, add_model_arguments, add_uncertainty_arguments, case_of
from .common import check_out_before_work, emit, load_model, output_folder, read_feedforward, uncertainty_of
from .invert import inverted
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm simulate tests/data/own-aluminium.toml --feedforward run --controller pd --plot"


def add(sub: Any) -> None:
    """Add ``sflm simulate``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    sim = sub.add_parser("simulate", help="closed-loop simulation: feedforward plus joint PD, friction, two-stage control")
    add_model_arguments(sim)
    add_inversion_arguments(sim)
    add_uncertainty_arguments(sim, "run the same loop (plant, controller, friction) on every perturbed link, the joint PD tuned for "
                                    "the nominal one: geometry keys with relative ranges, e.g. link.flexural_rigidity=10%%,"
                                    "payload.mass=20%% (summary 'robustness')")
    sim.add_argument("--plant", choices=("linear", "nonlinear", "nonlinear-paper", "nonlinear-large"), default="nonlinear",
                     help="linear (P8); nonlinear (default): P4 with the link's foreshortening, the geometric stiffening that "
                          "balances the centrifugal softening; nonlinear-paper: the paper's P4 as it is; nonlinear-large: the "
                          "inextensible link with exact kinematics (foreshortening, curvature and payload angle to all orders) "
                          "for large deflections, at most 8 modes")
    sim.add_argument("--controller", choices=("none", "pd", "two-stage"), default="pd", help="feedforward only, with joint PD (Eq. 40), or the two-stage controller (default pd)")
    sim.add_argument("--kp", type=float, metavar="KP", help="joint PD gain (default: the paper's for its cases, else the documented rule)")
    sim.add_argument("--kd", type=float, metavar="KD", help="joint PD gain (default: the paper's for its cases, else the documented rule)")
    sim.add_argument("--t-end", type=float, metavar="T", help="end of the simulation in s (default: the paper case's; else the end of the feedforward plus the window its "
                     "run was judged through, --window of invert: 2 s by default)")
    sim.add_argument("--coulomb-friction", type=float, metavar="F", help="plant's sliding hub friction, N m (default: the model's)")
    sim.add_argument("--breakaway-friction", type=float, metavar="F", help="plant's breakaway hub friction, N m (default: as sliding)")
    sim.add_argument("--friction-compensation", type=float, metavar="F", help="friction added in the direction of the desired motion, N m (default: the model's)")
    sim.add_argument("--plant-damping", type=float, metavar="ZETA", help="plant's Rayleigh damping ratio if it differs from the model's")
    sim.add_argument("--paper-plant", action="store_true", help="the plant the paper case's report assumes, fitted to the paper's observations (paper-exp: friction 0.55/0.60 N m, zeta 0.01); recorded in summary.json")
    sim.add_argument("--pulse-amplitude", type=float, metavar="T", help="two-stage: pulse torque, N m (default: twice the known friction)")
    sim.add_argument("--pulse-gain", type=float, metavar="G", help="two-stage: fraction of the hub error one pulse aims at (default 0.8)")
    sim.add_argument("--pulse-tolerance", type=float, metavar="M", help="two-stage: stop within this tip-equivalent hub error, m (default 0.2 %% of the move)")
    sim.add_argument("--pulse-period", type=float, metavar="S", help="two-stage: time between decisions, s (default 0.25)")
    sim.add_argument("--engine", choices=("cvodes", "scipy"), default="cvodes", help="integrator: CVODES in compiled code, or SciPy from Python to cross-check (default cvodes)")
    sim.add_argument("--feedforward", metavar="RUN", help="simulate exactly the table a run of sflm invert judged (its --out "
                     "folder, summary.json or inversion.csv; any method): its rows held over its period, no inversion here")
    sim.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/simulate)")
    sim.add_argument("--json", action="store_true", help="print summary.json")
    sim.add_argument("--plot", action="store_true", help="write torque.png, tip.png, tip_error.png")


def plant_arguments(args: argparse.Namespace, name: str) -> dict[str, Any]:
    """The plant's keyword arguments of :func:`simulation.simulate`, each value with its source."""
    from modelgen.errors import SettingsError
    from simulation.cases import fitted_plant

    out: dict[str, Any] = {"plant_overrides": {}, "plant_sources": {}}
    if args.paper_plant:
        case = case_of(args, name)
        if case is None or not case.plant:
            raise SettingsError("--paper-plant", name, "a paper case whose report assumes a plant (paper-exp)")
        fitted = fitted_plant(case)
        out["plant_overrides"].update(fitted.pop("plant_overrides"))
        out["plant_sources"].update(fitted.pop("plant_sources"))
        out.update(fitted)
    for option, key in (("coulomb_friction", "coulomb_friction"), ("breakaway_friction", "breakaway_friction"),
                        ("plant_damping", "zeta")):
        value = getattr(args, option)
        if value is None:
            continue
        if key == "zeta":
            out["plant_overrides"]["zeta"] = value
        else:
            out[key] = value
        out["plant_sources"][key] = f"command line (--{option.replace('_', '-')})"
    return out


def run(args: argparse.Namespace) -> int:
    """Run ``sflm simulate``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from simulation import simulate

    from ..summaries import simulation_text

    model = load_model(args, system=False)
    uncertainty = uncertainty_of(args, model)  # checked before the work
    check_out_before_work(args, model.name, "simulate")  # as --out, before the work (a run it reads, another command's)
    if args.feedforward is not None:
        inversion = read_feedforward(args, model)
    else:
        inversion = inverted(args, model)
    pulse = {"amplitude": args.pulse_amplitude, "gain": args.pulse_gain, "tolerance": args.pulse_tolerance,
             "period": args.pulse_period}
    options = dict(plant=args.plant, controller=args.controller, kp=args.kp, kd=args.kd, t_end=args.t_end,
                   friction_compensation=args.friction_compensation, pulse=pulse, rate=args.rate, engine=args.engine,
                   **plant_arguments(args, model.name))
    with args.reporter.stage("simulate", unit="%") as bar:
        result = simulate(model, inversion, progress=lambda fraction: bar(int(round(100 * fraction)), 100), **options)
    if uncertainty is not None:
        from simulation import simulate_uncertain

        with args.reporter.stage("perturbed links", unit="links") as bar:
            result = simulate_uncertain(model, inversion, uncertainty, nominal=result, progress=bar, **options)
    return emit(args, result, output_folder(args, model.name, "simulate"), "simulation.csv", "plot_simulation", simulation_text)

"""The ``sflm`` command line.

Subcommands: ``info``, ``generate``, ``invert``, ``explore``, ``compare``, ``simulate``, ``reproduce``, ``fmu``. User errors print one line on
stderr and exit with status 2; warnings print one line on stderr.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import warnings
from pathlib import Path
from typing import Any, NoReturn, Sequence

from inversion.config import DEFAULTS, tip_bound
from inversion.realtime.feedforward_c import export_c, export_table
from modelgen.errors import SflmError

from . import __version__

__all__ = ["main"]


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def _add_model_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL", help="a preset (paper-sim, paper-exp, hyperbolic, near-non-hyperbolic) or a geometry .toml "
                   "file; for info, invert, explore and compare also a transfer function in s, '(2 - s)/(s + 1)^3', or a .toml/.json "
                   "file with numerator and denominator (descending powers of s)")
    p.add_argument("--modes", type=int, metavar="N", help="number of assumed modes (default: the geometry's)")
    p.add_argument("--mode-shapes", metavar="F", help="mode-shape family: clamped-mass, clamped-free or polynomial")
    p.add_argument("--output-at", type=float, metavar="X",
                   help="where the output y = X theta + w(X) is measured, 0 < X <= L (m; default L, the tip)")


def _load_model(args: argparse.Namespace, system: bool = True) -> Any:
    """The model the command's MODEL, --modes, --mode-shapes and --output-at describe: a link, or (where ``system``) a
    transfer function in ``s`` or a file of one (:mod:`sflm.systems`)."""
    import modelgen

    from .systems import looks_like_transfer_function, system_from_model_argument, transfer_function_file

    if looks_like_transfer_function(args.model) or transfer_function_file(args.model):
        from modelgen.errors import SettingsError

        if not system:
            raise SettingsError("MODEL", args.model, f"a preset or a geometry file for sflm {args.command} (it is about a link's "
                                "model; a transfer function goes to invert, explore, compare and info)")
        for option, value in (("--modes", args.modes), ("--mode-shapes", args.mode_shapes), ("--output-at", args.output_at)):
            if value is not None:
                raise SettingsError(option, value, "nothing for a transfer function (it is about a link's assumed modes)")
        return system_from_model_argument(args.model)
    if hasattr(args, "reporter"):
        args.reporter(f"loading {args.model} (derived, generated and compiled the first time, then cached)")
    return modelgen.load(args.model, modes=args.modes, mode_shapes=args.mode_shapes, output_at=args.output_at)


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="sflm", description="Single flexible link manipulator: models, generated code, causal inversion.")
    parser.add_argument("--version", action="version", version=f"sflm {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    for add in (_add_info, _add_generate, _add_invert, _add_explore, _add_compare, _add_simulate, _add_reproduce, _add_fmu, _add_fit):
        add(sub)
    for command in sub.choices.values():  # every command: past 2 s its stage on stderr at least every 5 s, unless asked not to
        command.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr (past 2 s a command reports its "
                             "stage there at least every 5 s: a bar on a terminal, lines otherwise)")
    return parser


def _percent(fraction: float) -> str:
    """A default fraction as a percentage in an argparse help text (``%`` doubled)."""
    return f"{100 * fraction:g} %%"


def _list_text(values: Sequence[Any]) -> str:
    """A default list as the command line takes it."""
    return ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values)


def _add_info(sub: Any) -> None:
    info = sub.add_parser("info", help="model matrices, natural frequencies, zeros")
    _add_model_arguments(info)
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.add_argument("--matrices", action="store_true", help="also print the matrices (always in --json)")
    info.add_argument("--convergence", action="store_true", help="frequencies and zeros for n = 1..N beside a finite-element continuum reference")
    info.add_argument("--plot", action="store_true",
                      help="with --convergence: write convergence.png, frequencies and zeros against n for the three mode-shape families beside the continuum")
    info.add_argument("--out", metavar="DIR", help="folder of --plot (default sflm-out/<name>/info)")
    info.add_argument("--max-modes", type=int, default=8, metavar="N", help="largest n of --convergence when --modes is not given (default %(default)s)")
    info.add_argument("--trajectory", metavar="SPEC", help="the causal limit of this move: the least error any causal feedforward from "
                      "rest can hold it to (the zeros with Re > 0 alone), and the shortest duration of the same move that meets "
                      "--max-error; " + _TRAJECTORY_HELP_SHORT)
    info.add_argument("--max-error", type=float, metavar="E", help=f"with --trajectory: the bound the shortest duration is found for "
                      f"(default {_percent(DEFAULTS.bound)} of the move)")
    info.add_argument("--period", type=float, metavar="DT", help="with --trajectory: also the bounded causal limit, the least error "
                      "any causal feedforward held at DT s reaches within the torque and rate bounds (a linear programme)")
    info.add_argument("--max-torque", type=float, metavar="T", help="with --period: the peak torque bound (default "
                      f"{DEFAULTS.torque_ratio:g} x the rigid need)")
    info.add_argument("--max-torque-rate", type=float, metavar="R", help="with --period: the bound on the change between rows "
                      f"(default {DEFAULTS.torque_rate_ratio:g} x the rigid need's change over a period)")


def _add_generate(sub: Any) -> None:
    gen = sub.add_parser("generate", help="generate, compile and write the model's C code and manifest")
    _add_model_arguments(gen)
    gen.add_argument("--out", metavar="DIR", help="output folder (default generated/<name>-n<N>-<family>/)")
    gen.add_argument("--json", action="store_true", help="print the manifest as JSON")


def _add_invert(sub: Any) -> None:
    inv = sub.add_parser("invert", help="piece-wise causal inversion of a desired tip trajectory")
    _add_model_arguments(inv)
    _add_inversion_arguments(inv)
    _add_uncertainty_arguments(inv)
    inv.add_argument("--workers", type=int, metavar="N", help="with --objective robust: local processes for the explorer and the "
                     "judging (default: all cores; 1 runs in this process)")
    inv.add_argument("--scheduler", metavar="ADDRESS", help="with --objective robust: run them on an existing Dask distributed "
                     "cluster (pip install 'sflm[dask]')")
    inv.add_argument("--controller", choices=("none", "pd"), default=None,
                     help="the loop the table is judged in: none (default), the feedforward alone; pd, the joint PD of Eq. (40) "
                          "closed too (the paper's experiment, as sflm simulate runs it): every candidate must hold the tip within "
                          "--max-error in both, during the move and after it, and the summary reports both")
    inv.add_argument("--kp", type=float, metavar="KP", help="with --controller pd: the joint PD gain k_P (default: the paper's for "
                     "its cases, else the documented rule, as sflm simulate)")
    inv.add_argument("--kd", type=float, metavar="KD", help="with --controller pd: the joint PD gain k_D (default as --kp)")
    inv.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/invert)")
    inv.add_argument("--json", action="store_true", help="print summary.json")
    inv.add_argument("--plot", action="store_true", help="write output.png, redefinition_error.png, torque.png")
    inv.add_argument("--method", choices=["ssef", "polynomial", "stable", "ocp", "zv", "zvd", "replan"], default=None,
                     help="default: the paper's member for the paper's case as shipped or a member given, else the automatic "
                          "choice across methods (the family first; the optimal-control feedforward at the controller's period "
                          "only when no member passes; with --preview, stable inversion truncated to it competes); "
                          "ssef: the paper's causal inversion alone; polynomial: the same conditions met by a polynomial "
                          "per segment (one solution); stable: the non-causal stable-inversion baseline (exact tracking, "
                          "torque before t0; refused for purely imaginary zeros); ocp: the optimal-control feedforward, the least "
                          "peak torque (--objective torque) or energy (--objective energy) keeping the tip within --max-error at "
                          "every sample of --period (CasADi + IPOPT): the limit of any causal feedforward; zv, zvd: input shaping "
                          "(Singer & Seering) of the rigid joint reference, driven by the joint PD of simulate's rule: aimed at the "
                          "vibration after the move, not at the tip during it; replan: the move reshaped within --max-error (a "
                          "linear programme over splines) so that it is exactly, causally invertible and ends at rest, inverted "
                          "exactly: near the optimal-control limit's peak torque, smooth, in about a second")
    inv.add_argument("--preview", type=float, metavar="S", help="seconds of torque allowed before the move starts: stable "
                     "inversion truncated to S competes in the automatic choice (or bounds --method stable's pre-actuation)")
    inv.add_argument("--export-c", metavar="DIR", help="write DIR/feedforward.c and feedforward.h: the feedforward's closed form in C99 (freestanding: no library, not even libm)")
    inv.add_argument("--export-table", metavar="FILE", help="write t, tau, theta_d, thetadot_d at --rate as C arrays in FILE (a .h)")
    inv.add_argument("--c-prefix", default=DEFAULTS.c_prefix, metavar="NAME",
                     help="prefix of the exported C symbols (default %(default)s: %(default)s_eval)")


def _add_explore(sub: Any) -> None:
    grid = DEFAULTS.grid
    exp = sub.add_parser("explore", help="the family of redefinitions on a grid: errors, torques, the Pareto front, the best member")
    _add_model_arguments(exp)
    exp.add_argument("--trajectory", metavar="SPEC", help=_TRAJECTORY_HELP)
    _add_smooth_argument(exp)
    exp.add_argument("--segments", type=_int_list, metavar="LIST", help=f"segment counts, comma-separated (default {_list_text(grid.segments)})")
    exp.add_argument("--h", type=_int_list, metavar="LIST", help=f"orders of smooth joining (default {_list_text(grid.h)})")
    exp.add_argument("--cdec-fast", type=_float_list, metavar="LIST", help=f"fastest decays Cdec_f (default {_list_text(grid.cdec_fast)})")
    exp.add_argument("--cdec-slow", type=_float_list, metavar="LIST", help=f"slowest decays Cdec_s (default {_list_text(grid.cdec_slow)}; "
                     "pairs with Cdec_f >= Cdec_s are skipped)")
    exp.add_argument("--joining", type=_str_list, metavar="LIST", help=f"joinings: paper, position, anchored (default {_list_text(grid.joining)})")
    exp.add_argument("--eps", type=float, default=None, metavar="E", help=f"zeros with Re >= -E count as unstable (default {DEFAULTS.eps:g})")
    exp.add_argument("--end", type=_str_list, metavar="LIST", help="how the members end: free, settle (anchored only), rest "
                     "(default free, the paper's)")
    exp.add_argument("--objective", choices=("torque", "error"), default=None,
                     help=f"the automatic choice's objective, which marks the chosen member (default {DEFAULTS.objective})")
    exp.add_argument("--period", type=float, metavar="DT", help="the controller's period the chosen member is judged at "
                     f"(s; default {1 / DEFAULTS.rate:g}); with --plot, of the optimal-control front (default {DEFAULTS.ocp_period:g})")
    exp.add_argument("--hold", choices=("point", "zoh"), default=None, help=f"how the chosen member's samples are held (default {DEFAULTS.hold})")
    exp.add_argument("--max-torque", type=float, metavar="T", help="members with a larger peak torque (N m) are not chosen")
    exp.add_argument("--max-error", type=float, metavar="E", help=f"in m: the members' quality gate (default {_percent(DEFAULTS.quality_gate)} of "
                     f"the move) and the chosen member's tip bound (default {_percent(DEFAULTS.bound)}); inf accepts any")
    exp.add_argument("--workers", type=int, metavar="N", help="local processes (default: all cores; 1 runs in this process)")
    exp.add_argument("--scheduler", metavar="ADDRESS", help="run on an existing Dask distributed cluster (pip install 'sflm[dask]')")
    exp.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/explore)")
    _add_uncertainty_arguments(exp, "judge the members within the bounds (at most 16, spread over their peak torques) on perturbed "
                                    "links in the closed loop with the joint PD: geometry keys with relative ranges, e.g. "
                                    "link.flexural_rigidity=10%%,payload.mass=20%%; explore.csv gains worst_case_error, pareto.png "
                                    "colours by it")
    exp.add_argument("--json", action="store_true", help="print summary.json")
    exp.add_argument("--plot", action="store_true", help="write pareto.png")


def _add_compare(sub: Any) -> None:
    cmp = sub.add_parser("compare", help="the causal inversion beside its baselines (SSEF, SSEF with a rest end, polynomial, stable "
                                            "inversion) and the alternatives (optimal control, ZV, ZVD)")
    _add_model_arguments(cmp)
    _add_inversion_arguments(cmp)
    _add_uncertainty_arguments(cmp)
    cmp.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<name>/compare)")
    cmp.add_argument("--json", action="store_true", help="print the rows as JSON")
    cmp.add_argument("--plot", action="store_true", help="write compare.png: the torques on one time axis and the tip errors")


def _add_simulate(sub: Any) -> None:
    sim = sub.add_parser("simulate", help="closed-loop simulation: feedforward plus joint PD, friction, two-stage control")
    _add_model_arguments(sim)
    _add_inversion_arguments(sim)
    _add_uncertainty_arguments(sim, "run the same loop (plant, controller, friction) on every perturbed link, the joint PD tuned for "
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
    sim.add_argument("--t-end", type=float, metavar="T", help="end of the simulation in s (default: the paper case's; else t_f + 3 s)")
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


def _add_reproduce(sub: Any) -> None:
    rep = sub.add_parser("reproduce", help="the paper's simulation or experiment end to end: figures and report.md")
    rep.add_argument("case", metavar="CASE", choices=("paper-sim", "paper-exp"), help="paper-sim (section 7) or paper-exp (section 8)")
    rep.add_argument("--out", metavar="DIR", help="output folder (default sflm-out/<case>)")


def _add_fit(sub: Any) -> None:
    fit = sub.add_parser("fit", help="calibrate a geometry file to what was measured on the bench: natural frequencies, a "
                                     "frequency response or a time series")
    fit.add_argument("model", metavar="GEOMETRY", help="the nominal geometry .toml file (or a preset)")
    fit.add_argument("--data", required=True, metavar="FILE", help="frequencies (.toml: frequencies_hz = [...], boundary = "
                     "'hub-free' or 'hub-clamped'), a frequency response (.csv: f,magnitude,phase in Hz, absolute, degrees) or "
                     "a time series (.csv: t,tau,theta[,y], open loop from rest)")
    fit.add_argument("--params", metavar="LIST", help="the dotted names to fit, comma-separated (default: link.flexural_rigidity, "
                     "payload.mass, payload.inertia, hub.inertia, damping.ratio -- with [damping] modal, damping.modal_K for "
                     "each mode K the data reaches -- less those zero in the geometry or that the data's noise hides)")
    fit.add_argument("--output", choices=("theta", "y"), help="a frequency response's output: the hub angle (default) or the tip")
    fit.add_argument("--kp", type=float, metavar="KP", help="a closed-loop record's (t,tau_ff,theta_d,theta[,y]) joint PD gain k_P")
    fit.add_argument("--kd", type=float, metavar="KD", help="a closed-loop record's joint PD gain k_D")
    fit.add_argument("--modes", type=int, metavar="N", help="number of assumed modes (default: the geometry's)")
    fit.add_argument("--out", metavar="FILE", help="the calibrated geometry file to write (default sflm-out/<name>/fit/<name>-calibrated.toml)")
    fit.add_argument("--json", action="store_true", help="print the fit's figures as JSON")
    fit.add_argument("--plot", action="store_true", help="write fit.png beside the calibrated file: measured, nominal and fitted")


def _add_fmu(sub: Any) -> None:
    fmu = sub.add_parser("fmu", help="the model as an FMI 2.0 model-exchange FMU (input tau; outputs y, theta, thetadot, the "
                                     "deflections), or with --feedforward the feedforward of a summary.json")
    _add_model_arguments(fmu)
    fmu.add_argument("--plant", choices=("linear", "nonlinear"), default="nonlinear",
                     help="the right-hand side the FMU integrates: linear (P8) or nonlinear (default): P4 with the geometric stiffening")
    fmu.add_argument("--feedforward", metavar="RUN", help="an FMU of the feedforward itself (time in; tau, theta_d, thetadot_d "
                     "out): the table a run of sflm invert judged (its --out folder, summary.json or inversion.csv: any method), "
                     "or the member of an explore best.json, inverted again for MODEL")
    fmu.add_argument("--trajectory", metavar="SPEC", help="with --feedforward: " + _TRAJECTORY_HELP_SHORT)
    fmu.add_argument("--out", metavar="FILE", help="the .fmu to write (default sflm-out/<name>/fmu/<name>.fmu, or <name>-feedforward.fmu)")
    fmu.add_argument("--json", action="store_true", help="print what the FMU holds as JSON")


_TRAJECTORY_HELP_SHORT = "paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER] or a CSV file (presets default to the paper's)"
_TRAJECTORY_HELP = ("paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER] or a CSV file (t,y; FILE.csv:smoothing=S to smooth a "
                    "measured one); presets default to the paper's")


def _add_uncertainty_arguments(p: argparse.ArgumentParser, text: str | None = None) -> None:
    p.add_argument("--uncertainty", metavar="SPEC",
                   help=text or "judge the result on perturbed links in the closed loop with the joint PD: geometry keys with "
                                "relative ranges, e.g. link.flexural_rigidity=10%%,payload.mass=20%% (damping.modal_K: mode K's ratio of a "
                                "link damped per mode; fit:FILE: a calibration's intervals; every corner; summary 'robustness')")
    p.add_argument("--samples", type=int, default=0, metavar="N", help="with --uncertainty: also N seeded Latin-hypercube samples")


def _add_smooth_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--smooth", type=float, metavar="S", help="for a measured CSV trajectory: the smoothing factor s of its quintic "
                   "spline (scipy.interpolate.splrep: the squared residuals sum to at most s; about n sigma^2 for n samples of "
                   "noise sigma), the same as FILE.csv:smoothing=S")


def _add_inversion_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--trajectory", metavar="SPEC", help=_TRAJECTORY_HELP)
    _add_smooth_argument(p)
    p.add_argument("--segments", type=int, metavar="K", help="number of equal segments (preset default: the paper's)")
    p.add_argument("--h", type=int, metavar="H", help="order of smooth joining, Eq. (30) (preset default: the paper's)")
    p.add_argument("--cdec", type=float, nargs=2, metavar=("F", "S"), help="fastest and slowest decay over a segment, Eq. (35)")
    p.add_argument("--joining", choices=("paper", "position", "anchored"), help="joining conditions: the paper's, plus position, plus the unstable state anchored at the joints (default: paper for the paper's cases, else anchored)")
    p.add_argument("--auto", action="store_true", help="choose the member automatically by --objective: the least peak torque (default) or the smallest error among the members that reach the link within --max-error (the default for a geometry file or a trajectory not the preset's own)")
    p.add_argument("--settings", metavar="FILE", help="reuse a member: best.json of sflm explore, or a summary.json")
    p.add_argument("--max-error", type=float, metavar="E", help=f"quality gate: largest accepted max |y~ - y_d| in m (default {_percent(DEFAULTS.quality_gate)} "
                   f"of the move, {_percent(DEFAULTS.bound)} for the automatic choice; inf accepts any)")
    p.add_argument("--max-torque", type=float, metavar="T", help=f"largest accepted peak torque in N m (default "
                   f"{DEFAULTS.torque_ratio:g} x what a rigid link needs along y_d; inf accepts any)")
    p.add_argument("--max-torque-rate", type=float, metavar="R", help=f"largest accepted change of the held table from one row to "
                   f"the next, the first row against zero, in N m (default {DEFAULTS.torque_rate_ratio:g} x a rigid link's largest "
                   "change over one period along y_d; inf accepts any)")
    p.add_argument("--margin", type=float, metavar="F", help=f"the fraction of the bound the table keeps free (default "
                   f"{DEFAULTS.margin:g}: the automatic choice, optimal control and the re-plan aim within {1 - DEFAULTS.margin:g} of "
                   "--max-error where the bounded causal limit leaves room, within half the room where it leaves less; 0: the "
                   "limit itself). Every summary reports the margin kept and the plant errors the table tolerates")
    p.add_argument("--edges", choices=("match", "rest"), default=None,
                   help="how the redefined output meets y_d at t0 and tf: match (the paper's: y_d's acceleration and its first h "
                        "derivatives) or rest (its acceleration with those derivatives zero: the torque leaves and reaches rest with "
                        "zero slope where the move's jerk jumps at its ends). The automatic choice tries both where they differ")
    p.add_argument("--eps", type=float, default=None, metavar="E", help=f"zeros with Re >= -E count as unstable (default {DEFAULTS.eps:g})")
    p.add_argument("--end", choices=("free", "rest", "settle"), default=None,
                   help="free: the paper's end (the torque stops at t_f); rest: the feedforward ends at zero torque with the link at "
                        "rest (Remark 2); settle: after t_f the tip is held on y_d(t_f) while the link's internal modes decay (a causal "
                        "post-actuation; anchored joining). The automatic choice tries all three unless one is given")
    p.add_argument("--objective", choices=("torque", "error", "energy", "robust"), default=None,
                   help=f"what the automatic choice minimises: torque (default), the least peak torque within --max-error (default "
                        f"{_percent(DEFAULTS.bound)} of the move); error, the least error within the torque limit (default "
                        f"{DEFAULTS.torque_ratio:g} x what a rigid link needs); "
                        "energy: the optimal-control feedforward's other objective (--method ocp); robust (invert, with "
                        "--uncertainty): the least worst-case error on the perturbed links")
    p.add_argument("--period", type=float, metavar="DT",
                   help="the controller's period in s (default 1/--rate): the held table the summary's sampled block judges")
    p.add_argument("--hold", choices=("point", "zoh"), default=None,
                   help=f"point{' (default)' if DEFAULTS.hold == 'point' else ''}: samples at --rate, each value held by the controller; "
                        f"zoh{' (default)' if DEFAULTS.hold == 'zoh' else ''}: one row a period, the torque "
                        "its mean over the period it is held for (an error of O(DT^2) where the point value's is O(DT))")
    p.add_argument("--window", type=float, metavar="S",
                   help="seconds after the feedforward ends over which the tip must stay within --max-error of y_d(t_f) "
                        f"(default {DEFAULTS.vibration_window:g}, or 5 time constants of the plant's slowest stable mode)")
    p.add_argument("--zeros", choices=("all", "physical", "converged"), default=None,
                   help="unstable zeros the inversion constrains: all (default); physical: all but the truncation artefacts; "
                        "converged: only those converged to the continuum's. The others are left free; the full plant still checks the torque")
    p.add_argument("--rate", type=float, default=None, metavar="HZ", help=f"sampling rate of the output (default {DEFAULTS.rate:g}; at most "
                   f"{DEFAULTS.max_samples:,} samples: ~1.5 GB of CSV, with a progress bar)")
    p.add_argument("--tol", type=float, default=None, metavar="TOL", help=f"largest accepted relative residual of a segment system (default {DEFAULTS.tol:g})")


def _list(kind: type, text: str) -> list[Any]:
    """A comma-separated list for argparse (one line and exit 2 on a bad value)."""
    try:
        values = [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of {kind.__name__} values") from None
    if not values:
        raise argparse.ArgumentTypeError("an empty list")
    return values


def _int_list(text: str) -> list[int]:
    return _list(int, text)


def _float_list(text: str) -> list[float]:
    return _list(float, text)


def _str_list(text: str) -> list[str]:
    return _list(str, text)


def _case(args: argparse.Namespace, name: str) -> Any:
    """The paper case of a preset (``None`` for a geometry file, even one named like a preset)."""
    from modelgen.paper import case_named

    return case_named(name) if Path(str(args.model)).suffix.lower() != ".toml" else None


def _trajectory(args: argparse.Namespace, name: str) -> Any:
    """The desired trajectory: ``--trajectory``, or the preset's own."""
    from inversion.signals.trajectory import trajectory_from_spec
    from modelgen.errors import SettingsError

    case = _case(args, name)
    smooth = getattr(args, "smooth", None)
    if smooth is not None:
        if args.trajectory is None or not args.trajectory.strip().lower().endswith(".csv"):
            raise SettingsError("--smooth", smooth, "a smoothing for a CSV trajectory (--trajectory FILE.csv)")
        args.trajectory = f"{args.trajectory}:smoothing={smooth!r}"
    if args.trajectory is not None and not args.trajectory.strip():
        raise SettingsError("--trajectory", args.trajectory, "paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER] or a CSV "
                            "file (leave it out for a preset's own)")
    spec = args.trajectory or (case.trajectory.value if case else None)
    if spec is None:
        from .systems import looks_like_transfer_function

        what = "a transfer function has no move of its own" if looks_like_transfer_function(name) else (
            "a geometry file has no move of its own")
        raise SettingsError("--trajectory", None, f"a move ({what}): smoothstep:DISTANCE:DURATION[:ORDER], paper-sim, paper-exp or "
                            "a CSV file of t,y")
    return trajectory_from_spec(spec)


def _inversion_settings(args: argparse.Namespace, name: str) -> dict[str, Any]:
    """The keyword arguments of :func:`inversion.invert` from the command line.

    Values not given stay ``None``: :func:`inversion.invert` then takes the paper's member for
    a preset with its own trajectory, and chooses automatically otherwise (``--auto``).
    """
    return {
        "trajectory": _trajectory(args, name),
        "segments": args.segments,
        "h": args.h,
        "cdec": tuple(args.cdec) if args.cdec is not None else None,
        "joining": args.joining,
        "eps": args.eps,
        "end": args.end,
        "settings": args.settings,
        "auto": True if args.auto else None,
        "max_error": args.max_error,
        "max_torque": args.max_torque,
        "max_torque_rate": args.max_torque_rate,
        **({"margin": args.margin} if getattr(args, "margin", None) is not None else {}),
        "edges": args.edges,
        "rate": args.rate,
        "tol": args.tol,
        "method": getattr(args, "method", None),  # simulate: the automatic choice across methods, as invert makes it
        **({"preview": args.preview} if getattr(args, "preview", None) is not None else {}),
        **({"zeros": args.zeros} if args.zeros else {}),
        "objective": args.objective,
        "period": args.period,
        "hold": args.hold,
        "window": args.window,
    }


def _output_folder(args: argparse.Namespace, name: str, what: str) -> Path:
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in name).strip("._") or "system"  # '(2-s)/(s+1)^3' too
    folder = Path(args.out) if args.out else Path("sflm-out") / safe / what
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=folder):  # an existing read-only folder fails here, before any work is lost
            pass
    except OSError as exc:
        from modelgen.errors import SettingsError

        raise SettingsError("--out", str(folder), f"a folder that can be created and written ({exc.strerror})") from None
    return folder


def _uncertainty(args: argparse.Namespace, model: Any = None) -> Any:
    """``--uncertainty SPEC`` (and ``--samples``) parsed and checked against ``model``, or ``None``."""
    from inversion.studies.robustness import parse_uncertainty
    from modelgen.errors import SettingsError

    if args.uncertainty is None:
        if args.samples:
            raise SettingsError("--samples", args.samples, "0 without --uncertainty (the samples are of its ranges)")
        return None
    parsed = parse_uncertainty(args.uncertainty, args.samples)
    if model is not None:
        parsed.check(model)  # before the work: a transfer function, or a key that is zero in the geometry
    return parsed


def _robust(args: argparse.Namespace, model: Any, uncertainty: Any) -> Any:
    """``--objective robust``: the member of least worst-case error on the perturbed links (:func:`inversion.studies.robustness.robust_choice`)."""
    from inversion.studies.robustness import robust_choice
    from modelgen.errors import SettingsError

    if uncertainty is None:
        raise SettingsError("--objective", "robust", "robust together with --uncertainty SPEC (the links it is robust to)")
    given = [name for name in ("segments", "h", "cdec", "joining", "settings", "end") if getattr(args, name, None) is not None]
    if given or args.method not in (None, "ssef") or getattr(args, "preview", None) is not None or args.command != "invert":
        raise SettingsError("--objective", "robust", "invert of the family (no --method, member settings or --end: it explores them)")
    executor = _dask_client(args.scheduler) if args.scheduler else None
    try:
        with args.reporter.stage("robust choice", unit="members") as bar:
            return robust_choice(model, _trajectory(args, model.name), uncertainty, max_error=args.max_error, max_torque=args.max_torque,
                                 progress=bar, workers=args.workers, executor=executor)
    finally:
        if executor is not None:
            executor.close()


def _invert(args: argparse.Namespace, model: Any, **more: Any) -> Any:
    """:func:`inversion.invert` with the command line's settings (progress of an automatic choice on stderr)."""
    loop: dict[str, Any] = {}
    if getattr(args, "command", None) == "invert":  # the loop invert judges in (simulate runs its own, --controller)
        if args.controller != "pd" and (args.kp is not None or args.kd is not None):
            from modelgen.errors import SettingsError

            raise SettingsError("--kp" if args.kp is not None else "--kd", args.kp if args.kp is not None else args.kd,
                                "a gain together with --controller pd (the loop the table is judged in)")
        loop = {"controller": args.controller,
                **({"gains": (args.kp, args.kd)} if args.kp is not None or args.kd is not None else {})}
    from inversion.api import from_keywords, resolve

    flat = _inversion_settings(args, model.name)
    trajectory = flat.pop("trajectory")
    method = flat.pop("method")
    problem, chosen = from_keywords(model, trajectory, method, {**flat, **loop, **more})
    return resolve(problem, chosen, args.reporter)


def _cmd_invert(args: argparse.Namespace) -> int:

    from .summaries import inversion_text

    if args.export_c or args.export_table:
        from inversion.realtime.feedforward_c import check_prefix

        check_prefix(args.c_prefix)  # before the work
    model = _load_model(args)
    uncertainty = _uncertainty(args, model)  # checked before the work
    for option, value in (("--workers", args.workers), ("--scheduler", args.scheduler)):
        if value is not None and args.objective != "robust":
            from modelgen.errors import SettingsError

            raise SettingsError(option, value, "nothing without --objective robust (the one search invert spreads over processes)")
    if args.objective == "robust":
        result = _robust(args, model, uncertainty)
    else:  # the optimal-control programme holds the corners at once
        result = _invert(args, model, **({} if uncertainty is None else {"uncertainty": uncertainty}))
    if uncertainty is not None and args.objective != "robust":
        from inversion.studies.robustness import judge_robustness

        judge_robustness(result, uncertainty)
    extra: list[str] = []
    from modelgen.errors import SettingsError

    try:
        if args.export_c:
            extra += [str(p) for p in export_c(result, args.export_c, args.c_prefix)]
        if args.export_table:
            extra.append(str(export_table(result, args.export_table, args.c_prefix)))
    except SettingsError as exc:
        if exc.parameter in ("folder", "path"):  # the file or folder the flag named
            raise SettingsError("--export-c" if exc.parameter == "folder" else "--export-table", exc.value, exc.accepted) from None
        raise
    return _emit(args, result, _output_folder(args, model.name, "invert"), "inversion.csv", "plot_inversion", inversion_text, extra)


def _cmd_explore(args: argparse.Namespace) -> int:
    from inversion.family.explore import explore

    from .summaries import exploration_text

    model = _load_model(args)
    trajectory = _trajectory(args, model.name)
    folder = _output_folder(args, model.name, "explore")
    uncertainty = _uncertainty(args, model)  # checked before the work
    executor = _dask_client(args.scheduler) if args.scheduler else None
    try:
        with args.reporter.stage("explore", unit="members") as bar:
            result = explore(
                model, trajectory, segments=args.segments, h=args.h, cdec_fast=args.cdec_fast, cdec_slow=args.cdec_slow,
                joining=args.joining, eps=args.eps, end=args.end, max_error=args.max_error, max_torque=args.max_torque,
                workers=args.workers, executor=executor, progress=bar, objective=args.objective, period=args.period, hold=args.hold,
            )
        if uncertainty is not None:
            from inversion.studies.robustness import judge_family

            with args.reporter.stage("perturbed links", unit="members") as bar:
                judge_family(result, model, trajectory, uncertainty, max_error=args.max_error, progress=bar, workers=args.workers,
                             executor=executor)
    finally:
        if executor is not None:
            executor.close()
    files = [str(f) for f in result.write(folder)]
    if args.plot:
        from inversion.baselines.ocp import ocp_front, write_front

        from .plots import pareto_figure

        period = args.period if args.period is not None else DEFAULTS.ocp_period
        with args.reporter.stage("optimal-control front", unit="bounds") as bar:
            front = ocp_front(model, trajectory, period=period, progress=bar)
        files.append(str(write_front(front, folder / "ocp_front.csv")))
        files.append(str(pareto_figure(result, folder / "pareto.png", ocp=(front, period))))
    print(json.dumps(result.summary, indent=1) if args.json else exploration_text(result, files))
    return 0


def _dask_client(address: str) -> Any:
    """A client of the Dask scheduler at ``address`` (one line and exit 2 if there is none)."""
    from modelgen.errors import SettingsError

    try:
        from distributed import Client
    except ImportError:
        raise SettingsError("--scheduler", address, "an installed Dask distributed (pip install 'sflm[dask]')") from None
    fault = scheduler_fault(address)  # Dask retries a refused address for its whole timeout, and trusts what a stranger sends
    if fault is not None:
        raise SettingsError("--scheduler", address, f"the address of a running Dask scheduler ({fault})")
    try:
        return Client(address, timeout=10)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SettingsError("--scheduler", address, f"the address of a running Dask scheduler ({exc.__class__.__name__})") from None


#: Seconds a TCP peer has to send its first bytes: a Dask scheduler writes its handshake as soon as it accepts.
SCHEDULER_GREETING = 5.0
#: Largest first message a Dask scheduler sends (its handshake is a few hundred bytes).
_GREETING_BYTES = 1 << 20


def scheduler_fault(address: str, timeout: float = SCHEDULER_GREETING) -> str | None:
    """Why the TCP address ``address`` (``tcp://host:port`` or ``host:port``) is not a Dask scheduler, or ``None``.

    A Dask scheduler answers a connection at once with its handshake, framed as Dask's TCP
    comm frames it: eight bytes giving the length of what follows. A closed port refuses; a
    web server sends nothing until asked (Dask would wait for it without end) or answers
    ``HTTP/1.1 ...`` (whose first eight bytes Dask would read as a length of exbibytes and
    try to allocate). Other schemes, and addresses this machine cannot reach now, are left to
    Dask's own timeout.
    """
    import socket
    import struct
    from urllib.parse import urlsplit

    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    try:
        host, port = parts.hostname, parts.port
    except ValueError:  # a port that is not a number: Dask names the fault
        return None
    if parts.scheme != "tcp" or host is None or port is None:
        return None
    try:
        connection = socket.create_connection((host, port), timeout=2)
    except ConnectionRefusedError:
        return "the connection was refused"
    except OSError:  # unreachable or slow: Dask's timeout decides
        return None
    with connection:
        connection.settimeout(timeout)
        received = b""
        try:
            while len(received) < 8:
                chunk = connection.recv(8 - len(received))
                if not chunk:
                    break
                received += chunk
        except (TimeoutError, OSError):
            pass
    if not received:
        return f"the service there sent nothing in {timeout:g} s: not a Dask scheduler"
    length = struct.unpack("Q", received)[0] if len(received) == 8 else 0
    if not 0 < length <= _GREETING_BYTES:
        shown = received.decode("ascii", "replace")
        return f"the service there answered {shown!r}, not a Dask handshake"
    return None


def _emit(args: argparse.Namespace, result: Any, folder: Path, csv_name: str, plot: str, text: Any,
          extra: Sequence[str] = ()) -> int:
    """Write ``csv_name``, the figures of :mod:`sflm.plots`'s ``plot`` with ``--plot``, then ``summary.json`` with the run's
    record (:func:`inversion.realtime.runs.run_record`: one id, each file's SHA-256); print the summary.

    Each file is written under a temporary name and renamed, the summary last, the run it replaces kept meanwhile
    (:func:`inversion.realtime.runs.keep_previous`): a run killed at any moment leaves the old run or the new one to a
    reader (:func:`inversion.realtime.runs.read_run`), never a mix."""
    from inversion.realtime.runs import forget_previous, keep_previous, run_record

    written = [folder / csv_name]
    try:
        keep_previous(folder)
        with args.reporter.stage(f"writing {csv_name}", unit="rows") as bar:
            result.write_csv(folder / csv_name, bar)
        if args.plot:
            from . import plots  # matplotlib only when plotting (0.35 s to import)

            written += list(getattr(plots, plot)(result, folder))
        result.summary["run"] = run_record(written)
        result.write_summary(folder / "summary.json")
        forget_previous(folder)
    except OSError as exc:  # a full disk, a folder gone read-only: the folder the user chose is named, not a bare errno
        from modelgen.errors import SettingsError

        raise SettingsError("--out", str(folder), f"a folder with room for {csv_name} and summary.json "
                            f"({exc.strerror or exc})") from None
    files = [str(written[0]), str(folder / "summary.json"), *extra, *(str(p) for p in written[1:])]
    print(json.dumps(result.summary, indent=1) if args.json else text(result, files))
    return 0


def _plant_arguments(args: argparse.Namespace, name: str) -> dict[str, Any]:
    """The plant's keyword arguments of :func:`simulation.simulate`, each value with its source."""
    from modelgen.errors import SettingsError
    from simulation.cases import fitted_plant

    out: dict[str, Any] = {"plant_overrides": {}, "plant_sources": {}}
    if args.paper_plant:
        case = _case(args, name)
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


def _cmd_simulate(args: argparse.Namespace) -> int:
    from simulation import simulate

    from .summaries import simulation_text

    model = _load_model(args, system=False)
    uncertainty = _uncertainty(args, model)  # checked before the work
    if args.feedforward is not None:
        inversion = _run(args, model)
    else:
        inversion = _invert(args, model)
    pulse = {"amplitude": args.pulse_amplitude, "gain": args.pulse_gain, "tolerance": args.pulse_tolerance,
             "period": args.pulse_period}
    options = dict(plant=args.plant, controller=args.controller, kp=args.kp, kd=args.kd, t_end=args.t_end,
                   friction_compensation=args.friction_compensation, pulse=pulse, rate=args.rate, engine=args.engine,
                   **_plant_arguments(args, model.name))
    with args.reporter.stage("simulate", unit="%") as bar:
        result = simulate(model, inversion, progress=lambda fraction: bar(int(round(100 * fraction)), 100), **options)
    if uncertainty is not None:
        from simulation import simulate_uncertain

        with args.reporter.stage("perturbed links", unit="links") as bar:
            result = simulate_uncertain(model, inversion, uncertainty, nominal=result, progress=bar, **options)
    return _emit(args, result, _output_folder(args, model.name, "simulate"), "simulation.csv", "plot_simulation", simulation_text)


def _cmd_compare(args: argparse.Namespace) -> int:
    from inversion.studies.compare import compare

    from .summaries import comparison_text

    from inversion.api import from_keywords
    from inversion.family.method import Family

    model = _load_model(args)
    options = _inversion_settings(args, model.name)
    trajectory = options.pop("trajectory")
    folder = _output_folder(args, model.name, "compare")
    uncertainty = _uncertainty(args, model)
    objective = options.pop("objective")
    options.pop("end")
    options.pop("method")
    problem, family = from_keywords(model, trajectory, "ssef", {**options, "uncertainty": uncertainty})
    assert isinstance(family, Family)
    if objective is not None:
        from dataclasses import replace

        from inversion.studies.compare import check_objective

        check_objective(objective)
        family = replace(family, objective=objective)
    result = compare(problem, family=family, progress=args.reporter)
    files = [str(result.write_csv(folder / "compare.csv"))]
    if args.plot:
        from .plots import comparison_figure

        files.append(str(comparison_figure(result, folder / "compare.png", f"{model.name}: {trajectory.name}")))
    print(json.dumps(result.rows, indent=1) if args.json else comparison_text(result, files))
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    from .reproduce import reproduce

    folder = Path(args.out) if args.out else Path("sflm-out") / args.case
    result = reproduce(args.case, folder, progress=args.reporter)
    print(result.report.read_text())
    figures = [f for f in result.files if f.suffix == ".png"]
    print(f"wrote {len(result.files)} files to {result.folder}/ ({len(figures)} figures, report.md) "
          f"in {result.numbers['seconds']:.1f} s")
    return 0


def _cmd_fit(args: argparse.Namespace) -> int:
    from modelgen.fit import calibrated_toml, fit_file
    from modelgen.geometry import load_geometry

    from .summaries import fit_text

    nominal = load_geometry(args.model).with_model(args.modes)
    params = None if args.params is None else [p.strip() for p in args.params.split(",") if p.strip()]
    law = None if args.kp is None and args.kd is None else (args.kp, args.kd)
    args.reporter(f"fitting {nominal.name} to {Path(args.data).name} (least squares over the model's response)")
    result = fit_file(nominal, args.data, params, args.output, law)
    path = Path(args.out) if args.out else _output_folder(args, nominal.name, "fit") / f"{nominal.name}-calibrated.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(calibrated_toml(result, Path(args.data).name))
    files = [str(path)]
    if args.plot:
        from .plots import fit_figure

        files.append(str(fit_figure(result, args.data, args.output, path.parent / "fit.png", law)))
    if args.json:
        print(json.dumps({**result.summary(), "files": files}, indent=1))
    else:
        print(fit_text(result, files))
    return 0


def _cmd_fmu(args: argparse.Namespace) -> int:
    from modelgen.errors import SettingsError

    model = _load_model(args, system=False)
    if args.trajectory is not None and args.feedforward is None:
        raise SettingsError("--trajectory", args.trajectory, "nothing without --feedforward (the plant's FMU takes tau as its input)")
    stem = model.name + ("-feedforward" if args.feedforward else "")
    path = Path(args.out) if args.out else _output_folder(args, model.name, "fmu") / f"{stem}.fmu"
    args.reporter(f"building the FMU of {model.name}")
    if args.feedforward is None:
        from modelgen.fmu import build_fmu

        written = build_fmu(model, path, args.plant)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "modes": model.n,
                "plant": args.plant, "parameters": len(model.parameters), "states": 2 * (model.n + 1), "inputs": ["tau"],
                "outputs": ["y", "theta", "thetadot", *[f"delta_{j}" for j in range(1, model.n + 1)]]}
    elif _is_run(args.feedforward):
        from inversion.realtime.feedforward_fmu import build_feedforward_fmu

        result = _run(args, model)
        written = build_feedforward_fmu(result, path)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "feedforward": True,
                "run": result.summary.get("run", {}).get("id"), "method": result.summary.get("method", "ssef"),
                "period": result.summary["settings"]["period"], "hold": result.summary["settings"]["held_from"],
                "span": [float(result.signals.bounds[0]), float(result.signals.bounds[-1])] if result.signals is not None else None,
                "peak_torque": result.summary["peak_torque"], "inputs": [], "outputs": ["tau", "theta_d", "thetadot_d"]}
    else:
        from inversion import Family, Problem, invert
        from inversion.realtime.feedforward_fmu import build_feedforward_fmu
        from modelgen.files import DocumentError, read_document

        try:
            summary = read_document(args.feedforward, "json")
        except OSError as exc:
            raise SettingsError("--feedforward", args.feedforward, f"a readable file ({exc.strerror})") from None
        except DocumentError as exc:
            raise SettingsError("--feedforward", args.feedforward, f"a summary.json of sflm invert (or a best.json of explore); "
                                f"this one is {exc}") from None
        if not isinstance(summary, dict):
            raise SettingsError("--feedforward", args.feedforward, "a summary.json of sflm invert (or a best.json of explore)")
        of = summary.get("model")
        if isinstance(of, str) and of != model.name:  # another model's: said before anything is inverted with it
            raise SettingsError("--feedforward", args.feedforward, f"a summary of {model.name}'s (this summary is of model {of})")
        if args.trajectory is None and isinstance(summary.get("trajectory_spec"), str):
            args.trajectory = summary["trajectory_spec"]  # the summary says what it inverted
        try:
            result = invert(Problem(model, _trajectory(args, model.name)), method=Family(settings=args.feedforward))
        except SettingsError as exc:  # the settings are the file given as --feedforward
            if exc.parameter == "settings":
                raise SettingsError("--feedforward", args.feedforward, exc.accepted) from None
            raise
        expected = summary.get("peak_torque")
        if isinstance(expected, (int, float)) and abs(result.summary["peak_torque"] - expected) > 1e-9 * max(abs(expected), 1e-300):
            raise SettingsError("--feedforward", args.feedforward, f"the summary of a member of {model.name} on this trajectory (inverted "
                                f"again its peak torque is {result.summary['peak_torque']:.9g} N m, the file's {expected:.9g})")
        written = build_feedforward_fmu(result, path)
        held = {"fmu": str(written), "fmi_version": "2.0", "kind": "model exchange", "model": model.name, "feedforward": True,
                "span": [float(result.signals.bounds[0]), float(result.signals.bounds[-1])] if result.signals is not None else None,
                "peak_torque": result.summary["peak_torque"], "inputs": [], "outputs": ["tau", "theta_d", "thetadot_d"]}
    if args.json:
        print(json.dumps(held, indent=1))
    else:
        what = ("the feedforward (outputs tau, theta_d, thetadot_d; peak {:.4g} N m)".format(held["peak_torque"]) if args.feedforward
                else f"{held['modes']} modes, {held['plant']} plant: {held['states']} states, {held['parameters']} parameters, input tau, "
                     f"outputs {', '.join(held['outputs'])}")
        print(f"{model.name}: FMI 2.0 model-exchange FMU of {what}\n\nwrote {written}")
    return 0


def _is_run(path: str) -> bool:
    """Whether ``path`` names a run of ``sflm invert``: its folder, or its ``summary.json`` or ``inversion.csv`` beside the
    other."""
    run = Path(path)
    if run.is_dir():
        return True
    return run.name in ("summary.json", "inversion.csv") and (run.parent / "summary.json").is_file() and (
        run.parent / "inversion.csv").is_file()


def _run(args: argparse.Namespace, model: Any) -> Any:
    """The result ``--feedforward RUN`` names (:func:`inversion.realtime.runs.read_run`), refusing the inversion's own
    arguments beside it (the run holds its move and its settings)."""
    from inversion.realtime.runs import read_run
    from modelgen.errors import SettingsError

    given = [flag for flag, name in (("--trajectory", "trajectory"), ("--segments", "segments"), ("--h", "h"), ("--cdec", "cdec"),
                                     ("--settings", "settings"), ("--method", "method"), ("--max-error", "max_error"),
                                     ("--period", "period"), ("--hold", "hold"), ("--auto", "auto"), ("--end", "end"))
             if getattr(args, name, None) not in (None, False)]
    if given:
        raise SettingsError(given[0], getattr(args, given[0].lstrip("-").replace("-", "_")), "nothing with --feedforward RUN "
                            "(the run holds its move, its settings and the table it was judged with)")
    args.reporter(f"reading the run {args.feedforward}")
    try:
        return read_run(args.feedforward, model)
    except SettingsError as exc:
        if exc.parameter == "feedforward":
            raise SettingsError("--feedforward", exc.value, exc.accepted) from None
        raise


def _cmd_generate(args: argparse.Namespace) -> int:
    import time

    from modelgen.export import default_folder, export_model

    started = time.perf_counter()
    args.reporter("deriving, generating and compiling the model (cached after the first time)")
    model = _load_model(args, system=False)
    folder = Path(args.out) if args.out else default_folder(model.geometry)
    result = export_model(model, folder, model.functions.cache_hit, started)
    if args.json:
        print(json.dumps(result.manifest, indent=1, sort_keys=True))
    else:
        how = "cache hit" if result.cache_hit else "derived, generated and compiled"
        kind = "compiled C" if result.manifest["library"] else "no library: in-process CasADi fallback"
        print(f"{result.folder}/: {', '.join(result.files)}")
        print(f"  {model.name}, {model.n} {model.mode_family} mode{'s' if model.n != 1 else ''}; {how} in {result.seconds:.2f} s ({kind})")
        print(f"  {len(result.manifest['functions'])} functions sflm_<role>(p, ...); p has {len(model.parameter_names)} entries (manifest.json)")
    return 0


def _cmd_info(args: argparse.Namespace) -> int:
    import modelgen
    from modelgen.convergence import convergence
    from modelgen.geometry import MAX_MODES

    from .info import convergence_json, convergence_text, info_text

    def progress(n: int, total: int) -> None:
        args.reporter.count(n, total, "models")

    model = _load_model(args)
    limit = _info_limit(args, model)  # before the longer work: a bad trajectory or bound is one line at once
    bounded = _info_bounded(args, model, limit)
    if not isinstance(model, modelgen.Model):  # a transfer function: its poles, zeros and normal form
        from .systems import system_info

        if args.convergence or args.plot or args.matrices:
            from modelgen.errors import SettingsError

            option = "--convergence" if args.convergence else "--plot" if args.plot else "--matrices"
            raise SettingsError(option, True, "nothing for a transfer function (it is about a link's assumed modes)")
        data, text = system_info(model)
        data.update(_limits_json(limit, bounded))
        print(json.dumps(data, indent=1) if args.json else text + _limits_text(limit, bounded, model))
        return 0
    conv = None
    if args.convergence:
        top = args.modes if args.modes is not None else args.max_modes
        if args.modes is None and not 1 <= top <= MAX_MODES:
            from modelgen.errors import SettingsError

            raise SettingsError("--max-modes", top, f"an integer in 1..{MAX_MODES}")
        args.reporter("building the models of the convergence study")
        conv = convergence(
            model.geometry,
            top,
            loader=lambda g: modelgen.load(g, output_at=args.output_at),
            progress=progress,
            output_at=args.output_at,
        )
    from modelgen.zero_status import zero_status

    if args.plot and not args.convergence:
        from modelgen.errors import SettingsError

        raise SettingsError("--plot", True, "--plot together with --convergence (the figure is the convergence study)")
    from modelgen.continuum import continuum_reference

    # one continuum reference for the zeros' status and the figure (about 0.3 s)
    reference = continuum_reference(model.geometry, count=max(model.n, len(conv.models) if conv else 0) + 3, output_at=model.output_at)
    status = zero_status(model, reference=reference)
    figure = None
    if args.plot and conv is not None:
        from .plots import convergence_figure

        families: dict[str, Any] = {}
        for family in ("clamped-mass", "clamped-free", "polynomial"):
            if family == model.geometry.mode_shapes:
                families[family] = conv
            else:
                families[family] = convergence(model.geometry.with_model(mode_shapes=family), len(conv.models),
                                               loader=lambda g: modelgen.load(g, output_at=args.output_at),
                                               progress=progress, output_at=args.output_at)
        folder = _output_folder(args, model.name, "info")
        figure = convergence_figure(families, reference, folder / "convergence.png", model.name)
    if args.json:
        out: dict[str, Any] = model.summary()
        out.update(status.as_dict())
        if conv is not None:
            out["convergence"] = convergence_json(conv)
        out.update(_limits_json(limit, bounded))
        print(json.dumps(out, indent=1))
    else:
        print(info_text(model, matrices=args.matrices, status=status) + _limits_text(limit, bounded, model))
        if conv is not None:
            print()
            print(convergence_text(conv))
        if figure is not None:
            print(f"\nwrote {figure}")
    return 0


def _info_limit(args: argparse.Namespace, model: Any) -> Any:
    """``info --trajectory``: the causal limit of the move on the model (:mod:`inversion.lti.causal_limit`), or ``None``."""
    from modelgen.errors import SettingsError

    if args.trajectory is None:
        if args.max_error is not None:
            raise SettingsError("--max-error", args.max_error, "nothing without --trajectory (the bound of its causal limit)")
        return None
    from inversion.lti.causal_limit import causal_limit
    from inversion.signals.trajectory import trajectory_from_spec

    if not args.trajectory.strip():
        raise SettingsError("--trajectory", args.trajectory, _TRAJECTORY_HELP_SHORT)
    trajectory = trajectory_from_spec(args.trajectory)
    move = trajectory.move()
    if args.max_error is not None and not (args.max_error > 0):
        raise SettingsError("--max-error", args.max_error, "a number > 0 (m)")
    bound = tip_bound(args.max_error, move)
    return causal_limit(model, trajectory, bound)


def _info_bounded(args: argparse.Namespace, model: Any, limit: Any) -> Any:
    """``info --trajectory --period``: the bounded causal limit (:mod:`inversion.baselines.bounded_limit`), or ``None``."""
    import math

    from modelgen.errors import SettingsError

    if args.period is None:
        for flag, value in (("--max-torque", args.max_torque), ("--max-torque-rate", args.max_torque_rate)):
            if value is not None:
                raise SettingsError(flag, value, "nothing without --period (a bound of the bounded causal limit)")
        return None
    if limit is None:
        raise SettingsError("--period", args.period, "nothing without --trajectory (the period of the bounded causal limit)")
    for flag, value in (("--period", args.period), ("--max-torque", args.max_torque), ("--max-torque-rate", args.max_torque_rate)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise SettingsError(flag, value, "a finite number > 0")
    from inversion import InversionError
    from inversion.acceptance import Criteria
    from inversion.problem import check_period
    from inversion.baselines.bounded_limit import bounded_limit
    from inversion.signals.trajectory import trajectory_from_spec

    trajectory = trajectory_from_spec(args.trajectory)
    try:
        check_period(args.period, trajectory)
    except SettingsError as exc:
        raise SettingsError("--period", args.period, exc.accepted) from None
    bounds = Criteria(max_error=limit.bound, period=args.period, hold="zoh", max_torque=args.max_torque, max_torque_rate=args.max_torque_rate)
    args.reporter("the bounded causal limit (a chain programme)")
    try:  # asked for and within range: what cannot be computed is said in the output, beside every figure info has
        return bounded_limit(model, trajectory, bounds, shortest=True)
    except (InversionError, SettingsError) as exc:
        return f"not computed: {in_flags(str(exc), getattr(exc, 'parameter', None))}"


def _limits_json(limit: Any, bounded: Any) -> dict[str, Any]:
    """``info``'s ``causal_limit`` and ``bounded_limit`` keys, where they were asked for (a bounded limit that could not be
    computed: ``{"error": null, "reason": ...}``)."""
    out = {key: value.as_dict() for key, value in (("causal_limit", limit), ("bounded_limit", bounded))
           if value is not None and not isinstance(value, str)}
    if isinstance(bounded, str):
        out["bounded_limit"] = {"error": None, "relative_error": None, "reason": bounded}
    return out


def _limits_text(limit: Any, bounded: Any, model: Any) -> str:
    """The causal limit and the bounded one as ``info`` prints them, after a blank line ("" where neither was asked for)."""
    if limit is None:
        return ""
    text = "\n\n" + _limit_text(limit, model)
    if isinstance(bounded, str):
        text += f"\nbounded causal limit: {bounded}"
    elif bounded is not None:
        verdict = "no causal feedforward within these bounds meets it" if bounded.exceeds else "these bounds do not rule it out"
        text += f"\nbounded causal limit: {bounded.sentence()}; the bound {bounded.bound:.4g}: {verdict}"
        longer = bounded.duration_sentence()
        if longer:
            text += f"\n  {longer}"
    return text


def _limit_text(limit: Any, model: Any) -> str:
    """The causal limit as ``info`` prints it."""
    import modelgen

    unit = " m" if isinstance(model, modelgen.Model) else ""
    head = f"causal limit of a {limit.duration:g} s move of {limit.move:.4g}{unit}: "
    if limit.method == "none":
        return head + ("none: no zero with Re > 0 constrains a causal feedforward from rest"
                       + (f" ({limit.zeros_text()})" if limit.imaginary else ""))
    lines = [head + f"{limit.error:.4g}{unit} ({100 * limit.relative_error:.3g} % of the move; {limit.method}), from the zeros "
             f"{limit.zeros_text()}: no causal feedforward from rest holds the move closer"]
    if limit.shortest_duration is not None:
        meets = "meets" if not limit.exceeds else "does not meet"
        lines.append(f"  within {limit.bound:.4g}{unit} ({100 * limit.bound / (limit.move or 1.0):.3g} % of the move; this move {meets} it) "
                     f"the same move needs at least {limit.shortest_duration:.4g} s")
    return "\n".join(lines)


_COMMANDS = {
    "info": _cmd_info,
    "generate": _cmd_generate,
    "invert": _cmd_invert,
    "explore": _cmd_explore,
    "simulate": _cmd_simulate,
    "compare": _cmd_compare,
    "reproduce": _cmd_reproduce,
    "fmu": _cmd_fmu,
    "fit": _cmd_fit,
}


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int, line: str | None = None) -> str:
    return f"sflm: warning: {in_flags(str(message))}\n"


#: The library's keywords and the command line's flags that set them: the library's messages speak Python, the command
#: line's speak flags (:func:`in_flags`).
FLAGS = {
    "max_error": "--max-error", "max_torque": "--max-torque", "max_torque_rate": "--max-torque-rate", "method": "--method", "margin": "--margin",
    "end": "--end", "settings": "--settings", "trajectory": "--trajectory", "modes": "--modes", "mode_shapes": "--mode-shapes",
    "output_at": "--output-at", "rate": "--rate", "period": "--period", "hold": "--hold", "window": "--window", "eps": "--eps",
    "tol": "--tol", "joining": "--joining", "segments": "--segments", "h": "--h", "cdec": "--cdec", "objective": "--objective",
    "zeros": "--zeros", "prefix": "--c-prefix", "uncertainty": "--uncertainty", "samples": "--samples", "workers": "--workers",
    "scheduler": "--scheduler", "smoothing": "--smooth", "plant": "--plant", "controller": "--controller",
    "friction_compensation": "--friction-compensation", "kp": "--kp", "kd": "--kd", "t_end": "--t-end", "preview": "--preview", "edges": "--edges",
    "auto": "--auto", "feedforward": "--feedforward", "out": "--out", "solver": "--solver",
    "data": "--data", "output": "--output", "law": "--kp, --kd", "gains": "--kp, --kd", "params": "--params",
}


def in_flags(message: str, parameter: str | None = None) -> str:
    """A library message in the command line's words: ``method='stable'`` as ``--method stable``, ``auto=True`` as
    ``--auto``, ``max_error`` as ``--max-error``, and the refused ``parameter`` (a keyword) as its flag.

    Only keywords that are flags are rewritten, and bare words only where they hold an underscore (``max_error``), never an
    English word (``end``, ``method``) standing alone.
    """
    import re

    if parameter is not None and parameter in FLAGS:
        message = message.replace(f"{parameter} = ", f"{FLAGS[parameter]} = ", 1)

    def assignment(match: re.Match[str]) -> str:
        flag, value = FLAGS[match["name"]], match["value"]
        if value == "True":
            return flag
        return f"{flag} {value.strip(chr(39) + chr(34))}"

    names = "|".join(sorted(map(re.escape, FLAGS), key=len, reverse=True))
    message = re.sub(rf"(?<![\w.-])(?P<name>{names})=(?P<value>'[^']*'|\"[^\"]*\"|[\w.+-]+)", assignment, message)
    underscored = "|".join(re.escape(k) for k in sorted(FLAGS, key=len, reverse=True) if "_" in k)
    return re.sub(rf"(?<![\w.-])({underscored})(?![\w=])", lambda m: FLAGS[m[1]], message)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``sflm`` console script; the exit status.

    Parameters
    ----------
    argv : Sequence[str] | None, optional
        The arguments (``None``: ``sys.argv[1:]``).
    """
    warnings.formatwarning = _one_line_warning
    parser = _parser()
    if not (sys.argv[1:] if argv is None else list(argv)):
        parser.print_help(sys.stderr)
        return 2
    args = parser.parse_args(argv)
    from .progress import Reporter

    args.reporter = Reporter(args.command, enabled=not args.quiet)
    try:
        return _COMMANDS[args.command](args)
    except SflmError as exc:
        args.reporter.close()
        message = in_flags(str(exc), getattr(exc, "parameter", getattr(exc, "key", None)))
        print(f"sflm {args.command}: error: {message}", file=sys.stderr)
        if getattr(args, "json", False):
            _refusal_json(args, exc, message)
        return 2
    except BrokenPipeError:
        # the reader went away (`sflm ... | head -1`): say nothing more, as a killed writer would
        _silence_stdout()
        return 128 + 13  # SIGPIPE
    except OSError as exc:  # the system refused (a full disk, a folder gone read-only, a file removed)
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"sflm {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        args.reporter.close()
        print("sflm: interrupted", file=sys.stderr)
        return 130
    finally:
        args.reporter.close()


def _refusal_json(args: argparse.Namespace, exc: Exception, message: str) -> None:
    """A refusal as a result (``--json``): one JSON object on stdout, and the same as ``summary.json`` in the folder the
    command would have written (where it names one and can write it)."""
    from inversion.realtime.runs import forget_previous, run_record

    record: dict[str, Any] = {"status": "refused", "command": args.command, "message": message, "error": type(exc).__name__}
    parameter = getattr(exc, "parameter", None)
    if parameter is not None:
        record["parameter"] = FLAGS.get(parameter, parameter)
    for key in ("status", "causal_limit", "bounded_limit", "stages", "record"):
        value = getattr(exc, key, None)
        if value is not None:
            record["reason" if key == "status" else "search" if key == "record" else key] = value
    search = record.get("search")
    if isinstance(search, dict):
        record.setdefault("reason", "no-member")  # the family's search: no member passed
        if search.get("alternatives"):
            record["nearest"] = search["alternatives"]
    text = json.dumps(record, indent=1, default=str)
    print(text)
    out = getattr(args, "out", None)
    if out and args.command in ("invert", "simulate", "compare", "explore"):
        try:
            folder = Path(out)
            folder.mkdir(parents=True, exist_ok=True)
            from modelgen.files import write_json

            write_json(folder / "summary.json", {**json.loads(text), "run": run_record([])})
            forget_previous(folder)
        except OSError:
            pass  # the folder cannot be written: stdout has the record


def _silence_stdout() -> None:
    """Point stdout at the null device, so that the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


if __name__ == "__main__":
    sys.exit(main())

"""The argument groups the commands share, defined once, and their mapping onto the typed request of :mod:`inversion`.

The model (``MODEL``, ``--modes``, ...), the move (``--trajectory``, ``--smooth``), the family's member, the bounds every
method is judged by (:class:`inversion.Bounds`), the controller's sampling (:class:`inversion.Sampling`), the parameter
spread: each group is added by one function and read back by one (:func:`bounds_of`, :func:`sampling_of`,
:func:`request`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, NoReturn, Sequence

from inversion.config import DEFAULTS



class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def add_model_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("model", metavar="MODEL", help="a preset (paper-sim, paper-exp, hyperbolic, near-non-hyperbolic) or a geometry .toml "
                   "file; for info, invert, explore and compare also a transfer function in s, '(2 - s)/(s + 1)^3', or a .toml/.json "
                   "file with numerator and denominator (descending powers of s)")
    p.add_argument("--modes", type=int, metavar="N", help="number of assumed modes (default: the geometry's)")
    p.add_argument("--mode-shapes", metavar="F", help="mode-shape family: clamped-mass, clamped-free or polynomial")
    p.add_argument("--output-at", type=float, metavar="X",
                   help="where the output y = X theta + w(X) is measured, 0 < X <= L (m; default L, the tip)")


def percent(fraction: float) -> str:
    """A default fraction as a percentage in an argparse help text (``%`` doubled)."""
    return f"{100 * fraction:g} %%"


def list_text(values: Sequence[Any]) -> str:
    """A default list as the command line takes it."""
    return ",".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values)


TRAJECTORY_HELP_SHORT = "paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER] or a CSV file (presets default to the paper's)"


TRAJECTORY_HELP = ("paper-sim, paper-exp, smoothstep:DISTANCE:DURATION[:ORDER] (invert: smoothstep:DISTANCE:shortest[:ORDER], the "
                   "shortest move within absolute --max-torque and --max-torque-rate or the geometry's [drive]; shortest:DISTANCE, "
                   "the fastest of any profile) "
                   "or a CSV file (t,y; FILE.csv:smoothing=S to smooth a "
                    "measured one); presets default to the paper's")


def add_uncertainty_arguments(p: argparse.ArgumentParser, text: str | None = None) -> None:
    p.add_argument("--uncertainty", metavar="SPEC",
                   help=text or "judge the result on perturbed links in the closed loop with the joint PD: geometry keys with "
                                "relative ranges, e.g. link.flexural_rigidity=10%%,payload.mass=20%% (damping.modal_K: mode K's ratio of a "
                                "link damped per mode; fit:FILE: a calibration's intervals; every corner; summary 'robustness')")
    p.add_argument("--samples", type=int, default=0, metavar="N", help="with --uncertainty: also N seeded Latin-hypercube samples")


def add_smooth_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--smooth", type=float, metavar="S", help="for a measured CSV trajectory: the smoothing factor s of its quintic "
                   "spline (scipy.interpolate.splrep: the squared residuals sum to at most s; about n sigma^2 for n samples of "
                   "noise sigma), the same as FILE.csv:smoothing=S")


def add_inversion_arguments(p: argparse.ArgumentParser) -> None:
    """The groups an inversion takes: the move, the family's member, the bounds, the sampling (:func:`add_bounds_arguments`,
    :func:`add_sampling_arguments`)."""
    p.add_argument("--trajectory", metavar="SPEC", help=TRAJECTORY_HELP)
    add_smooth_argument(p)
    add_member_arguments(p)
    add_bounds_arguments(p)
    add_sampling_arguments(p)


def add_member_arguments(p: argparse.ArgumentParser) -> None:
    """The family's member and how it is chosen (:class:`inversion.Family`'s options; ``--end`` and ``--objective`` reach the
    other methods that take them)."""
    member = p.add_argument_group("the family's member (inversion.Family)")
    member.add_argument("--segments", type=int, metavar="K", help="number of equal segments (preset default: the paper's)")
    member.add_argument("--h", type=int, metavar="H", help="order of smooth joining, Eq. (30) (preset default: the paper's)")
    member.add_argument("--cdec", type=float, nargs=2, metavar=("F", "S"), help="fastest and slowest decay over a segment, Eq. (35)")
    member.add_argument("--joining", choices=("paper", "position", "anchored"), help="joining conditions: the paper's, plus position, plus the unstable state anchored at the joints (default: paper for the paper's cases, else anchored)")
    member.add_argument("--auto", action="store_true", help="choose the member automatically by --objective: the least peak torque (default) or the smallest error among the members that reach the link within --max-error (the default for a geometry file or a trajectory not the preset's own)")
    member.add_argument("--settings", metavar="FILE", help="reuse a member: best.json of sflm explore, or a summary.json")
    member.add_argument("--edges", choices=("match", "rest"), default=None,
                   help="how the redefined output meets y_d at t0 and tf: match (the paper's: y_d's acceleration and its first h "
                        "derivatives) or rest (its acceleration with those derivatives zero: the torque leaves and reaches rest with "
                        "zero slope where the move's jerk jumps at its ends). The automatic choice tries both where they differ")
    member.add_argument("--eps", type=float, default=None, metavar="E", help=f"zeros with Re >= -E count as unstable (default {DEFAULTS.eps:g})")
    member.add_argument("--end", choices=("free", "rest", "settle"), default=None,
                   help="free: the paper's end (the torque stops at t_f); rest: the feedforward ends at zero torque with the link at "
                        "rest (Remark 2); settle: after t_f the tip is held on y_d(t_f) while the link's internal modes decay (a causal "
                        "post-actuation; anchored joining). The automatic choice tries all three unless one is given")
    member.add_argument("--objective", choices=("torque", "error", "energy", "robust"), default=None,
                   help=f"what the automatic choice minimises: torque (default), the least peak torque within --max-error (default "
                        f"{percent(DEFAULTS.bound)} of the move); error, the least error within the torque limit (default "
                        f"{DEFAULTS.torque_ratio:g} x what a rigid link needs); "
                        "energy: the optimal-control feedforward's other objective (--method ocp); robust (invert, with "
                        "--uncertainty): the least worst-case error on the perturbed links")
    member.add_argument("--zeros", choices=("all", "physical", "converged"), default=None,
                   help="unstable zeros the inversion constrains: all (default); physical: all but the truncation artefacts; "
                        "converged: only those converged to the continuum's. The others are left free; the full plant still checks the torque")
    member.add_argument("--tol", type=float, default=None, metavar="TOL", help=f"largest accepted relative residual of a segment system (default {DEFAULTS.tol:g})")





def add_bounds_arguments(p: argparse.ArgumentParser) -> None:
    """The bounds every method is judged by (:class:`inversion.Bounds`) and the margin kept inside them."""
    bounds = p.add_argument_group("the bounds every method is judged by (inversion.Bounds)")
    bounds.add_argument("--max-error", type=float, metavar="E", help=f"quality gate: largest accepted max |y~ - y_d| in m (default {percent(DEFAULTS.quality_gate)} "
                   f"of the move, {percent(DEFAULTS.bound)} for the automatic choice; inf accepts any)")
    bounds.add_argument("--max-torque", type=float, metavar="T", help=f"largest accepted peak torque in N m (default "
                   f"{DEFAULTS.torque_ratio:g} x what a rigid link needs along y_d; inf accepts any)")
    bounds.add_argument("--max-torque-rate", type=float, metavar="R", help=f"largest accepted change of the held table from one row to "
                   f"the next, the first row against zero, in N m (default {DEFAULTS.torque_rate_ratio:g} x a rigid link's largest "
                   "change over one period along y_d; inf accepts any)")
    bounds.add_argument("--max-deflection", type=float, metavar="M", help="a link's largest accepted elastic deflection at its "
                        "output in m, over the table's rows (default: none): optimal control and the fastest move "
                        "(--trajectory shortest:DISTANCE) plan within it, every method is judged by it")
    bounds.add_argument("--margin", type=float, metavar="F", help=f"the fraction of the bound the table keeps free (default "
                   f"{DEFAULTS.margin:g}: the automatic choice, optimal control and the re-plan aim within {1 - DEFAULTS.margin:g} of "
                   "--max-error where the bounded causal limit leaves room, within half the room where it leaves less; 0: the "
                   "limit itself). Every summary reports the margin kept and the plant errors the table tolerates")


def add_sampling_arguments(p: argparse.ArgumentParser) -> None:
    """The controller's sampling (:class:`inversion.Sampling`)."""
    sampling = p.add_argument_group("the controller's sampling (inversion.Sampling)")
    sampling.add_argument("--period", type=float, metavar="DT",
                   help="the controller's period in s (default 1/--rate): the held table the summary's sampled block judges")
    sampling.add_argument("--hold", choices=("point", "zoh"), default=None,
                   help=f"point{' (default)' if DEFAULTS.hold == 'point' else ''}: samples at --rate, each value held by the controller; "
                        f"zoh{' (default)' if DEFAULTS.hold == 'zoh' else ''}: one row a period, the torque "
                        "its mean over the period it is held for (an error of O(DT^2) where the point value's is O(DT))")
    sampling.add_argument("--window", type=float, metavar="S",
                   help="seconds after the feedforward ends over which the tip must stay within --max-error of y_d(t_f) "
                        f"(default {DEFAULTS.vibration_window:g}, or 5 time constants of the plant's slowest stable mode)")
    sampling.add_argument("--rate", type=float, default=None, metavar="HZ", help=f"sampling rate of the output (default {DEFAULTS.rate:g}; at most "
                   f"{DEFAULTS.max_samples:,} samples: ~1.5 GB of CSV, with a progress bar)")


def bounds_of(args: argparse.Namespace) -> Any:
    """:class:`inversion.Bounds` of the bounds group.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from inversion.problem import Bounds

    return Bounds(max_error=args.max_error, max_torque=args.max_torque, max_torque_rate=args.max_torque_rate,
                  max_deflection=getattr(args, "max_deflection", None))


def sampling_of(args: argparse.Namespace) -> Any:
    """:class:`inversion.Sampling` of the sampling group.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    from inversion.problem import Sampling

    return Sampling(rate=args.rate, period=args.period, hold=args.hold, window=args.window)


#: The member group's flags, by the option of :class:`inversion.Family` each sets.
MEMBER = ("segments", "h", "cdec", "joining", "eps", "end", "edges", "settings", "auto", "objective", "zeros", "tol")


def member_of(args: argparse.Namespace) -> dict[str, Any]:
    """The family's options the member group gives (``None``: not given).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    given = {name: getattr(args, name, None) for name in MEMBER}
    given["cdec"] = None if given["cdec"] is None else tuple(given["cdec"])
    given["auto"] = True if given["auto"] else None
    return given


def request(args: argparse.Namespace, model: Any, loop: Any = None, uncertainty: Any = None) -> tuple[Any, Any]:
    """The problem and the method the command line asks for: the groups mapped onto :class:`inversion.Problem` (the model, the
    move, :func:`bounds_of`, :func:`sampling_of`, ``loop``, the spread, ``--margin``, ``--preview``) and the method
    (``--method`` with the member group's options: :func:`inversion.methods.keywords.method_from_keywords`).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    model : Model or LinearSystem
        The model.
    loop : inversion.Loop, optional
        The loop the table is judged in.
    uncertainty : Uncertainty, optional
        The parameter spread.
    """
    from inversion.methods.keywords import method_from_keywords
    from inversion.problem import Loop, Problem

    problem = Problem(model, trajectory_of(args, model.name), bounds=bounds_of(args), sampling=sampling_of(args), loop=loop or Loop(),
                      uncertainty=uncertainty, margin=getattr(args, "margin", None), preview=getattr(args, "preview", None))
    return problem, method_from_keywords(problem, getattr(args, "method", None), member_of(args))


def _list(kind: type, text: str) -> list[Any]:
    """A comma-separated list for argparse (one line and exit 2 on a bad value)."""
    try:
        values = [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a comma-separated list of {kind.__name__} values") from None
    if not values:
        raise argparse.ArgumentTypeError("an empty list")
    return values


def int_list(text: str) -> list[int]:
    return _list(int, text)


def float_list(text: str) -> list[float]:
    return _list(float, text)


def str_list(text: str) -> list[str]:
    return _list(str, text)


def case_of(args: argparse.Namespace, name: str) -> Any:
    """The paper case of a preset (``None`` for a geometry file, even one named like a preset)."""
    from modelgen.paper import case_named

    return case_named(name) if Path(str(args.model)).suffix.lower() != ".toml" else None


def trajectory_of(args: argparse.Namespace, name: str) -> Any:
    """The desired trajectory: ``--trajectory``, or the preset's own."""
    from inversion.signals.trajectory import trajectory_from_spec
    from modelgen.errors import SettingsError

    case = case_of(args, name)
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
        from ..systems import looks_like_transfer_function

        what = "a transfer function has no move of its own" if looks_like_transfer_function(name) else (
            "a geometry file has no move of its own")
        raise SettingsError("--trajectory", None, f"a move ({what}): smoothstep:DISTANCE:DURATION[:ORDER], paper-sim, paper-exp or "
                            "a CSV file of t,y")
    return trajectory_from_spec(spec)

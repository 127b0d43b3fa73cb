"""``sflm info``."""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable

from modelgen.threads import one_thread
from inversion.config import DEFAULTS, tip_bound

from .arguments import TRAJECTORY_HELP_SHORT, add_model_arguments, percent
from .common import load_model, output_folder
from .flags import in_flags
__all__ = ["add", "run"]

#: One run of the command, printed by its ``--help`` and on the documentation's command reference.
EXAMPLE = "sflm info tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2"


def add(sub: Any) -> None:
    """Add ``sflm info``'s parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The command line's subcommands.
    """
    info = sub.add_parser("info", help="model matrices, natural frequencies, zeros")
    add_model_arguments(info)
    info.add_argument("--json", action="store_true", help="print one JSON object")
    info.add_argument("--matrices", action="store_true", help="also print the matrices (always in --json)")
    info.add_argument("--convergence", action="store_true", help="frequencies and zeros for n = 1..N beside a finite-element continuum reference")
    info.add_argument("--plot", action="store_true",
                      help="with --convergence: write convergence.png, frequencies and zeros against n for the three mode-shape families beside the continuum")
    info.add_argument("--out", metavar="DIR", help="folder of --plot (default sflm-out/<name>/info)")
    info.add_argument("--max-modes", type=int, default=8, metavar="N", help="largest n of --convergence when --modes is not given (default %(default)s)")
    info.add_argument("--trajectory", metavar="SPEC", help="the causal limit of this move: the least error any causal feedforward from "
                      "rest can hold it to (the zeros with Re > 0 alone), and the shortest duration of the same move that meets "
                      "--max-error; " + TRAJECTORY_HELP_SHORT)
    info.add_argument("--max-error", type=float, metavar="E", help=f"with --trajectory: the bound the shortest duration is found for "
                      f"(default {percent(DEFAULTS.bound)} of the move)")
    info.add_argument("--period", type=float, metavar="DT", help="with --trajectory: also the bounded causal limit, the least error "
                      "any causal feedforward held at DT s reaches within the torque and rate bounds (a linear programme)")
    info.add_argument("--max-torque", type=float, metavar="T", help="with --period: the peak torque bound (default "
                      f"{DEFAULTS.torque_ratio:g} x the rigid need)")
    info.add_argument("--max-torque-rate", type=float, metavar="R", help="with --period: the bound on the change between rows "
                      f"(default {DEFAULTS.torque_rate_ratio:g} x the rigid need's change over a period)")


def run(args: argparse.Namespace) -> int:
    """Run ``sflm info``; the exit status.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    """
    model = load_model(args)
    limit = _info_limit(args, model)  # before the longer work: a bad trajectory or bound is one line at once
    # the bounded limit's programmes (HPIPM, which releases the GIL) on a second thread while the model's figures are
    # found on this one, every BLAS pool at one thread (the same bits whichever thread runs when)
    with one_thread(), ThreadPoolExecutor(max_workers=1) as second:
        asked = _info_bounded(args, model, limit)
        pending = None if asked is None else second.submit(asked)
        return _info_out(args, model, limit, lambda: None if pending is None else pending.result())


def _info_out(args: argparse.Namespace, model: Any, limit: Any, later: Callable[[], Any]) -> int:
    """:func:`run`'s figures and output; ``later()``: the bounded limit (or ``None``, or why not), computed beside."""
    import modelgen
    from modelgen.convergence import convergence
    from modelgen.geometry import MAX_MODES

    from ..info import convergence_json, convergence_text, info_text

    def progress(n: int, total: int) -> None:
        args.reporter.count(n, total, "models")

    if not isinstance(model, modelgen.Model):  # a transfer function: its poles, zeros and normal form
        from ..systems import system_info

        if args.convergence or args.plot or args.matrices:
            from modelgen.errors import SettingsError

            option = "--convergence" if args.convergence else "--plot" if args.plot else "--matrices"
            raise SettingsError(option, True, "nothing for a transfer function (it is about a link's assumed modes)")
        data, text = system_info(model)
        bounded = later()
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
    bounded = later()
    figure = None
    if args.plot and conv is not None:
        from ..plots import convergence_figure

        families: dict[str, Any] = {}
        for family in ("clamped-mass", "clamped-free", "polynomial"):
            if family == model.geometry.mode_shapes:
                families[family] = conv
            else:
                families[family] = convergence(model.geometry.with_model(mode_shapes=family), len(conv.models),
                                               loader=lambda g: modelgen.load(g, output_at=args.output_at),
                                               progress=progress, output_at=args.output_at)
        folder = output_folder(args, model.name, "info")
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
        raise SettingsError("--trajectory", args.trajectory, TRAJECTORY_HELP_SHORT)
    trajectory = trajectory_from_spec(args.trajectory)
    move = trajectory.move()
    if args.max_error is not None and not (args.max_error > 0):
        raise SettingsError("--max-error", args.max_error, "a number > 0 (m)")
    bound = tip_bound(args.max_error, move)
    return causal_limit(model, trajectory, bound)


def _info_bounded(args: argparse.Namespace, model: Any, limit: Any) -> Callable[[], Any] | None:
    """``info --trajectory --period``: the bounded causal limit's work (:mod:`inversion.methods.bounded_limit`: the
    limit, or why it was not computed), its flags checked at once; ``None`` where it is not asked."""
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
    from inversion.methods.bounded_limit import bounded_limit
    from inversion.signals.trajectory import trajectory_from_spec

    trajectory = trajectory_from_spec(args.trajectory)
    try:
        check_period(args.period, trajectory)
    except SettingsError as exc:
        raise SettingsError("--period", args.period, exc.accepted) from None
    bounds = Criteria(max_error=limit.bound, period=args.period, hold="zoh", max_torque=args.max_torque, max_torque_rate=args.max_torque_rate)
    args.reporter("the bounded causal limit (a chain programme)")

    def work() -> Any:
        try:  # asked for and within range: what cannot be computed is said in the output, beside every figure info has
            return bounded_limit(model, trajectory, bounds, shortest=True)
        except (InversionError, SettingsError) as exc:
            return f"not computed: {in_flags(str(exc), getattr(exc, 'parameter', None))}"

    return work


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

"""Non-causal stable inversion: the baseline the paper argues against.

Bayo (1987), Kwon & Book (1994), Devasia, Chen & Paden (1996) [docs/method.md, section 9]:
the output follows ``y_d`` exactly, and each internal mode ``zdot_i = lambda_i z_i + beta_i
yddot_d`` takes its one bounded solution -- integrated forwards from ``-inf`` when it is
stable, backwards from ``+inf`` when it is unstable::

    z_i(t) =  beta_i int_{-inf}^{t} e^{lambda_i (t - s)} yddot_d(s) ds      (Re lambda_i < 0)
    z_i(t) = -beta_i int_{t}^{+inf} e^{lambda_i (t - s)} yddot_d(s) ds      (Re lambda_i > 0)

``yddot_d`` vanishes outside ``[t_0, t_f]``, so the stable modes start at rest at ``t_0`` and
ring down after ``t_f`` (post-actuation), the unstable ones end at rest at ``t_f`` and grow
from zero before ``t_0`` (pre-actuation: torque *before* the motion). Both tails decay
exponentially and are cut where the torque and the joint reference they carry fall below
``tail_tolerance`` of their peaks.

A purely imaginary zero has no dichotomy: its mode neither decays forwards nor backwards,
and the inverse does not exist -- the paper's main argument for the causal method. Such a
model is refused, naming the zeros. Nearly imaginary zeros give an inverse with a long
pre-actuation, which the summary reports.

The integrals over the manoeuvre are exact quadrature: Gauss-Legendre on every interval
between samples (split at the trajectory's breakpoints, where it is a polynomial), with the
weight ``e^{-lambda u}`` (unstable) or ``e^{lambda (Delta - u)}`` (stable) bounded by one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from modelgen.zeros import is_imaginary

from ..acceptance import Acceptance, Criteria, judge, larger_model, summary_keys
from ..config import DEFAULTS, default, held_period, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.internal import ModalInternalDynamics
from ..lti.linear_system import LinearSystem
from ..lti.system import NormalForm
from ..options import InversionMethod, register
from ..problem import Problem
from ..result import InversionResult, SummaryFigures, caller_state, inverse_input, report_row, summarize, summary_words
from ..signals.chebyshev import LINK_SIGNALS, SYSTEM_SIGNALS, PiecewiseChebyshev, fit_chebyshev
from ..signals.trajectory import Trajectory

if TYPE_CHECKING:
    from modelgen.model import Model

__all__ = ["Stable", "stable_inversion", "DEFAULT_TAIL_TOLERANCE", "MAX_TAIL"]

#: The tails are cut where torque and joint reference fall below this fraction of their peaks
#: (:data:`inversion.config.DEFAULTS`).
DEFAULT_TAIL_TOLERANCE = DEFAULTS.tail_tolerance
#: Longest accepted pre- or post-actuation, in multiples of the manoeuvre's duration.
MAX_TAIL = 1000.0
_ORDER = 24
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(_ORDER)
#: Largest ``|lambda| * panel`` of one Gauss-Legendre panel (e-folds or radians).
_PANEL = 20.0


def _moments(trajectory: Trajectory, edges: NDArray[np.float64], lam: NDArray[np.complex128]) -> NDArray[np.complex128]:
    """``int_0^D w_i(u) yddot_d(t_k + u) du`` on every interval ``[t_k, t_k + D]`` of ``edges``, shape (intervals, modes).

    ``w_i(u) = e^{-lambda_i u}`` for ``Re lambda_i > 0``, ``e^{lambda_i (D - u)}`` otherwise:
    never above one. Each interval is cut into panels of at most ``_PANEL`` e-folds/radians
    of the fastest mode.
    """
    starts, widths = edges[:-1], np.diff(edges)
    panels = max(1, math.ceil(float(np.abs(lam).max(initial=0.0)) * float(widths.max(initial=0.0)) / _PANEL))
    # nodes: (interval, panel, node) -> offset u in [0, D]
    left = widths[:, None] * (np.arange(panels)[None, :] / panels)
    half = widths / (2 * panels)
    u = left[:, :, None] + half[:, None, None] * (1 + _NODES[None, None, :])
    weights = (half[:, None, None] * _WEIGHTS[None, None, :]) * np.ones_like(u)
    values = trajectory.derivative((starts[:, None, None] + u).ravel(), 2).reshape(u.shape)
    out = np.empty((starts.size, lam.size), dtype=complex)
    for i, rate in enumerate(lam):
        kernel = np.exp(-rate * u) if rate.real > 0 else np.exp(rate * (widths[:, None, None] - u))
        out[:, i] = (weights * values * kernel).sum(axis=(1, 2))
    return out


def _modal_states(form: NormalForm, trajectory: Trajectory, grid: NDArray[np.float64]) -> NDArray[np.complex128]:
    """The bounded modal internal state at the times ``grid`` (covering ``[t0, tf]``), shape (N, 2n)."""
    modal = form.modal(0.0)
    lam, beta = modal.lam, modal.beta
    inner = [b for b in trajectory.breakpoints if grid[0] < b < grid[-1]]
    edges = np.union1d(grid, inner)
    at = np.searchsorted(edges, grid)
    m = _moments(trajectory, edges, lam)
    widths = np.diff(edges)
    z = np.zeros((edges.size, lam.size), dtype=complex)
    for i in range(lam.size):
        if lam[i].real > 0:  # backwards from rest at t_f
            decay = np.exp(-lam[i] * widths)
            for k in range(edges.size - 2, -1, -1):
                z[k, i] = decay[k] * z[k + 1, i] - beta[i] * m[k, i]
        else:  # forwards from rest at t_0
            growth = np.exp(lam[i] * widths)
            for k in range(edges.size - 1):
                z[k + 1, i] = growth[k] * z[k, i] + beta[i] * m[k, i]
    return z[at]


def stable_inversion(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    rate: float | None = None,
    tail_tolerance: float | None = None,
    bounds: Criteria | None = None,
    preview: float | None = None,
    reference: Trajectory | None = None,
) -> InversionResult:
    """Non-causal stable inversion of the linear model.

    Parameters
    ----------
    model : Model or LinearSystem
        A loaded model, or a generic system (:mod:`inversion.lti.linear_system`; ``tau`` is then
        its input ``u``; the internal modes are those driven by ``yddot``,
        :class:`~inversion.lti.system.NormalForm`).
    trajectory : Trajectory
        Desired tip trajectory, at rest outside ``[t0, tf]``.
    rate : float, optional
        Sampling rate (Hz; default :data:`inversion.config.DEFAULTS`); the samples run from
        ``t0 - pre_actuation_time`` to ``tf + post_actuation_time`` on the grid ``t0 + k / rate``.
    tail_tolerance : float, optional
        The tails are cut where the torque and the joint reference fall below this fraction
        of their peaks (default :data:`DEFAULT_TAIL_TOLERANCE`).
    bounds : Criteria, optional
        The period and hold of the held table and the after-end window of what reaches the
        link (:mod:`inversion.acceptance`; default a 1 ms period, point hold).
    preview : float, optional
        The longest pre-actuation allowed (s; default: as long as the tails need). A shorter
        one truncates the unstable modes' tail: the plant then starts at rest ``preview``
        seconds before ``t0`` instead of on the exact inverse's state, and the output leaves
        ``y_d`` by the free response of the difference, ``C e^{A (t - t_s)} (x_rest - x(t_s))``
        -- reported as ``max_error`` and judged like any causal feedforward's.
    reference : Trajectory, optional
        The output inverted, when it is not ``trajectory`` itself: a re-planned output on the same span
        (:mod:`inversion.methods.replan`), whose distance from ``trajectory`` is the result's error. Its purely
        imaginary modes are then accepted: a re-planned output leaves them at rest at ``t_f``.

    Returns
    -------
    InversionResult
        ``y = y_d`` exactly; ``summary`` adds ``method``, ``pre_actuation_time`` and
        ``post_actuation_time``; ``signals`` holds the input (and a link's joint references)
        on the whole span as piecewise Chebyshev series, which the samples and the exported C
        evaluate (:mod:`inversion.signals.chebyshev`).

    Raises
    ------
    InversionError
        When a zero is purely imaginary (no stable inverse), or the tails would be longer
        than :data:`MAX_TAIL` manoeuvre durations.
    SettingsError
        For a rate or tolerance out of range, or more samples than the inversion allows.
    """
    rate = default("rate", rate)
    tail_tolerance = default("tail_tolerance", tail_tolerance)
    if preview is not None and (isinstance(preview, bool) or not isinstance(preview, (int, float)) or not 0 <= preview < math.inf):
        raise SettingsError("preview", preview, "a finite number >= 0 (s of torque allowed before the move starts)")
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
        raise SettingsError("rate", rate, "a finite number > 0 (Hz)")
    if isinstance(tail_tolerance, bool) or not isinstance(tail_tolerance, (int, float)) or not 0 < tail_tolerance < 1:
        raise SettingsError("tail_tolerance", tail_tolerance, "a number in (0, 1)")
    system = isinstance(model, LinearSystem)
    form = NormalForm.of_system(model) if system else NormalForm.of_model(model)
    modal = form.modal(0.0)
    lam = modal.lam
    imaginary = is_imaginary(lam)
    target = trajectory if reference is None else reference
    if reference is not None and (abs(reference.t0 - trajectory.t0) > 1e-12 or abs(reference.tf - trajectory.tf) > 1e-9):
        raise SettingsError("reference", reference.name, f"an output on the trajectory's span [{trajectory.t0:g}, {trajectory.tf:g}] s")
    if np.any(imaginary) and reference is None:
        shown = ", ".join(f"{abs(z.imag):.6g}i" for z in lam[imaginary] if z.imag > 0) or ", ".join(f"{z:.6g}" for z in lam[imaginary])
        raise InversionError(
            f"stable inversion does not exist for {model.name}: the zeros +-{shown} are purely imaginary, so their "
            "internal modes decay neither forwards nor backwards in time (no bounded non-causal solution); "
            "the causal inversion (method 'ssef', the default) handles them"
        )
    t0, tf = trajectory.t0, trajectory.tf
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    inside = t0 + np.arange(count) / rate
    if tf - inside[-1] > 1e-9 / rate:
        inside = np.append(inside, tf)
    z_inside = _modal_states(form, target, inside)
    # a re-planned output holds its purely imaginary modes at rest at both ends: no tail of theirs to wait for
    pre, post = _tail_lengths(model, form, modal, target.values(inside, form.top), trajectory.duration, z_inside, tail_tolerance,
                              ignored=imaginary)
    needed = pre
    pre = pre if preview is None else min(pre, float(preview))
    unstable = lam.real > 0
    before = np.arange(-math.ceil(pre * rate), 0) / rate + t0
    after = inside[-1] + np.arange(1, math.ceil(post * rate) + 1) / rate
    if before.size + inside.size + after.size > DEFAULTS.max_samples:
        raise SettingsError("rate", rate, f"at most {DEFAULTS.max_samples} samples over the {pre + trajectory.duration + post:.4g} s "
                                          "of stable inversion (pre- and post-actuation included)")
    # the tails: the unstable modes alone before t0, the stable ones alone after tf (each decaying)
    z = np.vstack([np.exp(np.outer(before - t0, np.where(unstable, lam, 0))) * np.where(unstable, z_inside[0], 0),
                   z_inside,
                   np.exp(np.outer(after - inside[-1], np.where(unstable, 0, lam))) * np.where(unstable, 0, z_inside[-1])])
    t = np.concatenate([before, inside, after])
    values = {**target.values(t, form.top), "XI": modal.to_physical(z)}  # at rest outside [t0, tf]
    y, ydot, yddot = values["y"], values["ydot"], values["yddot"]
    y_d = y if reference is None else trajectory.values(t, 0)["y"]
    X_form = np.asarray(form.state_of(values), dtype=float)
    error, at = 0.0, float(t0)
    if pre < needed:
        # a truncated pre-actuation: the plant starts at rest, and leaves y_d by the free response of the difference
        rest = {**target.values(t[:1], form.top), "XI": np.zeros((1, modal.V.shape[0]))}
        deviation = _free_response(np.asarray(form.A, dtype=float), t, np.asarray(form.state_of(rest), dtype=float)[0] - X_form[0])
        X_form = X_form + deviation
        dy = deviation @ np.asarray(form.C, dtype=float)
        y = y + dy
        ydot = ydot + deviation @ (np.asarray(form.C, dtype=float) @ np.asarray(form.A, dtype=float))  # free: d/dt C e^{At} dx
    if reference is not None or pre < needed:
        worst = int(np.argmax(np.abs(y - y_d)))
        error, at = float(abs(y[worst] - y_d[worst])), float(t[worst])
    X = caller_state(model, X_form)  # the input itself comes from the series below
    joint = None if isinstance(model, LinearSystem) else model.n + 1
    # the samples fed forward are those of the series the exported C evaluates (inversion.signals.chebyshev)
    signals = _signals(form, target, (float(t[0]), float(t[-1])), z_inside[0], z_inside[-1], joint)
    fed = signals.evaluate(t)
    tau = fed[signals.names[0]]
    move = abs(float(y_d[-1] - y_d[0]))
    bounds = Criteria(max_error=tip_bound(None, move, judged=False), period=held_period(None, rate)) if bounds is None else bounds
    acceptance = judge(form, trajectory, signals, bounds, x0=X_form[0], x_end=X_form[-1], feed_start=float(t[0]), feed_end=float(t[-1]),
                       reference=lambda times: target.derivative(np.clip(times, target.t0, target.tf), 0),
                       peak=float(np.abs(tau).max()), error=error, move=move, larger=larger_model(model, bounds.extra_modes))
    summary = _summary(model, trajectory, t, y, ydot, tau, X, rate, tail_tolerance, (pre, needed, post), modal, acceptance,
                       bounds.max_error, (error, at))
    return InversionResult(t=t, y_d=y_d, y=y, ydot=ydot, yddot=yddot, X=X, tau=tau, theta_d=None if joint is None else fed["theta_d"],
                           thetadot_d=None if joint is None else fed["thetadot_d"], summary=summary, model=model,
                           trajectory=trajectory, modal=modal, signals=signals, acceptance=acceptance)


def _tail_lengths(model: Model | LinearSystem, form: NormalForm, modal: ModalInternalDynamics, inside: dict[str, Any],
                  duration: float, z_inside: NDArray[np.complex128], tail_tolerance: float,
                  ignored: NDArray[np.bool_] | None = None) -> tuple[float, float]:
    """The pre- and post-actuation times: after them every unstable (before ``t0``) or stable (after ``tf``) mode's share
    of the torque and of a link's joint angle stays below ``tail_tolerance`` of their peaks over the move (``inside``:
    ``y_d``'s derivatives on the move's samples, :meth:`Trajectory.values`; ``duration``: the move's; ``ignored``: modes
    left out).

    Raises
    ------
    InversionError
        When a tail would be longer than :data:`MAX_TAIL` manoeuvre durations (a nearly imaginary zero).
    """
    lam, V = modal.lam, modal.V
    system = isinstance(model, LinearSystem)
    # what one unit of each mode puts into the torque and the joint angle (through X = T^-1 [y; ydot; X_I])
    tau_per_mode = -(form.CA2 @ form.Tinv[:, 2:] @ V) / form.CAB
    theta_per_mode = form.Tinv[0, 2:] @ V
    values = {**inside, "XI": modal.to_physical(z_inside)}
    X_inside, tau_inside = inverse_input(model, form, values)
    peaks = (float(np.abs(tau_inside).max()), float(np.abs(X_inside[:, 0] - X_inside[0, 0]).max()))
    # the shares the tails must shed: the torque's, and the joint angle's of a link (a system's input only)
    shares = ((tau_per_mode, peaks[0]),) if system else ((tau_per_mode, peaks[0]), (theta_per_mode, peaks[1]))

    def tail(z_end: NDArray[np.complex128], modes: NDArray[np.bool_]) -> float:
        """Time after which every mode's share of torque and joint angle stays below the tolerance."""
        longest = 0.0
        for i in np.flatnonzero(modes):
            for per_mode, peak in shares:
                size = abs(per_mode[i] * z_end[i]) * 2 * modes.sum()
                if peak > 0 and size > tail_tolerance * peak:
                    longest = max(longest, math.log(size / (tail_tolerance * peak)) / abs(lam[i].real))
        return longest

    unstable = lam.real > 0
    kept = np.ones(lam.shape, dtype=bool) if ignored is None else ~ignored
    pre, post = tail(z_inside[0], unstable & kept), tail(z_inside[-1], ~unstable & kept)
    if max(pre, post) > MAX_TAIL * duration:
        slowest = lam[np.argmin(np.abs(lam.real))]
        raise InversionError(
            f"stable inversion of {model.name} needs {pre:.4g} s of pre-actuation and {post:.4g} s of post-actuation "
            f"(more than {MAX_TAIL:g} x the {duration:g} s manoeuvre): the zero {slowest:.6g} is nearly imaginary"
        )
    return pre, post


def _signals(form: NormalForm, trajectory: Trajectory, span: tuple[float, float], z_start: NDArray[np.complex128],
             z_end: NDArray[np.complex128], joint: int | None) -> PiecewiseChebyshev:
    """The input (and a link's joint references) on the whole span, pre- and post-actuation included,
    as piecewise Chebyshev series (:mod:`inversion.signals.chebyshev`): what the exported C evaluates.

    The intervals are the pre-actuation, the manoeuvre cut at the trajectory's breakpoints, and
    the post-actuation; inside the manoeuvre the modes are integrated as for the samples, outside
    they are the decaying tails.
    """
    modal = form.modal(0.0)
    lam = modal.lam
    unstable = lam.real > 0
    t0, tf = trajectory.t0, trajectory.tf
    inner = [b for b in trajectory.breakpoints if t0 < b < tf]
    bounds = np.array(([span[0]] if span[0] < t0 else []) + [t0, *inner, tf] + ([span[1]] if span[1] > tf else []))

    def evaluate(k: NDArray[np.intp], s: NDArray[Any]) -> NDArray[Any]:
        times = bounds[k][:, None] + np.asarray(s, dtype=float)
        flat = times.ravel()
        z = np.zeros((flat.size, lam.size), dtype=complex)
        before, after = flat < t0, flat > tf
        inside = ~before & ~after
        if np.any(inside):
            grid = np.unique(np.r_[t0, flat[inside], tf])
            z[inside] = _modal_states(form, trajectory, grid)[np.searchsorted(grid, flat[inside])]
        z[before] = np.exp(np.outer(flat[before] - t0, np.where(unstable, lam, 0))) * np.where(unstable, z_start, 0)
        z[after] = np.exp(np.outer(flat[after] - tf, np.where(unstable, 0, lam))) * np.where(unstable, 0, z_end)
        values = {**trajectory.values(flat, form.top), "XI": modal.to_physical(z)}
        X = form.state_of(values)
        out = [form.input_of(values, X)] + ([] if joint is None else [X[:, 0], X[:, joint]])
        return np.stack([np.asarray(v).reshape(times.shape) for v in out], axis=1)

    return fit_chebyshev(SYSTEM_SIGNALS if joint is None else LINK_SIGNALS, bounds, evaluate)


def _free_response(A: NDArray[np.float64], t: NDArray[np.float64], x0: NDArray[np.float64]) -> NDArray[np.float64]:
    """``e^{A (t_k - t_0)} x0`` on the grid ``t`` (one matrix exponential per distinct step)."""
    import scipy.linalg  # lazy: keeps `import inversion` fast

    steps: dict[float, NDArray[np.float64]] = {}
    out = np.empty((t.size, x0.size))
    out[0] = x0
    for k in range(1, t.size):
        dt = round(float(t[k] - t[k - 1]), 12)
        if dt not in steps:
            steps[dt] = scipy.linalg.expm(A * dt)
        out[k] = steps[dt] @ out[k - 1]
    return out


def _summary(model: Model | LinearSystem, trajectory: Trajectory, t: Any, y: Any, ydot: Any, tau: Any, X: Any, rate: float,
             tail_tolerance: float, tails: tuple[float, float, float], modal: Any, acceptance: Acceptance, gate: float,
             error: tuple[float, float]) -> Any:
    """The summary of a stable inversion (:func:`inversion.result.summarize`): ``y = y_d`` (or its truncation's free
    response), the tails' lengths."""
    pre, needed, post = tails
    y_start, y_end = trajectory.y_start, trajectory.y_final
    move = abs(y_end - y_start)
    peak = int(np.argmax(np.abs(tau)))
    figures = SummaryFigures(
        max_error=error[0],  # 0: the output is y_d itself; else the truncated tail's free response
        time_of_max_error=error[1], move=move,
        gate=gate,  # the bound every inversion reports
        peak_torque=float(abs(tau[peak])), time_of_peak_torque=float(t[peak]), n_unstable=int((modal.lam.real > 0).sum()),
    )
    settings = {"method": "stable", "rate": float(rate), "tail_tolerance": float(tail_tolerance),
                "pre_actuation_needed": needed, "post_actuation_needed": post, "preview": None if pre >= needed else pre}
    top, verification = summary_keys(acceptance)
    extra = {"method": "stable", "pre_actuation_time": float(trajectory.t0 - t[0]), "post_actuation_time": float(t[-1] - trajectory.tf), **top}
    return summarize(model, trajectory, figures, {"t": t, "y": y, "ydot": ydot, "tau": tau, "X": X}, settings, verification=verification,
                     extra=extra)


@register
@dataclass(frozen=True)
class Stable(InversionMethod):
    """Non-causal stable inversion: exact tracking, pre-actuation.

    Non-causal stable inversion (Bayo; Kwon & Book; Devasia, Chen & Paden): exact tracking, its stable modes integrated
    forwards and its unstable ones backwards -- torque before ``t0`` (truncated to the problem's ``preview``, where it
    gives one) and after ``t_f``. It does not exist for a purely imaginary zero, and says so.

    It takes no option of its own: its pre-actuation is the problem's (:attr:`inversion.problem.Problem.preview`).
    """

    name = "stable"
    label = "stable inversion"
    title = "non-causal stable inversion's feedforward"
    rank = 2.0
    stage = 0.0
    causal = False
    help = "the non-causal stable-inversion baseline (exact tracking, torque before t0; refused for purely imaginary zeros)"
    series_text = "the stable inversion's quadrature and tails re-expanded"

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The stable inversion, judged at the quality gate.

        The stable inversion (:func:`stable_inversion`), judged at the quality gate.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        say : callable
            The progress display.
        """
        return stable_inversion(problem.system, problem.trajectory, problem.rate,
                                bounds=problem.criteria(problem.bound(judged=False), max_torque=None), preview=problem.preview)

    def takes_part(self, problem: Problem) -> bool:
        """A stage of the automatic choice where a preview is allowed.

        It competes with the family where the problem allows pre-actuation (a ``preview``).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        return problem.preview is not None

    def for_automatic(self, stage: Any) -> tuple[InversionMethod, Problem] | str:
        """Truncated to the problem's preview.

        Parameters
        ----------
        stage : inversion.methods.automatic.Stage
            The automatic choice's figures so far.
        """
        return self, stage.aimed(preview=stage.problem.preview)

    def compared(self, problem: Problem, run: Callable[[Problem, InversionMethod], InversionResult]) -> tuple[InversionResult, str]:
        """compare's row: at its own quality gate.

        ``compare``'s row: exact tracking, judged at its own quality gate (not the problem's tip bound).

        Parameters
        ----------
        problem : Problem
            The comparison's problem.
        run : callable
            The door.
        """
        return run(problem.with_bounds(max_error=None), self), ""

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """``"tails cut at 1e-09"``.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        return f"tails cut at {summary['settings']['tail_tolerance']:g}"

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """The C header's line.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s = summary
        return (f"non-causal stable inversion: {s['pre_actuation_time']:.6g} s of pre-actuation, "
                f"{s['post_actuation_time']:.6g} s of post-actuation")

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of ``sflm invert``'s text.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s = summary
        w = summary_words(s)
        m, unit, sym = w["m"], w["unit"], w["sym"]
        zeros = ", ".join(f"{re:.4g}{im:+.4g}i" if im else f"{re:.4g}" for re, im in s["zeros"])
        truncated = s["settings"].get("preview") is not None
        return [
            f"{s['model']}: non-causal stable inversion " + ("(the baseline; exact tracking)" if not truncated else
                                                              f"truncated to {s['pre_actuation_time']:.4g} s of pre-actuation")
            + f", zeros {zeros}",
            report_row("trajectory", f"{s['trajectory']}: y = y_d exactly ({s['move']:.4g}{m} move)" if not truncated else
                       f"{s['trajectory']}: y leaves y_d by {s['max_redefinition_error']:.3g}{m} "
                       f"({100 * s['relative_redefinition_error']:.3g} % of the {s['move']:.4g}{m} move; accepted "
                       f"{s['max_error']:.3g}{m}), the truncated tail's free response"),
            report_row("pre-actuation", f"{s['pre_actuation_time']:.4g} s of {w['inp']} before t0 ({sym} at the first sample "
                       f"{s['torque_at_start']:.2g}{unit})" + ("" if not truncated else
                                                               f"; truncated to --preview, the tails need "
                                                               f"{s['settings']['pre_actuation_needed']:.4g} s")),
            report_row("post-actuation", f"{s['post_actuation_time']:.4g} s of {w['inp']} after tf ({sym} at the last sample "
                       f"{s['torque_at_end']:.2g}{unit}); tails cut at {s['settings']['tail_tolerance']:.0e} of the peaks"),
            report_row(f"peak |{sym}|", f"{s['peak_torque']:.5g}{unit} (at t = {s['time_of_peak_torque']:.4g} s)"),
            report_row("samples", f"{s['samples']} at {s['settings']['rate']:g} Hz"),
        ]

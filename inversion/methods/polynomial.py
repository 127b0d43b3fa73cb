"""Polynomial redefinition: the paper's Eq. (2), the baseline with one solution.

In segment ``k`` (local time ``s`` in ``[0, T]``, ``u = s/T``) the desired acceleration is
replaced by a polynomial, ``yddot~(s) = sum_{j<r} a_j u^j``, meeting the conditions of the
exponential redefinition (:mod:`inversion.family.ssef`): smooth joining of ``yddot~`` and its
first ``h`` derivatives at both ends (P30), and for every unstable mode the bounded
solution starting where the previous segment ended (conditions 3-2 and 3-3). For a
polynomial forcing the bounded solution of ``zdot = lambda z + beta yddot~`` is itself a
polynomial::

    z_p(s) = -beta sum_{m >= 0} yddot~^(m)(s) / lambda^(m+1)

so condition 3-3 reads ``z_p(0) = z_i(t_k)``; a stable mode is ``z_p(s) + e^{lambda s}
(z_i(t_k) - z_p(0))``. With ``joining="position"`` the segment also ends on ``y_d`` and
``ydot_d``. Everything is closed form; the ``r = 2(h+1) (+2) + n_u`` coefficients are unique:
where the exponentials give a family, the polynomial gives one answer.

A generic system of relative degree ``rho`` (:mod:`inversion.lti.linear_system`) is redefined the
same way in the internal coordinates driven by ``yddot`` (:class:`~inversion.lti.system.NormalForm`),
with ``yddot~`` joined to order ``h + rho - 2`` so that its input is ``C^h``, as the SSEF's.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from ..acceptance import Criteria, judge, larger_model, summary_keys
from ..config import default, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form
from ..options import InversionMethod, Joining, register
from ..problem import Problem
from ..result import InversionResult, SummaryFigures, inverse_input, report_row, segment_summaries, summarize, summary_words
from ..settings import DEFAULT_SETTINGS, InversionSettings, paper_settings
from ..signals.chebyshev import LINK_SIGNALS, SYSTEM_SIGNALS, PiecewiseChebyshev, fit_chebyshev
from ..signals.trajectory import Trajectory, derivative_key

if TYPE_CHECKING:
    from modelgen.model import Model

__all__ = ["Polynomial", "polynomial_inversion", "polynomial_redefinition_error", "POLYNOMIAL_JOININGS"]

#: The joinings the polynomial redefinition supports.
POLYNOMIAL_JOININGS = (Joining.PAPER.value, Joining.POSITION.value)


def _derivative_matrix(r: int, T: float) -> NDArray[np.float64]:
    """``D`` with ``(D a)`` the coefficients (in ``u``) of ``d/ds`` of ``sum a_j u^j``."""
    D = np.zeros((r, r))
    for j in range(1, r):
        D[j - 1, j] = j / T
    return D


def _bounded(a: NDArray[Any], T: float, lam: complex, beta: complex) -> NDArray[np.complex128]:
    """Coefficients (in ``u``) of ``z_p = -beta sum_m p^(m) / lambda^(m+1)`` for the polynomial ``a``."""
    r = a.shape[-1]
    D = _derivative_matrix(r, T)
    out = np.zeros(a.shape, dtype=complex)
    term = a.astype(complex)
    for m in range(r):
        out = out + term / lam ** (m + 1)
        term = term @ D.T
    return -beta * out


def _values(a: NDArray[Any], u: NDArray[np.float64]) -> NDArray[Any]:
    """``sum_j a_j u^j`` at ``u`` (Horner)."""
    out = np.zeros(u.shape, dtype=np.result_type(a, u))
    for coefficient in a[::-1]:
        out = out * u + coefficient
    return out


def polynomial_inversion(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    segments: int = 5,
    h: int = 2,
    joining: str = "paper",
    rate: float | None = None,
    max_error: float | None = None,
    acceptance_bounds: Criteria | None = None,
) -> InversionResult:
    """Causal inversion with a polynomial redefinition per segment.

    The redefinition is the module docstring's.

    Parameters
    ----------
    model, trajectory :
        As :func:`inversion.invert` (a link model, or a generic system already converted by
        :func:`~inversion.lti.linear_system.as_linear_system`).
    segments : int
        Number of equal segments.
    h : int
        Order of smooth joining.
    joining : {"paper", "position"}
        The conditions, as for the exponential redefinition.
    rate : float, optional
        Sampling rate (Hz; default :data:`inversion.config.DEFAULTS`).
    max_error : float, optional
        Quality gate (m; default 5 % of the move).
    acceptance_bounds : Criteria, optional
        The period and hold of the held table and the after-end window of what reaches the
        link (:mod:`inversion.acceptance`; default a period of ``1/rate``, point hold).

    Raises
    ------
    SettingsError
        For values out of range.
    InversionError
        When the redefinition is further from ``y_d`` than ``max_error`` or not finite.
    """
    rate = default("rate", rate)
    member = _redefine(model, trajectory, segments, h, joining)
    form, modal, lam, bounds, pieces = member.form, member.modal, member.modal.lam, member.bounds, member.pieces
    K, errors, move, dense = bounds.size - 1, member.errors, member.move, member.dense
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    t = trajectory.t0 + np.arange(count) / rate
    if trajectory.tf - t[-1] > 1e-9 / rate:
        t = np.append(t, trajectory.tf)
    with np.errstate(over="ignore", invalid="ignore"):
        values = _evaluate(pieces, bounds, lam, t, form.top)
    gate = tip_bound(max_error, move, judged=False)
    if not np.all(np.isfinite(errors)) or not errors.max() <= gate:
        raise InversionError(f"the polynomial redefinition ({K} segments, h = {h}, {joining}) is {errors.max():.4g} m from the "
                             f"desired output ({100 * errors.max() / max(move, 1e-300):.3g} % of the {move:.4g} m move; "
                             f"accepted {gate:.3g} m)")
    X, tau = inverse_input(model, form, {**values, "XI": modal.to_physical(values["z"])})
    peak = int(np.argmax(np.abs(tau)))
    y_d = trajectory.derivative(t, 0)
    joint = None if isinstance(model, LinearSystem) else model.n + 1
    with np.errstate(over="ignore", invalid="ignore"):  # a member near divergence (its figures judge it)
        signals = _signals(form, pieces, bounds, lam, joint)
    X_form = np.asarray(form.state_of({**values, "XI": modal.to_physical(values["z"])}), dtype=float)
    bounds_of = Criteria(max_error=gate, period=1.0 / rate) if acceptance_bounds is None else acceptance_bounds
    acceptance = judge(form, trajectory, signals, bounds_of, x0=X_form[0], x_end=X_form[-1], feed_start=float(t[0]), feed_end=float(t[-1]),
                       reference=lambda times: _evaluate(pieces, bounds, lam, np.clip(times, trajectory.t0, trajectory.tf), 2)["y"],
                       peak=float(abs(tau[peak])), error=float(errors.max()), move=move, larger=larger_model(model, bounds_of.extra_modes))
    after = acceptance.after_end
    if not after.max_tip_excursion <= gate:  # y_d holds y_d(t_f) after the move: an output that strays from it is refused too
        raise InversionError(f"after the polynomial redefinition ({K} segments, h = {h}, {joining}) ends the output strays "
                             f"{after.max_tip_excursion:.4g} from y_d(t_f) in {after.window:g} s ({100 * after.max_tip_excursion / max(move, 1e-300):.3g} % "
                             f"of the {move:.4g} m move; accepted {gate:.3g} m), drifting at {after.drift:.3g}/s")
    figures = SummaryFigures(
        max_error=float(errors.max()), time_of_max_error=float(dense[int(np.argmax(errors))]), move=move, gate=gate,
        peak_torque=float(abs(tau[peak])), time_of_peak_torque=float(t[peak]), n_unstable=modal.n_unstable,
        max_constraint_residual=max(p["residual"] for p in pieces), max_condition_number=max(p["condition"] for p in pieces), r=member.r,
    )
    samples = {"t": t, "y": values["y"], "ydot": values["ydot"], "tau": tau, "X": X}
    settings_json = {"method": "polynomial", "segments": [float(v) for v in bounds], "h": h, "joining": joining, "rate": float(rate)}
    segment_rows = segment_summaries([(p["t"], p["t"] + p["T"], [], p["a"].tolist(), p["residual"], p["condition"]) for p in pieces])
    top, verification = summary_keys(acceptance)
    summary = summarize(model, trajectory, figures, samples, settings_json, segments=segment_rows, verification=verification,
                        extra={"method": "polynomial", **top})
    return InversionResult(t=t, y_d=y_d, y=values["y"], ydot=values["ydot"], yddot=values["yddot"], X=X, tau=tau,
                           theta_d=None if joint is None else X[:, 0], thetadot_d=None if joint is None else X[:, joint],
                           summary=summary, model=model, trajectory=trajectory, modal=modal, signals=signals,
                           acceptance=acceptance)


@dataclass(frozen=True)
class _Member:
    """A solved polynomial member: its pieces and its distance from ``y_d`` on a dense grid."""

    form: Any
    modal: Any
    bounds: NDArray[np.float64]
    pieces: list[dict[str, Any]]
    r: int
    dense: NDArray[np.float64]
    errors: NDArray[np.float64]
    move: float


def _redefine(model: Model | LinearSystem, trajectory: Trajectory, segments: int, h: int, joining: str) -> _Member:
    """The member ``(segments, h, joining)`` solved, Eq. (2) with the conditions (30) and 3-2/3-3, and its
    ``|y~ - y_d|`` at 20 001 points."""
    if joining not in POLYNOMIAL_JOININGS:
        raise SettingsError("joining", joining, "paper or position (the polynomial redefinition)")
    settings = InversionSettings(segments=segments, h=h, joining=joining)  # validates segments and h
    form = normal_form(model)
    if form.n_internal == 0:  # nothing to redefine (compare ranks members with this; invert refuses it before)
        raise SettingsError("system", getattr(model, "name", "the system"), "a system with zeros for the polynomial redefinition: "
                            "without zeros it has no internal dynamics, its exact inverse is causal and bounded")
    bounds = settings.boundaries(trajectory, form.rho)
    modal = form.modal(0.0)
    joined = h + form.rho - 2  # the order yddot~ is joined to (h for the link)
    r = 2 * (joined + 1) + (2 if joining == Joining.POSITION else 0) + len(modal.rows)
    dense = np.linspace(trajectory.t0, trajectory.tf, 20_001)
    # the carried unstable state of a diverging member overflows: its figures are not finite and it is refused by the
    # caller, with them, instead of printing NumPy's warnings
    with np.errstate(over="ignore", invalid="ignore"):
        pieces = _solve_pieces(form, modal, trajectory, bounds, joined, joining, r)
        dense_values = _evaluate(pieces, bounds, modal.lam, dense, form.top)
    y_d_dense = trajectory.derivative(dense, 0)
    move = abs(float(y_d_dense[-1] - y_d_dense[0]))
    return _Member(form=form, modal=modal, bounds=bounds, pieces=pieces, r=r, dense=dense,
                   errors=np.abs(dense_values["y"] - y_d_dense), move=move)


def polynomial_redefinition_error(model: Model | LinearSystem, trajectory: Trajectory, segments: int, h: int,
                                  joining: str) -> float:
    """The polynomial member's ``max |y~ - y_d|`` (m).

    How far the polynomial member's output is from ``y_d``: ``max |y~ - y_d|`` (m), inf if not finite.

    The figure :func:`polynomial_inversion` reports as ``max_redefinition_error``, without
    its samples, torque and checks: what a search over members ranks them by.

    Parameters
    ----------
    model : Model or LinearSystem
        A link model, or a generic system already converted by
        :func:`~inversion.lti.linear_system.as_linear_system`.
    trajectory : Trajectory
        The desired output.
    segments, h, joining :
        The member, as :func:`polynomial_inversion`.

    Raises
    ------
    SettingsError
        For values out of range.
    """
    errors = _redefine(model, trajectory, segments, h, joining).errors
    return float(errors.max()) if np.all(np.isfinite(errors)) else math.inf


def _solve_pieces(form: Any, modal: Any, trajectory: Trajectory, bounds: NDArray[np.float64], joined: int, joining: str,
                  r: int) -> list[dict[str, Any]]:
    """Each segment's polynomial, in order (the start state of one is the end state of the last): the coefficients
    ``a`` (in ``u = s/T``), the bounded parts ``zp`` of the modes, the stable modes' free parts, residual and condition."""
    lam, beta = modal.lam, modal.beta
    rows = modal.rows
    h1 = joined + 1
    K = bounds.size - 1
    start = trajectory.derivatives(bounds[:-1], range(2, joined + 3), "+")
    stop = trajectory.derivatives(bounds[1:], range(2, joined + 3), "-")
    y, ydot = float(trajectory.derivative([bounds[0]], 0)[0]), float(trajectory.derivative([bounds[0]], 1)[0])
    # at rest at t0 (X_I = 0); in the coordinates driven by yddot (zero for the link)
    z = modal.to_modal(form.internal_start(np.zeros(form.n_internal), trajectory.values([bounds[0]], form.top)))
    pieces: list[dict[str, Any]] = []
    for k in range(K):
        T = float(bounds[k + 1] - bounds[k])
        A = np.zeros((r, r))
        b = np.zeros(r)
        D = _derivative_matrix(r, T)
        basis = np.eye(r)
        for q in range(h1):  # Eq. (30): the q-th derivative at both ends
            A[2 * q] = basis[:, 0]
            A[2 * q + 1] = basis.sum(axis=1)
            b[2 * q], b[2 * q + 1] = start[k, q], stop[k, q]
            basis = basis @ D.T
        row = 2 * h1
        powers = np.arange(r)
        if joining == Joining.POSITION:  # ydot~(T) - ydot~(0) and y~(T) - y~(0) - ydot~(0) T
            A[row] = T / (powers + 1)
            A[row + 1] = T * T / ((powers + 1) * (powers + 2))
            end = trajectory.derivatives(bounds[k + 1 : k + 2], range(2), "-")[0]
            b[row], b[row + 1] = end[1] - ydot, end[0] - y - ydot * T
            row += 2
        for (i, part), line in zip(rows, range(row, r)):  # conditions 3-2 and 3-3
            coeffs = _bounded(np.eye(r), T, lam[i], beta[i])[:, 0]  # z_p(0) of each basis polynomial
            A[line] = coeffs.imag if part == "im" else coeffs.real
            b[line] = z[i].imag if part == "im" else z[i].real
        scale = np.abs(A).max(axis=1, keepdims=True)
        a = np.linalg.solve(A / scale, b / scale[:, 0])
        zp = np.array([_bounded(a, T, lam[i], beta[i]) for i in range(lam.size)])  # (modes, r) in u
        condition = float(np.linalg.cond(A / scale))
        residual = float(np.abs(A @ a - b).max() / max(np.abs(b).max(), 1e-300))
        pieces.append({"t": float(bounds[k]), "T": T, "a": a, "y0": y, "ydot0": ydot, "zp": zp, "residual": residual,
                       "condition": condition, "free": np.where(~modal.unstable, z - zp[:, 0], 0)})
        # the end values: the next segment's start
        ydot_end = ydot + T * float((a / (powers + 1)).sum())
        y = y + ydot * T + T * T * float((a / ((powers + 1) * (powers + 2))).sum())
        ydot = ydot_end
        z = zp.sum(axis=1) + pieces[-1]["free"] * np.exp(lam * T)
    return pieces


def _signals(form: Any, pieces: list[dict[str, Any]], bounds: NDArray[np.float64], lam: NDArray[np.complex128],
             joint: int | None) -> PiecewiseChebyshev:
    """The input (and a link's joint references) as piecewise Chebyshev series of the pieces (:mod:`inversion.signals.chebyshev`):
    what the samples' checks and an exported C evaluate."""
    modal = form.modal(0.0)

    def evaluate(k: NDArray[np.intp], s: NDArray[Any]) -> NDArray[Any]:
        local = np.asarray(s, dtype=float)
        values = _evaluate_local(pieces, lam, np.repeat(k, local.shape[1]), local.ravel(), form.top)
        values["XI"] = modal.to_physical(values.pop("z"))
        X = form.state_of(values)
        out = [form.input_of(values, X)] + ([] if joint is None else [X[:, 0], X[:, joint]])
        return np.stack([np.asarray(v).reshape(local.shape) for v in out], axis=1).astype(np.longdouble)

    return fit_chebyshev(SYSTEM_SIGNALS if joint is None else LINK_SIGNALS, bounds, evaluate)


def _evaluate(pieces: list[dict[str, Any]], bounds: NDArray[np.float64], lam: NDArray[np.complex128],
              t: NDArray[np.float64], top: int = 2) -> dict[str, NDArray[Any]]:
    """``y, ydot, yddot`` (and the derivatives up to ``top``) and the modal state ``z`` at the times ``t``."""
    k = np.clip(np.searchsorted(bounds, t, side="right") - 1, 0, len(pieces) - 1)
    return _evaluate_local(pieces, lam, k, np.asarray(t, dtype=float) - bounds[k], top)


def _evaluate_local(pieces: list[dict[str, Any]], lam: NDArray[np.complex128], k: NDArray[np.intp], s: NDArray[np.float64],
                    top: int = 2) -> dict[str, NDArray[Any]]:
    """:func:`_evaluate` at local times ``s`` of the pieces ``k`` (each piece's own values at its ends)."""
    out = {derivative_key(p): np.empty(s.size) for p in range(top + 1)}
    out["z"] = np.empty((s.size, lam.size), dtype=complex)
    for m, p in enumerate(pieces):
        at = k == m
        if not np.any(at):
            continue
        local = np.clip(s[at], 0.0, p["T"])
        u = local / p["T"]
        a, T = p["a"], p["T"]
        powers = np.arange(a.size)
        out["yddot"][at] = _values(a, u)
        out["ydot"][at] = p["ydot0"] + T * u * _values(a / (powers + 1), u)
        out["y"][at] = p["y0"] + p["ydot0"] * local + T * T * u * u * _values(a / ((powers + 1) * (powers + 2)), u)
        derivative = a
        for q in range(3, top + 1):
            derivative = derivative @ _derivative_matrix(a.size, T).T
            out[derivative_key(q)][at] = _values(derivative, u)
        zp = np.array([_values(p["zp"][i], u) for i in range(lam.size)]).T
        out["z"][at] = zp + p["free"][None, :] * np.exp(np.outer(local, lam))
    return out


#: The members ``compare`` tries when none is given: the smallest error wins.
COMPARE_SEGMENTS = (1, 2, 3, 4, 5, 6)
COMPARE_H = (1, 2, 3)


@register
@dataclass(frozen=True)
class Polynomial(InversionMethod):
    """The polynomial redefinition (the paper's Eq. (2)).

    The polynomial redefinition (the paper's Eq. (2)): the same conditions met by a polynomial per segment -- one
    solution where the exponentials give a family.

    Attributes
    ----------
    segments : int, optional
        Number of equal segments (default the paper's member's for its cases, else 5).
    h : int, optional
        Order of smooth joining (default as ``segments``).
    joining : {"paper", "position"}, optional
        The conditions (default the paper's).
    """

    name = "polynomial"
    label = "the polynomial redefinition"
    title = "polynomial redefinition's feedforward"
    rank = 1.0
    redefines = True
    help = "the same conditions met by a polynomial per segment (one solution)"
    series_text = "the polynomials' closed form re-expanded"

    segments: int | None = None
    h: int | None = None
    joining: str | None = None

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The polynomial redefinition's feedforward.

        The polynomial redefinition's feedforward (:func:`polynomial_inversion`), judged at the quality gate.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        say : callable
            The progress display.
        """
        base = paper_settings(problem.case) if problem.case is not None else DEFAULT_SETTINGS
        return polynomial_inversion(problem.system, problem.trajectory,
                                    segments=base.segment_count if self.segments is None else self.segments,
                                    h=base.h if self.h is None else self.h, joining=self.joining or "paper", rate=problem.rate,
                                    max_error=problem.bounds.max_error,
                                    acceptance_bounds=problem.criteria(problem.bound(judged=False), max_torque=None))

    def compared(self, problem: Problem, run: Callable[..., InversionResult]) -> tuple[InversionResult, str]:
        """compare's row: the member given, or the grid's best.

        ``compare``'s row: the member given, or the best of the grid (``COMPARE_SEGMENTS`` x ``COMPARE_H`` x the two
        joinings), ranked by the redefinition's error alone and inverted in full for the best that passes.

        Parameters
        ----------
        problem : Problem
            The comparison's problem.
        run : callable
            ``run(problem, method)``: the door (:func:`inversion.invert`).
        """
        if self.segments is not None or self.h is not None or self.joining is not None:
            return run(problem, self), ""
        trajectory = problem.trajectory
        members = [(k, h, joining) for k, h, joining in itertools.product(COMPARE_SEGMENTS, COMPARE_H, POLYNOMIAL_JOININGS)
                   if trajectory.max_derivative is None or h + 2 <= trajectory.max_derivative]
        tried = len(members)
        system = problem.system
        if problem.form.n_internal == 0:  # what no member changes: refused by name, as invert refuses it
            raise SettingsError("system", system.name, "a system with zeros for the polynomial redefinition (without zeros it "
                                "has no internal dynamics: its exact inverse is causal and bounded)")
        ranked: list[tuple[float, int]] = []
        for index, (k, h, joining) in enumerate(members):
            try:
                error = polynomial_redefinition_error(system, trajectory, segments=k, h=h, joining=joining)
            except (InversionError, SettingsError):
                continue
            if math.isfinite(error):
                ranked.append((error, index))
        best: InversionResult | None = None
        first: str | None = None  # why the member of least error was refused (the acceptance every method passes)
        loose = problem.with_bounds(max_error=math.inf)
        for _error, index in sorted(ranked):
            k, h, joining = members[index]
            try:
                best = run(loose, Polynomial(segments=k, h=h, joining=joining))
            except (InversionError, SettingsError) as exc:
                first = first or str(exc)
                continue
            break
        grid = f"{tried} members (segments 1..6, h 1..3, paper or position)"
        if best is None:
            if first is not None:
                raise InversionError(f"none of the {grid} of the polynomial redefinition passes; the closest to y_d: {first}")
            raise InversionError(f"none of the {grid} of the polynomial redefinition has a finite solution")
        s = best.summary
        gate = problem.bound(judged=False)
        if not s["max_redefinition_error"] <= gate:
            settings = s["settings"]
            raise InversionError(
                f"the best of {grid} ({len(settings['segments']) - 1} segments, h = {settings['h']}, {settings['joining']}) is "
                f"{s['max_redefinition_error']:.4g} m from the desired output ({100 * s['relative_redefinition_error']:.3g} % of "
                f"the {s['move']:.4g} m move; accepted {gate:.3g} m)"
            )
        return best, f"the smallest error of {grid}"

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """``"5 segments, h = 2, paper"``.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return f"{len(settings['segments']) - 1} segments, h = {settings['h']}, {settings['joining']}"

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """The C header's line.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return f"polynomial redefinition: {len(settings['segments']) - 1} segments, h = {settings['h']}, joining {settings['joining']}"

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of ``sflm invert``'s text.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s, st = summary, summary["settings"]
        w = summary_words(s)
        m, unit, sym = w["m"], w["unit"], w["sym"]
        return [
            f"{s['model']}: polynomial redefinition (the baseline; one solution), {len(st['segments']) - 1} segments, "
            f"h = {st['h']}, {st['joining']}, degree {s['r'] - 1}",
            report_row("trajectory", s["trajectory"]),
            report_row("max |y~ - y_d|", f"{s['max_redefinition_error']:.4g}{m} = {100 * s['relative_redefinition_error']:.3g} % of "
                       f"the {s['move']:.4g}{m} move (accepted {s['max_error']:.3g}{m})"),
            report_row(f"peak |{sym}|", f"{s['peak_torque']:.5g}{unit} (at t = {s['time_of_peak_torque']:.4g} s); {sym}(tf) = "
                       f"{s['torque_at_end']:.3g}{unit}"),
            report_row("segment systems", f"largest residual {s['max_constraint_residual']:.2g}, largest condition number "
                       f"{s['max_condition_number']:.3g}"),
        ]

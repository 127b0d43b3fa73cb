"""The one result of every inversion method: its samples, its typed summary, and the Eq. (12) step.

Each method -- the paper's sums of stable exponentials (:mod:`inversion.family.piecewise`), the
polynomial redefinition (:mod:`inversion.methods.polynomial`), stable inversion
(:mod:`inversion.methods.stable`) -- returns an :class:`InversionResult` whose ``summary`` is built by
:func:`summarize` alone, from the method's typed :class:`SummaryFigures`: the keys scripts rely
on (``sflm invert --json``) are written in one place. :func:`inverse_input` is the step every
method takes from the redefined output to the state and the torque (Eqs. (12), (14)).

This module sits below the methods; none of them imports another.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.files import write_columns, write_json
from modelgen.model import Model
from modelgen.paper import PaperCase

from .errors import InversionError
from .lti.internal import ModalInternalDynamics
from .lti.linear_system import LinearSystem
from .lti.system import NormalForm
from .settings import DEFAULT_SETTINGS, InversionSettings
from .signals.chebyshev import PiecewiseChebyshev
from .signals.trajectory import Trajectory

__all__ = ["InversionResult", "InversionSummary", "SystemInversionSummary", "SegmentSummary", "SummaryFigures", "CSV_COLUMNS",
           "SYSTEM_CSV_COLUMNS", "summarize", "segment_summaries", "inverse_input", "caller_state", "summary_words", "report_row"]

FloatArray = NDArray[np.float64]

#: Columns of ``inversion.csv`` (a contract relied on by scripts).
CSV_COLUMNS = ("t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "tau", "theta_d", "thetadot_d")
#: Columns of ``inversion.csv`` for a generic system (:mod:`inversion.lti.linear_system`): its input ``u``.
SYSTEM_CSV_COLUMNS = ("t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "u")


class SegmentSummary(TypedDict):
    """One segment of a summary (Eq. (29)).

    One segment in :class:`InversionSummary` (Eq. (29): ``yddot~ = sum c_j exp(mu_j s)``).
    """

    t_start: float
    t_end: float
    exponents: list[float]
    coefficients: list[float]
    residual: float
    condition_number: float


class _CommonKeys(TypedDict):
    """The keys every inversion summary has, of a link or of a generic system."""

    model: str
    method: str
    trajectory: str
    trajectory_spec: str | None
    max_redefinition_error: float
    relative_redefinition_error: float
    time_of_max_redefinition_error: float
    move: float
    max_error: float
    peak_torque: float
    time_of_peak_torque: float
    max_torque_jump: float
    max_output_jump: float
    max_constraint_residual: float
    max_condition_number: float
    amplification: float | None
    max_spectral_radius: float | None
    final_redefined_output: float
    final_desired_output: float
    final_redefined_velocity: float
    torque_at_start: float
    torque_at_end: float
    zeros: list[list[float]]
    n_unstable: int
    r: int
    matched_exponentials: int
    samples: int
    settings: dict[str, Any]
    verification: dict[str, Any]
    segments: list[SegmentSummary]
    rigid_torque: float
    torque_ratio: float
    rigid_torque_rate: float | None
    torque_rate_ratio: float | None
    sampled: dict[str, Any]
    causal_limit: dict[str, Any]
    bounds: dict[str, Any]
    margin: dict[str, Any]


class _SummaryKeys(_CommonKeys):
    """The keys every inversion summary of a link has (see :class:`InversionSummary`)."""

    modes: int
    mode_shapes: str
    output_at: float
    final_deflections: list[float]
    final_deflection_rates: list[float]


class InversionSummary(_SummaryKeys, total=False):
    """``summary.json`` of an inversion: the keys scripts rely on.

    ``summary.json`` of an inversion: the keys scripts rely on (``sflm invert --json``).

    Lengths in m, torques in N m, times in s. ``method`` names what was returned (``"ssef"``,
    ``"ocp"``, ``"stable"``, ...). ``auto`` is present when the member or the method was chosen
    automatically (``auto["stages"]``: what the automatic choice across methods tried, each
    stage's status, message and seconds); ``zero_dynamics`` when some unstable zeros were left free (``zeros=``); ``pre_actuation_time`` and ``post_actuation_time`` for a
    feedforward that acts outside ``[t0, tf]`` (stable inversion's tails, a settle end's
    post-actuation). ``output_at`` (m): where the link's output is measured
    (``modelgen.load(..., output_at=)``; the tip by default). What reaches the link
    (:mod:`inversion.acceptance`): ``rigid_torque`` (N m, what a rigid body needs along
    ``y_d``), ``torque_ratio`` (the peak over it), ``rigid_torque_rate`` (N m, the rigid body's
    largest change over one period) and ``torque_rate_ratio`` (the held table's largest change
    from row to row over it), ``sampled`` (the plant as a controller at ``period`` drives it,
    held, through the move and the after-end window, and on the model with more modes) and, in
    ``verification``, ``after_end`` and ``truncation`` (the continuous torque's). ``causal_limit``
    (:mod:`inversion.lti.causal_limit`): the least error any causal feedforward from rest can hold the
    move to. ``bounds``: the bounds the result was judged by, with their rules. ``margin``
    (:mod:`inversion.methods.margin`): how far inside the bound the table holds the tip -- at its rows, after the
    move, with more modes -- and the plant errors it tolerates (its robustness radius). ``trajectory_spec``: what :func:`inversion.trajectory_from_spec` reads the trajectory
    back from (``None`` for one given otherwise). ``loop``: the table judged with the feedforward alone and with the joint PD
    closed (a link's default, and ``controller="pd"``; absent with ``controller="none"``).
    """

    auto: dict[str, Any]
    zero_dynamics: dict[str, Any]
    pre_actuation_time: float
    post_actuation_time: float
    loop: dict[str, Any]


class SystemInversionSummary(_CommonKeys, total=False):
    """``summary.json`` of the inversion of a generic system.

    The keys of :class:`InversionSummary` that are not about a link, with ``torque`` read as
    the input ``u`` (in the system's units), and ``system``: its name, states, relative
    degree, high-frequency gain, the normal form's residual and transformation
    (:meth:`~inversion.lti.linear_system.LinearSystem.report`).
    """

    system: dict[str, Any]
    auto: dict[str, Any]


@dataclass(frozen=True)
class InversionResult:
    """The redefined trajectory and the causal inverse torque.

    Attributes
    ----------
    t : ndarray
        Sample times (s), ``t0 .. tf`` at ``rate``.
    y_d : ndarray
        Desired tip displacement (m).
    y, ydot, yddot : ndarray
        Redefined tip displacement, velocity, acceleration ``y~`` (Eq. (29) integrated).
    X : ndarray, shape (N, 2(n+1))
        Redefined state ``[theta, delta, thetadot, deltadot]`` (a generic system's state in
        the caller's realisation).
    tau : ndarray
        Feedforward torque ``tau_l`` (N m), Eq. (12); for a generic system its input
        (also :attr:`u`). Like ``theta_d`` and ``thetadot_d``, sampled from :attr:`signals`:
        the member's closed form to about ``1e-13`` of the peak, where the closed form summed
        in double precision can be uncertain by ``1e-9`` (nearly dependent exponentials).
    theta_d, thetadot_d : ndarray or None
        Joint angle and rate of ``X`` (from :attr:`signals`), the references of the PD law
        (Eq. (40)); ``None`` for a generic system.
    summary : InversionSummary
        Key figures (see :func:`invert`).
    model : Model or LinearSystem
        The model inverted (a link, or a generic system of :mod:`inversion.lti.linear_system`).
    trajectory : Trajectory
        The desired trajectory.
    modal : ModalInternalDynamics
        The diagonalised internal dynamics used.
    settings : InversionSettings
        The member of the family.
    signals : PiecewiseChebyshev
        ``tau``, ``theta_d``, ``thetadot_d`` (``u`` for a generic system) as piecewise
        Chebyshev series of the closed form (:mod:`inversion.signals.chebyshev`): what the samples
        above and the exported C evaluate.
    case : PaperCase or None
        The paper's case when the model is its preset as shipped and the trajectory the
        case's own (:func:`inversion.problem.paper_case`, decided once by the method): the
        closed loop then takes the paper's gains.
    acceptance : Acceptance or None
        What reaches the link, as the method judged it (:class:`inversion.acceptance.Acceptance`): the door judges it
        against the problem's bounds (``None`` for a run read back: it was judged when it was written).
    detail : object or None
        What the method keeps of its own: for the family's member an
        :class:`inversion.family.piecewise.MemberDetail` (its segments, figures, checks, closed form and settle tail,
        read through :attr:`segments`, :attr:`figures`, :attr:`checks`, :attr:`redefinition`, :attr:`tail`);
        ``None`` for the other methods.
    """

    t: FloatArray
    y_d: FloatArray
    y: FloatArray
    ydot: FloatArray
    yddot: FloatArray
    X: FloatArray
    tau: FloatArray
    theta_d: FloatArray | None
    thetadot_d: FloatArray | None
    summary: InversionSummary | SystemInversionSummary
    model: Model | LinearSystem = field(repr=False)
    trajectory: Trajectory = field(repr=False)
    modal: ModalInternalDynamics = field(repr=False)
    settings: InversionSettings = field(default=DEFAULT_SETTINGS)
    signals: PiecewiseChebyshev | None = field(default=None, repr=False)
    case: PaperCase | None = field(default=None, repr=False)
    detail: Any = field(default=None, repr=False)
    acceptance: Any = field(default=None, repr=False)

    @property
    def segments(self) -> list[Any]:
        """The family's segments (exponents, coefficients, residual, condition number); empty for another method."""
        return list(getattr(self.detail, "segments", []))

    @property
    def figures(self) -> Any:
        """The family's closed-form figures (largest redefinition error, peak torque), or ``None``."""
        return getattr(self.detail, "figures", None)

    @property
    def checks(self) -> Any:
        """The family's verification (solver, extended precision, plant), or ``None``."""
        return getattr(self.detail, "checks", None)

    @property
    def redefinition(self) -> Any:
        """The family's solved member (its closed form anywhere), or ``None``."""
        return getattr(self.detail, "redefinition", None)

    @property
    def tail(self) -> Any:
        """A settle end's post-actuation after ``t_f`` (:mod:`inversion.family.settle`), or ``None``."""
        return getattr(self.detail, "tail", None)

    @property
    def window(self) -> float | None:
        """The after-end window the acceptance judged the result through (s), or ``None`` for a result not judged.

        The held table's (``summary["sampled"]``), else the continuous input's (``summary["verification"]``). ``simulate``
        runs this long after the feedforward ends unless told otherwise: what ``invert`` judged is what it shows.
        """
        for block in (self.summary.get("sampled"), (self.summary.get("verification") or {}).get("after_end")):
            value = block.get("window") if isinstance(block, Mapping) else None
            if isinstance(value, (int, float)) and np.isfinite(value) and value > 0:
                return float(value)
        return None

    @property
    def u(self) -> FloatArray:
        """The input: the torque ``tau`` of a link, ``u`` of a generic system."""
        return self.tau

    @property
    def joints(self) -> FloatArray:
        """Segment boundaries ``t_0 .. t_K`` (s); ``[t_0, t_f]`` for a method without segments (stable inversion, the
        optimal-control feedforward, input shaping)."""
        if not self.segments:
            return np.array([self.trajectory.t0, self.trajectory.tf], dtype=float)
        return np.array([s.t_start for s in self.segments] + [self.segments[-1].t_end])

    def evaluate(self, t: ArrayLike) -> dict[str, FloatArray]:
        """The redefined quantities at arbitrary times.

        The redefined quantities at arbitrary times in ``[t0, tf]`` and a settle tail's after it (the family's closed
        form, compiled Eq. (12)).

        Parameters
        ----------
        t : array_like
            Times (s).

        Returns
        -------
        dict
            ``y, ydot, yddot, X, tau`` (``X`` of shape ``(N, 2(n+1))``).

        Raises
        ------
        InversionError
            For a method without a closed form (its samples are :attr:`signals`).
        """
        if not hasattr(self.detail, "evaluate"):
            raise InversionError(f"a {self.summary.get('method', '?')} result has no closed form to evaluate; its signals are result.signals")
        values = self.detail.evaluate(t)
        X, tau = inverse_input(self.model, self.detail.redefinition.form, values)
        return {"y": values["y"], "ydot": values["ydot"], "yddot": values["yddot"], "X": X, "tau": tau}

    def write_csv(self, path: str | Path, progress: Callable[[int, int], None] | None = None) -> None:
        """Write ``inversion.csv``.

        Write ``inversion.csv`` with the columns :data:`CSV_COLUMNS` (:data:`SYSTEM_CSV_COLUMNS` for a
        generic system).

        Parameters
        ----------
        path : str or Path
            The file.
        progress : callable, optional
            ``progress(rows_written, rows)`` after each block."""
        if self.theta_d is None or self.thetadot_d is None:
            write_columns(path, SYSTEM_CSV_COLUMNS, [self.t, self.y_d, self.y, self.ydot, self.yddot, self.tau], progress)
            return
        write_columns(path, CSV_COLUMNS, [self.t, self.y_d, self.y, self.ydot, self.yddot, self.tau, self.theta_d, self.thetadot_d],
                      progress)

    def write_summary(self, path: str | Path) -> None:
        """Write ``summary.json``.

        Parameters
        ----------
        path : str or Path
            The file.
        """
        write_json(path, self.summary)


def inverse_input(model: Model | LinearSystem, form: NormalForm, values: dict[str, Any]) -> tuple[FloatArray, FloatArray]:
    """The state and the input of Eq. (12) from the output's values.

    Parameters
    ----------
    model : Model or LinearSystem
        The link (its compiled ``sflm_inverse_torque``) or a generic system (its numerical
        normal form; its balanced state is scaled back to the caller's coordinates).
    form : NormalForm
        The normal form the values are in.
    values : mapping
        ``y``, its derivatives up to ``y^(rho)`` and ``XI`` at the samples.

    Returns
    -------
    X : ndarray, shape (N, 2(n+1))
        The state in the caller's coordinates, ``X = T^-1 [y; ydot; X_I]`` (Eq. (14)).
    u : ndarray, shape (N,)
        ``tau = (yddot - C A^2 X) / (C A B)`` (Eq. (12)); a system's
        ``(y^(rho) - C A^rho X) / C A^(rho-1) B``.
    """
    X = form.state_of(values)
    if isinstance(model, LinearSystem):
        return caller_state(model, X), np.asarray(form.input_of(values, X))
    return X, model.compiled_functions.inverse_torque(model.parameters, X, values["yddot"])


def caller_state(model: Model | LinearSystem, X: Any) -> FloatArray:
    """``X`` of the normal form in the caller's coordinates.

    ``X`` of the normal form in the caller's coordinates (a generic system's balanced state scaled back).

    Parameters
    ----------
    model : Model | LinearSystem
        The plant.
    X : Any
        States of the normal form.
    """
    return np.asarray(X) * model.scale if isinstance(model, LinearSystem) else np.asarray(X)


@dataclass(frozen=True)
class SummaryFigures:
    """The figures a result's method measured, typed.

    Attributes
    ----------
    max_error : float
        ``max |y~ - y_d|`` (m; 0 for stable inversion, which tracks ``y_d`` itself).
    time_of_max_error : float
        Where it occurs (s).
    move : float
        The move the relative figures are of (m).
    gate : float
        The quality gate applied (m).
    peak_torque, time_of_peak_torque : float
        ``max |tau|`` (N m; a system's ``max |u|``) and where (s).
    n_unstable : int
        Unstable zeros the method handles.
    max_torque_jump, max_output_jump : float
        Largest jumps of the torque and of ``y~`` at the joints.
    max_constraint_residual, max_condition_number : float
        Of the method's linear systems.
    amplification, max_spectral_radius : float or None
        Growth of the unstable state carried across segments (``None`` when none is).
    r : int
        Exponentials (or polynomial coefficients) per segment.
    matched_exponentials : int
        Matched exponentials of the ``anchored`` joining.
    """

    max_error: float
    time_of_max_error: float
    move: float
    gate: float
    peak_torque: float
    time_of_peak_torque: float
    n_unstable: int
    max_torque_jump: float = 0.0
    max_output_jump: float = 0.0
    max_constraint_residual: float = 0.0
    max_condition_number: float = 1.0
    amplification: float | None = None
    max_spectral_radius: float | None = None
    r: int = 0
    matched_exponentials: int = 0

    @property
    def relative_error(self) -> float:
        """``max_error`` as a fraction of the move."""
        return self.max_error / self.move if self.move else 0.0

    @classmethod
    def of(cls, figures: Any, gate: float, n_unstable: int, **more: Any) -> "SummaryFigures":
        """The figures of a member measured in closed form (an :class:`inversion.family.figures.Figures`)."""
        return cls(max_error=figures.max_error, time_of_max_error=figures.time_of_max_error, move=figures.move, gate=gate,
                   peak_torque=figures.peak_torque, time_of_peak_torque=figures.time_of_peak_torque, n_unstable=n_unstable, **more)


def segment_summaries(segments: list[tuple[float, float, list[float], list[float], float, float]]) -> list[SegmentSummary]:
    """The ``segments`` of a summary.

    The ``segments`` of a summary from ``(t_start, t_end, exponents, coefficients, residual, condition)``.

    Parameters
    ----------
    segments : list[tuple[float, float, list[float], list[float], float, float]]
        One tuple a segment.
    """
    return [{"t_start": a, "t_end": b, "exponents": mu, "coefficients": c, "residual": res, "condition_number": cond}
            for a, b, mu, c, res, cond in segments]


def summarize(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    figures: SummaryFigures,
    samples: Mapping[str, Any],
    settings: Mapping[str, Any],
    *,
    verification: Mapping[str, Any] | None = None,
    segments: list[SegmentSummary] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> InversionSummary | SystemInversionSummary:
    """The summary of any inversion.

    The summary of any inversion: every key of :class:`InversionSummary` (or :class:`SystemInversionSummary`), written here alone.

    Parameters
    ----------
    model : Model or LinearSystem
        What was inverted.
    trajectory : Trajectory
        The desired trajectory.
    figures : SummaryFigures
        The method's figures.
    samples : mapping
        The result's samples ``t, y, ydot, tau, X``: the end values come from them.
    settings : mapping
        The method's settings (JSON-ready).
    verification : mapping, optional
        The checks' figures.
    segments : list of SegmentSummary, optional
        The segments' exponents, coefficients, residuals and condition numbers.
    extra : mapping, optional
        Keys of the method (``method``, ``pre_actuation_time``, ``auto``, ...), added last.
    """
    t, y, ydot, tau, X = (np.asarray(samples[k]) for k in ("t", "y", "ydot", "tau", "X"))
    summary: Any = {
        "model": model.name,
        "trajectory": trajectory.name,
        "trajectory_spec": trajectory.spec,
        "max_redefinition_error": float(figures.max_error),
        "relative_redefinition_error": float(figures.relative_error),
        "time_of_max_redefinition_error": float(figures.time_of_max_error),
        "move": float(figures.move),
        "max_error": float(figures.gate),
        "peak_torque": float(figures.peak_torque),
        "time_of_peak_torque": float(figures.time_of_peak_torque),
        "max_torque_jump": float(figures.max_torque_jump),
        "max_output_jump": float(figures.max_output_jump),
        "max_constraint_residual": float(figures.max_constraint_residual),
        "max_condition_number": float(figures.max_condition_number),
        "amplification": figures.amplification,
        "max_spectral_radius": figures.max_spectral_radius,
        "final_redefined_output": float(y[-1]),
        "final_desired_output": trajectory.y_final,
        "final_redefined_velocity": float(ydot[-1]),
        "torque_at_start": float(tau[0]),
        "torque_at_end": float(tau[-1]),
        "zeros": [[float(v.real), float(v.imag)] for v in model.zeros],
        "n_unstable": int(figures.n_unstable),
        "r": int(figures.r),
        "matched_exponentials": int(figures.matched_exponentials),
        "samples": int(t.size),
        "settings": dict(settings),
        "verification": dict(verification or {}),
        "segments": list(segments or []),
    }
    if isinstance(model, LinearSystem):
        summary["system"] = model.report()
    else:
        n1 = model.n + 1
        summary.update({"modes": model.n, "mode_shapes": model.mode_family, "output_at": model.output_at,
                        "final_deflections": [float(v) for v in X[-1, 1:n1]],
                        "final_deflection_rates": [float(v) for v in X[-1, n1 + 1 :]]})
    summary.update(extra or {})
    return summary


def summary_words(summary: Mapping[str, Any]) -> dict[str, str]:
    """The words a report of ``summary`` uses.

    A link's (its tip, its torque in N m, what a rigid link needs) or a generic system's (its output, its input, no units,
    what its static inverse needs).

    Parameters
    ----------
    summary : mapping
        A result's summary (a generic system's has a ``system`` block).
    """
    if "system" in summary:
        return {"out": "output", "inp": "input", "sym": "u", "unit": "", "m": "", "speed": "/s", "need": "the static inverse",
                "needs": "the static need", "link": "the system"}
    return {"out": "tip", "inp": "torque", "sym": "tau_l", "unit": " N m", "m": " m", "speed": " m/s", "need": "a rigid link",
            "needs": "the rigid need", "link": "the link"}


def report_row(label: str, text: str) -> str:
    """A line of a result's text report.

    A line of a result's text report: its label in a column of 20 characters, then the text.

    Parameters
    ----------
    label : str
        What the line is about.
    text : str
        The figures.
    """
    return f"  {label:<19s} {text}"

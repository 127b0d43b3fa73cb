"""Piece-wise causal inversion by output redefinition (section 5 of the paper, and beyond it).

:func:`invert` picks a member of the family (the caller's settings, the paper's for its own
cases, or the automatic choice of :mod:`inversion.auto`), solves and verifies it
(:mod:`inversion.member`), and samples the bounded, continuous, causal feedforward torque
``tau_l = (yddot~ - C A^2 X) / CAB`` (Eq. (12)) with everything needed to use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.model import Model

from .errors import SettingsError
from .chebyshev import DEGREE, PiecewiseChebyshev, member_signals
from .figures import Figures
from .internal import ModalInternalDynamics
from .linear_system import LinearSystem, as_linear_system
from .member import MemberResult, evaluate_member
from .output import write_columns, write_json
from .redefinition import Redefinition
from .settings import DEFAULT_SETTINGS, InversionSettings, paper_case, paper_settings
from .ssef import SegmentSolution, Solver
from .system import NormalForm
from .threads import one_thread
from .trajectory import Trajectory
from .verify import Checks
from .zero_dynamics import ZERO_SETS, free_zeros, zero_dynamics_summary

__all__ = ["invert", "InversionResult", "InversionSummary", "SystemInversionSummary", "SegmentSummary", "CSV_COLUMNS",
           "SYSTEM_CSV_COLUMNS", "MAX_SAMPLES", "resolve_settings"]

FloatArray = NDArray[np.float64]

#: Inversion methods: the paper's causal one (sums of stable exponentials), the non-causal baseline.
METHODS = ("ssef", "polynomial", "stable")
#: Columns of ``inversion.csv`` (a contract relied on by scripts).
CSV_COLUMNS = ("t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "tau", "theta_d", "thetadot_d")
#: Columns of ``inversion.csv`` for a generic system (:mod:`inversion.linear_system`): its input ``u``.
SYSTEM_CSV_COLUMNS = ("t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "u")
#: Largest number of samples one inversion may produce: about 1 GB of arrays in memory and
#: 1.5 GB of ``inversion.csv`` (150 bytes a row), written in about a minute.
MAX_SAMPLES = 10_000_000


class SegmentSummary(TypedDict):
    """One segment in :class:`InversionSummary` (Eq. (29): ``yddot~ = sum c_j exp(mu_j s)``)."""

    t_start: float
    t_end: float
    exponents: list[float]
    coefficients: list[float]
    residual: float
    condition_number: float


class _CommonKeys(TypedDict):
    """The keys every inversion summary has, of a link or of a generic system."""

    model: str
    trajectory: str
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


class _SummaryKeys(_CommonKeys):
    """The keys every inversion summary of a link has (see :class:`InversionSummary`)."""

    modes: int
    mode_shapes: str
    output_at: float
    final_deflections: list[float]
    final_deflection_rates: list[float]


class InversionSummary(_SummaryKeys, total=False):
    """``summary.json`` of an inversion: the keys scripts rely on (``sflm invert --json``).

    Lengths in m, torques in N m, times in s. ``auto`` is present when the member was chosen
    automatically; ``zero_dynamics`` when some unstable zeros were left free (``zeros=``);
    ``method``, ``pre_actuation_time`` and ``post_actuation_time`` for the non-causal stable
    inversion (:mod:`inversion.stable`). ``output_at`` (m): where the link's output is
    measured (``modelgen.load(..., output_at=)``; the tip by default).
    """

    auto: dict[str, Any]
    zero_dynamics: dict[str, Any]
    method: str
    pre_actuation_time: float
    post_actuation_time: float


class SystemInversionSummary(_CommonKeys, total=False):
    """``summary.json`` of the inversion of a generic system (:mod:`inversion.linear_system`).

    The keys of :class:`InversionSummary` that are not about a link, with ``torque`` read as
    the input ``u`` (in the system's units), and ``system``: its name, states, relative
    degree, high-frequency gain, the normal form's residual and transformation
    (:meth:`~inversion.linear_system.LinearSystem.report`).
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
    segments : list of SegmentSolution
        Exponents, coefficients, residual and condition number of each segment.
    summary : InversionSummary
        Key figures (see :func:`invert`).
    model : Model or LinearSystem
        The model inverted (a link, or a generic system of :mod:`inversion.linear_system`).
    trajectory : Trajectory
        The desired trajectory.
    modal : ModalInternalDynamics
        The diagonalised internal dynamics used.
    settings : InversionSettings
        The member of the family.
    figures : Figures
        Largest redefinition error and peak torque, from the closed form.
    checks : Checks
        The verification (solver, extended precision, plant).
    redefinition : Redefinition
        The solved member (closed-form evaluation anywhere).
    signals : PiecewiseChebyshev
        ``tau``, ``theta_d``, ``thetadot_d`` (``u`` for a generic system) as piecewise
        Chebyshev series of the closed form (:mod:`inversion.chebyshev`): what the samples
        above and the exported C evaluate.
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
    segments: list[SegmentSolution]
    summary: InversionSummary | SystemInversionSummary
    model: Model | LinearSystem = field(repr=False)
    trajectory: Trajectory = field(repr=False)
    modal: ModalInternalDynamics = field(repr=False)
    settings: InversionSettings = field(default=DEFAULT_SETTINGS)
    figures: Figures | None = field(default=None, repr=False)
    checks: Checks | None = field(default=None, repr=False)
    redefinition: Redefinition | None = field(default=None, repr=False)
    signals: PiecewiseChebyshev | None = field(default=None, repr=False)

    @property
    def u(self) -> FloatArray:
        """The input: the torque ``tau`` of a link, ``u`` of a generic system."""
        return self.tau

    @property
    def joints(self) -> FloatArray:
        """Segment boundaries ``t_0 .. t_K`` (s)."""
        return np.array([s.t_start for s in self.segments] + [self.segments[-1].t_end])

    def evaluate(self, t: ArrayLike) -> dict[str, FloatArray]:
        """The redefined quantities at arbitrary times in ``[t0, tf]`` (closed form, compiled Eq. (12)).

        Returns
        -------
        dict
            ``y, ydot, yddot, X, tau`` (``X`` of shape ``(N, 2(n+1))``).
        """
        assert self.redefinition is not None
        values = self.redefinition.evaluate(np.atleast_1d(np.asarray(t, dtype=float)))
        X, tau = _input(self.model, self.redefinition.form, values)
        return {"y": values["y"], "ydot": values["ydot"], "yddot": values["yddot"], "X": X, "tau": tau}

    def write_csv(self, path: str | Path, progress: Callable[[int, int], None] | None = None) -> None:
        """Write ``inversion.csv`` with the columns :data:`CSV_COLUMNS` (:data:`SYSTEM_CSV_COLUMNS` for a
        generic system; ``progress(rows_written, rows)`` per block)."""
        if self.theta_d is None or self.thetadot_d is None:
            write_columns(path, SYSTEM_CSV_COLUMNS, [self.t, self.y_d, self.y, self.ydot, self.yddot, self.tau], progress)
            return
        write_columns(path, CSV_COLUMNS, [self.t, self.y_d, self.y, self.ydot, self.yddot, self.tau, self.theta_d, self.thetadot_d],
                      progress)

    def write_summary(self, path: str | Path) -> None:
        """Write ``summary.json``."""
        write_json(path, self.summary)

    def export_c(self, folder: str | Path, prefix: str = "sflm_feedforward") -> list[Path]:
        """Write ``feedforward.c`` and ``feedforward.h``: the member's signals in C99 (:func:`inversion.export.export_c`)."""
        from .export import export_c

        return export_c(self, folder, prefix)

    def export_table(self, path: str | Path, prefix: str = "sflm_feedforward") -> Path:
        """Write the samples of ``t, tau, theta_d, thetadot_d`` (``t, u``) as C arrays (:func:`inversion.export.export_table`)."""
        from .export import export_table

        return export_table(self, path, prefix)


def _input(model: Model | LinearSystem, form: NormalForm, values: dict[str, Any]) -> tuple[FloatArray, FloatArray]:
    """The state in the caller's coordinates and the input, Eq. (12), from the output's values
    (``y``, its derivatives up to ``y^(rho)``, ``XI``): compiled for a link, from the numerical
    normal form for a generic system (whose balanced state is scaled back)."""
    X = form.state_of(values)
    if isinstance(model, LinearSystem):
        return _caller_state(model, X), np.asarray(form.input_of(values, X))
    return X, model.compiled_functions.inverse_torque(model.parameters, X, values["yddot"])


def _caller_state(model: Model | LinearSystem, X: Any) -> FloatArray:
    """``X`` of the normal form in the caller's coordinates (a generic system's balanced state scaled back)."""
    return np.asarray(X) * model.scale if isinstance(model, LinearSystem) else np.asarray(X)


def _validate_common(rate: Any, solver: Any, tol: Any, max_error: Any, max_torque: Any) -> None:
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
        raise SettingsError("rate", rate, "a finite number > 0 (Hz)")
    if solver not in ("lu", "lstsq"):
        raise SettingsError("solver", solver, "'lu' or 'lstsq'")
    if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 < tol < 1:
        raise SettingsError("tol", tol, "a number in (0, 1)")
    if max_error is not None and (isinstance(max_error, bool) or not isinstance(max_error, (int, float)) or not max_error > 0):
        raise SettingsError("max_error", max_error, "a number > 0 (m), inf to accept any redefinition")
    if max_torque is not None and (
        isinstance(max_torque, bool) or not isinstance(max_torque, (int, float)) or not max_torque > 0 or math.isnan(max_torque)
    ):
        raise SettingsError("max_torque", max_torque, "a number > 0 (N m)")


def resolve_settings(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    explicit: Mapping[str, Any],
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
) -> InversionSettings:
    """The member a manual inversion uses: the paper's for its own cases, else the defaults, then the caller's.

    Parameters
    ----------
    model, trajectory :
        The case.
    explicit : mapping
        Values the caller gave (``segments``, ``h``, ``cdec``, ``joining``, ``eps``).
    settings : InversionSettings, mapping or path, optional
        A stored member (``best.json``); ``explicit`` values override it.
    """
    case = paper_case(model, trajectory)
    base = paper_settings(case) if case is not None else DEFAULT_SETTINGS
    if isinstance(settings, InversionSettings):
        base = settings
    elif isinstance(settings, Mapping):
        base = InversionSettings.from_dict(settings, base)
    elif settings is not None:
        base = InversionSettings.from_json(settings, base)
    changes = {k: (tuple(v) if k == "segments" and not isinstance(v, (int, np.integer)) else v) for k, v in explicit.items()}
    return base.with_changes(**changes) if changes else base


def invert(
    model: Model | LinearSystem | Any,
    trajectory: Trajectory,
    segments: int | Sequence[float] | None = None,
    h: int | None = None,
    cdec: tuple[float, float] | None = None,
    joining: str | None = None,
    *,
    end: str | None = None,
    settings: InversionSettings | Mapping[str, Any] | str | Path | None = None,
    auto: bool | None = None,
    max_error: float | None = None,
    max_torque: float | None = None,
    rate: float = 1000.0,
    eps: float | None = None,
    initial_internal_state: ArrayLike | None = None,
    solver: Solver = "lu",
    tol: float = 1e-8,
    progress: Callable[[str], None] | None = None,
    method: str = "ssef",
    zeros: str = "all",
) -> InversionResult:
    """Causal inverse torque of the linear model for a desired tip trajectory.

    Parameters
    ----------
    model : Model, or any SISO linear system
        A loaded model (:func:`modelgen.load`); its compiled ``inverse_torque`` gives Eq. (12).
        Or a generic system: a python-control ``StateSpace`` or ``TransferFunction``, a
        ``scipy.signal`` LTI system, a tuple ``(A, B, C)`` or a
        :class:`~inversion.linear_system.LinearSystem`, continuous-time, strictly proper; its
        normal form is computed numerically (:mod:`inversion.linear_system`) and the result's
        ``u`` is its input. Any relative degree ``rho >= 1`` (detected); every method, from
        rest, all its zeros constrained.
    trajectory : Trajectory
        Desired tip trajectory on ``[t0, tf]``.
    segments : int or sequence of float, optional
        Number of equal segments, or their boundaries ``[t0, ..., tf]`` (Eq. (28)).
    h : int, optional
        Order of smooth joining, Eq. (30): ``yddot~`` and its first ``h`` derivatives join
        ``y_d``'s. For a generic system of relative degree ``rho`` it is ``y~^(rho)`` and its
        first ``h`` derivatives that are continuous (the input is ``h`` times continuously
        differentiable, as the link's torque).
    cdec : (float, float), optional
        ``(Cdec_f, Cdec_s)``, Eq. (35); ``0 < Cdec_f < Cdec_s <= 1``.
    joining : {"paper", "position", "anchored"}, optional
        The joining conditions (:mod:`inversion.ssef`): the paper's, plus position
        joining, plus the unstable state anchored at every joint.
    end : {"free", "rest"}, optional
        ``"free"`` (default, the paper's) or ``"rest"``: the last segment also ends on
        ``y_d(t_f)``, ``ydot_d(t_f)`` with zero deflections and rates, so that the torque
        ends at zero and the linear plant at rest (the paper's Remark 2).
    settings : InversionSettings, mapping or path, optional
        A member chosen before (``best.json`` of :func:`inversion.explore`); the arguments
        above override its values.
    auto : bool, optional
        Choose the member automatically (:func:`inversion.auto.choose`): the smallest
        redefinition error whose peak torque respects ``max_torque``, verified. Default:
        automatic when nothing above is given and the case is not one of the paper's
        (whose member ends free: with ``end="rest"`` a paper case is chosen automatically too)
        (a preset as shipped with its own trajectory keeps the paper's settings). Values
        given with ``auto=True`` fix those dimensions of the search.
    max_error : float, optional
        The quality gate (m): a redefinition further from ``y_d`` raises
        :class:`InversionError`. Default 5 % of the move; ``math.inf`` accepts anything.
    max_torque : float, optional
        Largest accepted peak torque (N m); a member above it is refused.
    rate : float
        Sampling rate of the returned series (Hz).
    eps : float, optional
        Zeros with ``Re >= -eps`` are treated as unstable (default 0; purely imaginary
        ones always are).
    initial_internal_state : array_like, optional
        ``X_I(t0) = [delta; deltadot]`` (default: rest).
    solver : {"lu", "lstsq"}
        Linear solver of the segment systems (the other one checks it).
    tol : float
        Largest accepted relative constraint residual of a segment system.
    progress : callable, optional
        Receives one-line messages of the automatic choice.
    method : {"ssef", "polynomial", "stable"}
        ``"ssef"`` (default): the paper's causal inversion, a sum of stable exponential
        functions per segment. ``"polynomial"``: the same conditions met by a polynomial
        per segment (:func:`inversion.polynomial.polynomial_inversion`; ``segments``, ``h``
        and ``joining`` paper or position apply). ``"stable"``: the non-causal stable
        inversion baseline (:func:`inversion.stable.stable_inversion`: exact tracking,
        torque before ``t0``; no member settings apply).
    zeros : {"all", "physical", "converged"}
        The unstable zeros the inversion constrains (:mod:`inversion.zero_dynamics`): all
        (the default), all but the truncation artefacts, or only those converged to the
        continuum's; the others are left free (their particular solution, no continuity
        rows). The verification still drives the full model's plant, from its true initial
        state; the summary's ``zero_dynamics`` names the free zeros. SSEF only.

    Returns
    -------
    InversionResult
        Its ``summary`` holds ``max_redefinition_error`` (m), ``relative_redefinition_error``
        (of the move), ``peak_torque`` (N m) -- both from the closed form, whatever
        ``rate`` -- ``max_torque_jump``, ``max_constraint_residual``,
        ``max_condition_number``, ``verification`` (the checks of
        :mod:`inversion.verify`), ``zeros``, ``n_unstable``, ``r``, ``settings``, the
        segments' exponents and coefficients, and ``auto`` (the search) when chosen
        automatically.

    Raises
    ------
    SettingsError
        For settings out of range (named in the message with the accepted range).
    InversionError
        When the member fails: a segment system not solved to ``tol``, a torque that
        depends on the solver or on the precision, a plant that does not follow ``y~``,
        a redefinition beyond ``max_error`` or a torque beyond ``max_torque`` -- with its
        figures. Never a torque that is not what it claims.

    References
    ----------
    The paper, Eqs. (12), (14)-(17), (28)-(36); docs/method.md.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import invert, smoothstep
    >>> result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), segments=5, h=2, cdec=(1e-4, 1.0))
    >>> round(result.summary["max_redefinition_error"], 5)
    0.00573
    """
    _validate_common(rate, solver, tol, max_error, max_torque)
    if method not in METHODS:
        raise SettingsError("method", method, " or ".join(repr(m) for m in METHODS))
    if zeros not in ZERO_SETS:
        raise SettingsError("zeros", zeros, " or ".join(repr(z) for z in ZERO_SETS))
    if not isinstance(model, Model):
        model = _generic(model, zeros, initial_internal_state)
    if zeros != "all" and method != "ssef":
        raise SettingsError("zeros", zeros, f"'all' with method={method!r} (zeros are left free by the SSEF inversion only)")
    if zeros != "all" and end == "rest":
        raise SettingsError("zeros", zeros, "'all' with end='rest' (a rest end holds every internal mode at zero at t_f; "
                                           "a free mode ends on its particular solution)")
    if method == "stable":
        given = {k: v for k, v in (("segments", segments), ("h", h), ("cdec", cdec), ("joining", joining), ("eps", eps), ("end", end),
                                   ("settings", settings), ("auto", auto or None), ("max_torque", max_torque),
                                   ("initial_internal_state", initial_internal_state)) if v is not None}
        if given:
            name = next(iter(given))
            raise SettingsError(name, given[name], "nothing: stable inversion has no member to choose (it tracks y_d exactly)")
        from .stable import stable_inversion

        with one_thread():
            return stable_inversion(model, trajectory, rate)
    if method == "polynomial":
        given = {k: v for k, v in (("cdec", cdec), ("eps", eps), ("end", end), ("settings", settings), ("auto", auto or None),
                                   ("max_torque", max_torque), ("initial_internal_state", initial_internal_state)) if v is not None}
        if given:
            name = next(iter(given))
            raise SettingsError(name, given[name], "nothing: the polynomial redefinition takes segments, h and joining only")
        from .polynomial import polynomial_inversion

        case = paper_case(model, trajectory)
        base = paper_settings(case) if case is not None else DEFAULT_SETTINGS
        with one_thread():
            return polynomial_inversion(model, trajectory, segments=base.segment_count if segments is None else segments,  # type: ignore[arg-type]
                                        h=base.h if h is None else h, joining=joining or "paper", rate=rate, max_error=max_error)
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise SettingsError("rate", rate, f"at most {MAX_SAMPLES / trajectory.duration:.4g} Hz for this trajectory ({MAX_SAMPLES} samples)")
    explicit = {k: v for k, v in (("segments", segments), ("h", h), ("cdec", cdec), ("joining", joining), ("eps", eps),
                                  ("end", end)) if v is not None}
    with one_thread():  # skinny products and small solves: a BLAS pool would only spin
        if isinstance(model, LinearSystem):
            form = NormalForm.of_system(model)
        else:
            form = free_zeros(model, NormalForm.of_model(model), zeros)
        if auto is None:
            # the paper's member ends free: with a rest end, a paper case is chosen like any other
            member_given = any(k != "end" for k in explicit) or settings is not None
            auto = not member_given and (paper_case(model, trajectory) is None or end == "rest")
        search: dict[str, Any] | None = None
        if auto:
            if settings is not None:
                raise SettingsError("settings", settings, "no stored settings with auto=True (--auto searches the family itself)")
            from .auto import choose

            member, search = choose(form, trajectory, fixed=explicit, max_error=max_error, max_torque=max_torque,
                                    initial_internal_state=initial_internal_state, solver=solver, tol=tol, progress=progress)
        else:
            chosen = resolve_settings(model, trajectory, explicit, settings)
            chosen.boundaries(trajectory, form.rho)  # a user error: SettingsError, not a failed member
            member = evaluate_member(form, trajectory, chosen, initial_internal_state=initial_internal_state, solver=solver,
                                     tol=tol, max_error=max_error, max_torque=max_torque, verify=True, plant=True)
            if not member.ok:
                raise member.error("the automatic choice (auto=True, --auto) searches the family for a member that meets the bounds")
        return _sample(model, trajectory, member, rate, solver, tol, initial_internal_state, search, zeros)


def _generic(system: Any, zeros: str, initial_internal_state: ArrayLike | None) -> LinearSystem:
    """A generic system as a :class:`LinearSystem` the core takes (refusing the options that are about a link)."""
    converted = as_linear_system(system)
    if zeros != "all":
        raise SettingsError("zeros", zeros, "'all' for a generic system (its zeros have no continuum to be judged against)")
    if initial_internal_state is not None:
        raise SettingsError("initial_internal_state", initial_internal_state, "None for a generic system: it starts from rest")
    return converted


def _sample(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    member: MemberResult,
    rate: float,
    solver: str,
    tol: float,
    initial_internal_state: ArrayLike | None,
    search: dict[str, Any] | None,
    zeros: str = "all",
) -> InversionResult:
    """Sample a verified member at ``rate`` and write its summary."""
    redef, figures, checks = member.redefinition, member.figures, member.checks
    assert redef is not None and figures is not None and checks is not None
    plan = redef.plan
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    t = trajectory.t0 + np.arange(count) / rate
    if trajectory.tf - t[-1] > 1e-9 / rate:
        t = np.append(t, trajectory.tf)
    sampled = redef.sample(t)
    y, ydot, yddot = sampled["y"], sampled["ydot"], sampled["yddot"]
    X, tau_closed = _input(model, redef.form, sampled)  # Eq. (12), one batch
    # the signals fed forward, from their well-conditioned re-expansion (inversion.chebyshev)
    link = not isinstance(model, LinearSystem)
    signals = member_signals(redef, link)
    fed = signals.evaluate(t)
    tau = fed[signals.names[0]]
    peak = float(np.abs(tau).max()) or 1.0
    sampling = {"method": "piecewise Chebyshev series of the closed form, computed in extended precision",
                "pieces": signals.pieces, "degree": DEGREE, "largest_series_tail": signals.tail,
                "closed_form_in_double_difference": float(np.abs(np.asarray(tau_closed) - tau).max() / peak)}
    y_d = trajectory.derivative(t, 0)
    jumps = redef.joint_jumps()
    settings = member.settings
    XI0 = np.zeros(redef.form.n_internal) if initial_internal_state is None else np.asarray(initial_internal_state, dtype=float).reshape(-1)
    summary: Any = {
        "model": model.name,
        "trajectory": trajectory.name,
        "max_redefinition_error": figures.max_error,
        "relative_redefinition_error": figures.relative_error,
        "time_of_max_redefinition_error": figures.time_of_max_error,
        "move": figures.move,
        "max_error": member.max_error,
        "peak_torque": figures.peak_torque,
        "time_of_peak_torque": figures.time_of_peak_torque,
        "max_torque_jump": jumps["torque"],
        "max_output_jump": jumps["output"],
        "max_constraint_residual": member.max_constraint_residual,
        "max_condition_number": member.max_condition_number,
        "amplification": member.amplification,
        "max_spectral_radius": member.max_spectral_radius,
        "final_redefined_output": float(y[-1]),  # the samples run from t0 to tf exactly
        "final_desired_output": float(trajectory.derivative([trajectory.tf], 0, "-")[0]),
        "final_redefined_velocity": float(ydot[-1]),
        "torque_at_start": float(tau[0]),
        "torque_at_end": float(tau[-1]),
        "zeros": [[float(v.real), float(v.imag)] for v in model.zeros],
        "n_unstable": plan.modal.n_unstable,
        "r": plan.r,
        "matched_exponentials": int(plan.matched.max(initial=0)),
        "samples": int(t.size),
        "settings": {
            **settings.to_dict(),
            "segments": [float(b) for b in plan.bounds],
            "rate": float(rate),
            "solver": solver,
            "tol": float(tol),
            "initial_internal_state": XI0.tolist(),
        },
        "verification": {**checks.as_dict(), "sampling": sampling},
        "segments": [
            {
                "t_start": s.t_start,
                "t_end": s.t_end,
                "exponents": s.mu.tolist(),
                "coefficients": s.c.tolist(),
                "residual": s.residual,
                "condition_number": s.condition,
            }
            for s in redef.segments
        ],
    }
    if isinstance(model, LinearSystem):
        summary["system"] = model.report()
    else:
        n1 = model.n + 1
        summary.update({"modes": model.n, "mode_shapes": model.mode_family, "output_at": model.output_at,
                        "final_deflections": [float(v) for v in X[-1, 1:n1]],
                        "final_deflection_rates": [float(v) for v in X[-1, n1 + 1 :]]})
    if search is not None:
        summary["auto"] = search
    if zeros != "all":
        summary["zero_dynamics"] = zero_dynamics_summary(redef.form, zeros, settings.eps)
    return InversionResult(
        t=t,
        y_d=y_d,
        y=y,
        ydot=ydot,
        yddot=yddot,
        X=X,
        tau=tau,
        theta_d=fed["theta_d"] if link else None,
        thetadot_d=fed["thetadot_d"] if link else None,
        segments=redef.segments,
        summary=summary,
        model=model,
        trajectory=trajectory,
        modal=plan.modal,
        settings=settings,
        figures=figures,
        checks=checks,
        redefinition=redef,
        signals=signals,
    )

"""Closed-loop simulation of the manipulator (sections 7 and 8 of the paper; docs/method.md section 6).

:func:`simulate` drives a plant (:mod:`simulation.plant`: the linear (P8) or nonlinear
(P4) compiled right-hand side with hub stick-slip friction) by a controller
(:mod:`simulation.control`: feedforward ``tau_l`` plus joint PD (Eq. (40)) during the
manoeuvre, PD alone or pulse-width control after it). The loop is a hybrid system
(:mod:`simulation.hybrid`) integrated in compiled code (:mod:`simulation.integrate`).

Defaults are the same in the Python API and on the command line: the nonlinear plant,
the PD controller, the paper's gains for the paper's cases and the gains of
:func:`~simulation.control.default_gains` otherwise, the model's own friction for the
plant and for the compensation. A plant that differs from the model is always the
caller's explicit choice, and the summary's ``plant`` block lists every such value with
its source.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, TypedDict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.errors import SettingsError
from modelgen.files import write_columns, write_json
from inversion.config import DEFAULTS as INVERSION_DEFAULTS
from inversion.result import InversionResult
from modelgen.compiled import FastCall
from modelgen.joint_pd import check_stiffness
from modelgen.model import Model
from modelgen.paper import PaperCase

from .control import Controller, ControllerKind, Gains, PulseWidthLaw, default_gains
from .hybrid import DISCRETE, HybridLoop, PhaseName
from .integrate import Engine, SimulationError, integrate
from .options import SIMULATION_DEFAULTS, SimulationOptions
from .plant import HubFriction, Plant, PlantKind
from .reference import Reference

__all__ = ["simulate", "SimulationResult", "SimulationSummary", "SimulationError", "SIMULATION_COLUMNS", "MAX_SAMPLES"]

FloatArray = NDArray[np.float64]

#: Columns of ``simulation.csv`` (the first six are a contract relied on by scripts).
SIMULATION_COLUMNS = ("t", "y", "y_d", "y_redef", "theta", "tau", "thetadot", "friction", "stuck")
#: Largest number of output samples of one simulation.
MAX_SAMPLES = 5_000_000
#: Output samples integrated per call (a progress step).
_CHUNK = 250_000
#: Rows per mapped call of the output function (a map's construction grows with its size).
_OUTPUT_BLOCK = 1024
#: Length of the window of the steady-state figures (s).
STEADY_WINDOW = 1.0


class PulseRecord(TypedDict):
    """One pulse of stage 2."""

    start: float
    width: float
    torque: float


class _SimulationFigures(TypedDict):
    """The keys every simulation's summary has."""

    model: str
    plant: dict[str, Any]
    controller: str
    kp: float
    kd: float
    gains_source: str
    coulomb_friction: float
    breakaway_friction: float
    friction_compensation: float
    friction_compensation_source: str
    external_torque: float
    pulse_law: dict[str, Any] | None
    engine: str
    t_final_manoeuvre: float
    t_end: float
    final_tip_error: float
    final_tip_error_signed: float
    steady_tip_error: float
    residual_vibration: float
    steady_window: list[float]
    max_tracking_error: float
    max_redefined_tracking_error: float
    peak_torque: float
    settling_band: float
    settling_time: float | None
    settled: bool
    stick_slip_transitions: int
    times_stuck: int
    compensation_reversals: int
    pulses: list[PulseRecord]
    final_energy: float
    samples: int


class SimulationSummary(_SimulationFigures, total=False):
    """``summary.json`` of a simulation (the keys are a contract).

    ``summary.json`` of a simulation (the keys are a contract; see :func:`simulate`): the figures, ``robustness``
    with ``simulate --uncertainty`` (:mod:`simulation.uncertain`), and ``drive`` where the link's geometry has one (its
    ``[drive] max_torque`` against the peak torque the motor delivered: the plant is driven without the limit, so a
    peak beyond it is what the motor could not deliver).
    """

    robustness: dict[str, Any]
    drive: dict[str, Any]


@dataclass(frozen=True)
class SimulationResult:
    """A simulated manoeuvre.

    Attributes
    ----------
    t : ndarray
        Sample times (s).
    X : ndarray, shape (N, 2(n+1))
        Plant state.
    y : ndarray
        Tip displacement (m).
    y_d : ndarray
        Desired tip displacement (held at ``y_d(t_f)`` after the manoeuvre).
    y_redef : ndarray
        Redefined output ``y~`` during the manoeuvre, then ``y_d(t_f)`` (the reference).
    theta, thetadot : ndarray
        Joint angle and rate.
    deflections : ndarray, shape (N, n)
        Modal deflections ``delta``.
    tau : ndarray
        Motor torque (N m).
    friction : ndarray
        Dry-friction torque on the joint (N m).
    stuck : ndarray of bool
        Whether the hub is stuck.
    summary : SimulationSummary
        Key figures (see :func:`simulate`).
    plant : Plant
        The simulated plant.
    controller : Controller
        The control law.
    """

    t: FloatArray
    X: FloatArray
    y: FloatArray
    y_d: FloatArray
    y_redef: FloatArray
    theta: FloatArray
    thetadot: FloatArray
    deflections: FloatArray
    tau: FloatArray
    friction: FloatArray
    stuck: NDArray[np.bool_]
    summary: SimulationSummary
    plant: Plant = field(repr=False)
    controller: Controller = field(repr=False)

    def write_csv(self, path: str | Path, progress: Callable[[int, int], None] | None = None) -> None:
        """Write ``simulation.csv``.

        Write ``simulation.csv``: :data:`SIMULATION_COLUMNS` and ``delta_1..delta_n``.

        Parameters
        ----------
        path : str or Path
            The file.
        progress : callable, optional
            ``progress(rows_written, rows)`` after each block.
        """
        n = self.deflections.shape[1]
        names = list(SIMULATION_COLUMNS) + [f"delta_{j + 1}" for j in range(n)]
        cols = [self.t, self.y, self.y_d, self.y_redef, self.theta, self.tau, self.thetadot, self.friction, self.stuck]
        write_columns(path, names, cols + [self.deflections[:, j] for j in range(n)], progress)

    def write_summary(self, path: str | Path) -> None:
        """Write ``summary.json``.

        Parameters
        ----------
        path : str or Path
            The file.
        """
        write_json(path, dict(self.summary))


def _gains(model: Model, case: PaperCase | None, kp: float | None, kd: float | None) -> Gains:
    """The PD gains: given ones, else the paper case's, else the rule's."""
    if case is not None:
        base = Gains(float(case.kp.value), float(case.kd.value), f"the paper, {case.kp.source}")
    else:
        base = default_gains(model)
    if kp is None and kd is None:
        return base
    given = [name for name, value in (("kp", kp), ("kd", kd)) if value is not None]
    source = "given by the caller" if len(given) == 2 else f"{given[0]} given by the caller; the other from {base.source}"
    return Gains(base.kp if kp is None else kp, base.kd if kd is None else kd, source)


def _pulse_law(
    pulse: PulseWidthLaw | Mapping[str, Any] | None, case: PaperCase | None, known: float, move: float
) -> PulseWidthLaw:
    if isinstance(pulse, PulseWidthLaw):
        return pulse
    given = dict(pulse or {})
    if case is not None and case.pulse:
        base = {k: v.value for k, v in case.pulse.items()}
        values = {**base, **{k: v for k, v in given.items() if v is not None}}
        source = "assumed for the paper's case: the paper gives no details (its reference [26])"
        return PulseWidthLaw(**values, source=source + ("; some values given by the caller" if values != base else ""))
    return PulseWidthLaw.for_link(known, move, **given)


def _sample_times(t0: float, t_end: float, rate: float) -> FloatArray:
    count = int(math.floor((t_end - t0) * rate + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise SettingsError("rate", rate, f"a rate giving at most {MAX_SAMPLES:,} samples over {t_end - t0:g} s "
                            f"(at most {MAX_SAMPLES / (t_end - t0):.4g} Hz)")
    samples = t0 + np.arange(count) / rate
    if t_end - samples[-1] > 1e-9 / rate:
        samples = np.append(samples, t_end)
    return samples


def default_max_step(model: Model, reference: Reference | None, rate: float) -> float:
    """The largest step when events can happen: a tenth of the fastest time scale, at most one sample.

    The fastest time scale is ``1/omega`` for the largest of the model's flexible natural
    frequencies and the reference's rates; an event indicator (the hub's rate, the
    friction needed to hold it) cannot then cross zero and back within one step unnoticed.
    """
    omega = 2 * math.pi * float(np.max(model.natural_frequencies_hz, initial=0.0))
    if reference is not None:
        omega = max(omega, 0.02 / reference.spacing)
    return min(1.0 / rate, 0.1 / max(omega, 1e-9))


def simulate(
    model: Model,
    inversion: InversionResult | None = None,
    plant: PlantKind = "nonlinear",
    controller: ControllerKind = "pd",
    *,
    kp: float | None = None,
    kd: float | None = None,
    t_end: float | None = None,
    coulomb_friction: float | None = None,
    breakaway_friction: float | None = None,
    friction_compensation: float | None = None,
    pulse: PulseWidthLaw | Mapping[str, Any] | None = None,
    initial_state: ArrayLike | None = None,
    plant_overrides: Mapping[str, float] | None = None,
    plant_sources: Mapping[str, str] | None = None,
    external_torque: float = 0.0,
    rate: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    engine: Engine | None = None,
    max_step: float | None = None,
    settling_band: float | None = None,
    progress: Callable[[float], None] | None = None,
    options: SimulationOptions | None = None,
) -> SimulationResult:
    """Simulate the closed loop (Eq. (40)), linear or nonlinear.

    Parameters
    ----------
    model : Model
        The model the feedforward was computed for.
    inversion : InversionResult, optional
        The feedforward and the references; ``None`` simulates the plant without a
        manoeuvre (``controller`` must then be ``"none"``) from ``initial_state``.
    plant : {"linear", "nonlinear", "nonlinear-paper", "nonlinear-large"}
        (P8); (P4) with the link's foreshortening (geometric stiffening, docs/method.md
        section 1a; the default); the paper's (P4) as it is; or the link with exact
        kinematics for large deflections (:mod:`modelgen.large`, at most 8 modes).
    controller : {"none", "pd", "two-stage"}
        See :mod:`simulation.control`; default ``"pd"``.
    kp, kd : float, optional
        Joint PD gains; default the paper's for its cases, else
        :func:`~simulation.control.default_gains`.
    t_end : float, optional
        End of the simulation (s); default the paper case's, else the end of the feedforward plus the window its
        acceptance judged (:attr:`InversionResult.window`, 2 s by default): what ``invert`` judged is what it shows.
    coulomb_friction, breakaway_friction : float, optional
        The plant's hub dry friction ``F_c`` and breakaway level ``F_s >= F_c`` (N m);
        default the model's ``F_c`` for both.
    friction_compensation : float, optional
        ``F_hat`` added in the direction of the desired motion during the manoeuvre
        (N m); default the model's ``F_c`` (the paper's experiment: its measured 0.45 N m).
    pulse : PulseWidthLaw or mapping, optional
        Stage-2 law of the two-stage controller, or some of its values (the rest by
        :meth:`PulseWidthLaw.for_link`, or the paper case's).
    initial_state : array_like, optional
        ``X(t0)``; default the redefined state at ``t0`` (rest for a start from rest).
    plant_overrides : mapping, optional
        Physical parameters of the plant that differ from the model (model mismatch), by
        name: ``L, EI, rho, I_h, m_t, I_t, b_h, zeta``.
    plant_sources : mapping, optional
        Where each plant value that differs from the model came from (recorded in the
        summary's ``plant`` block); default "given by the caller".
    external_torque : float
        A constant torque added at the joint (N m).
    rate : float, optional
        Output sampling rate (Hz); at most :data:`MAX_SAMPLES` samples (default
        :attr:`inversion.config.Defaults.rate`, the feedforward's own).
    rtol, atol : float, optional
        Integrator tolerances (default 1e-9, 1e-12: :class:`~simulation.options.SimulationOptions`).
    engine : {"cvodes", "scipy"}, optional
        CasADi's CVODES in compiled code (:func:`casadi.integrator`, the default), or SciPy's LSODA
        from Python (:func:`scipy.integrate.solve_ivp`, to cross-check).
    max_step : float, optional
        Largest integrator step when events can happen (s); default
        :func:`default_max_step`.
    settling_band : float, optional
        Settling band as a fraction of the manoeuvre's distance (2 % by default).
    progress : callable, optional
        Called with the fraction done after each block of samples.
    options : SimulationOptions, optional
        ``rate``, ``rtol``, ``atol``, ``engine``, ``max_step`` and ``settling_band`` as one object; the keywords above,
        where given, override it.

    Returns
    -------
    SimulationResult
        Its ``summary`` holds ``final_tip_error`` (m, at ``t_end``), ``steady_tip_error``
        (m, the mean tip error over the last second) with ``residual_vibration`` (m, the
        tip's peak-to-peak motion over that second, which a mean hides), ``settled``
        (the tip within the settling band over that second), ``max_tracking_error``,
        ``peak_torque``, ``settling_time``, the ``plant`` block (kind, friction, every value
        that differs from the model with its source), the gains with their source, and
        the events (stick-slip transitions, pulses).

    Raises
    ------
    SettingsError
        For settings out of range.
    SimulationError
        If the integrator fails.
    """
    if controller not in ("none", "pd", "two-stage"):
        raise SettingsError("controller", controller, "'none', 'pd' or 'two-stage'")
    if controller != "none" and inversion is None:
        raise SettingsError("controller", controller, "'none' when no inversion (feedforward) is given")
    if inversion is not None and (inversion.signals is None or inversion.theta_d is None):
        raise SettingsError("inversion", f"a {inversion.summary.get('method', 'ssef')} inversion of {inversion.model.name}",
                            "a link's feedforward with its signals (the closed loop drives the link's joint)")
    opts = (SIMULATION_DEFAULTS if options is None else options).given(
        rate=rate, rtol=rtol, atol=atol, engine=engine, max_step=max_step, settling_band=settling_band).checked()
    rate, rtol, atol, engine, settling_band = opts.rate, opts.rtol, opts.atol, opts.engine, opts.settling_band
    assert rate is not None
    g = model.geometry
    case = inversion.case if inversion is not None else None  # decided once, by the inversion
    Fc = g.hub_coulomb_friction if coulomb_friction is None else coulomb_friction
    Fs = Fc if breakaway_friction is None else breakaway_friction
    the_plant = Plant(model, plant, HubFriction(Fc, Fs), plant_overrides, plant_sources)
    if plant == "nonlinear" and inversion is not None:
        _stiffened_holds(the_plant, inversion)
    reference = Reference(inversion) if inversion is not None else None
    t0 = reference.t0 if reference is not None else 0.0
    tf = reference.tf if reference is not None else t0
    move = 0.0
    if inversion is not None:
        traj = inversion.trajectory
        move = abs(float(traj.derivative([tf], 0)[0]) - float(traj.derivative([t0], 0)[0]))
    ctrl, law = _controller(model, case, controller, kp, kd, friction_compensation, pulse, external_torque, move)
    if t_end is None:
        judged = inversion.window if inversion is not None else None  # a result not judged: the acceptance's default
        t_end = float(case.t_end.value) if case is not None else tf + (judged or INVERSION_DEFAULTS.vibration_window)
    if not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end > t0 and t_end >= tf):
        raise SettingsError("t_end", t_end, f"a time after the start t0 = {t0:g} s, not before the end of the manoeuvre {tf:g} s")
    t_end = float(t_end)
    X0 = _initial_state(model, inversion, initial_state)
    max_step = default_max_step(model, reference, rate) if opts.max_step is None else opts.max_step

    samples = _sample_times(t0, t_end, rate)
    loop = HybridLoop(the_plant, ctrl, reference, model.output_at, float(model.M[0, 0]))  # joint error -> output error
    first: PhaseName = "manoeuvre" if reference is not None and tf > t0 else "after"
    x = loop.initial_state(X0, t0, first)
    rows = [x]
    pieces: list[tuple[PhaseName, FloatArray, FloatArray]] = []
    done_samples = 1
    total = samples.size

    def run(name: PhaseName, start: float, stop: float, state: FloatArray, extra: FloatArray) -> FloatArray:
        nonlocal done_samples
        inside = samples[(samples > start) & (samples <= stop)]
        times = np.union1d(np.append(inside, stop), extra[(extra > start) & (extra < stop)])
        is_sample = np.isin(times, inside)
        ph = loop.phase(name)
        out_rows = []
        begin = start
        for lo in range(0, times.size, _CHUNK):
            chunk = times[lo : lo + _CHUNK]
            try:
                block = integrate(ph, begin, chunk, state, engine, rtol, atol, max_step)
            except SimulationError as exc:
                raise SimulationError(f"{exc}{_near_singular(the_plant, state[: 2 * the_plant.n1], begin)}") from None
            out_rows.append(block)
            state, begin = block[-1], float(chunk[-1])
            done_samples += int(is_sample[lo : lo + _CHUNK].sum())
            if progress is not None:
                progress(min(done_samples / total, 1.0))
        block = np.vstack(out_rows)
        pieces.append((name, times[is_sample], block[is_sample]))
        return block[-1]

    if first == "manoeuvre":
        x = run("manoeuvre", t0, tf, x, np.zeros(0))
    if t_end > tf or first == "after":
        x = loop.settle("after", tf, x)
        extra: FloatArray = np.zeros(0)
        if controller == "two-stage" and law is not None:
            x[loop.index("next_decision")] = tf
            x = loop.apply("after", "decision", tf, x)
            # one output in the middle of every period keeps each pulse's record in the samples
            extra = tf + (np.arange(law.max_pulses + 1, dtype=float) + 0.5) * law.period
        run("after", tf, t_end, x, extra)
    return _assemble(model, inversion, loop, samples, rows, pieces, t0, tf, t_end, settling_band, engine)


def _stiffened_holds(plant: Plant, inversion: InversionResult) -> None:
    """Refuse the stiffened plant for a feedforward whose own states take it where its mass matrix is singular
    (:meth:`Plant.effective_inertia`): no integrator can follow it there."""
    X = np.asarray(inversion.X, dtype=float)
    if X.ndim != 2 or X.shape[1] != 2 * plant.n1:
        return
    X = _with_deflections(plant, inversion, X)
    margin = plant.effective_inertia(X)
    worst = int(np.argmin(margin))
    if margin[worst] > 0:
        return
    at_rest = float(plant.effective_inertia(np.zeros(X.shape[1]))[0])
    deflections = ", ".join(f"{d:.3g}" for d in X[worst, 1 : plant.n1])
    raise SettingsError("plant", plant.kind, f"'nonlinear-large' (exact kinematics), 'nonlinear-paper' or 'linear' for this move: "
                        f"the stiffened model's mass matrix is singular along it -- the hub's effective inertia, {at_rest:.4g} "
                        f"kg m^2 at rest, is {margin[worst]:.3g} at t = {float(inversion.t[worst]):.4g} s of the feedforward "
                        f"(modal deflections {deflections}), where the foreshortening's second-order term outweighs it")


def _with_deflections(plant: Plant, inversion: InversionResult, X: FloatArray) -> FloatArray:
    """The feedforward's states on the plant's link: the inversion's own where it was computed for this link; for a run
    read back (its rows keep the joint's reference only, the deflections zero) or another link (a corner of
    ``--uncertainty``: a softer link bends further), the plant's linear model driven by the table held row by row."""
    n1 = plant.n1
    t = np.asarray(inversion.t, dtype=float)
    own = getattr(inversion, "model", None) is plant.model and np.any(X[:, 1:n1])
    if own or t.size < 2 or not np.any(np.asarray(inversion.tau, dtype=float)):
        return X
    from inversion.lti.discrete import recurrence, zero_order_hold

    model = plant.model
    Ad, Bd = zero_order_hold(np.asarray(model.A, dtype=float), np.asarray(model.B, dtype=float).reshape(-1), float(t[1] - t[0]))
    states, _ = recurrence(Ad, Bd[:, None], X[0], np.asarray(inversion.tau, dtype=float)[:, None])
    return np.asarray(states, dtype=float)


def _near_singular(plant: Plant, X: FloatArray, t: float) -> str:
    """What an integrator's failure owes to the stiffened plant's mass matrix nearing singular, or nothing."""
    if plant.kind != "nonlinear" or not np.all(np.isfinite(X)):
        return ""
    margin, at_rest = (float(v) for v in plant.effective_inertia(np.vstack([X, np.zeros_like(X)])))
    if margin > 0.25 * at_rest:
        return ""
    return (f"; at t = {t:.6g} s the hub's effective inertia had fallen to {margin:.3g} kg m^2 ({at_rest:.4g} at rest): the "
            "stiffened model's mass matrix nears singular there -- plant='nonlinear-large' (exact kinematics) follows it")


def _initial_state(model: Model, inversion: InversionResult | None, given: ArrayLike | None) -> FloatArray:
    """The plant's state at the start: the one given, else the feedforward's (rest without one)."""
    n1 = model.n + 1
    if given is None:
        return inversion.X[0].copy() if inversion is not None else np.zeros(2 * n1)
    X0 = np.asarray(given, dtype=float).reshape(-1).copy()
    if X0.size != 2 * n1 or not np.all(np.isfinite(X0)):
        raise SettingsError("initial_state", given, f"{2 * n1} finite numbers")
    return X0


def _controller(model: Model, case: PaperCase | None, controller: ControllerKind, kp: float | None, kd: float | None,
                friction_compensation: float | None, pulse: PulseWidthLaw | Mapping[str, Any] | None, external_torque: float,
                move: float) -> tuple[Controller, PulseWidthLaw | None]:
    """The controller :func:`simulate` asked for: its gains (checked against the stiffness they imply), the friction
    compensation with its source, and the two-stage law (which needs dry friction to stop the hub between pulses)."""
    g = model.geometry
    if friction_compensation is None:
        compensation = float(case.friction_compensation.value) if case is not None else g.hub_coulomb_friction
        compensation_source = (f"the paper, {case.friction_compensation.source}" if case is not None
                               else "the model's hub.coulomb_friction")
    else:
        compensation, compensation_source = friction_compensation, "given by the caller"
    if not (isinstance(compensation, (int, float)) and math.isfinite(compensation) and compensation >= 0):
        raise SettingsError("friction_compensation", compensation, "a finite number >= 0 (N m)")
    known = compensation if compensation > 0 else g.hub_coulomb_friction
    if controller == "two-stage" and not known > 0:
        raise SettingsError("controller", controller, "'none' or 'pd' for a hub without dry friction: stage 2 of the "
                            "two-stage controller relies on the friction stopping the hub between pulses "
                            "(give a friction compensation or a geometry with hub.coulomb_friction > 0)")
    law = _pulse_law(pulse, case, known, move) if controller == "two-stage" else None
    gains = _gains(model, case, kp, kd)
    if controller != "none":
        check_stiffness(model, gains.kp, gains.kd)
    ctrl = Controller(controller, gains, float(compensation), float(known), law, external_torque, compensation_source)
    return ctrl, law


def _outputs(outputs: Any, times: FloatArray, states: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Motor torque and friction at every ``(t, x)`` row: one mapped call per block of ``_OUTPUT_BLOCK`` rows."""
    count = min(times.size, _OUTPUT_BLOCK)
    mapped = FastCall(outputs.map(count, "serial"))
    tau, fric = np.empty(times.size), np.empty(times.size)
    for lo in range(0, times.size, count):
        t, x = times[lo : lo + count], states[lo : lo + count]
        pad = count - t.size
        if pad:  # the last block repeats its last row
            t, x = np.append(t, np.full(pad, t[-1])), np.vstack([x, np.repeat(x[-1:], pad, axis=0)])
        a, b = mapped(t, x.T)
        tau[lo : lo + count] = a.reshape(-1)[: count - pad]
        fric[lo : lo + count] = b.reshape(-1)[: count - pad]
    return tau, fric


def _redefined_output(inversion: InversionResult, times: FloatArray) -> FloatArray:
    """``y~`` at ``times``: the inversion's own samples where the times coincide, the closed form elsewhere (a result
    without one, stable inversion's: its samples interpolated)."""
    grid = inversion.t
    if inversion.redefinition is None:
        return np.interp(times, grid, inversion.y)
    at = np.clip(np.searchsorted(grid, times), 0, grid.size - 1)
    near = np.abs(grid[at] - times) <= 1e-12 * max(1.0, abs(float(grid[-1])))
    y = np.empty(times.size)
    y[near] = inversion.y[at[near]]
    if not np.all(near):
        y[~near] = inversion.evaluate(times[~near])["y"]
    return y


def _pulses(loop: HybridLoop, discrete: FloatArray) -> list[PulseRecord]:
    """The two-stage controller's pulses, read from the discrete state's records."""
    pulses: list[PulseRecord] = []
    if loop.controller.kind == "two-stage":
        start_i, width_i, torque_i, count_i = (DISCRETE.index(k) for k in ("pulse_start", "pulse_width", "pulse_record", "pulses"))
        seen = np.rint(discrete[:, count_i])
        for k in range(1, int(seen.max(initial=0)) + 1):
            row = discrete[int(np.argmax(seen == k))]
            pulses.append({"start": float(row[start_i]), "width": float(row[width_i]), "torque": float(row[torque_i])})
    return pulses


def _desired(inversion: InversionResult | None, T: FloatArray, t0: float, tf: float) -> tuple[float, FloatArray, FloatArray, float]:
    """``y_d(t_f)``, ``y_d`` and the redefined output at the times ``T`` (held at ``y_d(t_f)`` after the move), and the move."""
    if inversion is not None:
        traj = inversion.trajectory
        y_final = float(traj.derivative([tf], 0)[0])
        y_d = np.where(T <= tf, traj.derivative(np.clip(T, traj.t0, tf), 0), y_final)
        during = T <= tf
        y_redef = np.full(T.size, y_final)
        if np.any(during):
            y_redef[during] = _redefined_output(inversion, T[during])
        move = abs(y_final - float(traj.derivative([t0], 0)[0]))
    else:
        y_final = 0.0
        y_d = np.zeros(T.size)
        y_redef = np.zeros(T.size)
        move = 0.0
    return y_final, y_d, y_redef, move


def _assemble(
    model: Model,
    inversion: InversionResult | None,
    loop: HybridLoop,
    samples: FloatArray,
    rows: list[FloatArray],
    pieces: list[tuple[PhaseName, FloatArray, FloatArray]],
    t0: float,
    tf: float,
    t_end: float,
    settling_band: float,
    engine: str,
) -> SimulationResult:
    first: PhaseName = pieces[0][0] if pieces else "after"
    T = np.concatenate([[t0]] + [p[1] for p in pieces])
    states = np.vstack([np.asarray(rows)] + [p[2] for p in pieces])
    phases = [first] + [name for name, times, _ in pieces for _ in range(times.size)]
    tau = np.zeros(T.size)
    fric = np.zeros(T.size)
    for name in ("manoeuvre", "after"):
        where = np.flatnonzero([p == name for p in phases])
        if where.size:
            tau[where], fric[where] = _outputs(loop.phase(name).outputs, T[where], states[where])
    n1 = model.n + 1
    Xs = states[:, : 2 * n1]
    discrete = states[:, 2 * n1 :]
    plant = loop.plant
    y = plant.tip(Xs)
    mode = np.rint(discrete[:, 0])
    stuck = (mode == 0) & plant.friction.active
    final = np.rint(discrete[-1])
    counts = {name: int(final[DISCRETE.index(name)]) for name in ("stops", "sticks", "breakaways", "reversals")}
    pulses = _pulses(loop, discrete)
    y_final, y_d, y_redef, move = _desired(inversion, T, t0, tf)
    band = settling_band * move
    during = T <= tf
    window = T >= max(tf, T[-1] - STEADY_WINDOW)
    if not np.any(window):
        window = T >= T[-1]
    steady = float(abs(y_final - y[window].mean()))
    vibration = float(np.ptp(y[window]))
    worst = float(np.abs(y[window] - y_final).max())
    settled = bool(band > 0 and worst <= band)  # within the band over the whole last second, not at one instant
    ctrl_block = loop.controller.block()
    summary: SimulationSummary = {
        "model": model.name,
        "plant": plant.block(),
        "controller": loop.controller.kind,
        "kp": loop.controller.gains.kp,
        "kd": loop.controller.gains.kd,
        "gains_source": loop.controller.gains.source,
        "coulomb_friction": plant.friction.coulomb,
        "breakaway_friction": plant.friction.breakaway,
        "friction_compensation": loop.controller.friction_compensation,
        "friction_compensation_source": loop.controller.compensation_source,
        "external_torque": loop.controller.external_torque,
        "pulse_law": ctrl_block.get("pulse_law"),
        "engine": engine,
        "t_final_manoeuvre": tf,
        "t_end": t_end,
        "final_tip_error": float(abs(y_final - y[-1])),
        "final_tip_error_signed": float(y_final - y[-1]),
        "steady_tip_error": steady,
        "residual_vibration": vibration,
        "steady_window": [float(T[window][0]), float(T[-1])],
        "max_tracking_error": float(np.abs(y - y_d).max()),
        "max_redefined_tracking_error": float(np.abs(y[during] - y_redef[during]).max()) if np.any(during) else 0.0,
        "peak_torque": float(np.abs(tau).max()),
        "settling_band": band,
        "settling_time": _settling_time(T, y, y_final, band, tf) if settled else None,
        "settled": settled,
        "stick_slip_transitions": counts["stops"] + counts["breakaways"],
        "times_stuck": counts["sticks"],
        "compensation_reversals": counts["reversals"],
        "pulses": pulses,
        "final_energy": float(plant.energy(Xs[-1:])[0]),
        "samples": int(T.size),
    }
    geometry = getattr(model, "geometry", None)
    drive = getattr(geometry, "drive_max_torque", None)
    if drive is not None:
        summary["drive"] = {"max_torque": float(drive), "source": f"[drive] max_torque of {getattr(geometry, 'source', model.name)}",
                            "peak_torque": summary["peak_torque"], "within": bool(summary["peak_torque"] <= float(drive) * (1 + 1e-12))}
    return SimulationResult(
        t=T, X=Xs, y=y, y_d=y_d, y_redef=y_redef, theta=Xs[:, 0], thetadot=Xs[:, n1], deflections=Xs[:, 1:n1],
        tau=tau, friction=fric, stuck=stuck, summary=summary, plant=plant, controller=loop.controller,
    )


def _settling_time(t: FloatArray, y: FloatArray, target: float, band: float, after: float) -> float | None:
    """Time from the start after which the tip stays within ``band`` of ``target`` (``None``: it does not)."""
    outside = np.flatnonzero(np.abs(y - target) > band)
    if outside.size == 0:
        return float(after - t[0]) if after > t[0] else 0.0
    last = int(outside[-1])
    if last == t.size - 1:
        return None
    return float(max(t[last + 1], after) - t[0])

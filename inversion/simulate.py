"""Closed-loop simulation of the manipulator (section 7 and 8 of the paper; docs/method.md section 6).

The plant (:mod:`inversion.plant`, linear (P8) or nonlinear (P4), compiled right-hand
sides, hub stick-slip friction) is driven by a controller (:mod:`inversion.control`):
feedforward ``tau_l`` plus joint PD (Eq. (40)) during the manoeuvre, PD alone or
pulse-width control after it. Integration is event-driven: the hub's stick/slip
transitions, the end of the manoeuvre and the controller's pulse edges are located
exactly, and the integrator restarts there; in between, ``scipy.integrate.solve_ivp``
(LSODA by default: it switches to a stiff method when needed) with the analytic
Jacobian of the compiled model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from modelgen.errors import SflmError
from modelgen.model import Model

from .control import Controller, ControllerKind, PulseWidthLaw, Reference
from .errors import SettingsError
from .output import write_columns, write_json
from .piecewise import InversionResult
from .plant import HubFriction, Plant, PlantKind

__all__ = ["simulate", "SimulationResult", "SimulationError", "SIMULATION_COLUMNS"]

FloatArray = NDArray[np.float64]

#: Columns of ``simulation.csv`` (the first six are a contract relied on by scripts).
SIMULATION_COLUMNS = ("t", "y", "y_d", "y_redef", "theta", "tau", "thetadot", "friction", "stuck")
#: Integrators accepted (``scipy.integrate.solve_ivp`` methods); the first three use the Jacobian.
_METHODS = ("LSODA", "Radau", "BDF", "DOP853", "RK45", "RK23")
#: Largest number of stick/slip transitions and controller decisions in one run.
_MAX_SWITCHES = 200_000


class SimulationError(SflmError):
    """The integration failed (the message says where and why)."""


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
    summary : dict
        ``final_tip_error`` (m, at the last sample), ``steady_tip_error`` (m, mean over
        the last second) with ``residual_vibration`` (half peak-to-peak there),
        ``max_tracking_error`` (m), ``peak_torque`` (N m), ``settling_time`` (s from the
        start, or ``None``) and more.
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
    summary: dict[str, Any] = field(default_factory=dict)

    def write_csv(self, path: str | Path) -> None:
        """Write ``simulation.csv``: :data:`SIMULATION_COLUMNS` and ``delta_1..delta_n``."""
        n = self.deflections.shape[1]
        names = list(SIMULATION_COLUMNS) + [f"delta_{j + 1}" for j in range(n)]
        cols = [self.t, self.y, self.y_d, self.y_redef, self.theta, self.tau, self.thetadot, self.friction, self.stuck]
        write_columns(path, names, cols + [self.deflections[:, j] for j in range(n)])

    def write_summary(self, path: str | Path) -> None:
        """Write ``summary.json``."""
        write_json(path, self.summary)


@dataclass
class _Mode:
    stuck: bool
    direction: float = 0.0  # +1 / -1 while slipping


class _ClosedLoop:
    """The right-hand side, Jacobian and events of the closed loop in one friction mode."""

    def __init__(self, plant: Plant, ctrl: Controller, friction: HubFriction, n1: int):
        self.plant, self.ctrl, self.friction, self.n1 = plant, ctrl, friction, n1

    def friction_needed(self, t: float, X: FloatArray) -> float:
        """The friction torque that would hold the hub at rest at ``(t, X)``."""
        tau_m, _ = self.ctrl.torque(t, X, self.n1)
        return self.plant.holding_torque(X)[0] - tau_m

    def settle_mode(self, t: float, X: FloatArray) -> _Mode:
        """The mode of a hub at (exactly) zero velocity: stuck, or slipping away from the friction."""
        if not self.friction.active:
            return _Mode(False, 0.0)
        needed = self.friction_needed(t, X)
        if abs(needed) <= self.friction.breakaway:
            return _Mode(True)
        return _Mode(False, -math.copysign(1.0, needed))

    def system(self, mode: _Mode) -> tuple[Callable[..., FloatArray], Callable[..., FloatArray], list[Any]]:
        """``(fun, jac, events)`` for ``solve_ivp`` in ``mode``."""
        plant, ctrl, n1 = self.plant, self.ctrl, self.n1
        if mode.stuck:

            def held(tt: float, xx: FloatArray) -> FloatArray:
                return plant.holding_torque(xx)[1]

            def breakaway(tt: float, xx: FloatArray) -> float:
                return self.friction.breakaway - abs(self.friction_needed(tt, xx))

            def held_jacobian(tt: float, xx: FloatArray) -> FloatArray:
                tau_m, _ = ctrl.torque(tt, xx, n1)
                J = plant.jacobian(xx, tau_m)[0].copy()
                J[[0, n1], :] = 0.0  # the hub is held
                return J

            breakaway.terminal = True  # type: ignore[attr-defined]
            breakaway.direction = -1  # type: ignore[attr-defined]
            return held, held_jacobian, [breakaway]

        d = mode.direction
        kinetic = -d * self.friction.coulomb

        def fun(tt: float, xx: FloatArray) -> FloatArray:
            tau_m, _ = ctrl.torque(tt, xx, n1)
            return plant.rhs(xx, tau_m + kinetic)

        def jac(tt: float, xx: FloatArray) -> FloatArray:
            tau_m, grad = ctrl.torque(tt, xx, n1)
            J, Jt = plant.jacobian(xx, tau_m + kinetic)
            return np.asarray(J + np.outer(Jt, grad))

        if not (self.friction.active and d != 0):
            return fun, jac, []

        def stops(tt: float, xx: FloatArray) -> float:
            return d * xx[n1]

        stops.terminal = True  # type: ignore[attr-defined]
        stops.direction = -1  # type: ignore[attr-defined]
        return fun, jac, [stops]


def _as_function(torque: float | Callable[[float], float]) -> Callable[[float], float] | None:
    if callable(torque):
        return torque
    if not (isinstance(torque, (int, float)) and math.isfinite(torque)):
        raise SettingsError("external_torque", torque, "a finite number (N m) or a function of time")
    value = float(torque)
    return None if value == 0.0 else (lambda t: value)


def _settling_time(t: FloatArray, y: FloatArray, target: float, band: float, after: float) -> float | None:
    outside = np.flatnonzero(np.abs(y - target) > band)
    if outside.size == 0:
        return float(t[0])
    last = int(outside[-1])
    if last == t.size - 1:
        return None
    return float(max(t[last + 1], after) - t[0])


def simulate(
    model: Model,
    inversion: InversionResult | None = None,
    plant: PlantKind = "linear",
    controller: ControllerKind = "pd",
    kp: float = 0.0,
    kd: float = 0.0,
    t_end: float | None = None,
    coulomb_friction: float | None = None,
    breakaway_friction: float | None = None,
    friction_compensation: float = 0.0,
    pulse: PulseWidthLaw | None = None,
    initial_state: ArrayLike | None = None,
    plant_overrides: dict[str, float] | None = None,
    external_torque: float | Callable[[float], float] = 0.0,
    rate: float = 1000.0,
    rtol: float = 1e-9,
    atol: float = 1e-12,
    method: str = "LSODA",
    settling_band: float = 0.02,
) -> SimulationResult:
    """Simulate the closed loop (Eq. (40)) on the linear or the nonlinear plant.

    Parameters
    ----------
    model : Model
        The loaded model; its compiled ``linear_rhs``/``nonlinear_rhs`` are integrated.
    inversion : InversionResult, optional
        The feedforward and the references; ``None`` simulates the unforced plant
        (``controller`` must then be ``"none"``) from ``initial_state``.
    plant : {"linear", "nonlinear"}
        (P8) or (P4).
    controller : {"none", "pd", "two-stage"}
        See :mod:`inversion.control`.
    kp, kd : float
        Joint PD gains.
    t_end : float, optional
        End of the simulation (s); default ``t_f + 3 s``.
    coulomb_friction : float, optional
        Hub dry friction ``F_c`` (N m); default the geometry's.
    breakaway_friction : float, optional
        Static friction level ``F_s >= F_c`` (default ``F_c``).
    friction_compensation : float
        ``F_hat`` added in the direction of the desired motion during the manoeuvre.
    pulse : PulseWidthLaw, optional
        Stage-2 law of the two-stage controller.
    initial_state : array_like, optional
        ``X(t0)``; default the redefined state at ``t0`` (rest for a start from rest).
    external_torque : float or callable
        A torque added at the joint: a constant or ``f(t)`` (a load, a test input).
    plant_overrides : dict, optional
        Physical parameters of the plant that differ from the model the feedforward was
        computed for (model mismatch), by name: ``L, EI, rho, I_h, m_t, I_t, b_h, zeta``.
    rate : float
        Output sampling rate (Hz).
    rtol, atol : float
        Integrator tolerances.
    method : str
        ``solve_ivp`` method (``"LSODA"``, ``"Radau"``, ``"BDF"``, ``"DOP853"`` ...).
    settling_band : float
        Settling band as a fraction of the manoeuvre's distance (2 % by default).

    Returns
    -------
    SimulationResult

    Raises
    ------
    SettingsError
        For settings out of range.
    SimulationError
        If the integrator fails.
    """
    if controller != "none" and inversion is None:
        raise SettingsError("controller", controller, "'none' when no inversion (feedforward) is given")
    for name, value in (("rate", rate), ("rtol", rtol), ("atol", atol), ("settling_band", settling_band)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise SettingsError(name, value, "a finite number > 0")
    if method not in _METHODS:
        raise SettingsError("method", method, "one of " + ", ".join(_METHODS))
    n1 = model.n + 1
    g = model.geometry
    Fc = g.hub_coulomb_friction if coulomb_friction is None else float(coulomb_friction)
    Fs = Fc if breakaway_friction is None else float(breakaway_friction)
    friction = HubFriction(Fc, Fs)
    sim_plant = Plant(model, plant, friction, plant_overrides)
    reference = Reference(inversion) if inversion is not None else None
    ctrl = Controller(
        kind=controller,
        reference=reference,
        kp=float(kp),
        kd=float(kd),
        friction_compensation=float(friction_compensation),
        pulse=pulse or PulseWidthLaw(),
        inertia=float(model.M[0, 0]),
        coulomb=float(friction_compensation) if friction_compensation > 0 else Fc,  # what the controller knows
        length=g.length,
        external=_as_function(external_torque),
    )
    t0 = float(inversion.t[0]) if inversion is not None else 0.0
    tf = float(inversion.t[-1]) if inversion is not None else t0
    t_end = tf + 3.0 if t_end is None else float(t_end)
    if not math.isfinite(t_end) or t_end <= t0 or t_end < tf:
        raise SettingsError("t_end", t_end, f"a time after the start t0 = {t0:g} s, not before the end of the manoeuvre {tf:g} s")
    if initial_state is None:
        X = inversion.X[0].copy() if inversion is not None else np.zeros(2 * n1)
    else:
        X = np.asarray(initial_state, dtype=float).reshape(-1).copy()
        if X.size != 2 * n1 or not np.all(np.isfinite(X)):
            raise SettingsError("initial_state", initial_state, f"{2 * n1} finite numbers")

    samples = t0 + np.arange(int(math.floor((t_end - t0) * rate + 1e-9)) + 1) / rate
    if t_end - samples[-1] > 1e-9 / rate:
        samples = np.append(samples, t_end)
    out_t: list[FloatArray] = []
    out_X: list[FloatArray] = []
    out_stuck: list[FloatArray] = []
    out_dir: list[FloatArray] = []

    loop = _ClosedLoop(sim_plant, ctrl, friction, n1)
    if friction.active and X[n1] == 0.0:
        mode = loop.settle_mode(t0, X)
    else:
        mode = _Mode(False, math.copysign(1.0, X[n1]) if X[n1] != 0 else 0.0)

    breaks = sorted(b for b in ctrl.breakpoints() if t0 < b < t_end)
    t = t0
    switches = 0
    stuck_intervals = 0
    while t < t_end - 1e-12:
        nxt = min([b for b in breaks if b > t + 1e-12] + [ctrl.next_decision(t), t_end])
        current = mode
        if current.stuck:
            X[n1] = 0.0
        fun, jac, events = loop.system(current)
        last = out_t[-1][-1] if out_t and out_t[-1].size else -math.inf
        window = samples[(samples > last) & (samples >= t) & (samples <= nxt)]
        t_eval = window if window.size and window[-1] == nxt else np.append(window, nxt)
        kwargs: dict[str, Any] = {"method": method, "rtol": rtol, "atol": atol, "t_eval": t_eval}
        if method in ("LSODA", "Radau", "BDF"):
            kwargs["jac"] = jac
        if method == "LSODA":
            kwargs["first_step"] = min(1e-4, max(nxt - t, 1e-9) / 2)
        sol = solve_ivp(fun, (t, nxt), X, events=events or None, **kwargs)
        if sol.status == -1:
            raise SimulationError(f"integration failed at t = {sol.t[-1] if sol.t.size else t:.6g} s: {sol.message}")
        is_sample = np.isin(sol.t, window)
        if np.any(is_sample):
            out_t.append(sol.t[is_sample])
            out_X.append(sol.y[:, is_sample].T)
            out_stuck.append(np.full(int(is_sample.sum()), 1.0 if current.stuck else 0.0))
            out_dir.append(np.full(int(is_sample.sum()), current.direction))
        if sol.status == 1:
            switches += 1
            if switches > _MAX_SWITCHES:
                raise SimulationError(f"more than {_MAX_SWITCHES} stick/slip transitions by t = {t:.6g} s (chattering)")
            t_event = float(sol.t_events[0][0])
            X = np.asarray(sol.y_events[0][0], dtype=float).copy()
            if current.stuck:  # breakaway: slip against the friction that could not hold
                mode = _Mode(False, -math.copysign(1.0, loop.friction_needed(t_event, X)))
            else:  # the hub stopped
                X[n1] = 0.0
                mode = loop.settle_mode(t_event, X)
                stuck_intervals += int(mode.stuck)
            t = max(t_event, t + 1e-15)
            continue
        t = nxt
        X = np.asarray(sol.y[:, -1], dtype=float).copy()  # the state at nxt (last of t_eval)
        if t >= ctrl.next_decision(t - 1e-12) - 1e-12:
            ctrl.decide(t, X)
        if friction.active and (mode.stuck or X[n1] == 0.0):  # the torque may have jumped here
            mode = loop.settle_mode(t, X)

    T = np.concatenate(out_t)
    Xs = np.vstack(out_X)
    stuck = np.concatenate(out_stuck).astype(bool)
    direction = np.concatenate(out_dir)
    return _assemble(model, inversion, ctrl, sim_plant, friction, T, Xs, stuck, direction, plant, controller,
                     t0, tf, t_end, settling_band, switches, stuck_intervals)


def _assemble(
    model: Model,
    inversion: InversionResult | None,
    ctrl: Controller,
    sim_plant: Plant,
    friction: HubFriction,
    T: FloatArray,
    Xs: FloatArray,
    stuck: NDArray[np.bool_],
    direction: FloatArray,
    plant: str,
    controller: str,
    t0: float,
    tf: float,
    t_end: float,
    settling_band: float,
    switches: int,
    stuck_intervals: int,
) -> SimulationResult:
    n1 = model.n + 1
    y = Xs[:, :n1] @ model.D
    tau = np.array([ctrl.torque(ti, xi, n1)[0] for ti, xi in zip(T, Xs)])
    fric = np.where(stuck, 0.0, -direction * friction.coulomb)
    if np.any(stuck):
        fric[stuck] = [sim_plant.holding_torque(xi)[0] - ti for xi, ti in zip(Xs[stuck], tau[stuck])]
    if inversion is not None:
        traj = inversion.trajectory
        y_final = float(traj.derivative([tf], 0)[0])
        y_d = np.where(T <= tf, traj.derivative(np.minimum(T, tf), 0), y_final)
        during = T <= tf
        y_redef = np.full(T.size, y_final)
        if np.any(during):
            y_redef[during] = inversion.evaluate(T[during])["y"]
        move = abs(y_final - float(traj.derivative([t0], 0)[0]))
    else:
        y_final = 0.0
        y_d = np.zeros(T.size)
        y_redef = np.zeros(T.size)
        move = 0.0
    band = settling_band * move
    during = T <= tf
    # steady state: the mean tip error and the vibration about it over the last second
    window = T >= max(tf, T[-1] - 1.0)
    steady = float(abs(y_final - y[window].mean())) if np.any(window) else float("nan")
    vibration = float(np.ptp(y[window]) / 2) if np.any(window) else float("nan")
    summary: dict[str, Any] = {
        "model": model.name,
        "plant": plant,
        "controller": controller,
        "kp": ctrl.kp,
        "kd": ctrl.kd,
        "coulomb_friction": friction.coulomb,
        "breakaway_friction": friction.breakaway,
        "friction_compensation": ctrl.friction_compensation,
        "t_final_manoeuvre": tf,
        "t_end": t_end,
        "final_tip_error": float(abs(y_final - y[-1])),
        "final_tip_error_signed": float(y_final - y[-1]),
        "steady_tip_error": steady,
        "residual_vibration": vibration,
        "steady_window": [float(T[window][0]), float(T[-1])] if np.any(window) else None,
        "max_tracking_error": float(np.abs(y - y_d).max()),
        "max_redefined_tracking_error": float(np.abs(y[during] - y_redef[during]).max()) if np.any(during) else 0.0,
        "peak_torque": float(np.abs(tau).max()),
        "settling_band": band,
        "settling_time": _settling_time(T, y, y_final, band, tf) if band > 0 else None,
        "stick_slip_transitions": switches,
        "times_stuck": stuck_intervals,
        "pulses": [{"start": s, "width": w, "torque": a} for s, w, a in ctrl.pulses],
        "final_energy": sim_plant.energy(Xs[-1]),
        "samples": int(T.size),
    }
    return SimulationResult(
        t=T,
        X=Xs,
        y=y,
        y_d=y_d,
        y_redef=y_redef,
        theta=Xs[:, 0],
        thetadot=Xs[:, n1],
        deflections=Xs[:, 1:n1],
        tau=tau,
        friction=fric,
        stuck=stuck,
        summary=summary,
    )

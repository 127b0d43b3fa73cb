"""Controllers of the closed loop: feedforward plus joint PD (Eq. (40)) and the two-stage controller.

* ``none`` -- the feedforward ``tau_l`` alone during the manoeuvre, nothing after.
* ``pd`` -- ``tau = tau_l + k_P (theta_d - theta) + k_D (thetadot_d - thetadot)`` during
  the manoeuvre (``theta_d, thetadot_d`` of the redefined state), plus the measured
  average dry friction ``F_hat sign(thetadot_d)`` (friction compensation, section 8);
  after ``t_f`` the PD alone on ``theta_d = y_d(t_f)/L``, ``thetadot_d = 0``.
* ``two-stage`` -- stage 1 as ``pd``; stage 2 (after ``t_f``) pulse-width control:
  see :class:`PulseWidthLaw`.

The pulse law (the paper gives no details, see its reference [26]): at each decision
time the hub error ``e = theta_d - theta`` is measured. If ``L |e|`` is within
``tolerance`` the controller stops (zero torque). Otherwise it applies a torque pulse of
amplitude ``amplitude`` in the direction of ``e`` and width::

    w = gain sqrt(2 |e| / (a1 (1 + a1/a2))),   a1 = (amplitude - F_c)/J,  a2 = F_c/J

the width that would move a rigid hub of inertia ``J`` (``M[0,0]``) by ``gain |e|`` --
accelerate with ``a1`` while the pulse lasts, then coast against the friction with
``a2`` -- clipped to ``[min_width, max_width]``. The width grows with the error; ``gain <
1`` undershoots so that the pulses converge from one side. The next decision is
``period`` after the pulse started (the hub has stuck again by then), up to
``max_pulses`` pulses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import CubicSpline

from .errors import SettingsError

__all__ = ["PulseWidthLaw", "Reference", "Controller", "ControllerKind"]

FloatArray = NDArray[np.float64]
ControllerKind = Literal["none", "pd", "two-stage"]


@dataclass(frozen=True)
class PulseWidthLaw:
    """Parameters of the stage-2 pulse-width control (see the module docstring).

    Attributes
    ----------
    amplitude : float
        Pulse torque (N m); must exceed the breakaway friction.
    gain : float
        Fraction of the error one pulse aims to remove, in (0, 1].
    tolerance : float
        Stop when the tip-equivalent hub error ``L |e|`` is below this (m).
    period : float
        Time between decisions (s): pulse plus settling.
    min_width, max_width : float
        Limits of the pulse width (s).
    max_pulses : int
        Upper bound on the number of pulses.
    """

    amplitude: float = 0.9
    gain: float = 0.8
    tolerance: float = 2e-4
    period: float = 0.25
    min_width: float = 1e-3
    max_width: float = 0.1
    max_pulses: int = 40

    def __post_init__(self) -> None:
        checks = [
            ("pulse amplitude", self.amplitude, self.amplitude > 0, "a number > 0 (N m)"),
            ("pulse gain", self.gain, 0 < self.gain <= 1, "a number in (0, 1]"),
            ("pulse tolerance", self.tolerance, self.tolerance > 0, "a number > 0 (m)"),
            ("pulse period", self.period, self.period > 0, "a number > 0 (s)"),
            ("pulse min_width", self.min_width, self.min_width > 0, "a number > 0 (s)"),
            ("pulse max_width", self.max_width, self.min_width <= self.max_width < self.period, "min_width <= max_width < period"),
            ("pulse max_pulses", self.max_pulses, self.max_pulses >= 1, "an integer >= 1"),
        ]
        for name, value, ok, accepted in checks:
            if not (isinstance(value, (int, float)) and math.isfinite(value) and ok):
                raise SettingsError(name, value, accepted)

    def width(self, error: float, inertia: float, coulomb: float) -> float:
        """Pulse width for a hub error ``error`` (rad)."""
        a1 = (self.amplitude - coulomb) / inertia
        a2 = max(coulomb, 1e-12) / inertia
        w = self.gain * math.sqrt(2 * abs(error) / (a1 * (1 + a1 / a2)))
        return min(max(w, self.min_width), self.max_width)


class Reference:
    """The feedforward ``tau_l`` and the references ``theta_d, thetadot_d`` as functions of time.

    Sampled from the inversion's closed form on a grid fine enough for the fastest
    exponential and interpolated by one vector-valued cubic spline (interpolation error
    ~ (dt |lambda|)^4 / 384, below 1e-9 of the values here).
    """

    def __init__(self, result: Any):
        rates = [abs(result.modal.lam).max()] + [abs(s.mu).max() for s in result.segments]
        dt = min(1e-4, 0.02 / max(max(rates), 1e-9))
        t0, tf = float(result.t[0]), float(result.t[-1])
        grid = np.linspace(t0, tf, int(math.ceil((tf - t0) / dt)) + 1)
        ev = result.evaluate(grid)
        n1 = result.model.n + 1
        values = np.column_stack([ev["tau"], ev["X"][:, 0], ev["X"][:, n1]])
        self.spline = CubicSpline(grid, values)
        self.t0, self.tf = t0, tf
        self.grid = grid
        self.thetadot_grid = values[:, 2]
        L = result.model.geometry.length
        self.theta_final = float(result.trajectory.derivative([tf], 0)[0]) / L
        #: below this |thetadot_d| the desired motion has no direction (rounding noise at rest)
        self.deadband = 1e-6 * float(np.abs(self.thetadot_grid).max(initial=0.0))

    def __call__(self, t: float) -> FloatArray:
        """``[tau_l, theta_d, thetadot_d]`` at ``t`` in ``[t0, tf]``."""
        return np.asarray(self.spline(t))

    def direction(self, thetadot_d: float) -> float:
        """Direction of the desired motion: ``sign(thetadot_d)``, 0 inside the deadband."""
        return 0.0 if abs(thetadot_d) <= self.deadband else math.copysign(1.0, thetadot_d)

    def direction_changes(self) -> list[float]:
        """Times where the direction of the desired motion changes (the friction compensation switches)."""
        v = self.thetadot_grid
        out = []
        for level in (self.deadband, -self.deadband):
            s = np.sign(v - level)
            for i in np.flatnonzero(s[:-1] * s[1:] < 0):
                a, b = self.grid[i], self.grid[i + 1]
                va, vb = v[i] - level, v[i + 1] - level
                out.append(float(a - va * (b - a) / (vb - va)))
        return sorted(out)


@dataclass
class Controller:
    """The control law of a simulation (see the module docstring).

    Attributes
    ----------
    kind : {"none", "pd", "two-stage"}
    reference : Reference or None
        The feedforward (``None``: no manoeuvre, zero torque).
    kp, kd : float
        Joint PD gains (N m/rad, N m s/rad).
    friction_compensation : float
        ``F_hat`` added as ``F_hat sign(thetadot_d)`` during the manoeuvre (N m).
    pulse : PulseWidthLaw
        Stage-2 law of the two-stage controller.
    inertia, coulomb, length : float
        Rigid-body inertia ``M[0,0]``, Coulomb friction and link length (for the pulse law).
    external : callable, optional
        A torque added at the joint, ``external(t)`` (a load, a test input).
    """

    kind: ControllerKind
    reference: Reference | None
    kp: float = 0.0
    kd: float = 0.0
    friction_compensation: float = 0.0
    pulse: PulseWidthLaw = field(default_factory=PulseWidthLaw)
    inertia: float = 1.0
    coulomb: float = 0.0
    length: float = 1.0
    external: Callable[[float], float] | None = None
    theta_hold: float = 0.0
    pulses: list[tuple[float, float, float]] = field(default_factory=list)  # (start, width, torque)
    done: bool = False

    def __post_init__(self) -> None:
        if self.kind not in ("none", "pd", "two-stage"):
            raise SettingsError("controller", self.kind, "'none', 'pd' or 'two-stage'")
        for name, value in (("kp", self.kp), ("kd", self.kd), ("friction_compensation", self.friction_compensation)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise SettingsError(name, value, "a finite number >= 0")
        if self.kind == "two-stage" and self.pulse.amplitude <= self.coulomb:
            raise SettingsError("pulse amplitude", self.pulse.amplitude, f"a torque above the friction {self.coulomb:g} N m")
        if self.reference is not None:
            self.theta_hold = self.reference.theta_final

    @property
    def t_final(self) -> float:
        """End of the manoeuvre (``-inf`` without one)."""
        return self.reference.tf if self.reference is not None else -math.inf

    def breakpoints(self) -> list[float]:
        """Known discontinuities of the torque during the manoeuvre."""
        if self.reference is None:
            return []
        points = [self.reference.tf]
        if self.friction_compensation > 0:
            points += self.reference.direction_changes()
        return sorted(points)

    def torque(self, t: float, X: FloatArray, n1: int) -> tuple[float, FloatArray]:
        """Motor torque at ``(t, X)`` (plus the external torque) and its gradient with respect to ``X``."""
        tau, grad = self._law(t, X, n1)
        if self.external is not None:
            tau += float(self.external(t))
        return tau, grad

    def _law(self, t: float, X: FloatArray, n1: int) -> tuple[float, FloatArray]:
        grad = np.zeros(X.size)
        if self.reference is not None and t < self.reference.tf:
            tau_l, theta_d, thetadot_d = self.reference(t)
            if self.kind == "none":
                return float(tau_l), grad
            tau = tau_l + self.kp * (theta_d - X[0]) + self.kd * (thetadot_d - X[n1])
            if self.friction_compensation > 0:
                tau += self.friction_compensation * self.reference.direction(float(thetadot_d))
            grad[0], grad[n1] = -self.kp, -self.kd
            return float(tau), grad
        if self.kind == "pd" and self.reference is not None:
            grad[0], grad[n1] = -self.kp, -self.kd
            return float(self.kp * (self.theta_hold - X[0]) - self.kd * X[n1]), grad
        if self.kind == "two-stage":
            for start, width, amp in reversed(self.pulses):
                if start <= t < start + width:
                    return amp, grad
                if start <= t:
                    break
        return 0.0, grad

    def next_decision(self, t: float) -> float:
        """The next time the two-stage controller acts (``inf`` when it does not)."""
        if self.kind != "two-stage" or self.reference is None or self.done:
            return math.inf
        if t < self.t_final:
            return self.t_final
        if not self.pulses:
            return self.t_final
        start, width, _ = self.pulses[-1]
        return start + width if t < start + width else start + self.pulse.period

    def decide(self, t: float, X: FloatArray) -> None:
        """At a decision time of stage 2: measure the hub error, start a pulse or stop."""
        if self.kind != "two-stage" or self.done or t < self.t_final:
            return
        if self.pulses:
            start, width, _ = self.pulses[-1]
            if t < start + self.pulse.period - 1e-12:
                return  # end of a pulse: coast until the period is over
        error = self.theta_hold - float(X[0])
        if self.length * abs(error) <= self.pulse.tolerance or len(self.pulses) >= self.pulse.max_pulses:
            self.done = True
            return
        width = self.pulse.width(error, self.inertia, self.coulomb)
        self.pulses.append((t, width, math.copysign(self.pulse.amplitude, error)))

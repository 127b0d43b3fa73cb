"""The references of the closed loop: feedforward, joint angle and rate, desired tip velocity.

While the feedforward acts the controller needs ``tau_l(t)`` (Eq. (12)), the joint angle and
rate of the redefined state ``theta_d(t), thetadot_d(t)`` (the PD references of Eq. (40)) and
the desired tip velocity ``ydot_d(t)`` (the direction of the friction compensation). They are
the signals the inversion feeds forward (``InversionResult.signals``: the series its samples
and its exported C evaluate, over its whole span -- a stable inversion's pre- and
post-actuation, a settle end's tail), sampled interval by interval and interpolated by one
cubic B-spline per interval (not-a-knot, SciPy), joined into one B-spline with a break at
every joint so that a jump of a derivative at a joint costs no accuracy. The sample spacing is
``0.02 / omega`` for the fastest rate ``omega`` of the redefinition (its exponentials and the
zeros of the model), which bounds the interpolation error by ``5 (0.02)^4 / 384 ~ 2e-9`` of each
component's size (docs/method.md section 6).

A result sampled with ``hold="zoh"`` is a controller's table: the references are then held,
one value a period (a B-spline of degree 0 on the period grid), the torque the period's mean.

The B-spline is handed to CasADi as it is (:meth:`Reference.casadi`): knots and
coefficients, nothing fitted twice.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import BSpline, make_interp_spline

from inversion.result import InversionResult
from modelgen.model import Model

__all__ = ["Reference", "REFERENCE_COMPONENTS"]

FloatArray = NDArray[np.float64]

#: Components of the reference, in order.
REFERENCE_COMPONENTS = ("tau_l", "theta_d", "thetadot_d", "ydot_d")
#: Sample spacing times the fastest rate of the redefinition.
_SPACING = 0.02
#: Largest sample spacing (s), whatever the rates.
_MAX_SPACING = 1e-3
#: ``|ydot_d|`` below this fraction of its peak has no direction (rounding at rest).
DEADBAND = 1e-6


class Reference:
    """The references of an inversion as one B-spline.

    The references of an inversion as one B-spline: piecewise cubic, or held (degree 0) for a held table.

    Parameters
    ----------
    inversion : InversionResult
        A result of :func:`inversion.invert` with the link's signals (its series are sampled).

    Attributes
    ----------
    t0, tf : float
        Start and end of the feedforward (s): the manoeuvre's, or its pre- and post-actuation.
    theta_final : float
        ``y_d(t_f) / L``, the joint angle the PD holds after the manoeuvre (rad).
    spacing : float
        Sample spacing (s; the period of a held table).
    held : bool
        Whether the references are a controller's held table (``hold="zoh"``).
    deadband : float
        ``|ydot_d|`` at or below this has no direction (m/s).
    direction : float
        ``+1`` or ``-1``: the direction of the desired motion at the start (the first
        ``ydot_d`` outside the deadband); ``0`` for no motion.
    """

    def __init__(self, inversion: InversionResult):
        signals = inversion.signals
        model = inversion.model
        if signals is None or not isinstance(model, Model) or inversion.theta_d is None:
            raise ValueError("the closed-loop reference samples a link's feedforward signals (its torque, joint angle and rate)")
        traj = inversion.trajectory
        settings = inversion.summary.get("settings", {})
        self.held = settings.get("hold") == "zoh"
        if self.held:
            self._held_table(inversion)
        else:
            rates = [float(np.abs(inversion.modal.lam).max(initial=0.0))]
            rates += [float(np.abs(s.mu).max(initial=0.0)) for s in inversion.segments]
            self.spacing = min(_MAX_SPACING, _SPACING / max(max(rates), 1e-9))
            self._splines(signals, traj)
        self.t0, self.tf = float(signals.bounds[0]), float(self.knots[-1] if self.held else signals.bounds[-1])
        self.theta_final = float(traj.derivative([traj.tf], 0)[0]) / model.output_at  # at rest y = x_out theta
        ydot = traj.derivative(np.linspace(traj.t0, traj.tf, 4001), 1)
        ydot_peak = float(np.abs(ydot).max())
        moving = np.flatnonzero(np.abs(ydot) > DEADBAND * max(ydot_peak, 1e-300))
        self.deadband = DEADBAND * ydot_peak
        self.direction = 0.0 if not moving.size or ydot_peak == 0.0 else math.copysign(1.0, float(ydot[moving[0]]))

    def _splines(self, signals: Any, traj: Any) -> None:
        """One cubic B-spline per interval of the series, joined."""
        knots: list[FloatArray] = []
        coefficients: list[FloatArray] = []
        for k in range(signals.bounds.size - 1):
            a, b = float(signals.bounds[k]), float(signals.bounds[k + 1])
            count = max(4, int(math.ceil((b - a) / self.spacing)) + 1)
            t = np.linspace(a, b, count)
            inside = np.clip(t, a, np.nextafter(b, a))  # the interval's own series at its end
            values = signals.evaluate(inside)
            ydot_d = traj.derivative(np.clip(t, traj.t0, traj.tf), 1)
            columns = np.column_stack([values["tau"], values["theta_d"], values["thetadot_d"], ydot_d])
            spline = make_interp_spline(t, columns, k=3)
            knots.append(spline.t if k == 0 else spline.t[4:])
            coefficients.append(spline.c)
        self.degree = 3
        self.knots = np.concatenate(knots)
        self.coefficients = np.vstack(coefficients)
        self.spline = BSpline(self.knots, self.coefficients, 3, extrapolate=False)

    def _held_table(self, inversion: InversionResult) -> None:
        """The controller's table held over each period: a B-spline of degree 0 on the period grid."""
        t = np.asarray(inversion.t, dtype=float)
        period = float(inversion.summary["settings"]["period"])
        traj = inversion.trajectory
        ydot_d = traj.derivative(np.clip(t, traj.t0, traj.tf), 1)
        assert inversion.theta_d is not None and inversion.thetadot_d is not None
        self.spacing = period
        self.degree = 0
        self.knots = np.append(t, t[-1] + period)
        self.coefficients = np.column_stack([inversion.tau, inversion.theta_d, inversion.thetadot_d, ydot_d])
        self.spline = BSpline(self.knots, self.coefficients, 0, extrapolate=False)

    @property
    def size(self) -> int:
        """Number of B-spline coefficients per component."""
        return int(self.coefficients.shape[0])

    def __call__(self, t: ArrayLike) -> FloatArray:
        """``[tau_l, theta_d, thetadot_d, ydot_d]`` at times in ``[t0, tf]``, one row per time."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.t0, np.nextafter(self.tf, self.t0) if self.held else self.tf)
        return np.asarray(self.spline(t), dtype=float)

    def casadi(self) -> Any:
        """The same B-spline as a CasADi function of ``t``.

        The same B-spline as a CasADi function ``t -> [tau_l, theta_d, thetadot_d, ydot_d]``.

        A held table is a staircase: CasADi's linear interpolant on each period's start and its
        end less a nanosecond (its B-spline of degree 0 cannot be differentiated: CasADi 3.8
        corrupts memory in that derivative with thousands of knots).
        """
        if self.held:
            starts, period = self.knots[:-1], self.spacing
            grid = np.empty(2 * starts.size)
            grid[0::2], grid[1::2] = starts, starts + period * (1 - 1e-9)
            values = np.repeat(self.coefficients, 2, axis=0)
            return ca.interpolant("sflm_reference", "linear", [grid.tolist()], values.ravel().tolist(), {})
        return ca.Function.bspline(
            "sflm_reference", [self.knots.tolist()], self.coefficients.ravel().tolist(), [self.degree], len(REFERENCE_COMPONENTS), {}
        )

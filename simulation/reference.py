"""The references of the closed loop: feedforward, joint angle and rate, desired tip velocity.

During the manoeuvre the controller needs ``tau_l(t)`` (Eq. (12)), the redefined joint
angle and rate ``theta_d(t), thetadot_d(t)`` (the PD references of Eq. (40)) and the
desired tip velocity ``ydot_d(t)`` (the direction of the friction compensation). They
are sampled from the inversion's closed form, segment by segment, and interpolated by
one cubic B-spline per segment (not-a-knot, SciPy), joined into one B-spline with a
break at every joint so that a jump of a derivative at a joint costs no accuracy. The
sample spacing is ``0.02 / omega`` for the fastest rate ``omega`` of the redefinition
(its exponentials and the zeros of the model), which bounds the interpolation error by
``5 (0.02)^4 / 384 ~ 2e-9`` of each component's size (docs/method.md section 6).

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
    """The references of an inversion as one piecewise-cubic B-spline.

    Parameters
    ----------
    inversion : InversionResult
        A result of :func:`inversion.invert` (its closed form is sampled).

    Attributes
    ----------
    t0, tf : float
        Start and end of the manoeuvre (s).
    theta_final : float
        ``y_d(t_f) / L``, the joint angle the PD holds after the manoeuvre (rad).
    spacing : float
        Sample spacing (s).
    deadband : float
        ``|ydot_d|`` at or below this has no direction (m/s).
    direction : float
        ``+1`` or ``-1``: the direction of the desired motion at the start (the first
        ``ydot_d`` outside the deadband); ``0`` for no motion.
    """

    def __init__(self, inversion: InversionResult):
        redef = inversion.redefinition
        if redef is None:
            raise ValueError("the inversion has no closed form (redefinition) to sample")
        model = inversion.model
        if not isinstance(model, Model):
            raise ValueError("the closed-loop reference samples a link's inversion (its joint angle and rate)")
        n1 = model.n + 1
        rates = [float(np.abs(inversion.modal.lam).max(initial=0.0))]
        rates += [float(np.abs(s.mu).max(initial=0.0)) for s in inversion.segments]
        rate = max(max(rates), 1e-9)
        self.spacing = min(_MAX_SPACING, _SPACING / rate)
        joints = inversion.joints
        traj = inversion.trajectory
        knots: list[FloatArray] = []
        coefficients: list[FloatArray] = []
        ydot_peak = 0.0
        first_motion: float | None = None
        for k in range(joints.size - 1):
            a, b = float(joints[k]), float(joints[k + 1])
            count = max(4, int(math.ceil((b - a) / self.spacing)) + 1)
            local = np.linspace(0.0, b - a, count)
            values = redef.evaluate_local(k, local)
            t = a + local
            t[-1] = b
            ydot_d = traj.derivative(np.clip(t, traj.t0, traj.tf), 1)
            columns = np.column_stack([
                np.asarray(values["tau"], dtype=float),
                np.asarray(values["X"][:, 0], dtype=float),
                np.asarray(values["X"][:, n1], dtype=float),
                ydot_d,
            ])
            spline = make_interp_spline(t, columns, k=3)
            knots.append(spline.t if k == 0 else spline.t[4:])
            coefficients.append(spline.c)
            ydot_peak = max(ydot_peak, float(np.abs(ydot_d).max()))
            if first_motion is None:
                moving = np.flatnonzero(np.abs(ydot_d) > DEADBAND * max(float(np.abs(ydot_d).max()), 1e-300))
                if moving.size:
                    first_motion = float(ydot_d[moving[0]])
        self.knots = np.concatenate(knots)
        self.coefficients = np.vstack(coefficients)
        self.spline = BSpline(self.knots, self.coefficients, 3, extrapolate=False)
        self.t0, self.tf = float(joints[0]), float(joints[-1])
        self.theta_final = float(traj.derivative([self.tf], 0)[0]) / model.output_at  # at rest y = x_out theta
        self.deadband = DEADBAND * ydot_peak
        self.direction = 0.0 if first_motion is None or ydot_peak == 0.0 else math.copysign(1.0, first_motion)

    @property
    def size(self) -> int:
        """Number of B-spline coefficients per component."""
        return int(self.coefficients.shape[0])

    def __call__(self, t: ArrayLike) -> FloatArray:
        """``[tau_l, theta_d, thetadot_d, ydot_d]`` at times in ``[t0, tf]``, one row per time."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.t0, self.tf)
        return np.asarray(self.spline(t), dtype=float)

    def casadi(self) -> Any:
        """The same B-spline as a CasADi function ``t -> [tau_l, theta_d, thetadot_d, ydot_d]``."""
        return ca.Function.bspline(
            "sflm_reference", [self.knots.tolist()], self.coefficients.ravel().tolist(), [3], len(REFERENCE_COMPONENTS), {}
        )

"""Controllers of the closed loop: feedforward plus joint PD (Eq. (40)), friction compensation, pulse-width control.

* ``none`` -- the feedforward ``tau_l`` alone during the manoeuvre, nothing after.
* ``pd`` -- ``tau = tau_l + k_P (theta_d - theta) + k_D (thetadot_d - thetadot)`` during
  the manoeuvre (``theta_d, thetadot_d`` of the redefined state), plus the compensation
  ``F_hat sign(ydot_d)`` of the known average dry friction in the direction of the
  desired tip motion (section 8 of the paper); after ``t_f`` the PD alone on
  ``theta_d = y_d(t_f)/L``, ``thetadot_d = 0``.
* ``two-stage`` -- stage 1 as ``pd``; stage 2 (after ``t_f``) pulse-width control, see
  :class:`PulseWidthLaw`.

Gains. Without gains of its own (the paper's cases have theirs, :mod:`modelgen.paper`),
a link gets PD gains by one documented rule (:func:`default_gains`): the rigid-body
loop ``J s^2 + k_D s + k_P`` critically damped at a tenth of the first flexible natural
frequency, ``k_P = J omega_c^2``, ``k_D = 2 J omega_c``, ``omega_c = omega_1 / 10`` with
``J = M[0, 0]`` (hub, link and payload about the joint). A joint PD is collocated, so
it cannot destabilise the linear model whatever the gains; the rule keeps the loop a
decade below the first flexible mode so that the PD does not excite it.

The pulse law (the paper gives no details, see its reference [26]): at each decision
time the hub error ``e = theta_d - theta`` is measured. If ``L |e|`` is within
``tolerance`` the controller stops (zero torque for good). Otherwise it applies a torque
pulse of amplitude ``amplitude`` in the direction of ``e`` and width::

    w = gain sqrt(2 |e| / (a1 (1 + a1/a2))),   a1 = (amplitude - F_hat)/J,  a2 = F_hat/J

the width that would move a rigid hub of inertia ``J`` by ``gain |e|`` -- accelerate
with ``a1`` while the pulse lasts, then coast against the friction with ``a2`` --
clipped to ``[min_width, max_width]``. ``gain < 1`` undershoots so that the pulses
converge from one side. Decisions are ``period`` apart (the hub has stuck again by
then), at most ``max_pulses`` pulses. The defaults follow rules stated in
:meth:`PulseWidthLaw.for_link`: twice the known friction, 0.2 % of the move.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, Literal

from modelgen.joint_pd import BANDWIDTH_FRACTION, rule_gains
from modelgen.errors import SettingsError
from modelgen.model import Model

__all__ = ["PulseWidthLaw", "Controller", "ControllerKind", "Gains", "default_gains", "BANDWIDTH_FRACTION"]

ControllerKind = Literal["none", "pd", "two-stage"]
CONTROLLERS = ("none", "pd", "two-stage")



def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


@dataclass(frozen=True)
class Gains:
    """Joint PD gains and where they came from.

    Attributes
    ----------
    kp : float
        Proportional gain (N m/rad).
    kd : float
        Derivative gain (N m s/rad).
    source : str
        The paper's section, the rule that gave them, or the caller.
    """

    kp: float
    kd: float
    source: str

    def __post_init__(self) -> None:
        for name, value in (("kp", self.kp), ("kd", self.kd)):
            if not (_finite(value) and value >= 0):
                raise SettingsError(name, value, "a finite number >= 0")


def default_gains(model: Model) -> Gains:
    """PD gains by this module's rule.

    PD gains by the rule of this module: rigid-body poles critically damped at ``omega_1 / 10``.

    Parameters
    ----------
    model : Model
        The model (its ``M[0, 0]`` and first flexible natural frequency).

    Returns
    -------
    Gains
        ``k_P = J omega_c^2``, ``k_D = 2 zeta J omega_c`` with ``omega_c = omega_1 / 10``,
        ``zeta = 1``.

    Examples
    --------
    >>> import modelgen
    >>> g = default_gains(modelgen.load("paper-sim"))
    >>> round(g.kp, 3), round(g.kd, 3)
    (12.734, 6.126)
    """
    J = float(model.M[0, 0])
    omega_1 = 2 * math.pi * float(model.natural_frequencies_hz[0])
    omega_c = BANDWIDTH_FRACTION * omega_1
    rule = (f"rule: rigid-body poles critically damped at omega_1/10 = {omega_c:.4g} rad/s "
            f"(J = M[0,0] = {J:.4g} kg m^2); k_P = J omega_c^2, k_D = 2 J omega_c")
    return Gains(*rule_gains(J, omega_1), rule)


@dataclass(frozen=True)
class PulseWidthLaw:
    """Parameters of the stage-2 pulse-width control.

    Attributes
    ----------
    amplitude : float
        Pulse torque (N m); must exceed the friction the controller knows.
    gain : float
        Fraction of the error one pulse aims to remove, in (0, 1].
    tolerance : float
        Stop when the tip-equivalent hub error ``L |e|`` is at most this (m).
    period : float
        Time between decisions (s): pulse plus settling.
    min_width, max_width : float
        Limits of the pulse width (s).
    max_pulses : int
        Upper bound on the number of pulses.
    source : str
        Where the values came from.
    """

    amplitude: float
    gain: float = 0.8
    tolerance: float = 2e-4
    period: float = 0.25
    min_width: float = 1e-3
    max_width: float = 0.1
    max_pulses: int = 40
    source: str = "given by the caller"

    def __post_init__(self) -> None:
        checks = [
            ("pulse_amplitude", self.amplitude, self.amplitude > 0 if _finite(self.amplitude) else False, "a number > 0 (N m)"),
            ("pulse_gain", self.gain, 0 < self.gain <= 1 if _finite(self.gain) else False, "a number in (0, 1]"),
            ("pulse_tolerance", self.tolerance, self.tolerance > 0 if _finite(self.tolerance) else False, "a number > 0 (m)"),
            ("pulse_period", self.period, self.period > 0 if _finite(self.period) else False, "a number > 0 (s)"),
            ("pulse_min_width", self.min_width, self.min_width > 0 if _finite(self.min_width) else False, "a number > 0 (s)"),
            ("pulse_max_width", self.max_width,
             self.min_width <= self.max_width < self.period if _finite(self.max_width) else False,
             f"a width in [min_width, period) = [{self.min_width:g}, {self.period:g}) s"),
            ("pulse_max_pulses", self.max_pulses, isinstance(self.max_pulses, int) and 1 <= self.max_pulses <= 100_000,
             "an integer in 1..100000"),
        ]
        for name, value, ok, accepted in checks:
            if not ok:
                raise SettingsError(name, value, accepted)

    @classmethod
    def for_link(cls, known_friction: float, move: float, **given: Any) -> "PulseWidthLaw":
        """The law with its defaults by rule, ``given`` values (``None`` ignored) taking precedence.

        Rules: ``amplitude = 2 F_hat`` (twice the friction the controller knows, so that
        the pulse's net acceleration equals the braking one); ``tolerance = 0.2 %`` of the
        move (at least 1 um); ``gain 0.8``, ``period 0.25 s``, widths ``1 ms .. 0.1 s``,
        40 pulses. For the paper's experiment (``F_hat = 0.45 N m``, 0.1 m) these give
        0.9 N m and 0.2 mm.
        """
        values = {k: v for k, v in given.items() if v is not None}
        rule = {"amplitude": 2.0 * known_friction, "tolerance": max(2e-3 * abs(move), 1e-6)}
        by_rule = [k for k in rule if k not in values]
        values = {**rule, **values}
        source = "given by the caller"
        if by_rule:
            source = ("rule: " + ", ".join({"amplitude": "amplitude = 2 F_hat", "tolerance": "tolerance = 0.2 % of the move"}[k]
                                           for k in by_rule) + ("; the rest given" if len(values) > len(by_rule) else ""))
        return cls(**values, source=source)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return asdict(self)

    def width(self, error: float, inertia: float, friction: float) -> float:
        """Pulse width for a hub error.

        Pulse width for a hub error (NumPy; the closed loop uses the same formula in CasADi).

        Parameters
        ----------
        error : float
            The hub's angle error (rad).
        inertia : float
            The inertia the pulse turns (kg m^2).
        friction : float
            The dry friction it works against (N m).
        """
        a1 = (self.amplitude - friction) / inertia
        a2 = max(friction, 1e-12) / inertia
        w = self.gain * math.sqrt(2 * abs(error) / (a1 * (1 + a1 / a2)))
        return min(max(w, self.min_width), self.max_width)


@dataclass(frozen=True)
class Controller:
    """The control law of a simulation (see the module docstring).

    Attributes
    ----------
    kind : {"none", "pd", "two-stage"}
    gains : Gains
        Joint PD gains.
    friction_compensation : float
        ``F_hat``, added as ``F_hat sign(ydot_d)`` during the manoeuvre (N m).
    known_friction : float
        The dry friction the controller assumes (the pulse law's ``F_hat``): the
        compensation if any, else the model's ``F_c``.
    pulse : PulseWidthLaw or None
        Stage-2 law (two-stage only).
    external_torque : float
        A constant torque added at the joint (a load, a test input) (N m).
    compensation_source : str
        Where ``friction_compensation`` came from.
    """

    kind: ControllerKind
    gains: Gains
    friction_compensation: float = 0.0
    known_friction: float = 0.0
    pulse: PulseWidthLaw | None = None
    external_torque: float = 0.0
    compensation_source: str = field(default="given by the caller")

    def __post_init__(self) -> None:
        if self.kind not in CONTROLLERS:
            raise SettingsError("controller", self.kind, "'none', 'pd' or 'two-stage'")
        if not (_finite(self.friction_compensation) and self.friction_compensation >= 0):
            raise SettingsError("friction_compensation", self.friction_compensation, "a finite number >= 0 (N m)")
        if not _finite(self.external_torque):
            raise SettingsError("external_torque", self.external_torque, "a finite number (N m)")
        if self.kind == "two-stage":
            if self.pulse is None:
                raise SettingsError("pulse", None, "a pulse-width law for the two-stage controller")
            if not self.known_friction > 0:
                raise SettingsError("controller", self.kind, "'none' or 'pd' for a hub without dry friction: stage 2 of the "
                                    "two-stage controller relies on the friction stopping the hub between pulses "
                                    "(give friction_compensation=F or a geometry with hub.coulomb_friction > 0)")
            if self.pulse.amplitude <= self.known_friction:
                raise SettingsError("pulse_amplitude", self.pulse.amplitude,
                                    f"a torque above the friction the controller knows, {self.known_friction:g} N m")

    def block(self) -> dict[str, Any]:
        """The controller part of a simulation summary."""
        out: dict[str, Any] = {
            "kind": self.kind,
            "kp": self.gains.kp,
            "kd": self.gains.kd,
            "gains_source": self.gains.source,
            "friction_compensation": self.friction_compensation,
            "friction_compensation_source": self.compensation_source,
            "external_torque": self.external_torque,
        }
        if self.pulse is not None:
            out["pulse_law"] = self.pulse.as_dict()
        return out


"""The closed loop as a hybrid system in CasADi: continuous state, discrete state, events, transitions.

The plant's state ``X`` is extended by a discrete state ``D`` (:data:`DISCRETE`) that the
right-hand side does not change (``Ddot = 0``) and that only events change:

* ``mode`` -- the hub's friction mode: ``+1``/``-1`` slipping in that direction, ``0``
  stuck (with dry friction; without, ``0`` means free).
* ``direction`` -- the sign of the desired tip velocity ``ydot_d`` that the friction
  compensation follows.
* ``pulse_torque``, ``next_decision``, ``pulse_end``, ``pulse_start``, ``pulse_width``,
  ``pulse_record`` (the last pulse's torque), ``pulses``, ``done`` -- stage 2 of the
  two-stage controller.
* ``stops``, ``sticks``, ``breakaways``, ``reversals`` -- counters of the events.

Events are zero crossings, from positive to negative, of the indicators :data:`EVENTS`:

* ``stop`` -- ``mode * thetadot`` (a slipping hub stops); then ``thetadot = 0`` and the
  hub sticks if the friction needed to hold it is within the breakaway level ``F_s``,
  else slips on in the direction the torque pushes.
* ``breakaway`` -- ``F_s - |F_needed|`` (a stuck hub's holding friction reaches ``F_s``);
  then it slips against that friction.
* ``direction`` -- ``direction * ydot_d + deadband`` (the desired motion reverses).
* ``decision`` -- ``next_decision - t`` (stage 2 measures the hub error, starts a pulse or stops).
* ``pulse_end`` -- ``pulse_end - t``.

Stuck, the friction supplies whatever torque keeps ``thetaddot = 0``: ``f`` is affine in
the net torque, ``f(X, tau) = f0(X) + tau b(X)``, so the holding torque is
``-f0_theta / b_theta`` and one pair ``f0, b`` serves every mode. After every event that
changes the torque a stuck hub is settled again (it breaks away at once if the new
torque needs more than ``F_s`` to be held).

One description serves both integrators of :mod:`simulation.integrate` (CasADi's CVODES
with its event location, and SciPy for cross-checking).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from .control import Controller
from .plant import Plant
from .reference import Reference

__all__ = ["HybridLoop", "Phase", "DISCRETE", "EVENTS", "PhaseName"]

FloatArray = NDArray[np.float64]
PhaseName = Literal["manoeuvre", "after"]

#: The discrete state, in order, after ``X``.
DISCRETE = ("mode", "direction", "pulse_torque", "next_decision", "pulse_end", "pulse_start", "pulse_width",
            "pulse_record", "pulses", "done", "stops", "sticks", "breakaways", "reversals")
#: The events, in the order of their indicators.
EVENTS = ("stop", "breakaway", "direction", "decision", "pulse_end")


@dataclass(frozen=True)
class Phase:
    """The CasADi functions of one phase of the closed loop.

    Attributes
    ----------
    name : {"manoeuvre", "after"}
    ode : casadi.Function
        ``(t, x) -> xdot``: the extended state's rate (the discrete part's is zero).
    events : tuple of str
        The events that can happen in this phase, in the order of ``indicators``.
    indicators : casadi.Function or None
        ``(t, x) -> g``: the event indicators (an event is ``g_k`` crossing from positive
        to non-positive); ``None`` when no event can happen.
    transition : casadi.Function or None
        ``(index, t, x) -> x``: the state after event ``index``.
    settle : casadi.Function
        ``(t, x) -> x``: a stuck hub that the torque at ``(t, x)`` breaks loose, slipping.
    outputs : casadi.Function
        ``(t, x) -> (tau, friction)``: motor torque and the dry-friction torque on the joint.
    """

    name: PhaseName
    ode: Any
    events: tuple[str, ...]
    indicators: Any
    transition: Any
    settle: Any
    outputs: Any

    def event_index(self, event: str) -> int:
        """Index of ``event`` among the phase's indicators.

        Parameters
        ----------
        event : str
            The event's name.
        """
        return self.events.index(event)


class HybridLoop:
    """The closed loop as CasADi functions.

    Parameters
    ----------
    plant : Plant
        The simulated plant.
    controller : Controller
        The control law.
    reference : Reference or None
        The references of the manoeuvre (``None``: no manoeuvre, only the ``after`` phase).
    length : float
        Where the model's output is measured (m; the link length for the tip): the pulse
        law's tolerance is on the output error ``x_out |e|`` of a joint error ``e``.
    inertia : float
        ``M[0, 0]`` of the model (kg m^2): the pulse law's rigid hub.
    """

    def __init__(self, plant: Plant, controller: Controller, reference: Reference | None, length: float, inertia: float):
        self.plant = plant
        self.controller = controller
        self.reference = reference
        self.length = float(length)
        self.inertia = float(inertia)
        self.n1 = plant.n1
        self.nx = 2 * self.n1
        self.size = self.nx + len(DISCRETE)
        self.theta_hold = reference.theta_final if reference is not None else 0.0
        self._rhs = plant.rhs()
        self._ref = reference.casadi() if reference is not None else None
        self._phases: dict[str, Phase] = {}

    def index(self, name: str) -> int:
        """Position of a discrete state in the extended state.

        Parameters
        ----------
        name : str
            The discrete state's name.
        """
        return self.nx + DISCRETE.index(name)

    def initial_state(self, X0: FloatArray, t0: float, phase: PhaseName) -> FloatArray:
        """The extended state at the start.

        The extended state at the start: ``X0``, the hub's friction mode settled, the motion's direction.

        Parameters
        ----------
        X0 : FloatArray
            The plant's initial state.
        t0 : float
            The start time (s).
        phase : PhaseName
            The first phase.
        """
        x = np.zeros(self.size)
        x[: self.nx] = X0
        thetadot = float(X0[self.n1])
        x[self.index("mode")] = 0.0 if thetadot == 0.0 or not self.plant.friction.active else np.sign(thetadot)
        x[self.index("direction")] = self.reference.direction if self.reference is not None else 0.0
        return self.settle(phase, t0, x)

    def settle(self, phase: PhaseName, t: float, x: FloatArray) -> FloatArray:
        """:attr:`Phase.settle` at ``(t, x)``.

        Parameters
        ----------
        phase : PhaseName
            The phase.
        t : float
            The time (s).
        x : FloatArray
            The extended state.
        """
        return np.asarray(self.phase(phase).settle(t, x), dtype=float).reshape(-1)

    def apply(self, phase: PhaseName, event: str, t: float, x: FloatArray) -> FloatArray:
        """The state after ``event`` at ``(t, x)``.

        The state after ``event`` at ``(t, x)`` (the start of stage 2 is a decision).

        Parameters
        ----------
        phase : PhaseName
            The phase.
        event : str
            The event's name.
        t : float
            The time (s).
        x : FloatArray
            The extended state.
        """
        ph = self.phase(phase)
        return np.asarray(ph.transition(ph.event_index(event), t, x), dtype=float).reshape(-1)

    def phase(self, name: PhaseName) -> Phase:
        """The CasADi pieces of phase ``name`` (built once).

        Parameters
        ----------
        name : PhaseName
            The phase's name.
        """
        if name not in self._phases:
            self._phases[name] = self._build(name)
        return self._phases[name]

    # -- the law ---------------------------------------------------------------------------

    def _torque(self, name: PhaseName, t: Any, x: Any) -> Any:
        """Motor torque (plus the external torque) at ``(t, x)``."""
        c = self.controller
        n1 = self.n1
        theta, thetadot = x[0], x[n1]
        tau: Any
        if name == "manoeuvre" and self._ref is not None:
            r = self._ref(t)
            tau = r[0]
            if c.kind != "none":
                tau = tau + c.gains.kp * (r[1] - theta) + c.gains.kd * (r[2] - thetadot)
                if c.friction_compensation > 0:
                    tau = tau + c.friction_compensation * x[self.index("direction")]
        elif c.kind == "pd" and self.reference is not None:
            tau = c.gains.kp * (self.theta_hold - theta) - c.gains.kd * thetadot
        elif c.kind == "two-stage":
            tau = x[self.index("pulse_torque")]
        else:
            tau = ca.MX(0)
        return tau + c.external_torque

    def _mechanics(self, tau: Any, x: Any) -> tuple[Any, Any, Any]:
        """``(Xdot, friction, needed)``: the plant's rate in its mode, the friction torque, the holding friction."""
        X = x[: self.nx]
        n1 = self.n1
        friction = self.plant.friction
        if not friction.active:
            return self._rhs(X, tau), ca.MX(0), ca.MX(0)
        f0 = self._rhs(X, 0)
        b = self._rhs(X, 1) - f0
        held_torque = -f0[n1] / b[n1]
        needed = held_torque - tau
        mode = x[self.index("mode")]
        stuck = ca.fabs(mode) < 0.5
        held = f0 + held_torque * b
        held = ca.vertcat(0, held[1:n1], 0, held[n1 + 1 :])
        kinetic = -ca.sign(mode) * friction.coulomb
        xdot = ca.if_else(stuck, held, f0 + (tau + kinetic) * b)
        return xdot, ca.if_else(stuck, needed, kinetic), needed

    def _build(self, name: PhaseName) -> Phase:
        c = self.controller
        friction = self.plant.friction
        t = ca.MX.sym("t")
        x = ca.MX.sym("x", self.size)
        tau = self._torque(name, t, x)
        xdot, fric, needed = self._mechanics(tau, x)
        ode = ca.vertcat(xdot, ca.MX.zeros(len(DISCRETE)))

        def at(key: str) -> Any:
            return x[self.index(key)]

        mode = at("mode")
        stuck = ca.fabs(mode) < 0.5
        indicators: dict[str, Any] = {}
        if friction.active:
            indicators["stop"] = ca.if_else(stuck, 1, mode * x[self.n1])
            indicators["breakaway"] = ca.if_else(stuck, friction.breakaway - ca.fabs(needed), 1)
        if (name == "manoeuvre" and self.reference is not None and c.kind != "none"
                and c.friction_compensation > 0 and self.reference.direction != 0 and self._ref is not None):
            ydot_d = self._ref(t)[3]
            indicators["direction"] = at("direction") * ydot_d + self.reference.deadband
        pulse = c.pulse
        if name == "after" and c.kind == "two-stage" and self.reference is not None and pulse is not None:
            indicators["decision"] = ca.if_else(at("done") > 0.5, 1, at("next_decision") - t)
            indicators["pulse_end"] = ca.if_else(ca.fabs(at("pulse_torque")) > 0.5 * pulse.amplitude, at("pulse_end") - t, 1)
        events = tuple(indicators)

        # settle: a stuck hub that the torque at (t, x) breaks loose slips against the holding friction
        def settled(xx: Any) -> Any:
            if not friction.active:
                return xx
            tau_x = self._torque(name, t, xx)
            need = self._mechanics(tau_x, xx)[2]
            m = xx[self.index("mode")]
            loose = ca.logic_and(ca.fabs(m) < 0.5, ca.fabs(need) > friction.breakaway)
            return _set(xx, self.index("mode"), ca.if_else(loose, -ca.sign(need), m))

        settle = ca.Function("sflm_settle", [t, x], [settled(x)], ["t", "x"], ["post_x"])
        outputs = ca.Function("sflm_outputs", [t, x], [tau, fric], ["t", "x"], ["tau", "friction"])
        ode_f = ca.Function("sflm_closed_loop", [t, x], [ode], ["t", "x"], ["xdot"])
        if not events:
            return Phase(name, ode_f, events, None, None, settle, outputs)
        g = ca.Function("sflm_indicators", [t, x], [ca.vertcat(*indicators.values())], ["t", "x"], ["g"])
        index = ca.MX.sym("index")
        posts = [self._post(event, t, x, needed, lambda y: settle(t, y)) for event in events]  # one call node each
        post = posts[-1]
        for k in range(len(posts) - 2, -1, -1):
            post = ca.if_else(index == k, posts[k], post)
        transition = ca.Function("sflm_transition", [index, t, x], [post], ["index", "t", "x"], ["post_x"])
        return Phase(name, ode_f, events, g, transition, settle, outputs)

    def _post(self, event: str, t: Any, x: Any, needed: Any, settled: Any) -> Any:
        """The state after ``event`` at ``(t, x)``."""
        i = self.index
        if event == "stop":  # the hub stops: it sticks, or slips on the way the torque pushes
            y = _set(x, self.n1, 0.0)
            y = _set(y, i("mode"), 0.0)
            y = _set(y, i("stops"), x[i("stops")] + 1)
            y = settled(y)
            return _set(y, i("sticks"), y[i("sticks")] + ca.if_else(ca.fabs(y[i("mode")]) < 0.5, 1, 0))
        if event == "breakaway":  # the holding friction reached F_s: slip against it
            y = _set(x, i("mode"), -ca.sign(needed))
            return _set(y, i("breakaways"), x[i("breakaways")] + 1)
        if event == "direction":
            y = _set(x, i("direction"), -x[i("direction")])
            return settled(_set(y, i("reversals"), x[i("reversals")] + 1))
        if event == "pulse_end":
            return settled(_set(x, i("pulse_torque"), 0.0))
        # decision: measure the hub error; pulse towards it, or stop for good
        pulse = self.controller.pulse
        assert pulse is not None
        error = self.theta_hold - x[0]
        known = self.controller.known_friction
        a1 = (pulse.amplitude - known) / self.inertia
        a2 = known / self.inertia
        width = ca.fmin(ca.fmax(pulse.gain * ca.sqrt(2 * ca.fabs(error) / (a1 * (1 + a1 / a2))), pulse.min_width),
                        pulse.max_width)
        finished = ca.logic_or(self.length * ca.fabs(error) <= pulse.tolerance, x[i("pulses")] >= pulse.max_pulses)
        torque = pulse.amplitude * ca.sign(error)
        y = _set(x, i("pulse_torque"), ca.if_else(finished, 0, torque))
        y = _set(y, i("pulse_record"), ca.if_else(finished, x[i("pulse_record")], torque))
        y = _set(y, i("next_decision"), t + pulse.period)
        y = _set(y, i("pulse_end"), ca.if_else(finished, x[i("pulse_end")], t + width))
        y = _set(y, i("pulse_start"), ca.if_else(finished, x[i("pulse_start")], t))
        y = _set(y, i("pulse_width"), ca.if_else(finished, x[i("pulse_width")], width))
        y = _set(y, i("pulses"), x[i("pulses")] + ca.if_else(finished, 0, 1))
        y = _set(y, i("done"), ca.if_else(finished, 1, 0))
        return settled(y)


def _set(x: Any, k: int, value: Any) -> Any:
    """``x`` with entry ``k`` replaced (a new expression)."""
    return ca.vertcat(x[:k], value, x[k + 1 :])

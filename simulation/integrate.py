"""Integrators of the closed loop: CasADi's CVODES in compiled code, and a SciPy loop to cross-check it.

Both integrate one :class:`~simulation.hybrid.Phase` from ``t0`` through the output
times, locate its events and apply its transitions.

* ``"cvodes"`` (default) -- ``casadi.integrator`` with SUNDIALS CVODES (BDF, Newton
  iterations on the compiled Jacobian) over the phase's CasADi graph: the right-hand
  side, the reference spline and the control law run in CasADi's virtual machine and
  the compiled model, with no Python per step. Without events, the whole phase is one
  call. With events, the phase is integrated in chunks of :data:`CHUNK` points of a
  check grid (one call each, through one integrator in normalised time built once);
  the indicators are evaluated at every check point in one mapped call, and a sign
  change is located by Brent's method (:func:`scipy.optimize.brentq`) on the
  indicator along the trajectory, to :data:`EVENT_TOLERANCE`. CasADi's own event
  support is not used: it is marked experimental and misses events (a decision after a
  transition, for one).
* ``"scipy"`` -- ``scipy.integrate.solve_ivp`` (LSODA with the analytic Jacobian) over the
  same functions called from Python, restarting at each event that its own event
  location finds: slower, independent of the chunked location above, kept to check it
  (tests and ``benchmarks/bench_simulation.py``).

Both see an event only if its indicator is non-positive at a check point (a step end
for SciPy): the check spacing (``max_step``) must be short enough that a crossing
cannot come and go in between; :func:`simulation.closed_loop.default_max_step` chooses
it from the fastest time scale of the loop.
"""

from __future__ import annotations

import math
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from modelgen.compiled import FastCall
from modelgen.errors import SflmError

from .hybrid import Phase
from .options import ENGINES, SIMULATION_DEFAULTS, Engine

__all__ = ["integrate", "Engine", "ENGINES", "SimulationError", "MAX_EVENTS", "CHUNK", "EVENT_TOLERANCE"]

FloatArray = NDArray[np.float64]
#: Largest number of events in one phase (stick/slip chattering is reported, not run forever).
MAX_EVENTS = 200_000
#: Check points per CVODES call when events can happen.
CHUNK = 128
#: Events are located to this (s).
EVENT_TOLERANCE = 1e-12


class SimulationError(SflmError):
    """The integration failed (the message says where and why)."""


def integrate(
    phase: Phase,
    t0: float,
    tout: FloatArray,
    x0: FloatArray,
    engine: Engine = SIMULATION_DEFAULTS.engine,
    rtol: float = SIMULATION_DEFAULTS.rtol,
    atol: float = SIMULATION_DEFAULTS.atol,
    max_step: float = math.inf,
) -> FloatArray:
    """Integrate ``phase`` from ``(t0, x0)`` to each of ``tout``.

    Parameters
    ----------
    phase : Phase
        The closed loop in one phase.
    t0 : float
        Start (s).
    tout : ndarray
        Increasing output times after ``t0`` (s).
    x0 : ndarray
        Extended state at ``t0``.
    engine : {"cvodes", "scipy"}
        See the module docstring.
    rtol, atol : float
        Integrator tolerances.
    max_step : float
        Largest spacing of the check points (CVODES) or step (SciPy) when the phase has
        events (s).

    Returns
    -------
    ndarray, shape (len(tout), len(x0))
        At an output time that is an event time, the state after the event.

    Raises
    ------
    SimulationError
        If the integrator fails or the events do not end (chattering).
    """
    tout = np.asarray(tout, dtype=float)
    x0 = np.asarray(x0, dtype=float)
    if tout.size == 0:
        return np.zeros((0, x0.size))
    if engine == "scipy":
        return _scipy(phase, t0, tout, x0, rtol, atol, max_step)
    if phase.indicators is None:
        return _cvodes_plain(phase, t0, tout, x0, rtol, atol)
    return _Chunked(phase, rtol, atol).run(t0, tout, x0, max_step)


def _options(rtol: float, atol: float) -> dict[str, Any]:
    return {"reltol": rtol, "abstol": atol, "max_num_steps": 1_000_000, "disable_internal_warnings": True, "linear_solver": "csparse"}


def _call(F: FastCall, x0: FloatArray, p: FloatArray, where: str) -> FloatArray:
    """One integrator call (``xf``, states as columns); a failure becomes a :class:`SimulationError` naming ``where``."""
    try:
        out = F(x0, [], p)[0]
    except RuntimeError as exc:
        if "KeyboardInterrupt" in str(exc):  # Ctrl-C inside CVODES: CasADi reports it as a failed right-hand side
            raise KeyboardInterrupt from None
        raise SimulationError(f"CVODES failed {where}: {_last_line(exc)}") from None
    if not np.all(np.isfinite(out)):
        raise SimulationError(f"the state is not finite {where}")
    return out


def _cvodes_plain(phase: Phase, t0: float, tout: FloatArray, x0: FloatArray, rtol: float, atol: float) -> FloatArray:
    """A phase without events: one call over every output time."""
    t = ca.MX.sym("t")
    x = ca.MX.sym("x", x0.size)
    dae = {"t": t, "x": x, "ode": phase.ode(t, x)}
    F = FastCall(ca.integrator(f"sflm_{phase.name}", "cvodes", dae, float(t0), tout.tolist(), _options(rtol, atol)))
    return _call(F, x0, np.zeros(0), f"in the {phase.name} phase between {t0:.6g} and {tout[-1]:.6g} s").T


class _Chunked:
    """CVODES in chunks of a check grid, with event location between check points."""

    def __init__(self, phase: Phase, rtol: float, atol: float):
        self.phase = phase
        x = ca.MX.sym("x", phase.ode.size1_in(1))
        s = ca.MX.sym("s")
        p = ca.MX.sym("p", 2)  # start and duration: t = p0 + s p1, s in [0, 1]
        dae = {"t": s, "x": x, "p": p, "ode": p[1] * phase.ode(p[0] + s * p[1], x)}
        grid = (np.arange(1, CHUNK + 1) / CHUNK).tolist()
        self.chunk = FastCall(ca.integrator(f"sflm_{phase.name}_chunk", "cvodes", dae, 0.0, grid, _options(rtol, atol)))
        self.step = FastCall(ca.integrator(f"sflm_{phase.name}_step", "cvodes", dae, 0.0, 1.0, _options(rtol, atol)))
        self.g_chunk = FastCall(phase.indicators.map(CHUNK, "serial"))
        self.g_one = FastCall(phase.indicators)
        self.events = 0

    def advance(self, t: float, x: FloatArray, duration: float) -> FloatArray:
        """The state ``duration`` after ``(t, x)`` (no event in between)."""
        if duration <= 0:
            return x.copy()
        where = f"in the {self.phase.name} phase between {t:.6g} and {t + duration:.6g} s"
        return _call(self.step, x, np.array([t, duration]), where).reshape(-1)

    def indicators(self, t: float, x: FloatArray) -> FloatArray:
        return self.g_one(t, x)[0].reshape(-1)

    def locate(self, t: float, x: FloatArray, h: float, g_start: FloatArray, g_end: FloatArray) -> tuple[float, int]:
        """The first event in ``(t, t + h]``: its time after ``t`` and its index.

        An indicator positive at ``t`` and non-positive at ``t + h`` crosses in between;
        Brent's method finds the crossing to :data:`EVENT_TOLERANCE`, and the event is put
        at the first point found where the indicator is no longer positive.
        """
        best = (math.inf, -1)
        for k in np.flatnonzero((g_start > 0) & (g_end <= 0)):
            def g(tau: float, k: int = int(k)) -> float:
                return float(self.indicators(t + tau, self.advance(t, x, tau))[k])

            tau = h
            if g(h) < 0:  # (re-integrated to t + h in one call, the indicator may end a rounding above zero)
                tau = float(brentq(g, 0.0, h, xtol=EVENT_TOLERANCE, rtol=4 * np.finfo(float).eps))
                if g(tau) > 0:
                    tau = min(h, tau + EVENT_TOLERANCE)
            if tau < best[0]:
                best = (tau, int(k))
        return best

    def run(self, t0: float, tout: FloatArray, x0: FloatArray, max_step: float) -> FloatArray:
        """Integrate through ``tout`` on a check grid of spacing at most ``max_step``."""
        out = np.zeros((tout.size, x0.size))
        grid, owners = _check_grid(t0, tout, max_step)
        t, x = float(t0), x0.copy()
        g_now = self.indicators(t, x)
        i = 0  # grid[i] <= t < grid[i + 1]
        while i < grid.size - 1:
            span = grid[i + 1 : i + CHUNK + 1]
            if t == grid[i] and span.size == CHUNK and _equal_steps(t, span):
                states, g_all = self._chunk(t, x, span)
            else:  # one interval: after an event, at the tail, or where the grid is not uniform
                span = span[:1]
                states = self.advance(t, x, float(span[0]) - t)[:, None]
                g_all = self.indicators(float(span[0]), states[:, 0])[:, None]
            before = np.column_stack([g_now, g_all[:, :-1]])
            fired = np.flatnonzero(np.any((g_all <= 0) & (before > 0), axis=0))
            clean = int(fired[0]) if fired.size else span.size
            for m in range(clean):
                if owners[i + 1 + m] >= 0:
                    out[owners[i + 1 + m]] = states[:, m]
            if not fired.size:
                t, x, g_now = float(span[-1]), states[:, -1].copy(), g_all[:, -1]
                i += span.size
                continue
            i += clean
            if clean > 0:
                t, x, g_now = float(grid[i]), states[:, clean - 1].copy(), g_all[:, clean - 1]
            tau, k = self.locate(t, x, float(grid[i + 1]) - t, g_now, g_all[:, clean])
            t_event = t + tau
            x_event = self.advance(t, x, tau)
            x = np.asarray(self.phase.transition(k, t_event, x_event), dtype=float).reshape(-1)
            t, g_now = t_event, self.indicators(t_event, x)
            self.events += 1
            if self.events > MAX_EVENTS:
                raise SimulationError(f"more than {MAX_EVENTS} events by t = {t:.6g} s in the {self.phase.name} phase (chattering)")
            if t >= grid[i + 1]:  # the event is at a grid point: the state there is the one after it
                i += 1
                if owners[i] >= 0:
                    out[owners[i]] = x
        return out

    def _chunk(self, t: float, x: FloatArray, span: FloatArray) -> tuple[FloatArray, FloatArray]:
        """States and indicators at the :data:`CHUNK` equally spaced points ``span`` after ``(t, x)``, one call."""
        duration = float(span[-1]) - t
        where = f"in the {self.phase.name} phase between {t:.6g} and {span[-1]:.6g} s"
        states = _call(self.chunk, x, np.array([t, duration]), where)
        times = t + duration * np.arange(1, CHUNK + 1) / CHUNK
        return states, self.g_chunk(times, states)[0]


def _check_grid(t0: float, tout: FloatArray, max_step: float) -> tuple[FloatArray, NDArray[np.intp]]:
    """Check points from ``t0`` through ``tout``: each output interval in equal parts of at most ``max_step``.

    Returns the points (``t0`` first) and, for each, the index of the output it is, or -1.
    """
    starts = np.concatenate([[t0], tout[:-1]])
    parts = np.maximum(1, np.ceil((tout - starts) / max_step - 1e-9)).astype(np.intp)
    output = np.repeat(np.arange(tout.size), parts)  # the output interval each point lies in
    ends = np.cumsum(parts)
    m = np.arange(output.size) - (ends - parts)[output] + 1  # 1 .. parts within its interval
    points = starts[output] + (tout - starts)[output] * m / parts[output]
    points[ends - 1] = tout  # each output time exactly
    owners = np.full(output.size, -1, dtype=np.intp)
    owners[ends - 1] = np.arange(tout.size)
    return np.concatenate([[t0], points]), np.concatenate([[-1], owners]).astype(np.intp)


def _equal_steps(t: float, span: FloatArray) -> bool:
    steps = np.diff(np.concatenate([[t], span]))
    return bool(np.all(np.abs(steps - steps[0]) <= 1e-9 * steps[0]))


def _scipy(phase: Phase, t0: float, tout: FloatArray, x0: FloatArray, rtol: float, atol: float, max_step: float) -> FloatArray:
    t = ca.MX.sym("t")
    x = ca.MX.sym("x", x0.size)
    ode = phase.ode
    jac = ca.Function("sflm_ode_jacobian", [t, x], [ca.jacobian(ode(t, x), x)])
    cache: dict[str, Any] = {"key": None, "value": None}

    def indicators(time: float, state: FloatArray) -> FloatArray:
        key = (time, state.tobytes())
        if cache["key"] != key:
            cache["key"], cache["value"] = key, np.asarray(phase.indicators(time, state), dtype=float).reshape(-1)
        return cache["value"]

    def indicator(k: int) -> Any:
        def g(time: float, state: FloatArray) -> float:
            return float(indicators(time, state)[k])

        g.terminal = True  # type: ignore[attr-defined]
        g.direction = -1  # type: ignore[attr-defined]
        return g

    events = [indicator(k) for k in range(len(phase.events))]
    out = np.zeros((tout.size, x0.size))
    done = 0
    t_now, state = float(t0), x0.copy()
    count = 0
    end = float(tout[-1])
    while t_now < end:
        sol = solve_ivp(
            lambda time, s: np.asarray(ode(time, s), dtype=float).reshape(-1),
            (t_now, end), state, method="LSODA", rtol=rtol, atol=atol, t_eval=tout[done:],
            jac=lambda time, s: np.asarray(jac(time, s), dtype=float), events=events or None,
            max_step=max_step if events else math.inf, first_step=min(1e-4, (end - t_now) / 2),
        )
        if sol.status == -1:
            raise SimulationError(f"LSODA failed in the {phase.name} phase at t = {t_now:.6g} s: {sol.message}")
        got = np.asarray(sol.t).size
        if got:
            out[done : done + got] = np.asarray(sol.y).T
        done += got
        if sol.status != 1:
            break
        k = next(j for j, te in enumerate(sol.t_events) if np.asarray(te).size)
        t_event = float(sol.t_events[k][0])
        state = np.asarray(phase.transition(k, t_event, sol.y_events[k][0]), dtype=float).reshape(-1)
        count += 1
        if count > MAX_EVENTS:
            raise SimulationError(f"more than {MAX_EVENTS} events by t = {t_event:.6g} s in the {phase.name} phase (chattering)")
        t_now = max(t_event, math.nextafter(t_now, math.inf))
        if done < tout.size and tout[done] <= t_now:  # an output at the event itself: the state after it
            out[done] = state
            done += 1
    return out


def _last_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[-1].strip()[:300] if text else exc.__class__.__name__

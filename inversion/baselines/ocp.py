"""Optimal control: the limit of any causal feedforward on the model, at a given error bound.

On the exactly discretised linear model at the controller's period ``DT`` (a zero-order hold,
:func:`inversion.lti.discrete.zero_order_hold`: ``x_{k+1} = A_d x_k + B_d u_k``), from the model's
state at ``t0`` (rest), :func:`ocp_inversion` chooses the held inputs ``u_0 .. u_{K-1}`` over
``[t0, tf]``::

    minimise    s,  -s <= u_k <= s                      objective "torque" (the peak)
                sum_k u_k^2 DT                          objective "energy"
    subject to  |C x_k - y_d(t_k)| <= E                  k = 0 .. K + K_a
                x_K = the rest state on y_d(t_f)         end "rest"

where the last ``K_a`` periods are the after-end window (:func:`inversion.acceptance.window_length`)
with the input held at what follows the feedforward (zero torque for a link, the equilibrium
input for a system): the tip must stay within ``E`` of ``y_d(t_f)`` after the move, as the
acceptance of every other method asks. The states are decision variables (multiple shooting:
one linear equality per period), so the KKT matrix is banded and IPOPT's sparse solver (MUMPS,
shipped with CasADi) takes a 1 kHz, 6 s problem in seconds; the torque objective is a linear
programme, the energy one a quadratic programme. The inputs are scaled by the rigid-body need
and the tip constraint by ``E``. A long move's programme may have its rows ``ramp`` periods apart: the table is then the
line through them sampled every period, modelled exactly (each period's state a linear map of the row's state and the two
rows' inputs) and its tip bounded at every period.

Any causal feedforward that keeps the tip within ``E`` at the samples needs at least this peak
torque (on this model, at this period): it is the yardstick of the family's members
(``benchmarks/bench_ocp.py``). The result is a held table -- one input a period, its summary
with the keys of every result -- that the acceptance judges like the others; IPOPT's status,
iterations and time are in its ``ocp`` block. Where IPOPT stalls (a min-max LP is degenerate: on
``(2 - s)/(s + 1)^3``'s 6 s move its dual infeasibility stayed at 1.6), HiGHS, the LP/QP solver
CasADi also ships, solves the unscaled programme. The torque objective carries a trace of the rows' total variation
(and IPOPT's one of the energy): the least peak alone is degenerate, its solution leaving the peak and coming back at
the rate bound for nothing. The inputs either returns are checked on the
plant, propagated again, before they are a result. An infeasible bound, or a failed solve, is an
:class:`~inversion.errors.InversionError` naming IPOPT's status.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model

from ..acceptance import WORDS, Bounds, Demand, demand, judge, larger_model, summary_keys, window_length
from ..acceptance import free_peaks as _free_peaks
from ..config import DEFAULTS
from ..errors import InversionError, SettingsError
from ..lti.discrete import recurrence, zero_order_hold
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form
from ..options import End, checked
from ..result import InversionResult, SummaryFigures, caller_state, summarize
from ..signals.chebyshev import DEGREE, LINK_SIGNALS, SYSTEM_SIGNALS, PiecewiseChebyshev
from ..signals.trajectory import Trajectory

__all__ = ["ocp_inversion", "ocp_front", "write_front", "OBJECTIVES", "held_signals", "FRONT_BOUNDS", "FRONT_COLUMNS"]

FloatArray = NDArray[np.float64]
#: What the optimal-control feedforward minimises.
OBJECTIVES = ("torque", "energy")
#: The bounds of :func:`ocp_front`, as fractions of the move.
FRONT_BOUNDS = (1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2)
#: Columns of ``ocp_front.csv``.
FRONT_COLUMNS = ("max_error", "relative_error", "status", "peak_torque", "torque_ratio", "iterations", "seconds", "message")
#: IPOPT's options: quiet, sparse (MUMPS), tight tolerances on the scaled problem.
_IPOPT: dict[str, Any] = {"print_level": 0, "sb": "yes", "linear_solver": "mumps", "max_iter": 150, "tol": 1e-8, "constr_viol_tol": 1e-9,
          "acceptable_tol": 1e-6, "acceptable_iter": 5, "mu_strategy": "adaptive", "hessian_constant": "yes",
          "jac_c_constant": "yes", "jac_d_constant": "yes"}
#: Refine the tip between the samples on this many points a period.
_BETWEEN = 8
#: The programme is solved this fraction inside the error bound (above the solvers' tolerance of 1e-9 on the scaled tip).
_INSIDE = 1e-6
#: The tip is bounded at the rows and half-way between them this fraction inside the bound (it strays a little further
#: elsewhere between them: room for it, instead of a second solve)
_BETWEEN_MARGIN = 1e-3
#: The energy's weight beside the peak in the torque objective (scaled inputs: the peak is about 1).
_TRACE = 1e-5
#: The rows' total variation's weight beside the peak in the torque objective (scaled inputs: the peak is about 1, the
#: variation a few to a few hundred): the peak moves by at most about this fraction of the variation it saves.
_VARIATION = 1e-4
#: The rows' rate bound is solved this fraction inside the acceptance's.
_RATE_INSIDE = 1e-4
#: IPOPT's options from a starting point near the solution (a coarser period's): a small barrier parameter to start with.
_WARM: dict[str, Any] = {"mu_init": 1e-4, "bound_push": 1e-6, "bound_frac": 1e-6}


def held_signals(names: tuple[str, ...], t0: float, period: float, values: FloatArray) -> PiecewiseChebyshev:
    """Held values as piecewise Chebyshev series.

    Held values as piecewise Chebyshev series: one constant a period (the series of :mod:`inversion.signals.chebyshev`).

    Parameters
    ----------
    names : tuple of str
        The signals.
    t0, period : float
        The first period's start and the period (s).
    values : ndarray, shape (K, S)
        Each period's values.
    """
    K, S = values.shape
    bounds = t0 + np.arange(K + 1) * period
    coefficients = np.zeros((K, S, DEGREE + 1))
    coefficients[:, :, 0] = values
    edges = np.column_stack([np.zeros(K), np.full(K, period)]).ravel()
    return PiecewiseChebyshev(names=names, bounds=bounds, piece_start=np.arange(K + 1, dtype=np.intp), edges=edges,
                              coefficients=coefficients, peaks=np.maximum(np.abs(values).max(axis=0), np.finfo(float).tiny))


def ocp_inversion(
    model: Model | LinearSystem,
    trajectory: Trajectory,
    *,
    period: float,
    max_error: float,
    objective: str = DEFAULTS.objective,
    end: str = End.FREE,
    window: float | None = None,
    bounds: Bounds | None = None,
    progress: Callable[[str], None] | None = None,
    ramp: int = 1,
) -> InversionResult:
    """The optimal-control feedforward (module docstring).

    Parameters
    ----------
    model : Model or LinearSystem
        A link, or a generic system (its input ``u``).
    trajectory : Trajectory
        The desired output.
    period : float
        The controller's period ``DT`` (s).
    max_error : float
        ``E`` (m): the tip within it of ``y_d`` at every sample, during the move and after it.
    objective : {"torque", "energy"}
        The peak input, or ``sum u_k^2 DT``.
    end : {"free", "rest"}
        ``"rest"``: also the rest state on ``y_d(t_f)`` at ``t_f``.
    window : float, optional
        The after-end window (s; default :func:`inversion.acceptance.window_length`).
    bounds : Bounds, optional
        What the acceptance judges the result with (default: ``max_error``, the period held).
    progress : callable, optional
        Receives one-line messages (the problem's size before the solve).
    ramp : int
        Periods of the table per row of the programme: with ``ramp > 1`` the programme's rows are ``ramp`` periods apart
        and the table is the line through them (from the input before the move) sampled at ``period`` and held. The
        programme models that table exactly (each period's state a linear map of the row's state and the two rows'
        inputs) and bounds the tip at every period of it, so a long move's programme keeps ``ramp`` times fewer variables
        while the table changes by a period's share of a row's change.

    Raises
    ------
    SettingsError
        For an objective, end, period or bound out of range, or a problem of more than
        :attr:`inversion.config.Defaults.ocp_max_periods` periods (naming the shortest period accepted).
    InversionError
        When IPOPT does not solve it (infeasible: no causal feedforward meets the bound at this
        period; or a failure), naming its status.
    """
    if objective not in OBJECTIVES:
        raise SettingsError("objective", objective, "'torque' or 'energy' for the optimal-control feedforward")
    if isinstance(ramp, bool) or not isinstance(ramp, int) or ramp < 1:
        raise SettingsError("ramp", ramp, "a whole number >= 1 of periods per row of the programme")
    end = checked(End, "end", end, ("free", "rest"))
    for name, value in (("period", period), ("max_error", max_error)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise SettingsError(name, value, "a finite number > 0")
    started = time.perf_counter()
    say = progress or (lambda message: None)
    form = normal_form(model)
    length = window_length(form, window)
    step = period * ramp  # the programme's rows
    K = max(1, math.ceil(trajectory.duration / step - 1e-9))
    Ka = max(1, math.ceil(length / step - 1e-9))
    if K + Ka > DEFAULTS.ocp_max_periods:
        longest = (trajectory.duration + length) / DEFAULTS.ocp_max_periods
        raise SettingsError("period", period, f"at least {longest:.3g} s for this move: {K} periods of the move and {Ka} of the "
                            f"{length:g} s after it are {K + Ka}, more than the {DEFAULTS.ocp_max_periods} one optimal-control "
                            "problem takes")
    _check_memory(form.n_states, K + Ka, step)
    judged = Bounds(max_error=float(max_error), period=period, hold="zoh", window=window) if bounds is None else bounds
    asked = demand(form, trajectory, period)  # the move's ends and its rigid need, read once
    rate = judged.rate_limit(asked.rigid_rate, form.inertia is not None)[0]  # the acceptance's bound
    # the rate, too, a little inside its bound (HiGHS meets its rows to 1e-7 of their scale)
    # (a ramp's rows change by `ramp` periods' worth, the table's periods by one of them)
    problem = _Problem.build(form, trajectory, asked, step, K, Ka, float(max_error), objective, end == End.REST,
                             rate * ramp * (1 - _RATE_INSIDE), ramp)
    guess = None
    coarse = _coarse_period(trajectory.duration, period, K + Ka) if ramp == 1 else None
    if coarse is not None:  # a coarse period first, its solution the fine one's starting point
        say(f"ocp: {K + Ka} periods of {period:g} s ({form.n_states} states): first at {coarse:g} s")
        first = time.perf_counter()
        try:
            rough = ocp_inversion(model, trajectory, period=coarse, max_error=max_error, objective=objective, end=end, window=window,
                                  bounds=replace(judged, period=coarse))
        except InversionError as exc:  # a coarse period may not meet what a finer one does: then the fine one from nothing
            say(f"ocp: at {coarse:g} s not solved ({str(exc).split(';')[0]}); now at {period:g} s without a start")
        else:
            guess = problem.upsample(rough.tau, coarse)
            say(f"ocp: at {coarse:g} s in {time.perf_counter() - first:.1f} s (peak {float(np.abs(rough.tau).max()):.4g}); now at "
                f"{period:g} s")
    else:
        say(f"ocp: {K + Ka} periods of {step:g} s ({K} of the move, {Ka} after it), {form.n_states} states"
            + (f", the input linear between them and held every {period:g} s" if ramp > 1 else ""))
    # solved a millionth inside the bound (the solvers' own tolerance), so that what it returns is within the bound itself;
    # the tip is bounded at the rows and half-way between them, so elsewhere (and in the window, where the free link rings)
    # it may stray a little further: then solved again that much inside, twice at most
    inside = float(max_error) * (1 - _BETWEEN_MARGIN)
    # a ramp's programme bounds the tip at every period of the table: HiGHS first (measured on (s - 1)(s^2 + 4)/((s + 1)^2
    # (s + 2)^3), 12 s, 20 periods a row: HiGHS 6.1 s; IPOPT had not finished one solve in 900 s)
    solvers: tuple[str, ...] = ("highs", "ipopt") if ramp > 1 else ("ipopt", "highs")
    for _ in range(3):
        knots, X_rows, stats = _solve(replace(problem, E=inside), guess, solvers)
        solvers = (stats["solver"],) if stats["solver"] == "highs" else solvers
        u, X, times, y_d = problem.table(knots, X_rows, trajectory, period)  # what a controller at `period` holds
        Kt = u.size
        between = _between(form, X[:-1], np.append(u, np.full(X.shape[0] - 1 - Kt, problem.hold)), times, trajectory, period)
        worst = max(between, float(_free_peaks(form.A, form.B, form.C, X[Kt][None, :], problem.y_final, problem.hold, length)[0]),
                    float(np.abs(X @ form.C - y_d[: X.shape[0]]).max()))
        if worst <= float(max_error):
            break
        inside *= float(max_error) / worst * (1 - _INSIDE)
        guess = (knots, X_rows)
    seconds = time.perf_counter() - started
    if ramp > 1:
        stats = {**stats, "ramp": ramp, "programme_period": step}
    return _result(model, form, trajectory, u, X, times, y_d, period, float(max_error), objective, str(end), length,
                   stats, seconds, problem.rigid, bounds, between)


#: Above this many periods a problem is first solved at a coarser period (at most :data:`_COARSE` s), its solution the start.
_WARM_ABOVE = 1500
#: The coarse period's upper limit (s) and its share of the move (at least this many periods in it).
_COARSE = 0.01
_COARSE_PERIODS = 100


def _coarse_period(duration: float, period: float, periods: int) -> float | None:
    """A period ``m`` times the requested one (``m >= 3``, at most :data:`_COARSE` s, with :data:`_COARSE_PERIODS` in the
    ``duration`` of the move) to solve first, or ``None`` for a problem small enough to solve as it is."""
    if periods <= _WARM_ABOVE:
        return None
    m = int(min(_COARSE, duration / _COARSE_PERIODS) / period)
    return m * period if m >= 3 else None


def _check_memory(states: int, periods: int, period: float) -> None:
    """Refuse, before any work, a problem whose factorisation would not fit the memory this machine has free.

    The programme's KKT matrix is banded: about ``(2N + 6) T`` rows of bandwidth ``6N + 20``; the sparse factorisation
    (MUMPS) keeps a few times that. Where the system does not say what is free, nothing is refused.
    """
    import os

    try:
        free = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return
    need = 8.0 * (2 * states + 6) * periods * (6 * states + 20) * 10
    if need > 0.5 * free:
        raise SettingsError("period", period, f"a longer period: {periods} periods of a {states}-state plant need about "
                            f"{need / 2**30:.1f} GB to solve, and {free / 2**30:.1f} GB of memory are free")


@dataclass(frozen=True)
class _Problem:
    """The optimal-control programme of a move at a period (module docstring), its data as arrays."""

    form: Any
    Ad: FloatArray
    Bd: FloatArray  # a row's input (with a ramp: the row's share of the line to the next)
    Ah: FloatArray  # half a period: the tip between the rows
    Bh: FloatArray
    x0: FloatArray
    x_rest: FloatArray
    times: FloatArray
    y_d: FloatArray
    y_mid: FloatArray
    K: int
    Ka: int
    hold: float
    before: float
    y_final: float
    E: float
    rigid: float
    objective: str
    rest: bool
    rate: float
    ramp: int = 1
    G1: FloatArray | None = None  # with a ramp: the next row's share of the next row's state
    inner: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None = None  # the tip at the periods between the rows

    @classmethod
    def build(cls, form: Any, trajectory: Trajectory, asked: Demand, period: float, K: int, Ka: int, E: float, objective: str,
              rest: bool, rate: float, ramp: int = 1) -> "_Problem":
        t0, tf = trajectory.t0, trajectory.tf
        times = np.asarray(t0 + np.arange(K + Ka + 1) * period, dtype=float)
        y_d = trajectory.derivative(np.clip(times, t0, tf), 0)
        y_mid = trajectory.derivative(np.clip(times[:-1] + period / 2, t0, tf), 0)
        y_start, y_final = float(y_d[0]), asked.y_final
        rigid = max(asked.rigid_torque, 1e-300)  # the objective's scale
        x0 = np.asarray(form.state(np.array([y_start]), np.zeros(1), np.zeros((1, form.n_internal)))[0], dtype=float)
        Ad, Bd = zero_order_hold(form.A, form.B, period)
        Ah, Bh = zero_order_hold(form.A, form.B, period / 2)
        G1 = inner = None
        if ramp > 1:  # the table held every period / ramp, linear from row to row: x_j = P_j x_k + H0_j u_k + H1_j u_{k+1}
            Ac, Bc = zero_order_hold(form.A, form.B, period / ramp)
            N = Ac.shape[0]
            P, H0, H1 = np.eye(N), np.zeros(N), np.zeros(N)
            maps = []
            for j in range(1, ramp + 1):
                share = (j - 1) / ramp  # the input held over the j-th period: u_k (1 - share) + u_{k+1} share
                P, H0, H1 = Ac @ P, Ac @ H0 + Bc * (1 - share), Ac @ H1 + Bc * share
                maps.append((P, H0, H1))
            Ad, Bd, G1 = maps[-1]
            inside = np.arange(1, ramp) / ramp
            inner = (np.array([form.C @ m[0] for m in maps[:-1]]), np.array([form.C @ m[1] for m in maps[:-1]]),
                     np.array([form.C @ m[2] for m in maps[:-1]]),
                     trajectory.derivative(np.clip(times[:-1][None, :] + inside[:, None] * period, t0, tf).ravel(), 0)
                     .reshape(inside.size, times.size - 1))
        return cls(form, Ad, Bd, Ah, Bh, x0, np.asarray(_rest_state(form, y_final), dtype=float), times, y_d, y_mid, K, Ka,
                   asked.hold_final, asked.hold_start, y_final, E, rigid, objective, rest, rate, ramp, G1, inner)

    def states(self, rows: FloatArray) -> FloatArray:
        """The states at the rows driven by ``rows`` (the move's and the window's: ``K + Ka`` inputs, one more with a ramp)."""
        if self.G1 is None:
            X, _ = recurrence(self.Ad, self.Bd[:, None], self.x0, np.asarray(rows, dtype=float)[:, None])
            return X
        X, _ = recurrence(self.Ad, np.column_stack([self.Bd, self.G1]), self.x0, np.column_stack([rows[:-1], rows[1:]]))
        return X

    def table(self, knots: FloatArray, X: FloatArray, trajectory: Trajectory, period: float
              ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The table a controller at ``period`` holds, its states (through the window), times and ``y_d``: the rows
        themselves, or with a ramp the line through them (from the input before the move to the one after it) sampled."""
        if self.ramp == 1:
            return knots, X, self.times, self.y_d
        t0 = float(self.times[0])
        line = np.append(knots, self.hold)  # the row at t_f: what follows the feedforward
        fine = t0 + np.arange(self.K * self.ramp) * period
        u = np.interp(fine, self.times[: self.K + 1], line)
        Ad, Bd = zero_order_hold(self.form.A, self.form.B, period)
        rows = np.append(u, np.full(self.Ka * self.ramp, self.hold))
        Xf, _ = recurrence(Ad, Bd[:, None], self.x0, rows[:, None])
        times = t0 + np.arange(rows.size + 1) * period
        return u, Xf, times, trajectory.derivative(np.clip(times, trajectory.t0, trajectory.tf), 0)

    def upsample(self, coarse_inputs: FloatArray, coarse: float) -> tuple[FloatArray, FloatArray]:
        """A starting point at this period from a coarser period's inputs: each held for its ``m`` rows, the states run."""
        m = int(round(coarse / (self.times[1] - self.times[0])))
        u = np.repeat(np.asarray(coarse_inputs, dtype=float), m)[: self.K]
        u = np.append(u, np.full(self.K - u.size, u[-1] if u.size else 0.0))
        rows = np.append(u, np.full(self.Ka, self.hold))
        X, _ = recurrence(self.Ad, self.Bd[:, None], self.x0, rows[:, None])
        return u, X


def _solve(problem: _Problem, guess: tuple[FloatArray, FloatArray] | None = None, solvers: tuple[str, ...] = ("ipopt", "highs")
           ) -> tuple[FloatArray, FloatArray, dict[str, Any]]:
    """The programme of the module docstring, by CasADi's Opti: IPOPT first, HiGHS (an LP/QP solver CasADi ships) where
    IPOPT stalls -- a min-max LP is degenerate, and on a non-minimum-phase system's long move IPOPT's dual infeasibility
    stayed at 1.6 after 300 iterations (``(2 - s)/(s + 1)^3``, 6 s at 10 ms) where HiGHS solves it in seconds. The tip is
    bounded at the rows and half-way between them (rows of ``C A_h`` on the states: no variables more); a rest end is the
    state at ``t_f``, and the window after it, where nothing moves, has no rows. ``guess``: inputs and states to start from;
    ``solvers``: which to try, in order (a problem solved again a little inside goes to the one that solved it)."""
    import casadi as ca  # lazy: keeps `import inversion` fast

    P = problem
    form, N, K = P.form, P.Ad.shape[0], P.K
    Ka = 0 if P.rest else P.Ka  # at rest at t_f the window holds itself: its rows would only make the programme degenerate
    moved = np.maximum(np.abs(P.x_rest - P.x0), np.abs(P.x0))  # the states in units of their move (the rigid mode's), for IPOPT
    moved = np.where(moved > 0, moved, max(float(moved.max()), 1.0))
    attempts: list[str] = []
    solution = None
    for solver in solvers:
        # HiGHS scales the programme itself, and misread it scaled so (measured: "Optimal" 3.7e3 off the bound on
        # (2 - s)/(s + 1)^3): the states in their own units for it
        scale = moved if solver == "ipopt" else np.ones(N)
        opti = ca.Opti() if solver == "ipopt" else ca.Opti("conic")
        # one variable block, [z_k; v_k] in each column: CasADi stores it column by column, so each period's state and
        # input sit next to each other and the KKT matrix stays banded (an input block after the states costs fill-in;
        # the after-end window as rows of C A_d^j on x_K, without states, costs iterations: measured 5x slower)
        W = opti.variable(N + 1, K + Ka + 1)
        Z, V = W[:N, :], W[N, :K]  # X = diag(scale) Z, u = rigid V
        _dynamics_and_tip(opti, P, Z, V, W[N, K:], scale, Ka)
        peak = _rows_and_objective(opti, V, (P.rate, P.before), P.rigid, P.hold, P.objective, _TRACE if solver == "ipopt" else 0.0)
        if solver == "ipopt":
            if guess is None:  # on the way: the states move from x0 to the rest state like y_d
                ramp = (P.y_d - P.y_d[0]) / (P.y_d[-1] - P.y_d[0]) if P.y_d[-1] != P.y_d[0] else np.zeros_like(P.y_d)
                opti.set_initial(W[:N, :], (P.x0[:, None] + np.outer(P.x_rest - P.x0, ramp[: K + Ka + 1])) / scale[:, None])
                if peak is not None:
                    opti.set_initial(peak, 1.0)
            else:
                u0, X0 = guess
                opti.set_initial(W[:N, :], np.asarray(X0[: K + Ka + 1], dtype=float).T / scale[:, None])
                opti.set_initial(V, np.asarray(u0, dtype=float)[None, :K] / P.rigid)
                if peak is not None:
                    opti.set_initial(peak, float(np.abs(u0).max()) / P.rigid * 1.01)
            opti.solver("ipopt", {"print_time": False}, dict(_IPOPT, **({} if guess is None else _WARM)))
        else:
            opti.solver("highs", {"print_time": False, "error_on_fail": False, "highs": {"output_flag": False}})
        try:
            solution = opti.solve()
        except RuntimeError as exc:
            try:
                stats = opti.stats()
            except RuntimeError:  # HiGHS with error_on_fail leaves no stats behind (measured: the steel strip at 1e-4)
                stats = {"return_status": "failed: " + str(exc).strip().splitlines()[-1].split(": ")[-1]}
            status = str(stats.get("return_status", "failed"))
            iterations = stats.get("iter_count", -1)
            attempts.append(f"{'HiGHS' if solver == 'highs' else 'IPOPT'} {status}"
                            + (f" after {iterations} iterations" if isinstance(iterations, int) and iterations >= 0 else ""))
            if "nfeasible" in status and solver == "highs":  # HiGHS proves it (an interior point's may be its restoration failing)
                break
            continue
        break
    if solution is None:
        raise _not_found(P, attempts)
    stats = solution.stats()
    u = P.rigid * np.asarray(solution.value(V), dtype=float).reshape(-1)
    X = P.states(np.append(u, np.full(P.Ka + (1 if P.G1 is not None else 0), P.hold)))
    # what the solver returns is checked, not trusted: the plant driven by the held inputs, propagated here
    worst = float(np.abs(X @ form.C - P.y_d).max())
    if not worst <= P.E * (1 + _BETWEEN_MARGIN / 2):  # within the bound still (P.E is inside it); the caller re-solves inside
        raise InversionError(f"the optimal-control solver ({'; '.join(attempts + [str(stats['return_status'])])}) returned inputs whose "
                             f"plant is {worst:.4g} from y_d at a sample, beyond the bound {P.E:.4g}: refused")
    iterations = (stats.get("iter_count") if solver == "ipopt" else
                  stats.get("simplex_iteration_count", stats.get("ipm_iteration_count")))
    return u, X, {"status": str(stats["return_status"]), "iterations": None if iterations is None or iterations < 0 else int(iterations),
                  "solver": solver, "attempts": attempts}


def _dynamics_and_tip(opti: Any, P: _Problem, Z: Any, V: Any, after: Any, scale: FloatArray, Ka: int) -> None:
    """The programme's rows on an Opti problem: the plant from row to row (``X = diag(scale) Z``, ``u = rigid V``), the
    tip within ``E`` at the rows and between them (half-way; with a ramp, at every period of the table), a rest end."""
    import casadi as ca  # lazy: keeps `import inversion` fast

    form, K = P.form, P.K
    Sx = ca.DM(np.diag(scale))
    Sinv = ca.DM(np.diag(1.0 / scale))
    ramped = P.G1 is not None  # the input linear from row to row, from the one before the move to the one after it
    inputs = ca.horzcat(P.rigid * V, ca.DM.ones(1, Ka + (1 if ramped else 0)) * P.hold)
    opti.subject_to(after == 0)  # no input of its own after the feedforward ends (the held one is in `inputs`)
    opti.subject_to(Z[:, 0] == ca.DM(P.x0 / scale))
    now = inputs[:, :-1] if ramped else inputs
    step = ca.DM(P.Ad) @ (Sx @ Z[:, :-1]) + ca.DM(P.Bd[:, None]) @ now
    if ramped:  # the table's own periods between the rows: the tip bounded at each
        assert P.G1 is not None and P.inner is not None
        opti.subject_to(V[0] == P.before / P.rigid)
        step = step + ca.DM(P.G1[:, None]) @ inputs[:, 1:]
        CP, h0, h1, y_in = P.inner
        middle = (ca.DM(CP * scale[None, :]) @ Z[:, :-1] + ca.DM(h0[:, None]) @ now + ca.DM(h1[:, None]) @ inputs[:, 1:])
        opti.subject_to(opti.bounded(-1, (middle - ca.DM(y_in[:, : K + Ka])) / P.E, 1))
    else:  # half-way between the rows
        middle = ca.DM((form.C @ P.Ah)[None, :] * scale[None, :]) @ Z[:, :-1] + ca.DM([[float(form.C @ P.Bh)]]) @ now
        opti.subject_to(opti.bounded(-1, (middle - ca.DM(P.y_mid[None, : K + Ka])) / P.E, 1))
    opti.subject_to(Z[:, 1:] == Sinv @ step)
    C = ca.DM(form.C[None, :] * scale[None, :])
    opti.subject_to(opti.bounded(-1, (C @ Z - ca.DM(P.y_d[None, : K + Ka + 1])) / P.E, 1))
    if P.rest:
        opti.subject_to(Z[:, K] == ca.DM(P.x_rest / scale))


def _not_found(P: _Problem, attempts: list[str]) -> InversionError:
    """The failure of both solvers, with the programme's figures and what may make it feasible."""
    link = P.form.inertia is not None
    exc = InversionError(
        f"the optimal-control feedforward does not exist or was not found: {'; '.join(attempts)} "
        f"({'peak ' + WORDS[link]['inp'] if P.objective == 'torque' else 'energy'}, the {WORDS[link]['out']} within {P.E:.4g} of y_d at "
        + (f"{P.K + P.Ka + 1} samples and half-way between them" if P.ramp == 1 else
           f"every period of a table through {P.K + P.Ka + 1} rows {P.ramp} periods apart") + (", ending at rest" if P.rest else "")
        + (f", the input changing by at most {P.rate / P.ramp:.4g} a period" if math.isfinite(P.rate) else "")
        + "); a larger max_error" + (", a larger max_torque_rate" if math.isfinite(P.rate) else "")
        + (", end='free'" if P.rest else "") + ", a longer move or a shorter period may make it feasible; method='stable' acts before t0")
    exc.unsolved = True  # type: ignore[attr-defined]  # no table: the caller may ask the bounded limit why
    return exc


def ocp_front(model: Model | LinearSystem, trajectory: Trajectory, *, period: float, fractions: tuple[float, ...] = FRONT_BOUNDS,
              end: str = End.FREE, progress: Any = None) -> list[dict[str, Any]]:
    """The least peak torque at each error bound (the OCP front).

    The optimal-control front: the least peak torque at each error bound ``fraction x move`` (:data:`FRONT_BOUNDS`).

    Each row has the keys :data:`FRONT_COLUMNS`; a bound no causal feedforward meets at this period is a row with status
    ``"infeasible"`` (or ``"failed"``) and IPOPT's message, not an exception. ``progress(done, total)`` after each bound.

    Parameters
    ----------
    model : Model | LinearSystem
        The plant.
    trajectory : Trajectory
        The desired output.
    period : float
        The controller's period (s).
    fractions : tuple[float, ...], optional
        The error bounds, as fractions of the move.
    end : str, optional
        ``"free"``, or ``"rest"`` for rest at the end.
    progress : Any, optional
        A callback ``(done, total)``, or ``None``.
    """
    move = trajectory.move()
    rows: list[dict[str, Any]] = []
    for done, fraction in enumerate(fractions, 1):
        E = fraction * (move if move > 0 else 1.0)
        started = time.perf_counter()
        try:
            result = ocp_inversion(model, trajectory, period=period, max_error=E, end=end)
        except InversionError as exc:
            status = "infeasible" if "nfeasible" in str(exc) else "failed"
            rows.append({"max_error": E, "relative_error": fraction, "status": status, "peak_torque": None, "torque_ratio": None,
                         "iterations": None, "seconds": time.perf_counter() - started, "message": str(exc)})
        else:
            s: Any = result.summary
            rows.append({"max_error": E, "relative_error": fraction, "status": "ok", "peak_torque": s["peak_torque"],
                         "torque_ratio": s["torque_ratio"], "iterations": s["ocp"]["iterations"], "seconds": s["ocp"]["seconds"],
                         "message": ""})
        if progress is not None:
            progress(done, len(fractions))
    return rows


def write_front(rows: list[dict[str, Any]], path: Any) -> Any:
    """Write ``ocp_front.csv`` (:data:`FRONT_COLUMNS`).

    Write ``ocp_front.csv`` (:data:`FRONT_COLUMNS`; empty cells for a bound that was not met).

    Parameters
    ----------
    rows : list[dict[str, Any]]
        The front's rows (:func:`ocp_front`).
    path : Any
        The folder written into.
    """
    import csv
    from pathlib import Path

    path = Path(path)
    with open(path, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(FRONT_COLUMNS))
        writer.writeheader()
        for row in rows:
            writer.writerow({k: "" if row[k] is None else (repr(row[k]) if isinstance(row[k], float) else row[k]) for k in FRONT_COLUMNS})
    return path


def _rest_state(form: Any, y: float) -> FloatArray:
    """The plant at rest on the output ``y`` (``X_I = 0``; a system's with its equilibrium input)."""
    return np.asarray(form.state(np.array([y]), np.zeros(1), np.zeros((1, form.n_internal)))[0], dtype=float)


def _rows_and_objective(opti: Any, V: Any, rate: tuple[float, float], rigid: float, hold: float, objective: str,
                        trace: float = 0.0) -> Any:
    """The rows' rate bound (the change from row to row, the first against the input before the table, the last against
    the one after) and the objective (the peak, returned as a variable, or the energy) on an Opti problem."""
    import casadi as ca  # lazy: keeps `import inversion` fast

    if math.isfinite(rate[0]):
        step = rate[0] / rigid
        rows = ca.horzcat(ca.DM([[rate[1] / rigid]]), V, ca.DM([[hold / rigid]]))
        opti.subject_to(opti.bounded(-step, rows[1:] - rows[:-1], step))
    if objective != "torque":
        opti.minimize(ca.sumsqr(V) / V.shape[1])
        return None
    peak = opti.variable()
    opti.subject_to(opti.bounded(-peak, V, peak))
    # the peak, with a trace of the energy for IPOPT: a min-max LP is degenerate (the input rides the peak on whole
    # stretches) and an interior point method crawls there; the trace makes the optimum unique and moves the peak by about
    # that fraction (HiGHS solves an LP: its QP interface would not take the energy). And for both, a trace of the rows'
    # total variation: without it the input leaves the peak and comes back at the rate bound for nothing (measured at 1 ms
    # and 1 %: the variation 382 -> 262 N m on the heavy payload's 0.343 s, 138 -> 81 on the steel strip's 0.6 s, 8.60 ->
    # 6.37 on (s - 1)(s^2 + 4)/((s + 1)^2 (s + 2)^3)'s 12 s, the peaks the same to 2e-4, the solves 10-30 % longer)
    rows = ca.horzcat(ca.DM([[rate[1] / rigid]]), V, ca.DM([[hold / rigid]]))
    change = opti.variable(1, rows.shape[1] - 1)
    opti.subject_to(opti.bounded(-change, rows[1:] - rows[:-1], change))
    opti.minimize(peak + _VARIATION * ca.sum2(change) + (trace * ca.sumsqr(V) / V.shape[1] if trace else 0))
    return peak


def _result(model: Model | LinearSystem, form: Any, trajectory: Trajectory, u: FloatArray, X: FloatArray, times: FloatArray,
            y_d: FloatArray, period: float, E: float, objective: str, end: str, window: float, stats: dict[str, Any],
            seconds: float, rigid: float, bounds: Bounds | None, between: float) -> InversionResult:
    """The held table as an :class:`~inversion.result.InversionResult` (its summary by :func:`~inversion.result.summarize`;
    ``between``: the tip's largest error between the rows)."""
    K = u.size
    t = times[:K]
    states = X[:K]
    y = states @ form.C
    ydot = states @ (form.A.T @ form.C)
    yddot = states @ (form.A.T @ form.A.T @ form.C) + form.CAB * u
    link = not isinstance(model, LinearSystem)
    n1 = form.n_states // 2
    values = np.column_stack([u, states[:, 0], states[:, n1]]) if link else u[:, None]
    signals = held_signals(LINK_SIGNALS if link else SYSTEM_SIGNALS, float(t[0]), period, values)
    move = trajectory.move()
    tip = X @ form.C
    at_samples = float(np.abs(tip - y_d).max())
    bounds = Bounds(max_error=E, period=period, hold="zoh", window=window, extra_modes=DEFAULTS.extra_modes) if bounds is None else bounds
    acceptance = judge(form, trajectory, signals, bounds, x0=X[0], x_end=X[K], feed_start=float(t[0]), feed_end=float(times[K]),
                       reference=lambda s: np.interp(s, times, tip), peak=float(np.abs(u).max()), error=at_samples, move=move,
                       larger=larger_model(model, bounds.extra_modes))
    worst = int(np.argmax(np.abs(tip - y_d)))
    figures = SummaryFigures(max_error=at_samples, time_of_max_error=float(times[worst]), move=move, gate=E,
                             peak_torque=float(np.abs(u).max()), time_of_peak_torque=float(t[int(np.argmax(np.abs(u)))]),
                             n_unstable=int(form.modal(0.0).n_unstable))
    settings = {"method": "ocp", "objective": objective, "period": period, "hold": "zoh", "max_error": E, "end": end, "window": window,
                "rate": 1.0 / period}
    top, verification = summary_keys(acceptance)
    extra = {"method": "ocp", "pre_actuation_time": 0.0, "post_actuation_time": 0.0, **top,
             "ocp": {**stats, "seconds": seconds, "periods": K, "after_periods": int(X.shape[0] - 1 - K), "rigid_torque": rigid,
                     "max_error_at_samples": at_samples, "max_error_between_samples": between,
                     "objective_value": float(np.abs(u).max()) if objective == "torque" else float(np.sum(u * u) * period)}}
    Xc = caller_state(model, states)
    summary = summarize(model, trajectory, figures, {"t": t, "y": y, "ydot": ydot, "tau": u, "X": Xc}, settings,
                        verification=verification, extra=extra)
    return InversionResult(t=t, y_d=y_d[:K], y=y, ydot=ydot, yddot=yddot, X=Xc, tau=u, theta_d=Xc[:, 0] if link else None,
                           thetadot_d=Xc[:, n1] if link else None, summary=summary, model=model,
                           trajectory=trajectory, modal=form.modal(0.0), signals=signals)


def _between(form: Any, X: FloatArray, u: FloatArray, times: FloatArray, trajectory: Trajectory, period: float) -> float:
    """``max |y - y_d|`` between the samples: each period on ``_BETWEEN`` points of the exact response to its held input."""
    fractions = np.arange(1, _BETWEEN) / _BETWEEN
    worst = 0.0
    for f in fractions:
        Ad, Bd = zero_order_hold(form.A, form.B, f * period)
        tip = (X @ Ad.T + np.outer(u, Bd)) @ form.C
        s = times[:-1] + f * period
        worst = max(worst, float(np.abs(tip - trajectory.derivative(np.clip(s, trajectory.t0, trajectory.tf), 0)).max()))
    return worst

"""The bounded causal limit: the least error any causal feedforward within the actuator's bounds can reach.

The causal limit (:mod:`inversion.lti.causal_limit`) bounds the error of any causal input, however large and however
fast. A drive has bounds, and the acceptance (:class:`inversion.acceptance.Bounds`) judges every result by them: the
peak torque ``T`` and the change between the controller's rows ``R``. On the exactly discretised model at the
controller's period ``DT`` (:func:`inversion.lti.discrete.zero_order_hold`), from rest at ``t0``, with inputs
``u_0 .. u_{M-1}`` held over the move and a horizon after it (free there too: a feedforward may settle after
``t_f``)::

    minimise    E
    subject to  |C x_k - y_d(t_k)| <= E                  (at the rows; y_d(t_f) after the move)
                |u_k| <= T,  |u_k - u_{k-1}| <= R        (u_{-1}: the input before the move)

The acceptance holds a table's tip to the bound at exactly these rows (:class:`inversion.acceptance.Sampled`'s
``max_tip_error``), so every causal feedforward held at ``DT`` that it passes meets these rows (it is asked more: after
a longer window, with more modes), and errs by at least ``E*``: where ``E*`` exceeds the bound, no
causal method -- the family, a re-planned output, optimal control, any other -- has a result to return at these
bounds, and a refusal can say so with the figure.

It is a linear programme with the states as variables (sparse: a few entries a row; each in units of its size when a
torque of the rigid need's size drives the plant), solved by HiGHS's interior point through
:func:`scipy.optimize.linprog`, with its presolve on short programmes and without it on long ones
(:data:`_PRESOLVE_CHAIN`). A programme larger than :data:`MAX_SIZE` keeps the states at every
few periods only (at most :data:`MAX_STRIDE`), each a linear map of the one before and the inputs between, and bounds the
tip there: fewer rows, a lower ``E*``, still a bound (on the 3 mm strip 7.3091e-3 and 7.3108e-3 with the states every 3
and 5 periods, against 7.3160e-3 every period). The
horizon after the move is a third of the move's duration (at most the window): fewer rows only lower ``E*``, so the
bound stays a bound, and on the 3 mm strip's 0.5 m in 0.6 s at 1 ms ``E*`` is the same to eight digits with the whole
move's duration after it (7.3160111e-3 m, by HiGHS's interior point and by its dual simplex), found in half the time:
2.1 s there, 5.5 s with 4 modes.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model

from ..acceptance import WORDS, Bounds, demand, window_length
from ..errors import InversionError, SettingsError
from ..lti.discrete import recurrence, zero_order_hold
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form
from ..signals.trajectory import Trajectory

__all__ = ["BoundedLimit", "bounded_limit", "MAX_SIZE"]

FloatArray = NDArray[np.float64]
#: The largest programme solved every period: its periods (the move's and the horizon's after it) times the plant's
#: states and input (the 3 mm strip's 0.6 s move at 1 ms with 4 modes, 8 800, takes 5.5 s); a larger one keeps the states
#: every few periods (:data:`MAX_STRIDE`).
MAX_SIZE = 12_000
#: HiGHS's interior point solves the programme, with its presolve up to this many kept states in the chain and without it
#: beyond; if it does not finish in the first of :data:`_SECONDS`, the other way round in the second. Presolve substitutes
#: the dynamics along the chain, which on a long one costs more than it saves. Measured (the interior point with presolve /
#: without / the dual simplex): the 3 mm strip's 0.6 s move at 1 ms, 800 periods, 3.3 / 4.7 / 3.6 s with 2 modes and 7.9 /
#: 11.9 / 23.4 s with 4; the flexible strip's 2.5 s at 2 ms, 1 667 periods, 19.5 / 12.1 s / numerical trouble;
#: 100/(s^2 + 2 s + 100), 3 s at 1 ms, 4 000 periods: nothing in 40 s / 7.1 s / nothing in 40 s; the flexible strip's 3 s at
#: 1 ms, 4 000 periods with the states kept every 3 (1 334 in the chain): 11.2 / 33.1 s.
_PRESOLVE_CHAIN = 1500
_SECONDS = (40.0, 20.0)  # room for a machine twice as busy as the one measured
#: Beyond :data:`MAX_SIZE`, the programme keeps the states at every few periods, at most this many apart (and the inputs,
#: one a period, at most half of :data:`MAX_SIZE`).
MAX_STRIDE = 5
#: The horizon after the move, as a fraction of its duration (at most the window).
_AFTER = 1 / 3


@dataclass(frozen=True)
class BoundedLimit:
    """The least error within the torque and rate bounds.

    Attributes
    ----------
    error : float
        ``E*`` (m; the output's units for a system): no causal feedforward held at ``period`` within the bounds keeps
        the tip closer to ``y_d`` at the rows.
    move : float
        The move (for the relative figure).
    period : float
        The controller's period (s).
    max_torque : float
        The peak bound ``T``.
    max_torque_rate : float
        The bound ``R`` on the change between rows.
    bound : float or None
        The error bound asked for.
    link : bool
        A link (torque, tip) or a system (input, output).
    seconds : float
        The programmes' time.
    rows_apart : int
        The tip is bounded at every ``rows_apart``-th row (1: at every row; more on a long programme, :data:`MAX_STRIDE`).
    """

    error: float
    move: float
    period: float
    max_torque: float
    max_torque_rate: float
    bound: float | None = None
    link: bool = True
    seconds: float = 0.0
    rows_apart: int = 1

    @property
    def exceeds(self) -> bool:
        """Whether ``E*`` exceeds the bound (no feedforward within the bounds passes)."""
        return self.bound is not None and self.error > self.bound

    def sentence(self) -> str:
        """The limit as a sentence.

        ``held at 1 ms with the torque within T and its change within R a period, no causal feedforward keeps ...``.
        """
        w = WORDS[self.link]
        return (f"held at {1e3 * self.period:.3g} ms with the {w['inp']} within {self.max_torque:.4g} and its change within "
                f"{self.max_torque_rate:.4g} a period, no causal feedforward keeps the {w['out']} closer than {self.error:.4g} "
                f"({100 * self.error / (self.move or 1.0):.3g} % of the move) at "
                + ("the rows" if self.rows_apart == 1 else f"one row in {self.rows_apart}")
                + " (a linear programme on the model)")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (a refusal's ``bounded_limit`` record)."""
        return {"error": self.error, "relative_error": self.error / (self.move or 1.0), "move": self.move, "period": self.period,
                "max_torque": self.max_torque, "max_torque_rate": self.max_torque_rate, "bound": self.bound, "seconds": self.seconds,
                "rows_apart": self.rows_apart}


def bounded_limit(model: Model | LinearSystem, trajectory: Trajectory, bounds: Bounds) -> BoundedLimit:
    """The least error of a causal feedforward within the bounds.

    The least error any causal feedforward held at the bounds' period, within their torque and rate bounds, reaches on
    the model (module docstring).

    Parameters
    ----------
    model : Model or LinearSystem
        The plant (its linear model).
    trajectory : Trajectory
        The desired output.
    bounds : Bounds
        The acceptance's bounds: ``max_error`` (the bound ``E*`` is compared with), the period, the torque and rate bounds
        (their defaults resolved against the rigid need as the acceptance resolves them).

    Raises
    ------
    SettingsError
        For a programme larger than :data:`MAX_SIZE` with the states kept every :data:`MAX_STRIDE` periods, or with more
        than half of it in inputs (naming the least period accepted).
    InversionError
        When HiGHS does not solve the programme (its status named).
    """
    started = time.perf_counter()
    form = normal_form(model)
    link = form.inertia is not None
    period = float(bounds.period)
    asked = demand(form, trajectory, period)
    need, need_rate = asked.rigid_torque, asked.rigid_rate
    T = bounds.torque_limit(need)
    R = bounds.rate_limit(need_rate, link)[0]
    after = min(window_length(form, bounds.window), _AFTER * trajectory.duration)
    programme = _Programme.build(form, trajectory, period, after, need)
    E = max(programme.least_error(T, R), 0.0)  # not -0 from rounding
    return BoundedLimit(error=E, move=trajectory.move(), period=period, max_torque=T, max_torque_rate=R, bound=float(bounds.max_error),
                        link=link, seconds=time.perf_counter() - started, rows_apart=programme.stride)


@dataclass(frozen=True)
class _Programme:
    """The rows of the module docstring's programme as sparse matrices: variables ``[x_0, x_s, x_2s .. x_M, u_0 .. u_{M-1},
    E, R, T]`` (``M``: the periods of the move and the horizon ``after`` it, a whole number of ``s = stride``; the states
    kept every ``stride`` periods, the tip bounded there)."""

    A_eq: Any
    b_eq: FloatArray
    A_ub: Any
    b_ub: FloatArray
    n_states: int
    M: int
    stride: int = 1

    @property
    def nx(self) -> int:
        """The state variables: ``n_states`` at every ``stride``-th period."""
        return (self.M // self.stride + 1) * self.n_states

    @classmethod
    def build(cls, form: Any, trajectory: Trajectory, period: float, after: float, need: float = 1.0) -> "_Programme":
        import scipy.sparse as sp

        K = max(1, math.ceil(trajectory.duration / period - 1e-9))
        M = K + max(1, math.ceil(after / period - 1e-9))
        N = form.n_states
        # a long programme keeps its states, and bounds the tip, at every `stride`-th period only: each of them a linear map
        # of the one before and the inputs between (exact); the inputs stay one a period, bounded as before
        stride = 1 if M * (N + 1) <= MAX_SIZE else math.ceil(M * N / max(MAX_SIZE - M, 1))
        if M > MAX_SIZE // 2 or stride > MAX_STRIDE:
            least = (trajectory.duration + after) * max(2.0, 1 + N / MAX_STRIDE) / MAX_SIZE
            raise SettingsError("period", period, f"at least {least:.3g} s for the bounded causal limit of this move: {M} periods "
                                f"of {N} states and the input are more than its {MAX_SIZE} with the states kept every {MAX_STRIDE} "
                                "periods")
        bounded = M // stride + 1  # the kept states within the horizon: the tip is bounded there
        M = stride * math.ceil(M / stride)  # inputs free after the horizon: they only lower E*
        J = M // stride
        t0, tf = trajectory.t0, trajectory.tf
        times = t0 + np.arange(J + 1) * stride * period
        y = trajectory.derivative(np.clip(times, t0, tf), 0)
        x0 = np.asarray(form.state(np.array([float(y[0])]), np.zeros(1), np.zeros((1, form.n_internal)))[0], dtype=float)
        before = float(form.equilibrium_input(float(y[0])))
        Ad, Bd = zero_order_hold(form.A, form.B, period)
        drives = [Bd]  # A_d^i B_d, i = 0 .. stride - 1
        for _ in range(stride - 1):
            drives.append(Ad @ drives[-1])
        jump, spread = np.linalg.matrix_power(Ad, stride), np.column_stack(drives[::-1])  # x_{j+1} = jump x_j + spread u_j..
        nx, nv = (J + 1) * N, (J + 1) * N + M + 3
        shift = sp.eye(J, J + 1, k=1, format="csr")
        stay = sp.eye(J, J + 1, format="csr")
        zeros = sp.csr_matrix((J * N, 3))
        dynamics = sp.hstack([sp.kron(shift, sp.eye(N)) - sp.kron(stay, jump), sp.kron(sp.eye(J), -spread), zeros])
        start = sp.hstack([sp.eye(N, nx), sp.csr_matrix((N, nv - nx))])
        A_eq = sp.vstack([dynamics, start], format="csr")
        b_eq = np.concatenate([np.zeros(J * N), x0])
        tip = sp.hstack([sp.kron(sp.eye(bounded, J + 1), form.C[None, :]), sp.csr_matrix((bounded, M))])
        y = y[:bounded]
        first = sp.eye(M) - sp.eye(M, k=-1)  # u_k - u_{k-1} (u_{-1} on the right-hand side)
        rate = sp.hstack([sp.csr_matrix((M, nx)), first])
        peak = sp.hstack([sp.csr_matrix((M, nx)), sp.eye(M)])
        lead = np.zeros(M)
        lead[0] = before
        blocks, column, rhs = [], [], []
        for block, which, value in ((tip, 0, y), (rate, 1, lead), (peak, 2, np.zeros(M))):
            for sign in (1.0, -1.0):  # |a - b| <= v: a - v <= b and -a - v <= -b
                blocks.append(sign * block)
                column.append(np.full(block.shape[0], which))
                rhs.append(sign * value)
        which = np.concatenate(column)
        slack = sp.csr_matrix((-np.ones(which.size), (np.arange(which.size), which)), shape=(which.size, 3))
        A_ub = sp.hstack([sp.vstack(blocks), slack], format="csr")
        b_ub = np.concatenate(rhs)
        # each state in units of its size when a torque of the rigid need's size drives the plant over the move (a
        # flexible mode's coordinate is 1e-5 of the hub's angle); measured on the programme's earlier form with half-way
        # rows: on the 3 mm strip with 4 modes at 1 ms the dual simplex then found E* in 26 s, where on the states as
        # they are it had not in 30 s; with 2 modes the interior point took 3.0 s against 9.1 s
        run = t0 + np.arange(M) * period
        drive = need * np.sin(2 * np.pi * (run - t0) / trajectory.duration) * (run <= tf)
        X, _ = recurrence(Ad, Bd[:, None], np.zeros(N), drive[:, None])
        size = np.abs(X).max(axis=0)
        size = np.where(size > 0, size, 1.0)
        scale = sp.diags(np.concatenate([np.tile(size, J + 1), np.ones(M + 3)]))
        A_eq, A_ub = (A_eq @ scale).tocsr(), (A_ub @ scale).tocsr()
        return cls(A_eq, b_eq, A_ub, b_ub, N, M, stride)

    def least_error(self, T: float, R: float) -> float:
        """``E*`` with the peak within ``T`` and the change within ``R`` (HiGHS's interior point, :data:`_PRESOLVE_CHAIN`)."""
        from scipy.optimize import linprog

        nx = self.nx
        c = np.zeros(nx + self.M + 3)
        c[nx + self.M] = 1.0
        bounds = [(None, None)] * (nx + self.M) + [(0.0, None), (0.0, R if math.isfinite(R) else None), (0.0, T if math.isfinite(T) else None)]
        statuses = []
        first = self.M // self.stride <= _PRESOLVE_CHAIN
        for presolve, seconds in zip((first, not first), _SECONDS):
            result = linprog(c, A_ub=self.A_ub, b_ub=self.b_ub, A_eq=self.A_eq, b_eq=self.b_eq, bounds=bounds, method="highs-ipm",
                             options={"time_limit": seconds, "presolve": presolve})
            if result.status == 0:
                return float(result.x[nx + self.M])
            statuses.append(f"interior point {'with' if presolve else 'without'} presolve: {result.message}")
        raise InversionError(f"the bounded causal limit was not found: {'; '.join(statuses)}")

"""The re-planned output: the move reshaped inside its error bound, then inverted exactly and causally.

The family of the paper (:mod:`inversion.family`) redefines the output segment by segment and follows ``y_d``'s
acceleration at every joint; the optimal-control feedforward (:mod:`inversion.methods.ocp`) reshapes the whole
move inside the error tube, which is where most of its lower peak torque comes from (``benchmarks/bench_ocp.py``: the
limit is within 2 % of a rigid link's). This module redefines the output once, over the whole move:

    y_r = y_d + delta,   delta = sum_k a_k B_k(t),   |delta(t)| <= bound

with ``B_k`` B-splines of degree 7 on ``[t_0, t_f]`` whose values and first four derivatives vanish at both ends (so
``y_r`` starts and ends as ``y_d`` does, and the input is continuous there), and the coefficients ``a`` chosen so that

* ``y_r`` is exactly and causally invertible from rest: for every zero ``lambda`` with ``Re lambda > 0`` the unstable
  internal mode driven by ``y_r``'s acceleration starts at zero, ``int_{t_0}^{t_f} e^{-lambda (t - t_0)} yddot_r dt =
  0`` -- the condition of the causal limit (docs/method.md section 7), ``Y_r(lambda) = 0``, which the paper's
  conditions 3-2 and 3-3 impose segment by segment;
* the end: by default (``"settle"``) the stable internal modes decay after ``t_f``, the input holding ``y_d(t_f)``;
  with ``"rest"`` every one ends at zero, ``int e^{lambda (t_f - t)} yddot_r dt = 0``; a purely imaginary zero's mode
  is held at zero either way (it would otherwise ring for ever);
* the peak of the exact inverse input (Eq. (12), the internal modes as above) is least, its change within the
  acceptance's rate bound: a linear programme (HiGHS), the input, the tube and the conditions all linear in ``a``;
  then, among the inputs within :data:`PEAK_SLACK` of that peak, the one of least total variation (the least peak alone
  is a vertex whose input rings between the bounds).

The knots are graded: a fast zero's condition lives within a few ``1/|lambda|`` of an end, so the spacing there is a
fraction of the fastest zero's time constant and grows geometrically to ``T / 40`` inside. ``y_r`` is then a piecewise
polynomial, and its exact inverse is stable inversion's closed form (:func:`~inversion.methods.stable.stable_inversion`
with ``reference=y_r``): no pre-actuation (the conditions hold; what little the programme's accuracy leaves before
``t_0`` is cut and its effect measured), and after ``t_f`` only the settling of the stable modes (none with ``"rest"``). The result is judged like every other
(:mod:`inversion.acceptance`): the distance of the plant's tip from ``y_d`` -- ``delta`` and that effect -- during the
move, after it and with more modes.

Only relative degree 2 (a link's tip; a system whose input reaches the output's second derivative) is re-planned.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from modelgen.zeros import is_imaginary

from ..acceptance import Criteria, demand, rest_state, window_length
from ..config import default, held_period, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.exponentials import exp_integrals
from ..lti.linear_system import LinearSystem
from ..lti.system import NormalForm
from ..options import End, InversionMethod, register
from ..problem import Problem
from ..result import InversionResult, report_row, summary_words
from ..signals.trajectory import PolynomialTrajectory, Trajectory
from .stable import stable_inversion

if TYPE_CHECKING:
    from modelgen.model import Model

__all__ = ["Replan", "ReplannedOutput", "replanned_output", "replanned_inversion", "Corners", "DEGREE"]

#: Degree of the B-splines of ``delta``: its values and first four derivatives vanish at both ends.
DEGREE = 7
#: The knot spacing inside the move, a fraction of its duration.
INNER_SPACING = 1.0 / 40.0
#: The knot spacing at the ends, a fraction of the fastest zero's time constant ``1/|lambda|``.
END_SPACING = 0.5
#: Growth of the spacing from an end inwards.
GRADING = 1.25
#: Points of the programme's grid in each knot interval.
POINTS_PER_INTERVAL = 20
#: The tube the programme keeps ``delta`` in, a fraction of the bound (what is left covers the controller's hold).
TUBE = 0.98
#: The input's rate of change the programme allows, a fraction of the judged bound on the change between rows over the
#: period (the rest is left for the hold).
SLOPE = 0.9
#: HiGHS's iteration limits on one solve of the programme (its interior point's, its dual simplex's): past them the stage
#: fails with HiGHS's status. No clock: the same programme gets the same answer on a free and on a busy machine
#: (measured: 20-60 interior-point iterations on the presets and the benchmark's links; one that does not converge ran to
#: 790 in 86 s on the aluminium bar's programme for its corners, where 200 stop it in a quarter of that).
ITERATIONS = {"highs-ipm": 200, "highs-ds": 200_000}
#: The peak the smoothing allows above the least one, a fraction of it.
PEAK_SLACK = 0.02
#: Other plants' rows (:func:`_cut_rows`): a programme starts with about this many of them, evenly spread, adds every row
#: its solution breaks (beyond this fraction of :attr:`Corners.bound`, HiGHS's own tolerance) and those within
#: ``CUT_NEAR`` of the bound, in at most ``CUT_ROUNDS`` solves (then all of them). Measured on the aluminium bar's two
#: corners through its 11.4 s window (9 516 rows): 2 000 to start, 7 617 after one solve (its corners ring near the
#: bound), three solves; with every row from the start HiGHS's interior point did not converge in 86 s.
CUT_START, CUT_TOLERANCE, CUT_NEAR, CUT_ROUNDS = 2_000, 1e-6, 0.02, 8
#: How many times the tube is narrowed when the held rows leave the bound (each time by what they exceed it).
SHRINKS = 3
_GAUSS_NODES, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(10)


@dataclass(frozen=True)
class ReplannedOutput:
    """A re-planned output and the programme's record.

    Attributes
    ----------
    output : PolynomialTrajectory
        ``y_r = y_d + delta``.
    peak : float
        The peak of its exact inverse input on the programme's grid.
    deviation : float
        ``max |delta|`` on the grid (m).
    splines : int
        The B-splines of ``delta``.
    residual : float
        Largest residual of the conditions, each row scaled to unit size.
    seconds : float
        The programme's time.
    """

    output: PolynomialTrajectory
    peak: float
    deviation: float
    splines: int
    residual: float
    seconds: float

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready record (the summary's ``replan`` block)."""
        return {"programme_peak": self.peak, "max_deviation": self.deviation, "splines": self.splines,
                "condition_residual": self.residual, "seconds": self.seconds, "degree": DEGREE}


@dataclass(frozen=True)
class Corners:
    """Other plants a re-planned output's input must hold.

    :func:`replanned_output`'s ``corners``. Each plant ``(A, B, C)`` in the model's coordinates starts at rest on ``y_d(t_0)``, is driven by the input's values
    at the controller's rows (``t_0 + k DT``, each held a period, as the acceptance holds a point table) and then by
    ``hold`` (the input after a rest end) over ``window``; its tip must stay within ``bound`` of ``y_d`` at every row
    and at every ``stride``-th period of the window.

    Attributes
    ----------
    plants : tuple of (ndarray, ndarray, ndarray)
        The plants.
    period : float
        The controller's period ``DT`` (s).
    bound : float
        The tube their tips are held in (m).
    hold : float
        The input after the move.
    window : float
        The window after it (s).
    link : bool
        Whether they are links (at rest: the joint turned, the deflections zero).
    stride : int
        The window's periods between its bounded ones.
    """

    plants: tuple[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]], ...]
    period: float
    bound: float
    hold: float
    window: float
    link: bool
    stride: int = 5

    @property
    def count(self) -> int:
        """The plants."""
        return len(self.plants)

    def rows(self, t0: float, tf: float) -> NDArray[np.float64]:
        """The controller's rows over the move.

        As :func:`inversion.acceptance.held_table` takes them.

        Parameters
        ----------
        t0, tf : float
            The move's span (s).
        """
        count = max(1, math.ceil((tf - t0) / self.period - 1e-9))
        return np.asarray(t0 + np.arange(count) * self.period, dtype=float)

    def responses(self, rows: NDArray[np.float64], y0: float) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """Each plant's tip at the rows and over the window, by input.

        Driven by the columns of ``rows`` (the first column's plant starts at rest on ``y0`` and is held at
        :attr:`hold` after them, the others from zero and then zero).

        Parameters
        ----------
        rows : ndarray, shape (K, c)
            The held inputs, by column.
        y0 : float
            The output at the start.

        Returns
        -------
        list of (ndarray, ndarray)
            By plant, ``(during, after)``: shapes ``(K + 1, c)`` and ``(W, c)`` (every :attr:`stride`-th period).
        """
        from ..lti.discrete import zero_order_hold

        out = []
        K, c = rows.shape
        steps = max(1, math.ceil(self.window / self.period - 1e-9))
        for A, B, C in self.plants:
            Ad, Bd = zero_order_hold(A, B, self.period)
            X = np.zeros((A.shape[0], c))
            X[:, 0] = rest_state(A, B, C, y0, self.link)
            during = np.empty((K + 1, c))
            during[0] = C @ X
            for k in range(K):
                X = Ad @ X + np.outer(Bd, rows[k])
                during[k + 1] = C @ X
            after = []
            hold = np.zeros(c)
            hold[0] = self.hold
            Ps, Bs = zero_order_hold(A, B, self.period * self.stride)
            for _ in range(max(1, steps // self.stride)):
                X = Ps @ X + np.outer(Bs, hold)
                after.append(C @ X)
            out.append((during, np.array(after)))
        return out

    def programme_rows(self, t: NDArray[np.float64], u_d: NDArray[np.float64], U: NDArray[np.float64],
                       trajectory: Trajectory) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The rows ``G x <= h`` of the linear programme.

        Every plant's tip within :attr:`bound` of ``y_d``, the input ``u_d + U x`` on the grid ``t``.

        Parameters
        ----------
        t : ndarray
            The programme's grid (the controller's rows among its points).
        u_d, U : ndarray
            The input's fixed part and its columns on the grid.
        trajectory : Trajectory
            The desired output.
        """
        at = np.searchsorted(t, self.rows(trajectory.t0, trajectory.tf))
        drive = np.c_[u_d[at], U[at]]
        K = at.size
        times = trajectory.t0 + np.arange(K + 1) * self.period
        y_rows = trajectory.derivative(np.clip(times, trajectory.t0, trajectory.tf), 0)
        y_final = float(trajectory.derivative(np.array([trajectory.tf]), 0)[0])
        G, h = [], []
        for during, after in self.responses(drive, float(y_rows[0])):
            for response, target in ((during, y_rows), (after, np.full(after.shape[0], y_final))):
                G += [response[:, 1:], -response[:, 1:]]
                h += [self.bound - (response[:, 0] - target), self.bound + (response[:, 0] - target)]
        return np.vstack(G), np.concatenate(h)

    def errors(self, u: NDArray[np.float64], trajectory: Trajectory) -> list[dict[str, float]]:
        """Each plant's largest tip error driven by held rows.

        ``|y - y_d|`` at the rows and over the window after them.

        Parameters
        ----------
        u : ndarray
            The held rows (the table's, what follows the move included).
        trajectory : Trajectory
            The desired output.
        """
        times = trajectory.t0 + np.arange(u.size + 1) * self.period
        y_rows = trajectory.derivative(np.clip(times, trajectory.t0, trajectory.tf), 0)
        y_final = float(trajectory.derivative(np.array([trajectory.tf]), 0)[0])
        out = []
        for during, after in self.responses(u[:, None], float(y_rows[0])):
            out.append({"max_tip_error": float(np.abs(during[:, 0] - y_rows).max()),
                        "after_end_excursion": float(np.abs(after[:, 0] - y_final).max())})
        return out


def graded_knots(t0: float, tf: float, fastest: float) -> NDArray[np.float64]:
    """The knots of ``delta``: fine at both ends, ``INNER_SPACING`` of the move inside.

    Parameters
    ----------
    t0, tf : float
        The move's span (s).
    fastest : float
        The largest ``|lambda|`` among the zeros (rad/s; 0 for none).

    Returns
    -------
    ndarray
        Increasing knots from ``t0`` to ``tf``, both included.
    """
    duration = tf - t0
    inner = INNER_SPACING * duration
    step = min(inner, END_SPACING / fastest) if fastest > 0 else inner
    side = [0.0]
    while side[-1] < duration / 2:
        side.append(side[-1] + step)
        step = min(step * GRADING, inner)
    side = np.array(side[:-1])
    # from both ends towards the middle, the middle interval no longer than the inner spacing
    left = t0 + side
    right = tf - side[::-1]
    middle = np.linspace(left[-1], right[0], max(2, math.ceil((right[0] - left[-1]) / inner) + 1))
    return np.unique(np.r_[left, middle, right])


def _basis(knots: NDArray[np.float64], t: NDArray[np.float64], derivative: int) -> NDArray[np.float64]:
    """The kept B-splines (or a derivative of them) at ``t``, shape ``(len(t), m)``."""
    from scipy.interpolate import BSpline  # lazy: keeps `import inversion` fast

    full = np.r_[[knots[0]] * DEGREE, knots, [knots[-1]] * DEGREE]
    count = full.size - DEGREE - 1
    spline = BSpline(full, np.eye(count), DEGREE, extrapolate=False)
    values = spline.derivative(derivative)(t) if derivative else spline(t)
    return np.nan_to_num(values)[:, 5:count - 5]  # the first and last five: delta and four derivatives vanish at the ends


def _moment_rows(form: NormalForm, trajectory: Trajectory, knots: NDArray[np.float64],
                 rest: bool) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The conditions ``rows @ a = rhs`` (real rows; module docstring), by Gauss-Legendre on every knot interval.

    One row a real zero, two a complex pair; each row scaled to unit size. Without ``rest`` the stable modes are free
    at ``t_f`` (they settle after it, the input holding ``y_d(t_f)``).
    """
    modal = form.modal(0.0)
    lam = modal.lam
    edges = np.union1d(knots, [b for b in trajectory.breakpoints if knots[0] < b < knots[-1]])
    half = np.diff(edges) / 2
    u = (edges[:-1, None] + half[:, None] * (1 + _GAUSS_NODES[None, :])).ravel()
    w = (half[:, None] * _GAUSS_WEIGHTS[None, :]).ravel()
    basis = _basis(knots, u, 2)
    desired = trajectory.derivative(u, 2)
    t0, tf = trajectory.t0, trajectory.tf
    rows, rhs = [], []
    imaginary = is_imaginary(lam)
    for i in np.flatnonzero(lam.imag >= 0):
        if not rest and lam[i].real < 0 and not imaginary[i]:
            continue
        kernel = np.exp(-lam[i] * (u - t0)) if lam[i].real > 0 else np.exp(lam[i] * (tf - u))
        row = (w * kernel) @ basis
        value = -(w * kernel) @ desired
        parts = [(row.real, value.real)] + ([(row.imag, value.imag)] if lam[i].imag > 0 else [])
        for r, v in parts:
            size = float(np.abs(r).max(initial=0.0))
            if size > 0:
                rows.append(r / size)
                rhs.append(v / size)
    return np.array(rows).reshape(-1, basis.shape[1]), np.array(rhs)


def _internal(lam: NDArray[np.complex128], beta: NDArray[np.complex128], t: NDArray[np.float64],
              yddot: NDArray[np.float64]) -> NDArray[np.complex128]:
    """Modal internal states of many accelerations (columns of ``yddot``, shape (N, m)) on the grid ``t``.

    Unstable modes backwards from zero at ``t[-1]``, the others forwards from zero at ``t[0]``; the acceleration linear
    between the points (exact for it). Shape (N, m, modes).
    """
    h = np.diff(t)
    z = np.zeros((t.size, yddot.shape[1], lam.size), dtype=complex)
    for i, rate in enumerate(lam):
        if rate.real > 0:  # weights of the ends of a linear input: h int_0^1 e^{x v} (1 - v) dv = h phi2, h (phi1 - phi2)
            decay, p1, p2 = exp_integrals(-rate * h)
            near, far = h * p2, h * (p1 - p2)
            for k in range(t.size - 2, -1, -1):
                z[k, :, i] = decay[k] * z[k + 1, :, i] - beta[i] * (near[k] * yddot[k] + far[k] * yddot[k + 1])
        else:
            growth, p1, p2 = exp_integrals(rate * h)
            early, late = h * (p1 - p2), h * p2
            for k in range(t.size - 1):
                z[k + 1, :, i] = growth[k] * z[k, :, i] + beta[i] * (early[k] * yddot[k] + late[k] * yddot[k + 1])
    return z


def _replannable(form: NormalForm, trajectory: Trajectory) -> None:
    """Refuse a plant of relative degree other than 2, or a move that is not piecewise polynomial (SettingsError)."""
    if form.rho != 2 or form.shift.any():
        raise SettingsError("method", "replan", f"a plant of relative degree 2 (this one's is {form.rho})")
    if not isinstance(trajectory, PolynomialTrajectory):
        raise SettingsError("trajectory", trajectory.name, "a piecewise polynomial trajectory for method='replan' (y_r = y_d + "
                                                           "delta is re-expanded piece by piece)")


def replanned_output(form: NormalForm, trajectory: Trajectory, bound: float, tube: float | None = None,
                     slope: float | None = None, end: str = "settle", corners: "Corners | None" = None,
                     explain: bool = True) -> ReplannedOutput:
    """The output of least peak exact inverse input near ``y_d``.

    Within ``tube`` of ``y_d``, causally invertible from rest (module docstring).

    Parameters
    ----------
    form : NormalForm
        The plant (relative degree 2).
    trajectory : Trajectory
        The desired output ``y_d``.
    bound : float
        The error bound (m).
    tube : float, optional
        The largest ``|y_r - y_d|`` (m; default :data:`TUBE` times ``bound``).
    slope : float, optional
        The largest rate of change of the input (per second; ``None``: any): a controller's bound on the change
        between its rows, divided by its period.
    end : {"settle", "rest"}
        ``"rest"``: every internal mode at zero at ``t_f`` (the input ends there); ``"settle"``: the stable ones decay
        after it, the input holding ``y_d(t_f)`` (a purely imaginary mode is held at rest either way).
    corners : Corners, optional
        Other plants the same input must hold (:class:`Corners`; ``end="rest"``): each one's tip, driven by the input's
        values at the controller's rows held a period each, within ``corners.bound`` of ``y_d`` at the rows and over
        the window after them -- rows of the same linear programme.
    explain : bool
        Whether a refusal says what would exist (the least tube the splines reach, the input's change without its bound:
        two programmes more); a caller that tries a wider tube next asks it only of the last.

    Returns
    -------
    ReplannedOutput

    Raises
    ------
    SettingsError
        For a relative degree other than 2.
    InversionError
        When no output of the splines meets the conditions within the bound (with the least tube they reach).
    """
    _replannable(form, trajectory)
    started = time.perf_counter()
    modal = form.modal(0.0)
    lam, beta = modal.lam, modal.beta
    t0, tf = trajectory.t0, trajectory.tf
    knots = graded_knots(t0, tf, float(np.abs(lam).max(initial=0.0)))
    # the programme's grid: every knot interval cut in equal parts (and the trajectory's breakpoints)
    parts = (knots[:-1, None] + np.diff(knots)[:, None] * np.arange(POINTS_PER_INTERVAL)[None, :] / POINTS_PER_INTERVAL).ravel()
    t = np.union1d(np.r_[parts, tf], [b for b in trajectory.breakpoints if t0 < b < tf])
    if corners is not None:  # the controller's rows are points of the grid: the corners are driven by them
        if end != "rest":
            raise SettingsError("end", end, "'rest' for a re-planned output that holds several plants (the input ends at t_f)")
        t = np.union1d(t, corners.rows(t0, tf))
    shapes = [_basis(knots, t, k) for k in range(3)]
    m = shapes[0].shape[1]
    desired = np.stack([trajectory.derivative(t, k) for k in range(3)], axis=1)  # (N, 3)
    z = _internal(lam, beta, t, np.c_[desired[:, 2], shapes[2]])
    XI = np.real(np.einsum("ij,nmj->nmi", modal.V, z))  # (N, 1 + m, 2n)
    outputs = np.stack([np.c_[desired[:, k], shapes[k]] for k in range(3)], axis=2)  # (N, 1 + m, 3)
    state = np.concatenate([outputs[:, :, :2], XI], axis=2)  # [y, ydot, X_I]
    X = np.einsum("ij,nmj->nmi", np.asarray(form.Tinv, dtype=float), state)
    u = (outputs[:, :, 2] - X @ np.ravel(form.CA2)) / float(form.CAB)  # Eq. (12) on the grid, (N, 1 + m)
    u_d, U = u[:, 0], u[:, 1:]
    rows, rhs = _moment_rows(form, trajectory, knots, end == "rest")
    tube = TUBE * bound if tube is None else tube
    slope = slope if slope is not None and math.isfinite(slope) else None
    extra = None if corners is None else corners.programme_rows(t, u_d, U * tube, trajectory)
    bound_rows = 0.0 if corners is None else corners.bound
    x, status = _programme(U * tube, u_d, shapes[0], rows * tube, rhs, None if slope is None else slope * np.diff(t), extra,
                           bound_rows)
    if x is None and not explain:
        raise InversionError(f"no re-planned output within {tube:.4g} m of y_d meets the conditions of a causal inverse ({status})")
    if x is None:
        least = _least_tube(shapes[0], rows, rhs)
        reached = f"; the least tube its {m} splines reach is {float(np.abs(shapes[0] @ least).max()):.4g} m" if least is not None else ""
        if slope is not None:
            free, _ = _programme(U * tube, u_d, shapes[0], rows * tube, rhs, None, extra, bound_rows)
            if free is not None:
                fastest = float(np.abs(np.diff(u_d + U @ (free * tube)) / np.diff(t)).max())
                reached = (f"; without the bound on the input's change it exists, changing {fastest / slope:.3g} x as fast as the "
                           f"bound allows (peak {float(np.abs(u_d + U @ (free * tube)).max()):.4g})")
        raise InversionError(f"no re-planned output within {bound:.4g} m of y_d meets the conditions of a causal inverse "
                             f"from rest{'' if slope is None else ' within the bound on the change between rows'}"
                             + ("" if corners is None else f" and holds the nominal plant's {corners.count} others within "
                                f"{corners.bound:.4g} m at once (narrower ranges may make it feasible)")
                             + f" ({status}){reached}")
    a = x * tube
    residual = float(np.abs(rows @ a - rhs).max(initial=0.0))
    delta = shapes[0] @ a
    output = _sum_output(trajectory, knots, a)
    return ReplannedOutput(output, float(np.abs(u_d + U @ a).max()), float(np.abs(delta).max()), m, residual,
                           time.perf_counter() - started)


def _solve(c: NDArray[np.float64], A_ub: Any, b_ub: NDArray[np.float64], rows: NDArray[np.float64], rhs: NDArray[np.float64],
           free: int, extra: int) -> Any:
    """``linprog`` of ``c`` under the conditions ``rows x = rhs``.

    ``free`` unbounded variables and ``extra`` non-negative ones, the conditions on the first of them. HiGHS's interior point without presolve goes first: its dual simplex, and the
    interior point after presolve, reported numerical trouble for 3-60 s on programmes that the plain interior point
    finds infeasible in 0.1 s. Where it stops without a verdict, it is asked again with every row of unit size
    (:func:`_unit_rows`: the same programme; neither scaling answers every programme, each answered where the other
    stopped: own-aluminium's 2 s move, heavy-payload's with six modes); the simplex takes over where neither answers.
    Each solve stops at its iteration limit (:data:`ITERATIONS`), never on a clock."""
    from scipy import sparse
    from scipy.optimize import linprog

    A_eq = sparse.hstack([sparse.csr_matrix(rows), sparse.csr_matrix((rows.shape[0], free + extra - rows.shape[1]))])
    bounds = [(None, None)] * free + [(0, None)] * extra
    b_ub, rhs = np.asarray(b_ub, dtype=float), np.asarray(rhs, dtype=float)
    for method, presolve, unit in (("highs-ipm", False, False), ("highs-ipm", False, True), ("highs-ds", True, False)):
        A, b = _unit_rows(sparse.csr_matrix(A_ub), b_ub) if unit else (A_ub, b_ub)
        E, e = _unit_rows(sparse.csr_matrix(A_eq), rhs, drop=False) if unit else (A_eq, rhs)
        out = linprog(c, A_ub=A, b_ub=b, A_eq=E, b_eq=e, bounds=bounds, method=method,
                      options={"maxiter": ITERATIONS[method], "presolve": presolve})
        if out.status in (0, 2):  # solved, or infeasible: no other method changes that
            return out
    return out


def _unit_rows(A: Any, b: NDArray[np.float64], drop: bool = True) -> tuple[Any, NDArray[np.float64]]:
    """The rows ``A x <= b`` (or ``= b``) each divided by its largest entry: the same set, every row of unit size.

    A row of zeros is dropped where ``drop`` and ``0 <= b`` holds it (it holds for every ``x``). The input's change over
    a stride has rows from 1e-8 to 2e4 (own-aluminium's 2 s move): HiGHS's interior point stopped at its 200 iterations
    and its dual simplex ran 12 s to "numerical difficulties"; with unit rows the interior point answers in 17 (the
    conditions' rows, 4e-3 at most, likewise)."""
    from scipy import sparse

    size = np.asarray(abs(A).max(axis=1).todense(), dtype=float).ravel()
    zero = size == 0
    keep = ~(zero & (b >= 0)) if drop else np.ones(size.size, dtype=bool)
    scale = np.where(zero, 1.0, size)[keep]
    return sparse.diags(1.0 / scale) @ A[keep], b[keep] / scale


def _least_tube(B: NDArray[np.float64], rows: NDArray[np.float64], rhs: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """The coefficients of least ``max |B a|`` that meet the conditions ``rows a = rhs`` (``None``: none found)."""
    from scipy import sparse

    n, m = B.shape
    one = np.ones((n, 1))
    out = _solve(np.r_[np.zeros(m), 1.0], sparse.csr_matrix(np.vstack([np.c_[B, -one], np.c_[-B, -one]])), np.zeros(2 * n),
                 rows, rhs, m + 1, 0)
    return out.x[:m] if out.status == 0 else None


def _programme(U: NDArray[np.float64], u_d: NDArray[np.float64], B: NDArray[np.float64], rows: NDArray[np.float64],
               rhs: NDArray[np.float64], change: NDArray[np.float64] | None,
               extra: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None, bound: float = 0.0
               ) -> tuple[NDArray[np.float64] | None, str]:
    """The programme's solution ``x`` (``a`` over the tube), or ``None`` and why (module docstring).

    The input on the grid is ``u_d + U x``, ``delta = B x`` within ``[-1, 1]``, the conditions ``rows x = rhs``, the
    input's change between neighbouring points at most ``change`` (per step), and ``extra``'s rows ``G x <= h`` (other
    plants' tips within ``bound``, :meth:`Corners.programme_rows`: those that bind, by a cutting plane, :func:`_cut_rows`).
    First the least peak; then, among the
    inputs within :data:`PEAK_SLACK` of it, the one of least total variation -- the least peak is a vertex, its input
    ringing between the bounds. Every row is scaled to unit size (the input by its desired peak); :func:`_solve` solves.
    """
    from scipy import sparse

    n, m = U.shape
    scale = float(np.abs(u_d).max(initial=0.0)) or 1.0
    Us, ud = U / scale, u_d / scale
    one = np.ones((n, 1))
    blocks = [np.c_[Us, -one], np.c_[-Us, -one], np.c_[B, 0 * one], np.c_[-B, 0 * one]]
    limits = [-ud, ud, np.ones(n), np.ones(n)]
    if change is not None:  # over strides of a quarter of a knot interval (the splines change no faster)
        stride = np.r_[np.arange(0, n - 1, max(1, POINTS_PER_INTERVAL // 4)), n - 1]
        span = np.add.reduceat(change, stride[:-1])
        dU, du = np.diff(U[stride], axis=0) / span[:, None], np.diff(u_d[stride]) / span
        blocks += [np.c_[dU, np.zeros((stride.size - 1, 1))], np.c_[-dU, np.zeros((stride.size - 1, 1))]]
        limits += [1 - du, 1 + du]
    A_ub, b_ub = np.vstack(blocks), np.concatenate(limits)
    G, h = (np.zeros((0, m)), np.zeros(0)) if extra is None else extra
    size = np.maximum(np.abs(G).max(axis=1, initial=0.0), 1e-300)  # each row to unit size, as the others
    G, h, unit = G / size[:, None], h / size, bound / size
    keep = _first_rows(G.shape[0])

    def least_peak(which: NDArray[np.bool_]) -> Any:
        return _solve(np.r_[np.zeros(m), 1.0], sparse.csr_matrix(np.vstack([A_ub, np.c_[G[which], np.zeros((int(which.sum()), 1))]])),
                      np.r_[b_ub, h[which]], rows, rhs, m + 1, 0)

    least, keep = _cut_rows(least_peak, G, h, keep, m, unit)
    if least.status != 0:
        return None, least.message.strip()
    # the variation over strides of half a knot interval (the splines do not ring faster): a tenth of the variables
    coarse = np.r_[np.arange(0, n - 1, max(1, POINTS_PER_INTERVAL // 2)), n - 1]
    steps = coarse.size - 1
    dUs, dus = np.diff(Us[coarse], axis=0), np.diff(ud[coarse])
    cap = np.r_[np.zeros(m), 1.0]

    def smoothest(which: NDArray[np.bool_]) -> Any:
        A_in = np.vstack([A_ub, np.c_[G[which], np.zeros((int(which.sum()), 1))]])
        A = sparse.vstack([sparse.hstack([sparse.csr_matrix(A_in), sparse.csr_matrix((A_in.shape[0], steps))]),
                           sparse.hstack([sparse.csr_matrix(cap[None, :]), sparse.csr_matrix((1, steps))]),
                           sparse.hstack([sparse.csr_matrix(np.c_[dUs, np.zeros((steps, 1))]), -sparse.identity(steps)]),
                           sparse.hstack([sparse.csr_matrix(np.c_[-dUs, np.zeros((steps, 1))]), -sparse.identity(steps)])], format="csr")
        return _solve(np.r_[np.zeros(m + 1), np.ones(steps)], A, np.r_[b_ub, h[which], (1 + PEAK_SLACK) * least.x[m], -dus, dus], rows,
                      rhs, m + 1, steps)

    smooth, _ = _cut_rows(smoothest, G, h, keep, m, unit)
    return (smooth.x if smooth.status == 0 else least.x)[:m], ""


def _first_rows(count: int) -> NDArray[np.bool_]:
    """Of ``count`` rows of other plants (:meth:`Corners.programme_rows`), those a programme starts with: about
    :data:`CUT_START`, evenly spread (:func:`_cut_rows`)."""
    keep = np.zeros(count, dtype=bool)
    keep[:: max(1, count // CUT_START)] = True
    return keep


def _cut_rows(solve: Callable[[NDArray[np.bool_]], Any], G: NDArray[np.float64], h: NDArray[np.float64], keep: NDArray[np.bool_],
              m: int, unit: Any) -> tuple[Any, NDArray[np.bool_]]:
    """``solve`` with the rows ``G x <= h`` that bind, by a cutting plane.

    With ``keep``'s rows, then with every row its solution breaks (by more than :data:`CUT_TOLERANCE` of ``unit``, the
    bound in each row's units) and those within :data:`CUT_NEAR` of it, until it breaks none: its optimum is then the
    programme's with every row (it holds them all, and no ``x`` holding them all does better); a subset without a
    solution means none with all. At most :data:`CUT_ROUNDS` solves, then every row. Returns the solution and the rows
    solved with."""
    keep = keep.copy()
    unit = np.broadcast_to(np.asarray(unit, dtype=float), h.shape)
    for _ in range(CUT_ROUNDS):
        if keep.all():
            break
        out = solve(keep)
        if out.status != 0:
            return out, keep
        slack = h - G @ out.x[:m]
        broken = bool((slack[~keep] < -CUT_TOLERANCE * unit[~keep]).any())
        keep |= slack < CUT_NEAR * unit
        if not broken:
            return out, keep
    keep[:] = True
    return solve(keep), keep


def _sum_output(trajectory: PolynomialTrajectory, knots: NDArray[np.float64], a: NDArray[np.float64]) -> PolynomialTrajectory:
    """``y_d + delta`` as one piecewise polynomial on the knots and ``y_d``'s breakpoints (exact)."""
    from scipy.interpolate import BSpline, PPoly  # lazy: keeps `import inversion` fast

    full = np.r_[[knots[0]] * DEGREE, knots, [knots[-1]] * DEGREE]
    coefficients = np.zeros(full.size - DEGREE - 1)
    coefficients[5:coefficients.size - 5] = a
    delta = PPoly.from_spline(BSpline(full, coefficients, DEGREE))
    edges = np.union1d(knots, [b for b in trajectory.breakpoints if knots[0] < b < knots[-1]])
    # each piece of y_d + delta re-expanded about its left edge: its Taylor coefficients from both parts' derivatives
    order = max(DEGREE, trajectory.ppoly.c.shape[0] - 1) + 1
    left = edges[:-1]
    c = np.empty((order, left.size))
    pieces = trajectory.ppoly
    for k in range(order):
        part = delta.derivative(k)(left) if k else delta(left)
        # y_d's own pieces, read directly: a sampled move's spline (degree 5) offers no derivative above its order, whose
        # pieces' higher coefficients are zero all the same
        own = pieces.derivative(k)(left) if 0 < k <= pieces.c.shape[0] - 1 else (pieces(left) if k == 0 else np.zeros_like(left))
        c[order - 1 - k] = (own + np.nan_to_num(part)) / math.factorial(k)
    return PolynomialTrajectory(PPoly(c, edges), f"{trajectory.name}, re-planned")


def replanned_inversion(model: Model | LinearSystem, trajectory: Trajectory, *, max_error: float | None = None,
                        rate: float | None = None, bounds: Criteria | None = None, end: str | None = None,
                        plants: Any = None, plant_names: Any = None, explain: bool = True) -> InversionResult:
    """The exact causal inverse of the re-planned output.

    Judged against ``y_d``, as every result is (:mod:`inversion.acceptance`).

    Parameters
    ----------
    model : Model or LinearSystem
        The plant (relative degree 2).
    trajectory : Trajectory
        The desired output ``y_d``.
    max_error : float, optional
        The bound on ``|y_r - y_d|`` (m; default the judged bound, a fraction of the move).
    rate : float, optional
        The samples' rate (Hz).
    bounds : Criteria, optional
        What the result is judged with (:mod:`inversion.acceptance`).
    end : {"settle", "rest"}, optional
        How the input ends (:func:`replanned_output`; default ``"settle"``, ``"rest"`` with ``plants``).
    plants : sequence of (A, B, C), optional
        Other plants the same table must hold (:class:`Corners`), the nominal one's own tube kept: in the programme, then
        measured on the held rows; ``summary["replan"]["plants"]`` has each one's figures.
    plant_names : sequence of str, optional
        Their names in the summary.
    explain : bool
        Whether a refusal says what would exist (:func:`replanned_output`).

    Returns
    -------
    InversionResult
        A stable inversion's result of ``y_r`` (:func:`~inversion.methods.stable.stable_inversion`), its ``summary``
        with ``method = "replan"`` and the programme's record under ``replan``.
    """
    end = ("settle" if not plants else "rest") if end is None else end
    if end not in ("settle", "rest"):
        raise SettingsError("end", end, "'settle' or 'rest' for the re-planned output (its input holds y_d(t_f) afterwards)")
    form = NormalForm.of_system(model) if isinstance(model, LinearSystem) else NormalForm.of_model(model)
    bound = tip_bound(max_error, trajectory.move())
    if not math.isfinite(bound):  # inf accepts any result elsewhere; here the bound is the tube the output is planned in
        raise SettingsError("max_error", max_error, "a finite number > 0 for method='replan' (the tube the output is re-planned "
                            "within: the default is 1 % of the move)")
    judged = Criteria(max_error=bound, period=held_period(None, rate)) if bounds is None else bounds
    rigid_rate = demand(form, trajectory, judged.period).rigid_rate
    slope = SLOPE * judged.rate_limit(rigid_rate, form.inertia is not None)[0] / judged.period
    # a controller holding each row for a period lags the input by half of it, so at the rows the tip trails y_r by about
    # max |ydot_d| DT / 2: the tube starts that much narrower (measured at 1 ms, the rows' excess over the tube: 0.142 of
    # the bound on paper-exp and 0.0146 on paper-sim, where this gives 0.156 and 0.017), and the loop below narrows it
    # further where the rows still exceed it (a zero-order hold's mean errs O(DT^2): no lag assumed)
    lag = 0.0
    if judged.hold == "point":
        lag = 0.5 * judged.period * float(np.abs(trajectory.derivative(np.linspace(trajectory.t0, trajectory.tf, 4001), 1)).max())
    tube = TUBE * bound - min(lag, 0.5 * TUBE * bound)
    corners = None
    if plants:
        asked = demand(form, trajectory, judged.period)
        corners = Corners(tuple((np.asarray(A, dtype=float), np.asarray(B, dtype=float).reshape(-1), np.asarray(C, dtype=float).reshape(-1))
                                for A, B, C in plants), judged.period, TUBE * bound, float(asked.hold_final),
                          float(window_length(form, judged.window)), form.inertia is not None)
    tries = []
    figures: list[dict[str, float]] = []
    for _ in range(SHRINKS + 1):
        replanned = replanned_output(form, trajectory, bound, tube, slope, end, corners, explain)
        result = stable_inversion(model, trajectory, default("rate", rate), bounds=judged, preview=0.0, reference=replanned.output)
        held = result.summary["sampled"]["max_tip_error"]
        tries.append({"tube": tube, "held_tip_error": held})
        worst = 0.0
        if corners is not None:  # the corners driven by the rows the acceptance holds, measured
            from .margin import held_rows

            figures = corners.errors(held_rows(result).u, trajectory)
            worst = max(max(f.values()) for f in figures)
            tries[-1].update(plants_bound=corners.bound, plants_error=worst)
        if held <= TUBE * bound and worst <= TUBE * bound:
            break
        # the controller's hold adds to the tube: narrow it by what the held rows exceed, and plan again
        if held > TUBE * bound:
            tube -= 1.2 * (held - TUBE * bound)
        if corners is not None and worst > TUBE * bound:
            corners = replace(corners, bound=corners.bound - 1.2 * (worst - TUBE * bound))
        if tube <= 0 or (corners is not None and corners.bound <= 0):
            break
    summary = result.summary
    summary["method"] = "replan"
    summary["settings"] = {"method": "replan", "rate": summary["settings"]["rate"], "max_error": bound, "end": end}
    summary["replan"] = {**replanned.as_dict(), "tubes": tries}
    if corners is not None:
        names = list(plant_names) if plant_names is not None else [f"plant {i + 1}" for i in range(corners.count)]
        summary["replan"]["plants"] = [{"name": str(n), **f} for n, f in zip(names, figures)]
    return result


@register
@dataclass(frozen=True)
class Replan(InversionMethod):
    """The re-planned output, inverted exactly.

    The re-planned output: the move reshaped within the bound (a linear programme over splines) so that it is exactly,
    causally invertible, inverted exactly -- near the optimal-control limit's peak torque, smooth, in about a second.

    Its output is planned within ``(1 - margin)`` of the bound, then within half that, then at the bound, until its peak
    is within the torque bound.

    Attributes
    ----------
    end : {"settle", "rest"}, optional
        The internal modes settle after ``t_f`` (default) or are at rest there.
    """

    name = "replan"
    label = "the re-planned output"
    title = "re-planned output's feedforward"
    rank = 6.0
    stage = 1.0
    plans = True
    redefines = True
    help = ("the move reshaped within --max-error (a linear programme over splines) so that it is exactly, causally invertible "
            "and ends at rest, inverted exactly: near the optimal-control limit's peak torque, smooth, in about a second")
    series_text = "the stable inversion's quadrature and tails re-expanded (of the re-planned output)"

    end: str | None = None

    def check(self, problem: Problem) -> None:
        """Refuse a plant of another relative degree, before any work.

        Refuse, before any work (the bounded causal limit asked first among it), a plant whose relative degree is not 2 and
        a move that is not piecewise polynomial (:func:`replanned_output`'s refusals).

        Parameters
        ----------
        problem : Problem
            What the user asked.
        """
        _replannable(problem.form, problem.trajectory)

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The re-planned output's exact inverse within the margin.

        The re-planned output's exact inverse (:func:`replanned_inversion`) within the margin the torque bound allows.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        say : callable
            The progress display.
        """
        from .margin import margin_block

        bound = problem.bound()
        judged = problem.criteria(bound, max_torque=None)
        corners = problem.corners
        kept = problem.kept

        def replanned(share: float, explain: bool) -> InversionResult:
            return replanned_inversion(problem.system, problem.trajectory, max_error=bound * (1 - share), rate=problem.rate,
                                       end=self.end, bounds=replace(judged, max_error=bound * (1 - share)),
                                       plants=None if corners is None else corners[1],
                                       plant_names=None if corners is None else corners[0], explain=explain)

        def within(result: InversionResult) -> bool:
            return judged.torque_limit(float(result.summary["rigid_torque"])) >= float(result.summary["peak_torque"])

        # the margin's tube first; where it fails, the bound's own (the widest: where it fails, every narrower one does,
        # and its refusal says why), then half the margin between them. A refusal costs two tries, not three (each with
        # its explanation's two programmes more: own-aluminium's 2 s move took 106 s to refuse)
        share = kept
        try:
            result = replanned(kept, explain=kept == 0)
            fits = within(result)
        except InversionError:
            if kept == 0:
                raise
            fits = False
        if not fits and kept > 0:
            share, result = 0.0, replanned(0.0, explain=True)  # raises where no re-planned output exists
            try:
                halfway = replanned(kept / 2, explain=False)
                if within(halfway):
                    share, result = kept / 2, halfway
            except InversionError:
                pass
        result.summary["max_error"] = bound
        result.summary["settings"]["max_error"] = bound
        result.summary["margin"] = margin_block(result, bound, aimed=bound * (1 - share), asked=kept, gains=problem.gains)
        return result

    def for_automatic(self, stage: Any) -> tuple[InversionMethod, Problem] | str:
        """The automatic choice's second stage.

        The second stage, where no member of the family passes: a rest or settle end where one was asked.

        Parameters
        ----------
        stage : inversion.methods.automatic.Stage
            The automatic choice's figures so far.
        """
        if not (stage.problem.form.rho == 2 and isinstance(stage.problem.trajectory, PolynomialTrajectory)):
            return "it re-plans a piecewise polynomial move of a plant of relative degree 2"
        end = stage.family.end if stage.family.end in (End.REST, End.SETTLE) else None
        return Replan(end=end), stage.aimed()

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """The re-plan in a sentence.

        ``"the move reshaped within 0.0157 m (12 splines of degree 7), inverted exactly; settle end"``.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s, settings = summary, summary["settings"]
        return (f"the move reshaped within {settings['max_error']:.3g} m ({s['replan']['splines']} splines of degree "
                f"{s['replan']['degree']}), inverted exactly; {settings['end']} end")

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """The C header's line.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return (f"re-planned output: y_r within {settings['max_error']:.6g} of y_d (B-splines), inverted exactly from rest, "
                f"{settings.get('end', 'settle')} end")

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of ``sflm invert``'s text.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s = summary
        w = summary_words(s)
        m, unit, sym = w["m"], w["unit"], w["sym"]
        plan = s["replan"]
        return [
            f"{s['model']}: the re-planned output (the move reshaped within the bound, inverted exactly; causal, "
            + ("at rest at tf)" if s["settings"]["end"] == "rest" else "its internal modes settling after tf)"),
            report_row("trajectory", s["trajectory"]),
            report_row("max |y_r - y_d|", f"{s['max_redefinition_error']:.4g}{m} = {100 * s['relative_redefinition_error']:.3g} % "
                       f"of the {s['move']:.4g}{m} move (accepted {s['max_error']:.3g}{m})"),
            report_row(f"peak |{sym}|", f"{s['peak_torque']:.5g}{unit} (at t = {s['time_of_peak_torque']:.4g} s); {sym}(t0) = "
                       f"{s['torque_at_start']:.2g}{unit}, {sym}(tf) = {s['torque_at_end']:.2g}{unit}"),
            report_row("programme", f"{plan['splines']} splines of degree {plan['degree']}, {len(plan['tubes'])} solve(s) in "
                       f"{plan['seconds']:.2g} s (the last with |y_r - y_d| <= {plan['tubes'][-1]['tube']:.3g}{m}); conditions "
                       f"met to {plan['condition_residual']:.1e}"),
            report_row("post-actuation", f"{s['post_actuation_time']:.4g} s of {w['inp']} after tf, holding y_d(tf) while the "
                       "internal modes " + ("settle" if s["settings"]["end"] == "settle" else
                                            "lose what the rounding of the rest conditions left")),
            report_row("samples", f"{s['samples']} at {s['settings']['rate']:g} Hz"),
        ]

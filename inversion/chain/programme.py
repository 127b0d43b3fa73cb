"""The chain programme: a held plant, its rows and its bounds, period by period -- built once, solved by HPIPM.

The bounded causal limit (:mod:`inversion.methods.bounded_limit`) and the optimal-control feedforward
(:mod:`inversion.methods.ocp`) are the same programme with other unknowns. On the plant held at the controller's
period ``DT`` (``x_{k+1} = A_d x_k + B_d u_k``, :func:`inversion.lti.discrete.zero_order_hold`), from its state ``x_0``
at ``t_0`` with the input ``u_{-1}`` before the move, over ``M`` periods of which the first ``K`` have inputs of their
own (after them the input holds ``u_hold``, or stays free where none is given)::

    |C x_k - y_k| <= E                       k = 1 .. M          (the rows)
    |C x_{k+1/2} - y_{k+1/2}| <= E           k = 0 .. M - 1      (half-way between them, where asked)
    |u_k| <= T,  |u_k - u_{k-1}| <= R         (the peak and the change between rows; the last against u_hold)
    |u_k + m_j x_k| <= T_m,  |u_k + s x_k + (h - 1) u_{k-1}| <= R_m    (a motor in a loop, where asked: :class:`Motor`)
    x_K = x_rest                              (a rest end, where asked: within REST_BAND)
    zero directions at the last row           (where asked: the move's unstable zeros after the horizon)

and minimises one of: ``E`` (the bounded limit: ``T`` and ``R`` given); the peak ``s = max |u_k|`` with a trace of the
rows' total variation and of their energy (the optimal-control table, ``E`` given); the energy ``sum u_k^2 DT``.

**Stages.** The unknowns that are one number for the whole move (``E``, ``s``) are states that stay the same from stage
to stage, and the input before each one (``u_{k-1}``) is a state too: every bound is on one stage's states and inputs,
the structure HPIPM's Riccati recursion factorises in time linear in ``M`` (:mod:`inversion.chain.hpipm`). The first
stage carries only those constants (``x_0`` and ``u_{-1}`` are known); an input a stage may not choose (after ``K``) is
no variable: ``u_hold`` is in the stage's ``b`` (equal bounds stall an interior point, :data:`REST_BAND`). Stages that
share their matrices go to HPIPM as blocks, each its row of the bounds (:class:`inversion.chain.hpipm.Block`).

**Units.** Each state is in units of its size when a torque of the rigid need's size drives the plant over the move,
each input in units of that need, each row in units of the output's scale (the bound, or the move): every number HPIPM
sees is of order one, and its tolerance is relative.

**The horizon's end** (:func:`zero_directions`). A row's bound after the horizon constrains the horizon too: for an
unstable zero ``zeta`` of the held plant (``|zeta| > 1``, beyond every pole), the row vector ``l`` and number ``m`` with
``l (A_d - zeta I) + m C = 0``, ``l B_d = 0`` give ``q_k = l x_k`` with ``q_{k+1} = zeta q_k - m y_k``, driven by the output
alone. A feedforward whose output stays within ``E`` of ``y_f`` at every later row, its states bounded, has
``|q_M - m y_f / (zeta - 1)| <= |m| E / (|zeta| - 1)``: a necessary condition at the last row (a complex pair: its
octagon), so the programme stays a relaxation -- its ``E`` a bound -- and a slow unstable zero no longer hides beyond a
short horizon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import InversionError, SettingsError
from ..lti.discrete import recurrence
from .hpipm import Block, ChainSolution, Stage, solve_chain

__all__ = ["Chain", "ChainResult", "Motor", "Window", "zero_directions", "window_rows", "work", "check_size", "MAX_WORK", "MAX_LP_WORK",
           "STAGE_OVERHEAD", "ROW_OVERHEAD", "BLOCK_WIDTH", "ITERATIONS", "TOLERANCE"]

FloatArray = NDArray[np.float64]
#: HPIPM's iteration limit (the only limit: no clock). Measured: 20-95 iterations on every programme of the benchmarks.
ITERATIONS = 300
#: A first solve stops here; one whose residuals all stand within :data:`STALLED` is kept, any other is solved again
#: up to :data:`ITERATIONS`. Measured: a solve that reaches its rounding floor above :data:`TOLERANCE` (the shortest
#: smoothstep's table: stationarity 1.5e-12 to 2.6e-12 from iteration 50 on) ran 300 iterations for the same table to
#: 1e-11, 0.7 s of its 3 s. Above the 93 the same table's loop programme takes: a solve past it pays twice.
FIRST_ITERATIONS = 120
#: The residuals of a solve kept at :data:`FIRST_ITERATIONS`: at its rounding floor, not on its way down.
STALLED = 1e-10
#: A solve stopped at :data:`FIRST_ITERATIONS` goes on only with every residual within this: beyond it the iterates are
#: not converging (measured: an infeasible programme at 4e15, which then stopped at HPIPM's least step after 165), and
#: the programme is refused at once with its figures. Measured on 138 solves of the optimal-control tests: every one
#: solved took at most 69 iterations.
RESUMED = 1.0
#: HPIPM's tolerance on every residual, of a programme in the units above (measured: 25-40 iterations reach it).
TOLERANCE = 1e-12
#: A rest end holds each state within this of its rest value (in its units above): a band, not an equality -- an
#: interior point cannot step inside bounds of zero width, and HPIPM stalled on them (300 iterations, its stationarity
#: stuck at 1e-9 to 1e14), where with a band of 1e-6 to 1e-10 it solves in 30-40 (measured on the steel strip).
REST_BAND = 1e-10
#: A solve that stops at its iteration limit, or at its least step, with every residual within this is accepted (and its
#: record says so): the figures it gives are good to about this, relative.
ACCEPT = 1e-8
#: A stage's share of an iteration beside its factorisation, in :func:`work`'s units (a ``w^3`` each, about 1e-9 s an
#: iteration here): HPIPM's and BLASFEO's fixed costs per stage, which dominate a narrow plant's. Fitted on this project's
#: 2-core machine (2026-12-06) to HPIPM's solves, a stage and an iteration (measured / the measure's): the paper's member
#: at 0.1-0.2 ms (width 10, 8 rows, 27 500-55 000 stages) 6.7-9.5 / 9.2 us; its rows 50 periods apart (106 rows) 34-49 /
#: 48 us; the 3 mm strip with 6 modes (width 18, 8 rows) 13.7 / 14.3 us; the heavy payload's 4 corner plants (width 33,
#: 11 rows, 2 000 stages, 16 399 condensed rows) 0.088 / 0.090 s an iteration; the aluminium bar with its corners in both
#: loops (width 114, 17 rows, 101 stages, 3 865 condensed rows) 0.076 / 0.074 s an iteration.
STAGE_OVERHEAD = 5_000
#: A bound's share of a stage's iteration beside its ``w^2`` (the same fit): a row costs about 0.4 us at width 10.
ROW_OVERHEAD = 300
#: Below this width a stage's factorisation costs its ``w^3``; above it, ``sqrt(w / BLOCK_WIDTH)`` times less (BLASFEO's
#: kernels are faster on larger blocks: the same fit, widths 18 to 114).
BLOCK_WIDTH = 12
#: The largest programme solved, in :func:`work`'s units (its stages times a stage's work per iteration): about 0.2 s an
#: iteration here, 12 s for the 60 iterations an optimal-control programme may take, its whole run (three solves) within
#: about half a minute. The paper's move at 0.1 ms, every period (5.1e8), took 57 s and 0.8 GB (issue 59, item 11: past
#: a minute where a check refuses it at once); at 0.2 ms (2.5e8), 29 s. Beyond it a programme is refused at once, naming
#: the period that fits (the optimal-control method puts its rows several periods apart instead, where it can).
MAX_WORK = 200_000_000
#: The largest linear programme (the bounded causal limit's, the fastest move's), in the same units: they take 10-20
#: iterations where the optimal-control programme takes 40-60 (measured: the paper's move at 0.1 ms, 73 335 stages of
#: width 9, 6.4e8, in 7-11 s and 13-15 iterations).
MAX_LP_WORK = 4 * MAX_WORK


def work(periods: int, states: int, variation: bool = False, rows: int = 8, final: int = 0) -> int:
    """A programme's size: its stages times a stage's factorisation.

    The measure of :data:`MAX_WORK`: a stage's width ``w`` is its states and inputs, its factorisation ``w^3``, its
    ``rows`` bounds' share ``rows (w^2 + ROW_OVERHEAD)`` and the fixed cost of a stage (:data:`STAGE_OVERHEAD`); the last
    stage's ``final`` rows (a window condensed onto it, :attr:`Chain.after`) add ``final (w^2 + ROW_OVERHEAD)``. The
    powers of ``w`` count ``sqrt(BLOCK_WIDTH / w)`` as much above :data:`BLOCK_WIDTH` (the constants' fit).

    Parameters
    ----------
    periods : int
        Its stages.
    states : int
        The plant's states.
    variation : bool
        Whether the rows' total variation is in the objective (one input more a stage).
    rows : int
        The bounds a stage holds (the tip's, the input's; a ramp's table adds two for each period inside a row).
    final : int
        The rows of the last stage beyond its own (:attr:`Chain.after`).
    """
    width = states + 3 + (1 if variation else 0)
    blocks = min(1.0, math.sqrt(BLOCK_WIDTH / width))  # larger blocks, faster kernels
    cube, row = width**3 * blocks, width**2 * blocks + ROW_OVERHEAD
    return int(int(periods) * (cube + int(rows) * row + STAGE_OVERHEAD) + int(final) * row)


def check_size(periods: int, states: int, variation: bool, period: float | None, span: float | None = None,
               what: str = "this programme", rows: int = 8, final: int = 0, linear: bool = False) -> None:
    """Refuse a programme beyond :data:`MAX_WORK`, before any work.

    The refusal names the least period that fits.

    Parameters
    ----------
    periods, states, variation, rows, final
        As :func:`work`.
    period : float or None
        The period asked for (s), named in the refusal.
    span : float, optional
        The programme's time span (s): the least period that fits is computed from it.
    what : str
        What the programme is, for the message.
    linear : bool
        A linear programme (:data:`MAX_LP_WORK` its limit).

    Raises
    ------
    SettingsError
        Naming the period, the size and the limit.
    """
    size, limit = work(periods, states, variation, rows, final), (MAX_LP_WORK if linear else MAX_WORK)
    if size <= limit:
        return
    longest = max(0, limit - work(0, states, variation, rows, final)) // work(1, states, variation, rows)
    least = "" if span is None else f"at least {span / max(longest, 1):.3g} s for {what}: "
    raise SettingsError("period", period, f"{least}{periods} periods of a {states}-state plant are {size:.3g} units of work, "
                        f"more than the {limit:.3g} one chain programme takes (at most {longest} periods of this plant)")


@dataclass(frozen=True)
class ChainResult:
    """A solved chain programme, in the plant's units.

    Attributes
    ----------
    u : ndarray, shape (K,)
        The inputs of the stages that choose theirs (with a ramp: the rows after the first, which is ``u_{-1}``).
    error : float
        ``E`` (the one asked, or the least found).
    peak : float
        ``s`` (the one asked, or the least found; ``inf`` where none).
    solution : ChainSolution
        HPIPM's record.
    """

    u: FloatArray
    error: float
    peak: float
    solution: ChainSolution

    def record(self) -> dict[str, Any]:
        """HPIPM's status, iterations and residuals (JSON-ready)."""
        s = self.solution
        return {"solver": "hpipm", "status": "solved" if s.solved else s.message, "iterations": s.iterations,
                "residuals": {k: v for k, v in s.residuals.items() if k != "obj"}}


def zero_directions(Ad: FloatArray, Bd: FloatArray, C: FloatArray) -> list[tuple[complex, FloatArray, complex]]:
    """The held plant's unstable zeros and their directions.

    Its zeros beyond every pole, each with its row vector ``l`` and number ``m``:
    ``[l, m] [[A_d - zeta I, B_d], [C, 0]] = 0`` (module docstring), the left null vectors of the Rosenbrock pencil at
    its finite generalised eigenvalues ``zeta``, kept where ``|zeta| > max(1, rho(A_d))`` by a margin (one of each
    complex pair), each scaled so that ``m = 1``.

    Parameters
    ----------
    Ad, Bd, C : ndarray
        The held plant (``C`` one row).
    """
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    N = Ad.shape[0]
    pencil = np.zeros((N + 1, N + 1))
    pencil[:N, :N], pencil[:N, N], pencil[N, :N] = Ad, Bd, C
    eye = np.zeros((N + 1, N + 1))
    eye[:N, :N] = np.eye(N)
    values, left = sla.eig(pencil, eye, left=True, right=False, homogeneous_eigvals=True)
    alpha, beta = values
    radius = max(1.0, float(np.abs(np.linalg.eigvals(Ad)).max(initial=0.0)))
    found = []
    for i in range(N + 1):
        if abs(beta[i]) <= 1e-12 * abs(alpha[i]):
            continue  # infinite: the relative degree
        zeta = complex(alpha[i] / beta[i])
        if abs(zeta) <= radius * (1 + 1e-6) or zeta.imag < 0:
            continue
        w = np.conj(left[:, i])  # w^H pencil = zeta w^H eye
        if abs(w[N]) == 0:
            continue
        w = w / w[N]
        # the residual of the defining equations, relative: a pencil this badly conditioned gives no usable row
        ell = w[:N]
        if np.abs(ell @ Bd) > 1e-8 * (np.abs(ell).max() * np.abs(Bd).max() + 1e-300):
            continue
        found.append((zeta, ell, complex(1.0)))
    return found


@dataclass(frozen=True)
class Motor:
    """A motor in a loop: its torque and steps at the rows.

    What a motor delivers where the table is fed forward inside a loop (the joint PD on the plan's own references). In a
    loop plant ``j`` stacked in the state, the motor's torque over period ``k`` is ``u_k + K_n x_k - K_j x(t)`` (the
    PD's references the nominal plan's state at the row, held; its measurement the loop plant's): at the rows
    ``u_k + m_j x_k`` (``m_j = K_n - K_j``), bounded by ``peak``. It steps at a row by the table's change and the
    references': ``u_k - u_{k-1} + K_n (x_k - x_{k-1})``, and the nominal plant's ``x_{k-1} = A_n^{-1} (x_k - B_n u_{k-1})``
    makes that ``u_k + (K_n - g) x_k + (h - 1) u_{k-1}`` with ``g = K_n A_n^{-1}``, ``h = g B_n``: bounded by ``rate``.
    After the table the input holds and the references rest: the motor's torque at the first held row is ``after - K_j
    x_K`` and its step there ``after - g x_K + (h - 1) u_{K-1}`` (``after``: the held input and the PD on the rest).

    Attributes
    ----------
    torque : ndarray, shape (L, N)
        The rows ``m_j`` (one a loop plant).
    held : ndarray, shape (L, N)
        The rows ``-K_j``.
    step : ndarray, shape (N,)
        ``K_n - g``.
    back : ndarray, shape (N,)
        ``g``.
    h : float
        ``g B_n``.
    peak, rate : float
        The motor's bounds (``inf``: none).
    after : float
        The loop's input after the table.
    """

    torque: FloatArray
    held: FloatArray
    step: FloatArray
    back: FloatArray
    h: float
    peak: float
    rate: float
    after: float


@dataclass(frozen=True)
class Window:
    """A window where the input holds, as rows on its first state.

    What :func:`window_rows` returns. Row ``i`` at period ``j`` is ``maps[i] A_d^j x_M + shift[j, i]`` measured from
    ``target[j, i]`` (NaN: no such row): the first ``bands`` maps are bands ``|.| <= E`` (the tips at the rows, then
    half-way between them), the others deflections ``|.| <= d``. Nothing is stored a row: :meth:`values` steps the plant, :meth:`rows` the maps, so a long
    window of several plants costs its targets alone.

    Attributes
    ----------
    Ad : ndarray
        The held plant over a period.
    maps : ndarray, shape (r, N)
        The rows' maps at ``j = 0``.
    shift, target : ndarray, shape (n + 1, r)
        What the held input adds (``maps[i] c_j``) and the targets.
    bands : int
        The maps that are bands in ``E``.
    """

    Ad: FloatArray
    maps: FloatArray
    shift: FloatArray
    target: FloatArray
    bands: int

    @property
    def n(self) -> int:
        """The periods after ``M``."""
        return int(self.shift.shape[0]) - 1

    @property
    def exists(self) -> NDArray[np.bool_]:
        """Where a row is, shape ``(n + 1, r)``."""
        return np.isfinite(self.target)

    def values(self, x: FloatArray) -> FloatArray:
        """Every row's value from the state at ``M``.

        Parameters
        ----------
        x : ndarray
            The state at ``M``.

        Returns
        -------
        ndarray, shape (n + 1, r)
            Each row's value less its target (NaN where no row).
        """
        N = self.Ad.shape[0]
        out, _ = recurrence(self.Ad, np.zeros((N, 1)), np.asarray(x, dtype=float), np.zeros((self.n, 1)), C=self.maps)
        return np.asarray(out, dtype=float).reshape(self.n + 1, -1) + self.shift - self.target

    def rows(self, keep: NDArray[np.bool_]) -> tuple[tuple[FloatArray, FloatArray], tuple[FloatArray, FloatArray] | None]:
        """The rows ``keep`` picks, as the chain takes them.

        Parameters
        ----------
        keep : ndarray of bool, shape (n + 1, r)
            The rows wanted (where one exists).

        Returns
        -------
        (W, t), (V, o) or None
            :attr:`Chain.after` and :attr:`Chain.after_bend` (``None``: no deflection's rows).
        """
        N = self.Ad.shape[0]
        keep = keep & self.exists
        W, t, V, o = [], [], [], []
        for i in range(self.maps.shape[0]):
            js = np.flatnonzero(keep[:, i])
            if not js.size:
                continue
            powers, _ = recurrence(self.Ad.T, np.zeros((N, 1)), self.maps[i], np.zeros((int(js.max()), 1)))  # maps[i] A^j
            if i < self.bands:
                W.append(powers[js])
                t.append(self.target[js, i] - self.shift[js, i])
            else:
                V.append(powers[js])
                o.append(self.shift[js, i] - self.target[js, i])
        after = (np.vstack(W), np.concatenate(t)) if W else (np.zeros((0, N)), np.zeros(0))
        return after, ((np.vstack(V), np.concatenate(o)) if V else None)


def window_rows(Ad: FloatArray, Bd: FloatArray, C: FloatArray, hold: float, y: FloatArray,
                middle: tuple[FloatArray, Any, FloatArray] | None = None, bend: FloatArray | None = None) -> Window:
    """A window where the input holds, as rows on its first state.

    After the last row ``M`` of a programme the input holds ``u_hold``: ``x_{M+j} = A_d^j x_M + c_j`` with ``c_0 = 0``,
    ``c_{j+1} = A_d c_j + B_d u_hold``, so every bound there is a row on ``x_M`` (:attr:`Chain.after`): one stage where a
    stage a period cost the Riccati recursion ``(N + 3)^3`` each (a lightly damped link's window is thousands of
    periods). The same programme, the same solution.

    Parameters
    ----------
    Ad, Bd : ndarray
        The held plant over a period.
    C : ndarray
        The output row, or rows (one a plant stacked in the state).
    hold : float
        ``u_hold``.
    y : ndarray, shape (n + 1,)
        The targets at the rows ``M .. M + n`` (the first is the last stage's own, not repeated here).
    middle : tuple, optional
        ``(CA, CB, y_mid)`` as :attr:`Chain.middle`, ``y_mid`` the targets half-way after the rows ``M .. M + n - 1``.
    bend : ndarray, optional
        The deflection's rows ``D`` (:attr:`Chain.deflection`), bounded at the rows ``M + 1 .. M + n``.

    Returns
    -------
    Window
        The tips at the rows ``M + 1 .. M + n`` and half-way after ``M .. M + n - 1`` (bands in ``E``), then the
        deflections at ``M + 1 .. M + n``.
    """
    N = Ad.shape[0]
    tips = np.atleast_2d(C)
    P = tips.shape[0]
    n = int(np.size(y)) - 1
    y = np.asarray(y, dtype=float)
    maps, targets = [tips], [np.repeat(y[:, None], P, axis=1)]
    targets[0][0] = np.nan  # row M is the last stage's own
    offsets = [np.zeros(P)]  # a constant added to every period's value (the half-way point's held input)
    if middle is not None:
        CA, CB = np.atleast_2d(middle[0]), np.atleast_1d(np.asarray(middle[1], dtype=float))
        mid = np.full((n + 1, CA.shape[0]), np.nan)
        mid[:n] = np.asarray(middle[2], dtype=float)[:n, None]
        maps.append(CA)
        targets.append(mid)
        offsets.append(CB * float(hold))
    bands = sum(m.shape[0] for m in maps)
    if bend is not None:
        D = np.atleast_2d(bend)
        zero = np.zeros((n + 1, D.shape[0]))
        zero[0] = np.nan
        maps.append(D)
        targets.append(zero)
        offsets.append(np.zeros(D.shape[0]))
    R0 = np.vstack(maps)
    c, _ = recurrence(Ad, np.asarray(Bd, dtype=float).reshape(N, 1), np.zeros(N), np.full((n, 1), float(hold)), C=R0)
    shift = np.asarray(c, dtype=float).reshape(n + 1, -1) + np.concatenate(offsets)[None, :]
    return Window(np.asarray(Ad, dtype=float), R0, shift, np.hstack(targets), bands)


#: The directions of the octagon that bounds a complex pair's condition (each a relaxation of the disc).
_OCTAGON = np.exp(1j * np.pi * np.arange(4) / 4)


@dataclass(frozen=True)
class Chain:
    """A chain programme (module docstring), in the plant's units.

    Attributes
    ----------
    Ad, Bd : ndarray
        The held plant over a period (with a ramp: over a row, ``Bd`` the row's own input's share).
    C : ndarray
        The output row, or rows (shape ``(P, N)``: the outputs of ``P`` plants stacked in the state, one input for all,
        each output within ``E`` of the same targets; the middle rows then ``CA`` of shape ``(P, N)``, ``CB`` ``(P,)``).
    x0 : ndarray
        The state at ``t_0``.
    before : float
        The input before the move ``u_{-1}``.
    y : ndarray, shape (M + 1,)
        The output's targets at the rows ``0 .. M`` (a NaN between the first and the last: that row is free, no bound).
    K : int
        The stages with inputs of their own.
    hold : float or None
        The input after them (``None``: free to ``M``, within the bounds).
    error : float or None
        ``E`` (``None``: minimised).
    peak : float or None
        ``T`` (``inf``: no bound; ``None``: minimised, with the traces below).
    rate : float
        ``R`` (``inf``: no bound).
    variation, energy : float
        The weights of the rows' total variation and of their energy (``sum u_k^2``) in the objective, in the scaled
        units (the peak about 1).
    smoothness : float
        The weight of the rows' squared changes ``sum (u_k - u_{k-1})^2`` (the first against ``before``, the last
        against ``hold``) in the objective, in the scaled units: with a peak given, the smoothest table under it.
    rest : ndarray or None
        The state at row ``rest_at`` (a rest end; a NaN entry leaves that state free: several plants stacked, the
        nominal one at rest, the others held by the rows after it).
    rest_at : int or None
        Its row (default ``K``).
    deflection : tuple or None
        ``(D, d)``: ``|D x_k| <= d`` at every row after the first (a link's elastic deflection at its output, ``D`` the
        output's row less ``x_out`` times the hub angle's: the linear model's small deflections kept small).
    after : tuple or None
        ``(W, t)``: rows ``|W x_M - t| <= E`` on the last row's state, shapes ``(m, N)`` and ``(m,)``: a window after the
        horizon where the input holds, condensed (the plant's outputs there are affine in ``x_M``: one stage instead of
        a stage a period, :func:`window_rows`).
    after_bend : tuple or None
        ``(V, o)``: rows ``|V x_M + o| <= d`` with ``d`` the :attr:`deflection`'s bound (the window's deflections).
    motor : Motor or None
        A motor in a loop whose torque and steps are bounded at the rows (:class:`Motor`; one row a period only).
    middle : tuple or None
        The tip half-way between the rows: ``(CA, CB, y_mid)`` -- the output half a period after row ``k`` is
        ``CA x_k + CB u_k``, ``y_mid`` shape ``(M,)``.
    inner : tuple or None
        With a ramp: ``(CP, H0, H1, y_in)`` -- the outputs of the periods inside row ``k`` are ``CP x_k + H0 u_k + H1 u_{k+1}``
        (shapes ``(m, N)``, ``(m,)``, ``(m,)``, ``(m, M)``).
    G1 : ndarray or None
        With a ramp: the next row's input's share of the next row's state.
    terminal : bool
        Bound the zero directions at the last row (module docstring).
    size : ndarray
        Each state's scale.
    input_scale, output_scale : float
        The input's and the output's scales.
    """

    Ad: FloatArray
    Bd: FloatArray
    C: FloatArray
    x0: FloatArray
    before: float
    y: FloatArray
    K: int
    hold: float | None
    error: float | None
    peak: float | None
    rate: float
    size: FloatArray
    input_scale: float
    output_scale: float
    variation: float = 0.0
    energy: float = 0.0
    smoothness: float = 0.0
    rest: FloatArray | None = None
    middle: tuple[FloatArray, Any, FloatArray] | None = None
    inner: tuple[FloatArray, FloatArray, FloatArray, FloatArray] | None = None
    G1: FloatArray | None = None
    terminal: bool = False
    rest_at: int | None = None
    deflection: tuple[FloatArray, float] | None = None
    after: tuple[FloatArray, FloatArray] | None = None
    after_bend: tuple[FloatArray, FloatArray] | None = None
    motor: Motor | None = None

    @property
    def M(self) -> int:
        """The periods (stages with dynamics)."""
        return int(self.y.size) - 1

    def work(self) -> int:
        """The programme's size (:func:`work`)."""
        return work(self.M, self.Ad.shape[0], bool(self.variation), self._rows(), self._final_rows())

    def _final_rows(self) -> int:
        """The last stage's rows beyond a stage's own (the condensed window's)."""
        return sum(int(np.shape(part[0])[0]) for part in (self.after, self.after_bend) if part is not None)

    def _rows(self) -> int:
        """Rows a stage has, about (the tip's and the middle's a plant, the rate's, the variation's, the peak's)."""
        inner = 0 if self.inner is None else 2 * int(np.shape(self.inner[0])[0])
        motor = 0 if self.motor is None else 1 + int(np.shape(self.motor.torque)[0])
        return 8 + inner + 4 * (int(np.atleast_2d(self.C).shape[0]) - 1) + motor

    @staticmethod
    def state_sizes(Ad: FloatArray, Bd: FloatArray, drive: FloatArray) -> FloatArray:
        """Each state's size under ``drive`` (the input at every period, from rest): the programme's units."""
        X, _ = recurrence(Ad, Bd[:, None], np.zeros(Ad.shape[0]), np.asarray(drive, dtype=float)[:, None])
        size = np.abs(X).max(axis=0)
        return np.where(size > 0, size, max(float(size.max(initial=0.0)), 1.0))

    def _rest_row(self) -> int:
        return self.K if self.rest_at is None else int(self.rest_at)

    def _layout(self) -> tuple[int, int, int, int]:
        """Indices of ``u_{k-1}``, ``E`` and ``s`` in a stage's states (``-1``: absent), and the stage's width."""
        N = self.Ad.shape[0]
        at = N + 1
        e = at if self.error is None else -1
        at += self.error is None
        s = at if self.peak is None else -1
        at += self.peak is None
        return N, e, s, at

    def stages(self) -> list[Stage | Block]:
        """The programme as HPIPM's stages (module docstring)."""
        N, ie, is_, nx = self._layout()
        M, K = self.M, self.K
        globals_ = [i for i in (ie, is_) if i >= 0]
        sz, us = self.size, self.input_scale
        ramp = self.G1 is not None
        nu = 1 + (1 if self.variation else 0)
        # dynamics in the scaled states: x' = Ad x + Bd u (with a ramp: Bd p + G1 u), p' = u, the globals stay
        A = np.zeros((nx, nx))
        A[:N, :N] = self.Ad * sz[None, :] / sz[:, None]
        B = np.zeros((nx, nu))
        if ramp:
            A[:N, N] = self.Bd * us / sz
            B[:N, 0] = np.asarray(self.G1) * us / sz
        else:
            B[:N, 0] = self.Bd * us / sz
        B[N, 0] = 1.0
        for i in globals_:
            A[i, i] = 1.0
        # the first stage's states are the globals alone: x_0 and u_{-1} are known, in b
        A0 = np.zeros((nx, len(globals_)))
        for j, i in enumerate(globals_):
            A0[i, j] = 1.0
        b0 = np.zeros(nx)
        b0[:N] = (self.Ad @ self.x0 + (self.Bd * self.before if ramp else 0.0)) / sz
        b0[N] = 0.0
        R_cost, r_cost = self._costs(nu)
        series = self._series()
        first = _Template(self, nx=len(globals_), nu=nu, k0=True, held=False)
        moving = _Template(self, nx=nx, nu=nu, k0=False, held=False)
        q0 = np.ones(len(globals_)) if globals_ else None  # min E, or min s (never both)
        R0, r0, Q_move, S_move, R_move = R_cost, r_cost, None, None, R_cost
        w = 2.0 * self.smoothness  # the cost is 1/2 z H z: w (u - p)^2 is H = 2w [1 -1; -1 1] on (u, p)
        if w:
            R0 = (np.zeros((nu, nu)) if R_cost is None else R_cost.copy())
            R0[0, 0] += w
            r0 = (np.zeros(nu) if r_cost is None else r_cost.copy())
            r0[0] -= w * self.before / us  # the first change is against the input before the move, known
            R_move = R0.copy()
            Q_move = np.zeros((nx, nx))
            Q_move[N, N] = w
            S_move = np.zeros((nu, nx))
            S_move[0, N] = -w
        stages: list[Stage | Block] = list(first.blocks(series, [0], dict(nx=len(globals_), nu=nu, A=A0, B=B.copy(), b=b0, q=q0,
                                                                         R=R0, r=r0)))
        if self.peak is None and ramp:  # the first row of a ramp is u_{-1}: within the peak too
            head = stages[0].stage if isinstance(stages[0], Block) else stages[0]
            head.idxbx = np.array([globals_.index(is_)], dtype=np.int32)
            head.lbx, head.ubx = np.array([abs(self.before) / us]), np.array([math.inf])
        zero = np.zeros(nx)
        plan: list[tuple[_Template, range]] = [(moving, range(1, min(K, M)))]
        if self.hold is not None and K < M:  # the input holds after K: the first such stage still bounds its change
            plan += [(_Template(self, nx=nx, nu=nu, k0=False, held=True, last_change=True), range(K, K + 1)),
                     (_Template(self, nx=nx, nu=nu, k0=False, held=True, last_change=False), range(K + 1, M))]
        elif K < M:
            plan.append((moving, range(K, M)))
        for template, ks in plan:
            costs: dict[str, Any] = {}
            if template.nu == nu:  # a stage that chooses its input
                Bk, bk, Rk, rk = B, zero, R_move, r_cost
                costs = {} if not w else dict(Q=Q_move, S=S_move)
            else:  # the input held: in b; what is left to choose is the last change's variation, if anything
                assert self.hold is not None  # a held template exists only with a hold
                Bk, bk = B[:, 1:1 + template.nu], B[:, 0] * (float(self.hold) / us)
                Rk, rk = None, (None if template.nu == 0 else np.array([self.variation]))
                if w and template.changes:  # the last change, to the held input: w (hold - p)^2
                    Qh, qh = np.zeros((nx, nx)), np.zeros(nx)
                    Qh[N, N], qh[N] = w, -w * float(self.hold) / us
                    costs = dict(Q=Qh, q=qh)
            stages += template.blocks(series, list(ks), dict(nx=nx, nu=template.nu, A=A, B=Bk, b=bk, R=Rk, r=rk, **costs))
        assert sum(b.count if isinstance(b, Block) else 1 for b in stages) == M
        stages.append(Stage(nx=nx, nu=0, **self._final(nx, N)))
        return stages

    def _series(self) -> dict[str, FloatArray]:
        """The targets each row is measured from, in the output's scale, by stage."""
        ys = self.output_scale
        out = {"tip": self.y / ys}
        if self.middle is not None:
            out["mid"] = np.asarray(self.middle[2], dtype=float) / ys
        if self.inner is not None:
            y_in = np.asarray(self.inner[3], dtype=float) / ys
            for j in range(y_in.shape[0]):
                out[f"in{j}"] = y_in[j]
        return out

    def _costs(self, nu: int) -> tuple[FloatArray | None, FloatArray | None]:
        R = r = None
        if self.energy:
            R = np.zeros((nu, nu))
            R[0, 0] = 2.0 * self.energy  # the cost is 1/2 v R v
        if self.variation:
            r = np.zeros(nu)
            r[1] = self.variation
        return R, r

    def _final(self, nx: int, N: int) -> dict[str, Any]:
        """The last stage's rows: the tip, the rest end where ``K = M``, the zero directions where asked."""
        _, ie, _, _ = self._layout()
        ys = self.output_scale
        rows = _RowList(nx, 0, ie if self.error is None else None, None if self.error is None else self.error / ys)
        for C in np.atleast_2d(self.C):
            c = np.zeros(nx)
            c[:N] = C * self.size / ys
            rows.band(c, np.zeros(0), float(self.y[-1]) / ys)
        if self.deflection is not None:
            _bend(rows, self, np.zeros(nx), np.zeros(0), N)
        if self.after is not None:  # the window after the horizon, condensed onto its last state
            W, targets = self.after
            c = np.zeros((np.shape(W)[0], nx))
            c[:, :N] = np.asarray(W) * (self.size / ys)[None, :]
            rows.bands(c, np.asarray(targets, dtype=float) / ys)
        if self.after_bend is not None and self.deflection is not None:
            V, offsets = self.after_bend
            d = float(self.deflection[1])
            c = np.zeros((np.shape(V)[0], nx))
            c[:, :N] = np.asarray(V) * (self.size / d)[None, :]
            rows.block(c, -1.0 - np.asarray(offsets, dtype=float) / d, 1.0 - np.asarray(offsets, dtype=float) / d)
        if self.terminal:
            y_final = float(self.y[-1])
            for zeta, ell, m in zero_directions(self.Ad, self.Bd, self.C):
                reach = abs(m) / (abs(zeta) - 1.0)  # |q_M - q*| <= reach E
                centre = m * y_final / (zeta - 1.0)
                for w in (_OCTAGON if abs(zeta.imag) > 0 else np.array([1.0 + 0j])):
                    row = np.zeros(nx)
                    row[:N] = np.real(w * ell) * self.size / (reach * ys)
                    rows.band(row, np.zeros(0), float(np.real(w * centre)) / (reach * ys))
        fields = rows.packed()
        if self.rest is not None and self._rest_row() == self.M:
            held, values = _rest_bounds(self.rest, self.size)
            fields.update(idxbx=held, lbx=values - REST_BAND, ubx=values + REST_BAND)
        return fields

    def solve(self) -> ChainResult:
        """Solve by HPIPM: the inputs, ``E`` and ``s``.

        In the plant's units.

        Raises
        ------
        SettingsError
            For a programme beyond :data:`MAX_WORK` (:data:`MAX_LP_WORK` where ``E`` is minimised: the bounded causal
            limit's, the fastest move's), before any work.
        InversionError
            Where HPIPM does not solve it within its iterations (its status and residuals).
        """
        check_size(self.M, self.Ad.shape[0], bool(self.variation), None, rows=self._rows(), final=self._final_rows(),
                   linear=self.error is None)
        stages = self.stages()
        solution = solve_chain(stages, iterations=min(FIRST_ITERATIONS, ITERATIONS), tolerance=TOLERANCE)
        if (solution.status == 1 and ITERATIONS > FIRST_ITERATIONS and not solution.within(STALLED)
                and solution.within(RESUMED)):  # on its way down: solved again from the same start, as if in one go
            solution = solve_chain(stages, iterations=ITERATIONS, tolerance=TOLERANCE)
        if not solution.solved and not solution.within(ACCEPT):
            exc = InversionError(f"the chain programme was not solved: {solution.message}")
            exc.solution = solution  # type: ignore[attr-defined]
            raise exc
        _, ie, is_, _ = self._layout()
        globals_ = [i for i in (ie, is_) if i >= 0]
        values = dict(zip(globals_, solution.x[0]))
        error = self.error if self.error is not None else float(values[ie]) * self.output_scale
        peak = self.peak if self.peak is not None else float(values[is_]) * self.input_scale
        u = np.array([solution.u[k][0] for k in range(self.K)]) * self.input_scale
        return ChainResult(u=u, error=float(error), peak=float(peak), solution=solution)


def _motor_rows(rows: "_RowList", chain: Chain, zx: FloatArray, zu: FloatArray, N: int, k0: bool, held: bool, changes: bool) -> None:
    """A stage's rows of :class:`Motor` (where the chain has one), in the input's units: at the first row (the state
    known, no step of the references: the table's own change, bounded by the rate's row), at a moving row, and at the
    first held one (``held``); none where the input holds and no longer ``changes``."""
    motor = chain.motor
    if motor is None or not changes:
        return
    us, sz = chain.input_scale, chain.size
    T, R = motor.peak / us, motor.rate / us
    if math.isfinite(T):
        for m, held_row in zip(np.atleast_2d(motor.torque), np.atleast_2d(motor.held)):
            c, d = zx.copy(), zu.copy()
            if k0:  # u_0 + m x_0
                d[0], offset = 1.0, float(m @ chain.x0) / us
            elif held:  # after - K_j x_K (the held input's column moves into the sides: D's first column 0 here)
                c[:N], offset = held_row * sz / us, motor.after / us
            else:
                c[:N], d[0], offset = m * sz / us, 1.0, 0.0
            rows.add(c, d, -T - offset, T - offset)
    if math.isfinite(R) and not k0:
        c, d = zx.copy(), zu.copy()
        c[N] = motor.h - 1.0
        if held:  # after - g x_K + (h - 1) u_{K-1}
            c[:N], offset = -np.asarray(motor.back) * sz / us, motor.after / us
        else:
            c[:N], d[0], offset = np.asarray(motor.step) * sz / us, 1.0, 0.0
        rows.add(c, d, -R - offset, R - offset)


def _bend(rows: "_RowList", chain: Chain, zx: FloatArray, zu: FloatArray, N: int) -> None:
    """The rows ``|D x| <= d`` of a stage (:attr:`Chain.deflection`), in units of ``d``."""
    assert chain.deflection is not None
    D, d = chain.deflection
    for row in np.atleast_2d(D):
        c = zx.copy()
        c[:N] = row * chain.size / d
        rows.add(c, zu.copy(), -1.0, 1.0)


def _rest_bounds(rest: FloatArray, size: FloatArray) -> tuple[NDArray[np.int32], FloatArray]:
    """The states a rest end holds (those of ``rest`` that are not NaN) and their values in the programme's units."""
    held = np.flatnonzero(np.isfinite(rest)).astype(np.int32)
    return held, (np.asarray(rest, dtype=float)[held] / np.asarray(size, dtype=float)[held])


class _RowList:
    """Rows ``lower <= c z + d v <= upper`` of a stage; a band ``|c z + d v - target| <= E`` is one row where ``E`` is
    given, two one-sided rows where it is the state ``e_col``."""

    def __init__(self, nx: int, nu: int, e_col: int | None, bound: float | None) -> None:
        self.nx, self.nu, self.e_col, self.bound = nx, nu, e_col, bound
        self.rows: list[tuple[FloatArray, FloatArray, float, float, str | None]] = []
        self.more: list[tuple[FloatArray, FloatArray, FloatArray]] = []  # blocks of rows without inputs, after these

    def block(self, c: FloatArray, lower: FloatArray, upper: FloatArray) -> None:
        """Rows ``lower <= c z <= upper`` at once (a stage without inputs: the last), each scaled to its largest entry 1
        (a window's rows grow with its length along a rigid body's rate)."""
        c = np.asarray(c, dtype=float)
        scale = np.maximum(np.abs(c).max(axis=1), 1e-300)
        self.more.append((c / scale[:, None], np.asarray(lower, dtype=float) / scale, np.asarray(upper, dtype=float) / scale))

    def bands(self, c: FloatArray, targets: FloatArray) -> None:
        """Bands ``|c_i z - target_i| <= E`` at once, as :meth:`band` (a stage without inputs)."""
        if self.e_col is None:
            assert self.bound is not None
            self.block(c, targets - self.bound, targets + self.bound)
            return
        below, above = c.copy(), c.copy()
        below[:, self.e_col] -= 1.0
        above[:, self.e_col] += 1.0
        inf = np.full(targets.size, math.inf)
        self.block(below, -inf, targets)
        self.block(above, targets, inf)

    def add(self, c: FloatArray, d: FloatArray, lower: float, upper: float, series: str | None = None) -> None:
        self.rows.append((c, d, lower, upper, series))

    def band(self, c: FloatArray, d: FloatArray, target: float, series: str | None = None) -> None:
        if self.e_col is None:
            assert self.bound is not None
            self.add(c, d, target - self.bound, target + self.bound, series)
            return
        below, above = c.copy(), c.copy()
        below[self.e_col] -= 1.0  # c z - E <= target
        above[self.e_col] += 1.0  # c z + E >= target
        self.add(below, d, -math.inf, target, series)
        self.add(above, d, target, math.inf, series)

    def packed(self) -> dict[str, Any]:
        if not self.rows and not self.more:
            return {}
        n = len(self.rows)
        C = np.vstack([np.array([r[0] for r in self.rows]).reshape(n, self.nx), *(m[0] for m in self.more)])
        D = np.zeros((C.shape[0], self.nu))  # the blocks have no inputs' columns
        D[:n] = np.array([r[1] for r in self.rows]).reshape(n, self.nu)
        return {"C": C, "D": D, "lg": np.concatenate([np.array([r[2] for r in self.rows], dtype=float), *(m[1] for m in self.more)]),
                "ug": np.concatenate([np.array([r[3] for r in self.rows], dtype=float), *(m[2] for m in self.more)])}


class _Template:
    """The rows of a kind of stage (the first; moving; the one where the input starts to hold; held; free after the move),
    their targets added stage by stage (:meth:`fields`)."""

    def __init__(self, chain: Chain, *, nx: int, nu: int, k0: bool, held: bool, last_change: bool = True) -> None:
        N, ie, is_, _ = chain._layout()
        globals_ = [i for i in (ie, is_) if i >= 0]
        at = (lambda i: globals_.index(i)) if k0 else (lambda i: i)
        ys, us = chain.output_scale, chain.input_scale
        ramp = chain.G1 is not None
        rows = _RowList(nx, nu, at(ie) if chain.error is None else None, None if chain.error is None else chain.error / ys)
        zx, zu = np.zeros(nx), np.zeros(nu)
        x0 = chain.x0
        # the tip at the row (the first row is the start: E at least its distance)
        outputs = np.atleast_2d(chain.C)  # one row a plant
        for C in outputs:
            if k0:
                if chain.error is None:
                    rows.band(zx.copy(), zu, float(chain.y[0] - C @ x0) / ys)
            else:
                c = zx.copy()
                c[:N] = C * chain.size / ys
                rows.band(c, zu, 0.0, "tip")
        if chain.deflection is not None and not k0:
            _bend(rows, chain, zx, zu, N)
        # the tip between the rows
        if chain.middle is not None and not ramp:
            for CA, CB in zip(np.atleast_2d(chain.middle[0]), np.atleast_1d(np.asarray(chain.middle[1], dtype=float))):
                c, d = zx.copy(), zu.copy()
                offset = float(CA @ x0) / ys if k0 else 0.0
                if not k0:
                    c[:N] = CA * chain.size / ys
                d[0] = CB * us / ys
                rows.band(c, d, -offset, "mid")
        if chain.inner is not None and ramp:
            CP, H0, H1, _ = chain.inner
            for j in range(CP.shape[0]):
                c, d = zx.copy(), zu.copy()
                offset = float(CP[j] @ x0 + H0[j] * chain.before) / ys if k0 else 0.0
                if not k0:
                    c[:N] = CP[j] * chain.size / ys
                    c[N] = H0[j] * us / ys
                d[0] = H1[j] * us / ys
                rows.band(c, d, -offset, f"in{j}")
        # the change from the row before (u - p; the first against u_{-1}), its total variation, the peak
        p_known = chain.before / us if k0 else 0.0
        changes = not held or last_change
        if math.isfinite(chain.rate) and changes:
            c, d = zx.copy(), zu.copy()
            d[0] = 1.0
            if not k0:
                c[N] = -1.0
            r = chain.rate / us
            rows.add(c, d, p_known - r, p_known + r)
        if chain.variation and changes:
            for sign in (-1.0, 1.0):  # u - p - v <= 0 ; u - p + v >= 0
                c, d = zx.copy(), zu.copy()
                d[0], d[1] = 1.0, sign
                if not k0:
                    c[N] = -1.0
                rows.add(c, d, p_known if sign > 0 else -math.inf, math.inf if sign > 0 else p_known)
        if chain.peak is None and not held:
            for sign in (-1.0, 1.0):  # u - s <= 0 ; u + s >= 0
                c, d = zx.copy(), zu.copy()
                d[0] = 1.0
                c[at(is_)] = sign
                rows.add(c, d, 0.0 if sign > 0 else -math.inf, math.inf if sign > 0 else 0.0)
        _motor_rows(rows, chain, zx, zu, N, k0, held, changes)
        self.packed = rows.packed()
        self.series = [r[4] for r in rows.rows]
        self.changes = changes
        self.nu = nu
        self.bounds: dict[str, Any] = {}
        if held:  # the input is u_hold, not a variable: its column moves into the sides (equal bounds stall HPIPM)
            assert chain.hold is not None
            self.nu = 1 if chain.variation and changes else 0
            if self.packed:
                shift = self.packed["D"][:, 0] * (chain.hold / us)
                self.packed["lg"] = self.packed["lg"] - shift
                self.packed["ug"] = self.packed["ug"] - shift
                self.packed["D"] = self.packed["D"][:, 1:1 + self.nu]
        elif chain.peak is not None and math.isfinite(chain.peak):
            self.bounds.update(idxbu=np.array([0], dtype=np.int32), lbu=np.array([-chain.peak / us]), ubu=np.array([chain.peak / us]))
        self.rest = None if chain.rest is None or k0 else (chain._rest_row(), *_rest_bounds(chain.rest, chain.size))

    def blocks(self, series: dict[str, FloatArray], ks: list[int], shared: dict[str, Any]) -> list[Block]:
        """The stages ``ks`` as blocks of stages that share the template's matrices (``shared``: the dynamics and costs),
        each stage its row of the bounds; the rest end's stage a block of its own."""
        if not ks:
            return []
        base = self.packed
        rows: dict[str, FloatArray] = {}
        if base:
            which = [i for i, name in enumerate(self.series) if name is not None]
            index = np.asarray(ks)
            lg = np.repeat(base["lg"][None, :], index.size, axis=0)
            ug = np.repeat(base["ug"][None, :], index.size, axis=0)
            for i in which:
                target = series[str(self.series[i])][index]
                lg[:, i] += target
                ug[:, i] += target
                free = np.isnan(target)  # a row without a target: no bound there (a free path, inversion.methods.fastest)
                lg[free, i], ug[free, i] = -math.inf, math.inf
            rows = {"lg": lg, "ug": ug}
        common: dict[str, Any] = {**shared, **self.bounds}
        if base:
            common.update(C=base["C"], D=base["D"], lg=base["lg"], ug=base["ug"])
        cuts = [0, len(ks)]
        if self.rest is not None and self.rest[0] in ks:
            at = ks.index(self.rest[0])
            cuts = sorted({0, at, at + 1, len(ks)})
        out = []
        for a, b in zip(cuts[:-1], cuts[1:]):
            fields = dict(common)
            if self.rest is not None and ks[a] == self.rest[0]:
                fields.update(idxbx=self.rest[1], lbx=self.rest[2] - REST_BAND, ubx=self.rest[2] + REST_BAND)
            out.append(Block(Stage(**fields), b - a, {name: value[a:b] for name, value in rows.items()}))
        return out

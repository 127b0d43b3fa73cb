"""The one home of the inversion layer's defaults (in the manner of python-control's ``config.defaults``).

Every public signature of :mod:`inversion` says ``None`` for "the default" and reads it here;
the command line shows these values in its help, and ``docs/method.md`` states them. A
default is changed in this file and nowhere else.

:data:`DEFAULTS` is read-only: a process and its workers (the explorer's, a Dask cluster's)
see the same values.

>>> from inversion.config import DEFAULTS
>>> DEFAULTS.rate, DEFAULTS.tol, DEFAULTS.c_prefix
(1000.0, 1e-08, 'sflm_feedforward')
>>> 5 in DEFAULTS.grid.segments and 6 in DEFAULTS.grid.segments  # the paper's members are on the grid
True

A ``None`` becomes a default in one of three functions and nowhere else: :func:`default` (any keyword),
:func:`tip_bound` (``max_error``: the bound a result is judged by, or a given member's quality gate) and
:func:`held_period` (a controller's ``period``: one sample at ``rate``).

>>> default("tol", None), default("tol", 1e-6), tip_bound(None, 0.3), tip_bound(None, 0.3, judged=False)
(1e-08, 1e-06, 0.003, 0.015)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar

__all__ = ["DEFAULTS", "Defaults", "SearchGrid", "default", "tip_bound", "held_period"]

T = TypeVar("T")


@dataclass(frozen=True)
class SearchGrid:
    """The grid of members the search starts from.

    The grid of members the automatic choice starts from and the explorer maps by default.

    Attributes
    ----------
    segments : tuple of int
        Numbers of equal segments (Eq. (28)); the paper's 5 and 6 among them.
    h : tuple of int
        Orders of smooth joining (Eq. (30)).
    cdec_fast, cdec_slow : tuple of float
        ``Cdec_f`` and ``Cdec_s`` of Eq. (35); pairs with ``Cdec_f >= Cdec_s`` are skipped.
    joining : tuple of str
        The joinings of :mod:`inversion.family.ssef`.
    """

    segments: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 8, 12, 16, 24, 32)
    h: tuple[int, ...] = (1, 2, 3)
    cdec_fast: tuple[float, ...] = (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
    cdec_slow: tuple[float, ...] = (1.0, 0.5)
    joining: tuple[str, ...] = ("anchored", "position", "paper")

    def as_dict(self) -> dict[str, tuple[Any, ...]]:
        """The grid by dimension."""
        return {"segments": self.segments, "h": self.h, "cdec_fast": self.cdec_fast, "cdec_slow": self.cdec_slow,
                "joining": self.joining}

    def coarse(self) -> "SearchGrid":
        """The automatic choice's first stage: a sixth of the grid.

        The automatic choice's first stage: segment counts that double, ``h`` up to 2, every other ``Cdec_f``,
        the first ``Cdec_s`` -- a sixth of the grid; its refinement explores around the best member it finds
        (measured on twelve links and moves: the peak torque within 1.2 % of the full grid's, in a quarter of the time).
        """
        return SearchGrid(segments=tuple(k for k in self.segments if k & (k - 1) == 0), h=self.h[:2], cdec_fast=self.cdec_fast[::2],
                          cdec_slow=self.cdec_slow[:1], joining=self.joining)

    @property
    def size(self) -> int:
        """Members of the full grid."""
        pairs = sum(1 for f in self.cdec_fast for s in self.cdec_slow if f < s)
        return len(self.segments) * len(self.h) * pairs * len(self.joining)


@dataclass(frozen=True)
class Defaults:
    """The defaults (SI units; fractions are of the move).

    Attributes
    ----------
    rate : float
        Sampling rate of a result's samples (Hz).
    eps : float
        Zeros with ``Re >= -eps`` count as unstable (1/s).
    solver : str
        The primary linear solver of the segment systems (the other one checks it).
    tol : float
        Largest accepted relative residual of a segment system.
    quality_gate : float
        A redefinition further from ``y_d`` than this fraction of the move is a failure.
    torque_margin : float
        With the ``error`` objective, the torque limit is at most this multiple of the least
        peak torque within the bound.
    max_samples : int
        Most samples one inversion may produce (about 1 GB of arrays, 1.5 GB of CSV).
    max_held_rows : int
        Most rows a held table may have over the move (each row is simulated through the held plant and judged in the
        loop: 5.5e5 rows of paper-sim took 1.0 GB and 4.7 s, 5.5e6 rows 5.1 GB and 28 s).
    c_prefix : str
        Prefix of the exported C symbols.
    tail_tolerance : float
        Stable inversion's tails are cut where torque and joint reference fall below this
        fraction of their peaks.
    vibration_window : float
        Seconds after ``t_f`` over which the residual vibration is measured.
    objective : str
        What the automatic choice minimises (:class:`inversion.options.Objective`).
    torque_tie : float
        With the ``torque`` objective, members whose peak torque is within this fraction of the
        least are equal in torque: the smallest error among them wins (a torque 2 % higher for
        an error a million times smaller: paper-sim's 1.25 nm at 0.428 N m against 6.6 mm at
        0.423 N m).
    bound : float
        The automatic choice's tip bound: within this fraction of the move during the move and
        after it (``max_error`` when not given).
    torque_ratio : float
        The automatic choice's torque limit without ``max_torque``: this multiple of what a
        rigid body needs along ``y_d`` (:meth:`inversion.lti.system.NormalForm.rigid_input`).
    extra_modes : int
        Modes the truncation check adds to a link's model.
    truncation_factor : float
        The held table on the model with ``extra_modes`` more modes must keep the tip within
        this multiple of the bound, during the move and after it (what the truncation may cost).
    torque_rate_ratio : float
        The default bound on the held table's largest change from one row to the next: this
        multiple of the rigid body's largest change over one period along ``y_d``.
    hold : str
        How the samples are held (:class:`inversion.options.Hold`).
    rest_tolerance : float
        A rest end (``end="rest"``) must bring the torque at ``t_f`` (with its rounding) within
        this fraction of the peak, and the tip's free motion in the 2 s after within this
        fraction of the move: a millionth, below what a drive resolves (a 16-bit converter
        steps by 1.5e-5 of its range) and far below what moves a link.
    settle_tolerance : float
        A settle tail (:mod:`inversion.family.settle`) is cut where every mode's share of the torque
        and of the joint angle falls below this fraction of their peaks.
    longest_tail : float
        Longest accepted post-actuation, in multiples of the move's duration.
    grid : SearchGrid
        The automatic choice's first grid and the explorer's default.
    ocp_max_periods : int
        No longer read: the optimal-control programme is a chain programme, refused by its work
        (:data:`inversion.chain.programme.MAX_WORK`), not by its periods. Kept for this release.
    margin : float
        The fraction of the tip bound the default tables keep free (docs/method.md, section 5j): the
        automatic choice and the optimal-control and re-planned methods aim within ``(1 - margin)``
        of the bound where the bounded causal limit leaves room, within half the room where it
        leaves less than twice that.
    smoothing : float
        The optimal-control table is the smoothest (least sum of squared changes between rows)
        whose peak is at most this fraction above the least.
    radius_span : float
        The robustness radius is searched up to this relative change of each parameter.
    radius_resolution : float
        And to this resolution (relative).
    fastest_deflection : float
        The fastest move's bound on a link's elastic deflection at its output where none is given, a fraction of the
        output's distance from the hub: the linear model's small deflections. Measured on the 3 mm strip with its
        drive (0.5 m, 5 mm): unbounded, the fastest move (0.352 s) bent it 75 % and the exact-kinematics plant missed the
        bound 22 times over; within 10 % (0.656 s) its tip strays 1.13 mm, 0.23 of it.
    torque_tolerance : float
        The automatic choice keeps an earlier stage's table (the family's) where its peak is within this fraction above
        the least found, and asks the optimal-control feedforward too where it is beyond this above the least peak any
        causal table within the tube can have (issue 60, item 6: a 3 mm strip's 0.5 m in 1.5 s, 2.5 mm at 1 ms, took the
        family's 1.85 N m where optimal control holds the bound at 1.647 and no table at less than 1.557).
    torque_robustness : float
        ... and takes the later stage's cheaper table only where it tolerates at least this share of the plant error the
        earlier one tolerates (the smallest relative error of a parameter, down or up, in the loops judged, that breaks
        the bound: :func:`inversion.methods.margin.robustness_radius`). Measured on that strip: optimal control's table
        broke the bound at a payload 0.054 % light, the family's at 0.66 %; on paper-sim with ``--end rest`` both hold
        EI within 50 % and optimal control's needs 0.336 N m against 0.428.
    robust_enough : float
        ... or that tolerates this relative error of every parameter (more than a calibrated link is off by): hyperbolic's
        1 rad in 3 s, optimal control's table 21 % cheaper than the family's, tolerates EI within 17.9 % (the family's
        50 %).
    ocp_period : float
        The optimal-control front's period in ``explore --plot`` when none is given (s): the front solves
        a programme per bound. ``compare`` judges its optimal-control row where ``invert`` does, at the
        controller's period.
    """

    rate: float = 1000.0
    eps: float = 0.0
    solver: Literal["lu", "lstsq"] = "lu"
    tol: float = 1e-8
    quality_gate: float = 0.05
    torque_margin: float = 1.5
    max_samples: int = 10_000_000
    max_held_rows: int = 1_000_000
    c_prefix: str = "sflm_feedforward"
    tail_tolerance: float = 1e-9
    vibration_window: float = 2.0
    objective: str = "torque"
    torque_tie: float = 0.02
    bound: float = 0.01
    torque_ratio: float = 3.0
    extra_modes: int = 4
    truncation_factor: float = 2.0
    torque_rate_ratio: float = 10.0
    hold: str = "point"
    rest_tolerance: float = 1e-6
    settle_tolerance: float = 1e-9
    longest_tail: float = 20.0
    grid: SearchGrid = field(default_factory=SearchGrid)
    ocp_max_periods: int = 10_000
    ocp_period: float = 0.01
    margin: float = 0.1
    smoothing: float = 0.05
    radius_span: float = 0.5
    radius_resolution: float = 1e-3
    fastest_deflection: float = 0.1
    torque_tolerance: float = 0.05
    torque_robustness: float = 0.5
    robust_enough: float = 0.1


#: The defaults of the inversion layer.
DEFAULTS = Defaults()


def default(name: str, value: T | None) -> T:
    """The caller's value, or the default of ``name``.

    The caller's value, or the default of ``name`` when it is ``None`` (python-control's ``_get_param``).

    Parameters
    ----------
    name : str
        A field of :class:`Defaults` (``rate``, ``eps``, ``solver``, ``tol``, ``hold``, ...).
    value : object or None
        What the caller gave.

    Returns
    -------
    object
        ``value``, or ``DEFAULTS.<name>``.
    """
    return getattr(DEFAULTS, name) if value is None else value


def tip_bound(max_error: float | None, move: float, judged: bool = True) -> float:
    """The tip's bound in metres.

    The tip's bound in metres: ``max_error`` when given, else a fraction of the move.

    Parameters
    ----------
    max_error : float or None
        The caller's bound (m).
    move : float
        The move (m): the range of ``y_d``.
    judged : bool
        ``True`` for a result chosen and judged on what reaches the link (the automatic choice, the explorer, the
        optimal-control feedforward, a robustness study: :attr:`Defaults.bound`); ``False`` for a member or a baseline
        the caller fixed, held to the looser quality gate (:attr:`Defaults.quality_gate`).

    Returns
    -------
    float
        The bound (m).
    """
    if max_error is not None:
        return float(max_error)
    return (DEFAULTS.bound if judged else DEFAULTS.quality_gate) * move


def held_period(period: float | None, rate: float | None = None) -> float:
    """The period a controller holds the rows at.

    The period a controller holds the rows at: ``period`` when given, else one sample at ``rate``.

    Parameters
    ----------
    period : float or None
        The caller's period (s).
    rate : float or None
        The samples' rate (Hz; :attr:`Defaults.rate` when ``None``).

    Returns
    -------
    float
        The period (s).
    """
    return 1.0 / default("rate", rate) if period is None else float(period)

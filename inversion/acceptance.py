"""What reaches the link: a feedforward judged where it is used, not on its own model alone.

A result is true on its continuous-time model (:mod:`inversion.family.verify`). What a user's link
sees differs, and is measured here (docs/method.md section 4b):

* **the held table through the window** -- a controller at period ``DT`` holds each row of the
  table (:func:`held_table`: the point value, ``hold="point"``, or the period's mean,
  ``"zoh"``), and the torque ends with the table. :func:`sampled` drives the exactly
  discretised plant (:mod:`inversion.lti.discrete`) with the rows from rest, through the move and
  the after-end window with the input that follows (zero torque for a link, the equilibrium
  input for a system): the tip at the rows against ``y~`` and ``y_d``, its largest excursion
  from ``y_d(t_f)`` after the table ends and the rate it keeps, and the same rows on the model
  with more modes. A ripple that cancels a mode above the controller's Nyquist frequency on the
  continuous model rings here. **These held figures are what the bounds apply to.**
* **the torque's rate** -- the largest change between consecutive rows (the first row against
  the input before the table, the last against the input after it), beside the rigid body's
  largest change over one period along ``y_d`` (:func:`demand`): a step the drive and the
  unmodelled modes see is refused beyond ``max_torque_rate``.
* **a plausible torque** -- the peak beside what a rigid body needs along ``y_d``
  (:meth:`NormalForm.rigid_input`): ``torque_ratio``.
* **in the loop it runs in** (where asked: :attr:`Criteria.loop`) -- the same rows with the joint PD
  closed around the plant (:func:`closed_loop`, the paper's Fig. 1: the joint references held with
  the torque), during the move and through the window after it.
* the closed form's own figures: **after the move** (:func:`after_end`, the plant left from
  the continuous torque's state where the feedforward ends) and **truncation**
  (:func:`truncation`, the continuous torque on the model with more modes).

:class:`Acceptance` holds the figures and says, against the :class:`Criteria` a user asked for,
whether the result passes or why not.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .config import DEFAULTS
from .errors import SettingsError
from .lti.discrete import recurrence, smooth_run, zero_order_hold
from .lti.system import NormalForm
from .signals.chebyshev import PiecewiseChebyshev
from .signals.trajectory import Trajectory

__all__ = ["Criteria", "AfterEnd", "Truncation", "Sampled", "Acceptance", "window_length", "free_excursions", "free_peaks", "after_end",
           "truncation", "held_table", "held_run", "sampled", "drive_series", "Demand", "demand", "table_rate", "outside_values", "judge",
           "summary_keys", "larger_model", "need_ratio", "need_word", "given_rule", "closed_loop", "loop_run", "loop_drive", "rest_angle", "rest_state", "WORDS", "WINDOW", "LONGEST_WINDOW"]

FloatArray = NDArray[np.float64]

#: The after-end window of a plant without stable modes (a link without damping), s: the one constant
#: (:attr:`inversion.config.Defaults.vibration_window`) the acceptance, ``compare``'s residual vibration and the help read.
WINDOW = DEFAULTS.vibration_window
#: Longest after-end window: five time constants of a very slow mode are cut here (s).
LONGEST_WINDOW = 60.0
#: Most points of a free response (the window's grid: four per period of the fastest mode, or fewer).
_FREE_POINTS = 20_000
#: Quintic-hold steps per Chebyshev piece when a series drives a plant.
_STEPS_PER_PIECE = 48


@dataclass(frozen=True)
class Criteria:
    """What a feedforward must meet to be what its user asked for.

    The judged form of a :class:`~inversion.problem.Problem`'s bounds and sampling
    (:meth:`~inversion.problem.Problem.criteria`: each field resolved), which the methods and the door read. Called
    ``Bounds`` until issue 55 (the name is the problem's now).

    Attributes
    ----------
    max_error : float
        The tip bound (m): the held plant's tip within it of ``y_d`` at the rows during the
        move, and of ``y_d(t_f)`` after the table ends (and the redefinition within it of ``y_d``).
    max_torque : float or None
        The caller's peak-torque limit (N m); ``None``: ``torque_ratio`` times the rigid-body need.
    torque_ratio : float
        The default limit, as a multiple of the rigid-body need.
    window : float or None
        The after-end window (s); ``None``: :func:`window_length`.
    extra_modes : int
        Modes the truncation check adds to a link's model (0: no check).
    period : float
        The controller's period (s).
    hold : str
        ``"point"`` or ``"zoh"`` (:func:`held_table`).
    max_torque_rate : float or None
        The largest accepted change between consecutive rows (N m); ``None``: ``torque_rate_ratio``
        times the rigid body's largest change over one period; ``inf`` accepts any.
    torque_rate_ratio : float
        The default rate bound, as a multiple of the rigid body's.
    truncation_factor : float
        With ``extra_modes`` more modes the held tip must stay within this multiple of ``max_error``.
    loop : (float, float) or None
        A link's joint PD gains ``(k_P, k_D)``: the held table is judged with that loop closed too (during the move and
        through the window after it, :func:`closed_loop`); ``None``: with the feedforward alone.
    max_torque_source, max_torque_rate_source : str
        Where a given bound comes from, in words (the caller's, or the drive's of the geometry file).
    """

    max_error: float
    max_torque: float | None = None
    torque_ratio: float = DEFAULTS.torque_ratio
    window: float | None = None
    extra_modes: int = DEFAULTS.extra_modes
    period: float = 1.0 / DEFAULTS.rate
    hold: str = DEFAULTS.hold
    max_torque_rate: float | None = None
    torque_rate_ratio: float = DEFAULTS.torque_rate_ratio
    truncation_factor: float = DEFAULTS.truncation_factor
    loop: tuple[float, float] | None = None
    max_torque_source: str = "the given max_torque"
    max_torque_rate_source: str = "the given max_torque_rate"

    def torque_limit(self, rigid: float) -> float:
        """The peak torque accepted (N m).

        Parameters
        ----------
        rigid : float
            The rigid (or static) need's peak (N m).
        """
        return float(self.max_torque) if self.max_torque is not None else self.torque_ratio * rigid

    def torque_rule(self, link: bool = True) -> str:
        """The peak torque's bound in words.

        Parameters
        ----------
        link : bool, optional
            Whether the plant is a link (else a generic system).
        """
        return self.max_torque_source if self.max_torque is not None else f"{self.torque_ratio:g} x the {need_word(link)}"

    def rate_limit(self, rigid_rate: float, link: bool = True) -> tuple[float, str]:
        """The largest change between rows accepted (N m) and its rule.

        Parameters
        ----------
        rigid_rate : float
            The rigid need's largest change over a period (N m).
        link : bool, optional
            Whether the plant is a link (else a generic system).
        """
        if self.max_torque_rate is not None:
            return float(self.max_torque_rate), self.max_torque_rate_source
        return self.torque_rate_ratio * rigid_rate, f"{self.torque_rate_ratio:g} x the {need_word(link)}'s change over a period"


def given_rule(bounds: Criteria) -> str:
    """An absolute peak torque's rule, as the family's records name it.

    ``"given"`` (the user's), else whence (the link's ``[drive]``: :attr:`Criteria.max_torque_source`).

    Parameters
    ----------
    bounds : Criteria
        Bounds with an absolute ``max_torque``.
    """
    return "given" if bounds.max_torque_source == Criteria.max_torque_source else bounds.max_torque_source


def need_ratio(value: float, need: float) -> float:
    """``value`` over what a rigid body (or the static inverse) needs.

    0 where neither is anything (a move of zero length), ``inf`` where only the need is zero.

    Parameters
    ----------
    value : float
        The peak or the rows' largest change.
    need : float
        The rigid need's (its peak, or its largest change over a period).
    """
    if need > 0:
        return value / need
    return 0.0 if value == 0 else math.inf


def need_word(link: bool) -> str:
    """What the torque is compared with: rigid or static need.

    Parameters
    ----------
    link : bool
        Whether the plant is a link (else a generic system).
    """
    return "rigid need" if link else "static need"


#: The words of the messages: a link's, a generic system's (its output and input, no units).
WORDS = {True: {"out": "tip", "inp": "torque", "m": " m", "speed": " m/s", "needs": "what a rigid body needs"},
         False: {"out": "output", "inp": "input", "m": "", "speed": "/s", "needs": "what the static inverse needs"}}


@dataclass(frozen=True)
class AfterEnd:
    """The linear plant left alone after the feedforward ends.

    Attributes
    ----------
    window : float
        Seconds after the feedforward's end over which the tip is watched.
    feed_end : float
        When the feedforward ends (``t_f``, or later with a post-actuation), s.
    max_tip_excursion : float
        ``max |y - y_d(t_f)|`` over ``[t_f, feed_end + window]`` (m).
    drift : float
        The output's rate the plant keeps for ever (m/s; a link's ``x_out h / J``).
    """

    window: float
    feed_end: float
    max_tip_excursion: float
    drift: float

    def as_dict(self) -> dict[str, float]:
        """JSON-ready."""
        return {"window": self.window, "feed_end": self.feed_end, "max_tip_excursion": self.max_tip_excursion, "drift": self.drift}


@dataclass(frozen=True)
class Truncation:
    """The feedforward applied to the model with more modes.

    Attributes
    ----------
    modes : int
        The modes of the larger model.
    tip_error : float
        ``max |y - y_d|`` over the move and the after-end window (m).
    """

    modes: int
    tip_error: float

    def as_dict(self) -> dict[str, float | int]:
        """JSON-ready."""
        return {"modes": self.modes, "tip_error": self.tip_error}


@dataclass(frozen=True)
class Sampled:
    """The discretised plant driven by the held table from rest.

    The exactly discretised plant driven by the held table from rest, through the move and the window after it.

    Attributes
    ----------
    period : float
        The controller's period (s).
    hold : str
        ``"point"`` (the value at the period's start) or ``"zoh"`` (the period's mean).
    max_tracking_error : float
        ``max_k |y_k - y~(t_k)|`` over the table (m).
    relative_tracking_error : float
        Of the move.
    max_tip_error : float
        ``max_k |y_k - y_d(t_k)|`` over the table (m): what the held plant does against the request.
    samples : int
        Rows.
    window : float
        The after-end window (s).
    after_end_excursion : float
        The held plant's largest ``|y - y_d(t_f)|`` over the window after the table ends, the input then the
        one that follows (m; between the rows too: the free response is exact).
    drift : float
        The output's rate the held plant keeps for ever after the table (m/s).
    more_modes : int or None
        Modes of the larger model (``None``: not checked).
    more_modes_error : float or None
        The larger model driven by the same rows from rest: its largest ``|y - y_d|`` during the move and over the
        window after (m).
    torque_rate : float
        The largest change between consecutive rows, the first against the input before the table and the last
        against the input after it (N m).
    rigid_torque_rate : float
        The rigid body's largest change of input over one period along ``y_d`` (:func:`demand`).
    loop_kp, loop_kd : float or None
        The joint PD gains the table was judged with in the loop (:attr:`Criteria.loop`; ``None``: not judged there).
    loop_error, loop_after : float or None
        In that loop: the tip's largest ``|y - y_d|`` at the rows during the move, and ``|y - y_d(t_f)|`` over the window
        after it (m).
    loop_torque, loop_torque_rate : float or None
        In that loop, where a torque bound is the motor's (absolute: given, or the link's ``[drive]``): what the motor
        delivers, the table and the PD's correction together -- its largest ``|tau|`` at the rows and through the window
        after the move, and its largest step from one row to the next (the references step at the rows, the measured
        state does not) (N m; ``None``: not asked, :func:`loop_drive`).
    """

    period: float
    hold: str
    max_tracking_error: float
    relative_tracking_error: float
    max_tip_error: float
    samples: int
    window: float = 0.0
    after_end_excursion: float = 0.0
    drift: float = 0.0
    more_modes: int | None = None
    more_modes_error: float | None = None
    torque_rate: float = 0.0
    rigid_torque_rate: float = 0.0
    loop_kp: float | None = None
    loop_kd: float | None = None
    loop_error: float | None = None
    loop_after: float | None = None
    loop_torque: float | None = None
    loop_torque_rate: float | None = None

    def motor_excess(self, bounds: "Criteria") -> str | None:
        """The motor in the loop beyond its bounds, in words.

        Where the motor in the loop (:attr:`loop_torque`, :attr:`loop_torque_rate`) is beyond an absolute bound of
        ``bounds`` (given, or the drive's): the figures in words; ``None`` where it is within them (or not measured).

        Parameters
        ----------
        bounds : Criteria
            The bounds judged by (their ``max_torque`` and ``max_torque_rate``: ``None`` where relative to the move).
        """
        if self.loop_torque is None or self.loop_torque_rate is None:
            return None
        over = [f"{what} {value:.4g} N m, beyond the bound {limit:.4g} ({source})" for what, value, limit, source in
                (("up to", self.loop_torque, bounds.max_torque, bounds.max_torque_source),
                 ("stepping at a row by up to", self.loop_torque_rate, bounds.max_torque_rate, bounds.max_torque_rate_source))
                if limit is not None and not value <= float(limit) * (1 + 1e-12)]
        return "; ".join(over) or None

    @property
    def torque_rate_ratio(self) -> float:
        """The rows' largest change over the rigid body's over a period (:func:`need_ratio`)."""
        return need_ratio(self.torque_rate, self.rigid_torque_rate)

    def as_dict(self) -> dict[str, float | int | str | None]:
        """JSON-ready (the summary's ``sampled`` block)."""
        return {"period": self.period, "hold": self.hold, "max_tracking_error": self.max_tracking_error,
                "relative_tracking_error": self.relative_tracking_error, "max_tip_error": self.max_tip_error,
                "samples": self.samples, "window": self.window, "after_end_excursion": self.after_end_excursion,
                "drift": self.drift, "more_modes": self.more_modes, "more_modes_error": self.more_modes_error,
                "torque_rate": self.torque_rate, "rigid_torque_rate": self.rigid_torque_rate,
                "torque_rate_ratio": self.torque_rate_ratio,
                **({} if self.loop_error is None else {"loop_kp": self.loop_kp, "loop_kd": self.loop_kd,
                                                       "loop_error": self.loop_error, "loop_after": self.loop_after}),
                **({} if self.loop_torque is None else {"loop_torque": self.loop_torque, "loop_torque_rate": self.loop_torque_rate})}


@dataclass(frozen=True)
class Acceptance:
    """The figures of what reaches the link (module docstring).

    Attributes
    ----------
    rigid_torque : float
        What a rigid body needs along ``y_d`` (N m; a system's input).
    peak_torque : float
        The feedforward's peak.
    error : float
        The result's ``max |y~ - y_d|`` (m).
    move : float
        The move (m).
    after_end : AfterEnd
    truncation : Truncation or None
        ``None`` for a generic system, or when not checked.
    sampled : Sampled or None
        ``None`` when not checked.
    link : bool
        A link's (its messages say tip, torque, m), or a generic system's (output, input).
    """

    rigid_torque: float
    peak_torque: float
    error: float
    move: float
    after_end: AfterEnd
    truncation: Truncation | None = None
    sampled: Sampled | None = None
    link: bool = True

    @property
    def torque_ratio(self) -> float:
        """The peak over the rigid-body need (:func:`need_ratio`)."""
        return need_ratio(self.peak_torque, self.rigid_torque)

    def failure(self, bounds: Criteria, torque_limit: tuple[float, str] | None = None) -> tuple[str, str] | None:
        """``(status, message)`` of the first bound missed, or ``None``.

        In order: the peak torque, the redefinition's error, then the held table through the
        window -- the tip at the rows, after the table ends, with more modes (within
        :attr:`Criteria.truncation_factor` times the bound) -- and the held rows' rate. ``torque_limit``: the limit and
        its rule in words, where a search set it (default :meth:`Criteria.torque_limit`).

        Parameters
        ----------
        bounds : Criteria
            The bounds to check.
        torque_limit : tuple[float, str] | None, optional
            The limit and its rule in words, where a search set it.
        """
        move = self.move if self.move > 0 else 1.0
        bound = bounds.max_error
        w = WORDS[self.link]
        m, out, inp = w["m"], w["out"], w["inp"]
        if torque_limit is None:
            limit, rule = bounds.torque_limit(self.rigid_torque), bounds.torque_rule(self.link)
        else:
            limit, rule = torque_limit
        if not self.peak_torque <= limit * (1 + 1e-12):
            return "max-torque", (f"the peak {inp} {self.peak_torque:.4g} is {self.torque_ratio:.3g} x {w['needs']} "
                                  f"({self.rigid_torque:.4g}); accepted {limit:.4g} ({rule})")
        held = self.sampled
        if not self.error <= bound:
            return "max-error", (f"the redefined output is {self.error:.4g}{m} from the desired one ({self.error / move:.3g} of the "
                                 f"move; accepted {bound:.3g}{m})")
        if held is not None:
            if not held.max_tip_error <= bound:
                return "sampled", (f"held at {held.period:g} s ({held.hold}) the plant's {out} is {held.max_tip_error:.4g}{m} from y_d "
                                   f"({held.max_tip_error / move:.3g} of the move; accepted {bound:.3g}{m})")
            if not held.after_end_excursion <= bound:
                return "after-end", (f"held at {held.period:g} s ({held.hold}) with the {inp} ended after the table, the {out} strays "
                                     f"{held.after_end_excursion:.4g}{m} from y_d(t_f) in the {held.window:g} s after it "
                                     f"({held.after_end_excursion / move:.3g} of the move; accepted {bound:.3g}{m}), drifting at "
                                     f"{held.drift:.3g}{w['speed']} (the continuous {inp}'s: {self.after_end.max_tip_excursion:.3g}{m})")
            if held.more_modes_error is not None and not held.more_modes_error <= bounds.truncation_factor * bound:
                return "truncation", (f"held at {held.period:g} s on the model with {held.more_modes} modes the {out} strays "
                                      f"{held.more_modes_error:.4g}{m} from y_d during and after the move ({held.more_modes_error / move:.3g} "
                                      f"of the move; accepted {bounds.truncation_factor:g} x {bound:.3g}{m}): the model has too few "
                                      "modes for this feedforward")
            rate, rate_rule = bounds.rate_limit(held.rigid_torque_rate, self.link)
            if not held.torque_rate <= rate * (1 + 1e-12):
                return "torque-rate", (f"held at {held.period:g} s ({held.hold}) the table changes by up to {held.torque_rate:.4g} from "
                                       f"one row to the next (the first row against the input before it, the last against the one "
                                       f"after), {held.torque_rate_ratio:.3g} x the {need_word(self.link)}'s largest change over a "
                                       f"period ({held.rigid_torque_rate:.4g}); accepted {rate:.4g} ({rate_rule}): a step the drive "
                                       "and the unmodelled modes see")
            if held.loop_error is not None and not max(held.loop_error, held.loop_after or 0.0) <= bound:
                return "closed-loop", (f"held at {held.period:g} s ({held.hold}) with the joint PD closed (k_P = {held.loop_kp:.4g}, "
                                       f"k_D = {held.loop_kd:.4g}) the {out} is {held.loop_error:.4g}{m} from y_d during the move "
                                       f"and strays {held.loop_after or 0.0:.4g}{m} from y_d(t_f) after it ({max(held.loop_error, held.loop_after or 0.0) / move:.3g} "
                                       f"of the move; accepted {bound:.3g}{m}; the feedforward alone: {held.max_tip_error:.4g}{m}): "
                                       "the loop it runs in drags the table")
            motor = held.motor_excess(bounds)
            if motor is not None:
                return "closed-loop", (f"held at {held.period:g} s ({held.hold}) with the joint PD closed (k_P = {held.loop_kp:.4g}, "
                                       f"k_D = {held.loop_kd:.4g}) the motor delivers the table and the PD's correction: {motor} "
                                       "(the table alone is within it)")
            return None
        after = self.after_end
        if not after.max_tip_excursion <= bound:
            return "after-end", (f"after the feedforward ends the {out} strays {after.max_tip_excursion:.4g}{m} from y_d(t_f) in "
                                 f"{after.window:g} s ({after.max_tip_excursion / move:.3g} of the move; accepted "
                                 f"{bound:.3g}{m}), drifting at {after.drift:.3g}{w['speed']}")
        if self.truncation is not None and not self.truncation.tip_error <= bounds.truncation_factor * bound:
            return "truncation", (f"with {self.truncation.modes} modes the {out} strays {self.truncation.tip_error:.4g}{m} from y_d "
                                  f"({self.truncation.tip_error / move:.3g} of the move; accepted {bounds.truncation_factor:g} x "
                                  f"{bound:.3g}{m}): the model has too few modes for this feedforward")
        return None


@dataclass(frozen=True)
class Demand:
    """What a move asks of the plant, sampled once.

    Its ends, the inputs that hold them, the rigid body's need (the scales of the torque and rate bounds).

    Attributes
    ----------
    y_start, y_final : float
        ``y_d(t_0)`` and ``y_d(t_f)``.
    hold_start, hold_final : float
        The inputs that hold the plant at rest there (:meth:`NormalForm.equilibrium_input`).
    rigid_torque : float
        What a rigid body needs along ``y_d`` at its peak (:meth:`NormalForm.rigid_input`, on a dense grid of the move
        and its breakpoints, from both sides).
    rigid_rate : float
        Its largest change over one period, ``max_t |need(t + DT) - need(t)|`` with the need zero before and after the move
        (a link: about ``J max |y_d^(3)| DT / x_out`` for a smooth move; a system: its static need's).
    """

    y_start: float
    y_final: float
    hold_start: float
    hold_final: float
    rigid_torque: float
    rigid_rate: float


_DEMANDS: dict[tuple[int, bytes, float], tuple[Trajectory, Demand]] = {}


def demand(form: NormalForm, trajectory: Trajectory, period: float, points: int = 20_001) -> Demand:
    """What the move asks of the plant (:class:`Demand`).

    ``y_d`` sampled once on every grid it is read from, then read by the plant. Kept for the trajectory and plant a search
    asks about again.

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    trajectory : Trajectory
        The desired output.
    period : float
        The controller's period ``DT`` (s).
    points : int, optional
        Size of the dense grid.
    """
    key = (id(trajectory), form.A.tobytes() + form.B.tobytes() + form.C.tobytes() + repr((form.inertia, form.output_at,
                                                                                        form.joint_damping)).encode(), float(period))
    cached = _DEMANDS.get(key)
    if cached is not None and cached[0] is trajectory:
        return cached[1]
    t0, tf = trajectory.t0, trajectory.tf
    inner = [b for b in trajectory.breakpoints if t0 < b < tf]
    t = np.union1d(np.linspace(t0 - period, tf, points), [*inner, *(b - period for b in inner), t0, tf - period])
    dense = np.union1d(np.linspace(t0, tf, points), [b for b in trajectory.breakpoints if t0 <= b <= tf])
    # y_d's derivatives on every grid the need is read from, taken at once: now and a period later; inside, from both sides
    orders = form.need_orders
    now, later, right, left = ({k: trajectory.derivative(times, k, side) for k in orders}
                               for times, side in ((t, "+"), (t + period, "+"), (dense, "+"), (dense, "-")))
    y_start, y_final = trajectory.y_start, trajectory.y_final
    # then the plant's reading of them
    needs = [form.rigid_need(s.__getitem__) for s in (now, later)]
    rate = float(np.abs(needs[1] - needs[0]).max(initial=0.0)) if needs[0].size else 0.0
    peak = form.rigid_input({k: np.concatenate([right[k], left[k]]) for k in orders}.__getitem__)
    found = Demand(y_start, y_final, form.equilibrium_input(y_start), form.equilibrium_input(y_final), peak, rate)
    if len(_DEMANDS) > 32:
        _DEMANDS.clear()
    _DEMANDS[key] = (trajectory, found)
    return found


def table_rate(rows: ArrayLike, before: float, after: float) -> float:
    """The largest change between consecutive rows of a held table.

    The largest change between consecutive rows of a held table, the first against ``before`` and the last against
    ``after`` (the inputs the drive holds outside the table).

    Parameters
    ----------
    rows : ArrayLike
        The table's inputs, one a row.
    before : float
        The input held before the table.
    after : float
        The input held after it.
    """
    values = np.concatenate([[float(before)], np.asarray(rows, dtype=float).reshape(-1), [float(after)]])
    return float(np.abs(np.diff(values)).max(initial=0.0))


def window_length(form: NormalForm, given: float | None = None) -> float:
    """The after-end window's length (s).

    The after-end window: ``given``, or :data:`WINDOW` (2 s), or five time constants of the slowest stable mode if longer.

    Capped at :data:`LONGEST_WINDOW`.

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    given : float | None, optional
        The caller's window (s), or ``None``.
    """
    if given is not None:
        return float(given)
    return _window_of(form.A.tobytes(), form.A.shape[0])


@functools.lru_cache(maxsize=32)
def _window_of(A_bytes: bytes, N: int) -> float:
    """:func:`window_length`'s rule for the plant matrix (kept: a search asks for it once a batch)."""
    poles = np.linalg.eigvals(np.frombuffer(A_bytes).reshape(N, N))
    scale = max(float(np.abs(poles).max(initial=0.0)), 1.0)
    stable = poles.real[poles.real < -1e-9 * scale]
    slowest = float(f"{5.0 / float(np.abs(stable).min()):.4g}") if stable.size else 0.0  # (the poles' rounding not shown)
    return float(min(max(WINDOW, slowest), LONGEST_WINDOW))


_FREE_ROWS: dict[tuple[bytes, bytes, bytes, float, float], tuple[FloatArray, FloatArray]] = {}


def _free_rows(A: FloatArray, B: FloatArray, C: FloatArray, window: float, hold: float) -> tuple[FloatArray, FloatArray]:
    """``(times, R)`` with ``y(t_j) = R[j] . [X; 1]``: the plant's free response, its input held, on the window's grid
    (kept for the plants of a search: every batch of members asks for the same)."""
    key = (np.asarray(A).tobytes(), np.asarray(B).tobytes(), np.asarray(C).tobytes(), float(window), float(hold))
    if key not in _FREE_ROWS:
        if len(_FREE_ROWS) > 16:
            _FREE_ROWS.clear()
        _FREE_ROWS[key] = _compute_free_rows(np.asarray(A), np.asarray(B), np.asarray(C), window, hold)
    return _FREE_ROWS[key]


def _compute_free_rows(A: FloatArray, B: FloatArray, C: FloatArray, window: float, hold: float) -> tuple[FloatArray, FloatArray]:
    """:func:`_free_rows`, computed."""
    N = A.shape[0]
    Aa = np.zeros((N + 1, N + 1))
    Aa[:N, :N], Aa[:N, N] = A, B * hold
    fastest = float(np.abs(np.linalg.eigvals(A)).max(initial=0.0))
    count = int(min(_FREE_POINTS, max(200, math.ceil(window * fastest * 2 / math.pi))))
    import scipy.linalg as sla  # lazy: keeps `import inversion` fast

    step = sla.expm(Aa * (window / count))
    rows = np.empty((count + 1, N + 1))
    rows[0] = np.append(C, 0.0)
    # rows[j] = rows[0] step^j by doubling: the rows known times step^filled give as many more (a few products of many
    # rows where a row at a time took 20 000; the margin's search asks it of each plant it perturbs: 16 ms -> 0.5 ms)
    filled, power = 1, step
    while filled <= count:
        take = min(filled, count + 1 - filled)
        rows[filled:filled + take] = rows[:take] @ power
        filled += take
        if filled <= count:
            power = power @ power
    return np.linspace(0.0, window, count + 1), rows


def free_excursions(form: NormalForm, X: ArrayLike, y_final: float, hold: float, window: float) -> tuple[FloatArray, FloatArray]:
    """The largest free excursions of the plant from many states.

    The largest ``|y - y_final|`` of the plant left from each state of ``X`` (rows) for ``window`` s with its
    input held at ``hold``, and the rate it keeps (:meth:`NormalForm.drift`): many members at once.

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    X : ArrayLike
        States in rows.
    y_final : float
        The output's final value.
    hold : float
        The input held.
    window : float
        How long the plant is left (s).
    """
    X = np.atleast_2d(np.asarray(X, dtype=float))
    return _free_peaks(form.A, form.B, form.C, X, y_final, hold, window), form.drift(X, hold)


def free_peaks(A: FloatArray, B: FloatArray, C: FloatArray, X: FloatArray, y_final: float, hold: float, window: float) -> FloatArray:
    """The largest free excursions of any plant ``(A, B, C)``.

    The largest ``|y - y_final|`` of the plant ``(A, B, C)`` left from each row of ``X`` for ``window`` s, its input held at
    ``hold`` (any plant: a closed loop's too).

    Parameters
    ----------
    A : FloatArray
        The plant's state matrix.
    B : FloatArray
        Its input matrix.
    C : FloatArray
        Its output row.
    X : FloatArray
        States in rows.
    y_final : float
        The output's final value.
    hold : float
        The input held.
    window : float
        How long the plant is left (s).
    """
    return _free_peaks(np.asarray(A, dtype=float), np.asarray(B, dtype=float), np.asarray(C, dtype=float), np.asarray(X, dtype=float),
                       y_final, hold, window)


def _free_peaks(A: FloatArray, B: FloatArray, C: FloatArray, X: FloatArray, y_final: float, hold: float, window: float) -> FloatArray:
    """The largest ``|y - y_final|`` of the free plant ``(A, B, C)`` from each row of ``X`` over ``window``."""
    _, rows = _free_rows(A, B, C, window, hold)
    Xa = np.concatenate([np.atleast_2d(X), np.ones((np.atleast_2d(X).shape[0], 1))], axis=1)
    worst = np.zeros(Xa.shape[0])
    for lo in range(0, Xa.shape[0], 64):
        y = Xa[lo : lo + 64] @ rows.T
        worst[lo : lo + 64] = np.abs(y - y_final).max(axis=1)
    return worst


def after_end(form: NormalForm, X_end: ArrayLike, feed_end: float, y_final: float, hold: float, window: float,
              before: float = 0.0) -> AfterEnd:
    """The plant left from ``X_end`` where the feedforward ends.

    ``before``: the tip's largest excursion from ``y_final`` between ``t_f`` and ``feed_end``
    (a post-actuation), included in the figure.

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    X_end : ArrayLike
        The state where the feedforward ends.
    feed_end : float
        When it ends (s).
    y_final : float
        The output's final value.
    hold : float
        The input held after the end.
    window : float
        How long the plant is left (s).
    before : float, optional
        The tip's largest excursion from ``y_final`` between ``t_f`` and ``feed_end``.
    """
    worst, drift = free_excursions(form, X_end, y_final, hold, window)
    return AfterEnd(float(window), float(feed_end), float(max(worst[0], before)), float(drift[0]))


def drive_series(A: ArrayLike, B: ArrayLike, x0: ArrayLike, signals: PiecewiseChebyshev, name: str, C: ArrayLike,
                 steps_per_piece: int = _STEPS_PER_PIECE) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The plant driven by a piecewise Chebyshev series, exactly.

    The plant driven by a signal of a piecewise Chebyshev series over its span (quintic hold, exact).

    Returns the times, the outputs ``C x`` there and the state at the span's end: each interval of the series' bounds on
    a grid of ``steps_per_piece`` steps of its shortest piece (a jump of a derivative at a joint costs nothing).

    Parameters
    ----------
    A : ArrayLike
        The plant's state matrix.
    B : ArrayLike
        Its input matrix.
    x0 : ArrayLike
        The state at the span's start.
    signals : PiecewiseChebyshev
        The piecewise Chebyshev series that drives it.
    name : str
        The driving signal's name.
    C : ArrayLike
        The output row.
    steps_per_piece : int, optional
        Hold intervals per piece of the series.
    """
    constant = ~np.any(signals.coefficients[:, :, 1:], axis=(1, 2))  # pieces held constant (a held table's)
    grids: list[FloatArray] = []
    for k in range(signals.bounds.size - 1):
        a, b = float(signals.bounds[k]), float(signals.bounds[k + 1])
        first, last = signals.piece_start[k], signals.piece_start[k + 1]
        widths = np.diff(signals.edges[first + k : last + k + 1])
        held = bool(np.all(constant[first:last])) and last - first == 1
        n = 1 if held else max(8, math.ceil((b - a) / float(widths.min()) * steps_per_piece))
        grids.append(np.linspace(a, b, n + 1))
    # every point of every interval at once, each interval's own series at its end
    inside = np.concatenate([np.clip(g, g[0], np.nextafter(g[-1], g[0])) for g in grids])
    values = [signals.evaluate(inside, derivative=d)[name] for d in range(3)]
    C = np.asarray(C, dtype=float).reshape(-1)
    x = np.asarray(x0, dtype=float).reshape(-1)
    times: list[FloatArray] = [np.array([signals.bounds[0]])]
    outputs: list[FloatArray] = [np.array([float(C @ x)])]
    at = 0
    for grid in grids:
        count = grid.size
        y, x = smooth_run(A, B, x, grid, *(v[at : at + count] for v in values), C=C)
        at += count
        times.append(grid[1:])
        outputs.append(y[1:])
    return np.concatenate(times), np.concatenate(outputs), x


def truncation(matrices: dict[str, Any], signals: PiecewiseChebyshev, y_desired: Callable[[FloatArray], FloatArray], y_final: float,
               feed_end: float, window: float, modes: int) -> Truncation:
    """The feedforward applied from rest to a model with more modes.

    The feedforward ``signals`` (its first signal, the torque) applied from rest to a larger model (:func:`modelgen.linear.linear_model`'s
    matrices), then the plant left alone for ``window`` s: the tip's largest distance from ``y_d`` (held at ``y_d(t_f)``).

    Parameters
    ----------
    matrices : dict[str, Any]
        The larger model's matrices (:func:`larger_model`).
    signals : PiecewiseChebyshev
        The feedforward's signals, the torque first.
    y_desired : callable
        The desired output ``y_d`` as a function of time (held outside the move).
    y_final : float
        ``y_d(t_f)``.
    feed_end : float
        When the feedforward ends (s).
    window : float
        How long the plant is left after it (s).
    modes : int
        The larger model's number of modes.
    """
    A, B, C = (np.asarray(matrices[k], dtype=float) for k in ("A", "B", "C_out"))
    B, C = B.reshape(-1), C.reshape(-1)
    t, y, x_end = drive_series(A, B, np.zeros(A.shape[0]), signals, signals.names[0], C)
    worst = float(np.abs(y - y_desired(t)).max())
    after = _free_peaks(A, B, C, x_end[None, :], y_final, 0.0, window)
    return Truncation(int(modes), max(worst, float(after[0])))


def outside_values(signals: PiecewiseChebyshev, t: float, held_input: float) -> FloatArray:
    """The signals at ``t`` with the input held outside the span.

    The signals at ``t`` with the input (the first signal) replaced by ``held_input``: what a held table holds
    outside the feedforward's span (the equilibrium input: zero torque for a link).

    Parameters
    ----------
    signals : PiecewiseChebyshev
        The feedforward's signals, the input first.
    t : float
        The time (s).
    held_input : float
        The input held outside the span.
    """
    values = np.array([float(v[0]) for v in signals.evaluate([t]).values()])
    values[0] = held_input
    return values


def held_table(signals: PiecewiseChebyshev, t0: float, feed_end: float, period: float, hold: str,
               before: ArrayLike, after: ArrayLike) -> tuple[FloatArray, dict[str, FloatArray]]:
    """The samples a controller at ``period`` holds.

    The samples a controller at ``period`` holds: ``t_k = t0 + k period`` from ``t0`` until the feedforward ends.

    ``hold="point"``: the signals at ``t_k``. ``hold="zoh"``: the torque (first signal) as its
    mean over ``[t_k, t_k + period)`` (exact, :meth:`PiecewiseChebyshev.means`; ``after``
    where the period runs past the feedforward's end), the other signals (a link's joint
    references) at ``t_k``, where a digital PD samples them.

    Parameters
    ----------
    signals : PiecewiseChebyshev
        The feedforward's signals, the input first.
    t0 : float
        The table's first time (s).
    feed_end : float
        When the feedforward ends (s).
    period : float
        The controller's period (s).
    hold : str
        ``"point"`` or ``"zoh"``.
    before : ArrayLike
        The signals before the span.
    after : ArrayLike
        The signals after the span.
    """
    count = max(1, math.ceil((feed_end - t0) / period - 1e-9))
    t = np.asarray(t0 + np.arange(count) * period, dtype=float)
    values = signals.evaluate(t)
    if hold == "zoh":
        name = signals.names[0]
        values[name] = signals.means(np.append(t, t[-1] + period), before, after)[name]
    return t, values


@functools.lru_cache(maxsize=64)
def _held_plant(A_bytes: bytes, B_bytes: bytes, N: int, period: float) -> tuple[FloatArray, FloatArray]:
    """:func:`~inversion.lti.discrete.zero_order_hold` of a plant, kept (a search judges many members at one period)."""
    return zero_order_hold(np.frombuffer(A_bytes).reshape(N, N), np.frombuffer(B_bytes), period)


def held_run(A: FloatArray, B: FloatArray, C: FloatArray, x0: FloatArray, rows: FloatArray, period: float) -> tuple[FloatArray, FloatArray]:
    """The plant held on ``rows``: its outputs and last state.

    The outputs at ``t_0 .. t_K`` and the state at ``t_K``.

    Parameters
    ----------
    A, B, C : ndarray
        The plant (``B`` and ``C`` as vectors).
    x0 : ndarray
        Its state at ``t_0``.
    rows : ndarray, shape (K,)
        The input held over each period.
    period : float
        The period (s).
    """
    A, B = np.ascontiguousarray(A, dtype=float), np.ascontiguousarray(B, dtype=float).reshape(-1)
    Ad, Bd = _held_plant(A.tobytes(), B.tobytes(), A.shape[0], float(period))
    return recurrence(Ad, Bd[:, None], x0, rows[:, None], np.asarray(C, dtype=float).reshape(-1))


def sampled(form: NormalForm, signals: PiecewiseChebyshev, x0: ArrayLike, t0: float, feed_end: float, period: float, hold: str,
            outside: tuple[ArrayLike, ArrayLike], reference: Callable[[FloatArray], FloatArray], y_desired: Callable[[FloatArray], FloatArray],
            move: float, *, y_final: float, window: float, larger: tuple[int, dict[str, Any]] | None = None,
            rigid_rate: float = 0.0, from_rest: bool = True, loop: tuple[float, float] | None = None, motor: bool = False) -> Sampled:
    """The held table through the window (module docstring).

    The held table through the window (module docstring): the exactly discretised plant driven by :func:`held_table`'s rows
    from ``x0``, against ``y~`` (``reference``) and ``y_d`` (``y_desired``) at the rows ``t_0 .. t_K``; then left with the input
    after the table (``outside[1]``'s first value) over ``window``; and the larger model (``larger``, from rest) on the same rows.

    ``outside``: the signals before the table and after it (:func:`outside_values`); ``y_final``: ``y_d(t_f)``;
    ``rigid_rate``: the rigid body's largest change over a period (:func:`demand`); ``from_rest``: whether the plant
    is at rest where the table starts (if not, no input was held before it: its first row is not judged against one).

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    signals : PiecewiseChebyshev
        The feedforward's signals, the input first.
    x0 : ArrayLike
        The plant's state at ``t0``.
    t0 : float
        The table's first time (s).
    feed_end : float
        When the feedforward ends (s).
    period : float
        The controller's period (s).
    hold : str
        ``"point"`` or ``"zoh"``.
    outside : tuple[ArrayLike, ArrayLike]
        The signals held before and after the table.
    reference : Callable[[FloatArray], FloatArray]
        The redefined output ``y~`` as a function of time.
    y_desired : Callable[[FloatArray], FloatArray]
        The desired output ``y_d`` as a function of time.
    move : float
        The range of ``y_d`` (the figures' scale).
    y_final : float
        The output's final value.
    window : float
        How long the plant is left after the table (s).
    larger : tuple[int, dict[str, Any]] | None, optional
        The larger model, its modes and matrices (:func:`larger_model`).
    rigid_rate : float, optional
        The rigid need's largest change over a period.
    from_rest : bool, optional
        Whether the larger model starts from rest.
    loop : (float, float), optional
        A link's joint PD gains: the same rows judged with that loop closed too (:func:`closed_loop`).
    motor : bool, optional
        Whether a torque bound is the motor's (absolute): the loop's own torque is then measured too (:func:`loop_drive`).
    """
    t, values = held_table(signals, t0, feed_end, period, hold, *outside)
    u = np.asarray(values[signals.names[0]], dtype=float)
    before, after = float(np.asarray(outside[0])[0]) if from_rest else float(u[0]), float(np.asarray(outside[1])[0])
    x0 = np.asarray(x0, dtype=float).reshape(-1)
    times = np.append(t, t[-1] + period)
    y, x_end = held_run(form.A, form.B, form.C, x0, u, period)
    tracking = float(np.abs(y - reference(times)).max())
    desired = y_desired(times)
    tip = float(np.abs(y - desired).max())
    excursion = float(_free_peaks(form.A, form.B, form.C, x_end[None, :], y_final, after, window)[0])
    drift = float(form.drift(x_end[None, :], after)[0])
    modes, more = None, None
    if larger is not None:
        A_L, B_L, C_L = (np.asarray(larger[1][k], dtype=float) for k in ("A", "B", "C_out"))
        B_L, C_L = B_L.reshape(-1), C_L.reshape(-1)
        y_L, x_L = held_run(A_L, B_L, C_L, np.zeros(A_L.shape[0]), u, period)
        more = max(float(np.abs(y_L - desired).max()), float(_free_peaks(A_L, B_L, C_L, x_L[None, :], y_final, 0.0, window)[0]))
        modes = int(larger[0])
    looped: dict[str, float] = {}
    if loop is not None and "theta_d" in values and "thetadot_d" in values:
        # after the table the joint references are the rest on y_d(t_f) (the exported C's FINAL, the simulation's)
        A_c, u_c, after_c, during, later = loop_run(form, loop, u, np.asarray(values["theta_d"], dtype=float),
                                                    np.asarray(values["thetadot_d"], dtype=float), x0, after, y_final, desired,
                                                    period, window)
        looped = {"loop_kp": float(loop[0]), "loop_kd": float(loop[1]), "loop_error": during, "loop_after": later}
        if motor:
            looped.update(zip(("loop_torque", "loop_torque_rate"),
                              loop_drive(A_c, form.B, loop, x0, u_c, before + float(loop[0]) * float(x0[0]) if from_rest
                                         else float(u_c[0]), after_c, period, window)))  # (not at rest: no row before)
    return Sampled(float(period), hold, tracking, tracking / move if move > 0 else 0.0, tip, int(u.size), float(window), excursion,
                   drift, modes, more, table_rate(u, before, after), float(rigid_rate), **looped)


def loop_run(form: NormalForm, gains: tuple[float, float], u: FloatArray, theta_d: FloatArray, thetadot_d: FloatArray,
             x0: FloatArray, after: float, y_final: float, desired: FloatArray, period: float, window: float
             ) -> tuple[FloatArray, FloatArray, float, float, float]:
    """A held table in the joint PD loop: the tip's largest errors.

    The tip's largest error during the move and after it. The loop of :func:`closed_loop` (the paper's Fig. 1, Eq. (40))
    driven by the rows ``u`` with their references, from ``x0``; after the table the input ``after`` with the references
    at rest on ``y_final`` (the exported C's ``FINAL``).

    Parameters
    ----------
    form : NormalForm
        A link's plant, its coordinates ``[theta, delta, thetadot, deltadot]``.
    gains : (float, float)
        ``(k_P, k_D)``.
    u, theta_d, thetadot_d : ndarray
        The held rows and their references (``K`` each).
    x0 : ndarray
        The state where the table starts.
    after : float
        The input held after the table.
    y_final : float
        ``y_d(t_f)``.
    desired : ndarray
        ``y_d`` at ``t_0 .. t_K`` (``K + 1``).
    period, window : float
        The controller's period and the window after the table (s).

    Returns
    -------
    tuple
        The loop's matrix, its held inputs and the input after the table (:func:`closed_loop`), then
        ``max |y - y_d|`` at the rows and the largest ``|y - y_d(t_f)|`` through the window after them.
    """
    A_c, u_c, after_c = closed_loop(form.A, form.B, gains, u, theta_d, thetadot_d, after, rest_angle(form.C, y_final), 0.0)
    y_c, x_c = held_run(A_c, form.B, form.C, np.asarray(x0, dtype=float), u_c, period)
    return (A_c, u_c, after_c, float(np.abs(y_c - desired).max()),
            float(_free_peaks(A_c, form.B, form.C, x_c[None, :], y_final, after_c, window)[0]))


def loop_drive(A_c: FloatArray, B: FloatArray, gains: tuple[float, float], x0: FloatArray, u_c: FloatArray, before_c: float,
               after_c: float, period: float, window: float) -> tuple[float, float]:
    """What the motor delivers in the joint PD loop.

    Its peak and its largest step between rows. In the loop of :func:`closed_loop` the motor's torque is
    ``tau(t) = u_c,k - K x(t)`` over period ``k`` (``u_c,k`` the table's row with the PD's references held, ``K x`` the
    PD on the measured hub angle and rate): it steps where the rows and the references do, by ``u_c,k - u_c,k-1``, and
    moves with the state in between. Its peak is taken at the rows and, after the table (``u_c = after_c``, the
    references at rest), through ``window`` (exactly, as the tip's: :func:`free_peaks`).

    Parameters
    ----------
    A_c, B : ndarray
        The loop's matrix and the link's input vector.
    gains : (float, float)
        ``(k_P, k_D)``.
    x0 : ndarray
        The link's state where the table starts.
    u_c : ndarray
        The loop's held inputs (:func:`closed_loop`).
    before_c, after_c : float
        The loop's input before the table (the link at rest on its references: the motor's torque there is the table's
        input before it) and after it.
    period, window : float
        The controller's period and the window after the table (s).

    Returns
    -------
    tuple of float
        The motor's largest ``|tau|`` and its largest step between rows (N m).
    """
    n1 = A_c.shape[0] // 2
    K = np.zeros(A_c.shape[0])
    K[0], K[n1] = (float(g) for g in gains)
    Kx, x_end = held_run(A_c, B, K, np.asarray(x0, dtype=float), u_c, period)
    rows = u_c - Kx[:-1]
    after = float(_free_peaks(A_c, np.asarray(B, dtype=float), K, x_end[None, :], after_c, after_c, window)[0])
    return max(float(np.abs(rows).max()), float(abs(after_c - Kx[-1])), after), table_rate(u_c, before_c, after_c)


def rest_angle(C: ArrayLike, y: float) -> float:
    """The joint angle of a link at rest with its output on ``y``.

    ``y / x_out``, the deflections zero (rad).

    Parameters
    ----------
    C : array_like
        The link's output row (its first entry the output point's distance ``x_out``).
    y : float
        The output (m).
    """
    first = float(np.asarray(C, dtype=float).reshape(-1)[0])
    return y / first if first else 0.0


def rest_state(A: FloatArray, B: FloatArray, C: FloatArray, y: float, link: bool) -> FloatArray:
    """A plant at rest with its output on ``y``.

    A link: the joint turned (:func:`rest_angle`), the deflections and rates zero; a system: its equilibrium
    ``x = -A^-1 B u`` with ``C x = y``.

    Parameters
    ----------
    A, B, C : ndarray
        The plant (``B`` and ``C`` vectors).
    y : float
        The output.
    link : bool
        Whether it is a link.
    """
    x = np.zeros(np.shape(A)[0])
    if y == 0.0:
        return x
    if link:
        x[0] = rest_angle(C, y)
        return x
    direction = -np.linalg.solve(A, np.asarray(B, dtype=float).reshape(-1))
    return direction * (y / float(np.asarray(C, dtype=float).reshape(-1) @ direction))


def closed_loop(A: FloatArray, B: FloatArray, gains: tuple[float, float], u: FloatArray, theta_d: FloatArray,
                thetadot_d: FloatArray, after: float, theta_after: float, thetadot_after: float
                ) -> tuple[FloatArray, FloatArray, float]:
    """A link's plant with its joint PD closed, driven by a held table.

    The paper's Fig. 1 and Eq. (40): the input is ``tau_k + k_P (theta_d,k - theta) + k_D (thetadot_d,k - thetadot)``, the
    references held with the torque over each period (as the exported C and the simulation hold them), so that the loop
    is ``x' = (A - B K) x + B (tau_k + k_P theta_d,k + k_D thetadot_d,k)`` with ``K = k_P e_theta + k_D e_thetadot``.

    Parameters
    ----------
    A, B : ndarray
        The link's model in its coordinates ``[theta, delta, thetadot, deltadot]`` (``B`` a vector).
    gains : (float, float)
        ``(k_P, k_D)``.
    u, theta_d, thetadot_d : ndarray
        The held rows.
    after, theta_after, thetadot_after : float
        What is held after the table (the references: the rest on ``y_d(t_f)``, :func:`rest_angle`, and 0).

    Returns
    -------
    tuple
        The loop's matrix, its held input rows and the input held after the table.
    """
    kp, kd = (float(g) for g in gains)
    n1 = A.shape[0] // 2
    K = np.zeros(A.shape[0])
    K[0], K[n1] = kp, kd
    return (np.asarray(A, dtype=float) - np.outer(np.asarray(B, dtype=float).reshape(-1), K), u + kp * theta_d + kd * thetadot_d,
            float(after + kp * theta_after + kd * thetadot_after))


def judge(
    form: NormalForm, trajectory: Trajectory, signals: PiecewiseChebyshev, bounds: Criteria, *, x0: ArrayLike, x_end: ArrayLike,
    feed_start: float, feed_end: float, reference: Callable[[FloatArray], FloatArray], peak: float, error: float, move: float,
    larger: tuple[int, dict[str, Any]] | None = None, at_rest: bool = True,
) -> Acceptance:
    """What reaches the link from any feedforward (module docstring).

    What reaches the link from any feedforward (module docstring): its signals over ``[feed_start, feed_end]``.

    Parameters
    ----------
    form : NormalForm
        The model's matrices.
    trajectory : Trajectory
        The desired trajectory.
    signals : PiecewiseChebyshev
        The signals fed forward (the input first).
    bounds : Criteria
        The period and hold of the held table, the after-end window.
    x0, x_end : array_like
        The plant's state where the feedforward starts and where it ends.
    feed_start, feed_end : float
        Its span (s; a stable inversion's pre-actuation starts before ``t0``).
    reference : callable
        ``y~(t)`` (the output the feedforward redefines; ``y_d`` for stable inversion).
    peak, error, move : float
        The result's peak input, ``max |y~ - y_d|`` and move.
    larger : (int, dict), optional
        The model with more modes (:func:`modelgen.linear.linear_model`) for the truncation checks.
    at_rest : bool
        Whether the plant is at rest where the feedforward starts (the larger model starts there).
    """
    asked = demand(form, trajectory, bounds.period)
    t0, tf = trajectory.t0, trajectory.tf

    def desired(t: FloatArray) -> FloatArray:
        return trajectory.derivative(np.clip(t, t0, tf), 0)

    y_final, hold = asked.y_final, asked.hold_final
    window = window_length(form, bounds.window)
    after = after_end(form, x_end, feed_end, y_final, hold, window)
    larger = larger if at_rest else None
    trunc = truncation(larger[1], signals, desired, y_final, feed_end, window, larger[0]) if larger is not None else None
    outside = (outside_values(signals, feed_start, asked.hold_start), outside_values(signals, feed_end, hold))
    held = sampled(form, signals, x0, feed_start, feed_end, bounds.period, bounds.hold, outside, reference, desired, move,
                   y_final=y_final, window=window, larger=larger, rigid_rate=asked.rigid_rate, from_rest=at_rest,
                   loop=bounds.loop if form.inertia is not None else None,
                   motor=bounds.max_torque is not None or bounds.max_torque_rate is not None)
    return Acceptance(asked.rigid_torque, float(peak), float(error), float(move), after, trunc, held, form.inertia is not None)


def summary_keys(acceptance: Acceptance) -> tuple[dict[str, Any], dict[str, Any]]:
    """What a summary holds of the acceptance.

    What a summary holds of the acceptance: its top-level keys (``rigid_torque``, ``torque_ratio``, ``rigid_torque_rate``,
    ``torque_rate_ratio``, ``sampled``) and its ``verification`` entries (``after_end``, ``truncation``).

    Parameters
    ----------
    acceptance : Acceptance
        A judged feedforward's acceptance.
    """
    held = acceptance.sampled
    top = {"rigid_torque": acceptance.rigid_torque, "torque_ratio": acceptance.torque_ratio,
           "rigid_torque_rate": None if held is None else held.rigid_torque_rate,
           "torque_rate_ratio": None if held is None else held.torque_rate_ratio,
           "sampled": None if held is None else held.as_dict()}
    verification = {"after_end": acceptance.after_end.as_dict(),
                    "truncation": None if acceptance.truncation is None else acceptance.truncation.as_dict()}
    return top, verification


def larger_model(model: Any, extra: int) -> tuple[int, dict[str, Any]] | None:
    """A link's model with ``extra`` more modes, for truncation checks.

    A link's model with ``extra`` more modes (:func:`modelgen.linear.linear_model`, no code generated; kept), for the
    truncation checks; ``None`` for a generic system, or when no check is asked for (``extra = 0``).

    Parameters
    ----------
    model : Any
        A link's model, or a generic system.
    extra : int
        How many modes to add.
    """
    from modelgen.model import Model

    if not isinstance(model, Model) or extra <= 0:
        return None
    from modelgen.geometry import MAX_MODES

    n = min(model.n + extra, MAX_MODES)
    return (n, _linear_model(model.geometry, n, float(model.output_at))) if n > model.n else None


@functools.lru_cache(maxsize=16)
def _linear_model(geometry: Any, n: int, output_at: float) -> dict[str, Any]:
    """:func:`modelgen.linear.linear_model`, kept for the geometries a session judges again (about 5 ms each)."""
    from modelgen.linear import linear_model

    return linear_model(geometry, n, output_at)


def __getattr__(name: str) -> Any:
    """``Bounds``, this module's former name of :class:`Criteria`, with a DeprecationWarning (the name goes with the next
    release; ``inversion.Bounds`` is the problem's bounds, :class:`inversion.problem.Bounds`)."""
    if name == "Bounds":
        import warnings

        warnings.warn("inversion.acceptance.Bounds is inversion.acceptance.Criteria now (inversion.Bounds is the problem's "
                      "bounds); the old name goes with the next release", DeprecationWarning, stacklevel=2)
        return Criteria
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

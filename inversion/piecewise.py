"""Piece-wise causal inversion by output redefinition (section 5 of the paper).

:func:`invert` divides ``[t0, tf]`` into segments, redefines the desired acceleration in
each by a sum of stable exponentials (:mod:`inversion.ssef`), carries the internal state
across the joints, and returns the bounded, continuous, causal feedforward torque
``tau_l = (yddot~ - C A^2 X) / CAB`` (Eq. (12)) with everything needed to use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from modelgen.model import Model

from .errors import InversionError, SettingsError
from .internal import ModalInternalDynamics
from .output import write_columns, write_json
from .ssef import SegmentSolution, Solver, solve_segment
from .trajectory import Trajectory

__all__ = ["invert", "InversionResult", "CSV_COLUMNS", "MAX_SAMPLES"]

FloatArray = NDArray[np.float64]

#: Columns of ``inversion.csv`` (a contract relied on by scripts).
CSV_COLUMNS = ("t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "tau", "theta_d", "thetadot_d")
#: Largest number of samples one inversion may produce.
MAX_SAMPLES = 50_000_000


@dataclass(frozen=True)
class InversionResult:
    """The redefined trajectory and the causal inverse torque.

    Attributes
    ----------
    t : ndarray
        Sample times (s), ``t0 .. tf`` at ``rate``.
    y_d : ndarray
        Desired tip displacement (m).
    y, ydot, yddot : ndarray
        Redefined tip displacement, velocity, acceleration ``y~`` (Eq. (29) integrated).
    X : ndarray, shape (N, 2(n+1))
        Redefined state ``[theta, delta, thetadot, deltadot]``.
    tau : ndarray
        Feedforward torque ``tau_l`` (N m), Eq. (12).
    theta_d, thetadot_d : ndarray
        Joint angle and rate of ``X``, the references of the PD law (Eq. (40)).
    segments : list of SegmentSolution
        Exponents, coefficients, residual and condition number of each segment.
    summary : dict
        Key figures (see :func:`invert`).
    model : Model
        The model inverted.
    trajectory : Trajectory
        The desired trajectory.
    modal : ModalInternalDynamics
        The diagonalised internal dynamics used.
    """

    t: FloatArray
    y_d: FloatArray
    y: FloatArray
    ydot: FloatArray
    yddot: FloatArray
    X: FloatArray
    tau: FloatArray
    theta_d: FloatArray
    thetadot_d: FloatArray
    segments: list[SegmentSolution]
    summary: dict[str, Any]
    model: Model = field(repr=False)
    trajectory: Trajectory = field(repr=False)
    modal: ModalInternalDynamics = field(repr=False)

    @property
    def joints(self) -> FloatArray:
        """Segment boundaries ``t_0 .. t_K`` (s)."""
        return np.array([s.t_start for s in self.segments] + [self.segments[-1].t_end])

    def evaluate(self, t: ArrayLike) -> dict[str, FloatArray]:
        """The redefined quantities at arbitrary times in ``[t0, tf]`` (closed form).

        Returns
        -------
        dict
            ``y, ydot, yddot, X, tau`` (``X`` of shape ``(N, 2(n+1))``).
        """
        return _evaluate(self.segments, self.modal, self.model, np.atleast_1d(np.asarray(t, dtype=float)))

    def write_csv(self, path: str | Path) -> None:
        """Write ``inversion.csv`` with the columns :data:`CSV_COLUMNS`."""
        write_columns(path, CSV_COLUMNS, [self.t, self.y_d, self.y, self.ydot, self.yddot, self.tau, self.theta_d, self.thetadot_d])

    def write_summary(self, path: str | Path) -> None:
        """Write ``summary.json``."""
        write_json(path, self.summary)


def _evaluate(
    segments: Sequence[SegmentSolution], modal: ModalInternalDynamics, model: Model, t: FloatArray
) -> dict[str, FloatArray]:
    """Closed-form evaluation over the segments containing ``t`` (last segment closed)."""
    starts = np.array([s.t_start for s in segments])
    idx = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(segments) - 1)
    n2 = 2 * model.n
    y = np.empty(t.size)
    ydot = np.empty(t.size)
    yddot = np.empty(t.size)
    XI = np.empty((t.size, n2))
    for k, seg in enumerate(segments):
        sel = idx == k
        if not np.any(sel):
            continue
        local = np.clip(t[sel] - seg.t_start, 0.0, seg.duration)
        y[sel], ydot[sel], yddot[sel], XI[sel], _ = seg.evaluate_state(local, modal)
    X = np.column_stack([y, ydot, XI]) @ model.Tinv.T
    tau = model.functions.inverse_torque(model.parameters, X, yddot)
    return {"y": y, "ydot": ydot, "yddot": yddot, "X": X, "tau": tau}


def _amplification(solutions: Sequence[SegmentSolution]) -> tuple[float, float]:
    """Largest (Frobenius) norm of the partial products of the propagation maps, and the largest spectral radius."""
    if solutions[0].propagation.size == 0:
        return 1.0, 0.0
    product = np.eye(solutions[0].propagation.shape[0])
    amplification = 1.0
    radius = 0.0
    for seg in solutions:
        product = seg.propagation @ product
        amplification = max(amplification, float(np.sqrt(np.sum(product * product))))
        radius = max(radius, float(np.abs(np.linalg.eigvals(seg.propagation)).max()))
    return amplification, radius


def _validate_cdec(cdec: Any) -> tuple[float, float]:
    accepted = "two numbers (Cdec_f, Cdec_s) with 0 < Cdec_f < Cdec_s <= 1"
    try:
        fast, slow = (float(v) for v in cdec)
    except (TypeError, ValueError):
        raise SettingsError("cdec", cdec, accepted) from None
    if not (math.isfinite(fast) and math.isfinite(slow) and 0 < fast < slow <= 1):
        raise SettingsError("cdec", cdec, accepted)
    return fast, slow


def _validate_segments(segments: int | Sequence[float], trajectory: Trajectory) -> FloatArray:
    t0, tf = trajectory.t0, trajectory.tf
    if isinstance(segments, bool):
        raise SettingsError("segments", segments, "an integer >= 1 or a list of boundaries")
    if isinstance(segments, (int, np.integer)):
        if segments < 1 or segments > 100_000:
            raise SettingsError("segments", segments, "an integer in 1..100000")
        return np.linspace(t0, tf, int(segments) + 1)
    try:
        bounds = np.asarray(segments, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise SettingsError("segments", segments, "an integer >= 1 or a list of boundaries") from None
    ok = (
        bounds.size >= 2
        and np.all(np.isfinite(bounds))
        and np.all(np.diff(bounds) > 0)
        and math.isclose(bounds[0], t0, abs_tol=1e-12 * max(1.0, abs(t0)))
        and math.isclose(bounds[-1], tf, rel_tol=1e-12, abs_tol=1e-12)
    )
    if not ok:
        raise SettingsError(
            "segments", list(bounds), f"strictly increasing finite boundaries from t0 = {t0:g} to tf = {tf:g}"
        )
    bounds[0], bounds[-1] = t0, tf
    return bounds


def invert(
    model: Model,
    trajectory: Trajectory,
    segments: int | Sequence[float] = 5,
    h: int = 2,
    cdec: tuple[float, float] = (1e-4, 1.0),
    rate: float = 1000.0,
    eps: float = 0.0,
    initial_internal_state: ArrayLike | None = None,
    solver: Solver = "lu",
    tol: float = 1e-8,
    max_amplification: float = 1e3,
) -> InversionResult:
    """Causal inverse torque of the linear model for a desired tip trajectory.

    Parameters
    ----------
    model : Model
        A loaded model (:func:`modelgen.load`); its compiled ``inverse_torque`` gives Eq. (12).
    trajectory : Trajectory
        Desired tip trajectory on ``[t0, tf]``.
    segments : int or sequence of float
        Number of equal segments, or their boundaries ``[t0, ..., tf]`` (Eq. (28)).
    h : int
        Order of smooth joining, Eq. (30): ``yddot~`` matches ``yddot_d`` and its first
        ``h`` derivatives at every joint (``h >= 1`` gives a continuously differentiable
        ``yddot~``).
    cdec : (float, float)
        ``(Cdec_f, Cdec_s)``: fastest and slowest decay of the exponentials over a
        segment, Eq. (35); ``0 < Cdec_f < Cdec_s <= 1``.
    rate : float
        Sampling rate of the returned series (Hz).
    eps : float
        Zeros with ``Re >= -eps`` are treated as unstable (purely imaginary ones always are).
    initial_internal_state : array_like, optional
        ``X_I(t0) = [delta; deltadot]`` (default: rest).
    solver : {"lu", "lstsq"}
        Linear solver of the segment systems.
    tol : float
        Largest accepted relative constraint residual of a segment system: the joining
        and continuity conditions must hold to this fraction of their size (the paper's
        cases reach ~1e-13; ill-posed exponents give 1e-3 and more).
    max_amplification : float
        Largest accepted growth of the unstable internal state carried across the joints
        (the Frobenius norm of the product of the segments' propagation maps). Short segments make
        each map expand (paper-exp: spectral radius 1.5 with 20 segments) and the
        redefinition then diverges geometrically while every segment system is solved
        exactly (paper-exp with 25 segments: 595 m off the desired trajectory); growth
        beyond this bound is reported as a failure.

    Returns
    -------
    InversionResult
        Its ``summary`` holds ``max_redefinition_error`` (m), ``peak_torque`` (N m),
        ``max_torque_jump`` (N m, over the joints), ``max_constraint_residual``,
        ``max_condition_number``, ``amplification``, ``max_spectral_radius``, ``zeros``,
        ``n_unstable``, ``r``, ``settings`` and the segments' exponents and coefficients.

    Raises
    ------
    SettingsError
        For settings out of range (named in the message with the accepted range).
    InversionError
        When a segment system cannot be solved to ``tol`` (with residual and condition
        number), or the unstable state grows beyond ``max_amplification`` across the
        segments (with the growth and the spectral radius).

    References
    ----------
    The paper, Eqs. (12), (14)-(17), (28)-(36); METHOD.md section 2.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import invert, smoothstep
    >>> result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), segments=5, h=2, cdec=(1e-4, 1.0))
    >>> round(result.summary["max_redefinition_error"], 5)
    0.00573
    """
    if isinstance(h, bool) or not isinstance(h, (int, np.integer)) or h < 1:
        raise SettingsError("h", h, "an integer >= 1")
    if trajectory.max_derivative is not None and h + 2 > trajectory.max_derivative:
        raise SettingsError(
            "h", h, f"an integer in 1..{trajectory.max_derivative - 2}: the trajectory {trajectory.name} has "
            f"derivatives up to order {trajectory.max_derivative} and h needs order h + 2"
        )
    fast, slow = _validate_cdec(cdec)
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not math.isfinite(rate) or rate <= 0:
        raise SettingsError("rate", rate, "a finite number > 0 (Hz)")
    if solver not in ("lu", "lstsq"):
        raise SettingsError("solver", solver, "'lu' or 'lstsq'")
    if not isinstance(tol, (int, float)) or not 0 < tol < 1:
        raise SettingsError("tol", tol, "a number in (0, 1)")
    if not isinstance(max_amplification, (int, float)) or not max_amplification >= 1:
        raise SettingsError("max_amplification", max_amplification, "a number >= 1")
    bounds = _validate_segments(segments, trajectory)
    count = int(math.floor(trajectory.duration * rate + 1e-9)) + 1
    if count > MAX_SAMPLES:
        raise SettingsError("rate", rate, f"at most {MAX_SAMPLES / trajectory.duration:.4g} Hz for this trajectory ({MAX_SAMPLES} samples)")
    if not isinstance(eps, (int, float)) or isinstance(eps, bool) or not math.isfinite(eps) or eps < 0:
        raise SettingsError("eps", eps, "a finite number >= 0 (1/s)")
    modal = ModalInternalDynamics.of_model(model, eps)
    n2 = 2 * model.n
    if initial_internal_state is None:
        XI0 = np.zeros(n2)
    else:
        XI0 = np.asarray(initial_internal_state, dtype=float).reshape(-1)
        if XI0.size != n2 or not np.all(np.isfinite(XI0)):
            raise SettingsError("initial_internal_state", initial_internal_state, f"{n2} finite numbers [delta; deltadot]")

    # targets at the joints: one-sided limits inside each segment
    targets_plus = trajectory.derivatives(bounds[:-1], range(2, h + 3), "+")
    targets_minus = trajectory.derivatives(bounds[1:], range(2, h + 3), "-")

    t = trajectory.t0 + np.arange(count) / rate
    if trajectory.tf - t[-1] > 1e-9 / rate:
        t = np.append(t, trajectory.tf)
    # samples of segment k: t_k <= t < t_{k+1} (the last segment closed)
    owner = np.clip(np.searchsorted(bounds, t, side="right") - 1, 0, bounds.size - 2)

    z = modal.to_modal(XI0)
    y0, ydot0 = (float(v) for v in trajectory.derivatives([bounds[0]], range(2), "+")[0])
    solutions: list[SegmentSolution] = []
    parts: list[tuple[FloatArray, FloatArray, FloatArray, FloatArray]] = []
    joint_acc: list[list[float]] = []  # yddot~ on the left and on the right of each interior joint
    for k in range(bounds.size - 1):
        T = float(bounds[k + 1] - bounds[k])
        seg = solve_segment(k, float(bounds[k]), T, targets_plus[k], targets_minus[k], y0, ydot0, z, modal, (fast, slow), solver, tol)
        solutions.append(seg)
        if joint_acc:
            joint_acc[-1].append(float(seg.c.sum()))
        local = np.append(t[owner == k] - bounds[k], T)  # the samples, and the end of the segment
        yk, ydk, yddk, XIk, z = seg.evaluate_state(local, modal)  # z: carried to the next segment
        parts.append((yk[:-1], ydk[:-1], yddk[:-1], XIk[:-1]))
        y0, ydot0 = float(yk[-1]), float(ydk[-1])
        if k < bounds.size - 2:
            joint_acc.append([float(yddk[-1])])

    amplification, radius = _amplification(solutions)
    if amplification > max_amplification:
        raise InversionError(
            f"the redefinition diverges: the unstable internal state carried across the {len(solutions)} segments grows "
            f"by {amplification:.3g} (> {max_amplification:g}; largest spectral radius of a segment's propagation map "
            f"{radius:.3g}); use fewer (longer) segments or other cdec",
        )

    y = np.concatenate([p[0] for p in parts])
    ydot = np.concatenate([p[1] for p in parts])
    yddot = np.concatenate([p[2] for p in parts])
    X = np.column_stack([y, ydot, np.concatenate([p[3] for p in parts])]) @ model.Tinv.T
    tau = model.functions.inverse_torque(model.parameters, X, yddot)  # Eq. (12), one batch
    y_d = trajectory.derivative(t, 0)

    # torque jump at every interior joint: the state X is carried across unchanged, so by
    # Eq. (12) the jump is that of yddot~ divided by CAB
    acc = np.array(joint_acc).reshape(-1, 2)
    jumps = np.abs(acc[:, 0] - acc[:, 1]) / abs(model.CAB)
    n1 = model.n + 1
    r = 2 * (h + 1) + len(modal.rows)
    summary = {
        "model": model.name,
        "modes": model.n,
        "mode_shapes": model.mode_family,
        "trajectory": trajectory.name,
        "max_redefinition_error": float(np.abs(y - y_d).max()),
        "peak_torque": float(np.abs(tau).max()),
        "max_torque_jump": float(jumps.max(initial=0.0)),
        "max_constraint_residual": max(s.residual for s in solutions),
        "max_condition_number": max(s.condition for s in solutions),
        "amplification": amplification,
        "max_spectral_radius": radius,
        "final_redefined_output": float(y[-1]),
        "final_desired_output": float(y_d[-1]),
        "final_redefined_velocity": float(ydot[-1]),
        "torque_at_start": float(tau[0]),
        "torque_at_end": float(tau[-1]),
        "zeros": [[float(v.real), float(v.imag)] for v in model.zeros],
        "n_unstable": modal.n_unstable,
        "r": r,
        "samples": int(t.size),
        "settings": {
            "segments": [float(b) for b in bounds],
            "h": int(h),
            "cdec": [fast, slow],
            "rate": float(rate),
            "eps": float(eps),
            "solver": solver,
            "tol": float(tol),
            "initial_internal_state": XI0.tolist(),
        },
        "segments": [
            {
                "t_start": s.t_start,
                "t_end": s.t_end,
                "exponents": s.mu.tolist(),
                "coefficients": s.c.tolist(),
                "residual": s.residual,
                "condition_number": s.condition,
            }
            for s in solutions
        ],
    }
    return InversionResult(
        t=t,
        y_d=y_d,
        y=y,
        ydot=ydot,
        yddot=yddot,
        X=X,
        tau=tau,
        theta_d=X[:, 0],
        thetadot_d=X[:, n1],
        segments=solutions,
        summary=summary,
        model=model,
        trajectory=trajectory,
        modal=modal,
    )

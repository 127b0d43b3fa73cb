"""Input shaping (Singer & Seering 1990): the rigid joint reference convolved with impulses at the flexible modes.

The method engineers pick first for residual vibration. For a mode of damped frequency
``omega_d`` and damping ratio ``zeta``, with ``K = exp(-zeta pi / sqrt(1 - zeta^2))`` and the
damped half period ``T_h = pi / omega_d``:

* ZV (zero vibration): impulses ``1/(1+K), K/(1+K)`` at ``0, T_h``;
* ZVD (zero vibration and derivative): ``1, 2K, K^2`` over ``(1+K)^2`` at ``0, T_h, 2 T_h``
  (robust to an error in the frequency, twice as long).

Two modes: the two shapers convolved. The rigid joint reference ``theta_r = y_d / x_out`` is
shaped, ``theta_s(t) = sum_i A_i theta_r(t - t_i)`` (the move lasts the shaper's duration
longer), and driven by the joint PD of the closed loop (:mod:`modelgen.joint_pd`'s rule) with
the rigid body's torque along it, ``J thetaddot_s + b thetadot_s`` (``J = M[0, 0]`` and the
joint's viscous damping ``b``: the computed torque of a rigid link, which spares the PD the lag
it would otherwise have)::

    u = J thetaddot_s + b thetadot_s + k_P (theta_s - theta) + k_D (thetadot_s - thetadot)

The modes shaped for are those that ring in that loop: its oscillating poles with a damping ratio
below :data:`RINGING` (a pole the PD damps harder hardly rings -- the rigid-body pair at the
rule's critically damped gains among them; the lowest one is taken when none rings). Input shaping aims at the vibration left after the move,
not at the tip during it: the shaped reference lags the desired one by about the shaper's
duration, and nothing shapes the deflection during the move.

:func:`shaped_inversion` returns it as any other result, in the closed loop's two-degree-of-
freedom form: the torque ``tau`` the PD applies to the nominal linear plant, and the nominal
joint angle and rate as the references -- then ``tau + k_P (theta_d - theta) + k_D (thetadot_d
- thetadot)`` equals the PD on the shaped reference on *any* plant (the nominal terms cancel),
which is what the closed loop (:mod:`simulation`) and the acceptance run. The nominal closed
loop is exact: within each interval between breakpoints the shaped reference is a polynomial,
whose particular response is a polynomial and whose homogeneous one is ``e^{A_cl s}``
(diagonalised); the span lasts until the rigid-body loop has settled (``(1 + w s) e^{-w s}``
below 1e-9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, ClassVar, Mapping

import numpy as np
from numpy.typing import NDArray

from modelgen.joint_pd import rule_gains
from modelgen.model import Model

from ..acceptance import Criteria, judge, larger_model, summary_keys
from ..config import default, tip_bound
from ..errors import InversionError, SettingsError
from ..lti.system import NormalForm
from ..options import InversionMethod, register
from ..problem import Problem
from ..result import InversionResult, SummaryFigures, summarize
from ..signals.chebyshev import LINK_SIGNALS, TOLERANCE, PiecewiseChebyshev, fit_chebyshev
from ..signals.trajectory import PolynomialTrajectory, Trajectory

__all__ = ["ZV", "ZVD", "shaper", "convolve", "closed_loop_modes", "shaped_inversion", "SHAPERS", "RINGING"]

FloatArray = NDArray[np.float64]
#: The shapers.
SHAPERS = ("zv", "zvd")
#: Modes of the joint PD's loop with a damping ratio at or above this do not ring (an overshoot below 16 %): not shaped for.
RINGING = 0.5
#: The span lasts until the rigid-body loop's error falls below this fraction.
_SETTLED = 1e-9


def shaper(kind: str, frequency: float, damping: float = 0.0) -> tuple[FloatArray, FloatArray]:
    """A ZV or ZVD shaper's impulses for a mode (module docstring).

    Parameters
    ----------
    kind : {"zv", "zvd"}
    frequency : float
        The mode's undamped natural frequency ``omega`` (rad/s).
    damping : float
        Its damping ratio ``zeta`` in ``[0, 1)``.

    Examples
    --------
    >>> a, t = shaper("zv", 2 * math.pi, 0.0)  # 1 Hz, undamped: half and half, half a period apart
    >>> a.tolist(), t.round(12).tolist()
    ([0.5, 0.5], [0.0, 0.5])
    """
    if kind not in SHAPERS:
        raise SettingsError("method", kind, "'zv' or 'zvd' (input shaping)")
    if not (math.isfinite(frequency) and frequency > 0 and 0 <= damping < 1):
        raise SettingsError("shaped mode", (frequency, damping), "a frequency > 0 (rad/s) and a damping ratio in [0, 1)")
    root = math.sqrt(1 - damping**2)
    K = math.exp(-damping * math.pi / root)
    half = math.pi / (frequency * root)
    if kind == "zv":
        return np.array([1.0, K]) / (1 + K), np.array([0.0, half])
    return np.array([1.0, 2 * K, K * K]) / (1 + K) ** 2, np.array([0.0, half, 2 * half])


def convolve(first: tuple[FloatArray, FloatArray], second: tuple[FloatArray, FloatArray]) -> tuple[FloatArray, FloatArray]:
    """Two shapers in series.

    Two shapers in series: every pair of impulses, amplitudes multiplied and times added (equal times merged).

    Parameters
    ----------
    first : tuple[FloatArray, FloatArray]
        A shaper's ``(amplitudes, times)``.
    second : tuple[FloatArray, FloatArray]
        Another shaper's.
    """
    amplitudes = np.outer(first[0], second[0]).ravel()
    times = np.add.outer(first[1], second[1]).ravel()
    order = np.argsort(times, kind="stable")
    times, amplitudes = times[order], amplitudes[order]
    merged_t, merged_a = [times[0]], [amplitudes[0]]
    for t, a in zip(times[1:], amplitudes[1:]):
        if abs(t - merged_t[-1]) <= 1e-12 * max(abs(t), 1.0):
            merged_a[-1] += a
        else:
            merged_t.append(t)
            merged_a.append(a)
    return np.asarray(merged_a), np.asarray(merged_t)


def closed_loop_modes(form: NormalForm, kp: float, kd: float, count: int) -> list[tuple[float, float]]:
    """The slowest oscillating modes of the joint PD's loop.

    The ``count`` slowest oscillating modes of the plant in the joint PD's loop: ``(omega, zeta)`` of its poles with a
    positive imaginary part, by frequency (which of them ring is :func:`shaped_inversion`'s choice, by :data:`RINGING`).

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    kp : float
        The joint PD's proportional gain.
    kd : float
        Its derivative gain.
    count : int
        How many modes.
    """
    poles = sorted((p for p in np.linalg.eigvals(_closed_loop(form, kp, kd)) if p.imag > 0), key=abs)
    return [(float(abs(p)), float(-p.real / abs(p))) for p in poles[:count]]


def _closed_loop(form: NormalForm, kp: float, kd: float) -> FloatArray:
    """``A - B K`` of the joint PD, ``K = k_P e_theta + k_D e_thetadot``."""
    n1 = form.n_states // 2
    gain = np.zeros(form.n_states)
    gain[0], gain[n1] = kp, kd
    return np.asarray(form.A - np.outer(form.B, gain))


def shaped_inversion(
    model: Any,
    trajectory: Trajectory,
    kind: str = "zv",
    *,
    modes: int | None = None,
    gains: tuple[float, float] | None = None,
    rate: float | None = None,
    bounds: Criteria | None = None,
) -> InversionResult:
    """The shaped rigid reference driven by the joint PD, as a result.

    The shaped rigid joint reference driven by the joint PD (module docstring), as a result.

    Parameters
    ----------
    model : Model
        A link (a generic system has no joint to shape a reference for: refused).
    trajectory : PolynomialTrajectory
        The desired tip trajectory (piecewise polynomial: the closed loop is exact on it).
    kind : {"zv", "zvd"}
        The shaper.
    modes : int, optional
        How many flexible modes are shaped for: the lowest ringing ones of the joint PD's loop
        (module docstring; default two, or as many as ring, at least one).
    gains : (float, float), optional
        ``(k_P, k_D)`` (default :func:`modelgen.joint_pd.rule_gains`).
    rate : float, optional
        Sampling rate of the result's samples (Hz).
    bounds : Criteria, optional
        What the acceptance judges it with.

    Raises
    ------
    SettingsError
        For a generic system, a trajectory that is not piecewise polynomial, or values out of range.
    InversionError
        When the tip strays beyond ``bounds.max_error`` from ``y_d`` (default the quality gate,
        :data:`inversion.config.DEFAULTS`): the shaper's delay and the unshaped deflection
        during the move, with the figures.
    """
    if not isinstance(model, Model):
        raise SettingsError("method", kind, "a link model for input shaping (it shapes the joint's reference)")
    if not isinstance(trajectory, PolynomialTrajectory):
        raise SettingsError("trajectory", trajectory.name, "a piecewise polynomial trajectory for input shaping (smoothstep, the "
                            "experiment's, a CSV spline)")
    rate = default("rate", rate)
    form = NormalForm.of_model(model)
    J = float(model.M[0, 0])
    kp, kd = rule_gains(J, 2 * math.pi * float(model.natural_frequencies_hz[0])) if gains is None else gains
    available = closed_loop_modes(form, kp, kd, model.n)
    if not available:
        raise SettingsError("method", kind, "a link whose joint PD loop has an oscillating flexible mode to shape for")
    ringing = [mode for mode in available if mode[1] < RINGING] or available[:1]
    count = min(2, len(ringing)) if modes is None else modes
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= len(ringing):
        raise SettingsError("modes", modes, f"an integer in 1..{len(ringing)} (the ringing flexible modes of the joint PD's loop)")
    shaped = ringing[:count]
    impulses = shaper(kind, *shaped[0])
    for omega, zeta in shaped[1:]:
        impulses = convolve(impulses, shaper(kind, omega, zeta))
    loop = _Loop(form, trajectory, impulses, (J, form.joint_damping, kp, kd), float(model.output_at))
    unshaped = _Loop(form, trajectory, (np.ones(1), np.zeros(1)), (J, form.joint_damping, kp, kd), float(model.output_at))
    return _result(model, form, trajectory, loop, kind, shaped, rate, bounds, residual_vibration(unshaped, rate, shaped))


def residual_vibration(loop: "_Loop", rate: float, shaped: list[tuple[float, float]]) -> tuple[float, float]:
    """What rings once the shaped reference has ended (``t >= t_f + `` the shaper's duration, sampled at ``rate`` until the
    loop has settled): the largest tip deflection ``|y - x_out theta|`` of the nominal loop, and the largest part of the tip
    the shaped modes' transients carry (``2 Re(C v_j (q_j - q_j,rest))`` for each shaped pole ``lambda_j``, eigenvector
    ``v_j``, about where the input at rest holds ``q_j``) -- the residual
    vibration input shaping aims at, zero for an exact shaper; the rest of the deflection is the loop's non-ringing modes
    settling."""
    start = loop.trajectory.tf + float(loop.delays[-1])
    t = np.arange(start, loop.end, 1.0 / rate)
    k = np.clip(np.searchsorted(loop.bounds, t, side="right") - 1, 0, loop.bounds.size - 2)
    q = loop._modal(loop.starts[k], loop.chains[k], t - loop.bounds[k])
    X = np.real(q @ loop.V.T)
    deflection = float(np.abs(X @ loop.form.C - loop.x_out * X[:, 0]).max(initial=0.0))
    poles = [int(np.argmin(np.abs(loop.poles - complex(-z * w, w * math.sqrt(1 - z * z))))) for w, z in shaped]
    rest = -loop.beta[poles] * loop.chains[-1, 0] / loop.poles[poles]  # where the constant input at rest holds them
    ringing = 2 * np.real((q[:, poles] - rest) * (loop.form.C @ loop.V[:, poles])[None, :]).sum(axis=1)
    return deflection, float(np.abs(ringing).max(initial=0.0))


class _Loop:
    """The nominal closed loop on the shaped reference, exact between the reference's breakpoints (module docstring).

    On an interval starting at ``a`` the loop's input is a polynomial ``u(a + r) = sum_m u_m r^m / m!``
    (``u_m`` its derivatives at ``a``). In the closed loop's modal coordinates ``q = V^-1 x`` each
    mode ``lambda`` then evolves as ``q(s) = e^{lambda s} q(0) + beta sum_m u_m s^(m+1) phi_(m+1)(lambda s)``
    (``beta = V^-1 B``; the phi-functions of exponential integrators, bounded by ``1/k!`` for ``Re
    lambda <= 0``): no particular solution, whose terms ``A^-(m+1) B u_m`` grow with a slow pole and
    cancel to the state's size, and no squaring of a long interval's matrix exponential.
    """

    def __init__(self, form: NormalForm, trajectory: PolynomialTrajectory, impulses: tuple[FloatArray, FloatArray],
                 gains: tuple[float, float, float, float], output_at: float):
        self.form, self.trajectory, self.x_out = form, trajectory, output_at
        self.J, self.b, self.kp, self.kd = gains
        self.amplitudes, self.delays = impulses
        # the reference's derivatives vanish from this order on: u = J thetaddot + ... has derivatives up to degree - 1
        # (and one spare) nonzero, the chain's length
        self.degree = int(trajectory.ppoly.c.shape[0])
        self.poles, self.V = np.linalg.eig(_closed_loop(form, self.kp, self.kd))
        self.V_inv = np.linalg.inv(self.V)
        self.beta = self.V_inv @ form.B
        slowest = float(np.abs(self.poles.real).min())
        cuts = {trajectory.t0, trajectory.tf, *(b for b in trajectory.breakpoints if trajectory.t0 < b < trajectory.tf)}
        self.end = float(trajectory.tf + self.delays[-1] + _settle_time(slowest))
        self.bounds = np.array(sorted({c + d for c in cuts for d in self.delays} | {self.end}))
        self.chains = self._input_chain(self.bounds[:-1])
        self.starts = self._starts()

    def reference(self, t: FloatArray, order: int, side: str = "+") -> FloatArray:
        """``theta_s^(order)`` at ``t`` (zero beyond the pieces' degree)."""
        out = np.zeros(np.shape(t))
        if order >= self.degree:
            return out
        traj = self.trajectory
        tol = 1e-12 * max(traj.tf - traj.t0, 1.0)
        for a, d in zip(self.amplitudes, self.delays):
            local = np.asarray(t, dtype=float) - d
            # snapped onto the copy's ends where it is within rounding of them (t = t_f + d lands on t_f up to an ulp)
            local = np.where(np.abs(local - traj.t0) <= tol, traj.t0, np.where(np.abs(local - traj.tf) <= tol, traj.tf, local))
            value = traj.derivative(local, order, side)  # type: ignore[arg-type]
            # the one-sided limits at the copy's own start and end are those of the rest around it
            # (the trajectory returns the values inside the manoeuvre there)
            rest = local <= traj.t0 if side == "-" else local >= traj.tf
            if order > 0:
                value = np.where(rest, 0.0, value)
            out = out + a * value
        return out / self.x_out

    def _input_chain(self, t: FloatArray) -> FloatArray:
        """``u^(m)(t+)``, ``u = J thetaddot_s + (b + k_D) thetadot_s + k_P theta_s`` (the loop's input with the state's
        terms in ``A_cl``), ``m = 0 .. degree - 1``: shape (len(t), degree)."""
        theta = [self.reference(t, m) for m in range(self.degree + 2)]
        return np.column_stack([self.J * theta[m + 2] + (self.b + self.kd) * theta[m + 1] + self.kp * theta[m]
                                for m in range(self.degree)])

    def _modal(self, q0: NDArray[np.complex128], chain: FloatArray, s: FloatArray) -> NDArray[np.complex128]:
        """Modal states at local times ``s`` (P,) from ``q0`` (P, N) with input chains ``chain`` (P, degree): (P, N)."""
        z = s[:, None] * self.poles[None, :]
        phi = _phi(z, self.degree)  # (degree + 1, P, N)
        forced = sum(chain[:, m, None] * s[:, None] ** (m + 1) * phi[m + 1] for m in range(self.degree))
        return phi[0] * q0 + self.beta[None, :] * forced

    def _starts(self) -> NDArray[np.complex128]:
        """The modal state at the start of every interval (exact propagation from rest at ``t0``)."""
        starts = [np.zeros(self.form.n_states, dtype=complex)]
        for length, chain in zip(np.diff(self.bounds), self.chains):
            starts.append(self._modal(starts[-1][None], chain[None], np.array([length]))[0])
        return np.asarray(starts)

    def states(self, k: NDArray[np.intp], s: FloatArray) -> FloatArray:
        """The state at local times ``s`` of intervals ``k`` (one each)."""
        k = np.asarray(k)
        return np.real(self._modal(self.starts[k], self.chains[k], np.asarray(s, dtype=float)) @ self.V.T)

    def noise(self, peaks: FloatArray) -> FloatArray:
        """The rounding of :meth:`signals` relative to their ``peaks``: a hundred ``eps cond(V)`` times the
        largest term summed (``k_P theta_s`` and its kin cancel in the torque as the joint follows)."""
        theta = np.abs(self.reference(self.bounds, 0)).max()
        scale = np.array([self.kp * theta + (self.kd + self.b) * peaks[2] + peaks[0], theta, peaks[2]])
        rounding = 100 * np.finfo(float).eps * float(np.linalg.cond(self.V)) * scale / peaks
        return np.maximum(rounding, 1e3 * TOLERANCE)

    def sampled(self, t: FloatArray) -> FloatArray:
        """The state at times ``t`` (each in the interval it falls in, the last one's end included)."""
        k = np.clip(np.searchsorted(self.bounds, t, side="right") - 1, 0, self.bounds.size - 2)
        return self.states(k, t - self.bounds[k])

    def signals(self, k: NDArray[np.intp], s: FloatArray) -> FloatArray:
        """``[tau, theta, thetadot]`` of the nominal loop at local times ``s`` (shape (P, n)) of intervals ``k``: (P, 3, n)."""
        kk = np.repeat(k, s.shape[1])
        ss = np.asarray(s, dtype=float).ravel()
        X = self.states(kk, ss)
        return self.torque_and_joint(self.bounds[kk] + ss, X).reshape(3, *s.shape).transpose(1, 0, 2)

    def torque_and_joint(self, t: FloatArray, X: FloatArray) -> FloatArray:
        """``[tau, theta, thetadot]`` (shape (3, len(t))) of the nominal loop at states ``X``."""
        n1 = self.form.n_states // 2
        rate = self.reference(t, 1)
        tau = (self.J * self.reference(t, 2) + self.b * rate + self.kp * (self.reference(t, 0) - X[:, 0])
               + self.kd * (rate - X[:, n1]))
        return np.stack([tau, X[:, 0], X[:, n1]])


def _settle_time(w: float) -> float:
    """When ``(1 + w s) e^{-w s}`` falls below :data:`_SETTLED` (a double pole at ``-w``: the loop's slowest, conservatively)."""
    s = 30.0
    for _ in range(60):  # Newton on log((1 + s) e^{-s}) = log(tolerance), in units of 1/w
        f = math.log1p(s) - s - math.log(_SETTLED)
        s -= f / (1 / (1 + s) - 1)
    return s / w


def _modes_text(shaped: list[tuple[float, float]]) -> str:
    """``"24.1 rad/s, zeta 0.068"`` for each shaped mode."""
    return " and ".join(f"{w:.4g} rad/s, zeta {z:.3g}" for w, z in shaped)


def _phi(z: NDArray[np.complex128], K: int) -> NDArray[np.complex128]:
    """``phi_0 .. phi_K`` at ``z``: ``phi_0 = e^z``, ``phi_k(z) = sum_j z^j / (j + k)!`` (shape (K + 1, *z.shape)).

    By the series where ``|z| < 1`` and by ``phi_k = (phi_(k-1) - 1/(k-1)!) / z`` elsewhere (the
    recurrence divides its errors by ``|z| >= 1``: stable there).
    """
    out = np.empty((K + 1, *z.shape), dtype=complex)
    small = np.abs(z) < 1
    zs, zl = z[small], z[~small]
    for k in range(K + 1):  # the series, 30 terms: below 1/30! for |z| < 1
        out[k][small] = sum(zs**j / math.factorial(j + k) for j in range(30))
    large = np.exp(zl)
    out[0][~small] = large
    for k in range(1, K + 1):
        large = (large - 1 / math.factorial(k - 1)) / zl
        out[k][~small] = large
    return out


def _result(model: Model, form: NormalForm, trajectory: Trajectory, loop: _Loop, kind: str, shaped: list[tuple[float, float]],
            rate: float, bounds: Criteria | None, unshaped: tuple[float, float]) -> InversionResult:
    """The shaped loop as an :class:`~inversion.result.InversionResult` (the two-degree-of-freedom form of the module docstring)."""
    def evaluate(k: NDArray[np.intp], s: NDArray[Any]) -> NDArray[Any]:
        return loop.signals(np.asarray(k), np.asarray(s, dtype=float)).astype(np.longdouble)

    signals: PiecewiseChebyshev = fit_chebyshev(LINK_SIGNALS, loop.bounds, evaluate, noise=loop.noise)
    t0 = trajectory.t0
    count = int(math.floor((loop.end - t0) * rate + 1e-9)) + 1
    t = t0 + np.arange(count) / rate
    if loop.end - t[-1] > 1e-9 / rate:
        t = np.append(t, loop.end)
    X = loop.sampled(t)
    fed = dict(zip(LINK_SIGNALS, loop.torque_and_joint(t, X)))
    y = X @ form.C
    ydot = X @ (form.A.T @ form.C)
    yddot = X @ (form.A.T @ form.A.T @ form.C) + form.CAB * fed["tau"]
    y_d = trajectory.derivative(np.clip(t, trajectory.t0, trajectory.tf), 0)
    errors = np.abs(y - y_d)
    move = trajectory.move()
    gate = tip_bound(None, move, judged=False)
    bounds = Criteria(max_error=gate, period=1.0 / rate) if bounds is None else bounds
    if not errors.max() <= bounds.max_error:
        raise InversionError(f"the {kind.upper()}-shaped joint reference (for {_modes_text(shaped)}) leaves the tip "
                             f"{errors.max():.4g} m from y_d at t = {t[int(np.argmax(errors))]:.4g} s ({errors.max() / max(move, 1e-300):.3g} "
                             f"of the move; accepted {bounds.max_error:.3g} m): input shaping delays the move by "
                             f"{loop.delays[-1]:.4g} s and does not shape the deflection during it -- a larger max_error shows it "
                             "anyway, method='ssef' or 'ocp' tracks the tip")
    acceptance = judge(form, trajectory, signals, bounds, x0=X[0], x_end=X[-1], feed_start=t0, feed_end=loop.end,
                       reference=lambda s: np.interp(s, t, y), peak=float(np.abs(fed["tau"]).max()), error=float(errors.max()),
                       move=move, larger=larger_model(model, bounds.extra_modes))
    worst, peak = int(np.argmax(errors)), int(np.argmax(np.abs(fed["tau"])))
    figures = SummaryFigures(max_error=float(errors.max()), time_of_max_error=float(t[worst]), move=move, gate=bounds.max_error,
                             peak_torque=float(abs(fed["tau"][peak])), time_of_peak_torque=float(t[peak]), n_unstable=0)
    settings = {"method": kind, "rate": float(rate), "kp": loop.kp, "kd": loop.kd,
                "modes": [{"frequency": w, "damping": z} for w, z in shaped],
                "impulses": {"amplitudes": loop.amplitudes.tolist(), "times": loop.delays.tolist()}}
    top, verification = summary_keys(acceptance)
    deflection, ringing = residual_vibration(loop, rate, shaped)
    shaping = {"shaper_duration": float(loop.delays[-1]), "residual_vibration": ringing, "unshaped_residual_vibration": unshaped[1],
               "residual_deflection": deflection, "unshaped_residual_deflection": unshaped[0],
               "settle_time": float(loop.end - trajectory.tf - loop.delays[-1])}
    extra = {"method": kind, "pre_actuation_time": 0.0, "post_actuation_time": float(loop.end - trajectory.tf), **top,
             "shaping": shaping}
    summary = summarize(model, trajectory, figures, {"t": t, "y": y, "ydot": ydot, "tau": fed["tau"], "X": X}, settings,
                        verification=verification, extra=extra)
    return InversionResult(t=t, y_d=y_d, y=y, ydot=ydot, yddot=yddot, X=X, tau=fed["tau"], theta_d=fed["theta_d"],
                           thetadot_d=fed["thetadot_d"], summary=summary, model=model, trajectory=trajectory,
                           modal=form.modal(0.0), signals=signals, acceptance=acceptance)


class _Shaping(InversionMethod):
    """Input shaping (Singer & Seering) of the rigid joint reference, driven by the joint PD: aimed at the vibration after
    the move, not at the tip during it. It takes no option of its own (its impulses follow from the plant's modes)."""

    kind: ClassVar[str] = ""
    needs_zeros = False
    help = ("input shaping (Singer & Seering) of the rigid joint reference, driven by the joint PD of simulate's rule: aimed at "
            "the vibration after the move, not at the tip during it")
    series_text = "the loop's closed form re-expanded"

    def solve(self, problem: Problem, say: Callable[[str], None]) -> InversionResult:
        """The shaped reference's loop as a result (:func:`shaped_inversion`), the paper's gains for its cases.

        Parameters
        ----------
        problem : Problem
            What the user asked.
        say : callable
            The progress display.
        """
        case = problem.case
        return shaped_inversion(problem.system, problem.trajectory, self.kind, rate=problem.rate,
                                gains=None if case is None else (float(case.kp.value), float(case.kd.value)),
                                bounds=problem.criteria(problem.bound(judged=False), max_torque=None))

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        """The modes shaped for, the shaper's duration, the gains and the ringing left.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s, settings = summary, summary["settings"]
        modes = ", ".join(f"{m['frequency']:.4g} rad/s" for m in settings["modes"])
        return (f"shaped for {modes} (shaper {s['shaping']['shaper_duration']:.3g} s), joint PD k_P {settings['kp']:.3g}, "
                f"k_D {settings['kd']:.3g}; the shaped modes ring {s['shaping']['residual_vibration']:.2g} m after "
                f"(unshaped {s['shaping']['unshaped_residual_vibration']:.2g} m)")

    def c_text(self, summary: Mapping[str, Any]) -> str:
        """The C header's line.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        settings = summary["settings"]
        return (f"input shaping ({self.name.upper()}) of the rigid joint reference, joint PD k_P {settings['kp']:.6g}, "
                f"k_D {settings['kd']:.6g}")

    def report(self, summary: Mapping[str, Any]) -> list[str]:
        """The first lines of ``sflm invert``'s text.

        Parameters
        ----------
        summary : mapping
            The result's summary.
        """
        s = summary
        st, sh = s["settings"], s["shaping"]
        modes = " and ".join(f"{m['frequency']:.4g} rad/s (zeta {m['damping']:.3g})" for m in st["modes"])
        return [
            f"{s['model']}: input shaping ({st['method'].upper()}) of the rigid joint reference for {modes}, driven by the joint "
            f"PD (k_P {st['kp']:.4g}, k_D {st['kd']:.4g}) with the rigid body's torque",
            f"  trajectory          {s['trajectory']}; the shaper lasts {sh['shaper_duration']:.4g} s",
            f"  max |y - y_d|       {s['max_redefinition_error']:.4g} m = {100 * s['relative_redefinition_error']:.3g} % of the "
            f"{s['move']:.4g} m move (at t = {s['time_of_max_redefinition_error']:.4g} s; accepted {s['max_error']:.3g} m): "
            "input shaping aims at the vibration after the move, not at the tip during it",
            f"  residual vibration  {sh['residual_vibration']:.3g} m of the tip in the shaped modes after the shaped reference "
            f"ends (unshaped: {sh['unshaped_residual_vibration']:.3g} m); the whole deflection {sh['residual_deflection']:.3g} m "
            f"(unshaped {sh['unshaped_residual_deflection']:.3g} m) as the loop settles in {sh['settle_time']:.3g} s more",
            f"  peak |tau|          {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s) on the nominal plant",
        ]


@register
@dataclass(frozen=True)
class ZV(_Shaping):
    """Zero-vibration input shaping.

    Zero-vibration input shaping: two impulses a mode (module docstring)."""

    name = "zv"
    kind = "zv"
    label = "ZV input shaping"
    title = "ZV-shaped loop's"
    rank = 4.0


@register
@dataclass(frozen=True)
class ZVD(_Shaping):
    """Zero-vibration-and-derivative input shaping.

    Zero-vibration-and-derivative input shaping: three impulses a mode, robust to the frequency (module docstring)."""

    name = "zvd"
    kind = "zvd"
    label = "ZVD input shaping"
    title = "ZVD-shaped loop's"
    rank = 5.0

"""A solved member of the family: the redefined output and the inverse torque, anywhere, in closed form.

:class:`Redefinition` joins one member of a solved batch (:mod:`inversion.family.ssef`) with the
normal form of the model (:mod:`inversion.lti.system`) and evaluates ``y~``, its derivatives,
the internal state, the state ``X`` and the torque of Eq. (12) at arbitrary times, in
the precision the segments were solved in. It is plain NumPy: the figures, the
verification and the explorer's workers use it; :class:`inversion.InversionResult`
samples it for the user.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..lti.system import NormalForm
from ..signals.trajectory import derivative_key
from .ssef import Coefficients, PlanSolution, SegmentPlan, SegmentSolution

__all__ = ["Redefinition", "evaluate_flat"]

#: From this many points of one segment :meth:`Redefinition.evaluate_local` evaluates them as one block.
_BLOCK = 16


def evaluate_flat(
    solution: PlanSolution, form: NormalForm, flat: NDArray[np.intp], s: ArrayLike, state: bool = True
) -> dict[str, NDArray[Any]]:
    """Everything at local times ``s`` of the flat segments ``flat``.

    ``s`` has the shape of ``flat`` (a point each), or ``(len(flat), M)`` (a block of
    points each); the outputs have its shape. Without ``state`` the torque is formed
    without ``X`` (which is then not returned).

    Parameters
    ----------
    solution : PlanSolution
        The batch's solution.
    form : NormalForm
        The plant's normal form.
    flat : NDArray[np.intp]
        Flat indices of the segments.
    s : ArrayLike
        Local times (s).
    state : bool, optional
        Whether to form ``X``.

    Returns
    -------
    dict
        ``y, ydot, yddot`` and the derivatives up to ``y^(rho+2)`` (``jerk, snap`` for the
        link; redefined output), ``XI``, ``X`` (the state ``[theta, delta, thetadot,
        deltadot]``) and ``tau`` (Eq. (12); a generic system's input).
    """
    stack = solution.stack
    flat = np.asarray(flat, dtype=np.intp)
    s = np.asarray(s, dtype=stack.c.dtype)
    top = form.top + 2  # what torque_rate needs
    # without the state, the torque needs one function of X_I (Eq. (12) on the outputs): formed as one state
    functional = None if state or form.higher.shape[1] else (form.Tinv.T @ form.CA2)[2:]
    if s.ndim == 2:  # blocks: s[q, m] in segment flat[q]
        share = solution.plan.share(flat) if np.all(s == s[:1]) else None  # one grid: equal segments share exponentials
        out = stack.evaluate_blocks(flat, np.clip(s, 0, stack.T[flat][:, None]), share=share, top=top, functional=functional)
    else:
        out = stack.evaluate(flat, np.clip(s, 0, stack.T[flat]), top=top, functional=functional)
    if state:
        X = form.state_of(out)
        out["X"] = X
        out["tau"] = form.input_of(out, X)
    elif functional is not None:
        w = (form.Tinv.T @ form.CA2).astype(np.result_type(out["XIf"], np.float64))
        out["tau"] = (np.asarray(out[form.drive]) - w[0] * np.asarray(out["y"]) - w[1] * np.asarray(out["ydot"]) - out["XIf"]) / form.CAB
    else:
        out["tau"] = form.input_of_output(out)
    return out


def torque_rate(form: NormalForm, values: dict[str, NDArray[Any]]) -> tuple[NDArray[Any], NDArray[Any]]:
    """``dtau/dt`` and ``d^2tau/dt^2`` from :func:`evaluate_flat`'s values.

    With ``Xdot = A X + B tau`` (the redefined state is the plant's trajectory):
    ``tau' = (yddot' - C A^2 Xdot)/CAB`` and ``tau'' = (yddot'' - C A^2 Xddot)/CAB``
    (``y^(rho+1)``, ``y^(rho+2)`` for a generic system).
    """
    A = form.A.astype(values["X"].dtype)
    B = form.B.astype(values["X"].dtype)
    tau = values["tau"]
    Xdot = values["X"] @ A.T + tau[..., None] * B
    tau1 = form.torque(values[derivative_key(form.rho + 1)], Xdot)
    Xddot = Xdot @ A.T + tau1[..., None] * B
    tau2 = form.torque(values[derivative_key(form.rho + 2)], Xddot)
    return tau1, tau2


@dataclass(frozen=True, eq=False)
class Redefinition:
    """One member of a solved batch.

    Attributes
    ----------
    solution : PlanSolution
        The solved batch.
    member : int
        The member's index in it.
    form : NormalForm
        The model's matrices.
    """

    solution: PlanSolution
    member: int
    form: NormalForm

    @property
    def plan(self) -> SegmentPlan:
        """Exponents, targets and anchors of the batch."""
        return self.solution.plan

    @cached_property
    def segments(self) -> list[SegmentSolution]:
        """The member's segments."""
        return self.solution.segments(self.member)

    @property
    def stack(self) -> Coefficients:
        """The vectorised evaluator of the batch."""
        return self.solution.stack

    @cached_property
    def extended(self) -> tuple[PlanSolution, Coefficients]:
        """The member alone, and its evaluator in extended precision (``numpy.longdouble``): the same
        double-precision coefficients, summed with 11 more bits (:mod:`inversion.signals.chebyshev`)."""
        ld = np.dtype(np.longdouble)
        sub = self.solution.subset([self.member])
        return sub, Coefficients(sub.plan, sub.c.astype(ld), sub.y0.astype(ld), sub.ydot0.astype(ld), sub.z0.astype(np.clongdouble))

    def end_state(self) -> NDArray[np.float64]:
        """``X_I(t_f)``, summed in extended precision, then rounded."""
        sub, stack = self.extended
        K = sub.plan.count
        values = stack.evaluate_blocks(np.array([K - 1]), np.array([[sub.plan.durations[-1]]], dtype=np.longdouble), top=self.form.top)
        return np.asarray(values["XI"][0, 0], dtype=float)

    @property
    def dtype(self) -> np.dtype[Any]:
        """Precision of the solution."""
        return self.solution.c.dtype

    @property
    def offset(self) -> int:
        """Flat index of the member's first segment."""
        return self.member * self.plan.count

    def owner(self, t: ArrayLike) -> NDArray[np.intp]:
        """The segment of each time.

        Segment of each time (``t_k <= t < t_{k+1}``, the last segment closed).

        Parameters
        ----------
        t : ArrayLike
            Times (s).
        """
        bounds = self.plan.bounds
        return np.clip(np.searchsorted(bounds, np.asarray(t, dtype=float), side="right") - 1, 0, bounds.size - 2)

    def evaluate_points(self, kk: ArrayLike, s: ArrayLike) -> dict[str, NDArray[Any]]:
        """Everything at local times ``s`` of the segments ``kk``.

        Parameters
        ----------
        kk : ArrayLike
            Segment of each point.
        s : ArrayLike
            Local time of each point (s).
        """
        return evaluate_flat(self.solution, self.form, np.asarray(kk, dtype=np.intp) + self.offset, s)

    def evaluate_local(self, k: int, s: ArrayLike) -> dict[str, NDArray[Any]]:
        """:meth:`evaluate_points` at local times ``s`` of segment ``k``.

        Parameters
        ----------
        k : int
            The segment.
        s : ArrayLike
            Local times (s).
        """
        s = np.atleast_1d(np.asarray(s, dtype=self.dtype))
        if s.ndim != 1 or s.size < _BLOCK:
            return self.evaluate_points(np.full(s.size, k, dtype=np.intp), s)
        # one block of the segment: products with its own coefficients, nothing gathered a point (the plant check's
        # thousand points a segment: 0.28 s -> 0.18 s over the 8-mode hyperbolic preset's 65); the same values to the
        # closed form's rounding
        values = evaluate_flat(self.solution, self.form, np.array([k + self.offset]), s[None, :])
        return {name: value[0] for name, value in values.items()}

    def evaluate(self, t: ArrayLike) -> dict[str, NDArray[Any]]:
        """:meth:`evaluate_points` at global times ``t``.

        Parameters
        ----------
        t : ArrayLike
            Times within ``[t_0, t_f]`` (s).
        """
        t = np.atleast_1d(np.asarray(t, dtype=self.dtype))
        kk = self.owner(t)
        return self.evaluate_points(kk, t - self.plan.bounds[kk].astype(self.dtype))

    def rounding(self, kk: ArrayLike, s: ArrayLike) -> dict[str, NDArray[Any]]:
        """Rounding bounds of ``tau``, ``theta``, ``thetadot``.

        First-order bounds of the rounding of ``tau``, ``theta`` and ``thetadot`` at local times ``s`` of segments ``kk``.

        ``eps`` times the magnitudes of the terms summed (:meth:`Coefficients.magnitudes`),
        carried through ``X = T^-1 [y; ydot; X_I]`` and Eq. (12). Any double-precision
        evaluator of the closed form is uncertain to about this much.

        Parameters
        ----------
        kk : ArrayLike
            Segment of each point.
        s : ArrayLike
            Local time of each point (s).
        """
        form = self.form
        flat = np.asarray(kk, dtype=np.intp) + self.offset
        m = self.stack.magnitudes(flat, np.asarray(s, dtype=float), top=form.top)
        v = np.column_stack([m["y"], m["ydot"], m["XI"]])
        X = v @ np.abs(form.Tinv).T
        for j in range(form.higher.shape[1]):
            X = X + np.outer(m[derivative_key(j + 2)], np.abs(form.higher[:, j]))
        eps = float(np.finfo(np.float64).eps)
        n1 = X.shape[1] // 2
        return {"tau": eps * (m[form.drive] + X @ np.abs(form.CA2)) / abs(form.CAB), "theta": eps * X[:, 0], "thetadot": eps * X[:, n1]}

    def sample(self, t: ArrayLike, chunk: int = 65_536) -> dict[str, NDArray[Any]]:
        """The redefined output and ``XI`` at increasing times ``t``.

        ``y, ydot, yddot, XI`` (and the derivatives up to ``y^(rho)``) at increasing times ``t`` (a sampled
        output), segment by segment.

        Each segment's samples are one block of :meth:`Coefficients.evaluate_blocks`
        (products with the segment's own coefficients, nothing gathered per sample), in
        chunks of at most ``chunk`` samples to bound the memory.

        Parameters
        ----------
        t : ArrayLike
            Increasing times (s).
        chunk : int, optional
            Most points evaluated at once.
        """
        t = np.asarray(t, dtype=self.dtype)
        kk = self.owner(t)
        starts = np.searchsorted(kk, np.arange(self.plan.count + 1))
        out = {name: np.empty(t.shape + ((self.form.n_internal,) if name == "XI" else ()), dtype=self.dtype)
               for name in ("XI",) + tuple(derivative_key(p) for p in range(self.form.top + 1))}
        for k in range(self.plan.count):
            for lo in range(int(starts[k]), int(starts[k + 1]), chunk):
                hi = min(lo + chunk, int(starts[k + 1]))
                local = np.clip(t[lo:hi] - self.dtype.type(self.plan.bounds[k]), 0, self.stack.T[self.offset + k])
                values = self.stack.evaluate_blocks(np.array([self.offset + k]), local[None, :], top=self.form.top)
                for name in out:
                    out[name][lo:hi] = values[name][0]
        return out

    def torque_rate(self, values: dict[str, NDArray[Any]]) -> tuple[NDArray[Any], NDArray[Any]]:
        """``dtau/dt`` and ``d^2tau/dt^2`` from the points' values.

        Parameters
        ----------
        values : dict[str, NDArray[Any]]
            What :meth:`evaluate_points` returned.
        """
        return torque_rate(self.form, values)

    def joint_jumps(self) -> dict[str, float]:
        """Largest jumps of ``y~``, ``ydot~`` and the torque at joints.

        Largest jumps of ``y~``, ``ydot~`` and the torque across the interior joints.
        """
        K = self.plan.count
        if K < 2:
            return {"output": 0.0, "velocity": 0.0, "torque": 0.0}
        k = np.arange(1, K)
        left = self.evaluate_points(k - 1, self.plan.durations[k - 1])
        right = self.evaluate_points(k, np.zeros(K - 1))
        return {name: float(np.abs(np.asarray(left[key] - right[key], dtype=float)).max())
                for name, key in (("output", "y"), ("velocity", "ydot"), ("torque", "tau"))}

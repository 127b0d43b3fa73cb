"""A solved member's signals as piecewise Chebyshev series (:mod:`inversion.signals.chebyshev`): its closed form
evaluated in extended precision at Chebyshev points and re-expanded, the torque of Eq. (12) and the joint references
of Eq. (40) among them."""

from __future__ import annotations

from typing import Any, Callable

import numpy as np
from numpy.typing import NDArray

from ..signals.chebyshev import DEGREE, LINK_SIGNALS, SYSTEM_SIGNALS, TOLERANCE, PiecewiseChebyshev, chebyshev_nodes, fit_chebyshev
from ..signals.trajectory import derivative_key
from .redefinition import Redefinition
from .settle import SettleTail

__all__ = ["chebyshev_signals", "member_signals"]

FloatArray = NDArray[np.float64]


def chebyshev_signals(
    redef: Redefinition, names: tuple[str, ...], signals: Callable[[dict[str, NDArray[Any]]], list[NDArray[Any]]],
    degree: int = DEGREE, tolerance: float = TOLERANCE, tail: SettleTail | None = None, functional: NDArray[Any] | None = None,
) -> PiecewiseChebyshev:
    """Re-expand a member's signals in piecewise Chebyshev series.

    Re-expand signals of a solved member in piecewise Chebyshev series on its segments (module docstring).

    Parameters
    ----------
    redef : Redefinition
        The solved member.
    names : tuple of str
        The signals' names.
    signals : callable
        ``signals(values) -> [signal, ...]`` from the values of
        :meth:`~inversion.family.ssef.Coefficients.evaluate_blocks` (``y``, its derivatives,
        ``XI``), in their precision (extended here).
    degree, tolerance :
        As :func:`fit_chebyshev`.
    tail : SettleTail, optional
        A post-actuation after ``t_f`` (:mod:`inversion.family.settle`): one more interval.
    functional : ndarray, shape (2n, F), optional
        The functions of ``X_I`` the signals need (``XIf`` among the values instead of ``XI``:
        :meth:`~inversion.family.ssef.Coefficients.evaluate_blocks`); the tail's values still give ``XI``.
    """
    ld = np.dtype(np.longdouble)
    sub, stack = redef.extended
    top = redef.form.top
    durations = np.asarray(sub.plan.durations, dtype=float)
    K = durations.size
    bounds = sub.plan.bounds if tail is None else np.append(sub.plan.bounds, tail.end)

    def evaluate(k: NDArray[np.intp], s: NDArray[Any]) -> NDArray[Any]:
        out = np.empty((k.size, len(names), s.shape[1]), dtype=ld)
        inside = k < K
        if np.any(inside):
            values = stack.evaluate_blocks(k[inside], s[inside], top=top, functional=functional)
            out[inside] = np.stack([np.asarray(v, dtype=ld) for v in signals(values)], axis=1)
        if tail is not None and not np.all(inside):
            local = np.asarray(s[~inside], dtype=float)
            values = {name: np.asarray(v).reshape(local.shape + np.asarray(v).shape[1:])
                      for name, v in tail.values(tail.start + local.ravel()).items()}
            out[~inside] = np.stack([np.asarray(v, dtype=ld) for v in signals(values)], axis=1)
        return out

    def noise(peaks: FloatArray) -> FloatArray:
        return _noise(redef, names, durations, chebyshev_nodes(degree), peaks)

    return fit_chebyshev(names, bounds, evaluate, noise, degree, tolerance)


def _noise(redef: Redefinition, names: tuple[str, ...], durations: FloatArray, x: NDArray[Any], peaks: FloatArray) -> FloatArray:
    """Per signal, the tail a piece may stop at when halving no longer helps: ``1e3`` times the
    tolerance, or ten times the rounding of the closed form in extended precision (its
    double-precision bound scaled by the ratio of the precisions), relative to the peak."""
    K = durations.size
    kk = np.repeat(np.arange(K), x.size)
    s = (np.asarray((x + 1) / 2, dtype=float)[None, :] * durations[:, None]).ravel()
    rounding = redef.rounding(kk, s)
    keys = {"tau": "tau", "u": "tau", "theta_d": "theta", "thetadot_d": "thetadot"}
    ratio = float(np.finfo(np.longdouble).eps / np.finfo(np.float64).eps)
    bound = np.array([float(rounding[keys[name]].max()) for name in names]) * ratio / peaks
    return np.maximum(1e3 * TOLERANCE, 10 * bound)


def member_signals(redef: Redefinition, link: bool, tail: SettleTail | None = None) -> PiecewiseChebyshev:
    """The series of what a member feeds forward.

    :func:`chebyshev_signals` of what a member feeds forward: ``tau`` (Eq. (12)), ``theta_d =
    X_0`` and ``thetadot_d = X_{n+1}`` for a link, the input ``u`` for a generic system (after
    ``t_f`` along ``tail``, if given).

    Parameters
    ----------
    redef : Redefinition
        A solved member's redefinition.
    link : bool
        Whether the plant is a link (else a generic system).
    tail : SettleTail | None, optional
        The settle tail after ``t_f``, if any.
    """
    form = redef.form
    ld = np.longdouble
    # what the signals need of the state X: theta_d = X_0 and thetadot_d = X_{n+1} (a link's), and C A^rho X for the input
    # (Eq. (12)), as columns of R; X R = y (Tinv R)_0 + ydot (Tinv R)_1 + X_I (Tinv R)_I + the higher derivatives' rows --
    # three functions of X_I where X_I has 2n: fewer of the closed form's products in extended precision (the 8-mode
    # hyperbolic preset's fit in 0.45 x its time)
    n1 = form.n_states // 2
    rows = [0, n1] if link else []
    R = np.zeros((form.n_states, len(rows) + 1), dtype=ld)
    R[rows, np.arange(len(rows))] = 1
    R[:, -1] = form.CA2
    TR = form.Tinv.astype(ld).T @ R
    HR = form.higher.astype(ld).T @ R if form.higher.shape[1] else np.zeros((0, R.shape[1]), dtype=ld)

    def signals(values: dict[str, NDArray[Any]]) -> list[NDArray[Any]]:
        if "XIf" not in values:  # the settle tail's values: the whole state
            X = form.state_of(values)
            return [form.input_of(values, X), X[..., 0], X[..., n1]] if link else [form.input_of(values, X)]
        XR = np.asarray(values["y"])[..., None] * TR[0] + np.asarray(values["ydot"])[..., None] * TR[1] + values["XIf"]
        for j in range(HR.shape[0]):
            XR = XR + np.asarray(values[derivative_key(j + 2)])[..., None] * HR[j]
        u = (np.asarray(values[form.drive]) - XR[..., -1]) / form.CAB
        return [u, XR[..., 0], XR[..., 1]] if link else [u]

    return chebyshev_signals(redef, LINK_SIGNALS if link else SYSTEM_SIGNALS, signals, tail=tail, functional=TR[2:])

"""After ``t_f``: the output held on ``y_d(t_f)`` while the link's internal modes settle (``end="settle"``).

``y_d`` holds its final value after the move, and so must the link. A member that ends with
``y~(t_f) = y_d(t_f)`` and its internal state excited leaves the link moving once the
torque stops (its angular momentum: it drifts on; its deflections: it rings). Holding the
output exactly on ``y_f = y_d(t_f)`` after ``t_f`` is the inversion on a constant desired
output: ``yddot = 0``, so every internal mode is free, ``z_i(t) = e^{lambda_i (t - t_f)}
z_i(t_f)`` (Eq. (17) without forcing). A stable mode decays; an unstable one stays bounded
only if it is zero at ``t_f`` -- which the ``anchored`` joining makes it (its exact-tracking
value ``z*(t_f) = 0``). The torque of Eq. (12) along this tail,

    tau = (0 - C A^2 X) / CAB,   X = T^-1 [y_f; 0; X_I(t)],

is continuous at ``t_f`` (the member's ``yddot~(t_f) = yddot_d(t_f)``, its state continuous),
decays with the slowest stable zero, and is cut where every mode's share of the torque and
of the joint angle falls below ``tolerance`` of their peaks: a causal post-actuation, after
which the linear plant is at rest on ``y_f`` to that tolerance. It is what stable inversion
does after ``t_f`` (:mod:`inversion.methods.stable`), without its pre-actuation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InversionError
from ..lti.internal import ModalInternalDynamics
from ..lti.system import NormalForm
from ..signals.trajectory import derivative_key

__all__ = ["SettleTail", "settle_tail"]

FloatArray = NDArray[np.float64]
#: An unstable mode must be this small at ``t_f`` (relative to the internal state's scale) to be held.
_UNSTABLE_LIMIT = 1e-9


@dataclass(frozen=True)
class SettleTail:
    """The tail after ``t_f`` of a member held on its final output.

    Attributes
    ----------
    start : float
        ``t_f`` (s).
    length : float
        The post-actuation (s): after ``start + length`` every mode's share of the torque and
        of the joint angle is below the tolerance.
    y_final : float
        The output held (m).
    z_start : ndarray of complex
        The modal internal state at ``t_f`` (the unstable modes zero).
    modal : ModalInternalDynamics
        The modes.
    form : NormalForm
        The model's matrices.
    """

    start: float
    length: float
    y_final: float
    z_start: NDArray[np.complex128]
    modal: ModalInternalDynamics
    form: NormalForm

    @property
    def end(self) -> float:
        """When the feedforward ends (s)."""
        return self.start + self.length

    def starting_at(self, XI: ArrayLike) -> "SettleTail":
        """The same tail started from ``X_I(t_f) = XI``.

        Parameters
        ----------
        XI : ArrayLike
            The internal state at ``t_f``.
        """
        z = np.where(self.modal.unstable | self.modal.free, 0, self.modal.to_modal(XI))
        return SettleTail(self.start, self.length, self.y_final, z, self.modal, self.form)

    def values(self, t: ArrayLike) -> dict[str, Any]:
        """The tail's values at the times ``t >= t_f``.

        ``y = y_f``, its derivatives zero, and ``XI`` at the times ``t >= t_f`` (as :meth:`Redefinition.evaluate`).

        Parameters
        ----------
        t : ArrayLike
            Times ``t >= t_f`` (s).
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        held = self.modal.unstable | self.modal.free  # zero from t_f on: their exponentials are never formed (they would overflow)
        rate = np.where(held, 0, self.modal.lam)
        z = np.exp(np.outer(t - self.start, rate)) * np.where(held, 0, self.z_start)[None, :]
        out: dict[str, Any] = {derivative_key(p): np.zeros(t.size) for p in range(self.form.top + 3)}
        out["y"] = np.full(t.size, self.y_final)
        out["XI"] = self.modal.to_physical(z)
        return out


def settle_tail(
    form: NormalForm, modal: ModalInternalDynamics, start: float, y_final: float, z_start: ArrayLike, peaks: tuple[float, float],
    tolerance: float, longest: float,
) -> SettleTail:
    """The tail of a member that ended at ``start``.

    The tail of a member that ended at ``start`` with the modal internal state ``z_start`` (module docstring).

    Parameters
    ----------
    form : NormalForm
        The model's matrices.
    modal : ModalInternalDynamics
        Its modes (the unstable set of the member).
    start, y_final : float
        ``t_f`` and ``y_d(t_f)``.
    z_start : array_like of complex
        ``z(t_f)``.
    peaks : (float, float)
        The member's peak torque and the range of its joint angle: the tail is cut where each
        mode's share falls below ``tolerance`` of them.
    tolerance : float
        Where the tail is cut.
    longest : float
        Longest accepted tail (s).

    Raises
    ------
    InversionError
        When an unstable mode is not at zero at ``t_f`` (a joining other than ``anchored``), or
        the tail would be longer than ``longest`` (a stable zero near the imaginary axis), with
        the figures.
    """
    z = np.asarray(z_start, dtype=complex).reshape(-1)
    lam = modal.lam
    held = modal.unstable | modal.free
    scale = max(float(np.abs(z).max(initial=0.0)), 1e-300)
    if np.any(held) and float(np.abs(z[held]).max()) > _UNSTABLE_LIMIT * max(scale, 1.0):
        raise InversionError(
            f"the output cannot be held after t_f: the unstable internal modes end at {float(np.abs(z[held]).max()):.3g} "
            "(only the anchored joining ends them at zero)")
    z = np.where(held, 0, z)
    # what one unit of each mode puts into the torque and the joint angle (X = T^-1 [y; ydot; X_I])
    shares = [(-(form.CA2 @ form.Tinv[:, 2:] @ modal.V) / form.CAB, peaks[0]), (form.Tinv[0, 2:] @ modal.V, peaks[1])]
    length = 0.0
    count = max(int(np.count_nonzero(~held)), 1)
    for i in np.flatnonzero(~held):
        if lam[i].real >= 0:
            continue
        for per_mode, peak in shares:
            size = abs(per_mode[i] * z[i]) * 2 * count
            if peak > 0 and size > tolerance * peak:
                length = max(length, math.log(size / (tolerance * peak)) / abs(lam[i].real))
    if length > longest:
        slowest = lam[~held][np.argmin(np.abs(lam[~held].real))]
        raise InversionError(f"holding the output after t_f needs {length:.4g} s of post-actuation (more than {longest:.4g} s): "
                             f"the stable zero {slowest:.6g} is close to the imaginary axis (eps = {abs(slowest.real):.3g} "
                             "or more counts it as unstable, anchored instead)")
    return SettleTail(float(start), float(length), float(y_final), z, modal, form)

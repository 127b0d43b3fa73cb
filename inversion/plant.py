"""The plant of a closed-loop simulation: compiled right-hand sides and hub dry friction.

The right-hand side ``Xdot = f(X, tau_net)`` is the compiled ``linear_rhs`` (P8/P9) or
``nonlinear_rhs`` (P4); hub viscous damping is part of the model's ``C``. Dry (Coulomb)
friction acts on the joint only and is handled here with genuine stick-slip:

* slipping with direction ``d``: ``tau_net = tau_motor - d F_c``;
* stuck: ``thetadot = 0`` and the friction supplies whatever torque keeps
  ``thetaddot = 0``, as long as that torque stays within the breakaway level ``F_s``.

``f`` is affine in ``tau_net``, so the holding torque is one division:
``thetaddot = a(X) + b(X) tau_net = 0``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from modelgen.compiled import FastCall
from modelgen.model import Model

from .errors import SettingsError

__all__ = ["Plant", "HubFriction", "OVERRIDABLE"]

#: Physical parameters a simulated plant may change with respect to the model.
OVERRIDABLE = ("L", "EI", "rho", "I_h", "m_t", "I_t", "b_h", "zeta")

FloatArray = NDArray[np.float64]
PlantKind = Literal["linear", "nonlinear"]


@dataclass(frozen=True)
class HubFriction:
    """Dry friction on the joint.

    Attributes
    ----------
    coulomb : float
        Kinetic (sliding) friction ``F_c`` (N m).
    breakaway : float
        Static level ``F_s >= F_c`` (N m): a hub at rest stays at rest while the torque
        needed to hold it is below this.
    """

    coulomb: float = 0.0
    breakaway: float = 0.0

    def __post_init__(self) -> None:
        for name, value in (("coulomb_friction", self.coulomb), ("breakaway_friction", self.breakaway)):
            if not np.isfinite(value) or value < 0:
                raise SettingsError(name, value, "a finite number >= 0 (N m)")
        if self.breakaway < self.coulomb:
            raise SettingsError("breakaway_friction", self.breakaway, f"a number >= the Coulomb friction {self.coulomb:g} N m")

    @property
    def active(self) -> bool:
        """Whether there is any dry friction."""
        return self.breakaway > 0


class Plant:
    """The model's compiled right-hand side with the hub's dry friction.

    Parameters
    ----------
    model : Model
        The loaded model (its compiled functions are called).
    kind : {"linear", "nonlinear"}
        (P8) or (P4).
    friction : HubFriction
        Dry friction on the joint.
    overrides : dict, optional
        Physical parameters of the plant that differ from the model's (by name, see
        :data:`OVERRIDABLE`): a plant that is not the model the controller was built on.
    """

    def __init__(self, model: Model, kind: PlantKind, friction: HubFriction, overrides: dict[str, float] | None = None):
        if kind not in ("linear", "nonlinear"):
            raise SettingsError("plant", kind, "'linear' or 'nonlinear'")
        self.model = model
        self.kind = kind
        self.friction = friction
        self.n1 = model.n + 1
        self.p = model.parameters.copy()
        names = list(model.parameter_names)
        for name, value in (overrides or {}).items():
            if name not in OVERRIDABLE:
                raise SettingsError(f"plant parameter {name!r}", value, "one of " + ", ".join(OVERRIDABLE))
            positive = name in ("L", "EI", "rho")
            if not (isinstance(value, (int, float)) and math.isfinite(value) and (value > 0 if positive else value >= 0)):
                raise SettingsError(f"plant parameter {name}", value, "a finite number " + ("> 0" if positive else ">= 0"))
            self.p[names.index(name)] = float(value)
        fns = model.functions
        self._rhs = FastCall(fns.functions[f"{kind}_rhs"])
        self._jac = FastCall(fns.functions["nonlinear_rhs_jacobian"]) if kind == "nonlinear" else None
        self._energy = FastCall(fns.functions["energy"])
        self._AB: tuple[FloatArray, FloatArray] | None = None

    def rhs(self, X: FloatArray, tau_net: float) -> FloatArray:
        """``Xdot`` for a net hub torque (motor plus dry friction)."""
        return self._rhs(self.p, X, tau_net)[0].reshape(-1)

    def jacobian(self, X: FloatArray, tau_net: float) -> tuple[FloatArray, FloatArray]:
        """``(df/dX, df/dtau)``."""
        if self._jac is None:
            if self._AB is None:
                A, B = self.model.functions.call("A", self.p)[0], self.model.functions.call("B", self.p)[0]
                self._AB = (A, B.reshape(-1))
            return self._AB
        J, Jt = self._jac(self.p, X, tau_net)
        return J, Jt.reshape(-1)

    def holding_torque(self, X: FloatArray) -> tuple[float, FloatArray]:
        """The net hub torque that makes ``thetaddot = 0`` at ``X``, and ``Xdot`` with it."""
        f0 = self.rhs(X, 0.0)
        f1 = self.rhs(X, 1.0)
        b = f1[self.n1] - f0[self.n1]
        tau = -f0[self.n1] / b
        xdot = f0 + tau * (f1 - f0)
        xdot[self.n1] = 0.0
        xdot[0] = 0.0
        return float(tau), xdot

    def energy(self, X: FloatArray) -> float:
        """Mechanical energy of the linear model, ``qdot^T M qdot / 2 + q^T K q / 2``."""
        return float(self._energy(self.p, X)[0].item())

"""The simulated plant: the model's compiled right-hand side, hub dry friction, and what differs from the model.

The right-hand side ``Xdot = f(X, tau_net)`` is the compiled ``linear_rhs`` (P8/P9),
``nonlinear_rhs`` (P4 with the link's foreshortening: geometric stiffening, the default) or
``nonlinear_paper_rhs`` (the paper's P4 as it is); hub viscous damping is part of the model's ``C``. Dry (Coulomb)
friction acts on the joint only; :mod:`simulation.hybrid` handles it with genuine
stick-slip.

A plant may differ from the model the feedforward was computed for: other physical
parameters (a plant whose link, hub or payload is not the model's; it is a model of its
own, derived for the changed geometry with the same number and family of modes) or other
friction. :attr:`Plant.differences` lists every such value with the model's and where
it came from, so that a report can say what it assumed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal, Mapping

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from modelgen.errors import SettingsError
from modelgen.geometry import Geometry
from modelgen.model import Model

__all__ = ["Plant", "HubFriction", "PlantKind", "PLANTS", "OVERRIDABLE", "PlantDifference"]

FloatArray = NDArray[np.float64]
PlantKind = Literal["linear", "nonlinear", "nonlinear-paper", "nonlinear-large"]
#: The plants: the linear model (P8), the nonlinear one with geometric stiffening (docs/method.md section 1a), the
#: paper's nonlinear (P4) without it.
PLANTS = ("linear", "nonlinear", "nonlinear-paper", "nonlinear-large")
#: The generated roles of each plant's right-hand side and its Jacobian.
_RHS = {"linear": ("linear_rhs", None), "nonlinear": ("nonlinear_rhs", "nonlinear_rhs_jacobian"),
        "nonlinear-paper": ("nonlinear_paper_rhs", "nonlinear_paper_rhs_jacobian")}
#: The generated energy of each plant that has one (:meth:`Plant.effective_inertia`).
_ENERGY = {"linear": "energy", "nonlinear": "nonlinear_energy"}

#: Physical parameters a simulated plant may change with respect to the model: name ->
#: (geometry field, unit, must be > 0).
OVERRIDABLE: dict[str, tuple[str, str, bool]] = {
    "L": ("length", "m", True),
    "EI": ("flexural_rigidity", "N m^2", True),
    "rho": ("linear_density", "kg/m", True),
    "I_h": ("hub_inertia", "kg m^2", False),
    "m_t": ("payload_mass", "kg", False),
    "I_t": ("payload_inertia", "kg m^2", False),
    "b_h": ("hub_viscous_damping", "N m s/rad", False),
    "zeta": ("damping_ratio", "", False),
}
#: Where a value came from when the caller does not say.
GIVEN = "given by the caller"


@dataclass(frozen=True)
class HubFriction:
    """Dry friction on the joint.

    Attributes
    ----------
    coulomb : float
        Kinetic (sliding) friction ``F_c`` (N m).
    breakaway : float
        Static level ``F_s >= F_c`` (N m): a hub at rest stays at rest while the torque
        needed to hold it is at most this.
    """

    coulomb: float = 0.0
    breakaway: float = 0.0

    def __post_init__(self) -> None:
        for name, value in (("coulomb_friction", self.coulomb), ("breakaway_friction", self.breakaway)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise SettingsError(name, value, "a finite number >= 0 (N m)")
        if self.breakaway < self.coulomb:
            raise SettingsError("breakaway_friction", self.breakaway, f"a number >= the Coulomb friction {self.coulomb:g} N m")

    @property
    def active(self) -> bool:
        """Whether there is any dry friction."""
        return self.breakaway > 0


@dataclass(frozen=True)
class PlantDifference:
    """One value of the simulated plant that is not the model's.

    Attributes
    ----------
    value, model : float
        The plant's value and the model's.
    unit : str
        Its unit.
    source : str
        Where the plant's value came from (an option, the caller, a labelled assumption).
    """

    value: float
    model: float
    unit: str
    source: str

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"value": self.value, "model": self.model, "unit": self.unit, "source": self.source}


class Plant:
    """The simulated plant: a model, its dynamics, its hub friction.

    Parameters
    ----------
    model : Model
        The model the controller was built on.
    kind : {"linear", "nonlinear", "nonlinear-paper", "nonlinear-large"}
        (P8) or (P4).
    friction : HubFriction, optional
        The plant's dry friction (default: the model's ``F_c``, breaking away at ``F_c``).
    overrides : mapping, optional
        Physical parameters that differ from the model's, by name (:data:`OVERRIDABLE`).
    sources : mapping, optional
        Where each value that differs from the model came from, by name (the names of
        ``overrides`` and ``coulomb_friction``, ``breakaway_friction``).

    Attributes
    ----------
    model : Model
        The plant's own model: ``model`` itself, or the model of the changed geometry.
    differences : dict of str to PlantDifference
        Every plant value that differs from the model's.
    """

    def __init__(
        self,
        model: Model,
        kind: PlantKind = "nonlinear",
        friction: HubFriction | None = None,
        overrides: Mapping[str, float] | None = None,
        sources: Mapping[str, str] | None = None,
    ):
        if kind not in PLANTS:
            raise SettingsError("plant", kind, "'linear', 'nonlinear' (with geometric stiffening), 'nonlinear-paper' (the "
                                               "paper's P4, without it) or 'nonlinear-large' (exact kinematics, for large "
                                               "deflections)")
        sources = dict(sources or {})
        g = model.geometry
        model_friction = g.hub_coulomb_friction
        self.friction = friction if friction is not None else HubFriction(model_friction, model_friction)
        self.kind: PlantKind = kind
        changes: dict[str, float] = {}
        self.differences: dict[str, PlantDifference] = {}
        for name, value in (overrides or {}).items():
            if name not in OVERRIDABLE:
                raise SettingsError(f"plant parameter {name!r}", value, "one of " + ", ".join(OVERRIDABLE))
            field_name, unit, positive = OVERRIDABLE[name]
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            ok = ok and (value > 0 if positive else value >= 0) and (name != "zeta" or value < 1)
            if not ok:
                accepted = "a finite number " + ("> 0" if positive else ">= 0") + (" and < 1" if name == "zeta" else "")
                raise SettingsError(f"plant parameter {name}", value, accepted)
            current = float(getattr(g, field_name))
            if float(value) != current:
                changes[field_name] = float(value)
                self.differences[name] = PlantDifference(float(value), current, unit, sources.get(name, GIVEN))
        for name, value in (("coulomb_friction", self.friction.coulomb), ("breakaway_friction", self.friction.breakaway)):
            if value != model_friction:
                self.differences[name] = PlantDifference(value, model_friction, "N m", sources.get(name, GIVEN))
        if changes:
            import modelgen

            changed: Geometry = replace(g, source=f"{g.source} (simulated plant)", **changes)  # type: ignore[arg-type]
            self.model = modelgen.load(changed)
        else:
            self.model = model
        self.p = np.asarray(self.model.parameters, dtype=float)

    @property
    def n1(self) -> int:
        """``n + 1``: the number of generalised coordinates."""
        return self.model.n + 1

    def rhs(self) -> Any:
        """The right-hand side as CasADi ``(X, tau_net) -> Xdot``.

        Compiled functions (``casadi.external``) carry no derivatives of their own: the
        function is given the compiled Jacobian as its ``custom_jacobian`` (the model's
        ``nonlinear_rhs_jacobian``, or ``A`` and ``B`` for the linear plant), so that an
        implicit integrator's Newton iterations run compiled code too. In-process
        functions (the no-compiler fallback) are differentiated by CasADi itself.
        """
        if self.kind == "nonlinear-large":  # built in this process (modelgen.large): CasADi differentiates it itself
            from modelgen.large import large_deflection_functions

            return large_deflection_functions(self.model)["rhs"]
        fns = self.model.compiled_functions
        nx = 2 * self.n1
        X = ca.MX.sym("X", nx)
        tau = ca.MX.sym("tau")
        p = ca.DM(self.p)
        role, jacobian_role = _RHS[self.kind]
        xdot = fns.functions[role](p, X, tau)
        if not fns.compiled:
            return ca.Function("sflm_plant", [X, tau], [xdot], ["X", "tau"], ["Xdot"])
        if jacobian_role is not None:
            dX, dtau = fns.functions[jacobian_role](p, X, tau)
        else:
            dX, dtau = ca.DM(self.model.A), ca.DM(self.model.B.reshape(-1, 1))
        out = ca.MX.sym("out_Xdot", nx)
        jac = ca.Function("jac_sflm_plant", [X, tau, out], [dX, dtau], ["X", "tau", "out_Xdot"], ["jac_Xdot_X", "jac_Xdot_tau"])
        return ca.Function("sflm_plant", [X, tau], [xdot], ["X", "tau"], ["Xdot"], {"custom_jacobian": jac, "jac_penalty": 0})

    def effective_inertia(self, X: FloatArray) -> FloatArray:
        """The hub's effective inertia along states (kg m^2).

        ``M_00(delta)`` less what the modes carry with it. Every entry of the mass matrix but ``M_00 = J + delta^T W delta`` is constant (docs/method.md section 1a), so
        ``M(delta)`` is positive definite exactly while ``M_00(delta) - M_0d M_dd^-1 M_d0`` is. The linear model's is
        constant; the stiffened model's falls with the deflection where the foreshortening's second-order term
        (``rho P / 2 + m_t L Q``) outweighs ``W`` -- a heavy payload on a light hub -- and at zero its equations have no
        solution. ``M_00(delta)`` is read from the compiled energy: ``E(delta, thetadot = 1) - E(delta, 0) = M_00 / 2``.

        Parameters
        ----------
        X : ndarray
            States, one per row.

        Raises
        ------
        SettingsError
            For a plant without a compiled energy of its own ('nonlinear-paper', 'nonlinear-large').
        """
        role = _ENERGY.get(self.kind)
        if role is None:
            raise SettingsError("plant", self.kind, "'linear' or 'nonlinear' (the plants whose energy is generated)")
        X = np.atleast_2d(np.asarray(X, dtype=float))
        n1 = self.n1
        q = np.column_stack([X[:, :n1], np.zeros((X.shape[0], n1))])
        turning = q.copy()
        turning[:, n1] = 1.0
        (moving,) = self.model.compiled_functions.map(role, self.p, turning)
        (still,) = self.model.compiled_functions.map(role, self.p, q)
        M = np.asarray(self.model.M, dtype=float)
        carried = float(M[0, 1:] @ np.linalg.solve(M[1:, 1:], M[1:, 0])) if n1 > 1 else 0.0
        return 2.0 * (np.asarray(moving, dtype=float) - np.asarray(still, dtype=float)).reshape(-1) - carried

    def tip(self, X: FloatArray) -> FloatArray:
        """Tip displacement ``y = D q`` with the plant's own shapes.

        Parameters
        ----------
        X : ndarray
            States, one per row.
        """
        return np.asarray(X[:, : self.n1] @ self.model.D, dtype=float)

    def energy(self, X: FloatArray) -> FloatArray:
        """Mechanical energy of states (of the linear model).

        Mechanical energy ``qdot^T M qdot / 2 + q^T K q / 2`` of states (of the linear model).

        Parameters
        ----------
        X : ndarray
            States, one per row.
        """
        X = np.atleast_2d(np.asarray(X, dtype=float))
        (E,) = self.model.compiled_functions.map("energy", self.p, X)
        return np.asarray(E, dtype=float).reshape(-1)

    def block(self) -> dict[str, Any]:
        """The ``plant`` block of a simulation summary.

        The ``plant`` block of a simulation summary: its kind, its friction and every value not the model's.
        """
        return {
            "kind": self.kind,
            "coulomb_friction": self.friction.coulomb,
            "breakaway_friction": self.friction.breakaway,
            "differs_from_model": {name: d.as_dict() for name, d in self.differences.items()},
        }

"""The link with exact kinematics, for large deflections (``simulate --plant nonlinear-large``; docs/method.md section 1a).

The stiffened model keeps the link's foreshortening to second order in the deflection. Here the
same assumed modes ``w(s, t) = sum_j phi_j(s) delta_j(t)`` describe an *inextensible* link whose
``s`` is the arc length, and nothing else is expanded:

* a point of the link is at ``(s + u(s), w(s))`` in the rotating frame, ``u(s) = int_0^s (sqrt(1 - w'^2) - 1)``
  (the foreshortening to all orders), so the kinetic energy keeps every term of
  ``rho/2 int [(udot - thetadot w)^2 + (wdot + thetadot (s + u))^2] ds``;
* the curvature is exact, ``kappa = w'' / sqrt(1 - w'^2)``, and ``V = EI/2 int kappa^2 ds``;
* the payload sits at ``(L + u(L), w(L))`` and turns with the link's end, ``theta + asin w'(L)``.

The integrals along the link are Gauss--Legendre sums over ``NODES`` points, ``u`` by the
matching cumulative-integration matrix (exact for polynomials of degree below ``NODES``);
Lagrange's equations are formed by CasADi's algorithmic differentiation of these sums, and
damping is the linear model's ``C qdot`` (Rayleigh's, Eq. (7), and the hub's). The function is
built in this process for the loaded model (no C is generated: CVODES calls it through CasADi's
virtual machine), and linearised at rest it is the linear model (P8) (tested).
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from numpy.polynomial import legendre
from numpy.typing import NDArray

from .errors import ModelError
from .model import Model

__all__ = ["NODES", "MAX_MODES", "large_deflection_functions", "gauss_nodes"]

#: Gauss--Legendre points along the link (the first ten modes' curvatures squared integrate to 1e-12 with 40).
NODES = 40
#: Most modes the model is built for (its graph grows like ``NODES n^2``).
MAX_MODES = 8


def gauss_nodes(length: float, count: int = NODES) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Gauss--Legendre nodes, weights and cumulative integration.

    Gauss--Legendre nodes ``s`` and weights on ``[0, length]``, and the cumulative-integration matrix ``I``:
    ``(I f)_k = int_0^{s_k} p`` for the polynomial ``p`` of degree ``count - 1`` through the samples ``f`` at the nodes.

    Parameters
    ----------
    length : float
        The interval's length.
    count : int, optional
        Number of nodes.
    """
    xi, weights = legendre.leggauss(count)
    vander = legendre.legvander(xi, count - 1)
    integrals = np.column_stack([legendre.legval(xi, legendre.legint(np.eye(count)[k], lbnd=-1)) for k in range(count)])
    half = length / 2
    cumulative = np.asarray(np.linalg.solve(vander.T, integrals.T).T * half, dtype=float)
    return (xi + 1) * half, weights * half, cumulative


def large_deflection_functions(model: Model, count: int = NODES) -> dict[str, Any]:
    """CasADi functions of the exact-kinematics model of the link.

    CasADi functions of the exact-kinematics model of ``model``'s link (module docstring).

    Parameters
    ----------
    model : Model
        The loaded link: its geometry, shapes and linear damping ``C``.
    count : int
        Gauss--Legendre points along the link.

    Returns
    -------
    dict
        ``"rhs"``: ``(X, tau) -> Xdot``; ``"energy"``: ``X -> T + V``; ``"tip_angle"``: ``X -> atan2(w(L), L + u(L))``
        minus ``theta`` (the tip seen from the hub, relative to the hub's angle).

    Raises
    ------
    ModelError
        For more than :data:`MAX_MODES` modes.
    """
    n = model.n
    if n > MAX_MODES:
        raise ModelError(f"the large-deflection model is built for at most {MAX_MODES} modes, not {n} (its graph grows like n^2 "
                         "per node); load the model with fewer modes")
    g = model.geometry
    L, EI, rho = g.length, g.flexural_rigidity, g.linear_density
    s, weights, cumulative = gauss_nodes(L, count)
    shape, slope, curvature = (ca.DM(model.shapes(s, k).T) for k in (0, 1, 2))
    end = model.shapes([L], 0)[:, 0], model.shapes([L], 1)[:, 0]
    W, I = ca.DM(weights), ca.DM(cumulative)

    X = ca.SX.sym("X", 2 * (n + 1))
    tau = ca.SX.sym("tau")
    q, qd = X[: n + 1], X[n + 1 :]
    thetadot, delta, deltadot = qd[0], q[1:], qd[1:]

    w, wdot = ca.mtimes(shape, delta), ca.mtimes(shape, deltadot)
    w1, w2 = ca.mtimes(slope, delta), ca.mtimes(curvature, delta)
    u = ca.mtimes(I, ca.sqrt(1 - w1**2) - 1)  # the foreshortening to all orders
    udot = ca.jtimes(u, delta, deltadot)
    radius = ca.DM(s) + u
    kinetic = g.hub_inertia / 2 * thetadot**2 + rho / 2 * ca.dot(W, (udot - thetadot * w) ** 2 + (wdot + thetadot * radius) ** 2)
    w_L, wdot_L = ca.dot(ca.DM(end[0]), delta), ca.dot(ca.DM(end[0]), deltadot)
    slope_L, slopedot_L = ca.dot(ca.DM(end[1]), delta), ca.dot(ca.DM(end[1]), deltadot)
    u_L = ca.dot(W, ca.sqrt(1 - w1**2) - 1)
    udot_L = ca.jtimes(u_L, delta, deltadot)
    kinetic += g.payload_mass / 2 * ((udot_L - thetadot * w_L) ** 2 + (wdot_L + thetadot * (L + u_L)) ** 2)
    kinetic += g.payload_inertia / 2 * (thetadot + slopedot_L / ca.sqrt(1 - slope_L**2)) ** 2
    potential = EI / 2 * ca.dot(W, w2**2 / (1 - w1**2))

    momentum = ca.gradient(kinetic, qd)
    M = ca.jacobian(momentum, qd)
    f = ca.mtimes(ca.jacobian(momentum, q), qd) - ca.gradient(kinetic, q) + ca.gradient(potential, q) + ca.mtimes(ca.DM(model.C), qd)
    H = ca.DM(model.H.reshape(-1, 1))
    qdd = ca.solve(M, H * tau - f)
    return {
        "rhs": ca.Function("sflm_large_rhs", [X, tau], [ca.vertcat(qd, qdd)], ["X", "tau"], ["Xdot"]),
        "energy": ca.Function("sflm_large_energy", [X], [kinetic + potential], ["X"], ["E"]),
        "tip_angle": ca.Function("sflm_large_tip_angle", [X], [ca.atan2(w_L, L + u_L)], ["X"], ["psi"]),
    }

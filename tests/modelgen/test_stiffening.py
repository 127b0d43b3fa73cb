"""Geometric stiffening (issue 22, item 1): the nonlinear plant with the link's foreshortening, checked against the classic
rotating-beam coefficients, its own linearisation and energy, and an independent finite-element engine."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import modelgen
from modelgen.geometry import Geometry
from modelgen.large import MAX_MODES, gauss_nodes, large_deflection_functions
from modelgen.modes import modal_constants, mode_shapes
from modelgen.parameters import parameter_names

L, EI, RHO = 1.005, 47.25, 2.032  # paper-sim's link (Table 1), without its payload: a bare cantilever on a light hub


def _bare(n: int) -> modelgen.Model:
    return modelgen.load(Geometry(name="bare", length=L, flexural_rigidity=EI, linear_density=RHO, hub_inertia=1.8e-3, modes=n))


def test_the_stiffening_integrals_give_southwells_coefficient() -> None:
    # a uniform cantilever spun about its root: omega^2 = omega_0^2 + K Omega^2, with K = 1.1933 for its first bending mode
    # (the Southwell coefficient of zero hub radius; Wright, Smith, Thresher & Wang, J. Appl. Mech. 49(1), 1982); here, with
    # the mode's own shape, K = (rho/2 int (L^2 - x^2) phi'^2) / (rho int phi^2) = P_11 / (2 N_11). Higher modes stiffen more.
    g = Geometry(name="b", length=1.0, flexural_rigidity=1.0, linear_density=1.0, hub_inertia=1e6, mode_shapes="clamped-free", modes=3)
    c = modal_constants(mode_shapes(g))
    K = [c.P[j, j] / (2 * c.N[j, j]) for j in range(3)]
    assert K[0] == pytest.approx(1.1933, rel=1e-4)
    assert K[0] < K[1] < K[2]  # measured 6.478 and 17.86


@pytest.mark.parametrize("role", ["nonlinear_rhs_jacobian", "nonlinear_paper_rhs_jacobian"])
def test_both_nonlinear_models_linearise_to_the_linear_one(role: str) -> None:
    model = modelgen.load("paper-sim", modes=3)
    J = np.asarray(model.functions.call(role, model.parameters, np.zeros(8), 0.0)[0])
    np.testing.assert_allclose(J, model.A, rtol=1e-12, atol=1e-12 * np.abs(model.A).max())


def test_the_stiffened_model_conserves_its_energy() -> None:
    # undamped and unforced, spun at 3 rad/s with the link bent: T + V (the stiffening term included) stays put
    model = _bare(3)
    f, p = model.functions, model.parameters
    X0 = np.array([0.0, 0.02, -0.004, 0.001, 3.0, 0.5, 0.0, -0.2])
    sol = solve_ivp(lambda t, X: np.asarray(f.call("nonlinear_rhs", p, X, 0.0)[0]).ravel(), (0.0, 2.0), X0, method="DOP853",
                    rtol=1e-12, atol=1e-14, t_eval=np.linspace(0, 2.0, 201))
    energy = np.array([float(np.asarray(f.call("nonlinear_energy", p, X)[0]).ravel()[0]) for X in sol.y.T])
    assert np.abs(energy - energy[0]).max() <= 1e-9 * energy[0]
    # and the stiffening is there: the same state in the paper's model accelerates the deflections differently
    a = np.asarray(f.call("nonlinear_rhs", p, X0, 0.0)[0]).ravel()
    b = np.asarray(f.call("nonlinear_paper_rhs", p, X0, 0.0)[0]).ravel()
    assert np.abs(a[5:] - b[5:]).max() > 1.0


def _prescribed_tip(model: modelgen.Model, role: str, theta, t: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The tip's angle seen from the hub, ``atan2(w(L), L + u_c(L))``, with the hub angle prescribed: the plant's torque
    is the one that gives ``thetaddot`` (its accelerations are affine in the torque). ``role`` ``"large"``: the
    exact-kinematics model (:mod:`modelgen.large`), its own tip angle."""
    f, p, n = model.functions, model.parameters, model.n
    n1 = n + 1
    large = large_deflection_functions(model) if role == "large" else None

    def call(X: np.ndarray, tau: float) -> np.ndarray:
        if large is not None:
            return np.asarray(large["rhs"](X, tau)).ravel()
        return np.asarray(f.call(role, p, X, tau)[0]).ravel()

    def rhs(s: float, z: np.ndarray) -> np.ndarray:
        X = np.concatenate([[theta(s)], z[:n], [theta(s, 1)], z[n:]])
        a = call(X, 0.0)
        b = call(X, 1.0) - a
        xd = a + b * (theta(s, 2) - a[n1]) / b[n1]
        return np.concatenate([xd[1:n1], xd[n1 + 1 :]])

    sol = solve_ivp(rhs, (0.0, t[-1]), np.zeros(2 * n), t_eval=t, method="DOP853", rtol=1e-10, atol=1e-13, max_step=3e-3)
    if large is not None:
        states = np.vstack([np.zeros(t.size), sol.y[:n], np.zeros((n1, t.size))]).T
        return np.array([float(large["tip_angle"](X)) for X in states])
    names = parameter_names(n)
    phi_L = np.array([p[names.index(f"phiL_{j}")] for j in range(1, n1)])
    Q = np.array([[p[names.index(f"Q_{min(i, j)}_{max(i, j)}")] for j in range(1, n1)] for i in range(1, n1)])
    delta = sol.y[:n].T
    return np.arctan2(delta @ phi_L, L - 0.5 * np.einsum("ki,ij,kj->k", delta, Q, delta))


@pytest.mark.slow
def test_the_stiffened_plant_is_closer_to_a_finite_element_engine() -> None:
    # Exudyn's geometrically exact ANCF cable elements (an optional test dependency: pip install "sflm[fe]"), clamped at a
    # hub turned 0.5 m (at the tip) in 0.6 s by a quintic; converged (8 -> 16 elements moves its tip angle by 2e-4 of its
    # peak). Measured, max |L (psi - psi_FE)| / move: linear 7.1e-4, stiffened 3.0e-4, the paper's P4 2.9e-3
    exu = pytest.importorskip("exudyn")
    from exudyn.itemInterface import (MarkerNodeCoordinate, NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D,
                                      ObjectConnectorCoordinate, SensorNode)

    T, D = 0.6, 0.5

    def theta(s: float, k: int = 0) -> float:
        u = min(max(s / T, 0.0), 1.0)
        if k == 0:
            return D / L * (10 * u**3 - 15 * u**4 + 6 * u**5)
        if s > T:
            return 0.0
        return D / L * ((30 * u**2 - 60 * u**3 + 30 * u**4) / T if k == 1 else (60 * u - 180 * u**2 + 120 * u**3) / T**2)

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround(referenceCoordinates=[0, 0, 0])), coordinate=0))
    elements, h, t_end = 8, 1e-3, 1.0
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * L / elements, 0, 1, 0])) for i in range(elements + 1)]
    for i in range(elements):
        mbs.AddObject(ObjectANCFCable2D(massPerLength=RHO, bendingStiffness=EI, axialStiffness=1e6 * EI / L**2, length=L / elements,
                                        nodeNumbers=[nodes[i], nodes[i + 1]]))
    root = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=k)) for k in range(4)]
    for k in (0, 1):
        mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground, root[k]]))
    # the root's slope turned with the hub: (cos theta, sin theta), as displacements of the reference (1, 0)
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground, root[2]], offsetUserFunction=lambda m, s, i, o: np.cos(theta(s)) - 1.0,
                                            offsetUserFunction_t=lambda m, s, i, o: -np.sin(theta(s)) * theta(s, 1)))
    mbs.AddObject(ObjectConnectorCoordinate(markerNumbers=[ground, root[3]], offsetUserFunction=lambda m, s, i, o: np.sin(theta(s)),
                                            offsetUserFunction_t=lambda m, s, i, o: np.cos(theta(s)) * theta(s, 1)))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=nodes[-1], storeInternal=True, outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_end / h))
    settings.timeIntegration.endTime = t_end
    settings.timeIntegration.generalizedAlpha.spectralRadius = 1.0
    settings.timeIntegration.verboseMode = 0
    settings.show.statistics = False
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = h
    mbs.SolveDynamic(settings)
    data = mbs.GetSensorStoredData(sensor)
    t = data[:, 0]
    psi_fe = np.arctan2(data[:, 2], data[:, 1]) - np.array([theta(s) for s in t])
    model = _bare(4)
    distance = {role: float(np.abs(L * (_prescribed_tip(model, role, theta, t) - psi_fe)).max() / D)
                for role in ("linear_rhs", "nonlinear_rhs", "nonlinear_paper_rhs", "large")}
    assert distance["nonlinear_rhs"] < 0.6 * distance["linear_rhs"]  # measured 3.0e-4 against 7.1e-4
    assert distance["nonlinear_rhs"] < 0.2 * distance["nonlinear_paper_rhs"]  # the paper's softening alone: 2.9e-3
    assert distance["nonlinear_rhs"] < 5e-4
    # the exact kinematics (plant nonlinear-large): measured 7.1e-5 here, and 2.4e-5 against 16 elements (153 s) where
    # the stiffened model stays at 2.5e-4 -- with 8 elements most of what is left is the engine's own discretisation
    assert distance["large"] < 0.3 * distance["nonlinear_rhs"] and distance["large"] < 1e-4, distance
    # as modes are added the stiffened plant converges (the change from 4 to 6 modes a tenth of that from 2 to 4, or
    # less), to a tip this close to the engine's: what is left is the model's truncation at second order, not the modes'
    psi = {n: _prescribed_tip(_bare(n), "nonlinear_rhs", theta, t) for n in (2, 6)}
    psi[4] = _prescribed_tip(model, "nonlinear_rhs", theta, t)
    assert np.abs(psi[6] - psi[4]).max() < 0.1 * np.abs(psi[4] - psi[2]).max()
    assert float(np.abs(L * (psi[6] - psi_fe)).max() / D) < 5e-4


def test_the_large_deflection_model_linearises_to_the_linear_one() -> None:
    import casadi as ca

    model = modelgen.load("paper-sim", modes=3)  # the payload's mass and inertia, the hub's and Rayleigh damping included
    X = ca.SX.sym("X", 8)
    rhs = large_deflection_functions(model)["rhs"]
    J = ca.Function("J", [X], [ca.jacobian(rhs(X, 0.0), X)])(np.zeros(8))
    np.testing.assert_allclose(np.asarray(J), model.A, rtol=1e-11, atol=1e-11 * np.abs(model.A).max())
    Bu = np.asarray(rhs(np.zeros(8), 1.0)).ravel()
    np.testing.assert_allclose(Bu, model.B.ravel(), rtol=1e-11, atol=1e-11 * np.abs(model.B).max())


def test_the_large_deflection_model_differs_from_the_stiffened_one_at_third_order() -> None:
    # both are the same Lagrangian to second order in the deflections: their accelerations differ by terms cubic in
    # (delta, deltadot, thetadot) -- halving the state divides the difference by 8
    model = modelgen.load("paper-sim", modes=2)
    rhs = large_deflection_functions(model)["rhs"]
    X = np.array([0.3, 0.04, -0.01, 2.0, 0.6, -0.3])
    differences = []
    for scale in (1.0, 0.5, 0.25):
        a = np.asarray(rhs(scale * X, 0.0)).ravel()
        b = np.asarray(model.functions.call("nonlinear_rhs", model.parameters, scale * X, 0.0)[0]).ravel()
        differences.append(np.abs(a - b)[3:].max())
    assert 6.5 < differences[1] / differences[2] < 9.5 and 6.0 < differences[0] / differences[1] < 10.0, differences


def test_the_large_deflection_model_conserves_its_energy() -> None:
    model = _bare(3)  # no damping: the energy T + V of the exact kinematics stays put, the link bent 10 % of L and spun
    functions = large_deflection_functions(model)
    X0 = np.array([0.0, 0.08, -0.01, 0.003, 3.0, 0.5, 0.0, -0.2])
    sol = solve_ivp(lambda t, X: np.asarray(functions["rhs"](X, 0.0)).ravel(), (0.0, 0.3), X0, method="DOP853", rtol=1e-12,
                    atol=1e-14, t_eval=np.linspace(0, 0.3, 31))  # a few periods of the first mode (20 s for 1 s: CasADi's VM)
    energy = np.array([float(functions["energy"](X)) for X in sol.y.T])
    assert np.abs(energy - energy[0]).max() <= 1e-9 * energy[0]
    # the foreshortening's integration matrix is exact on polynomials below its degree
    s, _, cumulative = gauss_nodes(2.0)
    np.testing.assert_allclose(cumulative @ s**5, s**6 / 6, rtol=0, atol=1e-13)
    from types import SimpleNamespace

    with pytest.raises(modelgen.ModelError, match="at most"):  # refused before anything is built
        large_deflection_functions(SimpleNamespace(n=MAX_MODES + 1))  # type: ignore[arg-type]


def test_the_large_deflection_plant_on_the_command_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    import json

    from sflm.cli import main

    assert main(["simulate", "paper-sim", "--plant", "nonlinear-large", "--t-end", "6", "--rate", "200", "--out", str(tmp_path),
                 "--json"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["plant"]["kind"] == "nonlinear-large" and summary["max_tracking_error"] < 0.01


def test_the_paper_plant_stays_available(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from inversion import invert, trajectory_from_spec
    from simulation import simulate

    model = modelgen.load("paper-sim")
    r = invert(model, trajectory_from_spec("paper-sim"))
    stiff = simulate(model, r, plant="nonlinear", controller="none", t_end=6.0, rate=200.0)
    paper = simulate(model, r, plant="nonlinear-paper", controller="none", t_end=6.0, rate=200.0)
    assert stiff.summary["plant"]["kind"] == "nonlinear" and paper.summary["plant"]["kind"] == "nonlinear-paper"
    assert 0 < np.abs(stiff.y - paper.y).max() < 1e-2 * 1.57  # a slow move: the two differ, a little

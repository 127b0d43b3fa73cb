"""The symbolic derivation: SymPy's Lagrange equations against the closed forms of docs/method.md."""

from __future__ import annotations

import pytest
import sympy as sp

from modelgen.errors import ModelError
from modelgen.lagrange import derive, lagrange_derivation, reduce_link_integrals


@pytest.mark.parametrize("n", [1, 2, 3])
def test_linear_mass_stiffness_damping_match_method(n: int) -> None:
    m = derive(n)
    P = m.params
    L, rho, EI = P["L"], P["rho"], P["EI"]
    I_h, m_t, I_t = P["I_h"], P["m_t"], P["I_t"]
    # docs/method.md section 1: J, m_j, M_d,ij, K_d,ij; (P7) C_D = (2 zeta/omega_1) K_B + diag(b_h, 0..) + Dm (modal
    # damping's matrix, zero for Rayleigh damping)
    J = I_h + rho * L**3 / 3 + m_t * L**2 + I_t
    assert sp.simplify(m.M[0, 0] - J) == 0
    for j in range(1, n + 1):
        mj = rho * P[f"S_{j}"] + m_t * L * P[f"phiL_{j}"] + I_t * P[f"dphiL_{j}"]
        assert sp.expand(m.M[0, j] - mj) == 0 and sp.expand(m.M[j, 0] - mj) == 0
        for i in range(1, n + 1):
            key = f"{min(i, j)}_{max(i, j)}"
            Md = rho * P[f"N_{key}"] + m_t * P[f"phiL_{i}"] * P[f"phiL_{j}"] + I_t * P[f"dphiL_{i}"] * P[f"dphiL_{j}"]
            assert sp.expand(m.M[i, j] - Md) == 0
            assert sp.expand(m.K[i, j] - EI * P[f"G_{key}"]) == 0
            assert sp.expand(m.C[i, j] - 2 * P["zeta"] / P["omega_1"] * EI * P[f"G_{key}"] - P[f"Dm_{key}"]) == 0
        assert sp.expand(m.C[0, j] - P[f"Dm_0_{j}"]) == 0 and sp.expand(m.C[j, 0] - P[f"Dm_0_{j}"]) == 0
    assert all(m.K[0, k] == 0 and m.K[k, 0] == 0 for k in range(n + 1))
    assert sp.expand(m.C[0, 0] - P["b_h"] - P["Dm_0_0"]) == 0
    assert m.H == sp.Matrix([1] + [0] * n)
    # the output y = x_out theta + w(x_out): the tip (x_out = L, phiX = phiL) unless loaded with output_at
    assert m.D == sp.Matrix([[P["x_out"]] + [P[f"phiX_{j}"] for j in range(1, n + 1)]])


@pytest.mark.parametrize("n", [1, 2, 3])
def test_nonlinear_linearised_at_rest_is_linear(n: int) -> None:
    m = derive(n)
    rest = {s: 0 for s in m.q + m.qd}
    for M_nl, f_nl in ((m.M_nl, m.f_nl), (m.M_nl_paper, m.f_nl_paper)):  # stiffened, and the paper's (P4)
        assert sp.simplify(M_nl.subs(rest) - m.M) == sp.zeros(n + 1)
        K_lin = f_nl.jacobian(m.q).subs(rest)
        C_lin = f_nl.jacobian(m.qd).subs(rest)
        assert sp.simplify(K_lin - m.K) == sp.zeros(n + 1)
        assert sp.simplify(C_lin - m.C) == sp.zeros(n + 1)
        assert f_nl.subs(rest) == sp.zeros(n + 1, 1)


@pytest.mark.parametrize("variant", ["paper", "stiffened"])
def test_nonlinear_terms_are_the_rotating_frame_ones(variant: str) -> None:
    # (P4) with one mode: J(delta) = J + a delta^2 and the centrifugal softening -a thetadot^2 delta in the flexible
    # equation, a = rho N_11 + m_t phiL_1^2. With the foreshortening (docs/method.md section 1a) the stiffening takes
    # rho P_11 / 2 + m_t L Q_11 off a: the same terms with a_s = a - rho P_11/2 - m_t L Q_11
    m = derive(1)
    P = m.params
    th, d = m.q
    thd, dd = m.qd
    a = P["rho"] * P["N_1_1"] + P["m_t"] * P["phiL_1"] ** 2
    if variant == "stiffened":
        a = a - P["rho"] * P["P_1_1"] / 2 - P["m_t"] * P["L"] * P["Q_1_1"]
        M_nl, f_nl = m.M_nl, m.f_nl
    else:
        M_nl, f_nl = m.M_nl_paper, m.f_nl_paper
    assert sp.expand(M_nl[0, 0] - m.M[0, 0] - a * d**2) == 0
    f1 = sp.expand(f_nl[1] - (m.K[1, 1] * d + m.C[1, 0] * thd + m.C[1, 1] * dd))  # C[1, 0]: modal damping's coupling
    assert sp.expand(f1 + a * thd**2 * d) == 0
    f0 = sp.expand(f_nl[0] - m.C[0, 0] * thd - m.C[0, 1] * dd)
    assert sp.expand(f0 - 2 * a * d * dd * thd) == 0


def test_mass_matrix_symmetric_and_energy_consistent() -> None:
    m = derive(2)
    assert sp.expand(m.M_nl - m.M_nl.T) == sp.zeros(3)
    qd = sp.Matrix(m.qd)
    # T_lin = qdot^T M qdot / 2, V = q^T K q / 2
    assert sp.expand(m.energies["T_lin"] - (qd.T * m.M * qd)[0] / 2) == 0
    q = sp.Matrix(m.q)
    assert sp.expand(m.energies["V"] - (q.T * m.K * q)[0] / 2) == 0


def test_unknown_integrand_is_refused() -> None:
    x = sp.Symbol("x")
    phi = [sp.Function("phi_1")]
    params = {"L": sp.Symbol("L"), "S_1": sp.Symbol("S_1")}
    with pytest.raises(ModelError, match="cannot integrate"):
        reduce_link_integrals(sp.Integral(sp.sin(x) * phi[0](x), (x, 0, params["L"])), x, phi, params)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_the_assembled_equations_are_lagranges(n: int) -> None:
    # derive() writes the matrices from their structure (M_00 + delta^T W delta); lagrange_derivation() differentiates the
    # energies of docs/method.md symbolically: the same equations, term by term, for both nonlinear models and (P8)
    fast, reference = derive(n), lagrange_derivation(n)
    for name in ("M", "K", "C", "D", "H", "M_nl", "f_nl", "M_nl_paper", "f_nl_paper", "lagrange_nonlinear", "lagrange_linear",
                 "W", "W_paper"):
        difference = sp.expand(getattr(fast, name) - getattr(reference, name))
        assert difference == sp.zeros(*difference.shape), name
    for name, energy in reference.energies.items():
        assert sp.expand(fast.energies[name] - energy) == 0, name
    assert fast.W != fast.W_paper  # the stiffening is there to compare

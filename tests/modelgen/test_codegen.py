"""Generated functions: compiled C against SymPy and NumPy, matrix order, plain C, the Jacobian."""

from __future__ import annotations

import subprocess
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
import sympy as sp

import modelgen
from modelgen.abi import COMPILE_FLAGS, ROLES, compiler_command
from modelgen.cache import ensure_model_functions
from modelgen.geometry import Geometry
from modelgen.lagrange import lagrange_derivation
from modelgen.modes import modal_constants, mode_shapes
from modelgen.parameters import parameter_values
from modelgen.statespace import state_space

pytestmark = pytest.mark.skipif(compiler_command() is None, reason="needs a C compiler")


def random_geometry(rng: np.random.Generator, n: int) -> Geometry:
    return Geometry(
        name="random",
        length=rng.uniform(0.2, 2.0),
        flexural_rigidity=rng.uniform(0.5, 100.0),
        linear_density=rng.uniform(0.2, 5.0),
        hub_inertia=rng.uniform(1e-3, 0.1),
        hub_viscous_damping=rng.uniform(0.0, 0.5),
        payload_mass=rng.uniform(0.0, 0.5),
        payload_inertia=rng.uniform(0.0, 0.05),
        damping_ratio=rng.uniform(0.0, 0.05),
        modes=n,
    )


def random_point(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, float, float]:
    """A parameter vector (real shapes, randomly rescaled), a state, a torque and an acceleration."""
    g = random_geometry(rng, n)
    shapes = mode_shapes(g).scaled(rng.uniform(0.3, 3.0, n) * rng.choice([-1.0, 1.0], n))
    p = parameter_values(g, modal_constants(shapes), omega_1=rng.uniform(5.0, 50.0))
    X = rng.normal(size=2 * (n + 1)) * np.r_[np.full(n + 1, 0.3), np.full(n + 1, 2.0)]
    return p, X, float(rng.normal()), float(rng.normal())


class SympyReference:
    """The roles evaluated from the SymPy expressions (lambdify) and NumPy linear algebra: the Lagrangian differentiated
    by SymPy (:func:`modelgen.lagrange.lagrange_derivation`), independent of the assembly the generated code is built from."""

    def __init__(self, n: int):
        m = lagrange_derivation(n)
        self.n = n
        args = [list(m.params.values()), m.q + m.qd, m.tau]
        self.second_order = sp.lambdify([args[0]], [m.M, m.K, m.C, m.D, m.H], "numpy")
        self.nonlinear = sp.lambdify(args, [m.M_nl, m.f_nl], "numpy")
        self.paper = sp.lambdify(args, [m.M_nl_paper, m.f_nl_paper], "numpy")
        self.nonlinear_energy = sp.lambdify(args[:2], m.energies["T"] + m.energies["V"], "numpy")

    def evaluate(self, p: np.ndarray, X: np.ndarray, tau: float, yddot: float) -> dict[str, list[np.ndarray]]:
        n1 = self.n + 1
        M, K, C, D, H = (np.asarray(a, dtype=float) for a in self.second_order(p))
        D, H = D.reshape(-1), H.reshape(-1)
        ss = state_space(M, K, C, D, H)
        Mnl, fnl = (np.asarray(a, dtype=float) for a in self.nonlinear(p, X, tau))
        qdd = np.linalg.solve(Mnl, H * tau - fnl.reshape(-1))
        Mp, fp = (np.asarray(a, dtype=float) for a in self.paper(p, X, tau))
        qdd_paper = np.linalg.solve(Mp, H * tau - fp.reshape(-1))
        q, qd = X[:n1], X[n1:]
        return {
            "M": [M], "K": [K], "C": [C], "D": [D], "H": [H],
            "A": [ss["A"]], "B": [ss["B"]], "C_out": [ss["C_out"]], "CAB": [ss["CAB"]], "CA2": [ss["CA2"]],
            "AI": [ss["AI"]], "BI": [ss["BI"]], "T": [ss["T"]], "Tinv": [ss["Tinv"]],
            "inverse_torque": [np.asarray((yddot - ss["CA2"] @ X) / ss["CAB"])],
            "linear_rhs": [ss["A"] @ X + ss["B"] * tau],
            "nonlinear_rhs": [np.r_[qd, qdd]],
            "nonlinear_paper_rhs": [np.r_[qd, qdd_paper]],
            "nonlinear_energy": [np.asarray(self.nonlinear_energy(p, X))],
            "tip_output": [np.asarray(D @ q), np.asarray(D @ qd)],
            "energy": [np.asarray(0.5 * qd @ M @ qd + 0.5 * q @ K @ q)],
        }


def close(actual: np.ndarray, desired: np.ndarray, rtol: float) -> None:
    """Normwise relative agreement (entries compared to the largest entry of ``desired``)."""
    a, d = np.asarray(actual, dtype=float).reshape(-1), np.asarray(desired, dtype=float).reshape(-1)
    assert a.shape == d.shape
    scale = max(np.abs(d).max(initial=0.0), 1e-300)
    assert np.abs(a - d).max(initial=0.0) <= rtol * scale, f"{np.abs(a - d).max():.3e} vs scale {scale:.3e}"


@pytest.mark.parametrize("n", [1, 2, 3])
def test_compiled_functions_match_sympy(n: int, rng: np.random.Generator) -> None:
    fns = ensure_model_functions(n)
    assert fns.compiled
    ref = SympyReference(n)
    for _ in range(5):
        p, X, tau, yddot = random_point(rng, n)
        expected = ref.evaluate(p, X, tau, yddot)
        args = {"p": p, "X": X, "tau": tau, "yddot": yddot}
        for role, outs in expected.items():
            inputs = [args[name] for name in ROLES[role][0]]
            got = fns.call(role, *inputs)
            for g, e in zip(got, outs):
                # 1e-12 of the largest entry; the largest seen is 2e-13 (CAB, AI: two different
                # solves of M, whose condition number reaches ~1e5 for these random links)
                close(g, e, 1e-12)


@pytest.mark.parametrize("n", [1, 2])
def test_external_library_matches_in_process_casadi(n: int, rng: np.random.Generator) -> None:
    fns = ensure_model_functions(n)
    inproc = ca.FileDeserializer(str(fns.folder / fns.manifest["serialized"])).unpack()
    p, X, tau, yddot = random_point(rng, n)
    args = {"p": p, "X": X, "tau": tau, "yddot": yddot}
    for f in inproc:
        role = f.name().removeprefix("sflm_")
        if role == "inverse_torque_batch":
            continue
        inputs = [args[name] for name in ROLES[role][0]]
        mine = [np.array(v) for v in f.call(inputs)]
        for a, b in zip(fns.call(role, *inputs), mine):
            close(a, b, 1e-14)


def test_matrix_order_non_square_non_symmetric(rng: np.random.Generator) -> None:
    # CasADi is column-major: a transposition anywhere would break these identities.
    fns = ensure_model_functions(2)
    p, X, tau, _ = random_point(rng, 2)
    m = fns.matrices(p)
    n1 = 3
    q, qd = X[:n1], X[n1:]
    y = m["T"] @ X  # [y; ydot; delta; deltadot]
    np.testing.assert_allclose(y, np.r_[m["D"] @ q, m["D"] @ qd, q[1:], qd[1:]], rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(m["Tinv"] @ y, X, rtol=1e-12, atol=1e-12)
    assert not np.allclose(m["T"], m["T"].T)
    assert not np.allclose(m["AI"], m["AI"].T)
    # the upper half of A is [0, I]: qdot; the lower is M^-1(...) -- a transpose would move the identity
    np.testing.assert_array_equal(m["A"][:n1, n1:], np.eye(n1))
    np.testing.assert_array_equal(m["A"][:n1, :n1], 0.0)
    (Xdot,) = fns.call("linear_rhs", p, X, tau)
    np.testing.assert_allclose(Xdot.reshape(-1), m["A"] @ X + m["B"] * tau, rtol=1e-12)
    J, Jtau = fns.call("nonlinear_rhs_jacobian", p, X, tau)
    assert J.shape == (6, 6) and Jtau.shape == (6, 1)
    np.testing.assert_array_equal(J[:n1, n1:], np.eye(n1))
    # a 2x3 test function through the same buffer path
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [ca.vertcat(ca.horzcat(x[0], x[1], x[2]), ca.horzcat(10 * x[0], 20 * x[1], 30 * x[2]))])
    from modelgen.compiled import FastCall

    (out,) = FastCall(f)(np.array([1.0, 2.0, 3.0]))
    np.testing.assert_array_equal(out, [[1, 2, 3], [10, 40, 90]])


def test_nonlinear_jacobian_matches_algorithmic_differentiation(rng: np.random.Generator) -> None:
    fns = ensure_model_functions(2)
    f = ca.FileDeserializer(str(fns.folder / fns.manifest["serialized"])).unpack()
    rhs = next(g for g in f if g.name() == "sflm_nonlinear_rhs")
    pp, XX, tt = ca.MX.sym("p", rhs.size1_in(0)), ca.MX.sym("X", 6), ca.MX.sym("tau")
    out = rhs(pp, XX, tt)
    ad = ca.Function("ad", [pp, XX, tt], [ca.jacobian(out, XX), ca.jacobian(out, tt)])
    for _ in range(3):
        p, X, tau, _ = random_point(rng, 2)
        J, Jt = fns.call("nonlinear_rhs_jacobian", p, X, tau)
        Jad, Jtad = (np.array(v) for v in ad(p, X, tau))
        close(J, Jad, 1e-12)
        close(Jt, Jtad, 1e-12)


@pytest.mark.parametrize("preset", ["paper-sim", "near-non-hyperbolic", "paper-exp"])
def test_jacobian_at_rest_is_A(preset: str) -> None:
    model = modelgen.load(preset)
    J, Jtau = model.functions.call("nonlinear_rhs_jacobian", model.parameters, np.zeros(2 * (model.n + 1)), 0.0)
    close(J, model.A, 1e-13)
    close(Jtau.reshape(-1), model.B, 1e-13)


def test_batch_inverse_torque_matches_single_calls(rng: np.random.Generator) -> None:
    model = modelgen.load("paper-sim")
    N = 1300  # not a multiple of the chunk
    X = rng.normal(size=(N, 6))
    ydd = rng.normal(size=N)
    tau = model.functions.inverse_torque(model.parameters, X, ydd)
    expected = (ydd - X @ model.CA2) / model.CAB
    np.testing.assert_allclose(tau, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    singles = [model.functions.call("inverse_torque", model.parameters, X[i], ydd[i])[0].item() for i in (0, 700, N - 1)]
    np.testing.assert_allclose(singles, expected[[0, 700, N - 1]], rtol=1e-12)
    (rhs,) = model.functions.map("linear_rhs", model.parameters, X[:5], ydd[:5])
    np.testing.assert_allclose(rhs, X[:5] @ model.A.T + np.outer(ydd[:5], model.B), rtol=1e-12, atol=1e-10)


C_MAIN = r"""
#include <stdio.h>
#include "sflm_n2.h"

/* one call of a generated function with its own work arrays (arg and res of their full
   sizes: the function may use the entries beyond its inputs and outputs as work space) */
#define CALL(f, out, ...) do { \
    const casadi_real* arg[f##_SZ_ARG] = {__VA_ARGS__}; \
    casadi_real* res[f##_SZ_RES] = {out}; \
    casadi_int iw[f##_SZ_IW + 1]; \
    casadi_real w[f##_SZ_W + 1]; \
    if (f(arg, res, iw, w, 0)) return 1; \
} while (0)

int main(void) {
    static const casadi_real p[%(np)d] = {%(p)s};
    static const casadi_real X[6] = {%(X)s};
    static const casadi_real tau = %(tau)s;
    casadi_real A[36], Xdot[6];
    CALL(sflm_A, A, p);
    CALL(sflm_nonlinear_rhs, Xdot, p, X, &tau);  /* a function of the state and the input */
    for (int i = 0; i < 36; ++i) printf("%%.17g\n", A[i]);
    for (int i = 0; i < 6; ++i) printf("%%.17g\n", Xdot[i]);
    return 0;
}
"""


def test_plain_c_program_calls_generated_functions(tmp_path: Path, rng: np.random.Generator) -> None:
    model = modelgen.load("paper-sim")
    if not model.functions.compiled:
        pytest.skip("needs a C compiler")
    folder = model.functions.folder
    X = rng.normal(size=6) * [0.5, 0.01, 0.01, 2.0, 0.1, 0.1]
    tau = float(rng.normal())
    main = tmp_path / "main.c"
    main.write_text(C_MAIN % {"np": model.parameters.size, "p": ", ".join(repr(float(v)) for v in model.parameters),
                              "X": ", ".join(repr(float(v)) for v in X), "tau": repr(tau)})
    exe = tmp_path / "calls"
    flags = [f for f in COMPILE_FLAGS if f not in ("-shared", "-fPIC")]
    build = subprocess.run(
        [compiler_command(), *flags, f"-I{folder}", "-o", str(exe), str(main), str(folder / "sflm_n2.c"), "-lm"],
        capture_output=True, text=True,
    )
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    values = np.array([float(v) for v in run.stdout.split()])
    np.testing.assert_array_equal(values[:36].reshape(6, 6, order="F"), model.A)  # column-major, bit for bit
    (expected,) = model.functions.call("nonlinear_rhs", model.parameters, X, tau)
    np.testing.assert_allclose(values[36:], np.asarray(expected).reshape(-1), rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(values[36:39], X[3:])  # thetadot, deltadot: the state reached the function

"""The SymPy -> CasADi converter, including the functions CasADi spells differently."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
import sympy as sp

from modelgen.sympy_casadi import to_casadi

x, y = sp.symbols("x y", real=True)

EXPRESSIONS = [
    x**2 * y - 3 * x / y + sp.Rational(1, 3),
    sp.sqrt(x**2 + y**2) + x ** (-3),
    sp.sin(x) * sp.cos(y) + sp.exp(-x) * sp.tanh(y) + sp.log(1 + x**2),
    sp.Abs(x - y) + sp.sign(y) * x,
    sp.Piecewise((x, x < 0), (y**2, x < 1), (x * y, True)),
    sp.Max(x, y) - sp.Min(x, 2 * y) + sp.Heaviside(x - y),
    sp.atan2(y, x) + sp.pi,
    sp.Abs(x) ** sp.Rational(3, 2) + (x + y) ** 5 - y ** (-2),
]


@pytest.mark.parametrize("expr", EXPRESSIONS, ids=[str(i) for i in range(len(EXPRESSIONS))])
def test_matches_sympy_numerically(expr: sp.Expr, rng: np.random.Generator) -> None:
    X, Y = ca.SX.sym("x"), ca.SX.sym("y")
    f = ca.Function("f", [X, Y], [to_casadi(expr, {x: X, y: Y})])
    g = sp.lambdify([x, y], expr, "numpy")
    for a, b in rng.uniform(-2, 2, size=(25, 2)):
        if abs(a - b) < 1e-9:
            continue
        expected = float(g(a, b))
        got = float(f(a, b))
        assert got == pytest.approx(expected, rel=1e-13, abs=1e-13)


def test_matrices_and_unknown_symbols() -> None:
    X = ca.SX.sym("x")
    M = to_casadi(sp.Matrix([[x, 2 * x], [3, x**2]]), {x: X})
    assert M.shape == (2, 2)
    assert np.array(ca.Function("m", [X], [M])(2.0)).tolist() == [[2.0, 4.0], [3.0, 4.0]]
    with pytest.raises(KeyError, match="no CasADi symbol"):
        to_casadi(x + y, {x: X})
    with pytest.raises(NotImplementedError):
        to_casadi(sp.besselj(0, x), {x: X})

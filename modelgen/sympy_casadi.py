"""Convert SymPy expressions to CasADi SX expressions.

There is no official bridge between the two; this is a small tree walk over the SymPy
expression, memoised so that shared subexpressions become shared SX nodes. Functions
CasADi spells differently are mapped (``Abs -> fabs``, ``sign -> sign``,
``Piecewise -> if_else``, ``Min/Max -> fmin/fmax``). Dynamic symbols must have been
replaced by plain symbols first (``modelgen.lagrange`` does so).
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

import casadi as ca
import sympy as sp

__all__ = ["SympyToCasadi", "to_casadi"]

_UNARY: dict[type, Callable[[Any], Any]] = {
    sp.sin: ca.sin,
    sp.cos: ca.cos,
    sp.tan: ca.tan,
    sp.asin: ca.asin,
    sp.acos: ca.acos,
    sp.atan: ca.atan,
    sp.sinh: ca.sinh,
    sp.cosh: ca.cosh,
    sp.tanh: ca.tanh,
    sp.exp: ca.exp,
    sp.log: ca.log,
    sp.Abs: ca.fabs,
    sp.sign: ca.sign,
    sp.floor: ca.floor,
    sp.ceiling: ca.ceil,
    sp.erf: ca.erf,
}


class SympyToCasadi:
    """Memoising converter of SymPy expressions to CasADi.

    Parameters
    ----------
    symbols : Mapping[sympy.Symbol, casadi.SX]
        The SX (scalar) expression each free symbol stands for.
    """

    def __init__(self, symbols: Mapping[sp.Symbol, Any]):
        self._symbols = dict(symbols)
        self._memo: dict[sp.Basic, Any] = {}

    def __call__(self, expr: sp.Basic) -> Any:
        """The SX expression of ``expr`` (a scalar SymPy expression)."""
        return self._convert(sp.sympify(expr))

    def matrix(self, mat: sp.MatrixBase) -> Any:
        """An SX matrix of the same shape (entries converted one by one).

        Parameters
        ----------
        mat : sp.MatrixBase
            A SymPy matrix.
        """
        rows, cols = mat.shape
        out = ca.SX(rows, cols)
        for i in range(rows):
            for j in range(cols):
                out[i, j] = self._convert(mat[i, j])
        return out

    def _convert(self, e: sp.Basic) -> Any:
        cached = self._memo.get(e)
        if cached is not None:
            return cached
        out = self._build(e)
        self._memo[e] = out
        return out

    def _build(self, e: sp.Basic) -> Any:
        if e.is_Symbol:
            try:
                return self._symbols[e]
            except KeyError:
                raise KeyError(f"no CasADi symbol given for {e}") from None
        if e.is_Integer:
            return ca.SX(float(int(e)))
        if e.is_Rational or e.is_Float:
            return ca.SX(float(e))
        if e is sp.pi:
            return ca.SX(float(sp.pi))
        if e is sp.E:
            return ca.SX(float(sp.E))
        if e is sp.true:
            return ca.SX(1.0)
        if e is sp.false:
            return ca.SX(0.0)
        if e.is_Add:
            terms = [self._convert(a) for a in e.args]
            total = terms[0]
            for t in terms[1:]:
                total = total + t
            return total
        if e.is_Mul:
            factors = [self._convert(a) for a in e.args]
            prod = factors[0]
            for f in factors[1:]:
                prod = prod * f
            return prod
        if e.is_Pow:
            base, exp = e.args
            b = self._convert(base)
            if exp.is_Integer:
                k = int(exp)
                if k == 2:
                    return b * b
                if k == -1:
                    return 1.0 / b
                return ca.power(b, float(k)) if k > 0 else 1.0 / ca.power(b, float(-k))
            if exp == sp.Rational(1, 2):
                return ca.sqrt(b)
            return ca.power(b, self._convert(exp))
        if isinstance(e, sp.Piecewise):
            return self._piecewise(e)
        if isinstance(e, (sp.Min, sp.Max)):
            op = ca.fmin if isinstance(e, sp.Min) else ca.fmax
            args = [self._convert(a) for a in e.args]
            out = args[0]
            for a in args[1:]:
                out = op(out, a)
            return out
        if isinstance(e, sp.Heaviside):
            x = self._convert(e.args[0])
            return ca.if_else(x > 0, 1.0, ca.if_else(x < 0, 0.0, 0.5))
        if isinstance(e, sp.core.relational.Relational):
            lhs, rhs = self._convert(e.lhs), self._convert(e.rhs)
            ops = {"<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b,
                   ">=": lambda a, b: a >= b, "==": lambda a, b: a == b, "!=": lambda a, b: a != b}
            return ops[e.rel_op](lhs, rhs)
        if isinstance(e, sp.And):
            return _fold(ca.logic_and, [self._convert(a) for a in e.args])
        if isinstance(e, sp.Or):
            return _fold(ca.logic_or, [self._convert(a) for a in e.args])
        if isinstance(e, sp.Not):
            return ca.logic_not(self._convert(e.args[0]))
        fn = _UNARY.get(type(e))
        if fn is not None and len(e.args) == 1:
            return fn(self._convert(e.args[0]))
        if isinstance(e, sp.atan2):
            return ca.atan2(self._convert(e.args[0]), self._convert(e.args[1]))
        raise NotImplementedError(f"no CasADi translation for {type(e).__name__}: {e}")

    def _piecewise(self, e: sp.Piecewise) -> Any:
        *pieces, (last_value, last_cond) = e.args
        if last_cond is not sp.true:
            raise NotImplementedError(f"Piecewise without a default branch: {e}")
        out = self._convert(last_value)
        for value, cond in reversed(pieces):
            out = ca.if_else(self._convert(cond), self._convert(value), out)
        return out


def _fold(op: Callable[[Any, Any], Any], args: list[Any]) -> Any:
    out = args[0]
    for a in args[1:]:
        out = op(out, a)
    return out


def to_casadi(expr: sp.Basic | sp.MatrixBase, symbols: Mapping[sp.Symbol, Any]) -> Any:
    """Convert one SymPy expression or matrix to CasADi SX.

    Parameters
    ----------
    expr : sp.Basic | sp.MatrixBase
        A SymPy expression or matrix.
    symbols : Mapping[sp.Symbol, Any]
        The CasADi value of each SymPy symbol.
    """
    conv = SympyToCasadi(symbols)
    if isinstance(expr, sp.MatrixBase):
        return conv.matrix(expr)
    return conv(expr)

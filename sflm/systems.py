"""Systems a control engineer already has, on the command line: a transfer function in ``s``, or a file of one.

``MODEL`` may be, beside a preset or a geometry file,

* an expression in ``s`` -- ``'(2 - s)/(s + 1)^3'``, ``'100/(s^2 + 2*s + 100)'`` (``^`` or ``**``,
  numbers, ``+ - * /`` and parentheses; nothing else is evaluated);
* a ``.toml`` or ``.json`` file with ``numerator`` and ``denominator``, the coefficients in
  descending powers of ``s`` (``numerator = [-1, 2]``, ``denominator = [1, 3, 3, 1]``), and
  optionally ``name``.

Either becomes a :class:`inversion.linear_system.LinearSystem` (its realisation, normal form and
zeros computed numerically, :mod:`inversion.linear_system`), which ``invert``, ``explore``,
``compare`` and ``info`` take; ``simulate`` and ``generate`` are about a link and say so.
"""

from __future__ import annotations

import ast
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from modelgen.errors import SettingsError

__all__ = ["looks_like_transfer_function", "transfer_function_file", "parse_transfer_function", "system_from_model_argument",
           "system_info"]

_ACCEPTED = ("a preset, a geometry .toml file, a transfer function in s such as '(2 - s)/(s + 1)^3', or a .toml/.json file "
             "with numerator and denominator (descending powers of s)")


def looks_like_transfer_function(text: str) -> bool:
    """Whether ``text`` is meant as an expression in ``s`` (not a path or a preset name such as ``paper-sim``): it is no
    file, and has a product, quotient, power or parentheses, or names nothing but ``s``."""
    if Path(text).exists() or text.endswith((".toml", ".json")) or "s" not in text:
        return False
    if any(c in text for c in "()*/^"):
        return True
    try:
        names = {node.id for node in ast.walk(ast.parse(text, mode="eval")) if isinstance(node, ast.Name)}
    except SyntaxError:
        return False
    return names == {"s"}


def transfer_function_file(path: str) -> bool:
    """Whether ``path`` is a file holding ``numerator`` and ``denominator`` (not a geometry)."""
    p = Path(path)
    if p.suffix.lower() not in (".toml", ".json") or not p.is_file():
        return False
    try:
        data = _read(p)
    except SettingsError:
        return p.suffix.lower() == ".json"
    return "numerator" in data or "denominator" in data


def _read(path: Path) -> dict[str, Any]:
    try:
        text = path.read_text()
        if path.suffix.lower() == ".json":
            data = json.loads(text)
        else:
            import tomllib

            data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise SettingsError("MODEL", str(path), f"a readable transfer-function file ({exc.__class__.__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise SettingsError("MODEL", str(path), "an object with numerator and denominator")
    return data


class _Polynomial:
    """A polynomial in ``s`` (coefficients in ascending powers) with the arithmetic of a parsed expression."""

    def __init__(self, ascending: list[float]):
        self.c = np.trim_zeros(np.asarray(ascending, dtype=float), "b") if np.any(ascending) else np.zeros(1)

    def __add__(self, other: "_Polynomial") -> "_Polynomial":
        return _Polynomial(list(np.polynomial.polynomial.polyadd(self.c, other.c)))

    def __sub__(self, other: "_Polynomial") -> "_Polynomial":
        return _Polynomial(list(np.polynomial.polynomial.polysub(self.c, other.c)))

    def __mul__(self, other: "_Polynomial") -> "_Polynomial":
        return _Polynomial(list(np.polynomial.polynomial.polymul(self.c, other.c)))


def parse_transfer_function(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``(numerator, denominator)`` of an expression in ``s``, in descending powers (module docstring).

    The expression is parsed, not evaluated: only numbers, ``s``, ``+ - * /``, integer powers
    ``^``/``**`` and parentheses are accepted; the result is one rational function ``N(s)/D(s)``.

    Raises
    ------
    SettingsError
        For anything else, or a division by zero.

    Examples
    --------
    >>> num, den = parse_transfer_function("(2 - s)/(s + 1)^3")
    >>> num.tolist(), den.tolist()
    ([-1.0, 2.0], [1.0, 3.0, 3.0, 1.0])
    """
    try:
        tree = ast.parse(text.replace("^", "**"), mode="eval")
    except SyntaxError:
        raise SettingsError("MODEL", text, _ACCEPTED) from None

    def rational(node: ast.AST) -> tuple[_Polynomial, _Polynomial]:
        if isinstance(node, ast.Expression):
            return rational(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            if not math.isfinite(node.value):
                raise SettingsError("MODEL", text, "finite coefficients")
            return _Polynomial([float(node.value)]), _Polynomial([1.0])
        if isinstance(node, ast.Name) and node.id == "s":
            return _Polynomial([0.0, 1.0]), _Polynomial([1.0])
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            n, d = rational(node.operand)
            return (_Polynomial([0.0]) - n if isinstance(node.op, ast.USub) else n), d
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, ast.Pow):
                exponent = node.right
                if not (isinstance(exponent, ast.Constant) and isinstance(exponent.value, int) and 0 <= exponent.value <= 60):
                    raise SettingsError("MODEL", text, "integer powers 0..60 of a term")
                n, d = rational(node.left)
                out_n, out_d = _Polynomial([1.0]), _Polynomial([1.0])
                for _ in range(exponent.value):
                    out_n, out_d = out_n * n, out_d * d
                return out_n, out_d
            (a, b), (c, d) = rational(node.left), rational(node.right)
            if isinstance(node.op, ast.Add):
                return a * d + c * b, b * d
            if isinstance(node.op, ast.Sub):
                return a * d - c * b, b * d
            if isinstance(node.op, ast.Mult):
                return a * c, b * d
            if isinstance(node.op, ast.Div):
                if not np.any(c.c):
                    raise SettingsError("MODEL", text, "a transfer function without a division by zero")
                return a * d, b * c
        raise SettingsError("MODEL", text, _ACCEPTED + " (only numbers, s, + - * /, integer powers and parentheses)")

    numerator, denominator = rational(tree)
    return numerator.c[::-1].copy(), denominator.c[::-1].copy()


def system_from_model_argument(model: str) -> Any:
    """The :class:`~inversion.linear_system.LinearSystem` that ``MODEL`` names (an expression in ``s`` or a file of one).

    Raises
    ------
    SettingsError
        For a malformed expression or file, or a system :func:`inversion.linear_system.as_linear_system` refuses.
    """
    import scipy.signal as sg

    from inversion.linear_system import as_linear_system

    if transfer_function_file(model):
        data = _read(Path(model))
        try:
            numerator = np.asarray(data["numerator"], dtype=float).ravel()
            denominator = np.asarray(data["denominator"], dtype=float).ravel()
        except (KeyError, TypeError, ValueError):
            raise SettingsError("MODEL", model, "a file whose numerator and denominator are lists of numbers (descending powers "
                                                "of s)") from None
        name = str(data.get("name", Path(model).stem))
    else:
        numerator, denominator = parse_transfer_function(model)
        name = model.replace(" ", "")
    if numerator.size == 0 or denominator.size == 0 or not (np.all(np.isfinite(numerator)) and np.all(np.isfinite(denominator))):
        raise SettingsError("MODEL", model, "finite numerator and denominator coefficients")
    if not np.any(denominator):
        raise SettingsError("MODEL", model, "a nonzero denominator")
    return as_linear_system(sg.TransferFunction(numerator, denominator), name=name)


def system_info(system: Any) -> tuple[dict[str, Any], str]:
    """``sflm info`` of a transfer function: its poles, zeros (stable or not), relative degree and gains, as JSON and text."""
    from modelgen.zeros import is_unstable
    from inversion.system import normal_form

    poles = np.sort_complex(np.linalg.eigvals(system.A))
    zeros = np.asarray(system.zeros, dtype=complex)
    unstable = is_unstable(zeros) if zeros.size else np.zeros(0, dtype=bool)
    order, gain = normal_form(system).low_frequency_gain()
    data = {**{k: v for k, v in system.report().items() if k != "transformation"},
            "poles": [[float(p.real), float(p.imag)] for p in poles], "zeros": [[float(z.real), float(z.imag)] for z in zeros],
            "n_unstable": int(np.count_nonzero(unstable)), "low_frequency": {"integrators": int(order), "gain": float(gain)}}

    def shown(values: np.ndarray) -> str:
        return ", ".join(f"{v.real:.6g}{v.imag:+.6g}i" if abs(v.imag) > 1e-12 * max(abs(v), 1.0) else f"{v.real:.6g}" for v in values) or "none"

    text = "\n".join([
        f"{system.name}: a SISO system of order {system.A.shape[0]}, relative degree {system.relative_degree}",
        f"  poles               {shown(poles)}",
        f"  zeros               {shown(zeros)} ({data['n_unstable']} unstable{': non-minimum phase' if data['n_unstable'] else ''})",
        f"  high-frequency gain C A^(r-1) B = {data['high_frequency_gain']:.6g}; at low frequency "
        + (f"G(0) = {gain:.6g}" if order == 0 else f"G(s) ~ {gain:.6g} / s^{order}"),
    ])
    return data, text

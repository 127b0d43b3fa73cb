"""Systems a control engineer already has, on the command line: a transfer function in ``s``, or a file of one.

``MODEL`` may be, beside a preset or a geometry file,

* an expression in ``s`` -- ``'(2 - s)/(s + 1)^3'``, ``'100/(s^2 + 2*s + 100)'`` (``^`` or ``**``,
  numbers, ``+ - * /`` and parentheses; nothing else is evaluated);
* a ``.toml`` or ``.json`` file with ``numerator`` and ``denominator``, the coefficients in
  descending powers of ``s`` (``numerator = [-1, 2]``, ``denominator = [1, 3, 3, 1]``), and
  optionally ``name``.

Either becomes a :class:`inversion.lti.linear_system.LinearSystem` (its realisation, normal form and
zeros computed numerically, :mod:`inversion.lti.linear_system`), which ``invert``, ``explore``,
``compare`` and ``info`` take; ``simulate`` and ``generate`` are about a link and say so.
"""

from __future__ import annotations

import ast
import hashlib
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from modelgen.errors import SettingsError
from modelgen.files import DocumentError, read_document

__all__ = ["looks_like_transfer_function", "transfer_function_file", "parse_transfer_function", "system_from_model_argument",
           "system_info"]

#: Longest expression in ``s`` accepted (characters).
MAX_EXPRESSION = 2000
#: Highest degree of a numerator or denominator: beyond it a polynomial's coefficients span more decades than double
#: precision holds ((s + 1)^60 has coefficients from 1 to 1.2e17), and its roots are noise.
MAX_ORDER = 60
#: Deepest nesting of an expression in ``s`` (operations inside operations): a polynomial of degree MAX_ORDER written
#: out term by term nests about 3 * MAX_ORDER deep. A fixed bound, so that what is refused does not depend on how much
#: of the interpreter's stack the caller has used (a sum of 990 terms parsed under one entry point and not another).
MAX_DEPTH = 400
#: A name given in a file: printable, one line, at most this long (it reaches reports, folders and generated C's comments).
MAX_NAME = 64

_ACCEPTED = ("a preset, a geometry .toml file, a transfer function in s such as '(2 - s)/(s + 1)^3', or a .toml/.json file "
             "with numerator and denominator (descending powers of s)")


def looks_like_transfer_function(text: str) -> bool:
    """Whether ``text`` is meant as an expression in ``s``.

    Whether ``text`` is meant as an expression in ``s`` (not a path or a preset name such as ``paper-sim``): it is no
    file, and has a product, quotient, power or parentheses, or names nothing but ``s``.

    Parameters
    ----------
    text : str
        The MODEL argument.
    """
    if _is_file(text) or text.endswith((".toml", ".json")):
        return False
    if "s" not in text:  # an expression of numbers alone ('1/0') is a transfer function attempt, refused as one
        try:
            tree = ast.parse(text.replace("^", "**"), mode="eval")
        except (SyntaxError, RecursionError, MemoryError, ValueError):
            return False
        return isinstance(tree.body, ast.BinOp) and not any(isinstance(node, ast.Name) for node in ast.walk(tree))
    if any(c in text for c in "()*/^\u2212\u00d7"):
        return True
    if len(text) > MAX_EXPRESSION:
        return True  # too long for a name: parsed, and refused as an expression (not taken for a path)
    try:
        names = {node.id for node in ast.walk(ast.parse(text, mode="eval")) if isinstance(node, ast.Name)}
    except (SyntaxError, RecursionError, MemoryError, ValueError):
        return False
    return names == {"s"}


def _is_file(text: str) -> bool:
    """Whether ``text`` names an existing file (a name too long for the system, or with a NUL, names none)."""
    try:
        return Path(text).is_file()
    except (OSError, ValueError):
        return False


def transfer_function_file(path: str) -> bool:
    """Whether ``path`` is a file of a transfer function.

    Whether ``path`` is a file holding ``numerator`` and ``denominator`` (not a geometry).

    Parameters
    ----------
    path : str
        A file's path.
    """
    p = Path(path)
    if p.suffix.lower() not in (".toml", ".json") or not _is_file(path):
        return False
    try:
        data = _read(p)
    except SettingsError:
        return p.suffix.lower() == ".json"
    return "numerator" in data or "denominator" in data


def _read(path: Path) -> dict[str, Any]:
    try:
        data = read_document(path)
    except (OSError, DocumentError) as exc:
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
        if self.c.size + other.c.size - 2 > 4 * MAX_ORDER:
            raise _TooHigh()
        return _Polynomial(list(np.polynomial.polynomial.polymul(self.c, other.c)))


class _TooHigh(Exception):
    """An intermediate polynomial beyond any order :func:`parse_transfer_function` accepts."""


def _depth(tree: ast.AST) -> int:
    """Deepest nesting of ``tree``'s nodes, counted without recursion."""
    deepest, stack = 0, [(tree, 1)]
    while stack:
        node, level = stack.pop()
        deepest = max(deepest, level)
        stack.extend((child, level + 1) for child in ast.iter_child_nodes(node))
    return deepest


_IMPLICIT = re.compile(r"(?<=[0-9.s)])\s*(?=[(s])")


#: Typographic characters a transfer function copied from a document may hold, read as their ASCII operators: the minus
#: sign U+2212, the en and em dashes, the multiplication sign and the middle dot.
_TYPOGRAPHIC = str.maketrans({"\u2212": "-", "\u2013": "-", "\u2014": "-", "\u00d7": "*", "\u22c5": "*", "\u00b7": "*"})


def parse_transfer_function(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``(numerator, denominator)`` of an expression in ``s``.

    ``(numerator, denominator)`` of an expression in ``s``, in descending powers (module docstring).

    The expression is parsed, not evaluated: only numbers, ``s``, ``+ - * /``, integer powers
    ``^``/``**`` and parentheses are accepted; a product may be written without its ``*``
    (``(s - 1)(s + 2)``, ``2s``, ``(s + 1)^2 (s + 2)``); the result is one rational function ``N(s)/D(s)``.

    Parameters
    ----------
    text : str
        The expression.

    Raises
    ------
    SettingsError
        For anything else, or a division by zero.

    Examples
    --------
    >>> num, den = parse_transfer_function("(2 - s)/(s + 1)^3")
    >>> num.tolist(), den.tolist()
    ([-1.0, 2.0], [1.0, 3.0, 3.0, 1.0])
    >>> parse_transfer_function("(s - 1)(s + 2)/((s + 1)^2 (s + 3))")[1].tolist()
    [1.0, 5.0, 7.0, 3.0]
    """
    shown = text if len(text) <= 80 else text[:60] + f"... ({len(text)} characters)"
    if len(text) > MAX_EXPRESSION:
        raise SettingsError("MODEL", shown, f"an expression in s of at most {MAX_EXPRESSION} characters")
    text = text.translate(_TYPOGRAPHIC)  # a minus or a times sign as a word processor writes them
    foreign = next((ch for ch in text if not ch.isascii()), None)
    if foreign is not None:
        import unicodedata

        raise SettingsError("MODEL", shown, f"an expression in s of ASCII characters: {foreign!r} "
                            f"({unicodedata.name(foreign, 'U+%04X' % ord(foreign))}) at position {text.index(foreign) + 1} "
                            "is none of the digits, s, + - * / ^ and parentheses")
    if "s" not in text:
        raise SettingsError("MODEL", shown, "a transfer function in s: this expression has no s (a constant is no system to invert)")
    try:
        # an implicit product: a number, s or ')' followed (across blanks) by '(' or s
        tree = ast.parse(_IMPLICIT.sub("*", text.replace("^", "**")), mode="eval")
    except (SyntaxError, ValueError):
        raise SettingsError("MODEL", shown, _ACCEPTED) from None
    except (RecursionError, MemoryError):
        raise SettingsError("MODEL", shown, "an expression in s nested less deeply") from None
    if _depth(tree) > MAX_DEPTH:
        raise SettingsError("MODEL", shown, f"an expression in s nested less deeply (at most {MAX_DEPTH} operations inside "
                                            "one another)")

    def rational(node: ast.AST) -> tuple[_Polynomial, _Polynomial]:
        if isinstance(node, ast.Expression):
            return rational(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            if not math.isfinite(node.value):
                raise SettingsError("MODEL", shown, "finite coefficients")
            return _Polynomial([float(node.value)]), _Polynomial([1.0])
        if isinstance(node, ast.Name) and node.id == "s":
            return _Polynomial([0.0, 1.0]), _Polynomial([1.0])
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            n, d = rational(node.operand)
            return (_Polynomial([0.0]) - n if isinstance(node.op, ast.USub) else n), d
        if isinstance(node, ast.BinOp):
            if isinstance(node.op, ast.Pow):
                exponent = node.right
                if not (isinstance(exponent, ast.Constant) and isinstance(exponent.value, int) and 0 <= exponent.value <= MAX_ORDER):
                    raise SettingsError("MODEL", shown, f"integer powers 0..{MAX_ORDER} of a term")
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
                    raise SettingsError("MODEL", shown, "a transfer function without a division by zero")
                return a * d, b * c
        raise SettingsError("MODEL", shown, _ACCEPTED + " (only numbers, s, + - * /, integer powers and parentheses)")

    try:
        numerator, denominator = rational(tree)
    except (RecursionError, MemoryError):
        raise SettingsError("MODEL", shown, "an expression in s nested less deeply") from None
    except _TooHigh:
        raise SettingsError("MODEL", shown, f"a numerator and denominator of degree at most {MAX_ORDER}") from None
    num, den = numerator.c[::-1].copy(), denominator.c[::-1].copy()
    if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise SettingsError("MODEL", shown, "coefficients that double precision holds (this expression overflows)")
    return num, den


def system_from_model_argument(model: str) -> Any:
    """The :class:`LinearSystem` that ``MODEL`` names.

    The :class:`~inversion.lti.linear_system.LinearSystem` that ``MODEL`` names (an expression in ``s`` or a file of one).

    Parameters
    ----------
    model : str
        The MODEL argument.

    Raises
    ------
    SettingsError
        For a malformed expression or file, a name that is not one printable line of at most :data:`MAX_NAME`
        characters, an improper transfer function, or a system :func:`inversion.lti.linear_system.as_linear_system` refuses.
    """
    from inversion.lti.linear_system import as_linear_system

    if transfer_function_file(model):
        data = _read(Path(model))
        try:
            numerator = np.asarray(data["numerator"], dtype=float).ravel()
            denominator = np.asarray(data["denominator"], dtype=float).ravel()
        except (KeyError, TypeError, ValueError):
            raise SettingsError("MODEL", model, "a file whose numerator and denominator are lists of numbers (descending powers "
                                                "of s)") from None
        name = data.get("name", Path(model).stem)
        if not isinstance(name, str) or not name or len(name) > MAX_NAME or not name.isprintable():
            raise SettingsError("name", name, f"a name of at most {MAX_NAME} printable characters on one line (it reaches reports, "
                                              "folder names and the comments of generated C)")
        shown = model
    else:
        numerator, denominator = parse_transfer_function(model)
        name = model.replace(" ", "")
        shown = model if len(model) <= 80 else model[:60] + f"... ({len(model)} characters)"
        if len(name) > MAX_NAME:
            name = name[: MAX_NAME - 12] + "~" + hashlib.sha256(name.encode()).hexdigest()[:11]
    if numerator.size == 0 or denominator.size == 0 or not (np.all(np.isfinite(numerator)) and np.all(np.isfinite(denominator))):
        raise SettingsError("MODEL", shown, "finite numerator and denominator coefficients")
    if not np.any(denominator):
        raise SettingsError("MODEL", shown, "a nonzero denominator")
    if not np.any(numerator):
        raise SettingsError("MODEL", shown, "a nonzero numerator (the output would not depend on the input)")
    numerator, denominator = np.trim_zeros(numerator, "f"), np.trim_zeros(denominator, "f")
    if numerator.size >= denominator.size:
        raise SettingsError("MODEL", shown, f"a strictly proper transfer function (the numerator of lower degree than the "
                            f"denominator; here {numerator.size - 1} and {denominator.size - 1}): a feedforward inverts the output's "
                            "relative degree, which a proper or improper one does not have")
    if denominator.size - 1 > MAX_ORDER:
        raise SettingsError("MODEL", shown, f"a denominator of degree at most {MAX_ORDER} (here {denominator.size - 1})")
    # the realisation of the numerator scaled to 1, its gain put back on C: "negligible" leading coefficients are judged
    # relative to the largest (1e-300/(s + 1)^3 is a fine system)
    gain, lead = float(np.abs(numerator).max()), float(denominator[0])
    A, B, C, D = controller_canonical(numerator / gain, denominator / lead)
    return as_linear_system((A, B, C * (gain / lead), D * (gain / lead)), name=name)


#: Leading numerator coefficients at most this (the numerator scaled to a largest coefficient of 1) are taken as zero, as
#: :func:`scipy.signal.normalize` takes them.
NEGLIGIBLE = 1e-14


def controller_canonical(numerator: np.ndarray, denominator: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The controller canonical realisation ``(A, B, C, D)`` of ``numerator / denominator``.

    The controller canonical realisation of a proper ``numerator / denominator`` (descending powers of ``s``; the
    denominator monic, its degree ``n >= 1``): ``A``'s first row ``-denominator[1:]`` above an identity, ``B = e_1``,
    ``C = b[1:] - b[0] denominator[1:]`` with ``b`` the numerator padded to ``n + 1`` coefficients, ``D = b[0]``. Bit for bit
    :func:`scipy.signal.tf2ss` (``tests/sflm/test_cli_systems.py``), leading numerator coefficients of at most
    :data:`NEGLIGIBLE` dropped as it drops them (with a warning), without importing :mod:`scipy.signal` (1.5 s of a
    transfer function's command, most of it parsing docstrings).

    Parameters
    ----------
    numerator : np.ndarray
        The numerator's coefficients, at most as many as the denominator's.
    denominator : np.ndarray
        The denominator's, the first 1.
    """
    import warnings

    b, a = np.asarray(numerator, dtype=float).ravel(), np.asarray(denominator, dtype=float).ravel()
    leading = int(np.argmax(np.abs(b) > NEGLIGIBLE)) if np.any(np.abs(b) > NEGLIGIBLE) else b.size - 1
    if leading:
        warnings.warn(f"the numerator's {leading} leading coefficient(s) are at most {NEGLIGIBLE:g} of its largest: taken as "
                      "zero (the results may be meaningless)", stacklevel=2)
        b = b[leading:]
    n = a.size - 1
    b = np.concatenate([np.zeros(n + 1 - b.size), b])
    A = np.vstack([-a[None, 1:], np.eye(n - 1, n)])
    B = np.eye(n, 1)
    C = (b[1:] - b[0] * a[1:])[None, :]
    return A, B, C, np.array([[b[0]]])


def system_info(system: Any) -> tuple[dict[str, Any], str]:
    """``sflm info`` of a transfer function.

    ``sflm info`` of a transfer function: its poles, zeros (stable or not), relative degree and gains, as JSON and text.

    Poles and zeros are shown as computed less their rounding noise (:func:`modelgen.zeros.cluster_roots`): a repeated
    root once with its multiplicity, a real or imaginary part within the computation's accuracy as zero.

    Parameters
    ----------
    system : Any
        A generic system.
    """
    from modelgen.zeros import cluster_roots, is_unstable
    from inversion.lti.system import normal_form

    scale = max(float(np.abs(np.linalg.eigvals(system.balanced[0])).max(initial=0.0)), 1.0)
    poles = cluster_roots(np.linalg.eigvals(system.A), scale)
    zeros = cluster_roots(np.asarray(system.zeros, dtype=complex), scale)
    unstable = sum(m for z, m in zeros if is_unstable([z])[0])
    order, gain = normal_form(system).low_frequency_gain()

    def listed(roots: list[tuple[complex, int]]) -> list[list[float]]:
        return [[float(v.real), float(v.imag)] for v, m in roots for _ in range(m)]

    data = {**{k: v for k, v in system.report().items() if k != "transformation"},
            "poles": listed(poles), "zeros": listed(zeros),
            "distinct_poles": [[float(v.real), float(v.imag), m] for v, m in poles],
            "distinct_zeros": [[float(v.real), float(v.imag), m] for v, m in zeros],
            "n_unstable": int(unstable), "low_frequency": {"integrators": int(order), "gain": float(gain)}}

    def shown(roots: list[tuple[complex, int]]) -> str:
        out = []
        for v, m in roots:
            if v.imag < 0 and any(w == v.conjugate() and k == m for w, k in roots):
                continue  # shown with its conjugate as +-
            text = (f"{v.real:.6g}" if v.imag == 0 else f"±{abs(v.imag):.6g}i" if v.real == 0
                    else f"{v.real:.6g}±{abs(v.imag):.6g}i" if any(w == v.conjugate() for w, _ in roots) else f"{v.real:.6g}{v.imag:+.6g}i")
            out.append(text + (f" (x{m})" if m > 1 else ""))
        return ", ".join(out) or "none"

    text = "\n".join([
        f"{system.name}: a SISO system of order {system.A.shape[0]}, relative degree {system.relative_degree}",
        f"  poles               {shown(poles)}",
        f"  zeros               {shown(zeros)} ({data['n_unstable']} unstable{': non-minimum phase' if data['n_unstable'] else ''})",
        f"  high-frequency gain C A^(r-1) B = {data['high_frequency_gain']:.6g}; at low frequency "
        + (f"G(0) = {gain:.6g}" if order == 0 else f"G(s) ~ {gain:.6g} / s^{order}"),
    ])
    return data, text

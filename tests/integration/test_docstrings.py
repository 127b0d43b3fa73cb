"""Every public function's every parameter is documented (numpydoc), in the manner of python-control's docstring test.

The public API is what the packages export (``modelgen.__all__``, ``inversion.__all__``, ``simulation.__all__``) and the
public methods of the classes among it. A function's parameters are listed under ``Parameters``; a class's constructor
parameters may be its ``Attributes`` (a dataclass's fields) or its ``Parameters``.
"""

from __future__ import annotations

import importlib
import inspect
import re
from typing import Any, Callable, Iterator

import pytest

PACKAGES = ("modelgen", "inversion", "simulation")


def documented(doc: str, *sections: str) -> set[str]:
    """The names a numpydoc docstring documents in ``sections`` (``a, b : type`` lines count for both)."""
    names: set[str] = set()
    for section in sections:
        match = re.search(rf"(?:^|\n){section}\n-+\n(.*?)(?:\n\n[A-Z][A-Za-z ]+\n-+\n|\Z)", doc, re.S)
        if match is None:
            continue
        for line in match.group(1).splitlines():
            head = re.match(r"^(\*{0,2}[A-Za-z_][\w, *]*?)\s*(?::|$)", line)
            if head and not line.startswith(" "):
                names |= {n.strip().lstrip("*") for n in head.group(1).split(",")}
    return names


def public_functions() -> Iterator[tuple[str, Callable[..., Any], str, tuple[str, ...]]]:
    """``(name, function, docstring, sections)`` of every public function and method with parameters."""
    for package in PACKAGES:
        module = importlib.import_module(package)
        for attr in module.__all__:
            obj = getattr(module, attr)
            if inspect.isfunction(obj):
                yield f"{package}.{attr}", obj, inspect.getdoc(obj) or "", ("Parameters",)
            elif inspect.isclass(obj):
                init = obj.__dict__.get("__init__")
                if inspect.isfunction(init) and not issubclass(obj, BaseException):
                    yield f"{package}.{attr}", init, inspect.getdoc(obj) or "", ("Parameters", "Attributes")
                for name, member in vars(obj).items():
                    if inspect.isfunction(member) and not name.startswith("_"):
                        yield f"{package}.{attr}.{name}", member, inspect.getdoc(member) or "", ("Parameters",)


def _parameters(function: Callable[..., Any]) -> list[str]:
    return [p.name for p in inspect.signature(function).parameters.values()
            if p.name not in ("self", "cls") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


CASES = [case for case in public_functions() if _parameters(case[1])]


def test_the_public_api_is_found() -> None:
    names = {name for name, *_ in CASES}
    assert {"inversion.invert", "inversion.explore", "simulation.simulate", "modelgen.load"} <= names and len(names) > 40


@pytest.mark.parametrize("name,function,doc,sections", CASES, ids=[c[0] for c in CASES])
def test_every_parameter_is_documented(name: str, function: Callable[..., Any], doc: str, sections: tuple[str, ...]) -> None:
    missing = [p for p in _parameters(function) if p not in documented(doc, *sections)]
    assert not missing, f"{name}: {missing} not documented under {' or '.join(sections)}"


def test_the_checker_sees_a_missing_parameter() -> None:
    def f(a: int, b: int) -> int:
        """Sum.

        Parameters
        ----------
        a : int
            One.
        """
        return a + b

    assert documented(inspect.getdoc(f) or "", "Parameters") == {"a"}

"""Every public object is documented (numpydoc), in the manner of python-control's docstring test.

The public objects are those every public module (no ``_`` in its dotted name) of the four packages lists in its
``__all__`` and defines itself, and the public methods of the classes among them. Each has a summary (its first
paragraph) of at most :data:`SUMMARY` characters, and each of its parameters documented: a function's under
``Parameters``; a class's constructor parameters under its ``Attributes`` (a dataclass's fields) or its ``Parameters``.
A parameter whose name starts with ``_`` is private (a dataclass's cache) and not asked for.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import re
from typing import Any, Callable, Iterator

import pytest

PACKAGES = ("modelgen", "inversion", "simulation", "sflm")
#: The longest summary accepted (python-control's rule).
SUMMARY = 64


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


def public_modules() -> Iterator[Any]:
    """Every public module of :data:`PACKAGES`, the packages themselves first."""
    for package in PACKAGES:
        root = importlib.import_module(package)
        yield root
        for info in pkgutil.walk_packages(root.__path__, package + "."):
            if not any(part.startswith("_") for part in info.name.split(".")):
                yield importlib.import_module(info.name)


def public_objects() -> Iterator[tuple[str, Any, Callable[..., Any] | None, tuple[str, ...]]]:
    """``(name, object, function, sections)`` of every public function, class and method, each once.

    ``function`` is what takes the parameters (a class's ``__init__``; ``None`` for a class without one of its own or
    an exception), ``sections`` where they are documented.
    """
    seen: set[int] = set()
    for module in public_modules():
        for attr in getattr(module, "__all__", ()):  # a room's __init__ may export nothing
            obj = getattr(module, attr)
            if getattr(obj, "__module__", None) != module.__name__ or id(obj) in seen:
                continue  # re-exported: judged where it is defined
            seen.add(id(obj))
            name = f"{module.__name__}.{attr}"
            if inspect.isfunction(obj):
                yield name, obj, obj, ("Parameters",)
            elif inspect.isclass(obj):
                init = obj.__dict__.get("__init__")
                own = inspect.isfunction(init) and not issubclass(obj, BaseException)
                yield name, obj, init if own else None, ("Parameters", "Attributes")
                for method, member in vars(obj).items():
                    if inspect.isfunction(member) and not method.startswith("_"):
                        yield f"{name}.{method}", member, member, ("Parameters",)


def _parameters(function: Callable[..., Any]) -> list[str]:
    return [p.name for p in inspect.signature(function).parameters.values()
            if p.name not in ("self", "cls") and not p.name.startswith("_") and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]


def summary(doc: str) -> str:
    """A docstring's summary: its first paragraph, on one line."""
    return " ".join(doc.strip().split("\n\n")[0].split())


OBJECTS = list(public_objects())
CASES = [(name, function, inspect.getdoc(obj) or "", sections) for name, obj, function, sections in OBJECTS
         if function is not None and _parameters(function)]


def test_the_public_api_is_found() -> None:
    names = {name for name, *_ in OBJECTS}
    assert {"inversion.api.invert", "inversion.family.explore.explore", "simulation.closed_loop.simulate",
            "modelgen.loader.load", "sflm.cli.main", "inversion.lti.system.NormalForm.torque"} <= names
    assert len(names) > 400 and len({name.split(".")[0] for name in names}) == len(PACKAGES)


@pytest.mark.parametrize("name,obj", [(name, obj) for name, obj, *_ in OBJECTS], ids=[name for name, *_ in OBJECTS])
def test_every_summary_is_short(name: str, obj: Any) -> None:
    text = summary(inspect.getdoc(obj) or "")
    assert text, f"{name} has no docstring"
    assert len(text) <= SUMMARY, f"{name}: summary of {len(text)} characters (at most {SUMMARY}): {text!r}"


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


def test_the_checker_sees_a_long_summary() -> None:
    def g() -> None:
        """A summary that runs on,
        over two lines of the source, past what a reader takes in at a glance.

        Then its detail.
        """

    assert len(summary(inspect.getdoc(g) or "")) > SUMMARY and summary("One.\n\nTwo.") == "One."

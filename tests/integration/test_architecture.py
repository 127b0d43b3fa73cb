"""The architecture: data flows one way and the numeric layer stays free of SymPy."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LAYERS = {"modelgen": 0, "inversion": 1, "simulation": 2, "sflm": 3}


def imports_of(path: Path) -> set[str]:
    tree = ast.parse(path.read_text())
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(LAYERS))
def test_no_layer_imports_a_later_one(package: str) -> None:
    for path in (ROOT / package).rglob("*.py"):
        later = {m for m in imports_of(path) if LAYERS.get(m, -1) > LAYERS[package]}
        assert not later, f"{path.relative_to(ROOT)} imports {later}"


def module_name(path: Path) -> str:
    """``inversion.family.ssef.plan`` for ``inversion/family/ssef/plan.py`` (a package's ``__init__`` is the package)."""
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_names(path: Path) -> list[tuple[str, list[str]]]:
    """Every import of a module, at any depth (in functions, under ``TYPE_CHECKING``: a type is a
    dependency too), as ``(absolute module, names taken from it)``."""
    here = module_name(path)
    package = here if path.name == "__init__.py" else here.rpartition(".")[0]
    out: list[tuple[str, list[str]]] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out += [(a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            out.append((module, [a.name for a in node.names]))
    return out


def project_modules() -> dict[str, Path]:
    return {module_name(path): path for package in LAYERS for path in (ROOT / package).rglob("*.py")}


def test_no_import_cycle_inside_a_package() -> None:
    # files that import each other, however indirectly, are one idea split in two (or two tangled)
    modules = project_modules()
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, path in modules.items():
        for module, names in imported_names(path):
            targets = {module} | {f"{module}.{n}" for n in names}
            graph[name] |= {t for t in targets if t in modules and t != name and t.split(".")[0] == name.split(".")[0]}
    # Tarjan's strongly connected components
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    assert not cycles, f"import cycles: {cycles}"


#: The rooms of inversion/ from the ground up: a room imports only rooms on lower floors (its own files aside).
ROOMS = {"errors": 0, "config": 0, "options": 1, "threads": 0, "signals": 1, "lti": 2, "settings": 2, "acceptance": 3,
         "result": 3, "chain": 3, "problem": 4, "family": 5, "methods": 6, "realtime": 6, "api": 7, "studies": 8, "": 9}


def room_of(module: str) -> str:
    """``family`` for ``inversion.family.ssef.plan``, ``acceptance`` for ``inversion.acceptance``, ``""`` for the package's face."""
    return module.split(".")[1] if "." in module else ""


def test_inversion_rooms_import_only_lower_floors() -> None:
    modules = {name: path for name, path in project_modules().items() if name.split(".")[0] == "inversion"}
    assert {room_of(name) for name in modules} == set(ROOMS), "a room of inversion/ was added or removed: place it in ROOMS"
    found = []
    for name, path in modules.items():
        here = room_of(name)
        for module, names in imported_names(path):
            for target in {module} | {f"{module}.{n}" for n in names}:
                if target in modules and room_of(target) != here and ROOMS[room_of(target)] >= ROOMS[here]:
                    found.append(f"{name} ({here}) -> {target} ({room_of(target)})")
    assert not found, found


#: Arrows between the rooms of inversion/ (a room's imports of another, counted once): issue 55 brought in the problem and
#: the method registry without adding to the 81 there were before it.
MOST_ARROWS = 81


def test_the_rooms_of_inversion_are_not_more_tangled() -> None:
    modules = {name: path for name, path in project_modules().items() if name.split(".")[0] == "inversion"}
    arrows = {(room_of(name), room_of(target)) for name, path in modules.items() for module, names in imported_names(path)
              for target in {module} | {f"{module}.{n}" for n in names} if target in modules and room_of(target) != room_of(name)}
    assert len(arrows) <= MOST_ARROWS, sorted(arrows)


def test_tests_mirror_the_code() -> None:
    # tests/<package>/<room>/test_<module>.py beside the code they test; what crosses packages in tests/integration
    folders = {p.relative_to(ROOT / "tests") for p in (ROOT / "tests").rglob("test_*.py")}
    assert all(len(f.parts) >= 2 for f in folders), [str(f) for f in folders if len(f.parts) < 2]
    for f in folders:
        home = ROOT / Path(*f.parts[:-1])
        assert f.parts[0] == "integration" or home.is_dir(), f"tests/{f} mirrors no folder of the code ({home.relative_to(ROOT)})"
    names = [f.name for f in folders]
    assert len(names) == len(set(names)), "two test files share a name (pytest imports them by their base names)"


def test_no_private_name_is_imported_from_another_module() -> None:
    # what two modules share is public in a third (STYLE.md): `from .x import _name` hides a dependency
    modules = project_modules()
    found = [f"{name} takes {n} from {module}" for name, path in modules.items() for module, names in imported_names(path)
             if module in modules for n in names if n.startswith("_") and not n.startswith("__")]
    assert not found, found


def code_lines(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function's body after its docstring (a numpydoc docstring is not what makes a function hard to read)."""
    body = function.body
    first = body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str) and len(body) > 1:
        first = body[1]
    return (function.end_lineno or first.lineno) - first.lineno + 1


def test_long_functions_stay_few() -> None:
    # issue 23: at most two bodies over 80 lines in the packages, none in the numeric layer
    long = sorted((code_lines(node), f"{path.relative_to(ROOT)}:{node.name}") for package in LAYERS
                  for path in (ROOT / package).rglob("*.py") for node in ast.walk(ast.parse(path.read_text()))
                  if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and code_lines(node) > 80)
    assert len(long) <= 2 and not [name for _, name in long if name.startswith("inversion")], long


def test_inversion_never_imports_sympy() -> None:
    for path in (ROOT / "inversion").glob("*.py"):
        assert "sympy" not in imports_of(path), path.name
    code = "import sys, inversion, simulation; print('sympy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_import_inversion_stays_light() -> None:
    # `import inversion` < 0.3 s (benchmarks/bench_inversion.py): SciPy, CasADi and matplotlib
    # (0.25, 0.1 and 0.35 s to import) load when first used, never at import
    code = "import sys, inversion; print(sorted({m.split('.')[0] for m in sys.modules} & {'scipy', 'casadi', 'matplotlib', 'sympy'}))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_cli_imports_matplotlib_only_to_plot() -> None:
    code = ("import sys; from sflm.cli import main\n"
            "try:\n    main(['invert', 'paper-sim', '--out', sys.argv[1], '--json'])\nexcept SystemExit:\n    pass\n"
            "print('matplotlib' in sys.modules, file=sys.stderr)")
    import tempfile

    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run([sys.executable, "-c", code, out], capture_output=True, text=True)
    assert done.stderr.strip().splitlines()[-1] == "False", done.stderr


def test_the_automatic_choice_imports_no_scipy_optimize() -> None:
    # issue 56 (imports only what a command uses): scipy.optimize costs 0.25-0.45 s to import, more than the causal limit's
    # linear programme it was imported for (now HiGHS through highspy); hyperbolic with 4 modes has three zeros to the
    # right, so its limit is that programme's; the JSON on stdout is whole (highspy's banner would precede it)
    code = ("import json, sys; from sflm.cli import main\n"
            "try:\n    main(['invert', 'hyperbolic', '--modes', '4', '--auto', '--out', sys.argv[1], '--json', '-q'])\n"
            "except SystemExit:\n    pass\n"
            "print('scipy.optimize' in sys.modules, file=sys.stderr)")
    import json
    import tempfile

    with tempfile.TemporaryDirectory() as out:
        # the second run is the everyday command's: the first, on a new cache, derives the model and the one with more modes
        # the judgement asks for, and finds their mode shapes' roots by scipy.optimize's brentq (kept in the cache)
        done = [subprocess.run([sys.executable, "-c", code, out], capture_output=True, text=True) for _ in range(2)][-1]
    assert done.stderr.strip().splitlines()[-1] == "False", done.stderr
    assert json.loads(done.stdout)["causal_limit"]["method"] == "linear programme"


def test_generated_files_are_headed() -> None:
    for path in (ROOT / "generated").glob("*/*.[ch]"):
        head = path.read_text()[:400]
        assert head.startswith("/* generated by sflm from") and "Do not edit by hand" in head, path

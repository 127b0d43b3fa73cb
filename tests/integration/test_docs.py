"""The Examples sections of the public docstrings run and print what they say."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

#: The repository (the README, docs/).
ROOT = Path(__file__).resolve().parents[2]

MODULES = [
    "modelgen.geometry",
    "modelgen.modes",
    "modelgen.lagrange",
    "modelgen.loader",
    "inversion.family.piecewise",
    "inversion.api",
    "inversion.config",
    "inversion.options",
    "inversion.settings",
    "inversion.family.explore",
    "inversion.family.auto",
    "inversion.realtime.feedforward_c",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name: str) -> None:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0, f"{name} has no examples"
    assert result.failed == 0


def _python_block(text: str, heading: str) -> str:
    return text.split(heading, 1)[1].split("```python", 1)[1].split("```", 1)[0]


def test_readme_python_block_runs(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # The README's Python example, as written, in a folder of its own that sees the repository's tests/data
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    (tmp_path / "tests").symlink_to(root / "tests")
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    block = _python_block((root / "README.md").read_text(), "from Python")
    exec(compile(block, "README.md", "exec"), namespace)  # noqa: S102 - the documentation's own code
    summary = namespace["result"].summary  # type: ignore[attr-defined]
    assert summary["method"] == "ssef" and summary["sampled"]["max_tip_error"] <= 0.01 * 0.5  # 1 % of the 0.5 m move
    assert (tmp_path / "ff" / "feedforward.c").is_file()
    assert namespace["closed"].summary["final_tip_error"] < 1e-3  # type: ignore[attr-defined]


@pytest.mark.slow  # the guide's example as written (23 s of automatic choices); the README's block stays in the quick suite
def test_the_guide_python_block_runs(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # docs/guide/models.md's Python example, as written, from the repository root.
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    block = _python_block((root / "docs" / "guide" / "models.md").read_text(), "## Python")
    monkeypatch.chdir(root)
    namespace: dict[str, object] = {}
    exec(compile(block, "models.md", "exec"), namespace)  # noqa: S102 - the documentation's own code
    chosen = namespace["chosen"].summary  # type: ignore[attr-defined]
    assert chosen["relative_redefinition_error"] <= 0.01 and chosen["torque_ratio"] <= 3  # the default bound and limit
    assert namespace["gentle"].summary["peak_torque"] <= 0.06  # type: ignore[attr-defined]


@pytest.mark.slow
@pytest.mark.parametrize("page", ["methods", "systems", "robust", "explore"])
def test_the_guide_s_commands_run(page: str, tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # each task page's shell example, as written (a running Dask scheduler and the user's own files aside), exits 0
    import re
    import shlex
    from pathlib import Path

    from sflm.cli import main

    root = Path(__file__).resolve().parents[2]
    (tmp_path / "tests").symlink_to(root / "tests")
    monkeypatch.chdir(tmp_path)
    text = (root / "docs" / "guide" / f"{page}.md").read_text()
    commands = [line.split("#", 1)[0].strip() for block in re.findall(r"```sh\n(.*?)```", text, re.S)
                for line in block.replace("\\\n", " ").splitlines()]
    runnable = [c for c in commands if c.startswith("sflm ") and "--scheduler" not in c]
    assert runnable
    for command in runnable:
        assert main(shlex.split(command)[1:]) == 0, command


@pytest.mark.slow
def test_getting_started_walks_to_a_controller(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # docs/guide/getting-started.md: its invert command, then its C controller loop compiled against the export and run
    import re
    import shlex
    import shutil
    import subprocess
    from pathlib import Path

    from sflm.cli import main

    compiler = shutil.which("gcc") or shutil.which("cc")
    if compiler is None:
        pytest.skip("no C compiler")
    root = Path(__file__).resolve().parents[2]
    text = (root / "docs" / "guide" / "getting-started.md").read_text().split("## The first run")[0]
    (tmp_path / "tests").symlink_to(root / "tests")
    monkeypatch.chdir(tmp_path)
    command = re.findall(r"```sh\n(sflm invert .*?)\n```", text)[0]
    assert main(shlex.split(command)[1:]) == 0
    (tmp_path / "main.c").write_text(re.findall(r"```c\n(.*?)```", text, re.S)[0])
    build = re.findall(r"`(gcc -std=c99 [^`]*?) && \./ff-demo`", text)[0].replace("gcc", compiler, 1)
    subprocess.run(shlex.split(build), check=True, cwd=tmp_path)
    out = subprocess.run(["./ff-demo"], capture_output=True, text=True, check=True, cwd=tmp_path).stdout
    said = re.findall(r"prints `([^`]*)`", text.replace("\n", " "))[0]
    assert out.strip() == said.replace("  ", " ")


def test_the_paper_to_code_table_names_objects_of_the_code() -> None:
    # the docs build warns (an error when strict) for a name of method.md's section 8 that is not in the code (docs/conf.py)
    import re
    import sys

    root = Path(__file__).resolve().parents[2]
    sys.path.insert(0, str(root / "docs"))
    try:
        import conf
    finally:
        sys.path.remove(str(root / "docs"))
    text = (root / "docs" / "method.md").read_text()
    start = text.index("## 8. From the paper's equations to the code")
    names = re.findall(r"`((?:modelgen|inversion|simulation)(?:\.\w+)+)`", text[start:text.index("\n## ", start + 4)])
    assert len(names) > 30 and all(conf.resolves(name) for name in names), [n for n in names if not conf.resolves(n)]
    assert not conf.resolves("inversion.methods.invert") and not conf.resolves("inversion.family.ssef.basis.no_such_function")


def test_every_markdown_table_keeps_its_columns() -> None:
    """Issue 49: a ``|`` inside back-ticks splits a table's row (GFM, MyST): the validation page showed sflm's figures
    under "the paper". Every row of every table in the documents has as many cells as its header (a pipe in a cell
    escaped as ``\\|``)."""
    import re

    root = Path(__file__).resolve().parents[2]
    broken = []
    for path in [*root.glob("docs/*.md"), *root.glob("docs/guide/*.md"), root / "README.md", root / "CHANGELOG.md"]:
        lines = path.read_text().splitlines()
        for i in range(len(lines) - 1):
            if not (lines[i].startswith("|") and re.fullmatch(r"\|[-:| ]+\|", lines[i + 1].strip())):
                continue
            width = len(re.split(r"(?<!\\)\|", lines[i].strip().strip("|")))
            for j in range(i + 2, len(lines)):
                if not lines[j].startswith("|"):
                    break
                cells = len(re.split(r"(?<!\\)\|", lines[j].strip().strip("|")))
                if cells != width:
                    broken.append(f"{path.relative_to(root)}:{j + 1}: {cells} cells under a header of {width}")
    assert not broken, broken


def test_method_md_splits_into_its_topic_pages_and_refuses_a_section_it_does_not_place() -> None:
    """Issue 49, item 3: docs/method.md on the site is a page per topic; a new numbered section that no page lists stops
    the build (it would vanish from the site), as does a listed one the file lacks."""
    import importlib.util

    root = Path(__file__).resolve().parents[2]
    spec = importlib.util.spec_from_file_location("sflm_docs_build_split", root / "docs" / "build.py")
    assert spec is not None and spec.loader is not None
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    text = (root / "docs" / "method.md").read_text()
    pages = build.method_pages(text)
    assert set(pages) == {"index", *(name for name, _, _ in build.METHOD_PAGES)}
    sections = [line for line in text.splitlines() if line.startswith("## ")]
    assert sum(page.count("\n## ") for name, page in pages.items() if name != "index") == len(sections)
    with pytest.raises(ValueError, match=r"sections \['10'\] on no page"):
        build.method_pages(text + "\n## 10. A new section\n\ntext\n")


def test_every_library_the_docs_link_to_has_an_inventory_offline() -> None:
    """docs/conf.py's intersphinx falls back, for each library, to a copy in docs/inventories/ that Sphinx can read and
    that holds the objects the API pages name (issue 49, item 4): an offline strict build links as an online one."""
    import runpy

    from sphinx.util.inventory import InventoryFile

    root = Path(__file__).resolve().parents[2]
    conf = runpy.run_path(str(root / "docs" / "conf.py"))
    mapping = conf["intersphinx_mapping"]
    assert set(mapping) == {"python", "numpy", "scipy", "sympy", "control", "casadi"}
    needed = {"numpy": ("numpy.ndarray", "numpy.typing.ArrayLike"), "scipy": ("scipy.integrate.solve_ivp", "scipy.signal.lti"),
              "sympy": ("sympy.matrices.dense.Matrix", "sympy.core.symbol.Symbol"),
              "control": ("control.StateSpace", "control.zeros"), "casadi": ("casadi.Function", "casadi.external"),
              "python": ("float", "pathlib.Path")}
    for name, (url, locations) in mapping.items():
        assert url.startswith("https://") and url.endswith("/")
        assert locations[0] is None  # the site's own inventory first
        local = Path(locations[-1])
        assert local.parent == root / "docs" / "inventories" and local.is_file(), name
        with local.open("rb") as stream:
            inventory = InventoryFile.load(stream, url, lambda base, uri: base + uri)
        objects = {key for entries in inventory.values() for key in entries}
        assert set(needed[name]) <= objects, (name, set(needed[name]) - objects)
        links = [item.uri if hasattr(item, "uri") else item[2] for entries in inventory.values() for item in entries.values()]
        assert all(link.startswith(url) for link in links)  # Sphinx 9 has items with fields, earlier ones tuples


def test_method_md_writes_its_formulas_as_latex() -> None:
    """Issue 49, item 3: docs/method.md's formulas are LaTeX (rendered by MathJax), not ASCII in code spans; code spans
    hold code (names, commands, settings). A span with a power, a sum or an integral, a tilde, a derivative's dots, a
    Greek letter or an inequality -- and no quote, call or flag that makes it code -- is a formula left behind."""
    import re

    text = (Path(__file__).resolve().parents[2] / "docs" / "method.md").read_text()
    prose = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    spans = [" ".join(s.split()) for s in re.findall(r"(?<!`)`([^`]+?)`(?!`)", prose)]
    formula = re.compile(r"(\^|\bsum_|\bint_|~|\by?ddot|\bydot|\blambda\b|\btheta|\bzeta\b|<=|>=|\bDT\b|\btau\b|\bmax \|)")
    code = re.compile(r'(^--|^sflm |^python |^pytest |"|\w\(\.\.\.|^[\w.]+$)')
    assert [s for s in spans if formula.search(s) and not code.search(s)] == []
    # and the math is there: MyST's dollar math, inline and displayed
    assert len(re.findall(r"(?<!\$)\$[^$\n]+\$(?!\$)", prose)) > 600


def test_the_landing_figure_shows_what_its_caption_says(tmp_path: Path) -> None:
    """The README's and the landing page's figure (issue 58): made by ``docs/landing_figure.py``, whose figures the caption
    quotes -- the causal table's tip within 0.42 mm during the move and at rest after it, the rigid-body feedforward's
    9.4 mm and 6.2 mm (the loop stepped exactly here, apart from the acceptance's; both held at 1 ms)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("landing_figure", ROOT / "docs" / "landing_figure.py")
    assert spec is not None and spec.loader is not None
    landing = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(landing)
    figures = landing.draw(tmp_path / "landing.png")
    assert (tmp_path / "landing.png").stat().st_size > 10_000
    assert round(1e3 * figures["causal_during"], 2) == 0.42 and figures["causal_after"] < 1e-8
    assert round(1e3 * figures["rigid_during"], 1) == 9.4 and round(1e3 * figures["rigid_after"], 1) == 6.2
    readme = (ROOT / "README.md").read_text()
    assert "docs/figures/own-aluminium-feedforward.png" in readme and (ROOT / "docs/figures/own-aluminium-feedforward.png").is_file()
    assert "0.42 mm" in readme and "9.4 mm" in readme and "6.2 mm" in readme


def test_the_guide_s_drawings_are_drawn_by_their_script_and_shown(tmp_path: Path) -> None:
    """The link's sketch and the loop's block diagram (issue 58): ``docs/diagrams.py`` draws both; the committed ones are
    on the models and closed-loop pages."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("diagrams", ROOT / "docs" / "diagrams.py")
    assert spec is not None and spec.loader is not None
    diagrams = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(diagrams)
    written = diagrams.draw(tmp_path)
    assert [p.name for p in written] == ["link-sketch.png", "loop-diagram.png"] and all(p.stat().st_size > 10_000 for p in written)
    for page, name in (("models", "link-sketch.png"), ("closed-loop", "loop-diagram.png")):
        assert f"../figures/{name}" in (ROOT / "docs" / "guide" / f"{page}.md").read_text()
        assert (ROOT / "docs" / "figures" / name).is_file()

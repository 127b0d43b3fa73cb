"""Build sflm's documentation: ``python docs/build.py OUT [--strict]`` writes HTML to OUT.

The source tree is assembled in a temporary folder: ``docs/`` (this configuration, ``method.md``, the user guide in
``docs/guide/``), the command-line reference generated from the parser (:mod:`sflm.cli_reference`), the notebooks, an
index, and an API page per package of ``modelgen``, ``inversion`` and ``simulation``: its public face (the names its
``__all__`` exports) and a map of its modules. ``--strict`` turns every warning into an error (``sphinx -W``), as the tests build it. The notebooks are executed by
the build (two at a time) and shown with their outputs, in a gallery with the last figure of each as its thumbnail;
``--no-execute`` renders them as stored (without outputs), for a quick look at the text.
"""

from __future__ import annotations

import importlib
import os
import re
import importlib.util
import pkgutil
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("modelgen", "inversion", "simulation")
#: The user guide's pages (docs/guide/), in reading order; the validation page holds the measured tables.
GUIDE = ("getting-started", "tutorial", "models", "calibration", "inverting", "methods", "systems", "robust", "explore", "closed-loop",
         "realtime", "validation", "design")


def public_modules(package: str) -> list[str]:
    """The package's modules without a leading underscore, in order."""
    module = importlib.import_module(package)
    return sorted(info.name for info in pkgutil.walk_packages(module.__path__, package + ".")
                  if not any(part.startswith("_") for part in info.name.split(".")))


#: Modules documented in full on their package's page besides its ``__all__``: what a user calls by its module's name.
SECTIONS = {"modelgen": (("modelgen.fit", "Calibration: `modelgen.fit` (`sflm fit`)"),)}


def _api_page(package: str) -> str:
    """The package's public face (the names its ``__all__`` exports, documented in full), then a map of its modules with
    their one-line summaries: what a user imports, not every module's internals."""
    lines = [f"# `{package}`", "", *_summary(package), "```{eval-rst}", f".. automodule:: {package}", "   :members:", "```", ""]
    for module, title in SECTIONS.get(package, ()):  # a layer's other public face, documented in full too
        lines += [f"## {title}", "", *_summary(module), "```{eval-rst}", f".. automodule:: {module}", "   :members:", "```", ""]
    lines += ["## Its modules", "", f"The names above are `{package}`'s public face; the modules below hold them and the "
             "rest of the layer (each documented in its docstrings: `help(module)`).", "", "| module | what it holds |", "|---|---|"]
    for name in public_modules(package):
        doc = (importlib.import_module(name).__doc__ or "").strip().split("\n\n")[0].replace("\n", " ").replace("|", "\\|")
        lines.append(f"| `{name}` | {doc} |")
    return "\n".join(lines) + "\n"


#: ``docs/method.md`` on the site: a page per topic, its numbered sections (``## 5f. ...``) in the order given. The file
#: stays one (the docstrings cite "docs/method.md section 5f"); a section no page lists stops the build.
METHOD_PAGES = (
    ("model", "The model", ("1", "1a", "2")),
    ("inversion", "The inversion by output redefinition", ("3", "5", "5a", "5b", "5b'", "5c", "5d", "5e", "5g")),
    ("acceptance", "Acceptance: what reaches the link", ("4", "4b", "5j", "5k")),
    ("limits", "Limits, optimal control and the re-plan", ("7a", "5f", "5f''", "5f'", "5i", "5h")),
    ("closed-loop", "The closed loop and the feedforward as C", ("6", "6a")),
    ("reference", "The paper's cases, the paper-to-code table, the bibliography", ("7", "8", "9")),
)


def method_pages(text: str) -> dict[str, str]:
    """``docs/method.md`` split into :data:`METHOD_PAGES` and an ``index`` (its title, its introduction and the pages'
    table of contents).

    Parameters
    ----------
    text : str
        The contents of ``docs/method.md``.

    Raises
    ------
    ValueError
        For a numbered section no page lists, or a page's section the file lacks.
    """
    import re

    parts = re.split(r"(?m)^(?=## )", text)
    intro, sections = parts[0], {re.match(r"## (\S+?)\.? ", p).group(1): p for p in parts[1:]}  # type: ignore[union-attr]
    listed = [number for _, _, numbers in METHOD_PAGES for number in numbers]
    unplaced = [n for n in sections if n not in listed]
    absent = [n for n in listed if n not in sections]
    if unplaced or absent:
        raise ValueError(f"docs/method.md and docs/build.py's METHOD_PAGES disagree: sections {unplaced} on no page, "
                         f"{absent} listed but not in the file")
    title, _, rest = intro.partition("\n")
    pages = {"index": "\n".join([title, rest.rstrip(), "", "```{toctree}", ":maxdepth: 2", "",
                                  *(name for name, _, _ in METHOD_PAGES), "```", ""])}
    for name, heading, numbers in METHOD_PAGES:
        pages[name] = f"# {heading}\n\n" + "".join(sections[n].rstrip() + "\n\n" for n in numbers)
    return pages


def _summary(module: str) -> list[str]:
    """A summary table of the names ``module`` exports (its ``__all__``): each with its docstring's first paragraph, linked
    to its entry below."""
    import inspect

    imported = importlib.import_module(module)
    names = [n for n in getattr(imported, "__all__", ()) if callable(getattr(imported, n, None))]
    if not names:
        return []
    rows = ["| name | what it is |", "|---|---|"]
    for name in names:
        obj = getattr(imported, name)
        # the docstring's whole first paragraph (autosummary cut it at the first full stop: "Simulate the closed loop (Eq.")
        first = (inspect.getdoc(obj) or "").split("\n\n")[0]
        text = " ".join(first.split()).replace("|", "\\|")
        text = re.sub(r":(\w+):`([^`]+)`", r"{py:\1}`\2`", text).replace("``", "`")  # reST roles and literals, as MyST writes them
        rows.append(f"| {{py:obj}}`{name} <{module}.{name}>` | {text} |")
    return [*rows, ""]


def _downloadable(folder: Path) -> None:
    """Each notebook in ``folder`` with a line under its title that offers the notebook itself (``.ipynb``)."""
    import nbformat

    for path in sorted(folder.glob("*.ipynb")):
        nb = nbformat.read(path, as_version=4)
        link = nbformat.v4.new_markdown_cell(f"{{download}}`Download this notebook ({path.name}) <{path.name}>`")
        nb.cells.insert(1 if nb.cells and nb.cells[0].cell_type == "markdown" else 0, link)
        nbformat.write(nb, path)


def _executed(notebooks: list[Path], folder: Path) -> None:
    """Each notebook executed (from its own folder, as CI runs them) into ``folder``, two at a time: the gallery shows
    their outputs, computed by this build."""
    from concurrent.futures import ThreadPoolExecutor

    import nbformat
    from nbclient import NotebookClient

    done: list[str] = []

    def run(notebook: Path) -> None:
        PROGRESS.stage = f"executing the notebooks: {notebook.name} ({len(done)} of {len(notebooks)} done)"
        nb = nbformat.read(notebook, as_version=4)
        NotebookClient(nb, timeout=600, resources={"metadata": {"path": str(notebook.parent)}}).execute()
        nbformat.write(nb, folder / notebook.name)
        done.append(notebook.name)
        PROGRESS.stage = f"executing the notebooks: {notebook.name} done ({len(done)} of {len(notebooks)})"

    with ThreadPoolExecutor(max_workers=2) as pool:
        list(pool.map(run, notebooks))


def _gallery(notebooks: list[Path], folder: Path) -> str:
    """The notebooks' gallery page: a thumbnail each (its last figure, when it has one) with its title and a link."""
    import base64
    import json

    (folder / "thumbnails").mkdir(exist_ok=True)
    lines = ["# Gallery", "", "The notebooks, executed by this build (`pytest --nbmake notebooks` runs them in CI too).", ""]
    for notebook in notebooks:
        cells = json.loads((folder / notebook.name).read_text())["cells"]
        title = next((c["source"] if isinstance(c["source"], str) else "".join(c["source"]) for c in cells
                      if c["cell_type"] == "markdown"), notebook.stem).splitlines()[0].lstrip("# ").strip()
        images = [o["data"]["image/png"] for c in cells if c["cell_type"] == "code" for o in c.get("outputs", [])
                  if "image/png" in o.get("data", {})]
        lines += [f"## [{title}](notebooks/{notebook.stem}.ipynb)", "",
                  f"{{download}}`Download the notebook ({notebook.name}) <notebooks/{notebook.name}>`", ""]
        if images:
            picture = folder / "thumbnails" / f"{notebook.stem}.png"
            data = images[-1] if isinstance(images[-1], str) else "".join(images[-1])
            picture.write_bytes(base64.b64decode(data))
            lines += [f"[![{title}](notebooks/thumbnails/{notebook.stem}.png)](notebooks/{notebook.stem}.ipynb)", ""]
    return "\n".join(lines)


def assemble(source: Path, execute: bool = False) -> None:
    """Write the documentation's source tree into ``source`` (the notebooks executed when ``execute``)."""
    source.mkdir(parents=True, exist_ok=True)
    shutil.copy(ROOT / "docs" / "conf.py", source / "conf.py")
    shutil.copytree(ROOT / "docs" / "_static", source / "_static", dirs_exist_ok=True)
    # the libraries' inventories, which conf.py's intersphinx reads where their sites cannot be reached
    shutil.copytree(ROOT / "docs" / "inventories", source / "inventories", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("*.py", "*.md"))
    (source / "guide").mkdir(exist_ok=True)
    for page in GUIDE:
        text = (ROOT / "docs" / "guide" / f"{page}.md").read_text()
        if execute:  # the figures of the plotting commands a page runs, made by the build from the commands shown
            text = _with_figures(page, text, source / "figures" / "guide")
        (source / "guide" / f"{page}.md").write_text(text)
    (source / "method").mkdir(exist_ok=True)
    for name, text in method_pages((ROOT / "docs" / "method.md").read_text()).items():
        if execute:  # a guide command's figure where the method explains it (made above, with the guide's)
            for anchor, figure, caption in METHOD_FIGURES.get(name, ()):
                end = text.index("\n\n", text.index(anchor))
                text = text[:end] + _figure(figure, caption) + text[end:]
        (source / "method" / f"{name}.md").write_text(text)
    from sflm.cli import _parser
    from sflm.cli_reference import reference_markdown

    (source / "cli.md").write_text(reference_markdown(_parser()))
    notebooks = sorted((ROOT / "notebooks").glob("*.ipynb"))
    (source / "notebooks").mkdir(exist_ok=True)
    if execute:
        _executed(notebooks, source / "notebooks")
    else:
        for notebook in notebooks:
            shutil.copy(notebook, source / "notebooks" / notebook.name)
    (source / "gallery.md").write_text(_gallery(notebooks, source / "notebooks"))
    _downloadable(source / "notebooks")
    (source / "figures").mkdir(exist_ok=True)
    for figure in sorted((ROOT / "docs" / "figures").glob("*.png")):  # the landing figure and the drawings (docs/diagrams.py)
        shutil.copy(figure, source / "figures" / figure.name)
    (source / "changelog.md").write_text((ROOT / "CHANGELOG.md").read_text())
    (source / "citation.md").write_text(_citation())
    pages = []
    for package in PACKAGES:
        (source / f"api-{package}.md").write_text(_api_page(package))
        pages.append(f"api-{package}")
    index = [*_landing(), "```{toctree}", ":maxdepth: 1", ":caption: User guide", "",
             *(f"guide/{page}" for page in GUIDE), "cli", "```", "",
             "```{toctree}", ":maxdepth: 1", ":caption: The method", "", "method/index", "```", "",
             "```{toctree}", ":maxdepth: 1", ":caption: Notebooks", "", "gallery"]
    index += [f"notebooks/{n.stem}" for n in notebooks] + ["```", "", "```{toctree}", ":maxdepth: 1", ":caption: API reference", ""]
    index += pages + ["```", "", "```{toctree}", ":maxdepth: 1", ":caption: About", "", "changelog", "citation", "```", ""]
    (source / "index.md").write_text("\n".join(index))


def _citation() -> str:
    """The how-to-cite page: ``CITATION.cff`` as it is, and the two references as BibTeX read from it."""
    text = (ROOT / "CITATION.cff").read_text()

    def field(name: str, block: str) -> str:
        import re

        found = re.search(rf"^[\s-]*{name}:\s*\"?([^\"\n]+)\"?\s*$", block, re.M)
        return found.group(1).strip() if found else ""

    software, _, cited = text.partition("references:")
    bibtex = ["@software{sflm,", f"  title = {{{field('title', software)}}},", f"  author = {{{field('name', software)}}},",
              f"  version = {{{field('version', software)}}},", f"  year = {{{field('date-released', software)[:4]}}},", "}", "",
              "@article{sflm_paper,", f"  title = {{{field('title', cited)}}},", f"  journal = {{{field('journal', cited)}}},",
              f"  volume = {{{field('volume', cited)}}},", f"  number = {{{field('issue', cited)}}},",
              f"  year = {{{field('year', cited)}}},", "}"]
    return "\n".join(["# How to cite", "", "If you use sflm, please cite the software and the paper whose method it implements "
                      "(`CITATION.cff` in the repository, which GitHub and Zenodo read).", "", "```bibtex", *bibtex, "```", "",
                      "## CITATION.cff", "", "```yaml", text.rstrip(), "```", ""])


#: The plotting commands a guide page shows, run by the build (in this process, from the repository's root): the page,
#: the command as the page prints it (the figures go under it), the arguments run, the figures shown and their caption.
GUIDE_FIGURES: dict[str, list[tuple[str, list[str], list[str], str]]] = {
    "getting-started": [
        ("sflm invert tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --plot --export-c ff/",
         ["invert", "tests/data/own-aluminium.toml", "--trajectory", "smoothstep:0.5:2:2", "--plot"],
         ["torque.png", "output.png"],
         "What `sflm invert ... --plot` draws: the feedforward torque (the segments' joints in grey), and the desired and the "
         "redefined tip (made by this build from the command above)."),
    ],
    "tutorial": [
        ("sflm invert tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --plot --out tutorial/invert",
         ["invert", "tests/data/own-aluminium.toml", "--trajectory", "smoothstep:0.5:2:2", "--plot"],
         ["torque.png", "output.png"],
         "The feedforward torque (the segments' joints in grey), and the desired and the redefined tip."),
        ("sflm simulate tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --controller pd --plot --out tutorial/loop",
         ["simulate", "tests/data/own-aluminium.toml", "--trajectory", "smoothstep:0.5:2:2", "--controller", "pd", "--plot"],
         ["tip_error.png"],
         "The tip's error in the closed loop (feedforward and joint PD, nonlinear plant): during the move, and at rest after it."),
        ("sflm invert tests/data/own-aluminium.toml --trajectory smoothstep:0.5:shortest:2 --max-torque 0.1 --max-torque-rate 0.002 --plot --out tutorial/shortest",
         ["invert", "tests/data/own-aluminium.toml", "--trajectory", "smoothstep:0.5:shortest:2", "--max-torque", "0.1",
          "--max-torque-rate", "0.002", "--plot"],
         ["shortest.png", "torque.png"],
         "The least tip error within the drive's bounds against the move's duration (the bounded causal limit: below the "
         "bound's crossing no table exists), the returned move and the rigid floor; and the returned table's torque, on "
         "its bound."),
    ],
    "calibration": [
        ("sflm fit tests/data/glass-fibre-rod.toml --data tests/data/bench-doublet.csv --plot",
         ["fit", "tests/data/glass-fibre-rod.toml", "--data", "tests/data/bench-doublet.csv", "--plot"],
         ["fit.png"],
         "What `sflm fit ... --plot` draws for a record: the measured hub angle (the encoder's counts), the nominal and the "
         "fitted model; below, the residual tests -- each channel's residual against the torque at each lag, in its "
         "standard deviations were the model right, and the band beyond which the fit is refused (made by this build from "
         "the command above)."),
    ],
    "explore": [
        ("sflm explore paper-sim --segments 5,10,20 --h 1,2 --plot --workers 2",
         ["explore", "paper-sim", "--segments", "5,10,20", "--h", "1,2", "--plot", "--workers", "1"],
         ["pareto.png"],
         "What `sflm explore ... --plot` draws: every member's redefinition error against its peak torque by joining, the "
         "Pareto front, the paper's member and the one the automatic choice takes, and the optimal-control front held at "
         "10 ms beside them — the least peak torque any causal feedforward needs for each error (made by this build from "
         "the command above, on one worker)."),
    ],
    "methods": [
        ("sflm compare tests/data/own-aluminium.toml --trajectory smoothstep:0.5:2:2 --plot",
         ["compare", "tests/data/own-aluminium.toml", "--trajectory", "smoothstep:0.5:2:2", "--plot"],
         ["compare.png"],
         "What `sflm compare ... --plot` draws: each method's torque on one time axis (pre-actuation included) and its tip "
         "error (made by this build from the command above)."),
        ("sflm invert tests/data/steel-strip-3mm-drive.toml --trajectory shortest:0.5 --max-error 0.005 --period 0.002 --plot",
         ["invert", "tests/data/steel-strip-3mm-drive.toml", "--trajectory", "shortest:0.5", "--max-error", "0.005", "--period",
          "0.002", "--plot"],
         ["shortest.png", "torque.png"],
         "The fastest move of any profile: the least tip error after the move within the drive's bounds (and the link bending "
         "at most 10 % of its length) against the move's duration -- below the bound's crossing no causal table of any "
         "profile exists --, the returned move, the rigid floor, the shortest smoothstep and the ZV-shaped bang-bang; and "
         "the returned table's torque (made by this build from the command above)."),
    ],
}


#: Figures of :data:`GUIDE_FIGURES` shown on a method page too: the page, the start of the paragraph they follow, the
#: figure's name as the guide's build wrote it, and its caption.
METHOD_FIGURES: dict[str, list[tuple[str, str, str]]] = {
    "limits": [
        ("**The shortest duration within the bounds**", "tutorial-invert-2-shortest.png",
         "The bounded causal limit against the move's duration: the tutorial's aluminium link (0.5 m along a quintic, a "
         "drive of 0.1 N m changing at most 0.002 N m a 1 ms row). Below the duration where it crosses the bound no causal "
         "table within the drive exists (the certificate); the returned move just above it, and the rigid body's floor. Made "
         "by this build from `sflm invert tests/data/own-aluminium.toml --trajectory smoothstep:0.5:shortest:2 --max-torque "
         "0.1 --max-torque-rate 0.002 --plot` ([the tutorial](../guide/tutorial.md), section 4)."),
    ],
}


def _figure(name: str, caption: str, shown: bool = True) -> str:
    """A figure the build made (``figures/guide/NAME``) as a page's Markdown: the caption under it where ``shown``, and
    as its alternative text in plain words (no code spans or links in an attribute a reader hears)."""
    import re

    alt = re.sub(r"\[([^\]]+)\]\([^)]+\)", r"\1", caption).replace("`", "")
    return f"\n\n```{{figure}} ../figures/guide/{name}\n:alt: {alt}\n:width: 100%\n\n{caption if shown else ''}\n```"


def _with_figures(page: str, text: str, folder: Path) -> str:
    """``text`` with the figures of its plotting commands (:data:`GUIDE_FIGURES`) after the code block that shows each."""
    import contextlib
    import io
    import os

    from sflm.cli import main

    seen: list[str] = []
    for shown, arguments, figures, caption in GUIDE_FIGURES.get(page, []):
        seen.append(arguments[0])  # a command a page runs twice: its second run's figures under other names
        out = folder / (f"{page}-{arguments[0]}" + (f"-{seen.count(arguments[0])}" if seen.count(arguments[0]) > 1 else ""))
        before = os.getcwd()
        os.chdir(ROOT)
        try:
            PROGRESS.stage = f"the figures of guide/{page}.md: sflm {' '.join(arguments)}"
            with contextlib.redirect_stdout(io.StringIO()):
                # sflm fit writes a file (the calibrated geometry, its figure beside it); the others a folder
                status = main([*arguments, "--out", str(out / "calibrated.toml" if arguments[0] == "fit" else out), "-q"])
        finally:
            os.chdir(before)
        if status != 0:
            raise RuntimeError(f"guide/{page}.md: `{shown}` exited with {status}")
        for name in figures:  # named for its page and command: Sphinx copies every picture into one _images folder
            shutil.copyfile(out / name, folder / f"{out.name}-{name}")
        at = text.index(shown)
        end = text.index("```", at) + 3  # the end of the code block that shows the command
        block = "".join(_figure(f"{out.name}-{name}", caption, k == len(figures) - 1) for k, name in enumerate(figures))
        text = text[:end] + block + text[end:]
    return text


def _landing() -> list[str]:
    """The landing page's text: what sflm does, with one figure, the two install commands (the README's quick start) and
    a five-line example."""
    readme = (ROOT / "README.md").read_text()
    start = readme.index("## Quick start")
    block = readme[readme.index("```", start):]
    commands = block[: block.index("```", 3) + 3]
    return ["# sflm", "",
            "sflm models a single flexible link manipulator and computes a causal feedforward torque for its tip to follow a "
            "desired trajectory: SymPy derives the assumed-mode equations of a link described in a geometry file, CasADi "
            "emits C for the model, and the numeric layer inverts the dynamics piece by piece, redefining the desired output "
            "with sums of stable exponentials, so that the torque stays bounded, continuous and causal although the link is "
            "non-minimum phase. Every answer is judged where it reaches the link -- held at the controller's period, "
            "through the window after the move, with more modes -- or refused with its figures.", "",
            "```{figure} figures/own-aluminium-feedforward.png", ":alt: the tip's error under sflm's causal feedforward and "
            "under the rigid-body feedforward, the joint PD closed", ":width: 100%", "", "What the causal feedforward buys "
            "(`python docs/landing_figure.py`): the tutorial's aluminium link, 0.5 m in 2 s, each table held at 1 ms with "
            "the joint PD closed. The table `sflm invert` returns keeps the tip within 0.42 mm during the move and at rest "
            "after it (1e-10 m); the rigid-body feedforward (the link's inertia times the hub's acceleration) leaves it 9.4 mm "
            "off during the move and 6.2 mm after it.", "```", "",
            "## Install and run", "", "The README's quick start: the first command installs sflm and runs it on its built-in "
            "default (the paper's simulation, end to end), the second installs the test dependencies and runs the tests.", "", commands, "",
            "## Six lines of Python", "", "```python", "import modelgen, inversion",
            "model = modelgen.load(\"paper-sim\")          # derived, compiled once",
            "move = inversion.smoothstep(1.57, 5.5, 5)   # 1.57 m in 5.5 s",
            "problem = inversion.Problem(model, move)    # the bounds and sampling: the defaults",
            "result = inversion.invert(problem)          # the paper's member, judged as a 1 kHz controller holds it",
            "print(result.summary[\"peak_torque\"], result.summary[\"max_redefinition_error\"])", "```", ""]


def build(out: Path, strict: bool = False, execute: bool = True) -> int:
    """Assemble the sources (the notebooks executed unless ``execute`` is false) and run Sphinx's HTML builder into
    ``out``; its exit status."""
    from sphinx.cmd.build import build_main

    with tempfile.TemporaryDirectory() as tmp, PROGRESS:
        source = Path(tmp) / "source"
        PROGRESS.stage = "assembling the sources"
        assemble(source, execute)
        PROGRESS.stage = "Sphinx: reading and writing the pages"
        return build_main([str(source), str(out), "-b", "html", "-q", "-d", str(Path(tmp) / "doctrees"), *(["-W", "--keep-going"] if strict else [])])


class Progress:
    """A line on stderr at least every ``every`` seconds while the build runs: its stage and the time so far (the notebooks'
    execution and Sphinx's writing are minutes of silence otherwise)."""

    def __init__(self, every: float = 5.0) -> None:
        self.every, self.stage, self._stop = every, "starting", None

    def __enter__(self) -> "Progress":
        import threading
        import time

        self._stop = threading.Event()
        started = time.perf_counter()

        def beat() -> None:
            while not self._stop.wait(self.every):  # type: ignore[union-attr]
                print(f"docs/build.py: {self.stage} ({time.perf_counter() - started:.0f} s)", file=sys.stderr, flush=True)

        threading.Thread(target=beat, daemon=True).start()
        return self

    def __exit__(self, *exc: object) -> None:
        if self._stop is not None:
            self._stop.set()


#: The build's progress display.
PROGRESS = Progress()


#: What the build imports, and what the notebooks it executes import beyond the package's own dependencies: the ``docs``
#: extra installs them all (``pip install -e ".[docs]"``).
NEEDS = ("sphinx", "myst_nb", "numpydoc", "nbformat", "nbclient", "ipykernel", "control", "furo", "sphinx-mathjax-offline")
USAGE = "usage: python docs/build.py OUT [--strict] [--no-execute]"


def missing(names: tuple[str, ...] | None = None) -> list[str]:
    """Those of ``names`` (default :data:`NEEDS`) that cannot be imported here."""
    return [name for name in (NEEDS if names is None else names) if importlib.util.find_spec(name) is None]


def main(argv: list[str]) -> int:
    """Check the arguments and what the build needs before any work, then build; the exit status (2: a refusal, one line
    on stderr)."""
    flags = [a for a in argv if a.startswith("-")]
    arguments = [a for a in argv if not a.startswith("-")]
    unknown = [f for f in flags if f not in ("--strict", "--no-execute")]
    if len(arguments) != 1 or unknown:
        print(f"python docs/build.py: error: {'unknown option ' + unknown[0] if unknown else 'one OUT folder expected'}; {USAGE}",
              file=sys.stderr)
        return 2
    out = Path(arguments[0])
    if out.exists() and not out.is_dir():
        print(f"python docs/build.py: error: OUT = {out} is a file, not a folder", file=sys.stderr)
        return 2
    try:  # a folder that cannot be written is refused before the work (it was Sphinx's crash report after it)
        out.mkdir(parents=True, exist_ok=True)
        probe = out / f".write-probe-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        print(f"python docs/build.py: error: OUT = {out} cannot be written ({exc.strerror or exc}); expected a folder of yours "
              "with room", file=sys.stderr)
        return 2
    absent = missing()
    if absent:
        print(f"python docs/build.py: error: {', '.join(absent)} not installed: pip install -e \".[docs]\" installs what the "
              "documentation and its notebooks need", file=sys.stderr)
        return 2
    return build(out, "--strict" in flags, "--no-execute" not in flags)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

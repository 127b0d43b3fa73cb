"""Build sflm's documentation: ``python docs/build.py OUT [--strict]`` writes HTML to OUT.

The source tree is assembled in a temporary folder: ``docs/`` (this configuration, ``method.md``, the user guide in
``docs/guide/``), the command-line reference generated from the parser (:mod:`sflm.cli_reference`), the notebooks, an
index, and an API page per public module of ``modelgen``, ``inversion`` and ``simulation`` (``automodule`` of each, the
members its ``__all__`` names). ``--strict`` turns every warning into an error (``sphinx -W``), as the tests build it.
"""

from __future__ import annotations

import importlib
import pkgutil
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("modelgen", "inversion", "simulation")
#: The user guide's pages (docs/guide/), in reading order; the validation page holds the measured tables.
GUIDE = ("getting-started", "models", "calibration", "inverting", "closed-loop", "realtime", "validation", "design")


def public_modules(package: str) -> list[str]:
    """The package's modules without a leading underscore, in order."""
    module = importlib.import_module(package)
    return sorted(info.name for info in pkgutil.walk_packages(module.__path__, package + ".")
                  if not any(part.startswith("_") for part in info.name.split(".")))


def assemble(source: Path) -> None:
    """Write the documentation's source tree into ``source``."""
    source.mkdir(parents=True, exist_ok=True)
    for name in ("conf.py", "method.md"):
        shutil.copy(ROOT / "docs" / name, source / name)
    (source / "guide").mkdir(exist_ok=True)
    for page in GUIDE:
        shutil.copy(ROOT / "docs" / "guide" / f"{page}.md", source / "guide" / f"{page}.md")
    from sflm.cli import _parser
    from sflm.cli_reference import reference_markdown

    (source / "cli.md").write_text(reference_markdown(_parser()))
    notebooks = sorted((ROOT / "notebooks").glob("*.ipynb"))
    (source / "notebooks").mkdir(exist_ok=True)
    for notebook in notebooks:
        shutil.copy(notebook, source / "notebooks" / notebook.name)
    pages = []
    for package in PACKAGES:
        lines = [f"# `{package}`", "", "```{eval-rst}", f".. automodule:: {package}", "   :no-members:", "```", ""]
        for name in public_modules(package):
            lines += [f"## `{name}`", "", "```{eval-rst}", f".. automodule:: {name}", "```", ""]
        (source / f"api-{package}.md").write_text("\n".join(lines))
        pages.append(f"api-{package}")
    index = ["# sflm", "", "Single flexible link manipulator: symbolic assumed-mode models, generated C, and piece-wise causal",
             "inversion by output redefinition.", "", "```{toctree}", ":maxdepth: 1", ":caption: User guide", "",
             *(f"guide/{page}" for page in GUIDE), "cli", "```", "",
             "```{toctree}", ":maxdepth: 1", ":caption: The method", "", "method", "```", "",
             "```{toctree}", ":maxdepth: 1", ":caption: Notebooks", ""]
    index += [f"notebooks/{n.stem}" for n in notebooks] + ["```", "", "```{toctree}", ":maxdepth: 1", ":caption: API reference", ""]
    index += pages + ["```", ""]
    (source / "index.md").write_text("\n".join(index))


def build(out: Path, strict: bool = False) -> int:
    """Assemble the sources and run Sphinx's HTML builder into ``out``; its exit status."""
    from sphinx.cmd.build import build_main

    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp) / "source"
        assemble(source)
        return build_main([str(source), str(out), "-b", "html", "-q", "-d", str(Path(tmp) / "doctrees"), *(["-W", "--keep-going"] if strict else [])])


if __name__ == "__main__":
    arguments = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(arguments) != 1:
        sys.exit("usage: python docs/build.py OUT [--strict]")
    sys.exit(build(Path(arguments[0]), "--strict" in sys.argv))

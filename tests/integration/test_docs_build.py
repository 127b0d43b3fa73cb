"""The documentation builds: the API reference from the numpydoc docstrings, docs/method.md and the notebooks, with
every Sphinx warning an error (issue 25)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
def test_the_documentation_builds_without_a_warning(tmp_path: Path) -> None:
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        spec = importlib.util.spec_from_file_location("sflm_docs_build", ROOT / "docs" / "build.py")
        assert spec is not None and spec.loader is not None
        build = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(build)
    finally:
        sys.path.remove(str(ROOT / "docs"))
    assert build.build(tmp_path / "html", strict=True) == 0
    api = (tmp_path / "html" / "api-inversion.html").read_text()
    # the reference is the docstrings': invert's parameters, rendered by numpydoc
    assert 'id="inversion.invert"' in api and "Parameters" in api and "Order of smooth joining" in api
    # the calibration API in full on modelgen's page (issue 48: it was only a line in the modules' table)
    calibration = (tmp_path / "html" / "api-modelgen.html").read_text()
    assert all(f'id="modelgen.fit.{name}"' in calibration for name in ("fit", "fit_file", "read_data", "FitError"))
    assert (tmp_path / "html" / "method.html").stat().st_size > 50_000
    assert len(list((tmp_path / "html" / "notebooks").glob("*.html"))) == len(list((ROOT / "notebooks").glob("*.ipynb")))
    # the user guide, and the command-line reference generated from the parser
    guide = sorted(p.stem for p in (tmp_path / "html" / "guide").glob("*.html"))
    assert guide == sorted(p.stem for p in (ROOT / "docs" / "guide").glob("*.md"))
    assert "--preview" in (tmp_path / "html" / "cli.html").read_text()
    assert "causal limit" in (tmp_path / "html" / "guide" / "inverting.html").read_text()
    # the notebooks executed by the build: each rendered with its figures, a thumbnail each in the gallery
    gallery = (tmp_path / "html" / "gallery.html").read_text()
    notebooks = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert all(f"_images/{name}.png" in gallery for name in notebooks)
    assert all("<img" in (tmp_path / "html" / "notebooks" / f"{name}.html").read_text() for name in notebooks)
    # no page links to a page or a picture that is not there
    import re

    broken = []
    for page in (tmp_path / "html").rglob("*.html"):
        for ref in re.findall(r'(?:href|src)="([^"]+)"', page.read_text()):
            if not re.match(r"^[a-z]+:", ref) and not ref.startswith("#"):
                if not (page.parent / ref.split("#")[0].split("?")[0]).exists():
                    broken.append((page.name, ref))
    assert broken == []

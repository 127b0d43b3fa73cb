"""The documentation builds: the API reference from the numpydoc docstrings, docs/method.md and the notebooks, with
every Sphinx warning an error (issue 25)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The documentation built once for the module's tests, strict (every warning an error)."""
    tmp_path = tmp_path_factory.mktemp("docs")
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        spec = importlib.util.spec_from_file_location("sflm_docs_build", ROOT / "docs" / "build.py")
        assert spec is not None and spec.loader is not None
        build = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(build)
    finally:
        sys.path.remove(str(ROOT / "docs"))
    assert build.build(tmp_path / "html", strict=True) == 0
    return tmp_path


@pytest.mark.slow  # the documentation built (170 s of CPU), as the tests beside it
def test_the_command_reference_on_the_page_is_the_help(site: Path, capsys: pytest.CaptureFixture[str],
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 58, item 1: on the rendered page (not in its Markdown) every option keeps its help text -- choices ``{a|b}``
    split the table row and 27 options lost theirs -- and every ``<name>`` placeholder (it went in as a raw tag)."""
    import html
    import re

    from sflm.cli import main, parser

    page = (site / "html" / "cli.html").read_text()
    monkeypatch.setenv("COLUMNS", "100000")
    sub = next(a for a in parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    for command in sub.choices:
        with pytest.raises(SystemExit):
            main([command, "--help"])
        printed = " ".join(capsys.readouterr().out.split())
        section = page.split(f'id="sflm-{command}"', 1)[1].split("</h2>", 1)[1].split("<h2", 1)[0]
        rows = re.findall(r"<tr[^>]*>(.*?)</tr>", section, re.S)[1:]  # the header's row aside
        assert rows, command
        for row in rows:
            cells = [" ".join(html.unescape(re.sub(r"<[^>]+>", "", c)).split()) for c in re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)]
            assert len(cells) == 3, (command, cells)  # a row split by a pipe has more
            if cells[2]:
                assert cells[2] in printed, (command, cells)
    assert "sflm-out/&lt;name&gt;/fit/&lt;name&gt;-calibrated.toml" in page


@pytest.mark.slow
def test_the_documentation_builds_without_a_warning(site: Path) -> None:
    tmp_path = site
    api = (tmp_path / "html" / "api-inversion.html").read_text()
    # the reference is the docstrings': invert's parameters, rendered by numpydoc
    assert 'id="inversion.invert"' in api and "Parameters" in api and "Order of smooth joining" in api
    # the calibration API in full on modelgen's page (issue 48: it was only a line in the modules' table)
    calibration = (tmp_path / "html" / "api-modelgen.html").read_text()
    assert all(f'id="modelgen.fit.{name}"' in calibration for name in ("fit", "fit_file", "read_data", "FitError"))
    # method.md, a page per topic (docs/build.py's METHOD_PAGES), every numbered section on one of them
    method = {p.stem: p.read_text() for p in (tmp_path / "html" / "method").glob("*.html")}
    assert set(method) == {"index", "model", "inversion", "acceptance", "limits", "closed-loop", "reference"}
    assert sum(len(t) for t in method.values()) > 150_000 and "Modal damping" in method["model"]
    assert len(list((tmp_path / "html" / "notebooks").glob("*.html"))) == len(list((ROOT / "notebooks").glob("*.ipynb")))
    # the user guide, and the command-line reference generated from the parser
    guide = sorted(p.stem for p in (tmp_path / "html" / "guide").glob("*.html"))
    assert guide == sorted(p.stem for p in (ROOT / "docs" / "guide").glob("*.md"))
    assert "--preview" in (tmp_path / "html" / "cli.html").read_text()
    # issue 58: the guide pages that run a plotting command show its figures, made by the build; a changelog, a page on
    # citing, a favicon (it was a 404 on every page); the summary tables keep their first sentence whole ("(Eq.")
    started = (tmp_path / "html" / "guide" / "getting-started.html").read_text()
    assert "_images/getting-started-invert-torque.png" in started and "_images/getting-started-invert-output.png" in started
    # the tutorial (issue 58): its three plotting commands' figures, the second invert's under names of its own
    tutorial = (tmp_path / "html" / "guide" / "tutorial.html").read_text()
    for name in ("tutorial-invert-torque.png", "tutorial-simulate-tip_error.png", "tutorial-invert-2-shortest.png",
                 "tutorial-invert-2-torque.png"):
        assert f"_images/{name}" in tutorial and (tmp_path / "html" / "_images" / name).is_file(), name
    assert "_images/methods-compare-compare.png" in (tmp_path / "html" / "guide" / "methods.html").read_text()
    # every guide page whose shell blocks run a plotting command shows a figure the build made from one (explore's
    # Pareto plot was missing); a synopsis's "[--plot]" is not a run
    import re

    for source in sorted((ROOT / "docs" / "guide").glob("*.md")):
        blocks = re.findall(r"```(?:sh|shell|console)\n(.*?)```", source.read_text(), re.S)
        if any(re.match(r"\s*sflm \S+ .*(?<!\[)--plot\b", line) for block in blocks for line in block.splitlines()):
            built = (tmp_path / "html" / "guide" / f"{source.stem}.html").read_text()
            assert re.search(rf'<img[^>]+src="[^"]*_images/{source.stem}-[^"]+\.png"', built), source.name
    # the figures' alternative text is plain text (a caption's code spans and links were in it as Markdown)
    for page in (tmp_path / "html").rglob("*.html"):
        assert not [alt for alt in re.findall(r'<img[^>]+alt="([^"]*)"', page.read_text()) if "`" in alt or "](" in alt], page.name
    # issue 61: the calibration guide's bench record, fitted, with its residual tests
    assert "_images/calibration-fit-fit.png" in (tmp_path / "html" / "guide" / "calibration.html").read_text()
    assert "How to cite" in (tmp_path / "html" / "citation.html").read_text()
    assert "Changelog" in (tmp_path / "html" / "changelog.html").read_text()
    assert 'icon" href="_static/favicon.svg"' in (tmp_path / "html" / "index.html").read_text() and (tmp_path / "html" / "_static" / "favicon.svg").is_file()
    assert "Simulate the closed loop (Eq. (40)), linear or nonlinear." in (tmp_path / "html" / "api-simulation.html").read_text()
    assert "causal limit" in (tmp_path / "html" / "guide" / "inverting.html").read_text()
    # the notebooks executed by the build: each rendered with its figures, a thumbnail each in the gallery
    gallery = (tmp_path / "html" / "gallery.html").read_text()
    notebooks = sorted(p.stem for p in (ROOT / "notebooks").glob("*.ipynb"))
    assert all(f"_images/{name}.png" in gallery for name in notebooks)
    assert all("<img" in (tmp_path / "html" / "notebooks" / f"{name}.html").read_text() for name in notebooks)
    # no page links to a page or a picture that is not there
    broken = []
    for page in (tmp_path / "html").rglob("*.html"):
        for ref in re.findall(r'(?:href|src)="([^"]+)"', page.read_text()):
            if not re.match(r"^[a-z]+:", ref) and not ref.startswith("#"):
                if not (page.parent / ref.split("#")[0].split("?")[0]).exists():
                    broken.append((page.name, ref))
    assert broken == []


#: The libraries whose objects the API pages name, and where a link to each must lead (docs/conf.py's intersphinx).
SITES = {"numpy": "https://numpy.org/doc/", "scipy": "https://docs.scipy.org/doc/", "sympy": "https://docs.sympy.org/",
         "control": "https://python-control.readthedocs.io/", "casadi": "https://web.casadi.org/",
         "python": "https://docs.python.org/3/"}


@pytest.mark.slow
def test_the_api_pages_link_to_the_libraries_they_name_offline(site: Path) -> None:
    """Issue 49, item 4: each name of NumPy, SciPy, SymPy, python-control or CasADi written as a cross reference in a
    docstring is a link to that library's site -- built here without a network, from docs/inventories/ (an unresolved
    reference renders as plain code, silently, which this catches) -- and the parameter types link (numpydoc)."""
    import re

    xref = re.compile(r'(<a class="reference external" href="([^"]+)"[^>]*>)?<code class="xref py[^"]*"><span class="pre">'
                      r'~?((numpy|scipy|sympy|control|casadi)\.[^<]*)</span>')
    found: dict[str, list[str]] = {}
    unresolved = []
    for page in sorted((site / "html").glob("api-*.html")):
        for opened, href, name, library in xref.findall(page.read_text()):
            if not opened or not href.startswith(SITES[library]):
                unresolved.append((page.name, name, href))
            found.setdefault(library, []).append(name)
    assert unresolved == []
    # every library of the issue is reached, by the names the docstrings give (modelgen.load, Model, invert, simulate)
    assert {"casadi.external()", "casadi.Function", "control.StateSpace", "sympy.matrices.dense.Matrix",
            "scipy.integrate.solve_ivp()", "scipy.optimize.least_squares()"} <= {n for names in found.values() for n in names}
    api = (site / "html" / "api-inversion.html").read_text()
    for library in ("numpy", "python"):  # the parameter types: ndarray, array_like, float, str
        assert f'href="{SITES[library]}' in api, library


def _browser() -> tuple[object, str | None]:
    """Playwright's synchronous API and a Chromium to drive (the system's, else Playwright's own), or a skip."""
    import shutil

    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("the browser test needs Playwright (pip install playwright) and a Chromium (apt install chromium, or "
                    "playwright install chromium)")
    executable = next((shutil.which(name) for name in ("chromium", "chromium-browser", "google-chrome") if shutil.which(name)), None)
    return sync_playwright, executable


#: Measured in the page: MathJax's rendered elements, pictures that did not decode, elements of the content that reach
#: past the window's right edge outside any scrolling box, the page's own horizontal overflow, and the internal links.
_MEASURE = r"""() => {
  const width = document.documentElement.clientWidth;
  const scrolled = e => { for (let a = e.parentElement; a && a !== document.body; a = a.parentElement) {
      const o = getComputedStyle(a).overflowX; if (o === 'auto' || o === 'scroll') return true; } return false; };
  const past = [...document.querySelectorAll('article *')].filter(e => e.getBoundingClientRect().right > width + 1 && !scrolled(e));
  return {math: document.querySelectorAll('mjx-container').length, math_errors: document.querySelectorAll('mjx-merror').length,
          raw_math: (document.querySelector('article')?.innerText.match(/\\\(|\\\[/g) || []).length,
          broken_images: [...document.images].filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src),
          past: past.slice(0, 3).map(e => e.tagName + '.' + e.className), page_overflow: document.documentElement.scrollWidth - width,
          code_cut: [...document.querySelectorAll('article div.highlight pre')].filter(p => p.scrollWidth > p.clientWidth + 1)
              .map(p => p.textContent.slice(0, 40)),
          tables_wide: [...document.querySelectorAll('article table')].filter(t => t.scrollWidth > t.clientWidth + 1 ||
              (t.parentElement && t.parentElement.scrollWidth > t.parentElement.clientWidth + 1)).map(t => t.textContent.slice(0, 40)),
          equations_cut: [...document.querySelectorAll('article mjx-container[display="true"]')].filter(m => m.firstElementChild &&
              m.firstElementChild.getBoundingClientRect().width > m.clientWidth + 1).map(m => m.textContent.slice(0, 40)),
          links: [...document.querySelectorAll('a[href]')].map(a => a.href).filter(h => h.startsWith(location.origin))};
}"""


@pytest.mark.slow
def test_every_page_in_a_browser_at_a_desk_and_on_a_phone(request: pytest.FixtureRequest) -> None:
    """Issue 49, item 7: the built site in headless Chromium at 1280 and 390 px -- every page loads, nothing of the
    content reaches past the window (code, outputs and wide tables scroll in their own boxes), the notebooks' math is
    rendered by the MathJax the site serves itself (no raw TeX left, none it refused), every picture decodes, every internal link
    resolves."""
    import functools
    import http.server
    import threading

    sync_playwright, executable = _browser()  # before the build: a machine without a browser skips at once
    html = request.getfixturevalue("site") / "html"

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args: object) -> None:
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Quiet, directory=str(html)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    base = f"http://127.0.0.1:{server.server_port}/"
    pages = sorted(str(p.relative_to(html)) for p in html.rglob("*.html") if not p.name.startswith(("genindex", "search", "py-modindex")))
    problems: list[tuple[int, str, str]] = []
    links: set[str] = set()
    math = 0
    try:
        with sync_playwright() as playwright:  # type: ignore[operator]
            try:
                browser = playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
            except Exception as exc:  # noqa: BLE001 (Playwright's own error types vary by version)
                pytest.skip(f"no Chromium to drive: {str(exc).splitlines()[0]} (apt install chromium, or playwright install chromium)")
            for width in (1280, 390):
                page = browser.new_page(viewport={"width": width, "height": 900})
                for name in pages:
                    response = page.goto(base + name)
                    page.wait_for_load_state("networkidle")
                    page.evaluate("() => window.MathJax && MathJax.startup && MathJax.startup.promise")  # typeset
                    if response is None or not response.ok:
                        problems.append((width, name, "did not load"))
                        continue
                    found = page.evaluate(_MEASURE)
                    math += found["math"] if width == 1280 else 0
                    links.update(found["links"])
                    for key, bad in (("broken_images", found["broken_images"]), ("past the window", found["past"]),
                                     ("raw TeX", found["raw_math"]), ("TeX MathJax refused", found["math_errors"]),
                                     ("page overflow (px)", max(found["page_overflow"], 0)),
                                     # issue 58: code wider than its column, a formula cut at a phone's width, a table
                                     # wider than the text column at a desk (on a phone it may scroll in its own box)
                                     ("code cut at the column", found["code_cut"]), ("equation cut", found["equations_cut"]),
                                     ("table wider than the column", found["tables_wide"] if width == 1280 else [])):
                        if bad:
                            problems.append((width, name, f"{key}: {bad}"))
            browser.close()
    finally:
        server.shutdown()
    assert problems == []
    assert math > 0  # the notebooks' equations, rendered offline
    missing = [link for link in links if not (html / link[len(base):].split("#")[0].split("?")[0]).exists()]
    assert missing == []

"""Rebuild the intersphinx inventories the documentation links with when it cannot reach the libraries' own sites.

``docs/conf.py`` asks each site for its ``objects.inv`` first and falls back to the file here, so a build offline (CI, a
laptop on a train) links the API pages' types and "See Also" entries to NumPy, SciPy, SymPy, python-control, CasADi and
Python as a build online does. Run where Debian's archive and PyPI are reachable::

    python docs/inventories/refresh.py

What each file is, and where it comes from (``README.md`` beside this script says the same for a reader):

* ``python.inv``, ``numpy.inv``, ``scipy.inv``: the ``objects.inv`` that Sphinx wrote when Debian built the libraries'
  documentation packages (``python3.13-doc``, ``python-numpy-doc``, ``python-scipy-doc``), byte for byte.
* ``sympy.inv``: Debian's ``python-sympy-doc`` ships SymPy's HTML without its inventory; the entries are read back from
  the HTML (each ``<dl class="py ROLE"><dt id="NAME">`` that Sphinx wrote for an object, each ``module-NAME`` section).
* ``control.inv``: python-control's documentation built by Sphinx from the ``doc/`` folder of its source release
  (without its notebook, link-to-source and copy-button extensions, which add no object).
* ``casadi.inv``: CasADi's Python API page is not known to publish an inventory; the few names sflm's documentation
  uses point at that page (no anchors: the page's own ids could not be checked).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tarfile
import tempfile
import urllib.request
import zlib
from pathlib import Path

HERE = Path(__file__).resolve().parent
DEBIAN = "http://deb.debian.org/debian/"
#: Debian packages (trixie) whose documentation holds an inventory: file, package, version, the inventory's path inside.
DEBIAN_DOCS = {
    "python": ("pool/main/p/python3.13/python3.13-doc_3.13.5-2+deb13u5_all.deb", "Python", "3.13",
               "usr/share/doc/python3.13/html/objects.inv"),
    "numpy": ("pool/main/n/numpy/python-numpy-doc_2.2.4+ds-1_all.deb", "NumPy", "2.2",
              "usr/share/doc/python-numpy/html/objects.inv"),
    "scipy": ("pool/main/s/scipy/python-scipy-doc_1.15.3-1_all.deb", "SciPy", "1.15.3",
              "usr/share/doc/python-scipy-doc/html/objects.inv"),
}
SYMPY = ("pool/main/s/sympy/python-sympy-doc_1.13.3-5_all.deb", "SymPy", "1.13.3", "usr/share/doc/python-sympy-doc/html")
CONTROL_VERSION = "0.10.2"
#: The CasADi names sflm's documentation uses, with their Sphinx roles; each links to the Python API page itself.
CASADI = {"casadi.Function": "class", "casadi.SX": "class", "casadi.MX": "class", "casadi.DM": "class",
          "casadi.CodeGenerator": "class", "casadi.external": "function", "casadi.integrator": "function",
          "casadi.nlpsol": "function"}


def write_inventory(path: Path, project: str, version: str, entries: list[tuple[str, str, str]]) -> None:
    """Write ``entries`` (name, ``domain:role``, URI relative to the site) as a Sphinx inventory, version 2."""
    lines = sorted({f"{name} {role} 1 {uri} -\n" for name, role, uri in entries})
    header = (f"# Sphinx inventory version 2\n# Project: {project}\n# Version: {version}\n"
              "# The remainder of this file is compressed using zlib.\n")
    path.write_bytes(header.encode() + zlib.compress("".join(lines).encode(), 9))
    print(f"{path.name}: {len(lines)} entries ({project} {version})")


def _deb_members(deb: bytes, workdir: Path) -> Path:
    """Unpack a Debian package's files into ``workdir`` (dpkg-deb where there is one; Debian's own format otherwise)."""
    package = workdir / "package.deb"
    package.write_bytes(deb)
    target = workdir / "root"
    subprocess.run(["dpkg-deb", "-x", str(package), str(target)], check=True)
    return target


def _download(url: str) -> bytes:
    print(f"downloading {url}")
    with urllib.request.urlopen(url, timeout=120) as response:  # noqa: S310 (a fixed https/http address)
        return response.read()


def sympy_entries(html: Path) -> list[tuple[str, str, str]]:
    """The objects of SymPy's HTML documentation, as Sphinx wrote them into each page: ``<dl class="py ROLE">`` followed
    by ``<dt class="sig sig-object py" id="NAME">``, and ``<section id="module-NAME">``."""
    entry = re.compile(r'<dl class="py (\w+)">\s*<dt class="sig sig-object py" id="([\w.]+)"')
    module = re.compile(r'<section id="module-([\w.]+)"')
    entries = []
    for page in sorted(html.rglob("*.html")):
        relative = page.relative_to(html).as_posix()
        if relative.startswith(("_", "search", "genindex", "py-modindex")):
            continue
        text = page.read_text(errors="replace")
        entries += [(name, f"py:{role}", f"{relative}#{name}") for role, name in entry.findall(text)]
        entries += [(name, "py:module", f"{relative}#module-{name}") for name in module.findall(text)]
    return entries


def control_inventory(workdir: Path) -> bytes:
    """python-control's inventory, built by Sphinx from its source release's ``doc/`` folder."""
    subprocess.run([sys.executable, "-m", "pip", "download", f"control=={CONTROL_VERSION}", "--no-binary", ":all:",
                    "--no-deps", "-q", "-d", str(workdir)], check=True)
    with tarfile.open(next(workdir.glob("control-*.tar.gz"))) as archive:
        archive.extractall(workdir, filter="data")
    doc = workdir / f"control-{CONTROL_VERSION}" / "doc"
    out = workdir / "html"
    subprocess.run([sys.executable, "-m", "sphinx", "-b", "html", "-Q", "-D", "html_theme=alabaster", "-D",
                    "extensions=sphinx.ext.autodoc,sphinx.ext.autosummary,numpydoc,sphinx.ext.todo,sphinx.ext.doctest",
                    str(doc), str(out)], check=True, cwd=doc)
    return (out / "objects.inv").read_bytes()


def main() -> None:
    """Write every inventory of this folder afresh."""
    with tempfile.TemporaryDirectory() as tmp:
        for name, (path, _project, _version, member) in DEBIAN_DOCS.items():
            workdir = Path(tmp) / name
            workdir.mkdir()
            root = _deb_members(_download(DEBIAN + path), workdir)
            (HERE / f"{name}.inv").write_bytes((root / member).read_bytes())
            print(f"{name}.inv: {path}")
        workdir = Path(tmp) / "sympy"
        workdir.mkdir()
        root = _deb_members(_download(DEBIAN + SYMPY[0]), workdir)
        write_inventory(HERE / "sympy.inv", SYMPY[1], SYMPY[2], sympy_entries(root / SYMPY[3]))
        workdir = Path(tmp) / "control"
        workdir.mkdir()
        (HERE / "control.inv").write_bytes(control_inventory(workdir))
        print(f"control.inv: control {CONTROL_VERSION}'s doc/, built by Sphinx")
    write_inventory(HERE / "casadi.inv", "CasADi", "3", [(name, f"py:{role}", "") for name, role in CASADI.items()])


if __name__ == "__main__":
    main()
